"""The C core against the Python reference on the shared vectors (tests/vectors/core.json, tools/gen_vectors.py)."""
import json
from pathlib import Path

import numpy as np
import pytest

import flatstep as fs
from flatstep import core
from flatstep.core.structs import _plant
from flatstep.control.smc import FlatnessSMC, SMCGains
from flatstep.model.flat import FlatFlag
from flatstep.model.motor import MotorParams
from flatstep.plan.rest_to_rest import RestToRest

VECTORS = json.loads((Path(__file__).parent / "vectors" / "core.json").read_text())
RTOL = 1e-12


def assert_rel(c, p, what):
    """Componentwise |c - p| <= 1e-12 |p| (exact where the reference is 0)."""
    c, p = np.asarray(c, dtype=float).ravel(), np.asarray(p, dtype=float).ravel()
    bad = np.abs(c - p) > RTOL * np.abs(p)
    assert not bad.any(), f"{what}: C {c[bad]} vs Python {p[bad]}"


def test_vectors_cover_every_map():
    counts = {k: len(v) for k, v in VECTORS.items() if isinstance(v, list)}
    assert min(counts.values()) >= 100, counts
    assert {r["measurement"] for r in VECTORS["smc"]} == {"ideal", "model"}
    assert len({json.dumps(r["gains"]) for r in VECTORS["smc"]}) == 3
    assert len({json.dumps(r["motor"]) for r in VECTORS["smc"]}) == 2


def test_plan_eval():
    by_plan: dict[str, list] = {}
    for r in VECTORS["plan"]:
        by_plan.setdefault(json.dumps(r["plan"]), []).append(r)
    for key, recs in by_plan.items():
        flag = core.plan_flag(RestToRest(**json.loads(key)), [r["t"] for r in recs])
        assert_rel(np.array(flag).T, [r["flag"] for r in recs], key)


def test_flat_voltages():
    for r in VECTORS["flat_voltages"]:
        assert_rel(core.flat_voltages(MotorParams(**r["motor"]), *r["args"]), r["v"], r["args"])


def test_flat_to_state():
    for r in VECTORS["flat_to_state"]:
        x, v = core.flat_to_state(FlatFlag(*r["flag"]), MotorParams(**r["motor"]), r["load"])
        assert_rel(x, r["x"], r["flag"])
        assert_rel(v, r["v"], r["flag"])


def test_state_to_flat():
    for r in VECTORS["state_to_flat"]:
        flag = core.state_to_flat(r["x"], r["v"], MotorParams(**r["motor"]), r["load"])
        assert_rel(np.array(flag), r["flag"], r["x"])


def test_smc_step():
    groups: dict[str, list] = {}
    for r in VECTORS["smc"]:
        groups.setdefault(json.dumps([r["motor"], r["plan"], r["gains"], r["measurement"]]), []).append(r)
    for key, recs in groups.items():
        motor, plan, gains, measurement = json.loads(key)
        ctrl = FlatnessSMC(MotorParams(**motor), RestToRest(**plan), SMCGains(**gains), measurement)
        y = np.array([r["y"] for r in recs]).T
        v, status = core.smc_voltages(ctrl, [r["t"] for r in recs], y[:4], y[4] if measurement == "ideal" else None)
        assert not status.any(), core.status_names(np.bitwise_or.reduce(status))
        assert_rel(v.T, [r["v"] for r in recs], key)


def test_binding_matches_the_reference_on_arrays_with_shape(motor, plan):
    """The binding keeps the reference's array shapes (components first, then the sample shape)."""
    t = np.linspace(0.0, 0.06, 12).reshape(3, 4)
    flag_c, flag_p = core.plan_flag(plan, t), plan.flag(t)
    assert np.shape(flag_c) == (6, 3, 4)
    np.testing.assert_array_equal(np.array(flag_c), np.array(flag_p))
    x_c, v_c = core.flat_to_state(flag_c, motor)
    assert x_c.shape == (4, 3, 4) and v_c.shape == (2, 3, 4)


@pytest.mark.parametrize("state, ddtheta, names", [
    ([np.nan, 0.0, 0.0, 0.0], 0.0, ["nonfinite"]),
    ([0.4, 0.0, 0.0, 0.0], np.inf, ["nonfinite"]),
    ([0.0, 0.0, 0.0, 0.0], 0.0, ["rho"]),
    ([0.4, 0.0, 0.0, 0.0], 1e5, ["sqrt"]),
    ([200.0, 0.0, 0.0, 0.0], 0.0, ["saturated"]),
])
def test_smc_guards_where_the_reference_gives_nan_or_huge_voltages(motor, plan, state, ddtheta, names):
    ctrl = FlatnessSMC(motor, plan)
    v, status = core.smc_voltages(ctrl, 0.03, np.array(state)[:, None], ddtheta)
    assert core.status_names(status[0]) == names
    assert np.all(np.isfinite(v)) and np.hypot(*v[:, 0]) <= core.V_LIMIT * (1 + 1e-15)
    if names != ["saturated"]:
        assert np.all(v == 0.0)
    else:  # saturation keeps the direction of the reference's voltage
        ref = ctrl.voltages(0.03, np.array(state), ddtheta)
        np.testing.assert_allclose(v[:, 0], ref / np.hypot(*ref) * core.V_LIMIT, rtol=1e-12)


