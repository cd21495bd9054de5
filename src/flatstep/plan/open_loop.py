r"""Plans for a step/dir drive at its physical limit: an acceleration that follows the pull-out curve.

A step/dir driver holds a set current and turns its angle; the rotor follows while the torque it needs stays below
the pull-out torque :math:`T_{po}(\omega)` (:func:`flatstep.model.pullout.pullout_torque`). With a share
``margin`` of it (the torque margin is ``1 - margin``) and a known load :math:`\tau`, the acceleration may be

.. math:: a(\omega) = \frac{m\,T_{po}(\omega) - \tau}{J},

which falls with the speed, where a firmware's trapezoid takes one constant acceleration for the whole move, as low
as its top speed needs. The plan accelerates along :math:`a(\omega)`, cruises at the speed cap, and brakes along
the same curve (braking is helped by the back-EMF, so the same curve is on the safe side). The speed cap is where
:math:`a(\omega)` has fallen to :data:`CRUISE_SHARE` of its value at rest (beyond it the speed grows too slowly to
pay), or ``w_max`` if the user gives one (lowered to where :math:`a(\omega)` is :data:`FLOOR_SHARE` of its value
at rest).

The curve is cut into :data:`SEGMENTS` speed steps; on each the acceleration runs linearly in time from the curve's
value one step ahead to its value two steps ahead (below the curve at every speed of the step, since
:math:`T_{po}` falls with the speed), so that it is continuous from the first step to the peak: the plan is a
:class:`~flatstep.plan.piecewise.PiecewisePlan` of cubic segments at the run current, for
:class:`~flatstep.control.microstep.Microstepping` or any controller. The acceleration jumps only at the start, at
the peak and at the end, which the shaping (:func:`box_shaped`) turns into ramps.

:func:`profile_plan` is the general form that a search tunes on the drive: an acceleration :math:`a(\omega)` and a
braking :math:`b(\omega)` of their own (:func:`speed_profile`: piecewise linear in the speed), up to a cruise speed;
constant profiles give a constant-acceleration trapezoid, so the family holds the firmware's plan.
"""
from __future__ import annotations

import math
from typing import Callable, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.motor import MotorParams
from ..model.pullout import DRIVE_KINDS, pullout_torque
from ..validate import InputError, check_choice, check_quantity
from .arguments import check_angle, check_motor, check_t0
from .piecewise import NCOEF, PiecewisePlan

Array = NDArray[np.float64]
#: Speed steps of the acceleration along the pull-out curve.
SEGMENTS = 24
#: The cruise speed is where the acceleration has fallen to this share of its value at rest.
CRUISE_SHARE = 0.5
#: A user's speed cap is lowered to where the acceleration has fallen to this share of its value at rest.
FLOOR_SHARE = 0.01


PulloutCurve = Callable[[Array], Array]


def tabulated(speeds: ArrayLike, torque: ArrayLike) -> PulloutCurve:
    """A pull-out curve from a table (measured, or read off a datasheet): speeds [rad/s] and torques [N m].

    Linear between the points, held at the first point's torque below it and 0 beyond the last; made
    non-increasing (each torque at most those at lower speeds), so that a segment's upper end is its lowest.
    """
    w = np.asarray(speeds, dtype=float)
    t = np.asarray(torque, dtype=float)
    if w.ndim != 1 or w.shape != t.shape or w.size < 2 or not (np.diff(w) > 0).all() or not np.isfinite(t).all() \
            or (t < 0).any() or w[0] < 0:
        raise InputError("speeds", speeds, "a tabulated pull-out curve needs at least 2 increasing speeds >= 0 [rad/s] "
                         "and as many finite torques >= 0 [N m]")
    t = np.minimum.accumulate(t)

    def curve(x: Array) -> Array:
        return np.interp(np.asarray(x, dtype=float), w, t, right=0.0)
    return curve


