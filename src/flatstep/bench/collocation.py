r"""The true minimum time of a rest-to-rest move: direct collocation of the optimal-control problem (CasADi, IPOPT).

The yardstick of the time-optimal planners (:mod:`flatstep.plan.time_optimal`): the same motor, the same limits
(:class:`~flatstep.plan.limits.MotorLimits`), no assumption on the shape of the move or on the law that will track
it. CasADi (PyPI ``casadi``, the ``bench`` and ``test`` extras) builds the problem and its derivatives and IPOPT
solves it.

**The problem.** Eq. (1) rotated into the rotor's frame by the electrical angle :math:`\phi = N_r\theta`
(:math:`i_d = i_a\cos\phi + i_b\sin\phi`, :math:`i_q = -i_a\sin\phi + i_b\cos\phi`, the voltages likewise):

.. math::
    L\dot i_d = v_d - R i_d + N_r\omega L i_q,\quad
    L\dot i_q = v_q - R i_q - N_r\omega L i_d - K_m\omega,\\
    J\dot\omega = K_m i_q - B\omega - \tau + \tau_p(\omega, \theta),\quad \dot\theta = \omega

(:math:`\tau` the constant load, :math:`\tau_p` the detent, Coulomb friction and iron loss of
:class:`~flatstep.model.plant.PlantEffects`). Minimise :math:`t_f` subject to

* the bus, ``voltage="vector"``: :math:`v_d^2 + v_q^2 \le (v_{use} v_{bus})^2` (what the planner checks,
  :mod:`flatstep.plan.limits`); ``voltage="phase"``: :math:`|v_a|, |v_b| \le v_{use} v_{bus}` (two full
  H-bridges, each phase its own share of the bus);
* the current, :math:`i_d^2 + i_q^2 \le i_{max}^2`; the optional speed and acceleration caps;
* ``field_weakening=False``: :math:`i_d = 0` throughout (field-oriented control without field weakening);
* rest at both ends: :math:`\theta(0) = 0`, :math:`\theta(t_f) =` ``distance``, :math:`\omega = 0`, the torque
  current that holds the load there, and :math:`i_d =` ``i_hold``, the current across the torque axis that
  the paper's law's plans start and end with (0 without field weakening; ``i_rest`` to choose).

The torque-angle cap of ``limits`` is the paper's law's and is not imposed: the optimum is that of the motor, not
of one law. A jerk cap is refused (it needs the voltage's derivative).

**Discretisation.** Trapezoidal collocation on ``grid`` equal intervals of the free duration: the states and the
voltages at the ``grid + 1`` nodes, the limits at the nodes, every variable scaled to about 1. Its error falls
with the square of the interval where the solution is smooth and with the interval at a switch;
:func:`grid_converged` solves on two grids and reports the change. With ``voltage="phase"`` the limit turns with
the rotor, so the grid is refined to at least :data:`PHASE_NODES_PER_TURN` nodes per electrical turn of the move;
with a detent torque, to at least :data:`DETENT_NODES_PER_PERIOD` nodes per period of the detent.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple, Optional

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from ..model.plant import PlantEffects
from ..plan.arguments import check_angle, check_limits, check_motor
from ..plan.limits import MotorLimits
from ..validate import InputError, check_choice, check_quantity

Array = NDArray[np.float64]
VOLTAGES = ("vector", "phase")
#: The least nodes per electrical turn of the move with ``voltage="phase"`` (the limit turns with the rotor).
PHASE_NODES_PER_TURN = 16
#: The least nodes per period of the detent torque, when there is one.
DETENT_NODES_PER_PERIOD = 8
#: The most intervals of a grid.
MAX_GRID = 20000
_SLOWER = (1.0, 1.6, 2.5)  # the first guesses' cruise speeds, as fractions 1 / slower of 0.9 the steady top speed
_IPOPT = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.max_iter": 3000,
          "ipopt.tol": 1e-9, "ipopt.acceptable_tol": 1e-7, "ipopt.mu_strategy": "adaptive"}


def _casadi() -> Any:
    """The ``casadi`` module, or an ImportError that names the extra to install."""
    try:
        import casadi
    except ImportError:
        raise ImportError("flatstep.bench.collocation needs CasADi: pip install 'flatstep[bench]' "
                          "(or pip install casadi)") from None
    return casadi


@dataclass(frozen=True)
class OptimalMove:
    """The minimum-time move on the collocation grid: its duration and every signal at the ``grid + 1`` nodes.

    Parameters
    ----------
    distance : float
        The move [rad].
    tf : float
        The minimum duration [s].
    t, theta, omega, i_d, i_q, v_d, v_q, v_a, v_b : ndarray
        Time [s], angle [rad], speed [rad/s], currents [A] and voltages [V] at the nodes; ``v_a``, ``v_b`` the
        phase voltages (the d-q voltages turned back by the electrical angle).
    grid : int
        Intervals of the grid.
    voltage : str
        ``"vector"`` or ``"phase"``: the bus limit solved under.
    field_weakening : bool
        Whether ``i_d`` was free (False: held at 0).
    v_limit : float
        The voltage bound [V], ``v_use v_bus``.
    i_max : float
        The current bound [A].
    status : str
        IPOPT's return status.
    iterations : int
        IPOPT's iterations.
    """

    distance: float
    tf: float
    t: Array
    theta: Array
    omega: Array
    i_d: Array
    i_q: Array
    v_d: Array
    v_q: Array
    v_a: Array
    v_b: Array
    grid: int
    voltage: str
    field_weakening: bool
    v_limit: float
    i_max: float
    status: str
    iterations: int

    def peaks(self) -> dict[str, float]:
        """The worst use of each limit on the grid (1 = at the limit), the peak speed and the least ``i_d``."""
        if self.voltage == "vector":
            v = float(np.max(np.hypot(self.v_d, self.v_q)))
        else:
            v = float(np.max(np.maximum(np.abs(self.v_a), np.abs(self.v_b))))
        return dict(voltage=v / self.v_limit, current=float(np.max(np.hypot(self.i_d, self.i_q))) / self.i_max,
                    speed_peak=float(np.max(np.abs(self.omega))), i_d_min=float(np.min(self.i_d)))


class Converged(NamedTuple):
    """The same problem on two grids: both solutions and the relative change of the duration, ``|fine/coarse - 1|``."""

    coarse: OptimalMove
    fine: OptimalMove
    change: float


def _check_options(distance: Any, motor: Any, limits: Any, voltage: Any, grid: Any, load: Any,
                   effects: Any) -> tuple[float, str, int, float, PlantEffects]:
    """The arguments checked before any work (an InputError naming the one that is wrong)."""
    d = check_angle(distance, "distance")
    if d == 0:
        raise InputError("distance", distance, "distance=0.0 rad: a move needs a distance; a rest is a dwell")
    check_motor(motor)
    check_limits(limits)
    voltage = check_choice("voltage", voltage, VOLTAGES)
    grid = _check_grid(grid)
    load = check_quantity("load", load)
    if effects is None:
        effects = PlantEffects()
    if not isinstance(effects, PlantEffects):
        raise InputError("effects", effects, f"effects={effects!r} is not a flatstep.model.plant.PlantEffects")
    if limits.jerk_max is not None:
        raise InputError("limits.jerk_max", limits.jerk_max, "the collocation does not impose a jerk cap (it needs "
                         "the voltage's derivative): give limits without jerk_max")
    return d, voltage, grid, load, effects


def _check_grid(grid: Any) -> int:
    """``grid`` as int, or an InputError unless it is an integer in [4, MAX_GRID]."""
    if isinstance(grid, bool) or not isinstance(grid, (int, np.integer)) or not 4 <= grid <= MAX_GRID:
        raise InputError("grid", grid, f"grid={grid!r}: the intervals of the collocation grid are an integer in "
                         f"[4, {MAX_GRID}] (flatstep.bench.collocation.MAX_GRID)")
    return int(grid)


def _least_grid(d: float, motor: MotorParams, voltage: str, effects: PlantEffects) -> int:
    """The fewest intervals that resolve the electrical turns (phase limit) and the detent's periods of the move."""
    turns = motor.Nr * abs(d) / (2 * math.pi)
    least = PHASE_NODES_PER_TURN * turns if voltage == "phase" else 0.0
    if effects.detent_torque > 0:
        least = max(least, DETENT_NODES_PER_PERIOD * effects.detent_harmonic * turns)
    return math.ceil(least)


