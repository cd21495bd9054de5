"""Write the C core's parity vectors from the Python reference: tests/vectors/core.json and core.txt.

core.json is read by tests/test_core_parity.py; core.txt holds the same records one per line
(``kind`` then numbers, shortest round-trip decimals) for the C unit test, which reads it with stdio.
Run ``python tools/gen_vectors.py`` after a change to the reference; the output is deterministic.
Records: the plan, the flat maps and the sliding controller (paper's motors and moves), then on their own random
stream one ``step`` of each baseline (microstep, cascade, exact_linearization: state before, voltages, state
after; random motors, moves, gains, control periods and buses, v_limit None for inf) and ``plant`` (plant_rhs
with random effects).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from flatstep import (
    PAPER_PLAN,
    CascadeFOC,
    ExactLinearization,
    FlatnessSMC,
    Microstepping,
    MotorParams,
    PlantEffects,
    RestToRest,
    SMCGains,
    flat_to_state,
    state_to_flat,
)
from flatstep.control import CascadeGains, LinearizationGains, MicrostepGains
from flatstep.model.flat import flat_voltages
from flatstep.model.plant import plant_rhs

OUT = Path(__file__).resolve().parents[1] / "tests" / "vectors"
PAPER = MotorParams.preset("paper")
MOTORS = [PAPER, PAPER.replace(R=12.0, L=0.005), PAPER.replace(Km=0.08, J=7e-6, B=0.0),
          PAPER.replace(Nr=1, B=3e-4), MotorParams(R=1.2, L=0.0025, Km=0.3, J=2e-5, B=5e-4, Nr=50)]
PLANS = [PAPER_PLAN, RestToRest(0.0, -0.03, 0.4, 0.3, 0.01, 0.025), RestToRest(0.1, 0.13, 0.5, 0.45, 0.0, 0.05),
         RestToRest(-0.2, -0.19, 0.3, 0.35, 0.005, 0.015)]
GAINS = [SMCGains(), SMCGains(W1=300.0, W2=300.0), SMCGains(W1=50.0, W2=500.0, eps1=0.01, eps2=0.002, xi=0.7,
                                                            wn=20.0)]
LOADS = [0.0, 1e-5, -2e-5]
V_MAX = 900.0  # keep the controller vectors below the C core's default v_limit of 1e3 V

MOTOR_KEYS = ("R", "L", "Km", "J", "B", "Nr")
PLAN_KEYS = ("theta1", "theta2", "rho1", "rho2", "t0", "tf")
GAIN_KEYS = ("W1", "W2", "eps1", "eps2", "xi", "wn")
LIN_KEYS = ("wn", "xi", "p3", "pd")


def times(plan: RestToRest, rng: np.random.Generator, n: int) -> np.ndarray:
    """Sample times around the plan: its knots exactly, just inside and outside them, and random ones."""
    T = plan.tf - plan.t0
    edges = [plan.t0, plan.tf, plan.t0 + 1e-9, plan.tf - 1e-9, plan.t0 - 1e-3, plan.tf + 1e-3, 0.0]
    return np.concatenate([edges, plan.t0 + T * rng.uniform(-0.2, 1.2, n)])


def main() -> None:
    """Write tests/vectors/core.json and core.txt from the reference, with a fixed seed."""
    rng = np.random.default_rng(20240601)
    rec: dict[str, list] = {"plan": [], "flat_voltages": [], "flat_to_state": [], "state_to_flat": [], "smc": []}
    for plan in PLANS:
        t = times(plan, rng, 40)
        flag = np.array(plan.flag(t))
        rec["plan"] += [dict(plan=plan.as_dict(), t=float(ti), flag=f.tolist())
                        for ti, f in zip(t, flag.T, strict=True)]
    for motor in MOTORS:
        # flat_voltages in its domain |A| < Km rho: A a random fraction of Km rho
        n = 30
        rho = rng.uniform(0.05, 1.0, n)
        args = [rho, rng.normal(0, 20, n), rng.uniform(-1, 1, n), rng.normal(0, 5, n), rng.normal(0, 500, n),
                rng.normal(0, 1e5, n), rng.uniform(-np.pi, np.pi, n), rng.uniform(-0.95, 0.95, n) * motor.Km * rho]
        v = flat_voltages(motor, *args)
        rec["flat_voltages"] += [dict(motor=motor.as_dict(), args=[float(a[i]) for a in args], v=v[:, i].tolist())
                                 for i in range(n)]
        for load in LOADS:
            for plan in PLANS[:2]:
                t = np.linspace(plan.t0 - 0.002, plan.tf + 0.002, 13)
                flag = plan.flag(t)
                x, v = flat_to_state(flag, motor, load)
                rec["flat_to_state"] += [dict(motor=motor.as_dict(), load=load, flag=np.array(flag)[:, i].tolist(),
                                              x=x[:, i].tolist(), v=v[:, i].tolist()) for i in range(t.size)]
            x = np.array([rng.normal(0, 0.4, 8), rng.normal(0, 0.4, 8), rng.normal(0, 5, 8), rng.uniform(-1, 1, 8)])
            v = rng.normal(0, 5, (2, 8))
            flag = np.array(state_to_flat(x, v, motor, load))
            rec["state_to_flat"] += [dict(motor=motor.as_dict(), load=load, x=x[:, i].tolist(), v=v[:, i].tolist(),
                                          flag=flag[:, i].tolist()) for i in range(8)]
    for motor in MOTORS[:2]:
        for plan in PLANS:
            for gains in GAINS:
                for measurement in ("ideal", "model"):
                    rec["smc"] += smc_records(FlatnessSMC(motor, plan, gains, measurement), rng)
    # The baselines and the plant effects, after the records above and on their own stream (those stay unchanged).
    rng = np.random.default_rng(20250301)
    rec["microstep"] = [r for _ in range(24) for r in microstep_records(rng)]
    rec["cascade"] = [r for _ in range(24) for r in cascade_records(rng)]
    rec["exact_linearization"] = [r for _ in range(24) for r in linearization_records(rng)]
    rec["plant"] = plant_records(rng, 160)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "core.json").write_text(json.dumps({"generator": "tools/gen_vectors.py", **rec}, indent=None) + "\n")
    (OUT / "core.txt").write_text(text_lines(rec))
    print({k: len(v) for k, v in rec.items()})


def smc_records(ctrl: FlatnessSMC, rng: np.random.Generator) -> list[dict]:
    """Controller outputs at states scattered around the reference state (on it for the first samples)."""
    t = times(ctrl.plan, rng, 8)
    ref = ctrl.plan.flag(t)
    x, _ = flat_to_state(ref, ctrl.motor)
    scale = np.array([0.02, 0.02, 0.5, 2e-3])[:, None] * (np.arange(t.size) >= 3)
    x = x + scale * rng.normal(size=x.shape)
    acc = np.asarray(ref.ddtheta) + 50 * rng.normal(size=t.size) * (np.arange(t.size) >= 3)
    v = ctrl.voltages(t, x, acc if ctrl.measurement == "ideal" else None)
    keep = np.all(np.isfinite(v), axis=0) & (np.hypot(v[0], v[1]) < V_MAX)
    gains = ctrl.gains.as_dict()  # the SMC gains of the paper's law: the records predate hold_damping
    base = dict(motor=ctrl.motor.as_dict(), plan=ctrl.plan.as_dict(), gains={k: gains[k] for k in GAIN_KEYS},
                measurement=ctrl.measurement)
    return [dict(base, t=float(t[i]), y=[*x[:, i].tolist(), float(acc[i])], v=v[:, i].tolist())
            for i in np.flatnonzero(keep)]


def random_motor(rng: np.random.Generator) -> MotorParams:
    """A motor of the size the library targets: Nr = 50 or 100 hybrids, an Nr = 1 machine now and then, B = 0 at times.

    The ranges: R 0.5-15 ohm, L 1-20 mH, Km 0.02-0.4, J 2e-6 to 5e-5 kg m^2.
    """
    return MotorParams(R=float(rng.uniform(0.5, 15.0)), L=float(np.exp(rng.uniform(np.log(1e-3), np.log(2e-2)))),
                       Km=float(rng.uniform(0.02, 0.4)), J=float(np.exp(rng.uniform(np.log(2e-6), np.log(5e-5)))),
                       B=float(rng.choice([0.0, rng.uniform(0.0, 5e-4)])), Nr=int(rng.choice([1, 50, 50, 100])))


def random_plan(rng: np.random.Generator) -> RestToRest:
    """A short rest-to-rest move with a change of current norm."""
    theta1, t0 = float(rng.uniform(-0.3, 0.3)), float(rng.uniform(0.0, 0.02))
    return RestToRest(theta1, theta1 + float(rng.uniform(-0.05, 0.05)), float(rng.uniform(0.2, 1.0)),
                      float(rng.uniform(0.2, 1.0)), t0, t0 + float(rng.uniform(0.01, 0.05)))


def random_move(rng: np.random.Generator) -> tuple[MotorParams, RestToRest]:
    """A random motor and plan whose torque demand stays within reach (drawn again until it does)."""
    while True:
        motor, plan = random_motor(rng), random_plan(rng)
        try:
            flat_to_state(plan.flag(np.linspace(plan.t0, plan.tf, 201)), motor)
        except ValueError:
            continue
        return motor, plan


def measurements(motor: MotorParams, plan: RestToRest, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Times around the plan and measurements y = (ia, ib, omega, theta, theta'') about its reference state.

    The first three samples sit on the reference state.
    """
    t = times(plan, rng, 3)
    ref = plan.flag(t)
    x, _ = flat_to_state(ref, motor)
    scale = np.array([0.05, 0.05, 2.0, 5e-3, 200.0])[:, None] * (np.arange(t.size) >= 3)
    y = np.vstack([x, np.asarray(ref.ddtheta)[None, :]])
    return t, y + scale * rng.normal(size=y.shape)


