"""Builds the C core's cffi extension at install time; all other metadata lives in pyproject.toml."""
from setuptools import setup

setup(cffi_modules=["src/flatstep/core/build.py:ffibuilder"])