def _plant_torque(ca: Any, omega: Any, theta: Any, motor: MotorParams, effects: PlantEffects) -> Any:
    """The torque of ``effects`` on the rotor [N m], symbolic (:meth:`PlantEffects.torque`)."""
    out = -effects.detent_torque * ca.sin(effects.detent_harmonic * motor.Nr * theta)
    if effects.coulomb_torque > 0:
        out = out - effects.coulomb_torque * ca.tanh(omega / effects.coulomb_speed)
    if effects.magnetizing_resistance is not None:
        out = out - motor.Km**2 / effects.magnetizing_resistance * omega
    return out


def _rest_torque_current(theta: float, motor: MotorParams, load: float, effects: PlantEffects) -> float:
    """The torque current [A] that holds the rotor at rest at ``theta`` against the load and the detent."""
    return float(load - effects.torque(0.0, theta, motor)) / motor.Km


def _first_guess(d: float, motor: MotorParams, limits: MotorLimits, v_lim: float,
                 slower: float = 1.0) -> tuple[float, float, float]:
    """A move to start from: (duration [s], acceleration [rad/s^2], cruise speed [rad/s]) of a trapezoid.

    Its acceleration is 70 % of the current's torque over J, its cruise speed ``1 / slower`` of 0.9 times the
    steady top speed (or the speed cap).
    """
    a = 0.7 * motor.Km * limits.i_max / motor.J
    w = 0.9 * v_lim / motor.Km / slower
    if limits.speed_max is not None:
        w = min(w, limits.speed_max)
    d = abs(d)
    if w * w / a >= d:
        w = math.sqrt(d * a)
        return 2.0 * w / a, a, w
    return w / a + d / w, a, w


