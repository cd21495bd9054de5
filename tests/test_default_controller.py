"""The controller a scenario file runs when it names none (docs/comparison.md, "The default controller")."""
import math
from pathlib import Path

import pytest

from flatstep.control.spec import (
    DEFAULT_TYPE,
    DEFAULT_TYPE_CONTINUOUS,
    DEFAULT_TYPE_TORQUES,
    ControllerSpec,
    default_type,
)
from flatstep.studies.scenario_file import load_scenario

DRIVE = "[drive]\ncontrol_rate = 20000.0\nv_bus = 24.0\n"
TORQUES = "[feedforward]\ndetent_torque = 1e-3\n"


def test_the_default_types():
    """The default is the plan-frame cascade on a drive (with the torques' options where known), smc without one."""
    assert default_type(sampled=True, torques=False) == DEFAULT_TYPE == "cascade+voltage_feedforward+plan_frame"
    assert default_type(sampled=True, torques=True) == DEFAULT_TYPE_TORQUES
    assert ControllerSpec.parse(DEFAULT_TYPE_TORQUES) == ControllerSpec(
        "cascade", feedforward=True, observer_torques=True, voltage_feedforward=True, plan_frame=True)
    assert default_type(sampled=False, torques=True) == DEFAULT_TYPE_CONTINUOUS == "smc"


@pytest.mark.parametrize("text, kind", [
    (DRIVE, DEFAULT_TYPE),
    (DRIVE + TORQUES, DEFAULT_TYPE_TORQUES),
    ("[controller]\nW1 = 50.0\n", "smc"),                      # no drive: the paper's law in continuous time
    (DRIVE + '[controller]\ntype = "smc"\n', "smc"),          # the paper's law by name
    (DRIVE + '[controller]\nlaw = "dq_smc"\n', "dq_smc"),
])
def test_a_file_runs_the_default_unless_it_names_a_law(tmp_path, text, kind):
    """A file runs the default controller unless its [controller] table names a type or a law."""
    path = tmp_path / "s.toml"
    path.write_text(text)
    scenario = load_scenario(path)[0]
    assert scenario.controller_type == kind
    assert ControllerSpec.parse(scenario.controller_type).law == ControllerSpec.parse(kind).law


def test_sliding_gains_without_a_type_name_the_default(tmp_path):
    """Sliding gains in a file that names no type are refused, naming the default's law."""
    path = tmp_path / "s.toml"
    path.write_text(DRIVE + "[controller]\nW1 = 50.0\n")
    with pytest.raises(ValueError, match=r"controller.W1: W1 is not a gain of law 'cascade' \(the file names no type"):
        load_scenario(path)


def test_without_torques_turns_off_what_needs_them():
    """Without the torques a type loses the options that need them and keeps the rest."""
    spec = ControllerSpec.parse(DEFAULT_TYPE_TORQUES).without_torques()
    assert spec.name() == DEFAULT_TYPE
    assert ControllerSpec.parse("dq_smc_i_ff_km").without_torques().name() == "dq_smc_i"
    assert ControllerSpec.parse("smc_la").without_torques().name() == "smc_la"


def test_compare_clean_runs_a_file_whose_default_knows_the_torques(cli):
    """--clean drops [feedforward]: the file's default law runs without the options that need it."""
    path = Path(__file__).parent.parent / "examples" / "compare-paper-20khz.toml"
    run = cli(["compare", str(path), "--tuned", "--clean", "--controllers", "cascade", "--budget", "10",
               "--population", "5", "--frontier", "1", "--quiet"])
    assert run.returncode == 0, run.stderr
    assert "compare-paper-20khz (clean)" in run.stdout and "cascade" in run.stdout


@pytest.mark.parametrize("text, kind", [
    # options without a law are set over the default's law and options, not over the paper's law
    (DRIVE + TORQUES + "[controller]\nfeedforward = true\n", DEFAULT_TYPE_TORQUES),
    (DRIVE + TORQUES + "[controller]\nobserver_torques = false\n",
     "cascade+feedforward+voltage_feedforward+plan_frame"),
    (DRIVE + "[controller]\nvoltage_feedforward = false\n", "cascade+plan_frame"),
    (TORQUES + "[controller]\nfeedforward = true\n", "smc_ff"),  # no drive: the default is the paper's law
])
def test_options_without_a_law_follow_the_default(tmp_path, text, kind):
    """Options given without a law are set over the default's law and options."""
    path = tmp_path / "s.toml"
    path.write_text(text)
    assert load_scenario(path)[0].controller_type == kind