def v_limits(peak: np.ndarray, rng: np.random.Generator) -> list[float]:
    """Per sample: inf (no limit) for a third, else the peak voltage times 0.5 .. 1.5."""
    return [math.inf if rng.uniform() < 1 / 3 else float(p * rng.uniform(0.5, 1.5)) for p in peak]


def baseline_records(make, rng: np.random.Generator, n_state: int, state_scale) -> list[dict]:
    """Records of one baseline configuration, one ``step`` each; ``make(v_limit)`` builds the controller.

    The state before is its initial state (first two samples) or random (``state_scale``), none for a static law;
    each sample has its own v_limit: None (inf) or around its peak voltage, so that about half of the finite
    ones hold the integrators (anti-windup). v_limit None in the JSON is inf ("inf" in core.txt).
    """
    ctrl = make(math.inf)
    t, y = measurements(ctrl.motor, ctrl.plan, rng)
    if n_state:
        state = [ctrl.initial_state() if i < 2 else np.asarray(state_scale) * rng.normal(size=n_state)
                 for i in range(t.size)]
    else:
        state = [None] * t.size
    peak = np.array([np.max(np.abs(ctrl.step(state[i], y[:, i], float(t[i]))[0])) for i in range(t.size)])
    out = []
    for i, v_limit in enumerate(v_limits(peak, rng)):
        c = make(v_limit)
        v, new = c.step(state[i], y[:, i], float(t[i]))
        out.append(dict(motor=c.motor.as_dict(), plan=c.plan.as_dict(), gains=c.gains.as_dict(),
                        measurement=c.measurement, control_period=c.control_period,
                        v_limit=None if math.isinf(v_limit) else v_limit, t=float(t[i]),
                        state=None if state[i] is None else np.asarray(state[i], dtype=float).tolist(),
                        y=y[:, i].tolist(), v=np.asarray(v, dtype=float).tolist(),
                        state_after=None if new is None else np.asarray(new, dtype=float).tolist()))
    return out


