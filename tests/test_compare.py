"""Controller comparison: metrics against hand computations, scenario-file keys, the compare command."""
import json
from pathlib import Path

import numpy as np
import pytest

from flatstep.cli import main
from flatstep.studies.compare import compare, metrics
from flatstep.plan.rest_to_rest import RestToRest
from flatstep.studies.scenario_file import load_scenario

PLAN = RestToRest(0.0, 0.02, 0.4, 0.4, t0=0.01, tf=0.03)
EXAMPLES = Path(__file__).parent.parent / "examples"


def test_metrics_against_hand_computations():
    t = np.linspace(0.0, 0.05, 501)  # 1e-4 s apart
    e = np.where(t < 0.01, 5.0, 0.0) + np.where((t >= 0.01) & (t <= 0.03), 2e-3 * np.sin(2 * np.pi * (t - 0.01) / 0.02), 0.0)
    e = e + np.where((t > 0.03) & (t <= 0.0405), 1e-3, 0.0) + np.where(t > 0.0405, 1e-5, 0.0)
    ia, ib = np.where(t < 0.01, 9.0, 0.3), np.where(t < 0.01, 9.0, -0.4)
    va, vb = np.where(t < 0.01, 99.0, 2.0), np.where(t == 0.02, -7.5, 1.0)
    m = metrics(t, e, ia, ib, va, vb, PLAN, band=1e-4, R=8.0)
    move = (t >= 0.01) & (t <= 0.03)
    assert m["move_max"] == pytest.approx(2e-3, rel=1e-6)
    assert m["move_rms"] == pytest.approx(np.sqrt(np.mean(e[move] ** 2))) and m["move_rms"] == pytest.approx(2e-3 / np.sqrt(2), rel=0.03)
    assert m["final"] == pytest.approx(1e-5)
    assert m["settling_time"] == pytest.approx(0.0406 - 0.03, abs=1e-12)  # first sample after the last one outside
    assert m["peak_voltage"] == 7.5 and m["peak_current"] == pytest.approx(0.4)  # t < t0 is left out
    assert m["rms_current"] == pytest.approx(np.sqrt((0.09 + 0.16) / 2))
    assert m["copper_loss"] == pytest.approx(8.0 * 0.25 * 0.04)  # R (ia^2 + ib^2) over [t0, t_end]
    assert metrics(t, 0 * e, ia, ib, va, vb, PLAN, band=1e-4, R=8.0)["settling_time"] == 0.0
    assert metrics(t, e + 1.0, ia, ib, va, vb, PLAN, band=1e-4, R=8.0)["settling_time"] is None
    with pytest.raises(ValueError, match="band=0"):
        metrics(t, e, ia, ib, va, vb, PLAN, band=0, R=8.0)


def _file(tmp_path, **tables):
    base = {"motor": 'preset = "paper"', "drive": "control_rate = 20000.0\nv_bus = 24.0",
            "plan": "t0 = 0.005\ntf = 0.02", "controller": "design = true"}
    base.update(tables)
    text = 't_end = 0.03\n' + "\n".join(f"[{k}]\n{v}" for k, v in base.items() if v is not None)
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path


def test_scenario_file_controller_type_and_plant_effects(tmp_path):
    sc, _ = load_scenario(_file(tmp_path, plant="detent_torque = 1e-3\ncoulomb_torque = 2e-4\nmagnetizing_resistance = 40.0",
                                controller='design = true\ntype = "cascade"\nbandwidth_scale = 2.0'))
    assert sc.controller_type == "cascade" and sc.simulated_plant.motor == sc.motor and sc.bandwidth_scale == 2.0
    fx = sc.simulated_plant.effects
    assert (fx.detent_torque, fx.coulomb_torque, fx.magnetizing_resistance) == (1e-3, 2e-4, 40.0)
    assert sc.controller().gains.position_bandwidth == pytest.approx(2 * 1500.0)
    # the sliding controller's design is told the detent and friction as expected disturbance torque
    smc, _ = load_scenario(_file(tmp_path, plant="detent_torque = 1e-3"))
    clean, _ = load_scenario(_file(tmp_path, plant=None))
    lam, J = 0.3 / 5e-5, smc.motor.J
    assert smc.gains.W2 - clean.gains.W2 == pytest.approx(2 * 1e-3 * lam / J, rel=1e-9)  # W = 2 d_max, + tau lam/J


@pytest.mark.parametrize("tables, match", [
    (dict(controller='type = "pid"'), r"type='pid' is unknown"),
    (dict(plant="detent = 1e-3"), r"unknown key\(s\) \['detent'\] in \[plant\]"),
    (dict(plant="coulomb_torque = -1.0"), r":plant.coulomb_torque: coulomb_torque=-1.0"),
    (dict(drive=None, controller='type = "microstep"'), "tuned from the control period"),
])
def test_scenario_file_errors(tmp_path, tables, match):
    with pytest.raises(ValueError, match=match):
        load_scenario(_file(tmp_path, **tables))


def test_compare_runs_every_controller_on_the_same_plant(tmp_path):
    sc, _ = load_scenario(_file(tmp_path, sensors="encoder_counts = 16384", load="torque = 1e-5"))
    res = compare(sc, ("smc", "microstep", "cascade"))
    assert list(res) == ["smc", "microstep", "cascade"]
    assert {r["result"].meta["controller"] for r in res.values()} == {"FlatnessSMC", "Microstepping", "CascadeFOC"}
    assert all(r["result"].meta["observer"] == res["smc"]["result"].meta["observer"] for r in res.values())
    count = 2 * np.pi / 16384
    assert res["smc"]["metrics"]["move_max"] < 2 * count and res["cascade"]["metrics"]["move_max"] < 2 * count
    assert res["microstep"]["metrics"]["move_max"] > 3 * res["smc"]["metrics"]["move_max"]
    # the d-q controller holds i_d = 0: far less current than the ones that hold rho = 0.4 A
    assert res["cascade"]["metrics"]["copper_loss"] < 0.2 * res["smc"]["metrics"]["copper_loss"]


def test_compare_cli_table_and_json(tmp_path, capsys):
    path = _file(tmp_path, sensors="encoder_counts = 16384", plant="detent_torque = 1e-3")
    out = tmp_path / "out"
    assert main(["compare", str(path), "--controllers", "smc,cascade", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "flatness + SMC" in text and "cascaded PID (FOC)" in text and "target" in text
    assert (out / "overlay.png").read_bytes()[:4] == b"\x89PNG"
    report = json.loads((out / "compare.json").read_text())
    assert set(report["controllers"]) == {"smc", "cascade"}
    assert main(["compare", str(path), "--controllers", "microstep", "--json", "--scales", "2"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["bandwidth_sweep"]["2.0"]["microstep"]["move_max"] != rep["controllers"]["microstep"]["metrics"]["move_max"]
    assert main(["compare", str(path), "--controllers", "pid"]) == 2
    assert "'pid'" in capsys.readouterr().err


@pytest.mark.slow
def test_compare_worst_over_the_corners_of_the_example(capsys):
    """docs/comparison.md: on the paper's move both closed loops stay within one count on all 32 plants."""
    assert main(["compare", str(EXAMPLES / "compare-paper-20khz.toml"), "--controllers", "smc,cascade",
                 "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    count = 2 * np.pi / 16384
    assert rep["robustness"]["plants"] == 32
    for kind in ("smc", "cascade"):
        w = rep["robustness"]["worst"][kind]
        assert w["failed"] == 0 and w["metrics"]["move_max"] < count and w["metrics"]["peak_voltage"] <= 24.0