def test_an_option_the_default_law_does_not_take_needs_a_law(tmp_path):
    """Integral is an option of dq_smc alone: without a law the default (the cascade) cannot take it."""
    path = tmp_path / "s.toml"
    path.write_text(DRIVE + "[controller]\nintegral = true\n")
    with pytest.raises(ValueError, match=r"s.toml:controller.integral: the table names no law, so the controller is "
                                         r"the default 'cascade\+voltage_feedforward\+plan_frame' "
                                         r"\(law 'cascade'.*law = one of "
                                         r"\['dq_smc'\]"):
        load_scenario(path)


def test_the_default_follows_the_plan_frame_rule(tmp_path):
    """The default's gains: the rule of flatstep.control.cascade.plan_frame_rule, from Ts, the plan and the model."""
    import math

    from flatstep.control.cascade import PLAN_FRAME_RULE

    path = tmp_path / "s.toml"
    path.write_text('t_end = 0.1\n[motor]\npreset = "nema17"\n[plan]\ntheta2 = 0.5\nrho1 = 1.0\nrho2 = 1.0\n'
                    't0 = 0.01\ntf = 0.07\n' + DRIVE)
    sc = load_scenario(path)[0]
    g, m, r = sc.controller().gains, sc.motor, PLAN_FRAME_RULE
    assert g.plan_frame and g.voltage_feedforward and g.d_hold == pytest.approx(r["d_hold"])  # the bus has room
    Ts = 1 / 20000.0
    w = min(r["w_ts"] / Ts, math.sqrt(m.Km * r["d_hold"] * 1.0 * m.Nr / m.J))
    assert g.current_bandwidth == pytest.approx(r["lambda_ts"] / Ts)
    assert w < r["w_ts"] / Ts  # the spring, not the sampling, sets the loop here: no take-over
    assert (g.k_theta, g.ki_omega) == pytest.approx((r["k_theta"] * w, r["ki_omega"] * w * w))
    assert g.k_omega == pytest.approx(r["k_omega_ts"] / Ts)  # no encoder in the file: the sampling's bound alone
    spring = math.sqrt(m.Km * r["d_hold"] * 1.0 * m.Nr / m.J)
    text = path.read_text()
    for rate in (10000.0, 5000.0):
        slow = load_scenario(path.write_text(text.replace("20000.0", str(rate))) and path)[0]
        gs = slow.controller().gains
        assert gs.k_omega == pytest.approx(r["k_omega_ts"] * rate)  # capped by Ts
        # the sampling caps the loop below the spring: the spring takes over (more held), the integral slows
        cap = r["w_ts"] * rate
        short = cap / spring
        assert short < 1.0
        assert r["d_hold"] < gs.d_hold <= min(1.0, r["d_hold"] / short**2) * (1 + 1e-12)
        # the current loops and the position gain follow the spring, the integral falls: by powers of r, floored
        rbar = max(short, r["r_min"])
        assert gs.ki_omega == pytest.approx(r["ki_omega"] * cap**2 * rbar ** r["integral_fall"])
        assert gs.k_theta == pytest.approx(r["k_theta"] * cap / rbar ** r["follow_position"])
        lam = min(r["lambda_ts"] / rbar ** r["follow_current"], r["lambda_ts_max"])
        assert gs.current_bandwidth == pytest.approx(lam * rate)
        if rate == 10000.0:  # r = 0.77: the current loops by 1/r^2, under their fastest
            assert short > r["r_min"] and lam < r["lambda_ts_max"]
            assert gs.k_theta > r["k_theta"] * spring  # above the spring's frequency's gain
        else:  # r = 0.38: the fastest current loop, its discrete pole inside the unit circle
            assert short < r["r_min"] and gs.current_bandwidth / rate == pytest.approx(r["lambda_ts_max"])
        assert 0.0 < gs.current_bandwidth / rate < 2.0  # a discrete pole 1 - lambda Ts inside the unit circle