def microstep_records(rng: np.random.Generator) -> list[dict]:
    """Microstepping steps for a random motor, plan, bandwidth, feedforward, control period and bus."""
    motor, plan = random_move(rng)
    Ts = float(np.exp(rng.uniform(np.log(2e-5), np.log(2e-4))))
    gains = MicrostepGains(float(0.3 / Ts * rng.uniform(0.5, 2.0)), feedforward=bool(rng.uniform() < 0.7))
    return baseline_records(lambda v_limit: Microstepping(motor, plan, gains, control_period=Ts, v_limit=v_limit),
                            rng, 2, [2.0, 2.0])


def cascade_records(rng: np.random.Generator) -> list[dict]:
    """Cascade steps for a random motor, plan, bandwidths, decoupling, control period and bus."""
    motor, plan = random_move(rng)
    Ts = float(np.exp(rng.uniform(np.log(2e-5), np.log(2e-4))))
    wc = float(0.3 / Ts * rng.uniform(0.5, 2.0))
    gains = CascadeGains(wc, float(wc / 4 * rng.uniform(0.5, 2.0)), decoupling=bool(rng.uniform() < 0.7))
    return baseline_records(lambda v_limit: CascadeFOC(motor, plan, gains, control_period=Ts, v_limit=v_limit),
                            rng, 3, [500.0, 1.0, 1.0])


def linearization_records(rng: np.random.Generator) -> list[dict]:
    """Exact-linearization steps for a random motor, plan, poles, measurement mode and bus."""
    motor, plan = random_move(rng)
    lam = float(0.3 / np.exp(rng.uniform(np.log(2e-5), np.log(2e-4))))
    gains = LinearizationGains(wn=float(lam / 4 * rng.uniform(0.5, 2.0)), xi=float(rng.uniform(0.5, 1.2)),
                               p3=float(lam * rng.uniform(0.5, 2.0)), pd=float(lam * rng.uniform(0.5, 2.0)))
    measurement = str(rng.choice(["ideal", "model", "model", "observer"]))
    return baseline_records(lambda v_limit: ExactLinearization(motor, plan, gains, measurement=measurement,
                                                               v_limit=v_limit), rng, 0, None)


