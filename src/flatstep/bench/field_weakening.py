"""The field-weakening benchmarks' motors and drive, and the d-q law's run of a plan on that drive.

The drive of docs/planning.md section 8 (benchmarks/field_weakening_optimum.py, field_weakening_baselines.py and
quantization_sources.py): 20 kHz, 4 RK4 substeps a period, the bus, a 4000-count encoder that latches its count
edges, a 12-bit current sensor sized to the motor's current, the designed observer predicting with the torque's
ramp, and the d-q law with the designed gains and its angle advance (docs/controllers.md, "Quantization").
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..control.dq_smc import DQFlatnessSMC, advance_of
from ..engine.simulate import simulate
from ..loop.design import design_gains
from ..loop.sensors import Sensors
from ..model.datasheet import motor_from_table
from ..model.motor import MotorParams
from ..studies.file_values import read_toml
from ..studies.verify import drive_loop

#: The drive's control rate [Hz].
RATE = 20000.0
#: The share of the bus the plans may use.
V_USE = 0.84


def motor(name: str, motors: Path) -> tuple[MotorParams, float]:
    """The motor and its i_max [A]: the preset at 1 A, or ``motors/<name>.toml`` at its rated current norm."""
    if name in ("nema17", "paper"):
        return MotorParams.preset(name), 1.0
    path = motors / f"{name}.toml"
    model = motor_from_table(read_toml(path)["motor"], str(path))
    return model.params, model.rated_rho


def adc_range(i_max: float) -> float:
    """The current sensor's full scale [A]: 2 A, or the next whole ampere above 1.2 i_max where that is more.

    A sensor that clips below the planned current feeds the law and the observer a wrong torque (the LDO-42STH60's
    2.83 A on the default 2 A range).
    """
    return max(2.0, float(math.ceil(1.2 * i_max)))


def track(m: MotorParams, fw: Any, v_bus: float, counts: int = 4000, advance: bool = True,
          i_max: float = 1.0, wn_scale: float = 1.0, edge_timing: bool = True,
          torque_ramp: bool = True, bandwidth_scale: float = 1.0) -> tuple[str, float]:
    """The d-q law's run of a plan on the 20 kHz drive: its status and the largest |theta error| [rad] in the move.

    ``fw``: anything with a ``plan`` and its ``d_current`` (a planner's result, a baseline). ``advance``: the
    law's angle advance of half a control period; the 12-bit current sensor spans :func:`adc_range` of ``i_max``;
    the designed ``wn`` times ``wn_scale``; ``edge_timing``: the encoder latches its count edges; ``torque_ramp``:
    the designed observer predicts with the torque's ramp; its bandwidth times ``bandwidth_scale``.
    """
    plan, d_current = fw.plan, fw.d_current
    sensors = Sensors(encoder_counts=counts, current_range=adc_range(i_max), edge_timing=edge_timing)
    loop = drive_loop(v_bus, RATE, sensors=sensors)
    d = design_gains(m, plan, control_period=loop.control_period, v_bus=v_bus, encoder_counts=counts,
                     current_step=sensors.current_step)
    loop = replace(loop, observer=replace(d.observer, torque_ramp=torque_ramp,
                                          bandwidth=d.observer.bandwidth * bandwidth_scale))
    gains = replace(d.gains, wn=d.gains.wn * wn_scale)
    ctrl = DQFlatnessSMC(m, plan, gains, "observer", d_current=d_current,
                         advance=advance_of(loop.control_period) if advance else 0.0)
    r = simulate(m, plan, ctrl, loop=loop, t_end=plan.tf + 0.01, x0=[0.0, 0.0, 0.0, plan.theta1])
    during = (r.t >= plan.t0) & (r.t <= plan.tf)
    return r.status, float(np.max(np.abs(r.theta_error[during])))
