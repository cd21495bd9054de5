"""What each estimator changes on the realistic 20 kHz drive (examples/drive-20khz-14bit.toml).

Run: python examples/observer_comparison.py
Prints, for each way of obtaining speed and acceleration, the worst tracking error in encoder counts during
the move and at rest (t >= tf + 5 ms), for the nominal plant and for the file's perturbed plant.
"""
from dataclasses import replace
from pathlib import Path

import numpy as np

from flatstep.loop.observers import Observer
from flatstep.studies.robustness import encoder_count
from flatstep.studies.scenario_file import load_scenario

scenario, _ = load_scenario(Path(__file__).parent / "drive-20khz-14bit.toml")
count = encoder_count(scenario)
bw = scenario.loop.observer.bandwidth
perturbed = scenario.simulated_plant
nominal = replace(perturbed, motor=scenario.motor)  # the controller's model, the same load
variants = {
    "encoder difference, zero-load model": dict(observer=None, measurement="model"),
    "speed observer (no load state)": dict(observer=Observer(bw, load_states=0), measurement="observer"),
    "load observer (constant load)": dict(observer=Observer(bw, load_states=1), measurement="observer"),
    "load observer (load ramp), default": dict(observer=Observer(bw, load_states=2), measurement="observer"),
}
print(f"{'speed and acceleration from':<38}{'plant':>10}{'move':>9}{'rest':>9}{'final':>9}  [counts]")
for label, change in variants.items():
    for plant_label, plant in (("nominal", nominal), ("perturbed", perturbed)):
        loop = replace(scenario.loop, observer=change["observer"])
        r = replace(scenario, plant=plant, loop=loop, measurement=change["measurement"]).run()
        t, e = r.t, np.abs(r.theta_error) / count
        p = scenario.plan
        move, rest = e[(t >= p.t0) & (t <= p.tf)].max(), e[t >= p.tf + 5e-3].max()
        print(f"{label:<38}{plant_label:>10}{move:>9.3f}{rest:>9.3f}{e[-1]:>9.3f}")
