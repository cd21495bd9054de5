r"""What a law's builder gets from a run: the model, the plan, the drive's facts, and the design rules.

:func:`flatstep.control.make_controller` turns its arguments into one :class:`BuildContext` and hands it, with the
:class:`~flatstep.control.spec.ControllerSpec`, to the law's builder (each law file's ``from_spec``). The baselines
take their bandwidths from the same design quantities :func:`flatstep.loop.design.design_gains` uses for the sliding
controller on that drive:

* inner (current) bandwidth :math:`\lambda = 0.3/T_s` (0.15/T_s with a computation delay), the sliding
  controller's :math:`W/\epsilon`;
* outer (position) bandwidth :math:`\omega_n = \lambda/4`, its error dynamics' natural frequency, with
  :math:`\xi = 0.9`;
* the same bus voltage for the anti-windup, the same measurement (observer or encoder) as the scenario's.

``bandwidth_scale`` multiplies every bandwidth of a baseline. Two more settings make every law's gains free:
``lambda_ts`` replaces the rule's :math:`\lambda T_s` (the current loop's speed: a baseline's current bandwidth
:math:`\lambda`, a sliding law's boundary layers :math:`W/\epsilon`), and ``law_gains`` gives a law's gains by
name over its rule (the fields of its gains class: ``CascadeGains``'s ``k_theta``, say).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any, Mapping, Optional, TypeVar

from ..model.motor import MotorParams
from ..model.torque_model import NO_TORQUES, TorqueModel
from ..plan.d_current import ZERO_D_CURRENT, DCurrentPlan
from ..plan.loss_aware import LossAwareRho
from ..plan.protocol import Plan
from ..validate import InputError, check_finite, check_positive
from .smc import SMCGains

#: The design rules of flatstep.loop.design (docs/drive.md): the boundary layer's bandwidth times the control period
#: (halved with a computation delay), the error dynamics' natural frequency over it and their damping, the margin
#: of the reaching gains over the disturbance bound.
LAMBDA_TS = 0.3
LAMBDA_TS_DELAYED = 0.15
WN_OVER_LAMBDA = 0.25
XI = 0.9
W_MARGIN = 2.0
#: A gains class (a dataclass) a law builds from its rule and ``law_gains``.
G = TypeVar("G")


def check_lambda_ts(value: Any) -> float:
    """The current loop's speed times the control period, in (0, 1] (the error decays by 1 - lambda Ts a period)."""
    lam_ts = check_positive("lambda_ts", value)
    if lam_ts > 1.0:
        raise InputError("lambda_ts", value, f"lambda_ts={value!r} must be in (0, 1]: the current loop's error "
                         "decays by 1 - lambda Ts a period (0.3 is the design rule)")
    return lam_ts


def bandwidths(control_period: float, compute_delay: bool = False) -> tuple[float, float]:
    r"""``(lambda, omega_n)`` [rad/s] for a control period.

    .. math:: \lambda T_s = 0.3 \text{ (0.15 delayed)},\qquad \omega_n = \lambda/4
    """
    Ts = check_positive("control_period", control_period, unit=" s")
    lam = (LAMBDA_TS_DELAYED if compute_delay else LAMBDA_TS) / Ts
    return lam, WN_OVER_LAMBDA * lam


