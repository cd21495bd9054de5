"""Fixtures the tests share: the paper's motor and move, the in-process command line, samples near a plan."""
import contextlib
import io
from dataclasses import dataclass

import numpy as np
import pytest

import flatstep as fs

#: The paper's move on a 20 kHz drive, two plants (R off by +-10 %): a tiny study that runs in a
#: second (the tuner's and the held-out check's tests).
TINY = """name = "tiny"
t_end = 0.05

[plan]
theta1 = 0.0
theta2 = 0.02
rho1 = 0.4
rho2 = 0.4
t0 = 0.01
tf = 0.03

[controller]
design = true
uncertainty = 0.1

[drive]
control_rate = 20000.0
v_bus = 24.0

[sensors]
encoder_counts = 16384

[robustness]
relative_error = 0.1
parameters = ["R"]
"""


@pytest.fixture(scope="session")
def motor():
    """The paper's motor, the ``paper`` preset."""
    return fs.MotorParams.preset("paper")


@pytest.fixture(scope="session")
def plan():
    """The paper's move, :data:`flatstep.PAPER_PLAN`: 0.02 rad at 0.4 A from t = 20 ms to 40 ms."""
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


@pytest.fixture(scope="session")
def near_plan():
    """``near_plan(plan, n, seed)``: n sorted times in the move and measurements near the plan.

    The measurements are (ia, ib, omega, theta, acceleration); the d-q law's tests want |s2| on both sides of
    eps2 = 50.
    """
    def sample(plan, n, seed):
        rng = np.random.default_rng(seed)
        t = np.sort(rng.uniform(plan.t0, plan.tf, n))
        ref = plan.flag(t)
        y = np.array([rng.normal(0, 0.4, n), rng.normal(0, 0.4, n), ref.dtheta + rng.normal(0, 0.01, n),
                      ref.theta + rng.normal(0, 1e-5, n), ref.ddtheta + rng.normal(0, 30, n)])
        return t, y
    return sample
