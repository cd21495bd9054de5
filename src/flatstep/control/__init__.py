"""Controllers: the paper's flatness + sliding-mode law first."""
from .smc import MEASUREMENTS, FlatnessSMC, SMCGains

__all__ = ["FlatnessSMC", "SMCGains", "MEASUREMENTS"]
