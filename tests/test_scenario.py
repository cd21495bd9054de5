"""Scenario (studies/scenario.py): the plant, loop and solver objects it holds, and what it refuses."""
from dataclasses import replace

import pytest

import flatstep as fs


def test_defaults_are_the_papers_continuous_fig1(motor):
    s = fs.Scenario()
    assert s.simulated_plant == fs.Plant(motor) and s.control_period is None and s.loop is None
    r = s.run()
    assert r.meta["engine"] == "c" and r.meta["method"] == "DOP853" and r.meta["plant"] == fs.Plant(motor).as_dict()


def test_the_loop_and_solver_reach_the_run(motor):
    loop = fs.DriveLoop(1e-4, substeps=3, drive=fs.Drive(v_bus=24.0))
    s = fs.Scenario("s", plant=fs.Plant(motor.replace(R=9.0), load=1e-5), loop=loop, t_end=0.04)
    assert s.control_period == 1e-4
    r = s.run(engine="python")
    assert (r.meta["engine"], r.meta["control_period"], r.meta["substeps"]) == ("python", 1e-4, 3)
    assert r.meta["plant"]["motor"]["R"] == 9.0 and r.meta["plant"]["load"] == 1e-5
    assert r.meta["gains"] == s.gains.as_dict()  # the controller is built on the model, not the plant
    r = replace(s, loop=None, solver=fs.Continuous("LSODA", dt_out=1e-3)).run(engine="scipy")
    assert (r.meta["method"], r.t.size) == ("LSODA", 41)


def test_the_loop_tunes_the_baselines(motor):
    s = fs.Scenario("m", controller_type="microstep", loop=fs.DriveLoop(5e-5, drive=fs.Drive(v_bus=12.0)))
    assert s.controller().v_limit == 12.0 and s.controller().control_period == 5e-5
    with pytest.raises(ValueError, match="tuned from the control period"):
        replace(s, loop=None)


@pytest.mark.parametrize("kwargs, match", [
    (dict(loop=fs.DriveLoop(), solver=fs.Continuous()), "either a loop .* or a solver"),
    (dict(plant=fs.PAPER_PLAN), r"Scenario.plant=RestToRest\(.*\) is not a Plant"),
    (dict(loop=5e-5), r"Scenario.loop=5e-05 is not a DriveLoop"),
    (dict(solver="LSODA"), r"Scenario.solver='LSODA' is not a Continuous"),
    (dict(t_end=-1.0), r"t_end=-1.0 s is out of range: .*valid: \(0, 1e\+06\] s"),
    (dict(measurement="x"), r"measurement='x'"),
])
def test_bad_scenarios_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        fs.Scenario(**kwargs)