def acceleration_curve(motor: MotorParams, v_bus: float, current: float, speeds: Array, *, margin: float,
                       load: float = 0.0, drive_kind: str = "chopper", pullout: Optional[PulloutCurve] = None) -> Array:
    r"""The allowed acceleration :math:`(m T_{po}(\omega) - \tau)/J` [rad/s^2] at each speed (module docstring).

    :math:`T_{po}` is ``pullout`` if given (e.g. :func:`tabulated`), else the model's curve of ``drive_kind``.
    """
    torque = pullout(speeds) if pullout is not None else pullout_torque(motor, drive_kind, v_bus, current, speeds)
    return (margin * torque - load) / motor.J


def _cruise_speed(motor: MotorParams, v_bus: float, current: float, margin: float, load: float, drive_kind: str,
                  w_max: Optional[float], pullout: Optional[PulloutCurve]) -> float:
    """The speed cap: where the acceleration falls to CRUISE_SHARE of its value at rest, or ``w_max``."""
    a0 = float(acceleration_curve(motor, v_bus, current, np.zeros(1), margin=margin, load=load,
                                  drive_kind=drive_kind, pullout=pullout)[0])
    if a0 <= 0:
        raise InputError("load", load, f"load={load!r} N m is more than margin x the pull-out torque at rest "
                         f"({margin:g} x {a0 * motor.J / margin + load / margin:.4g} N m): the drive cannot start")
    top = 20.0 * v_bus / motor.Km
    grid = np.linspace(0.0, top, 4001)
    a = acceleration_curve(motor, v_bus, current, grid, margin=margin, load=load, drive_kind=drive_kind,
                           pullout=pullout)
    low = np.flatnonzero(a < (CRUISE_SHARE if w_max is None else FLOOR_SHARE) * a0)
    w = float(grid[low[0] - 1]) if low.size else top
    return min(w, w_max) if w_max is not None else w


def open_loop_plan(motor: MotorParams, v_bus: float, current: float, distance: float, *, margin: float = 0.4,
                   load: float = 0.0, drive_kind: str = "chopper", w_max: Optional[float] = None,
                   theta1: float = 0.0, t0: float = 0.0, shaping: bool = True,
                   pullout: Optional[PulloutCurve] = None) -> PiecewisePlan:
    """A rest-to-rest move of ``distance`` [rad] for a step/dir drive, accelerating along its pull-out curve.

    Parameters
    ----------
    motor : MotorParams
        The drive's model of the motor (with the load's inertia in J).
    v_bus : float
        The bus [V].
    current : float
        The run current, the current-vector norm the driver holds [A] (the plan's rho).
    distance : float
        The move [rad], either sign.
    margin : float
        The share of the pull-out torque the plan uses, in (0, 1]: the torque margin is ``1 - margin``.
    load : float
        A known load torque [N m], >= 0, that the drive carries besides the acceleration.
    drive_kind : str
        The curve (:data:`flatstep.model.pullout.DRIVE_KINDS`; ``"chopper"`` for a step/dir driver).
    w_max : float, optional
        A speed cap of the user's [rad/s] (e.g. the drive's electrical-frequency limit).
    theta1, t0 : float
        Start angle [rad] and time [s].
    shaping : bool
        Average the angle over one :func:`natural_period` of the loaded rotor (:func:`box_shaped`): every jump of
        the acceleration becomes a ramp that leaves the undamped rotor without ringing (default); ``False``: the
        three jumps (start, peak, end) as they are.
    pullout : callable, optional
        The pull-out curve to follow, torque [N m] of speed [rad/s] (e.g. :func:`tabulated` from a measurement);
        default: the model's curve of ``drive_kind``.

    Returns
    -------
    PiecewisePlan
        Along the curve up, a cruise if the move is long enough, along the curve down: cubic segments.
    """
    check_motor(motor)
    check_choice("drive_kind", drive_kind, DRIVE_KINDS)
    v_bus, current = check_quantity("v_bus", v_bus), check_quantity("current", current)
    d = check_angle(distance, "distance")
    if d == 0:
        raise InputError("distance", distance, "distance=0.0 rad: a move needs a distance; a rest is a dwell")
    m = check_quantity("fraction", margin, as_name="margin")
    load = check_quantity("torque_amplitude", load, as_name="load")
    w_max = None if w_max is None else check_quantity("speed", w_max, as_name="w_max")
    theta1, t0 = check_angle(theta1, "theta1"), check_t0(t0)
    cap = _cruise_speed(motor, v_bus, current, m, load, drive_kind, w_max, pullout)

    def accel(w: Array) -> Array:
        return acceleration_curve(motor, v_bus, current, w, margin=m, load=load, drive_kind=drive_kind,
                                  pullout=pullout)

    half = 0.5 * abs(d)
    up, reach = _ramp_up(accel, cap)
    if reach > half:  # the peak speed is below the cap: the one whose ramp covers half the move
        lo, hi = 0.0, cap
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _ramp_up(accel, mid)[1] <= half else (lo, mid)
        up, reach = _ramp_up(accel, lo)
    peak = up[-1][0] + 0.5 * (up[-1][1] + up[-1][2]) * up[-1][3]
    cruise = (abs(d) - 2 * reach) / peak
    down = [(w0 + 0.5 * (a0 + a1) * h, -a1, -a0, h) for w0, a0, a1, h in reversed(up)]
    phases = up + ([(peak, 0.0, 0.0, cruise)] if cruise > 1e-9 * (abs(d) / peak) else []) + down
    rows, p = np.zeros((len(phases), NCOEF)), 0.0
    for j, (w0, a0, a1, h) in enumerate(phases):
        rows[j, -4:] = [(a1 - a0) * h * h / 6, a0 * h * h / 2, w0 * h, p]
        p += w0 * h + a0 * h * h / 2 + (a1 - a0) * h * h / 6
    rows[-1, -1] += abs(d) - p  # the rounding of the bisection, on the last segment's constant
    sign = 1.0 if d > 0 else -1.0
    rows *= sign
    rows[:, -1] += theta1
    breaks = t0 + np.concatenate([[0.0], np.cumsum([h for *_, h in phases])])
    rho = np.zeros_like(rows)
    rho[:, -1] = current
    plan = PiecewisePlan(breaks, rows, rho)
    return box_shaped(plan, natural_period(motor, current, m)) if shaping else plan


