"""Builds the C core's cffi extension at install time; all other metadata lives in pyproject.toml."""
from setuptools import setup

setup(cffi_modules=["src/flatstep/_build_core.py:ffibuilder"])
