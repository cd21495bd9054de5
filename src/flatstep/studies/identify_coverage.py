"""Coverage of :func:`~flatstep.studies.identify.identify`'s intervals on ordinary recordings, and its refusals.

An ordinary recording is what a user records without the suggested excitation: one rest-to-rest move of 0.5 to
10 rad in 0.2 to 0.6 s (lengthened, or beyond 0.75 s shortened, until it is feasible on the drive), 1 s recorded
on a 20 kHz drive with a 14-bit encoder and a 12-bit ADC with 2 to 10 mA rms of noise, on a plant whose R, L, Km,
J, B are off the controller's model by up to +-10 %, with or without a constant load, detent torque and Coulomb
friction, with or without the detent hold (``hold_damping``). Each case is drawn from its own seed, so the grid
is the same on every machine. :func:`coverage_table` gives, per parameter, how often the intervals of the
accepted recordings hold the truth, and how many recordings were refused or flagged, and why.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ..model.motor import MotorParams
from ..model.plant import Plant, PlantEffects
from ..plan.feasibility import check_feasibility
from ..plan.rest_to_rest import RestToRest
from .excitation import VOLTAGE_MARGIN
from .identify import identify
from .record import Recording, recording_from_result
from .scenario import Scenario
from .scenario_file import load_scenario

#: The example drives the grid's plants sit on (the controller's model is the file's motor).
DRIVES = {"nema17": "nema17-20khz.toml", "paper": "drive-20khz-14bit.toml"}
#: The parameters whose intervals are checked, with the plant's attribute of each.
CHECKED = ("R", "L", "Km", "J", "B", "load_torque", "J/Km", "B/Km", "load_torque/Km")
#: Refusal reasons: the first pattern a message matches names it.
REASONS = (("cannot be separated", "not separable"), ("ill-conditioned", "ill-conditioned"),
           ("rotor moves", "too little motion"), ("not modelled", "wide intervals, a left-out term named"),
           ("intervals are", "wide intervals"),
           ("current noise makes up", "current noise"), ("shifted", "misaligned"),
           ("range flatstep accepts", "out of range"), ("interval", "negative friction"))


@dataclass(frozen=True)
class Case:
    """One ordinary recording of the grid: the drive, the move, the sensors and the plant."""

    index: int
    drive: str
    move: float
    duration: float
    noise: float
    load: float
    effects: bool
    hold: bool
    scale: tuple[float, float, float, float, float]


def examples_dir() -> Path:
    """The repository's examples/ (the drives of :data:`DRIVES`)."""
    return Path(__file__).resolve().parents[3] / "examples"


def cases(n: int, seed: int = 0) -> list[Case]:
    """``n`` ordinary recordings, case ``k`` drawn from ``seed * 1_000_003 + k`` (module docstring)."""
    out = []
    for k in range(n):
        rng = np.random.default_rng(seed * 1_000_003 + k)
        move = float(np.exp(rng.uniform(math.log(0.5), math.log(10.0)))) * float(rng.choice([-1.0, 1.0]))
        out.append(Case(index=k, drive=("nema17", "paper")[k % 2], move=move, duration=float(rng.uniform(0.2, 0.6)),
                        noise=float(rng.uniform(0.002, 0.010)),
                        load=float(rng.uniform(0.02, 0.1) * rng.choice([-1.0, 1.0])) if rng.random() < 0.5 else 0.0,
                        effects=bool(rng.random() < 0.5), hold=bool(rng.random() < 0.5),
                        scale=tuple(float(s) for s in rng.uniform(0.9, 1.1, 5))))  # type: ignore[arg-type]
    return out


def _scenario(case: Case) -> Scenario:
    """The case's scenario: the drive's file with the case's plan, plant, sensors and hold."""
    base = load_scenario(examples_dir() / DRIVES[case.drive])[0]
    model = base.motor
    torque = model.Km * base.plan.rho2  # the torque the current norm makes: the load and effects scale with it
    truth = MotorParams(**{k: getattr(model, k) * s for k, s in zip("R L Km J B".split(), case.scale, strict=True)},
                        Nr=model.Nr)
    effects = PlantEffects(detent_torque=0.05 * torque, coulomb_torque=0.01 * torque) if case.effects else None
    plant = Plant(truth, effects=effects, load=case.load * torque)
    assert base.loop is not None and base.loop.sensors is not None and base.loop.drive is not None
    v_max = VOLTAGE_MARGIN * base.loop.drive.v_bus
    t0, duration, margin = 0.05, case.duration, abs(case.load * torque) + 0.3 * torque
    plan = RestToRest(theta1=0.0, theta2=case.move, rho1=base.plan.rho2, rho2=base.plan.rho2, t0=t0, tf=t0 + duration)
    while not all(check_feasibility(plan, model, load_torque=s * margin, v_max=v_max).feasible for s in (-1, 1)):
        if t0 + 1.2 * duration > 0.8:  # no time left in the 1 s: shorten the move instead
            plan = replace(plan, theta2=0.7 * plan.theta2)
        else:
            duration *= 1.2
            plan = replace(plan, tf=t0 + duration)
    sensors = replace(base.loop.sensors, current_noise=case.noise, seed=case.index)
    return replace(base, name=f"case {case.index}", plan=plan, plant=plant, t_end=1.0,
                   gains=replace(base.gains, hold_damping=0.7 if case.hold else None),
                   loop=replace(base.loop, sensors=sensors))


