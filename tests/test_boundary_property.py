"""Property: any scenario, however hostile its values, is refused with a ValueError, or runs to a finite result
with a status, or stops with a RunError that names why and when. Never another exception, never NaN in a result.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import flatstep as fs  # noqa: E402
from flatstep.control.tuning import CONTROLLER_TYPES  # noqa: E402
from flatstep.errors import REASONS, RunError  # noqa: E402

HOSTILE = [math.nan, math.inf, -math.inf, 0.0, -1.0, 1e300, -1e300, 5e-324, 1e-300, True, "1", None]


def _values(typical: float, bad: int, spread: float = 0.3) -> st.SearchStrategy[object]:
    """Values within ``spread`` decades of ``typical``; with ``bad`` > 0, 1 in ``bad`` hostile, negative or far off."""
    near = st.floats(-spread, spread).map(lambda e: typical * 10.0**e)
    if not bad:
        return near
    far = st.floats(-12.0, 12.0).map(lambda e: typical * 10.0**e)
    return st.integers(0, 3 * bad - 1).flatmap(lambda k: st.sampled_from(HOSTILE) if k == 0 else near.map(
        lambda v: -v) if k == 1 else far if k == 2 else near)


@st.composite
def scenarios(draw: st.DrawFn) -> dict[str, object]:
    bad = draw(st.sampled_from((0, 0, 0, 40, 10)))  # none, rare or frequent hostile values in this example

    def val(typical: float, spread: float = 0.3) -> object:
        return draw(_values(typical, bad, spread))

    def pick(good: st.SearchStrategy[object], hostile: st.SearchStrategy[object]) -> object:
        return draw(good if not bad or draw(st.integers(0, bad - 1)) else hostile)

    motor = dict(R=val(8.4), L=val(0.01), Km=val(0.05), J=val(3.6e-6), B=val(1e-4),
                 Nr=pick(st.sampled_from((50, 50, 12, 100)),
                         st.one_of(st.integers(-5, 2000), st.sampled_from(HOSTILE))))
    t0 = draw(st.floats(0.0, 0.02))
    plan = dict(theta1=val(0.01), theta2=val(0.02), rho1=val(0.4, 0.2), rho2=val(0.4, 0.2), t0=pick(
        st.just(t0), st.sampled_from(HOSTILE)), tf=pick(st.just(t0 + draw(st.floats(0.01, 0.04))), st.floats(-1, 1)))
    gains = dict(W1=val(150.0), W2=val(3e5), eps1=val(0.025), eps2=val(50.0), xi=val(0.9, 0.1), wn=val(1500.0))
    sampled = draw(st.integers(0, 3)) > 0
    loop, measurement = None, draw(st.sampled_from(("ideal", "model")))
    if sampled:
        sensors, observer = draw(st.booleans()), draw(st.booleans())
        loop = dict(control_period=val(5e-5, 0.5), v_bus=val(24.0, 0.5), sensors=sensors, observer=observer,
                    substeps=pick(st.integers(1, 8), st.one_of(st.integers(-2, 10**6), st.sampled_from(HOSTILE))),
                    counts=pick(st.sampled_from((16384, 4000)), st.one_of(st.integers(-10, 70000),
                                                                          st.sampled_from(HOSTILE))))
        measurement = "observer" if observer else "model" if sensors else measurement
    kinds = [k for k in CONTROLLER_TYPES if not k.endswith("_ff")] + ["smc"] * 4
    return dict(motor=motor, plan=plan, gains=gains, loop=loop, load=val(1e-5, 1),
                t_end=pick(st.floats(0.07, 0.12), st.one_of(st.floats(-1, 1), st.sampled_from(HOSTILE))),
                kind=draw(st.sampled_from(kinds if sampled else ["smc", "dq_smc"])),
                measurement=pick(st.just(measurement), st.sampled_from(("ideal", "model", "observer", "other"))))


def _build(d: dict[str, object]) -> fs.Scenario:
    motor = fs.MotorParams(**d["motor"])
    loop = None
    if d["loop"] is not None:
        lp = d["loop"]
        sensors = fs.Sensors(encoder_counts=lp["counts"]) if lp["sensors"] else None
        loop = fs.DriveLoop(control_period=lp["control_period"], substeps=lp["substeps"],
                            drive=fs.Drive(v_bus=lp["v_bus"]), sensors=sensors,
                            observer=fs.Observer() if lp["observer"] else None)
    return fs.Scenario(motor=motor, plan=fs.RestToRest(**d["plan"]), gains=fs.SMCGains(**d["gains"]),
                       plant=fs.Plant(motor, load=d["load"]), loop=loop, t_end=d["t_end"],
                       controller_type=d["kind"], measurement=d["measurement"])


@settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))
@given(scenarios())
def test_a_scenario_is_refused_or_runs_to_a_finite_result_with_a_status(d):
    try:
        scenario = _build(d)
        result = scenario.run()
    except ValueError as exc:  # refused: the message names something
        assert "=" in str(exc) or "infeasible" in str(exc) or "needs" in str(exc), str(exc)
        return
    except RunError as exc:  # stopped early: why and when
        assert exc.reason in REASONS and math.isfinite(exc.t_fail)
        return
    series = [result.t, result.ia, result.ib, result.omega, result.theta, result.va, result.vb]
    assert all(np.all(np.isfinite(s)) for s in series)
    summary = result.summary()
    assert summary["status"] in ("ok", "lost", "fault")
    assert all(math.isfinite(v) for v in summary.values() if isinstance(v, float))
