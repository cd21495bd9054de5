"""The package version (pyproject.toml's ``version``; batch files and ``flatstep --version`` read it)."""
__version__ = "0.1.0"
