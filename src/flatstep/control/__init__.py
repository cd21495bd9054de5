"""Controllers: the paper's flatness + sliding-mode law first, the baselines beside it."""
from .build import BuildContext
from .cascade import CascadeFOC, CascadeGains
from .dq_smc import DQFlatnessSMC, DQIntegral, DQKmAdaptation
from .exact_linearization import ExactLinearization, LinearizationGains
from .microstep import MicrostepGains, Microstepping
from .protocol import Controller, SlidingController, StaticController, is_static
from .smc import MEASUREMENTS, FlatnessSMC, SMCGains
from .spec import CONTROLLER_TYPES, LABELS, LAWS, ControllerSpec
from .tuning import make_controller

__all__ = ["Controller", "StaticController", "SlidingController", "is_static", "FlatnessSMC", "SMCGains",
           "MEASUREMENTS", "DQFlatnessSMC", "DQIntegral", "DQKmAdaptation", "Microstepping", "MicrostepGains",
           "CascadeFOC", "CascadeGains", "ExactLinearization", "LinearizationGains", "CONTROLLER_TYPES", "LABELS",
           "make_controller", "ControllerSpec", "LAWS", "BuildContext"]