def _ramp_up(accel: Callable[[Array], Array], peak: float) -> tuple[list[tuple[float, float, float, float]], float]:
    """From rest to ``peak`` in SEGMENTS speed steps, the acceleration linear in time and continuous; its distance.

    On step k, from speed w_k to w_k+1, the acceleration goes from ``accel(w_k+1)`` to ``accel(w_k+2)`` (the curve one
    and two steps ahead: below it at every speed of the step, as the curve falls), over ``2 dw / (a0 + a1)``.
    Returns (start speed, start and end acceleration, duration) per step and the distance covered.
    """
    dw = peak / SEGMENTS
    edges = dw * np.arange(SEGMENTS + 2, dtype=np.float64)
    a = np.maximum(accel(edges[1:]), 1e-9 * max(float(accel(edges[:1])[0]), 1e-9))
    h = 2 * dw / (a[:-1] + a[1:])
    dist = edges[:-2] * h + a[:-1] * h * h / 2 + (a[1:] - a[:-1]) * h * h / 6
    steps = [(float(edges[k]), float(a[k]), float(a[k + 1]), float(h[k])) for k in range(SEGMENTS)]
    return steps, float(np.sum(dist))


def natural_period(motor: MotorParams, current: float, margin: float) -> float:
    r"""The period [s] of the rotor's ringing about its load angle on an open-loop drive.

    .. math:: T_n = 2\pi\Big/\sqrt{K_m I N_r \cos\delta / J},\qquad \sin\delta = m

    (the stiffness of the torque-angle curve :math:`K_m I \sin N_r e` at the load angle the margin ``m`` gives).
    """
    stiffness = motor.Km * current * motor.Nr * math.sqrt(max(1.0 - margin * margin, 0.01))
    return 2.0 * math.pi / math.sqrt(stiffness / motor.J)


