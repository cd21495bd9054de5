import contextlib
import io
from dataclasses import dataclass

import pytest

import flatstep as fs


@pytest.fixture(scope="session")
def motor():
    return fs.MotorParams.preset("paper")


@pytest.fixture(scope="session")
def plan():
    return fs.PAPER_PLAN


@dataclass
class CliRun:
    """What one in-process command-line run gave: the exit code and the two streams (like subprocess's result)."""

    returncode: int
    stdout: str
    stderr: str


def run_cli(argv, cwd=None):
    """Run ``flatstep ARGV`` in this process through ``flatstep.cli.main.main`` (no interpreter start-up).

    stdout and stderr are captured; ``cwd`` is entered for the run. Use a subprocess only for what needs one
    (signals, the installed entry point, start-up imports).
    """
    from flatstep.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.ExitStack() as stack:
        if cwd is not None:
            stack.enter_context(contextlib.chdir(cwd))
        stack.enter_context(contextlib.redirect_stdout(out))
        stack.enter_context(contextlib.redirect_stderr(err))
        code = main([str(a) for a in argv])
    return CliRun(int(code), out.getvalue(), err.getvalue())


@pytest.fixture
def cli():
    """The in-process command line: ``cli(["plan", "f.toml"], cwd=tmp_path)`` returns a :class:`CliRun`."""
    return run_cli
