"""The least-copper-loss plan against the paper's psi in the same time (docs/planning.md, section 4).

    .venv/bin/python examples/copper_loss.py
"""
import numpy as np
from flatstep.model.motor import PRESETS
from flatstep.plan.baselines import _split, with_torque_current
from flatstep.plan.copper import copper_loss, min_copper_plan
from flatstep.plan.limits import MotorLimits
from flatstep.plan.rest_to_rest import _PSI_HORNER
m, lim = PRESETS["nema17"], MotorLimits(v_bus=24.0, i_max=1.0, i_run=0.1)
for d, T in ((5.0, 0.2), (5.0, 0.4), (1.0, 0.05)):
    best = copper_loss(min_copper_plan(d, T, m, lim), m)
    rows, h = _split(d * _PSI_HORNER[0][None, :], np.array([T]), 8)
    psi = copper_loss(with_torque_current(rows, h, m, lim), m)
    print(f"{d:g} rad in {1e3 * T:g} ms: least loss {1e3 * best:.2f} mJ, psi {1e3 * psi:.2f} mJ, ratio {best / psi:.3f}")
