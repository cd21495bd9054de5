r"""Pull-out torque against speed: the steady-state phasor equations of eq. (1) under a drive's current and voltage.

At a constant speed :math:`\omega` every quantity of eq. (1) is a phasor at the electrical frequency
:math:`\omega_e = N_r\omega`. In the rotor frame (:math:`i_{dq} = (i_a + j i_b)e^{-jN_r\theta}`, torque
:math:`K_m i_q`) the phase equations are

.. math::
    v_{dq} = Z\,i_{dq} + jK_m\omega,\qquad Z = R + j\omega_e L,

and a drive that holds the current-vector norm to :math:`I` (the peak of a sine phase current) on a bus that allows
each phase a sine of amplitude :math:`V` confines the current to two disks,

.. math:: |i_{dq}| \le I,\qquad |i_{dq} - c| \le V/|Z|,\quad c = -jK_m\omega/Z .

The shaft's pull-out torque is :math:`K_m \max i_q - B\omega` over what the drive can reach:

* ``"chopper"``: a current-mode step/dir driver at a set current. It puts :math:`I` at the commanded angle, the rotor
  lags by a load angle :math:`\delta` that the load sets, :math:`i_{dq} = I e^{j\delta}`, until the bus runs out;
  past that the bridges stay on and the current falls short of the set value. An open-loop rotor keeps in step on
  the rising side of its torque-angle curve, :math:`\delta \le 90` electrical degrees, i.e. :math:`i_d \ge 0`:
  the largest :math:`i_q` of the two disks with :math:`i_d \ge 0`, which is the :math:`i_d = 0` point (the voltage
  disk's centre has :math:`i_d < 0`). Past the corner speed the steady state also exists at
  :math:`\delta > 90` degrees, up to the ``"foc_weakening"`` torque, but the undamped rotor holds only a small
  part of it: the C engine's runs keep the step there with far less load (docs/curves.md).
* ``"foc_weakening"``: field-oriented control that chooses :math:`i_d` freely: the same set, the same largest
  :math:`i_q`, held stably by the loop.
* ``"foc"``: field-oriented control with :math:`i_d = 0`: :math:`i_q \le I` and
  :math:`(R i_q + K_m\omega)^2 + (\omega_e L i_q)^2 \le V^2`.

The voltage is the sine amplitude each H-bridge can give, :math:`V = v_{bus}` (the per-phase limit of
:class:`~flatstep.loop.drive.Drive`; ``voltage_factor`` scales it). A chopper whose bridges stay fully on in
saturation applies a square wave, whose fundamental is :math:`4v_{bus}/\pi`: ``voltage_factor`` up to
:data:`SQUARE_WAVE` covers that.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import InputError, check_choice, check_quantity
from .motor import MotorParams

if TYPE_CHECKING:  # the datasheet imports the motor, not this module
    from .datasheet import MotorModel

Array = NDArray[np.float64]
#: The drive kinds of :func:`pullout_torque` (module docstring).
DRIVE_KINDS = ("chopper", "foc", "foc_weakening")
#: The fundamental of a square wave over its amplitude, :math:`4/\pi`: a chopper's bridges fully on in saturation.
SQUARE_WAVE = 4.0 / math.pi
#: The largest electrical frequency a sampled drive commutates, as a fraction of its control rate: at least 10
#: samples per electrical period (a sine reference of 10 points, each 36 electrical degrees apart).
ELECTRICAL_FRACTION = 0.1


def _check_inputs(motor: MotorParams, drive_kind: str, v_bus: float, current: float, speeds: ArrayLike,
                  voltage_factor: float) -> tuple[float, float, Array]:
    """The checked voltage amplitude [V], current [A] and speeds [rad/s] (>= 0), or an InputError naming the value."""
    if not isinstance(motor, MotorParams):
        raise InputError("motor", motor, f"motor={motor!r} is not a MotorParams")
    check_choice("drive_kind", drive_kind, DRIVE_KINDS)
    v = check_quantity("v_bus", v_bus)
    i = check_quantity("current", current)
    k = check_quantity("scale", voltage_factor, as_name="voltage_factor")
    if not 0.5 <= k <= SQUARE_WAVE + 1e-12:
        raise InputError("voltage_factor", voltage_factor, f"voltage_factor={k!r} must be in [0.5, 4/pi]: the share "
                         "of v_bus the bridges give as a sine amplitude (1: a sine; 4/pi: a square wave)")
    w = np.asarray(speeds, dtype=float)
    if w.ndim > 1 or not np.isfinite(w).all() or (w < 0).any():
        raise InputError("speeds", speeds, "speeds must be finite speeds >= 0 [rad/s] (one value or a 1-D array)")
    return k * v, i, np.atleast_1d(w)


def _max_iq_two_disks(radius_i: float, center: NDArray[np.complex128], radius_v: Array) -> Array:
    """The largest imaginary part over {|z| <= radius_i} and {|z - center| <= radius_v}; -inf where they miss."""
    best = np.full(center.shape, -np.inf)
    top_i = 1j * radius_i  # the top of the current disk
    ok = np.abs(top_i - center) <= radius_v * (1 + 1e-12)
    best = np.where(ok, radius_i, best)
    top_v = center + 1j * radius_v  # the top of the voltage disk
    ok = np.abs(top_v) <= radius_i * (1 + 1e-12)
    best = np.maximum(best, np.where(ok, top_v.imag, -np.inf))
    d = np.abs(center)  # the circles' crossings (law of cosines along the line of centres)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (radius_i**2 - radius_v**2 + d**2) / (2 * d)
        h = np.sqrt(np.maximum(radius_i**2 - a**2, 0.0))
        u = center / d
        cross = (d > 0) & (d <= radius_i + radius_v) & (d >= np.abs(radius_i - radius_v))
        for sign in (1.0, -1.0):
            z = a * u + sign * 1j * h * u
            best = np.maximum(best, np.where(cross, z.imag, -np.inf))
    return best


def pullout_torque(motor: MotorParams, drive_kind: str, v_bus: float, current: float, speeds: ArrayLike, *,
                   voltage_factor: float = 1.0) -> Array:
    r"""The shaft's pull-out torque [N m] at each speed [rad/s] (module docstring), 0 where the drive cannot turn.

    Parameters
    ----------
    motor : MotorParams
        R, L, Km, B, Nr of eq. (1).
    drive_kind : {"chopper", "foc", "foc_weakening"}
        The drive (module docstring).
    v_bus : float
        The bus [V]: each phase's sine amplitude up to ``voltage_factor * v_bus``.
    current : float
        The current-vector norm :math:`I` the drive holds [A] (the peak of a sine phase current; a driver set to
        an RMS current :math:`I_{rms}` holds :math:`\sqrt 2 I_{rms}`).
    speeds : array_like
        Speeds >= 0 [rad/s].
    voltage_factor : float
        The sine amplitude per phase over ``v_bus``: 1 (default), up to :data:`SQUARE_WAVE`.

    Returns
    -------
    ndarray
        :math:`\max(0, K_m i_{q,max} - B\omega)` per speed.
    """
    V, Imax, w = _check_inputs(motor, drive_kind, v_bus, current, speeds, voltage_factor)
    m = motor
    we = m.Nr * w
    Z = m.R + 1j * we * m.L
    absZ = np.abs(Z)
    if drive_kind in ("foc", "chopper"):
        a = absZ**2
        b = 2 * m.R * m.Km * w
        c = (m.Km * w) ** 2 - V**2
        disc = b * b - 4 * a * c
        with np.errstate(invalid="ignore"):
            iq = np.where(disc >= 0, (-b + np.sqrt(np.maximum(disc, 0.0))) / (2 * a), -np.inf)
        iq = np.minimum(iq, Imax)
    else:
        iq = _max_iq_two_disks(Imax, -1j * m.Km * w / Z, V / absZ)
    torque = m.Km * iq - m.B * w
    return np.where(np.isfinite(torque), np.maximum(torque, 0.0), 0.0)


def corner_speed(motor: MotorParams, v_bus: float, current: float, *, voltage_factor: float = 1.0) -> float:
    r"""The highest speed at which the drive still holds the full current in quadrature [rad/s].

    .. math:: (R I + K_m\omega)^2 + (N_r\omega L I)^2 = V^2
    """
    V, Imax, _ = _check_inputs(motor, "foc", v_bus, current, 0.0, voltage_factor)
    m = motor
    a = m.Km**2 + (m.Nr * m.L * Imax) ** 2
    b = 2 * m.R * Imax * m.Km
    c = (m.R * Imax) ** 2 - V**2
    if c >= 0:
        return 0.0  # the bus cannot even drive the current at rest
    return float((-b + math.sqrt(b * b - 4 * a * c)) / (2 * a))


def top_speed(motor: MotorParams, drive_kind: str, v_bus: float, current: float, load: float, *,
              voltage_factor: float = 1.0, w_max: Optional[float] = None) -> float:
    """The highest speed [rad/s] whose pull-out torque is at least ``load`` [N m] (0 if not even at rest).

    With no load, where the torque ends (below 1e-6 of its value at rest).

    Searched from rest upwards on a fine grid, then by bisection on the crossing; ``w_max`` bounds the search
    (default: the no-load speed of the bus, ``voltage_factor v_bus / Km`` times 20).
    """
    load = check_quantity("torque_amplitude", load, as_name="load")
    V, _, _ = _check_inputs(motor, drive_kind, v_bus, current, 0.0, voltage_factor)
    top = 20.0 * V / motor.Km if w_max is None else check_quantity("speed", w_max, as_name="w_max")
    grid = np.linspace(0.0, top, 4001)
    t = pullout_torque(motor, drive_kind, v_bus, current, grid, voltage_factor=voltage_factor)
    load = max(load, 1e-6 * float(t[0]))  # no load: where the torque ends
    below = np.flatnonzero(t < load)
    if below.size == 0:
        return float(top)
    k = int(below[0])
    if k == 0:
        return 0.0
    lo, hi = float(grid[k - 1]), float(grid[k])
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if pullout_torque(motor, drive_kind, v_bus, current, mid, voltage_factor=voltage_factor)[0] >= load:
            lo = mid
        else:
            hi = mid
    return lo


def electrical_speed_limit(motor: MotorParams, control_rate: float, fraction: float = ELECTRICAL_FRACTION) -> float:
    r"""The speed whose electrical frequency is ``fraction`` of the control rate [rad/s]: :math:`2\pi f_c k/N_r`."""
    rate = check_quantity("rate", control_rate, as_name="control_rate")
    k = check_quantity("fraction", fraction)
    return 2.0 * math.pi * rate * k / motor.Nr


@dataclass(frozen=True)
class PulloutCurve:
    """A pull-out curve and its landmarks (:func:`pullout_curve`).

    Parameters
    ----------
    drive_kind : str
        The drive (:data:`DRIVE_KINDS`).
    v_bus, current : float
        The bus [V] and the current-vector norm [A].
    speeds, torque : ndarray
        Speeds [rad/s] and the pull-out torque at each [N m].
    corner_speed : float
        :func:`corner_speed` [rad/s].
    """

    drive_kind: str
    v_bus: float
    current: float
    speeds: Array
    torque: Array
    corner_speed: float

    @property
    def rpm(self) -> Array:
        """The speeds in revolutions per minute."""
        return self.speeds * 60.0 / (2.0 * math.pi)


def pullout_curve(motor: MotorParams, drive_kind: str, v_bus: float, current: float, speeds: ArrayLike, *,
                  voltage_factor: float = 1.0) -> PulloutCurve:
    """The pull-out torque at ``speeds`` with the corner speed (:func:`pullout_torque`, :func:`corner_speed`)."""
    torque = pullout_torque(motor, drive_kind, v_bus, current, speeds, voltage_factor=voltage_factor)
    return PulloutCurve(drive_kind, float(v_bus), float(current), np.atleast_1d(np.asarray(speeds, dtype=float)),
                        torque, corner_speed(motor, v_bus, current, voltage_factor=voltage_factor))


#: The fundamental of :class:`~flatstep.loop.drive.Drive`'s saturation over ``v_bus``: a vector scaled onto the
#: square :math:`|v_a|, |v_b| \le v_{bus}` keeps its direction, and its mean radius over a turn is
#: :math:`(4/\pi)\ln\tan(3\pi/8) = 1.1222`.
SQUARE_VECTOR = 4.0 / math.pi * math.log(math.tan(3.0 * math.pi / 8.0))


def convention_band(model: "MotorModel", drive_kind: str, v_bus: float, set_current: float, speeds: ArrayLike, *,
                    voltage_factor: float = 1.0) -> tuple[Array, Array]:
    r"""The lowest and highest pull-out torque [N m] the datasheet's conventions leave open, per speed.

    A datasheet's :math:`K_m = T_2/\rho_r` (:func:`flatstep.model.datasheet.torque_constant`) depends on whether its
    rated current is RMS (or DC) or peak (:math:`\sqrt 2` apart) and on its holding torque's tolerance (typical:
    +-10 %; a minimum: 0 to +20 %); a driver set to ``set_current`` holds :math:`\rho = \sqrt 2 I` if the setting
    is RMS (or a full-step DC current), :math:`\rho = I` if it is the peak. Every combination (the tolerance on 9
    points) is evaluated with the model's R, L, B, Nr, and the envelope returned.
    """
    from .datasheet import HOLDING_TORQUE_TOLERANCE, torque_constant

    sheet = model.datasheet
    rating = sheet.get("holding_torque_rating", "typical")
    low, high = (1.0, 1.2) if rating == "minimum" else (1.0 - HOLDING_TORQUE_TOLERANCE, 1.0 + HOLDING_TORQUE_TOLERANCE)
    scales = np.linspace(low, high, 9)  # the torque is not monotone in Km at speed (more Km, more back-EMF)
    current = check_quantity("current", set_current, as_name="set_current")
    curves = []
    for convention in ("rms", "peak"):
        Km, _ = torque_constant(sheet["holding_torque"], sheet["rated_current"], current=convention,
                                holding_torque_phases=sheet.get("holding_torque_phases", 2))
        for scale in scales:
            motor = model.params.replace(Km=Km * float(scale))
            for rho in (current, math.sqrt(2.0) * current):
                curves.append(pullout_torque(motor, drive_kind, v_bus, rho, speeds, voltage_factor=voltage_factor))
    stack = np.array(curves)
    return stack.min(axis=0), stack.max(axis=0)
