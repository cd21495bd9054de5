"""A closed-loop scenario: the motor, the move, the controller settings and the load, run in one call."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Optional

from ..control.smc import SMCGains
from ..control.tuning import make_controller
from ..loop.drive import Drive
from ..plan.feasibility import FeasibilityReport, check_feasibility
from ..validate import check_integer, check_positive
from ..model.motor import MotorParams
from ..loop.observers import Observer
from ..model.plant import PlantEffects
from ..plan.rest_to_rest import PAPER_PLAN, RestToRest
from ..engine.result import SimResult
from ..loop.sensors import Sensors
from ..engine.simulate import simulate


@dataclass(frozen=True)
class Scenario:
    """Everything one closed-loop run needs; defaults are the paper's Fig. 1 (Section 3).

    ``motor`` is the controller's model; ``plant`` the simulated motor (default: the same, a perfect model).
    ``control_period`` ``None`` evaluates the law continuously (the paper); a period [s] samples it with a
    zero-order hold, the plant integrated by ``substeps`` RK4 steps per period. ``drive``, ``sensors``,
    ``observer`` and ``compute_delay`` describe a realistic drive around the sampled controller
    (see :func:`flatstep.simulate`). ``controller_type`` names the law (:data:`flatstep.control.CONTROLLER_TYPES`):
    the paper's ``"smc"`` with ``gains``, or a baseline tuned for this drive by
    :func:`flatstep.control.make_controller` (``bandwidth_scale`` scales its bandwidths). ``effects`` are the
    plant's detent, Coulomb friction and iron loss (sampled loop only; the controllers do not know them).
    """

    name: str = "run"
    motor: MotorParams = field(default_factory=lambda: MotorParams.preset("paper"))
    plan: RestToRest = PAPER_PLAN
    gains: SMCGains = SMCGains()
    measurement: str = "ideal"
    load_torque: float = 0.0
    t_end: float = 0.06
    plant: Optional[MotorParams] = None
    control_period: Optional[float] = None
    substeps: int = 10
    drive: Optional[Drive] = None
    sensors: Optional[Sensors] = None
    observer: Optional[Observer] = None
    compute_delay: bool = False
    controller_type: str = "smc"
    effects: Optional[PlantEffects] = None
    bandwidth_scale: float = 1.0

    def __post_init__(self) -> None:
        check_positive("t_end", self.t_end, unit=" s")
        if self.control_period is not None:
            check_positive("control_period", self.control_period, unit=" s")
        check_integer("substeps", self.substeps, why="RK4 steps per period")
        if self.effects is not None and self.effects.active and self.control_period is None:
            raise ValueError("plant effects (detent, Coulomb friction, iron loss) are modelled on the sampled "
                             "drive loop only: give a control_period")
        self.controller()  # validates the measurement mode and the controller type

    @property
    def plant_motor(self) -> MotorParams:
        return self.motor if self.plant is None else self.plant

    def controller(self):
        """The scenario's controller: :class:`~flatstep.control.smc.FlatnessSMC` or a tuned baseline."""
        return make_controller(self.controller_type, self.motor, self.plan, control_period=self.control_period,
                               measurement=self.measurement, smc_gains=self.gains,
                               v_limit=self.drive.v_bus if self.drive is not None else math.inf,
                               bandwidth_scale=self.bandwidth_scale, compute_delay=self.compute_delay)

    def feasibility(self) -> FeasibilityReport:
        """The plan checked against the controller's singularity; the load is unknown to the plan."""
        return _feasibility(self.plan, self.motor)

    def run(self, **simulate_options: Any) -> SimResult:
        """Refuse an infeasible plan, then simulate the closed loop."""
        self.feasibility().raise_if_infeasible()
        if self.control_period is not None:
            simulate_options = {"control_period": self.control_period, "substeps": self.substeps,
                                "drive": self.drive, "sensors": self.sensors, "observer": self.observer,
                                "compute_delay": self.compute_delay, "effects": self.effects, **simulate_options}
        return simulate(self.plant_motor, self.plan, self.controller(), load=self.load_torque, t_end=self.t_end,
                        **simulate_options)


@lru_cache(maxsize=256)
def _feasibility(plan: RestToRest, motor: MotorParams) -> FeasibilityReport:
    return check_feasibility(plan, motor)  # batches share plans: check each once per process


#: The paper's two simulations (Section 3): t0 = 0.02 s, tf = 0.04 s, 0.06 s horizon, ideal measurement.
PAPER_SCENARIOS = {
    "fig1": Scenario("fig1"),
    "fig2": Scenario("fig2", gains=SMCGains(W1=300.0, W2=300.0), load_torque=1e-5),
}