def box_shaped(plan: PiecewisePlan, period: float) -> PiecewisePlan:
    r"""The plan's angle averaged over a sliding window of one ``period``: no residual ringing at that period.

    .. math:: \theta_s(t) = \frac1T\int_{t - T}^{t} \theta(s)\,ds

    Every jump of the acceleration becomes a ramp of duration :math:`T`; a rotor that rings at :math:`1/T` is left
    at rest after each ramp (a box input shaper). The move keeps its ends and lasts :math:`T` longer; its segments,
    between the breaks and the breaks shifted by :math:`T`, are one degree above the plan's.
    """
    from scipy.interpolate import PPoly

    T = check_quantity("period", period)
    b, h = plan.breaks, plan.durations
    local = plan.theta.T * h[None, :] ** -np.arange(NCOEF - 1, -1, -1)[:, None]
    hold1, hold2 = np.zeros((NCOEF, 1)), np.zeros((NCOEF, 1))
    hold1[-1, 0], hold2[-1, 0] = plan.theta1, plan.theta2
    x = np.concatenate([[b[0] - T], b, [b[-1] + T]])
    antider = PPoly(np.hstack([hold1, local, hold2]), x).antiderivative()
    edges = np.unique(np.concatenate([b, b + T]))
    edges = edges[np.concatenate([[True], np.diff(edges) > 1e-9 * max(T, 1e-6)])]
    used = np.flatnonzero(np.any(plan.theta != 0.0, axis=0))
    degree = min(NCOEF - 1, NCOEF - int(used[0]) if used.size else 1)  # one above the plan's own
    tau = np.linspace(0.0, 1.0, degree + 1)
    t = edges[:-1, None] + np.diff(edges)[:, None] * tau[None, :]
    values = (antider(t) - antider(t - T)) / T
    vander = np.vander(tau, degree + 1)
    rows = np.linalg.solve(vander, values.T).T
    rho = np.zeros((rows.shape[0], NCOEF))
    rho[:, -1] = plan.rho1
    return PiecewisePlan(edges, rows, rho)


#: Speed steps of a :func:`profile_plan` from rest to its cruise speed (the knots are added to them).
PROFILE_STEPS = 20


def speed_profile(speeds: ArrayLike, accelerations: ArrayLike, name: str = "accel") -> PulloutCurve:
    """An acceleration [rad/s^2] of the speed [rad/s]: linear between the knots, held beyond the first and the last.

    The knot speeds increase from 0; the accelerations are > 0 (for :func:`profile_plan`, up or down).
    """
    w = np.asarray(speeds, dtype=float)
    a = np.asarray(accelerations, dtype=float)
    if w.ndim != 1 or w.shape != a.shape or w.size < 1 or not np.isfinite(w).all() or w[0] != 0.0 \
            or not (np.diff(w) > 0).all() or not np.isfinite(a).all() or not (a > 0).all():
        raise InputError(name, (speeds, accelerations), f"{name}: a speed profile needs knot speeds increasing from 0 "
                         "[rad/s] and as many finite accelerations > 0 [rad/s^2]")

    def profile(x: Array) -> Array:
        return np.interp(np.asarray(x, dtype=float), w, a)
    profile.knots = w  # type: ignore[attr-defined]
    return profile


def _staircase(profile: PulloutCurve, cruise: float) -> tuple[Array, Array]:
    """Speed edges from 0 to ``cruise`` (PROFILE_STEPS steps and the profile's knots) and the acceleration on each.

    On each step the acceleration is the profile's lower end value (the profile is linear between the edges, so
    that is its least on the step): the staircase stays below the profile at every speed.
    """
    knots = np.asarray(getattr(profile, "knots", np.zeros(0)), dtype=float)
    edges = np.unique(np.concatenate([np.linspace(0.0, cruise, PROFILE_STEPS + 1), knots[knots < cruise]]))
    values = profile(edges)
    return edges, np.minimum(values[:-1], values[1:])


def _ramp_to(edges: Array, acc: Array, peak: float) -> tuple[Array, Array]:
    """The staircase cut at ``peak``: start speeds and accelerations of its steps, and the speed each ends at."""
    n = max(int(np.searchsorted(edges, peak, side="left")), 1)
    w0 = edges[:n]
    w1 = np.minimum(edges[1:n + 1], peak)
    return np.stack([w0, acc[:n]]), w1


