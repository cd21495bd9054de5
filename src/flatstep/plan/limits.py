r"""The motor's limits on a plan, and a plan's worst margins against them through the flat maps.

A plan of the flat outputs fixes, at every instant, the currents and voltages the motor needs
(:func:`flatstep.model.flat.flat_to_state`: R i, L di/dt, the back EMF and the reactance).
:func:`~flatstep.plan.margins.plan_margins` samples a plan and reports how much of each limit it uses:

* ``voltage``: the largest voltage magnitude :math:`\sqrt{v_a^2 + v_b^2}` over the bus voltage: each phase
  voltage reaches it once per electrical turn, so it bounds them at any rotor angle (and does not depend on
  where the samples fall on the turn);
* ``current``: the largest current magnitude :math:`\rho` over ``i_max``;
* ``torque_angle``: the largest :math:`|\cos\delta| = |J\ddot\theta + B\dot\theta| / K_m\rho` over
  :math:`\sin` of ``torque_angle_max`` (the paper's law is singular at :math:`|\cos\delta| = 1`);
* ``speed``, ``acceleration``, ``jerk``: the peaks over the optional caps.

A plan is feasible when every ratio is at most 1.

**Limits for a drive** (:meth:`MotorLimits.for_drive`). The defaults of :class:`MotorLimits` suit the two presets;
for another motor and drive the limits follow from the motor, the bus, the control rate, the encoder and the
relative uncertainty :math:`\delta` of the model (R, L, Km, J), each rule with its reason:

* ``i_hold`` :math:`= 0.3\,i_{max}` (:data:`HOLD_FRACTION`): the law needs :math:`\rho > 0` at rest (its angle is
  undefined at zero current), and the magnetic stiffness :math:`K_m N_r i_{hold}` then holds the rotor in place;
* ``speed_corner`` :math:`= R/(N_r L)`: the electrical corner, where the winding's reactance at the electrical
  frequency :math:`N_r\omega` equals its resistance; above it the across-axis current costs more voltage in
  reactance than in copper;
* ``torque_angle_max`` :math:`= \arcsin\big(s_\tau (1 - \delta)/(1 + \delta)\big) - N_r q/2`
  (:data:`TORQUE_SHARE` :math:`s_\tau`): a plant whose Km is :math:`\delta` low and J :math:`\delta` high needs
  :math:`(1 + \delta)/(1 - \delta)` times the planned torque current, and the feedback a share on top; an encoder
  count :math:`q` misplaces the commutation angle by up to :math:`N_r q/2` electrical radians;
* ``v_use`` :math:`= s_v/(1 + \delta)` (:data:`VOLTAGE_SHARE` :math:`s_v`): every voltage term (R i, the back EMF
  :math:`K_m\omega`, the reactance :math:`N_r\omega L i`) grows with its parameter's error, and the feedback needs
  headroom above the feedforward;
* ``speed_max`` :math:`= a_{max} f_c / N_r` (:data:`COMMUTATION_ANGLE` :math:`a_{max}`): a sampled drive holds its
  voltage over a control period while the electrical angle turns by :math:`N_r\omega T_s`; beyond
  :math:`a_{max}` electrical radians per period (:math:`2\pi/a_{max}` periods per electrical turn) the law
  commutates too late to hold the torque angle. With an encoder, also at most :data:`ENCODER_COUNTS_PER_PERIOD`
  counts per period, so that the observer's speed and the commutation angle stay within a few counts.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.motor import MotorParams
from ..validate import InputError, check_finite, check_positive, check_quantity

Array = NDArray[np.float64]
#: Samples per segment of a margin check.
SAMPLES_PER_SEGMENT = 24
#: ``i_hold`` over ``i_max`` (:meth:`MotorLimits.for_drive`).
HOLD_FRACTION = 0.3
#: The share of the worst-case torque current the plan may ask for, the rest is the feedback's.
TORQUE_SHARE = 0.9
#: The share of the worst-case bus headroom the plan's feedforward may use, the rest is the feedback's.
VOLTAGE_SHARE = 0.9
#: The largest electrical angle [rad] the rotor may turn in one control period (about 42 periods per electrical
#: turn at 0.15); measured on a 20 kHz drive with a 4000-count encoder (docs/planning.md).
COMMUTATION_ANGLE = 0.15
#: The most encoder counts the rotor may pass in one control period.
ENCODER_COUNTS_PER_PERIOD = 64


@dataclass(frozen=True)
class MotorLimits:
    r"""The bus, the current and the law's torque-angle margin, and optional speed, acceleration and jerk caps.

    Parameters
    ----------
    v_bus : float
        Bus voltage [V]: each phase voltage must stay within +-v_bus.
    i_max : float
        Largest current-vector magnitude rho [A].
    i_hold : float
        The current across the torque axis at rest, :math:`\rho\sin\delta` [A], > 0 (the holding current).
    i_run : float, optional
        The current across the torque axis at speed [A], in (0, i_hold]; ``None``: i_hold throughout. Less of
        it lowers the reactance voltage :math:`N_r\omega L i_d` (the plan of rho*, :meth:`across`).
    speed_corner : float
        The speed [rad/s] at which the across-axis floor is halfway from i_hold to i_run.
    torque_angle_max : float
        Largest torque angle the plan may ask for, :math:`\pi/2 - \delta` [rad], in (0, pi/2).
    v_use : float
        Fraction of v_bus the plan's feedforward may use, in (0, 1]; the rest is the controller's to correct.
    speed_max, accel_max, jerk_max : float, optional
        Caps [rad/s, rad/s^2, rad/s^3].
    uncertainty : float
        The relative error :math:`\delta` of R, L, Km and J the plan must leave room for, in [0, 0.5): the check on
        the drive (:mod:`flatstep.studies.verify`) runs the plan on the nominal plant and the :math:`2^4` corners of
        :math:`\pm\delta` (0: the nominal plant only); :meth:`for_drive` derives the margins from it.

    Notes
    -----
    Every field is a number (not a bool, not a string) in its range of :mod:`flatstep.validate.ranges`:
    ``v_bus`` that of ``v_bus``, the currents that of ``current``, ``speed_corner`` and ``speed_max`` that of
    ``speed``, ``accel_max`` ``acceleration``, ``jerk_max`` ``jerk``, ``torque_angle_max`` ``torque_angle`` and
    ``v_use`` ``fraction``, ``uncertainty`` ``relative``; an :class:`~flatstep.validate.InputError` names the field
    otherwise.
    """

    v_bus: float
    i_max: float
    i_hold: float = 0.3
    i_run: Optional[float] = None
    speed_corner: float = 10.0
    torque_angle_max: float = 1.2
    v_use: float = 0.9
    speed_max: Optional[float] = None
    accel_max: Optional[float] = None
    jerk_max: Optional[float] = None
    uncertainty: float = 0.1

    def __post_init__(self) -> None:
        # every field in its range of flatstep.validate.ranges (an InputError naming the field otherwise)
        for name, kind in (("v_bus", "v_bus"), ("i_max", "current"), ("i_hold", "current"),
                           ("speed_corner", "speed"), ("torque_angle_max", "torque_angle"), ("v_use", "fraction"),
                           ("uncertainty", "relative")):
            object.__setattr__(self, name, check_quantity(kind, getattr(self, name), as_name=name))
        for name, kind in (("i_run", "current"), ("speed_max", "speed"), ("accel_max", "acceleration"),
                           ("jerk_max", "jerk")):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, check_quantity(kind, getattr(self, name), as_name=name))
        if self.i_hold >= self.i_max:
            raise InputError("i_hold", self.i_hold, f"i_hold={self.i_hold!r} A must be below i_max={self.i_max!r} A, "
                             "or no torque is left")
        if self.i_run is not None and self.i_run > self.i_hold:
            raise InputError("i_run", self.i_run, f"i_run={self.i_run!r} A must be in (0, i_hold={self.i_hold!r} A]")

    @classmethod
    def for_drive(cls, motor: MotorParams, *, v_bus: float, i_max: float, control_rate: float,
                  encoder_counts: Optional[int] = None, uncertainty: float = 0.1) -> "MotorLimits":
        r"""The limits of ``motor`` on a drive, each derived by a rule of the module docstring.

        Parameters
        ----------
        motor : MotorParams
            The motor's nominal model.
        v_bus : float
            The drive's bus voltage [V].
        i_max : float
            The largest current magnitude [A] (the motor's rated peak phase current, or the drive's, the lower).
        control_rate : float
            The drive's control rate [Hz].
        encoder_counts : int, optional
            The encoder's counts per revolution (``None``: an exact angle).
        uncertainty : float
            The relative error of R, L, Km and J the plan must leave room for, in [0, 0.5).

        Raises
        ------
        ValueError
            A value out of range, or an encoder so coarse that no torque angle is left.
        """
        v_bus = check_positive("v_bus", v_bus, unit=" V")
        i_max = check_positive("i_max", i_max, unit=" A")
        rate = check_positive("control_rate", control_rate, unit=" Hz")
        delta = check_finite("uncertainty", uncertainty)
        if not 0 <= delta < 0.5:
            raise ValueError(f"uncertainty={delta!r} must be in [0, 0.5): the relative error of R, L, Km and J")
        count = 0.0 if encoder_counts is None else 2 * math.pi / check_positive("encoder_counts", encoder_counts)
        angle = math.asin(TORQUE_SHARE * (1 - delta) / (1 + delta)) - motor.Nr * count / 2
        if angle <= 0.05:
            raise ValueError(f"encoder_counts={encoder_counts!r}: one count is {motor.Nr * count:.3g} electrical rad, "
                             "which leaves no torque angle for the plan; use a finer encoder")
        speed = COMMUTATION_ANGLE * rate / motor.Nr
        if count:
            speed = min(speed, ENCODER_COUNTS_PER_PERIOD * count * rate)
        return cls(v_bus=v_bus, i_max=i_max, i_hold=HOLD_FRACTION * i_max, speed_corner=motor.R / (motor.Nr * motor.L),
                   torque_angle_max=angle, v_use=VOLTAGE_SHARE / (1 + delta), speed_max=speed, uncertainty=delta)

    def floor(self, omega: ArrayLike) -> Array:
        """The across-axis current without torque: i_hold at rest, towards i_run at speed."""
        w = np.abs(np.asarray(omega, dtype=float))
        run = self.i_hold if self.i_run is None else self.i_run
        return run + (self.i_hold - run) / (1.0 + (w / self.speed_corner) ** 2)

    def across(self, iq: ArrayLike, omega: ArrayLike) -> Array:
        r"""The planned current across the torque axis for the torque current ``iq`` at speed ``omega``.

        .. math:: i_d = \sqrt{f(\omega)^2 + (i_q\cot\alpha_{max})^2}

        smooth in both, and never below :math:`|i_q|\cot\alpha_{max}`: the torque angle stays below
        ``torque_angle_max``.
        """
        return np.hypot(self.floor(omega), np.asarray(iq, dtype=float) / math.tan(self.torque_angle_max))

    def rho(self, iq: ArrayLike, omega: ArrayLike) -> Array:
        """The planned current magnitude rho* = hypot(iq, across(iq, omega))."""
        return np.hypot(np.asarray(iq, dtype=float), self.across(iq, omega))

    def iq_cap(self, omega: ArrayLike) -> Array:
        """The largest torque current within i_max at speed ``omega``."""
        room = np.sqrt(np.maximum(self.i_max**2 - self.floor(omega) ** 2, 0.0))
        return room * math.sin(self.torque_angle_max)

    def as_dict(self) -> dict[str, Optional[float]]:
        """The limits by name, for JSON."""
        return asdict(self)