@pytest.mark.parametrize("counts, rho", [(16384, 1.0), (16384, 0.3), (4000, 1.0), (4000, 0.3)])
def test_the_default_velocity_gain_follows_the_encoder(tmp_path, counts, rho):
    """k_omega: half the sampling rate, or less where one count per period of speed error asks more than 2 rho*."""
    import math

    from flatstep.control.cascade import PLAN_FRAME_RULE

    path = tmp_path / "s.toml"
    path.write_text(f't_end = 0.1\n[motor]\npreset = "nema17"\n[plan]\ntheta2 = 0.5\nrho1 = {rho}\nrho2 = {rho}\n'
                    f't0 = 0.01\ntf = 0.07\n[sensors]\nencoder_counts = {counts}\n' + DRIVE)
    sc = load_scenario(path)[0]
    g, m, r, Ts, q = sc.controller().gains, sc.motor, PLAN_FRAME_RULE, 1 / 20000.0, 2 * math.pi / counts
    by_count = r["k_omega_count"] * m.Km * rho * Ts / (m.J * q)
    assert g.k_omega == pytest.approx(min(r["k_omega_ts"] / Ts, by_count))
    # the bound: a speed error of one count per period asks at most k_omega_count times rho* of the q loop
    assert m.J * g.k_omega * q / (m.Km * Ts) <= r["k_omega_count"] * rho * (1 + 1e-12)
    # which bound holds: the sampling's on the fine encoder at 1 A, the encoder's on the coarse one or at 0.3 A
    assert (g.k_omega < r["k_omega_ts"] / Ts * 0.999) == (counts == 4000 or rho == 0.3)


def test_the_rule_without_an_angle_step_keeps_the_sampling_bound():
    """A context without an encoder count (an exact angle) gives the sampling's bound alone; a negative is refused."""
    from flatstep.control.build import BuildContext
    from flatstep.control.cascade import PLAN_FRAME_RULE, plan_frame_rule
    from flatstep.model.motor import PRESETS
    from flatstep.plan.rest_to_rest import RestToRest

    plan = RestToRest(0.0, 0.5, 0.3, 0.3, 0.01, 0.07)
    exact = plan_frame_rule(BuildContext(PRESETS["nema17"], plan, "observer", control_period=5e-5))
    counted = plan_frame_rule(BuildContext(PRESETS["nema17"], plan, "observer", control_period=5e-5,
                                           angle_step=2 * math.pi / 16384))
    assert exact["k_omega"] == pytest.approx(PLAN_FRAME_RULE["k_omega_ts"] / 5e-5)
    assert counted["k_omega"] < exact["k_omega"]
    assert {k: v for k, v in exact.items() if k != "k_omega"} == {k: v for k, v in counted.items() if k != "k_omega"}
    with pytest.raises(ValueError, match=r"angle_step=-1.0 rad must be >= 0"):
        BuildContext(PRESETS["nema17"], plan, "observer", control_period=5e-5, angle_step=-1.0)


def test_the_default_holds_less_where_the_bus_is_short(tmp_path):
    """The held share falls until the move's feedforward with it fits in 3/4 of the bus; the loop keeps its speed."""
    from flatstep.control.cascade import HOLD_VOLTAGE_SHARE, PLAN_FRAME_RULE

    text = ('t_end = 0.1\n[motor]\npreset = "nema17"\n[plan]\ntheta2 = 0.5\nrho1 = 1.0\nrho2 = 1.0\n'
            't0 = 0.01\ntf = 0.07\n')
    holds, k_omega = [], []
    for bus in (24.0, 12.0, 8.0):
        path = tmp_path / f"s{bus:g}.toml"
        path.write_text(text + DRIVE.replace("24.0", str(bus)))
        g = load_scenario(path)[0].controller().gains
        holds.append(g.d_hold)
        k_omega.append(g.k_omega)
    assert holds[0] == pytest.approx(PLAN_FRAME_RULE["d_hold"]) and holds[0] > holds[1] > holds[2] >= 0.0
    assert k_omega[0] == k_omega[1] == k_omega[2]
    assert 0.0 < HOLD_VOLTAGE_SHARE < 1.0
