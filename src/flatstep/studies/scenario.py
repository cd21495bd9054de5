"""A closed-loop scenario: the plant, the move, the controller and the loop or solver, run in one call."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Mapping, Optional

from ..control.smc import SMCGains
from ..control.spec import ControllerSpec
from ..control.tuning import AnyController, make_controller
from ..engine.result import SimResult
from ..engine.settings import Continuous
from ..engine.simulate import check_run, simulate
from ..loop.reference import DriveLoop
from ..model.motor import MotorParams
from ..model.plant import Plant
from ..model.torque_model import TorqueModel
from ..plan.d_current import ZERO_D_CURRENT, DCurrentPlan
from ..plan.feasibility import FeasibilityReport, check_feasibility
from ..plan.loss_aware import LossAwareRho
from ..plan.piecewise import PiecewisePlan
from ..plan.protocol import Plan
from ..plan.rest_to_rest import PAPER_PLAN, RestToRest
from ..validate import check_quantity


@dataclass(frozen=True)
class Scenario:
    """Everything one closed-loop run needs, as the objects :func:`~flatstep.engine.simulate.simulate` takes.

    The defaults are the paper's Fig. 1 (Section 3).

    Parameters
    ----------
    name : str
        A label for tables, rows and figures.
    motor : MotorParams
        The controller's model of the motor (and the plant's, when ``plant`` is ``None``).
    plan : RestToRest or PiecewisePlan
        The move (any plan: the paper's, or a waypoint sequence's segment table).
    controller_type : str
        The law (:data:`flatstep.control.CONTROLLER_TYPES`): the paper's ``"smc"`` with ``gains``, or a
        baseline tuned for this loop by :func:`flatstep.control.make_controller`.
    gains : SMCGains
        The sliding controller's gains (``controller_type="smc"``).
    measurement : str
        Where the controller's speed and acceleration come from: ``"ideal"``, ``"model"`` or ``"observer"``.
    bandwidth_scale : float
        Multiplies every bandwidth of a baseline (1: the tuning rule).
    lambda_ts : float, optional
        The current loop's speed times the control period, for every law (``None``: the rule's 0.3).
    law_gains : mapping, optional
        Each law's gains by name over its rule, by law (``{"cascade": {"k_theta": 300.0}}``, say; a law not named,
        or ``None``: the rule's), so that one scenario can carry the gains of every law it compares.
    plant : Plant, optional
        The simulated plant (motor, effects, load); ``None``: ``Plant(motor)``, a perfect model, no load.
    loop : DriveLoop, optional
        Sampled control in a drive (period, substeps, drive, sensors, observer, delay); ``None``:
        continuous-time control, as in the paper.
    torques : TorqueModel, optional
        The torques the ``_ff`` controller types know beyond eq. (1) (the feedforward; other types ignore it).
    d_current : DCurrentPlan
        The d current the d-q flatness types track (default 0; other types ignore it).
    loss_aware : LossAwareRho
        The loss-aware rho*(t) of the ``smc_la`` types (``None``: ``LossAwareRho.for_plan(plan)``; other types
        ignore it).
    solver : Continuous, optional
        How continuous-time control is solved (``None``: the defaults of
        :class:`~flatstep.engine.settings.Continuous`); only without a loop.
    t_end : float
        Horizon [s].
    """

    name: str = "run"
    motor: MotorParams = field(default_factory=lambda: MotorParams.preset("paper"))
    plan: Plan = PAPER_PLAN
    controller_type: str = "smc"
    gains: SMCGains = SMCGains()
    measurement: str = "ideal"
    bandwidth_scale: float = 1.0
    plant: Optional[Plant] = None
    loop: Optional[DriveLoop] = None
    solver: Optional[Continuous] = None
    t_end: float = 0.06
    torques: Optional[TorqueModel] = None
    d_current: DCurrentPlan = ZERO_D_CURRENT
    loss_aware: Optional[LossAwareRho] = None
    lambda_ts: Optional[float] = None
    law_gains: Optional[Mapping[str, Any]] = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "t_end", check_quantity("t_end", self.t_end))
        object.__setattr__(self, "bandwidth_scale", check_quantity("scale", self.bandwidth_scale,
                                                                  as_name="bandwidth_scale"))
        if not isinstance(self.name, str):
            raise ValueError(f"Scenario.name={self.name!r} must be a string")
        kinds: tuple[tuple[str, Any], ...] = (
            ("motor", MotorParams), ("plan", (RestToRest, PiecewisePlan)), ("gains", SMCGains), ("plant", Plant),
            ("loop", DriveLoop), ("solver", Continuous), ("torques", TorqueModel), ("d_current", DCurrentPlan),
            ("loss_aware", LossAwareRho))
        for name, kind in kinds:
            value = getattr(self, name)
            if value is not None and not isinstance(value, kind):
                names = " or ".join(k.__name__ for k in (kind if isinstance(kind, tuple) else (kind,)))
                raise ValueError(f"Scenario.{name}={value!r} is not a {names}")
        if self.loop is not None and self.solver is not None:
            raise ValueError("a scenario has either a loop (sampled control) or a solver (continuous control)")
        self.controller()  # validates the measurement mode and the controller type
        # timing and the integration's cost (the memory of the series is checked when a run returns them)
        check_run(self.plan, self.t_end, self.loop or self.solver or Continuous(), "c", series=False)

    @property
    def simulated_plant(self) -> Plant:
        """The plant that is simulated: ``plant``, or the controller's model with no effects and no load."""
        return self.plant if self.plant is not None else Plant(self.motor)

    @property
    def control_period(self) -> Optional[float]:
        """The loop's control period [s], ``None`` for continuous-time control."""
        return self.loop.control_period if self.loop is not None else None

    def controller(self) -> AnyController:
        """The scenario's controller: :class:`~flatstep.control.smc.FlatnessSMC` or a baseline tuned for its loop."""
        loop = self.loop
        v_bus = loop.drive.v_bus if loop is not None and loop.drive is not None else math.inf
        return make_controller(self.controller_type, self.motor, self.plan, control_period=self.control_period,
                               measurement=self.measurement, smc_gains=self.gains, v_limit=v_bus,
                               bandwidth_scale=self.bandwidth_scale,
                               compute_delay=loop.compute_delay if loop is not None else False,
                               torques=self.torques, d_current=self.d_current, loss_aware=self.loss_aware,
                               lambda_ts=self.lambda_ts,
                               law_gains=(self.law_gains or {}).get(ControllerSpec.parse(self.controller_type).law),
                               angle_step=loop.sensors.angle_step if loop is not None and loop.sensors is not None
                               else 0.0)

    def feasibility(self) -> FeasibilityReport:
        """The plan checked against the controller's singularity; the load is unknown to the plan."""
        return _feasibility(self.plan, self.motor)  # type: ignore[arg-type]  # the plans are frozen dataclasses

    def run(self, engine: str = "c") -> SimResult:
        """Refuse an infeasible plan, then simulate the closed loop on ``engine``."""
        self.feasibility().raise_if_infeasible()
        return simulate(self.simulated_plant, self.plan, self.controller(), loop=self.loop, solver=self.solver,
                        engine=engine, t_end=self.t_end)


@lru_cache(maxsize=256)
def _feasibility(plan: Plan, motor: MotorParams) -> FeasibilityReport:
    """:func:`~flatstep.plan.feasibility.check_feasibility` with no load, cached."""
    return check_feasibility(plan, motor)  # batches share plans: check each once per process


#: The paper's two simulations (Section 3): t0 = 0.02 s, tf = 0.04 s, 0.06 s horizon, ideal measurement.
PAPER_SCENARIOS = {
    "fig1": Scenario("fig1"),
    "fig2": Scenario("fig2", gains=SMCGains(W1=300.0, W2=300.0), plant=Plant(MotorParams.preset("paper"), load=1e-5)),
}