def minimum_time(distance: float, motor: MotorParams, limits: MotorLimits, *, voltage: str = "vector",
                 field_weakening: bool = True, grid: int = 200, load: float = 0.0,
                 effects: Optional[PlantEffects] = None, i_rest: Optional[float] = None,
                 initial: Optional[OptimalMove] = None) -> OptimalMove:
    """The minimum-time rest-to-rest move over ``distance`` [rad] under ``limits`` (module docstring).

    Parameters
    ----------
    distance : float
        The move [rad], non-zero.
    motor : MotorParams
        The motor.
    limits : MotorLimits
        ``v_bus``, ``v_use``, ``i_max``, ``i_hold`` (the rest current across the torque axis), ``speed_max`` and
        ``accel_max`` if set; ``jerk_max`` must be None.
    voltage : {"vector", "phase"}
        The bus limit on the voltage vector's norm, or on each phase.
    field_weakening : bool
        Whether ``i_d`` is free (it may go negative to cancel back EMF); False holds it at 0.
    grid : int
        Intervals of the collocation grid, in [4, ``MAX_GRID``] (raised for ``voltage="phase"`` and a detent,
        module docstring).
    load : float
        A constant load torque [N m].
    effects : PlantEffects, optional
        Detent, Coulomb friction and iron loss of the plant.
    i_rest : float, optional
        The d current at rest at both ends [A]; default ``limits.i_hold`` with field weakening (the paper's law's
        plans), 0 without. A planner whose plans rest at ``i_d = 0`` (a field-oriented one) is measured against
        ``i_rest=0``.
    initial : OptimalMove, optional
        A solution to start from (interpolated onto this grid), e.g. the same problem on a coarser grid.

    Returns
    -------
    OptimalMove

    Raises
    ------
    InputError
        An argument out of range, checked before any work.
    ImportError
        Without CasADi (the ``bench`` extra).
    ValueError
        When IPOPT finds no solution (an infeasible problem: the rest current above ``i_max``, a load the
        current cannot hold).
    """
    d, voltage, grid, load, effects = _check_options(distance, motor, limits, voltage, grid, load, effects)
    field_weakening = bool(field_weakening)
    if i_rest is None:
        i_rest = limits.i_hold if field_weakening else 0.0
    i_rest = check_quantity("d_current", i_rest, as_name="i_rest")
    if not field_weakening and i_rest != 0:
        raise InputError("i_rest", i_rest, f"i_rest={i_rest!r} A: without field weakening i_d is held at 0, "
                         "at rest too")
    ca = _casadi()
    m = motor
    v_lim = limits.v_use * limits.v_bus
    n = min(MAX_GRID, max(grid, _least_grid(d, m, voltage, effects)))
    iq0 = _rest_torque_current(0.0, m, load, effects)
    iq1 = _rest_torque_current(d, m, load, effects)
    for name, iq in (("start", iq0), ("end", iq1)):
        if math.hypot(i_rest, iq) > limits.i_max:
            raise ValueError(f"the rest at the {name} needs {math.hypot(i_rest, iq):.4g} A (i_d {i_rest:g} A, "
                             f"i_q {iq:.4g} A against the load and detent), above i_max={limits.i_max:g} A")

    t_scale = _first_guess(d, m, limits, v_lim)[0]
    w_scale = abs(d) / t_scale
    sx = np.array([limits.i_max, limits.i_max, w_scale, abs(d)])  # state scales: i_d, i_q, omega, theta

    opti = ca.Opti()
    xs = opti.variable(4, n + 1)      # scaled states
    us = opti.variable(2, n + 1)      # scaled voltages v_d, v_q
    ts = opti.variable()              # scaled duration
    i_d, i_q = limits.i_max * xs[0, :], limits.i_max * xs[1, :]
    w, th = w_scale * xs[2, :], abs(d) * xs[3, :]
    v_d, v_q = v_lim * us[0, :], v_lim * us[1, :]
    tf = t_scale * ts
    accel = (m.Km * i_q - m.B * w - load + _plant_torque(ca, w, th, m, effects)) / m.J
    f = ca.vertcat((v_d - m.R * i_d + m.Nr * w * m.L * i_q) / m.L,
                   (v_q - m.R * i_q - m.Nr * w * m.L * i_d - m.Km * w) / m.L,
                   accel, w)
    scale = ca.DM(sx)
    fs = f / ca.repmat(scale, 1, n + 1)  # scaled derivatives
    h = tf / n
    opti.subject_to(xs[:, 1:] - xs[:, :-1] - 0.5 * h * (fs[:, 1:] + fs[:, :-1]) == 0)
    opti.subject_to(xs[0, :] ** 2 + xs[1, :] ** 2 <= 1)
    if voltage == "vector":
        opti.subject_to(us[0, :] ** 2 + us[1, :] ** 2 <= 1)
    else:
        phi = m.Nr * th
        va = us[0, :] * ca.cos(phi) - us[1, :] * ca.sin(phi)
        vb = us[0, :] * ca.sin(phi) + us[1, :] * ca.cos(phi)
        opti.subject_to(opti.bounded(-1, va, 1))
        opti.subject_to(opti.bounded(-1, vb, 1))
        opti.subject_to(opti.bounded(-1.5, us, 1.5))
    if not field_weakening:
        opti.subject_to(xs[0, :] == 0)
    if limits.speed_max is not None:
        opti.subject_to(opti.bounded(-limits.speed_max / w_scale, xs[2, :], limits.speed_max / w_scale))
    if limits.accel_max is not None:
        opti.subject_to(opti.bounded(-1, accel / limits.accel_max, 1))
    sign = 1.0 if d > 0 else -1.0
    opti.subject_to(xs[:, 0] == ca.DM([i_rest / limits.i_max, iq0 / limits.i_max, 0.0, 0.0]))
    opti.subject_to(xs[:, n] == ca.DM([i_rest / limits.i_max, iq1 / limits.i_max, 0.0, sign]))
    opti.subject_to(ts >= 1e-3)
    opti.minimize(ts)
    opti.solver("ipopt", dict(_IPOPT))
    sol = None
    for slower in (1.0,) if initial is not None else _SLOWER:  # first guesses, until IPOPT converges from one
        guess = _first_guess(d, m, limits, v_lim, slower)
        _set_initial(opti, xs, us, ts, d, m, limits, sx, v_lim, t_scale, n, i_rest, initial, guess)
        try:
            sol = opti.solve()
            break
        except RuntimeError:
            continue
    if sol is None:
        raise ValueError(f"IPOPT found no minimum-time move of {d} rad ({voltage} bus, field weakening "
                         f"{field_weakening}, grid {n}): {opti.stats().get('return_status')}")
    stats, get = sol.stats(), sol.value
    x = np.asarray(get(xs)) * sx[:, None]
    u = np.asarray(get(us)) * v_lim
    duration = float(get(ts)) * t_scale
    phi_n = m.Nr * x[3]
    return OptimalMove(distance=d, tf=duration, t=np.linspace(0.0, duration, n + 1), theta=x[3], omega=x[2],
                       i_d=x[0], i_q=x[1], v_d=u[0], v_q=u[1],
                       v_a=u[0] * np.cos(phi_n) - u[1] * np.sin(phi_n), v_b=u[0] * np.sin(phi_n) + u[1] * np.cos(phi_n),
                       grid=n, voltage=voltage, field_weakening=field_weakening, v_limit=v_lim, i_max=limits.i_max,
                       status=str(stats.get("return_status")), iterations=int(stats.get("iter_count", -1)))


