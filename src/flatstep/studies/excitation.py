r"""A suggested excitation for identification: a seeded sequence of rest-to-rest moves on a scenario's drive.

One move alone leaves the rotor at rest most of the time, where only the resistance shows. The sequence
moves the rotor back and forth, one move per ``segment`` (80 ms by default): each move has a random length
between ``steps`` full steps (1 to 12, either direction), a random duration, lengthened (or the move shortened)
until the plan is feasible with a torque margin (:data:`TORQUE_MARGIN`) and its feedforward voltages stay within
:data:`VOLTAGE_MARGIN` of the bus, and a random current norm between ``rho_range`` times the scenario's end
current norm, so that the current changes while the rotor rests too. Accelerations show the inertia, speeds
the friction and
the back-emf, current changes the inductance, and currents at rest the resistance.

Each move is one run of the scenario's own controller, loop (drive, sensors, observer) and simulated plant,
started from the state where the previous run ended; the sensors' noise seed changes from run to run. The
series are joined into one :class:`~flatstep.studies.record.Recording` of what the drive measured.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..engine.result import full_step
from ..engine.simulate import simulate
from ..plan.feasibility import check_feasibility
from ..plan.rest_to_rest import RestToRest
from ..validate import check_count, check_nonnegative, check_positive, check_quantity
from ..validate.limits import MIN_PERIODS_PER_MOVE, check_resources, estimate
from .record import Recording, recording_from_result
from .scenario import Scenario

#: The torque the plans keep in reserve, as a fraction of Km rho (the plant may differ from the model).
TORQUE_MARGIN = 0.3
#: The fraction of the bus voltage the plans' feedforward may use.
VOLTAGE_MARGIN = 0.7


def _move(rng: np.random.Generator, scenario: Scenario, theta1: float, rho1: float, segment: float,
          steps: tuple[float, float], rho_range: tuple[float, float]) -> RestToRest:
    """One random, feasible rest-to-rest move from ``(theta1, rho1)`` within a segment of ``segment`` s."""
    motor = scenario.motor
    drive = scenario.loop.drive if scenario.loop is not None else None
    v_max = VOLTAGE_MARGIN * drive.v_bus if drive is not None else None
    length = rng.choice([-1.0, 1.0]) * rng.uniform(*steps) * full_step(motor.Nr)
    rho2 = scenario.plan.rho2 * rng.uniform(*rho_range)
    t0, duration = 0.05 * segment, rng.uniform(0.3, 0.6) * segment
    load = abs(scenario.simulated_plant.constant_load or 0.0)
    margin = TORQUE_MARGIN * motor.Km * min(rho1, rho2)
    for _ in range(100):
        plan = RestToRest(theta1=theta1, theta2=theta1 + length, rho1=rho1, rho2=rho2, t0=t0, tf=t0 + duration)
        if all(check_feasibility(plan, motor, load_torque=sign * (load + margin), v_max=v_max).feasible
               for sign in (-1.0, 1.0)):  # the margin against either sign of the torque demand
            return plan
        if t0 + 1.2 * duration > 0.75 * segment:  # no time left: shorten the move instead
            length *= 0.7
        else:
            duration *= 1.2
    raise ValueError(f"scenario {scenario.name!r}: no feasible move of the excitation from theta={theta1!r} rad at "
                     f"rho {rho1!r} -> {rho2!r} A within {segment!r} s: the load {load!r} N m leaves too little of "
                     f"Km rho = {motor.Km * min(rho1, rho2)!r} N m; raise the plan's rho2 or lengthen the segment")


def excite(scenario: Scenario, *, duration: float = 1.0, seed: int = 0, segment: float = 0.08,
           steps: tuple[float, float] = (1.0, 12.0), rho_range: tuple[float, float] = (0.5, 1.3),
           current_noise: float | None = None) -> Recording:
    """Record the move sequence of the module docstring on ``scenario``'s drive and plant.

    Parameters
    ----------
    scenario : Scenario
        A sampled-drive scenario (it has a loop): its controller, loop and simulated plant run the moves.
    duration : float
        Length of the recording [s].
    seed : int
        Seed of the moves and of the sensors' noise.
    segment : float
        Time given to each move and the rest after it [s].
    steps : (float, float)
        The range of the move lengths, in full steps (:func:`~flatstep.engine.result.full_step`).
    rho_range : (float, float)
        The range of the current norms, as factors on the scenario's end current norm ``plan.rho2``.
    current_noise : float, optional
        The ADC noise [A rms] to use instead of the scenario's sensors' own.

    Returns
    -------
    Recording
        What the drive measured over ``duration``.
    """
    loop = scenario.loop
    if loop is None:
        raise ValueError(f"scenario {scenario.name!r} has no drive loop: the excitation is recorded by a sampled "
                         "drive ([drive] control_rate in the scenario file)")
    duration = check_quantity("duration", duration)
    check_resources(estimate(duration, control_period=loop.control_period, substeps=loop.substeps),
                    what=f"the excitation of {duration:g} s")
    segment = check_positive("segment", segment, unit=" s")
    if not (0 < steps[0] <= steps[1] and 0 < rho_range[0] <= rho_range[1]):
        raise ValueError(f"steps={steps!r} and rho_range={rho_range!r} must be ranges (low, high) of positive numbers")
    sensors = loop.sensors
    if current_noise is not None:
        if sensors is None:
            raise ValueError("current_noise needs the scenario's sensors ([sensors] in the scenario file)")
        sensors = replace(sensors, current_noise=check_nonnegative("current_noise", current_noise, unit=" A"))
    rng = np.random.default_rng(check_count("seed", seed))
    plant = scenario.simulated_plant
    theta, rho = scenario.plan.theta1, scenario.plan.rho1
    x = scenario.plan.x0(plant.motor.Nr)
    parts: list[dict[str, np.ndarray]] = []
    elapsed = 0.0
    for k in range(math.ceil(duration / segment - 1e-9)):
        remaining = duration - elapsed
        if remaining < MIN_PERIODS_PER_MOVE * loop.control_period:  # too short a tail for a sampled controller
            break
        plan = _move(rng, scenario, theta, rho, segment, steps, rho_range)
        if plan.tf > remaining:  # the last, shorter segment: hold where the rotor is
            plan = RestToRest(theta, theta, rho, rho, t0=0.0, tf=remaining)
        run_loop = replace(loop, sensors=replace(sensors, seed=seed * 100_003 + k)) if sensors is not None else loop
        run = replace(scenario, plan=plan, loop=run_loop)
        result = simulate(plant, plan, run.controller(), loop=run_loop, t_end=min(segment, remaining), x0=x)
        part = recording_from_result(result, source=f"{scenario.name} excitation").columns()
        part["t"] = part["t"] + elapsed
        parts.append({c: v[:-1] for c, v in part.items()})  # the last sample is the next run's first
        x = np.array([result.ia[-1], result.ib[-1], result.omega[-1], result.theta[-1]])
        theta, rho, elapsed = plan.theta2, plan.rho2, elapsed + float(result.t[-1])
        if elapsed >= duration - 1e-9:
            break
    parts[-1] = {c: np.append(v, part[c][-1]) for c, v in parts[-1].items()}
    cols = {c: np.concatenate([p[c] for p in parts]) for c in part}
    return Recording(**cols, source=f"{scenario.name} excitation (seed {seed})")
