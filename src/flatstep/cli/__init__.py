"""Command line: ``flatstep reproduce``, ``simulate``, ``design``, ``robustness``, ``compare``, ``bench``."""
from .main import main

__all__ = ["main"]