def _distance(edges: Array, acc: Array, peak: float) -> float:
    """The distance from rest to ``peak`` along the staircase (or from ``peak`` to rest)."""
    (w0, a), w1 = _ramp_to(edges, acc, peak)
    return float(np.sum((w1 * w1 - w0 * w0) / (2 * a)))


def profile_plan(distance: float, cruise: float, accel: PulloutCurve, brake: PulloutCurve, current: float, *,
                 theta1: float = 0.0, t0: float = 0.0) -> PiecewisePlan:
    r"""A rest-to-rest move whose acceleration is a function of the speed, one profile up and one down.

    From rest the plan accelerates at :math:`a(\omega)` (``accel``, e.g. :func:`speed_profile`) up to ``cruise``,
    cruises, and brakes at :math:`b(\omega)` (``brake``) to rest; if the move is too short for the cruise, up to the
    peak speed at which the two ramps cover it. Each ramp is a staircase in speed (:data:`PROFILE_STEPS` steps up to
    the cruise, and the knots): constant acceleration on each of its steps, at most the profile's value anywhere on
    the step, so that the plan is a :class:`~flatstep.plan.piecewise.PiecewisePlan` of parabolas (bounded
    acceleration, as a trapezoid's). Constant profiles give the trapezoid of ``cruise`` and that acceleration
    exactly.

    Parameters
    ----------
    distance : float
        The move [rad], either sign.
    cruise : float
        The cruise speed [rad/s], > 0.
    accel, brake : callable
        Acceleration and deceleration [rad/s^2], > 0, of the speed [rad/s].
    current : float
        The run current the driver holds [A] (the plan's rho).
    theta1, t0 : float
        Start angle [rad] and time [s].
    """
    d = check_angle(distance, "distance")
    if d == 0:
        raise InputError("distance", distance, "distance=0.0 rad: a move needs a distance; a rest is a dwell")
    v = check_quantity("speed", cruise, as_name="cruise")
    current = check_quantity("current", current)
    theta1, t0 = check_angle(theta1, "theta1"), check_t0(t0)
    up, down = _staircase(accel, v), _staircase(brake, v)
    for name, (_, acc) in (("accel", up), ("brake", down)):
        if not (np.isfinite(acc).all() and (acc > 0).all()):
            raise InputError(name, acc, f"{name}: the acceleration must be finite and > 0 at every speed up to "
                             f"the cruise ({v:g} rad/s)")
    half = abs(d)
    peak = v
    if _distance(*up, v) + _distance(*down, v) > half:
        lo, hi = 0.0, v
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _distance(*up, mid) + _distance(*down, mid) <= half else (lo, mid)
        peak = lo
    (w_up, a_up), e_up = _ramp_to(*up, peak)
    (w_dn, a_dn), e_dn = _ramp_to(*down, peak)
    cruise_distance = half - _distance(*up, peak) - _distance(*down, peak)
    cruising = cruise_distance > 1e-12 * half
    speed = np.concatenate([w_up, [peak] if cruising else [], e_dn[::-1]])  # at the start of each phase
    acc = np.concatenate([a_up, [0.0] if cruising else [], -a_dn[::-1]])
    dur = np.concatenate([(e_up - w_up) / a_up, [cruise_distance / peak] if cruising else [],
                          ((e_dn - w_dn) / a_dn)[::-1]])
    keep = dur > 1e-9 * float(np.sum(dur))  # not a step the peak only grazes
    speed, acc, dur = speed[keep], acc[keep], dur[keep]
    step = speed * dur + acc * dur * dur / 2
    rows = np.zeros((dur.size, NCOEF))
    rows[:, -3] = acc * dur * dur / 2
    rows[:, -2] = speed * dur
    rows[:, -1] = np.concatenate([[0.0], np.cumsum(step)[:-1]])
    p = float(np.sum(step))
    rows[-1, -1] += half - p  # the rounding of the bisection, on the last segment's constant
    rows *= 1.0 if d > 0 else -1.0
    rows[:, -1] += theta1
    breaks = t0 + np.concatenate([[0.0], np.cumsum(dur)])
    rho = np.zeros_like(rows)
    rho[:, -1] = current
    return PiecewisePlan(breaks, rows, rho)