def recording(case: Case) -> tuple[Recording, Plant]:
    """The case's recording (C engine) and the plant it was recorded on."""
    scenario = _scenario(case)
    return recording_from_result(scenario.run("c"), source=scenario.name), scenario.simulated_plant


def reason(message: str) -> str:
    """A short name for a refusal's message (:data:`REASONS`)."""
    for pattern, name in REASONS:
        if pattern in message:
            return name
    return re.sub(r"^[^:]*: ", "", message)[:40]


def run_case(case: Case, **options: Any) -> dict[str, Any]:
    """Record and identify one case; the row says what was refused or flagged, the errors and what is covered."""
    rec, plant = recording(case)
    truth = {k: getattr(plant.motor, k) for k in "R L Km J B".split()}
    truth["load_torque"] = plant.constant_load or 0.0
    row: dict[str, Any] = {"case": case.index, "drive": case.drive, "move": case.move, "effects": case.effects,
                           "load": case.load != 0.0, "hold": case.hold, "noise": case.noise}
    try:
        result = identify(rec, Nr=plant.motor.Nr, **options)
    except ValueError as exc:
        return {**row, "status": "refused", "reason": reason(str(exc)), "message": str(exc)}
    if any("one direction" in n for n in result.notes) and plant.effects is not None:
        truth["load_torque"] += plant.effects.coulomb_torque * math.copysign(1.0, case.move)  # as the note says
    truth.update({f"{k}/Km": truth[k] / truth["Km"] for k in ("J", "B", "load_torque")})
    row.update(status="flagged" if result.flags else "accepted", flags=list(result.flags),
               errors={k: result.estimates[k] / v - 1.0 if v else result.estimates[k] - v for k, v in truth.items()},
               sigma={k: abs(result.estimates[k] - v) / result.std[k] if result.std[k] > 0 else math.inf
                      for k, v in truth.items()},
               covered={k: bool(result.interval(k)[0] <= v <= result.interval(k)[1]) for k, v in truth.items()})
    return row


def coverage_table(rows: list[dict[str, Any]], confidence: Optional[float] = 0.95) -> str:
    """Coverage per parameter over the accepted rows, the 95th percentile of |error|/std, refusals and flags."""
    accepted = [r for r in rows if r["status"] == "accepted"]
    flagged = [r for r in rows if r["status"] == "flagged"]
    refused = [r for r in rows if r["status"] == "refused"]
    lines = [f"{len(rows)} recordings: {len(accepted)} accepted, {len(flagged)} flagged, {len(refused)} refused "
             f"({len(refused) / max(len(rows), 1):.0%})"]
    lines.append(f"{'':<24}" + "".join(f"{k:>15}" for k in CHECKED))
    for label, group in (("covered (accepted)", accepted), ("covered (flagged)", flagged)):
        if group:
            lines.append(f"{label:<24}" + "".join(
                f"{sum(r['covered'][k] for r in group) / len(group):>15.1%}" for k in CHECKED))
    if accepted:
        lines.append(f"{'|error|/std, 95th pct':<24}" + "".join(
            f"{np.percentile([r['sigma'][k] for r in accepted], 95):>15.3g}" for k in CHECKED))
        lines.append(f"{'|error|, 95th pct':<24}" + "".join(
            f"{np.percentile([abs(r['errors'][k]) for r in accepted], 95):>15.2%}"
            if not k.startswith("load") else f"{'-':>15}" for k in CHECKED))  # a zero load has no relative error
    why: dict[str, int] = {}
    for r in refused:
        why[r["reason"]] = why.get(r["reason"], 0) + 1
    for r in flagged:
        for f in r["flags"]:
            key = "flag: " + re.sub(r"\s*[-=+(\d].*$", "", f)[:40]
            why[key] = why.get(key, 0) + 1
    lines += [f"  {n:>4}  {k}" for k, n in sorted(why.items(), key=lambda kv: -kv[1])]
    return "\n".join(lines)
