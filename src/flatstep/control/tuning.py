r"""Every controller built for one drive: the sliding controller with its gains, the baselines tuned by rule.

The baselines take their bandwidths from the same design quantities :func:`flatstep.loop.design.design_gains`
uses for the sliding controller on that drive, so that none is faster or slower by choice:

* inner (current) bandwidth :math:`\lambda = 0.3/T_s` (0.15/T_s with a computation delay), the sliding
  controller's :math:`W/\epsilon`;
* outer (position) bandwidth :math:`\omega_n = \lambda/4`, its error dynamics' natural frequency, with
  :math:`\xi = 0.9`;
* the same bus voltage for the anti-windup, the same measurement (observer or encoder) as the scenario's.

``bandwidth_scale`` multiplies every bandwidth of a baseline; docs/comparison.md runs 0.5 and 2 to show
that none of them is crippled by the rule (halving or doubling does not make it much better).
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Optional, Union

from ..model.motor import MotorParams
from ..model.torque_model import NO_TORQUES, TorqueModel
from ..plan.d_current import ZERO_D_CURRENT, DCurrentPlan
from ..plan.loss_aware import LossAwareRho
from ..plan.protocol import Plan
from ..validate import check_positive
from .cascade import CascadeFOC, CascadeGains
from .dq_smc import DQFlatnessSMC, DQIntegral, DQKmAdaptation
from .exact_linearization import ExactLinearization, LinearizationGains
from .microstep import MicrostepGains, Microstepping
from .smc import FlatnessSMC, SMCGains
from .spec import ALIASES, ControllerSpec

#: The controllers a scenario can name by their historical type names (``[controller] type``), the paper's first;
#: each is a :class:`~flatstep.control.spec.ControllerSpec` (:data:`~flatstep.control.spec.ALIASES`), and any other
#: valid combination of a law and its options is named ``law+option+...``. The ``_ff`` types know the scenario's
#: torque model (``[feedforward]``): the flatness laws' feedforward, the cascade's anti-cogging.
CONTROLLER_TYPES = tuple(ALIASES)
#: Short labels for tables and figures (:func:`label` for any name).
LABELS = {"smc": "flatness + SMC", "microstep": "open-loop microstep", "cascade": "cascaded PID (FOC)",
          "exact_linearization": "exact linearization", "dq_smc": "flatness d-q + SMC",
          "smc_ff": "flatness + SMC + ff", "dq_smc_ff": "flatness d-q SMC + ff",
          "cascade_ff": "cascade + anti-cogging", "cascade_model": "cascade + model obs.",
          "smc_la": "flatness + SMC, rho(t)", "smc_la_ff": "flatness rho(t) + ff",
          "dq_smc_i": "flatness d-q SMC + I", "dq_smc_i_ff": "flatness d-q SMC+I+ff",
          "smc_ff_hold": "flatness SMC+ff, hold", "dq_smc_i_ff_km": "flatness d-q I+ff+Km"}
#: The types whose gains are the scenario's :class:`~flatstep.control.smc.SMCGains` (not tuned by rule).
SMC_TYPES = tuple(k for k, s in ALIASES.items() if s.sliding)
#: The flatness types that can run in continuous time (no integral or estimate advancing by the control period).
CONTINUOUS_TYPES = tuple(k for k, s in ALIASES.items() if s.continuous)
#: The types that need a torque model.
FEEDFORWARD_TYPES = tuple(k for k, s in ALIASES.items() if s.needs_torques)
#: The design rules of flatstep.loop.design (docs/drive.md): the boundary layer's bandwidth times the control period
#: (halved with a computation delay), the error dynamics' natural frequency over it and their damping, the margin
#: of the reaching gains over the disturbance bound.
LAMBDA_TS = 0.3
LAMBDA_TS_DELAYED = 0.15
WN_OVER_LAMBDA = 0.25
XI = 0.9
W_MARGIN = 2.0
#: The damping ratio of the ``smc_ff_hold`` type's detent hold when the scenario's gains give none: critical
#: damping of the magnetic spring (docs/comparison.md, "At rest on the paper's move").
REST_HOLD_DAMPING = 1.0
#: The sliding controller's default gains, the paper's.
_PAPER_SMC_GAINS = SMCGains()
#: What :func:`make_controller` returns.
AnyController = Union[FlatnessSMC, DQFlatnessSMC, Microstepping, CascadeFOC, ExactLinearization]


def label(kind: str) -> str:
    """The label of a controller name (:data:`LABELS`, or the spec's own for a ``law+option+...`` name)."""
    return LABELS.get(kind) or ControllerSpec.parse(kind).label()


def bandwidths(control_period: float, compute_delay: bool = False) -> tuple[float, float]:
    r"""``(lambda, omega_n)`` [rad/s] for a control period.

    .. math:: \lambda T_s = 0.3 \text{ (0.15 delayed)},\qquad \omega_n = \lambda/4
    """
    Ts = check_positive("control_period", control_period, unit=" s")
    lam = (LAMBDA_TS_DELAYED if compute_delay else LAMBDA_TS) / Ts
    return lam, WN_OVER_LAMBDA * lam


def make_controller(kind: str, motor: MotorParams, plan: Plan, *, control_period: float | None,
                    measurement: str, smc_gains: SMCGains = _PAPER_SMC_GAINS, v_limit: float = math.inf,
                    bandwidth_scale: float = 1.0, compute_delay: bool = False,
                    torques: Optional[TorqueModel] = None,
                    d_current: DCurrentPlan = ZERO_D_CURRENT,
                    loss_aware: Optional[LossAwareRho] = None) -> AnyController:
    """The controller ``kind`` (one of :data:`CONTROLLER_TYPES`) for this motor model, plan and drive.

    ``smc`` is :class:`~flatstep.control.smc.FlatnessSMC` and ``dq_smc``
    :class:`~flatstep.control.dq_smc.DQFlatnessSMC`, both with ``smc_gains`` (the scenario's, designed or given);
    the baselines are tuned by the rules above and need ``control_period``. ``smc_ff``, ``dq_smc_ff`` and ``cascade_ff``
    are the same laws with the known ``torques`` (required for them, read by no other type), whose observer shares
    them except the cascade's (anti-cogging as firmware does it); ``cascade_model`` gives them to its observer too.
    The d-q flatness types track the planned ``d_current``; ``smc_la`` and ``smc_la_ff`` are the paper's law on the
    ``loss_aware`` rho*(t) (:mod:`flatstep.plan.loss_aware`; default ``LossAwareRho.for_plan(plan)``).
    ``smc_ff_hold`` is ``smc_ff`` with the detent hold from tf on (``smc_gains.hold_damping``, or
    :data:`REST_HOLD_DAMPING`), turned by the known torques' load angle on the target.
    ``dq_smc_i`` and ``dq_smc_i_ff`` are the d-q law with integral action on ``s2``
    (:meth:`~flatstep.control.dq_smc.DQIntegral.designed`: its pole at ``omega_n/4`` as the cascade's velocity
    integral, held while the bus ``v_limit`` limits); they need ``control_period``. ``dq_smc_i_ff_km`` is
    ``dq_smc_i_ff`` with the online estimate of ``Km`` (:meth:`~flatstep.control.dq_smc.DQKmAdaptation.designed`:
    at the integral's rate, held as the integral is).
    """
    spec = ControllerSpec.parse(kind, "controller type")
    if spec.needs_torques and torques is None:
        raise ValueError(f"controller type {kind!r} needs the torques it knows beyond eq. (1): give a TorqueModel "
                         "(a [feedforward] table in a scenario file), or use the type without feedforward")
    known = torques if spec.needs_torques and torques is not None else NO_TORQUES
    if spec.law == "smc":
        gains = smc_gains
        if spec.hold and smc_gains.hold_damping is None:
            gains = replace(smc_gains, hold_damping=REST_HOLD_DAMPING)
        return FlatnessSMC(motor, plan, gains, measurement, torques=known,
                           loss_aware=(loss_aware or LossAwareRho.for_plan(plan)) if spec.rho_plan == "loss_aware"
                           else None)
    if spec.law == "dq_smc" and not spec.integral:
        return DQFlatnessSMC(motor, plan, smc_gains, measurement, torques=known, d_current=d_current)
    if control_period is None:
        raise ValueError(f"controller type {kind!r} is tuned from the control period (lambda = 0.3/Ts): give one "
                         f"([drive] control_rate); only the flatness types {CONTINUOUS_TYPES} have gains of their own "
                         "for continuous time")
    if spec.law == "dq_smc":
        return DQFlatnessSMC(motor, plan, smc_gains, measurement, torques=known, d_current=d_current,
                             integral=DQIntegral.designed(smc_gains, control_period, v_limit),
                             adaptation=DQKmAdaptation.designed(motor, plan, smc_gains, control_period, v_limit)
                             if spec.km_estimate else None)
    scale = check_positive("bandwidth_scale", bandwidth_scale)
    lam, wn = (scale * w for w in bandwidths(control_period, compute_delay))
    if spec.law == "microstep":
        return Microstepping(motor, plan, MicrostepGains(lam), control_period=control_period,
                             measurement=measurement, v_limit=v_limit)
    if spec.law == "cascade":
        return CascadeFOC(motor, plan, CascadeGains(current_bandwidth=lam, position_bandwidth=wn),
                          control_period=control_period, measurement=measurement, v_limit=v_limit, torques=known,
                          model_observer=spec.observer_torques)
    return ExactLinearization(motor, plan, LinearizationGains(wn=wn, xi=XI, p3=lam, pd=lam),
                              control_period=control_period, measurement=measurement, v_limit=v_limit)
