"""The pull-out curve (flatstep.model.pullout) on analytic cases and a brute-force search; ``flatstep curve``."""
from __future__ import annotations

import math

import numpy as np
import pytest

from flatstep.model.datasheet import from_datasheet
from flatstep.model.motor import MotorParams
from flatstep.model.pullout import (DRIVE_KINDS, convention_band, corner_speed, electrical_speed_limit,
                                    pullout_torque, top_speed)
from flatstep.studies.pullout import engine_pullout

NEMA17 = MotorParams.preset("nema17")


def test_no_resistance_has_closed_forms():
    """R -> 0, B = 0: i_d = 0 gives sqrt(V^2 - (Km w)^2)/(w_e L); weakening gives V/(w_e L) (constant power)."""
    m = NEMA17.replace(R=1e-6, B=0.0)
    V, current = 24.0, 1.0
    assert m.Km / (m.Nr * m.L) < current  # the characteristic current is inside the current disk
    w = np.array([150.0, 200.0, 300.0])
    we = m.Nr * w
    foc = np.sqrt(np.maximum(V**2 - (m.Km * w) ** 2, 0.0)) / (we * m.L)
    np.testing.assert_allclose(pullout_torque(m, "foc", V, current, w), m.Km * np.minimum(foc, current), rtol=1e-6)
    np.testing.assert_allclose(pullout_torque(m, "foc_weakening", V, current, w), m.Km * V / (we * m.L), rtol=1e-6)
    np.testing.assert_allclose(pullout_torque(m, "chopper", V, current, w), pullout_torque(m, "foc", V, current, w))


def test_low_speed_is_the_current_limit_and_the_corner_speed_is_where_it_ends():
    """Below the corner speed every drive gives Km I - B w; just above it, i_d = 0 gives less."""
    wc = corner_speed(NEMA17, 24.0, 1.0)
    assert wc == pytest.approx(39.79, rel=1e-3)
    for kind in DRIVE_KINDS:
        t = pullout_torque(NEMA17, kind, 24.0, 1.0, [0.0, 0.999 * wc])
        np.testing.assert_allclose(t, NEMA17.Km - NEMA17.B * np.array([0.0, 0.999 * wc]), rtol=1e-9)
    above = pullout_torque(NEMA17, "foc", 24.0, 1.0, 1.05 * wc)[0]
    assert above < NEMA17.Km - NEMA17.B * 1.05 * wc - 1e-3


@pytest.mark.parametrize("kind", ["foc_weakening", "foc"])
def test_the_largest_iq_matches_a_brute_force_search(kind):
    """The two-disk maximum equals the largest i_q on a dense grid of currents that satisfy both limits."""
    m, V, current = NEMA17.replace(B=0.0), 24.0, 1.0
    d, q = np.meshgrid(np.linspace(-1, 1, 801), np.linspace(0, 1, 401))
    if kind == "foc":
        d = np.zeros_like(q)
    for w in (20.0, 60.0, 120.0, 250.0):
        z = m.R + 1j * m.Nr * w * m.L
        v = np.abs(z * (d + 1j * q) + 1j * m.Km * w)
        ok = (np.hypot(d, q) <= current) & (v <= V)
        best = q[ok].max() if ok.any() else 0.0
        assert pullout_torque(m, kind, V, current, w)[0] == pytest.approx(m.Km * best, abs=m.Km * 4e-3)


def test_top_speed_electrical_limit_and_square_wave():
    """The top speed at a load sits where the curve crosses it; the electrical limit is 2 pi f k / Nr."""
    w = top_speed(NEMA17, "chopper", 24.0, 1.0, 0.1)
    assert pullout_torque(NEMA17, "chopper", 24.0, 1.0, w - 1e-3)[0] >= 0.1 > \
        pullout_torque(NEMA17, "chopper", 24.0, 1.0, w + 1e-2)[0]
    assert top_speed(NEMA17, "chopper", 24.0, 1.0, 1.0) == 0.0  # more than the holding torque
    assert electrical_speed_limit(NEMA17, 20e3) == pytest.approx(2 * math.pi * 2000 / 50)
    square = pullout_torque(NEMA17, "chopper", 24.0, 1.0, 80.0, voltage_factor=4 / math.pi)[0]
    assert square > pullout_torque(NEMA17, "chopper", 24.0, 1.0, 80.0)[0]


