"""Controllers as a spec (flatstep.control.spec): a law and orthogonal options, the historical names as aliases."""
import pytest

import flatstep as fs
from flatstep.control.spec import ALIASES, LAWS, ControllerSpec
from flatstep.control.tuning import (CONTINUOUS_TYPES, CONTROLLER_TYPES, FEEDFORWARD_TYPES, REST_HOLD_DAMPING,
                                     SMC_TYPES, label, make_controller)
from flatstep.model.torque_model import TorqueModel

MOTOR = fs.MotorParams.preset("paper")
TORQUES = TorqueModel(detent_torque=1e-3)


def build(kind, **kw):
    return make_controller(kind, MOTOR, fs.PAPER_PLAN, control_period=5e-5, measurement="observer",
                           torques=TORQUES, **kw)


def test_the_derived_facts_are_the_historical_ones():
    assert CONTROLLER_TYPES[0] == "smc" and len(CONTROLLER_TYPES) == 15
    assert set(FEEDFORWARD_TYPES) == {"smc_ff", "dq_smc_ff", "smc_la_ff", "cascade_ff", "cascade_model",
                                      "dq_smc_i_ff", "smc_ff_hold", "dq_smc_i_ff_km"}
    assert set(SMC_TYPES) == {"smc", "dq_smc", "smc_la", "smc_ff", "dq_smc_ff", "smc_la_ff", "dq_smc_i",
                              "dq_smc_i_ff", "smc_ff_hold", "dq_smc_i_ff_km"}
    assert set(CONTINUOUS_TYPES) == set(SMC_TYPES) - {"dq_smc_i", "dq_smc_i_ff", "dq_smc_i_ff_km"}


@pytest.mark.parametrize("alias", list(ALIASES))
def test_every_alias_round_trips_and_builds_its_law(alias):
    spec = ControllerSpec.parse(alias)
    assert spec.name() == alias and ControllerSpec.parse(spec.name()) == spec
    composed = "+".join([spec.law] + [k for k in ("feedforward", "observer_torques", "integral", "km_estimate", "hold")
                                      if getattr(spec, k)] + ([spec.rho_plan] if spec.rho_plan != "plan" else []))
    assert ControllerSpec.parse(composed) == spec  # the composed name reads as the alias
    ctrl = build(alias)
    law_class = {"smc": fs.FlatnessSMC, "dq_smc": fs.DQFlatnessSMC, "cascade": fs.CascadeFOC,
                 "microstep": fs.Microstepping, "exact_linearization": fs.ExactLinearization}[spec.law]
    assert type(ctrl) is law_class
    torques = getattr(ctrl, "torques", None)
    if torques is not None:
        assert (torques == TORQUES) == spec.feedforward
    if spec.law == "dq_smc":
        assert (ctrl.integral is not None) == spec.integral and (ctrl.adaptation is not None) == spec.km_estimate
    if spec.law == "smc":
        assert (ctrl.loss_aware is not None) == (spec.rho_plan == "loss_aware")
        assert (ctrl.gains.hold_damping == REST_HOLD_DAMPING) == spec.hold


def test_a_combination_without_a_historical_name_is_a_controller():
    spec = ControllerSpec.parse("smc+hold")
    assert spec == ControllerSpec("smc", hold=True) and spec.name() == "smc+hold" and not spec.needs_torques
    ctrl = build("smc+hold")
    assert ctrl.gains.hold_damping == REST_HOLD_DAMPING and ctrl.torques != TORQUES
    assert label("smc+hold") == "flatness + SMC, hold"
    assert ControllerSpec.parse({"law": "dq_smc", "integral": True, "feedforward": True}).name() == "dq_smc_i_ff"


@pytest.mark.parametrize("value, match", [
    ("cascade+integral", r"integral=true is not an option of law 'cascade'"),
    ("dq_smc+km_estimate", "needs integral=true and feedforward=true"),
    ("cascade+observer_torques", "needs feedforward=true"),
    ("microstep+feedforward", "not an option of law 'microstep'"),
    ("smc+hold+loss_aware", "give one of them"),
    ("dq_smc+loss_aware", "rho_plan='loss_aware' is an option of"),
    ("pid", "'pid' is unknown"),
    ("smc+turbo", "unknown option 'turbo'"),
    (3, "is not a controller name"),
    ({"law": "smc", "speed": 1}, r"unknown key\(s\) \['speed'\]"),
    ({"law": "smc", "feedforward": "yes"}, "feedforward='yes' is not true or false"),
    ({"law": "fast"}, "law='fast' is unknown"),
])
def test_invalid_specs_are_refused_naming_what_is_valid(value, match):
    with pytest.raises(ValueError, match=match):
        ControllerSpec.parse(value)


def test_every_law_has_a_default_spec_and_options_listed():
    for law in LAWS:
        assert ControllerSpec.parse(law).law == law
    assert ControllerSpec.options_of("dq_smc") == ["feedforward", "integral", "km_estimate", "advance"]


DRIVE = "[drive]\ncontrol_rate = 20000.0\nv_bus = 24.0\n[sensors]\nencoder_counts = 16384\n[controller]\ndesign = true\n"


@pytest.mark.parametrize("keys, name", [('law = "dq_smc"\nintegral = true\n', "dq_smc_i"),
                                        ('law = "smc"\nhold = true\n', "smc+hold"),
                                        ('type = "smc+hold"\n', "smc+hold"),
                                        ('type = "cascade_model"\n', "cascade_model")])
def test_a_scenario_file_names_its_controller_by_type_or_by_law_and_options(tmp_path, keys, name):
    from flatstep.studies.scenario_file import load_scenario

    path = tmp_path / "s.toml"
    path.write_text(DRIVE + keys + ("[feedforward]\nload = 0.0\n" if name == "cascade_model" else ""))
    assert load_scenario(path)[0].controller_type == name


@pytest.mark.parametrize("keys, match", [
    ('law = "smc"\ntype = "smc"\n', r"s.toml:controller: give the controller by type='smc' or by law"),
    ('law = "dq_smc"\nhold = true\n', r"s.toml:controller: hold=true is not an option of law 'dq_smc'"),
    ('type = "pid"\n', r"s.toml:controller.type: type='pid' is unknown"),
    ('law = "pid"\n', r"s.toml:controller: law='pid' is unknown"),
])
def test_a_bad_controller_in_a_file_names_its_key(tmp_path, keys, match):
    from flatstep.studies.scenario_file import load_scenario

    path = tmp_path / "s.toml"
    path.write_text(DRIVE + keys)
    with pytest.raises(ValueError, match=match):
        load_scenario(path)
