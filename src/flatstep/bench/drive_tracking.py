"""A plan tracked on the 20 kHz drive of the planning comparisons: its error during the move and its status.

The drive of docs/planning.md's comparisons: a 20 kHz sampled loop (4 plant substeps a period), the bus, the
default sensors (14-bit encoder, 12-bit current ADC), the designed observer and gains
(:func:`~flatstep.loop.design.design_gains`). The paper's law (:class:`~flatstep.control.smc.FlatnessSMC`)
tracks a (rho, theta) plan; the d-q law (:class:`~flatstep.control.dq_smc.DQFlatnessSMC`) a (theta, i_d) plan,
from rest at zero current.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any, Optional, cast

import numpy as np

from ..control.dq_smc import DQFlatnessSMC
from ..control.smc import FlatnessSMC
from ..engine.simulate import simulate
from ..loop.design import design_gains
from ..loop.drive import Drive
from ..loop.reference import DriveLoop
from ..loop.sensors import Sensors
from ..model.motor import MotorParams
from ..plan.d_current import DCurrentPlan
from ..plan.piecewise import PiecewisePlan

#: The control period of the comparisons' drive [s].
CONTROL_PERIOD = 5e-5


def track(plan: PiecewisePlan, motor: MotorParams, v_bus: float,
          d_current: Optional[DCurrentPlan] = None) -> dict[str, Any]:
    r"""The plan on the drive (module docstring): the d-q law with ``d_current`` if given, else the paper's law.

    Returns ``max_error`` [rad], the largest :math:`|\theta - \theta^*|` from the plan's start to its end,
    ``status`` (:attr:`~flatstep.engine.result.SimResult.status`, over the move and 20 ms at rest),
    ``saturated`` (the share of control periods with a phase voltage at the bus), ``v_peak`` [V] and
    ``faults`` (controller faults).
    """
    design = design_gains(motor, cast(Any, plan), control_period=CONTROL_PERIOD, v_bus=v_bus)
    loop = DriveLoop(control_period=CONTROL_PERIOD, substeps=4, drive=Drive(v_bus=v_bus), sensors=Sensors(),
                     observer=design.observer)
    x0 = None
    if d_current is None:
        controller: Any = FlatnessSMC(motor, plan, design.gains, "observer")
    else:
        controller = DQFlatnessSMC(motor, plan, replace(design.gains, hold_damping=None), "observer",
                                   d_current=d_current)
        x0 = np.array([0.0, 0.0, 0.0, plan.theta1])
    run = simulate(motor, plan, controller, loop=loop, t_end=plan.tf + 0.02, x0=x0)
    during = (run.t >= plan.t0) & (run.t <= plan.tf)
    peak = np.max(np.abs([run.va, run.vb]), axis=0)
    return dict(max_error=float(np.max(np.abs(run.theta - run.theta_ref)[during])), status=run.status,
                saturated=float(np.mean(peak >= v_bus * (1 - 1e-9))), v_peak=float(peak.max()),
                faults=int(run.meta.get("controller_faults", 0)))
