"""The pull-out torque of the open-loop microstepping drive measured on the C engine: constant speed, rising load.

At each speed the drive (:class:`~flatstep.control.microstep.Microstepping`, the current loops of a step/dir driver,
no position feedback) brings the rotor up to speed on a gentle ramp and holds it there, against a load that rises
with the speed (a Coulomb friction, :func:`_loaded`). The largest load it carries without losing a step (status
``ok``: never a full step behind the command, docs/errors.md) is found by bisection, every speed's run at one
bisection level in one batch. The model's curve is :func:`flatstep.model.pullout.pullout_torque`.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..loop.drive import Drive
from ..loop.reference import DriveLoop
from ..model.motor import MotorParams
from ..model.plant import Plant, PlantEffects
from ..model.pullout import pullout_torque
from ..plan.piecewise import NCOEF, PiecewisePlan
from ..validate import InputError, check_quantity
from .batch import run_batch
from .scenario import Scenario

#: The share of the model's pull-out torque spent on the ramp's acceleration (the rest is left for the load).
RAMP_SHARE = 0.05
#: How long the speed is held after the ramp: this many electrical periods, at least :data:`HOLD_MIN` [s].
HOLD_PERIODS = 10
HOLD_MIN = 0.02
#: The load reaches tanh(LOAD_RISE) = 0.9993 of its value at the held speed.
LOAD_RISE = 4.0


def ramp_and_hold(motor: MotorParams, speed: float, acceleration: float, current: float,
                  hold: float) -> PiecewisePlan:
    """From rest at 0 rad, a constant ``acceleration`` up to ``speed``, then ``hold`` seconds at it, at ``current``."""
    ta = speed / acceleration
    rows = np.zeros((2, NCOEF))
    rows[0, -3:] = [acceleration * ta * ta / 2, 0.0, 0.0]
    rows[1, -3:] = [0.0, speed * hold, acceleration * ta * ta / 2]
    rho = np.zeros((2, NCOEF))
    rho[:, -1] = current
    return PiecewisePlan(np.array([0.0, ta, ta + hold]), rows, rho)


def _loaded(motor: MotorParams, load: float, speed: float) -> Plant:
    """The plant with a load that rises with the speed: ``load tanh(4 omega / speed)``, 0 at rest, ``load`` at speed.

    A Coulomb friction of ``load`` with the speed scale ``speed / 4`` (:class:`~flatstep.model.plant.PlantEffects`):
    the load comes on as the ramp brings the rotor up to speed, not as a step at rest.
    """
    return Plant(motor, effects=PlantEffects(coulomb_torque=load, coulomb_speed=speed / LOAD_RISE))


def engine_pullout(motor: MotorParams, v_bus: float, current: float, speeds: ArrayLike, *,
                   control_rate: float = 20e3, substeps: int = 4, iterations: int = 10,
                   plant: MotorParams | None = None, **batch: Any) -> np.ndarray:
    """The largest constant load [N m] the open-loop drive carries at each speed [rad/s] without losing a step.

    Parameters
    ----------
    motor : MotorParams
        The drive's model (and the plant's, unless ``plant`` is given).
    v_bus : float
        The bus [V].
    current : float
        The run current (current-vector norm) [A].
    speeds : sequence of float
        Speeds > 0 [rad/s].
    control_rate : float
        The drive's current-loop rate [Hz] (its bandwidth is 0.3 of it, :mod:`flatstep.control.microstep`).
    substeps : int
        RK4 steps of the plant per control period.
    iterations : int
        Bisection steps on the load, between 0 and 1.5 times the model's pull-out torque at rest.
    plant : MotorParams, optional
        The simulated motor, when it differs from the drive's model.
    **batch
        Passed to :func:`~flatstep.studies.batch.run_batch` (``workers``, ``progress``).
    """
    v_bus = check_quantity("v_bus", v_bus)
    current = check_quantity("current", current)
    w = np.asarray(speeds, dtype=float)
    if w.ndim != 1 or w.size == 0 or not np.isfinite(w).all() or (w <= 0).any():
        raise InputError("speeds", speeds, "speeds must be a non-empty list of speeds > 0 [rad/s]")
    model = pullout_torque(motor, "foc_weakening", v_bus, current, w)
    t_rest = float(pullout_torque(motor, "foc_weakening", v_bus, current, 0.0)[0])
    accel = np.maximum(RAMP_SHARE * np.maximum(model, 0.05 * t_rest) / motor.J, 1.0)
    hold = np.maximum(HOLD_PERIODS * 2 * np.pi / (motor.Nr * w), HOLD_MIN)
    plans = [ramp_and_hold(motor, float(s), float(a), current, float(h)) for s, a, h in zip(w, accel, hold,
                                                                                             strict=True)]
    loop = DriveLoop(control_period=1.0 / control_rate, substeps=substeps, drive=Drive(v_bus=v_bus))
    lo, hi = np.zeros(w.size), np.full(w.size, 1.5 * t_rest)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        runs = [Scenario(f"pullout[{s:g} rad/s, {t:.4g} N m]", motor=motor, plan=p, controller_type="microstep",
                         measurement="model", plant=_loaded(plant or motor, float(t), float(s)), loop=loop,
                         t_end=p.tf)
                for s, t, p in zip(w, mid, plans, strict=True)]
        rows = run_batch(runs, **batch)
        kept = np.array([r["error"] is None and r["status"] == "ok" for r in rows])
        lo, hi = np.where(kept, mid, lo), np.where(kept, hi, mid)
    return lo