def _set_initial(opti: Any, xs: Any, us: Any, ts: Any, d: float, m: MotorParams, limits: MotorLimits, sx: Array,
                 v_lim: float, t_scale: float, n: int, i_rest: float, initial: Optional[OptimalMove],
                 guess: tuple[float, float, float]) -> None:
    """The starting point: ``initial`` interpolated onto the grid, or the first-guess trapezoid ``guess``."""
    s = np.linspace(0.0, 1.0, n + 1)
    if initial is not None:
        tau = initial.t / initial.tf
        x = np.array([np.interp(s, tau, y) for y in (initial.i_d, initial.i_q, initial.omega, initial.theta)])
        u = np.array([np.interp(s, tau, y) for y in (initial.v_d, initial.v_q)])
        tf = initial.tf
    else:
        tf, a, w = guess
        t = s * tf
        t1 = w / a
        omega = np.minimum(np.minimum(a * t, w), a * (tf - t))
        accel = np.where(t < t1, a, np.where(t > tf - t1, -a, 0.0))
        theta = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * np.diff(t))])
        theta = d * theta / theta[-1]
        omega, accel = np.sign(d) * omega, np.sign(d) * accel
        i_q = np.clip((m.J * accel + m.B * omega) / m.Km, -limits.i_max, limits.i_max)
        i_d = np.full_like(s, i_rest)
        v_q = m.R * i_q + m.Km * omega + m.Nr * omega * m.L * i_d
        v_d = m.R * i_d - m.Nr * omega * m.L * i_q
        x, u = np.array([i_d, i_q, omega, theta]), np.array([v_d, v_q])
        norm = np.maximum(1.0, np.hypot(u[0], u[1]) / v_lim)
        u = u / norm
    opti.set_initial(xs, x / sx[:, None])
    opti.set_initial(us, u / v_lim)
    opti.set_initial(ts, tf / t_scale)


def grid_converged(distance: float, motor: MotorParams, limits: MotorLimits, *, grids: tuple[int, int] = (200, 400),
                   **options: Any) -> Converged:
    """The same problem on two grids, the fine one started from the coarse one (:func:`minimum_time`'s options).

    ``change`` is the relative change of the duration, the estimate of the coarse grid's error.
    """
    if not (isinstance(grids, tuple) and len(grids) == 2):
        raise InputError("grids", grids, f"grids={grids!r}: give two grid sizes (coarse, fine)")
    coarse_n, fine_n = _check_grid(grids[0]), _check_grid(grids[1])
    if fine_n <= coarse_n:
        raise InputError("grids", grids, f"grids={grids!r}: the second grid must be finer than the first")
    coarse = minimum_time(distance, motor, limits, grid=coarse_n, **options)
    # a grid the phase limit or the detent refined: the fine one doubles it
    fine_n = max(fine_n, 2 * coarse.grid) if coarse.grid > coarse_n else fine_n
    fine = minimum_time(distance, motor, limits, grid=min(fine_n, MAX_GRID), initial=coarse, **options)
    return Converged(coarse, fine, abs(fine.tf / coarse.tf - 1.0))