@dataclass(frozen=True)
class BuildContext:
    """Everything a law's builder may read besides its spec.

    Parameters
    ----------
    motor : MotorParams
        The controller's nominal model.
    plan : Plan
        The move.
    measurement : str
        Where speed and acceleration come from (``"ideal"``, ``"model"``, ``"observer"``).
    control_period : float or None
        Ts [s]; ``None`` for continuous time (only laws and options that do not need it).
    smc_gains : SMCGains
        The sliding laws' gains (designed or given).
    v_limit : float
        The bus voltage the anti-windup knows [V] (``inf``: none).
    bandwidth_scale : float
        Multiplies every bandwidth of a baseline.
    compute_delay : bool
        One control period between measuring and applying (halves the baselines' bandwidths).
    torques : TorqueModel
        The torques the law knows beyond eq. (1): the run's, when an option that needs them is on, else none.
    d_current : DCurrentPlan
        The planned d current of the d-q laws.
    loss_aware : LossAwareRho or None
        The loss-aware rho*(t), when one is given.
    lambda_ts : float or None
        The current loop's speed times Ts, in (0, 1] (``None``: the rule's 0.3, 0.15 delayed).
    law_gains : mapping
        The law's gains by name, over its rule (empty: the rule's).
    angle_step : float
        One count of the angle the law reads [rad] (0: an exact angle, or none known).
    """

    motor: MotorParams
    plan: Plan
    measurement: str
    control_period: Optional[float] = None
    smc_gains: SMCGains = SMCGains()
    v_limit: float = math.inf
    bandwidth_scale: float = 1.0
    compute_delay: bool = False
    torques: TorqueModel = NO_TORQUES
    d_current: DCurrentPlan = ZERO_D_CURRENT
    loss_aware: Optional[LossAwareRho] = None
    lambda_ts: Optional[float] = None
    law_gains: Mapping[str, Any] = field(default_factory=dict)
    angle_step: float = 0.0

    def __post_init__(self) -> None:
        step = check_finite("angle_step", self.angle_step)
        if step < 0:
            raise InputError("angle_step", step, f"angle_step={step!r} rad must be >= 0 (one encoder count; 0: exact)")
        object.__setattr__(self, "angle_step", step)
        if self.lambda_ts is not None:
            object.__setattr__(self, "lambda_ts", check_lambda_ts(self.lambda_ts))
        if not isinstance(self.law_gains, Mapping):
            raise InputError("law_gains", self.law_gains, f"law_gains={self.law_gains!r} is not a mapping of gain "
                             "names to values")

    @property
    def period(self) -> float:
        """The control period [s] (make_controller has checked that a law needing it has one)."""
        if self.control_period is None:
            raise ValueError("this controller advances by the control period: give control_period "
                             "([drive] control_rate)")
        return self.control_period

    def bandwidths(self) -> tuple[float, float]:
        r"""The baselines' ``(lambda, omega_n)`` [rad/s].

        :func:`bandwidths` (or ``lambda = lambda_ts / Ts``, ``omega_n = lambda / 4`` with ``lambda_ts``), times
        ``bandwidth_scale``.
        """
        scale = check_positive("bandwidth_scale", self.bandwidth_scale)
        lam, wn = bandwidths(self.period, self.compute_delay)
        if self.lambda_ts is not None:
            lam = self.lambda_ts / self.period
            wn = WN_OVER_LAMBDA * lam
        return scale * lam, scale * wn

    def gains(self, kind: type[G], rule: Mapping[str, Any], fixed: Mapping[str, Any] = {}) -> G:
        """The law's gains: ``kind(**rule)`` with ``law_gains`` over the rule and the spec's ``fixed`` over both.

        Raises
        ------
        InputError
            For a name in ``law_gains`` that is not a field of ``kind`` (or is set by the spec's options).
        """
        return kind(**{**rule, **self.checked_gains(kind, fixed), **fixed})

    def sliding_gains(self) -> SMCGains:
        r"""The sliding laws' gains: ``smc_gains``, ``law_gains`` over them, and the boundary layers of ``lambda_ts``.

        With ``lambda_ts``, :math:`\epsilon_i = W_i/\lambda` for :math:`\lambda` = ``lambda_ts / Ts``, so that each
        boundary layer's bandwidth :math:`W_i/\epsilon_i` is the current loop's speed asked for.
        """
        g = replace(self.smc_gains, **self.checked_gains(SMCGains)) if self.law_gains else self.smc_gains
        if self.lambda_ts is None:
            return g
        lam = self.lambda_ts / self.period
        return replace(g, eps1=g.W1 / lam, eps2=g.W2 / lam)

    def checked_gains(self, kind: type, fixed: Mapping[str, Any] = {}) -> Mapping[str, Any]:
        """``law_gains``, refused by name if one is not a field of ``kind`` or is one of ``fixed``."""
        valid = [f.name for f in fields(kind) if f.name not in fixed]
        for name, value in self.law_gains.items():
            if name not in valid:
                raise InputError(name, value, f"{name}={value!r} is not a gain of this law ({kind.__name__}); "
                                 f"valid: {valid}")
        return self.law_gains
