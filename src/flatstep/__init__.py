"""flatstep: flatness-based planning and sliding-mode control of permanent-magnet stepping motors."""
from .control import (CONTROLLER_TYPES, CascadeFOC, ExactLinearization, FlatnessSMC, Microstepping, SMCGains,
                      make_controller)
from .model.plant import PlantEffects
from .model.equilibria import CriticalPoint, equilibrium_currents, rest_positions, stable_angle
from .plan.feasibility import FeasibilityReport, InfeasiblePlanError, check_feasibility
from .model.flat import FlatFlag, cartesian, flat_to_state, polar, polar_rhs, state_to_flat
from .model.motor import PRESETS, MotorParams, rhs
from .plan.rest_to_rest import PAPER_PLAN, RestToRest, point_to_point, psi
from .engine.result import SimResult
from .studies.scenario import PAPER_SCENARIOS, Scenario
from .studies.batch import run_batch, scenario_grid
from .engine.simulate import simulate

__version__ = "0.1.0"

__all__ = [
    "MotorParams", "PRESETS", "rhs",
    "CriticalPoint", "rest_positions", "stable_angle", "equilibrium_currents",
    "FlatFlag", "polar", "cartesian", "polar_rhs", "flat_to_state", "state_to_flat",
    "RestToRest", "PAPER_PLAN", "point_to_point", "psi",
    "FeasibilityReport", "InfeasiblePlanError", "check_feasibility",
    "FlatnessSMC", "SMCGains", "simulate", "SimResult",
    "Microstepping", "CascadeFOC", "ExactLinearization", "CONTROLLER_TYPES", "make_controller", "PlantEffects",
    "Scenario", "PAPER_SCENARIOS", "run_batch", "scenario_grid",
]
