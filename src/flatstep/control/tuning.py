"""Every controller built for one drive: parse the spec, check what it needs, call its law's builder.

:func:`make_controller` knows no law and no option by name: the spec (:mod:`flatstep.control.spec`) says what the
law and its options need from a run (a torque model, a control period), and the law's file builds the controller
from the spec and a :class:`~flatstep.control.build.BuildContext` (the baselines' design rules are there).
"""
from __future__ import annotations

import math
from typing import Any, Mapping, Optional, Union

from ..model.motor import MotorParams
from ..model.torque_model import NO_TORQUES, TorqueModel
from ..plan.d_current import ZERO_D_CURRENT, DCurrentPlan
from ..plan.loss_aware import LossAwareRho
from ..plan.protocol import Plan
from .build import LAMBDA_TS, LAMBDA_TS_DELAYED, W_MARGIN, WN_OVER_LAMBDA, XI, BuildContext, bandwidths
from .cascade import CascadeFOC
from .dq_smc import DQFlatnessSMC
from .exact_linearization import ExactLinearization
from .microstep import Microstepping
from .smc import REST_HOLD_DAMPING, FlatnessSMC, SMCGains
from .spec import CONTINUOUS_TYPES, CONTROLLER_TYPES, FEEDFORWARD_TYPES, LABELS, SMC_TYPES, ControllerSpec, label

__all__ = ["make_controller", "AnyController", "CONTROLLER_TYPES", "LABELS", "SMC_TYPES", "CONTINUOUS_TYPES",
           "FEEDFORWARD_TYPES", "REST_HOLD_DAMPING", "LAMBDA_TS", "LAMBDA_TS_DELAYED", "WN_OVER_LAMBDA", "XI",
           "W_MARGIN", "bandwidths", "label"]

#: The sliding controller's default gains, the paper's.
_PAPER_SMC_GAINS = SMCGains()
#: What :func:`make_controller` returns.
AnyController = Union[FlatnessSMC, DQFlatnessSMC, Microstepping, CascadeFOC, ExactLinearization]


def make_controller(kind: object, motor: MotorParams, plan: Plan, *, control_period: float | None,
                    measurement: str, smc_gains: SMCGains = _PAPER_SMC_GAINS, v_limit: float = math.inf,
                    bandwidth_scale: float = 1.0, compute_delay: bool = False,
                    torques: Optional[TorqueModel] = None,
                    d_current: DCurrentPlan = ZERO_D_CURRENT,
                    loss_aware: Optional[LossAwareRho] = None, lambda_ts: Optional[float] = None,
                    law_gains: Optional[Mapping[str, Any]] = None, angle_step: float = 0.0) -> AnyController:
    """The controller ``kind`` for this motor model, plan and drive.

    ``kind`` is a :class:`~flatstep.control.spec.ControllerSpec`, a name (one of :data:`CONTROLLER_TYPES` or
    ``law+option+...``) or a mapping of the spec's fields. The sliding laws take ``smc_gains`` (the scenario's,
    designed or given); the baselines are tuned by rule (:mod:`flatstep.control.build`) from ``control_period``,
    with every bandwidth times ``bandwidth_scale``. ``torques`` (the torques known beyond eq. (1)) is required by
    the options that need it (``feedforward``) and read by no other controller; ``d_current`` is the d-q laws'
    planned d current, ``loss_aware`` the loss-aware rho*(t) (default ``LossAwareRho.for_plan(plan)``).
    ``lambda_ts`` replaces the rule's current-loop speed times Ts for every law (a sliding law's boundary layers,
    a baseline's current bandwidth; needs ``control_period``), and ``law_gains`` gives the law's gains by name over
    its rule (:class:`~flatstep.control.build.BuildContext`); ``angle_step`` is one count of the angle the law reads
    [rad] (0: exact or unknown; the default controller's rule reads it). What each option adds is said by its law's
    ``from_spec``.

    Raises
    ------
    ValueError
        For an unknown or invalid spec, a missing torque model or control period.
    """
    spec = ControllerSpec.parse(kind, "controller type")
    if spec.needs_torques and torques is None:
        raise ValueError(f"controller type {spec.name()!r} needs the torques it knows beyond eq. (1): give a "
                         "TorqueModel (a [feedforward] table in a scenario file), or use the type without feedforward")
    if (spec.needs_control_period or lambda_ts is not None) and control_period is None:
        raise ValueError(f"controller type {spec.name()!r} is tuned from the control period "
                         f"(lambda = 0.3/Ts) or advances by it: give one ([drive] control_rate); only the flatness "
                         f"types {CONTINUOUS_TYPES} have gains of their own for continuous time")
    context = BuildContext(motor, plan, measurement, control_period=control_period, smc_gains=smc_gains,
                           v_limit=v_limit, bandwidth_scale=bandwidth_scale, compute_delay=compute_delay,
                           torques=torques if spec.needs_torques and torques is not None else NO_TORQUES,
                           d_current=d_current, loss_aware=loss_aware, lambda_ts=lambda_ts,
                           law_gains=dict(law_gains or {}), angle_step=angle_step)
    controller: AnyController = spec.build(context)
    return controller
