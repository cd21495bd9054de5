"""Write the C core's parity vectors from the Python reference: tests/vectors/core.json and core.txt.

core.json is read by tests/test_core_parity.py; core.txt holds the same records one per line
(``kind`` then numbers, shortest round-trip decimals) for the C unit test, which reads it with stdio.
Run ``python tools/gen_vectors.py`` after a change to the reference; the output is deterministic.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from flatstep.control.smc import FlatnessSMC, SMCGains
from flatstep.flat import flat_to_state, flat_voltages, state_to_flat
from flatstep.motor import MotorParams
from flatstep.plan import PAPER_PLAN, RestToRest

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


def times(plan: RestToRest, rng: np.random.Generator, n: int) -> np.ndarray:
    """Sample times around the plan: its knots exactly, just inside and outside them, and random ones."""
    T = plan.tf - plan.t0
    edges = [plan.t0, plan.tf, plan.t0 + 1e-9, plan.tf - 1e-9, plan.t0 - 1e-3, plan.tf + 1e-3, 0.0]
    return np.concatenate([edges, plan.t0 + T * rng.uniform(-0.2, 1.2, n)])


def main() -> None:
    rng = np.random.default_rng(20240601)
    rec: dict[str, list] = {"plan": [], "flat_voltages": [], "flat_to_state": [], "state_to_flat": [], "smc": []}
    for plan in PLANS:
        t = times(plan, rng, 40)
        flag = np.array(plan.flag(t))
        rec["plan"] += [dict(plan=plan.as_dict(), t=float(ti), flag=f.tolist()) for ti, f in zip(t, flag.T)]
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
    base = dict(motor=ctrl.motor.as_dict(), plan=ctrl.plan.as_dict(), gains=ctrl.gains.as_dict(),
                measurement=ctrl.measurement)
    return [dict(base, t=float(t[i]), y=[*x[:, i].tolist(), float(acc[i])], v=v[:, i].tolist())
            for i in np.flatnonzero(keep)]


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
    return "\n".join(x if isinstance(x, str) else " ".join(map(repr_num, x)) for x in lines) + "\n"


def repr_num(x) -> str:
    return x if isinstance(x, str) else repr(float(x)) if not isinstance(x, int) else str(x)


if __name__ == "__main__":
    main()
