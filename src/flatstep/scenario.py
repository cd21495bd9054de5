"""A closed-loop scenario: the motor, the move, the controller settings and the load, run in one call."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .control.smc import FlatnessSMC, SMCGains
from .feasibility import FeasibilityReport, check_feasibility
from .motor import MotorParams, check_positive
from .plan import PAPER_PLAN, RestToRest
from .result import SimResult
from .simulate import simulate


@dataclass(frozen=True)
class Scenario:
    """Everything one closed-loop run needs; defaults are the paper's Fig. 1 (Section 3)."""

    name: str = "run"
    motor: MotorParams = field(default_factory=lambda: MotorParams.preset("paper"))
    plan: RestToRest = PAPER_PLAN
    gains: SMCGains = SMCGains()
    measurement: str = "ideal"
    load_torque: float = 0.0
    t_end: float = 0.06

    def __post_init__(self) -> None:
        check_positive("t_end", self.t_end, unit=" s")
        self.controller()  # validates the measurement mode

    def controller(self) -> FlatnessSMC:
        return FlatnessSMC(self.motor, self.plan, self.gains, self.measurement)

    def feasibility(self) -> FeasibilityReport:
        """The plan checked against the controller's singularity; the load is unknown to the plan."""
        return check_feasibility(self.plan, self.motor)

    def run(self, **simulate_options: Any) -> SimResult:
        """Refuse an infeasible plan, then simulate the closed loop."""
        self.feasibility().raise_if_infeasible()
        return simulate(self.motor, self.plan, self.controller(), load=self.load_torque, t_end=self.t_end,
                        **simulate_options)


#: The paper's two simulations (Section 3): t0 = 0.02 s, tf = 0.04 s, 0.06 s horizon, ideal measurement.
PAPER_SCENARIOS = {
    "fig1": Scenario("fig1"),
    "fig2": Scenario("fig2", gains=SMCGains(W1=300.0, W2=300.0), load_torque=1e-5),
}
