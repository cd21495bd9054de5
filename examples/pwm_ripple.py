"""Switched PWM against the averaged bridge on the realistic drive: current ripple and tracking.

Run: python examples/pwm_ripple.py
40 kHz bipolar centre-aligned PWM on a 24 V bus, with and without 0.5 us dead time, against the averaged
model the rest of flatstep uses by default.
"""
from dataclasses import replace
from pathlib import Path

import numpy as np

from flatstep.loop.drive import Drive
from flatstep.model.plant import plant_rhs
from flatstep.studies.robustness import encoder_count
from flatstep.studies.scenario_file import load_scenario

scenario, _ = load_scenario(Path(__file__).parent / "drive-20khz-14bit.toml")
count = encoder_count(scenario)
p, plant = scenario.plan, scenario.simulated_plant
print(f"{'bridge':<34}{'move':>8}{'rest':>8}  [counts]{'ripple ia':>12}  [mA peak-to-peak, within a period at rest]")
for label, drive in (("averaged", Drive()), ("switched 40 kHz", Drive(pwm="switched", f_pwm=40e3)),
                     ("switched 40 kHz, 0.5 us dead time", Drive(pwm="switched", f_pwm=40e3, dead_time=0.5e-6))):
    fine = replace(scenario, loop=replace(scenario.loop, drive=drive))
    r = fine.run()  # the C engine, switched PWM included
    t, e = r.t, np.abs(r.theta_error) / count
    # ripple: integrate one control period at rest finely under the applied PWM pattern
    k = int(np.searchsorted(t, 0.05))
    x = np.array([r.ia[k], r.ib[k], r.omega[k], r.theta[k]])
    dur, lv = drive.pwm_segments(np.array([r.va[k], r.vb[k]]), x[:2], fine.control_period)
    ia = [x[0]]
    for h, v in zip(dur, lv):
        for _ in range(20):
            x = x + h / 20 * plant_rhs(x, v, plant.motor, plant.load, plant.effects)
            ia.append(x[0])
    move, rest = e[(t >= p.t0) & (t <= p.tf)].max(), e[t >= p.tf + 5e-3].max()
    print(f"{label:<34}{move:>8.3f}{rest:>8.3f}{1e3 * (max(ia) - min(ia)):>20.2f}")