def plant_records(rng: np.random.Generator, n: int) -> list[dict]:
    """plant_rhs at random states, voltages, loads and effects.

    Each effect is absent now and then, the iron loss None; the first records have no effects object at all.
    """
    out = []
    for i in range(n):
        motor = random_motor(rng)
        effects = PlantEffects(detent_torque=float(rng.choice([0.0, rng.uniform(0.0, 0.02)])),
                               coulomb_torque=float(rng.choice([0.0, rng.uniform(0.0, 0.01)])),
                               coulomb_speed=float(np.exp(rng.uniform(np.log(1e-3), np.log(1.0)))),
                               magnetizing_resistance=None if rng.uniform() < 0.4 else float(rng.uniform(5.0, 500.0)))
        load = float(rng.choice([0.0, rng.normal(0.0, 5e-3)]))
        x = np.array([rng.normal(0, 0.5), rng.normal(0, 0.5), rng.normal(0, 20.0), rng.uniform(-1.0, 1.0)])
        v = rng.normal(0, 10.0, 2)
        dx = plant_rhs(x, v, motor, load, None if i < 4 else effects)
        out.append(dict(motor=motor.as_dict(), load=load, effects=None if i < 4 else effects.as_dict(),
                        x=x.tolist(), v=v.tolist(), dx=np.asarray(dx, dtype=float).tolist()))
    return out


def text_lines(rec: dict[str, list]) -> str:
    """The records as ``kind n1 n2 ...`` lines (see csrc/tests/test_core.c for the column order)."""
    def m(r):
        return [r["motor"][k] for k in MOTOR_KEYS]

    lines = ["# generated by tools/gen_vectors.py from the Python reference; do not edit"]
    for r in rec["plan"]:
        lines.append(["plan", *(r["plan"][k] for k in PLAN_KEYS), r["t"], *r["flag"]])
    for r in rec["flat_voltages"]:
        lines.append(["fv", *m(r), *r["args"], *r["v"]])
    for r in rec["flat_to_state"]:
        lines.append(["f2s", *m(r), r["load"], *r["flag"], *r["x"], *r["v"]])
    for r in rec["state_to_flat"]:
        lines.append(["s2f", *m(r), r["load"], *r["x"], *r["v"], *r["flag"]])
    for r in rec["smc"]:
        lines.append(["smc", *m(r), *(r["plan"][k] for k in PLAN_KEYS), *(r["gains"][k] for k in GAIN_KEYS),
                      int(r["measurement"] == "model"), r["t"], *r["y"], *r["v"]])
    def lim(r):
        return math.inf if r["v_limit"] is None else r["v_limit"]

    for r in rec["microstep"]:
        g = r["gains"]
        lines.append(["ms", *m(r), *(r["plan"][k] for k in PLAN_KEYS), g["current_bandwidth"], int(g["feedforward"]),
                      r["control_period"], lim(r), r["t"], *r["state"], *r["y"], *r["v"], *r["state_after"]])
    for r in rec["cascade"]:
        g = r["gains"]
        lines.append(["cas", *m(r), *(r["plan"][k] for k in PLAN_KEYS), g["current_bandwidth"],
                      g["position_bandwidth"], int(g["decoupling"]), r["control_period"], lim(r), r["t"], *r["state"],
                      *r["y"], *r["v"], *r["state_after"]])
    for r in rec["exact_linearization"]:
        lines.append(["el", *m(r), *(r["plan"][k] for k in PLAN_KEYS), *(r["gains"][k] for k in LIN_KEYS),
                      int(r["measurement"] == "model"), lim(r), r["t"], *r["y"], *r["v"]])
    for r in rec["plant"]:
        e = r["effects"] or PlantEffects().as_dict()
        lines.append(["plant", *m(r), r["load"], e["detent_torque"], e["coulomb_torque"], e["coulomb_speed"],
                      e["magnetizing_resistance"] or 0.0, *r["x"], *r["v"], *r["dx"]])
    return "\n".join(x if isinstance(x, str) else " ".join(map(repr_num, x)) for x in lines) + "\n"


def repr_num(x) -> str:
    """A string as it is, an int in decimal, any other number as the repr of its float (exact round trip)."""
    return x if isinstance(x, str) else repr(float(x)) if not isinstance(x, int) else str(x)


if __name__ == "__main__":
    main()