def test_binding_rejects_bad_input(motor, plan):
    ctrl = FlatnessSMC(motor, plan)
    with pytest.raises(ValueError, match="v_limit=0.0"):
        core.smc_voltages(ctrl, 0.0, np.zeros((4, 1)), 0.0, v_limit=0.0)
    with pytest.raises(ValueError, match=r"x has shape \(3, 1\)"):
        core.smc_voltages(ctrl, 0.0, np.zeros((3, 1)), 0.0)
    with pytest.raises(ValueError, match="ddtheta"):
        core.smc_voltages(ctrl, 0.0, np.zeros((4, 1)))
    with pytest.raises(ValueError, match="outside the domain"):
        core.flat_to_state(plan.flag(np.array([0.0, 0.03])), motor, load_torque=1.0)
    with pytest.raises(ValueError, match="ia = ib = 0"):
        core.state_to_flat(np.zeros(4), np.zeros(2), motor)
    assert np.isnan(core.flat_voltages(motor, 0.0, 0, 0, 0, 0, 0, 0, 0)).all()


BASELINES = {"microstep": (fs.Microstepping, fs.MicrostepGains), "cascade": (fs.CascadeFOC, fs.CascadeGains),
             "exact_linearization": (fs.ExactLinearization, fs.LinearizationGains)}
GAIN_FIELDS = {"microstep": ("current_bandwidth", "feedforward"),
               "cascade": ("current_bandwidth", "position_bandwidth", "decoupling"),
               "exact_linearization": ("wn", "xi", "p3", "pd")}
ABS_FLOOR = 1e-13  # integrals that cancel to ~1e-16 need a floor (tools/gen_vectors.py)


def _baseline(kind, r):
    cls, gains_cls = BASELINES[kind]
    gains = gains_cls(**{k: r["gains"][k] for k in GAIN_FIELDS[kind]})
    v_limit = np.inf if r["v_limit"] is None else r["v_limit"]
    return cls(MotorParams(**r["motor"]), RestToRest(**r["plan"]), gains, measurement=r["measurement"],
               control_period=r["control_period"], v_limit=v_limit)


@pytest.mark.parametrize("kind", list(BASELINES))
def test_baseline_steps_match_the_reference(kind):
    """One step of each baseline's C twin (bound through controller_struct) from the recorded state."""
    records = VECTORS[kind]
    assert len(records) >= 200
    for r in records:
        ctrl = _baseline(kind, r)
        bound = core.controller_struct(ctrl)
        if r["state"] is not None:
            for i, value in enumerate(r["state"]):
                bound.state.integral[i] = value
        v = core.ffi.new("double[2]")
        status = bound.iface.step(bound.iface.self, r["t"], core.ffi.new("double[5]", r["y"]), v)
        assert not status & core.FAULT_BITS
        c = np.array([v[0], v[1]] + ([bound.state.integral[i] for i in range(len(r["state"]))] if r["state"] else []))
        p = np.array(r["v"] + (r["state_after"] or []))
        err = np.abs(c - p)
        assert np.all(err <= 1e-12 * np.abs(p) + ABS_FLOOR), f"{kind}: C {c} vs Python {p}"


def test_plant_effects_match_the_reference():
    """plant_rhs (csrc/plant.c) against flatstep.model.plant.plant_rhs with detent, Coulomb and iron loss."""
    active = 0
    for r in VECTORS["plant"]:
        effects = None if r["effects"] is None else fs.PlantEffects(**r["effects"])
        active += effects is not None and effects.active
        plant = _plant(MotorParams(**r["motor"]), r["load"], effects)
        dx = core.ffi.new("double[4]")
        core.lib.plant_rhs(plant, core.ffi.new("double[4]", r["x"]), core.ffi.new("double[2]", r["v"]), dx)
        c, p = np.array(list(dx)), np.array(r["dx"])
        assert np.all(np.abs(c - p) <= 1e-12 * np.abs(p) + ABS_FLOOR), f"C {c} vs Python {p} ({r['effects']})"
    assert active >= 100
