"""flatstep: flatness-based planning and sliding-mode control of permanent-magnet stepping motors.

The public API, listed in ``__all__`` in the order a move flows through it: model, plan, flat maps, control, loop,
engine, studies.
"""
from ._version import __version__ as __version__
from .control import (
    CONTROLLER_TYPES,
    CascadeFOC,
    CascadeGains,
    Controller,
    DQFlatnessSMC,
    ExactLinearization,
    FlatnessSMC,
    LinearizationGains,
    MicrostepGains,
    Microstepping,
    SMCGains,
    make_controller,
)
from .engine.result import SimResult
from .engine.settings import Continuous
from .engine.simulate import simulate
from .loop.drive import Drive
from .loop.observers import Observer
from .loop.reference import DriveLoop
from .loop.sensors import Sensors
from .model.equilibria import CriticalPoint, equilibrium_currents, rest_positions, stable_angle
from .model.flat import FlatFlag, cartesian, flat_to_state, polar, polar_rhs, state_to_flat
from .model.flat_dq import DQFlag, dq_to_state, state_to_dq
from .model.motor import PRESETS, MotorParams, rhs
from .model.plant import Plant, PlantEffects
from .model.torque_model import TorqueModel
from .plan.d_current import DCurrentPlan
from .plan.feasibility import FeasibilityReport, InfeasiblePlanError, check_feasibility
from .plan.rest_to_rest import PAPER_PLAN, RestToRest, point_to_point, psi
from .studies.batch import run_batch, scenario_grid
from .studies.batch_file import BatchWriteError
from .studies.scenario import PAPER_SCENARIOS, Scenario

__all__ = [
    "MotorParams", "PRESETS", "rhs", "Plant", "PlantEffects", "TorqueModel",
    "CriticalPoint", "rest_positions", "stable_angle", "equilibrium_currents",
    "FlatFlag", "polar", "cartesian", "polar_rhs", "flat_to_state", "state_to_flat",
    "DQFlag", "dq_to_state", "state_to_dq",
    "RestToRest", "PAPER_PLAN", "point_to_point", "psi", "DCurrentPlan",
    "FeasibilityReport", "InfeasiblePlanError", "check_feasibility",
    "Controller", "FlatnessSMC", "SMCGains", "DQFlatnessSMC", "Microstepping", "MicrostepGains", "CascadeFOC",
    "CascadeGains", "ExactLinearization", "LinearizationGains", "CONTROLLER_TYPES", "make_controller",
    "Drive", "Sensors", "Observer", "DriveLoop", "Continuous",
    "simulate", "SimResult",
    "Scenario", "PAPER_SCENARIOS", "run_batch", "scenario_grid", "BatchWriteError",
]
