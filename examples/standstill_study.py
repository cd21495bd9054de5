"""Standstill on a quantized encoder: what holding the rotor after the move costs, strategy by strategy.

Run: python examples/standstill_study.py [--workers N]
For the 14-bit, the 4000-count and the NEMA 17 drive files, every +-10 % plant (32 sign combinations), prints the worst
|theta - theta*| in encoder counts during the move, at rest (t >= tf + 5 ms) and at the end, for the
designed law without the files' detent hold and for the standstill strategies tried against its half-count
limit cycle (docs/drive.md, "Standstill"), the shipped detent hold (``SMCGains.hold_damping``) among them.
Each strategy changes the loop only from tf on; the move itself is the designed one.

The loop here is the period-by-period drive loop of flatstep.loop.reference (averaged bridge), written out so that a strategy can change the observer and the law at rest (no measurement or computation
delay); on the designed loop it reproduces `flatstep robustness` to the printed digits.
"""
from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np

from flatstep.control.smc import FlatnessSMC
from flatstep.loop.observers import Observer
from flatstep.loop.reference import _rk4  # the reference loop's RK4 step over one substep
from flatstep.studies.robustness import REST_AFTER, encoder_count, perturbed, plant_errors
from flatstep.studies.scenario_file import Robustness, load_scenario

HERE = Path(__file__).parent
FILES = ("drive-20khz-14bit.toml", "drive-20khz-optical-4000.toml", "nema17-20khz.toml")

#: strategy -> what it changes from tf on (see docs/drive.md, "Standstill")
STRATEGIES = {
    "designed law, no standstill handling": {},
    "observer dead band of +-1/2 count": {"dead_band": 0.5},
    "slower loop: wn = observer bandwidth = 400 rad/s": {"rest_bandwidth": 400.0},
    "  the same, exact encoder": {"rest_bandwidth": 400.0, "exact_encoder": True},
    "constant-load observer (ramp state dropped)": {"rest_load_states": 1},
    "  the same, for the whole run": {"rest_load_states": 1, "whole_run": True},
    "detent hold (current vector on theta2), damping 0.2": {"hold_damping": 0.2},
    "detent hold (current vector on theta2), damping 0.4": {"hold_damping": 0.4},
    "detent hold, damping 0.7 (the drive files' setting)": {"hold_damping": 0.7},
}


def _embedded(observer: Observer, motor, Ts: float, order: int):
    """The observer's (Ad, Bd, Lc) padded to ``order`` states (missing states stay at zero)."""
    Ad, Bd, Lc = observer.matrices(motor, Ts)
    n = observer.order
    A, B, L = np.zeros((order, order)), np.zeros(order), np.zeros(order)
    A[:n, :n], B[:n], L[:n] = Ad, Bd, Lc
    return A, B, L


def run(scenario, dead_band=0.0, rest_bandwidth=None, rest_load_states=None, hold_damping=None,
        exact_encoder=False, whole_run=False):
    """One run of ``scenario`` with the strategy's changes from tf on (from t = 0 with ``whole_run``), the
    encoder exact with ``exact_encoder``, the detent hold from tf on with ``hold_damping``; returns
    (t, theta - theta*)."""
    scenario = replace(scenario, gains=replace(scenario.gains, hold_damping=hold_damping))
    if exact_encoder:
        loop = scenario.loop
        scenario = replace(scenario, loop=replace(loop, sensors=replace(loop.sensors, encoder_counts=None)))
    ctrl, plant, loop = scenario.controller(), scenario.simulated_plant, scenario.loop
    sensors, drive = loop.sensors, loop.drive
    model, plan, Ts, sub = ctrl.motor, ctrl.plan, loop.control_period, loop.substeps
    obs = loop.observer
    order = obs.order
    moving = _embedded(obs, model, Ts, order)
    resting, rest_ctrl = moving, ctrl
    if rest_bandwidth is not None:
        resting = _embedded(replace(obs, bandwidth=rest_bandwidth), model, Ts, order)
        rest_ctrl = FlatnessSMC(model, plan, replace(ctrl.gains, wn=rest_bandwidth), ctrl.measurement)
    if rest_load_states is not None:
        resting = _embedded(replace(obs, load_states=rest_load_states), model, Ts, order)
    n = int(np.ceil(scenario.t_end / Ts - 1e-9))
    x, xh, q = plan.x0(model.Nr), None, sensors.angle_step
    theta, noise = np.empty(n + 1), sensors.noise(n + 1)
    for k in range(n + 1):
        t = k * Ts
        rest = whole_run or t >= plan.tf
        theta[k] = x[3]
        Ad, Bd, Lc = resting if rest else moving
        th_m = float(sensors.read_angle(x[3]))
        i_m = sensors.read_currents(x[:2], noise[k])
        innovation = 0.0 if xh is None else th_m - xh[0]
        if rest and dead_band:
            innovation = np.sign(innovation) * max(abs(innovation) - dead_band * q, 0.0)
        xh = np.r_[th_m, np.zeros(order - 1)] if xh is None else xh + Lc * innovation
        Te = model.Km * (i_m[1] * np.cos(model.Nr * xh[0]) - i_m[0] * np.sin(model.Nr * xh[0]))
        y = np.array([i_m[0], i_m[1], xh[1], xh[0], (Te - model.B * xh[1] - xh[2]) / model.J])
        v, _ = (rest_ctrl if rest else ctrl).step(None, y, t)
        v = drive.saturate(v)
        if k == n:
            break
        for _ in range(sub):
            x = _rk4(x, v, Ts / sub, plant.motor, plant.load, plant.effects)
        xh = Ad @ xh + Bd * Te
    t = np.arange(n + 1) * Ts
    return t, theta - plan.flag(t).theta


def worst(job):
    """Worst move / rest / final error in counts of one strategy over the file's plants."""
    file, options = job
    scenario, study = load_scenario(HERE / file)
    plan, q = scenario.plan, encoder_count(scenario)
    out = np.zeros(3)
    for plant_case in perturbed(scenario, plant_errors(study or Robustness())):
        t, e = run(plant_case, **options)
        e = np.abs(e) / q
        out = np.maximum(out, [e[(t >= plan.t0) & (t <= plan.tf)].max(), e[t >= plan.tf + REST_AFTER].max(), e[-1]])
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=None, help="processes (default: all cores)")
    args = parser.parse_args()
    jobs = [(f, opts) for f in FILES for opts in STRATEGIES.values()]
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(worst, jobs))
    for i, file in enumerate(FILES):
        print(f"{file}: worst of 32 plants, +-10 %   [counts]")
        print(f"  {'from tf on':<52}{'move':>8}{'rest':>8}{'final':>8}")
        for j, label in enumerate(STRATEGIES):
            move, rest, final = results[i * len(STRATEGIES) + j]
            print(f"  {label:<52}{move:>8.3f}{rest:>8.3f}{final:>8.3f}")


if __name__ == "__main__":
    main()
