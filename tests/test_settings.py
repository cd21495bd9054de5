"""Continuous-time settings (engine/settings.py): validation, metadata, and which engine takes which method."""
import numpy as np
import pytest

import flatstep as fs
from flatstep.engine.settings import C_METHODS, SCIPY_METHODS


def test_defaults_and_as_dict():
    s = fs.Continuous()
    assert s.as_dict() == {"method": None, "rtol": 1e-10, "atol": 1e-12, "dt_out": 1e-5, "max_steps": 10_000_000,
                           "max_wall_time": 15.0}
    assert isinstance(fs.Continuous(rtol=1, atol=1, dt_out=1).rtol, float)  # numbers are stored as floats


@pytest.mark.parametrize("kwargs, match", [
    (dict(method="Euler"), r"method='Euler' is not an integrator; valid: \('DOP853'"),
    (dict(method="dop853"), r"method='dop853' is not an integrator"),
    (dict(rtol=0.0), r"rtol=0.0 is out of range: .*valid: \[1e-16, 1\]"),
    (dict(atol=-1e-12), r"atol=-1e-12 is out of range"),
    (dict(dt_out=-1.0), r"dt_out=-1.0 s is out of range"),
    (dict(dt_out=np.nan), r"dt_out=nan"),
    (dict(rtol=np.inf), r"rtol=inf"),
])
def test_bad_settings_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        fs.Continuous(**kwargs)


@pytest.mark.parametrize("method", C_METHODS + SCIPY_METHODS)
def test_each_method_runs_on_its_engine_and_is_refused_by_the_other(motor, plan, method):
    solver = fs.Continuous(method, rtol=1e-8, atol=1e-10, dt_out=1e-3, max_wall_time=300.0)
    engine, other = ("c", "scipy") if method in C_METHODS else ("scipy", "c")
    if method in C_METHODS and method in SCIPY_METHODS:  # DOP853 is both
        other = None
    r = fs.simulate(motor, plan, solver=solver, engine=engine, t_end=0.04)
    assert r.meta["method"] == method and r.meta["engine"] == engine and r.t.size == 41
    assert abs(r.theta[-1] - plan.flag(0.04).theta) < 1e-5
    if other is not None:
        with pytest.raises(ValueError, match=f"method={method!r} is not a"):
            fs.simulate(motor, plan, solver=solver, engine=other, t_end=0.04)


@pytest.mark.parametrize("engine, method", [("c", "DOP853"), ("scipy", "LSODA")])
def test_each_engine_has_its_default_method(motor, plan, engine, method):
    r = fs.simulate(motor, plan, solver=fs.Continuous(dt_out=1e-3), engine=engine, t_end=0.04)
    assert r.meta["method"] == method and r.meta["engine"] == engine