def test_convention_band_brackets_the_nominal_curve():
    """The band of the conventions holds the curve of the datasheet's own reading, and is wide (sqrt 2 at rest)."""
    model = from_datasheet(step_angle=1.8, rated_current=0.84, holding_torque=0.2746, resistance=5.75,
                           inductance=9.3e-3, rotor_inertia=34e-7)
    w = np.linspace(0, 150, 31)
    low, high = convention_band(model, "chopper", 24.0, 0.84, w)
    nominal = pullout_torque(model.params, "chopper", 24.0, math.sqrt(2) * 0.84, w)
    assert (low <= nominal + 1e-12).all() and (nominal <= high + 1e-12).all()
    assert high[0] / low[0] == pytest.approx(1.1 / 0.9 * 2.0, rel=1e-9)  # Km x sqrt 2 and rho x sqrt 2


@pytest.mark.parametrize(("call", "match"), [
    (lambda: pullout_torque(NEMA17, "stepper", 24.0, 1.0, 1.0), "drive_kind"),
    (lambda: pullout_torque(NEMA17, "foc", 24.0, 1.0, [-1.0]), "speeds"),
    (lambda: pullout_torque(NEMA17, "foc", 24.0, 1.0, [np.nan]), "speeds"),
    (lambda: pullout_torque(NEMA17, "foc", -24.0, 1.0, 1.0), "v_bus"),
    (lambda: pullout_torque(NEMA17, "foc", 24.0, 1.0, 1.0, voltage_factor=2.0), "voltage_factor"),
])
def test_bad_input_is_refused(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_engine_keeps_most_of_the_model_load_at_low_speed():
    """At 20 rad/s the open-loop drive on the C engine carries 80-100 % of the model's pull-out torque (the undamped
    rotor rings about its load angle: docs/curves.md, 88 % measured)."""
    kept = engine_pullout(NEMA17, 24.0, 1.0, [20.0], iterations=7, progress=False)[0]
    model = pullout_torque(NEMA17, "chopper", 24.0, 1.0, 20.0)[0]
    assert 0.8 * model <= kept <= model


SCENARIO = """
[motor]
preset = "nema17"
[drive]
control_rate = 20000.0
v_bus = 24.0
"""


def test_cli_curve_prints_landmarks_and_writes_the_figure(cli, tmp_path):
    (tmp_path / "s.toml").write_text(SCENARIO)
    run = cli(["curve", "s.toml", "--current", "1.0", "--setting", "peak", "--load", "0.1", "--out", "c.png"],
              cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "corner speed 39.79 rad/s" in run.stdout
    assert "top speed at 0.1 N m, chopper: 68.94 rad/s" in run.stdout
    assert "electrical-frequency limit" in run.stdout
    assert (tmp_path / "c.png").read_bytes().startswith(b"\x89PNG")


def test_cli_curve_of_a_motor_file_needs_a_bus(cli, tmp_path):
    (tmp_path / "m.toml").write_text('[motor]\npreset = "nema17"\n')
    run = cli(["curve", "m.toml"], cwd=tmp_path)
    assert run.returncode == 2
    assert "--v-bus" in run.stderr
    run = cli(["curve", "m.toml", "--v-bus", "24", "--drive", "foc", "--json"], cwd=tmp_path)
    assert run.returncode == 0 and '"foc"' in run.stdout


def test_cli_curve_of_a_datasheet_motor_defaults_to_its_rated_current_and_gives_the_band(cli, tmp_path):
    (tmp_path / "m.toml").write_text("[motor]\nstep_angle = 1.8\nrated_current = 0.84\nholding_torque = 0.2746\n"
                                     "resistance = 5.75\ninductance = 9.3e-3\nrotor_inertia = 34e-7\n")
    run = cli(["curve", "m.toml", "--v-bus", "24", "--points", "5"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "current-vector norm 1.188 A" in run.stdout  # sqrt 2 x 0.84 A
    run = cli(["curve", "m.toml", "--v-bus", "24", "--current", "0.84", "--points", "5", "--json"], cwd=tmp_path)
    assert run.returncode == 0 and '"band"' in run.stdout
    run = cli(["curve", "m.toml", "--out", "m.toml", "--v-bus", "24"], cwd=tmp_path)
    assert run.returncode == 2 and "input" in run.stderr


def test_figure_legend_names_the_drives_in_the_docs_words(cli, tmp_path):
    """The legend says what docs/curves.md says (open-loop chopper, field-oriented with i_d = 0 or field weakening),
    not the drive kinds' internal names."""
    import json

    import matplotlib.pyplot as plt

    from flatstep.cli.curve import _plot

    (tmp_path / "s.toml").write_text(SCENARIO)
    run = cli(["curve", "s.toml", "--current", "1.0", "--points", "5", "--json"], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    fig = _plot(json.loads(run.stdout))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    plt.close(fig)
    assert labels[:3] == ["open-loop chopper (step/dir driver)", "field-oriented, i_d = 0",
                          "field-oriented, field weakening"]
    assert not set(labels) & set(DRIVE_KINDS)
