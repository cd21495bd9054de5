import pytest

import flatstep as fs


@pytest.fixture(scope="session")
def motor():
    return fs.MotorParams.preset("paper")


@pytest.fixture(scope="session")
def plan():
    return fs.PAPER_PLAN
