r"""How well :func:`~flatstep.studies.calibrate.calibrate` recovers the plant: errors over a robustness study's plants.

Each plant of the study (the scenario's ``[robustness]``: every corner of +-10 % in R, L, Km, J, B) is
calibrated with the controller's nominal model, and its estimates are compared with that plant's true detent
(phase 0: the plant's detent is :math:`-T_d\sin hN_r\theta`, i.e. :math:`E = T_d\sin(hN_r\theta + 0)`),
Coulomb friction and load.
"""
from __future__ import annotations

import math
from typing import Any

from ..model.plant import Plant
from .calibrate import Calibration, calibrate
from .robustness import perturbed, plant_errors
from .scenario import Scenario
from .scenario_file import Robustness

#: The largest error accepted: relative for the amplitudes, a fraction of a detent period for the phase.
TARGETS = {"detent_torque": 0.05, "detent_phase": 0.02, "coulomb_torque": 0.10}
#: The columns of the table, with their headings.
COLUMNS = {"detent_torque": "detent amp", "detent_phase": "phase [per.]", "coulomb_torque": "Coulomb",
           "load": "load", "Km": "Km (EMF)"}


def calibration_errors(calibration: Calibration, plant: Plant) -> dict[str, float]:
    """The calibration's errors against ``plant``: relative, and the phase's as a fraction of a detent period.

    A quantity the plant does not have (zero) is left out.
    """
    e, est = plant.effects, calibration.estimates
    truth = {"detent_torque": e.detent_torque if e else 0.0, "coulomb_torque": e.coulomb_torque if e else 0.0,
             "load": plant.constant_load or 0.0, "Km": plant.motor.Km}
    out = {k: est[k] / v - 1.0 for k, v in truth.items() if v}
    if truth["detent_torque"]:
        phase = math.remainder(est["detent_phase"], 2.0 * math.pi)
        out["detent_phase"] = phase / (2.0 * math.pi)
    return out


def accuracy(scenario: Scenario, study: Robustness, **options: Any) -> list[dict[str, Any]]:
    """Calibrate every plant of ``study`` (``options``: those of :func:`calibrate`); one row of errors per plant."""
    rows = []
    for err, sc in zip(plant_errors(study), perturbed(scenario, plant_errors(study)), strict=True):
        cal = calibrate(sc, **options)
        rows.append({"plant": err, "errors": calibration_errors(cal, sc.simulated_plant),
                     "feedforward": cal.torques.as_dict()})
    return rows


def worst(rows: list[dict[str, Any]]) -> dict[str, float]:
    """The largest error in absolute value per quantity, with its sign."""
    out: dict[str, float] = {}
    for row in rows:
        for k, v in row["errors"].items():
            if abs(v) > abs(out.get(k, 0.0)):
                out[k] = v
    return out


def meets_targets(rows: list[dict[str, Any]]) -> dict[str, bool]:
    """Whether each quantity of :data:`TARGETS` stays within its target on every plant."""
    w = worst(rows)
    return {k: abs(w[k]) <= t for k, t in TARGETS.items() if k in w}


def accuracy_table(rows: list[dict[str, Any]]) -> str:
    """One line per plant and the worst, errors in percent (the phase in percent of a detent period)."""
    keys = [k for k in COLUMNS if any(k in r["errors"] for r in rows)]
    head = f"{'plant':<32}" + "".join(f"{COLUMNS[k]:>14}" for k in keys)
    lines = [head]
    for r in rows:
        tag = " ".join(f"{k}{v:+.3g}" for k, v in r["plant"].items())
        lines.append(f"{tag:<32}" + "".join(f"{100 * r['errors'][k]:>13.2f}%" if k in r["errors"] else f"{'':>14}"
                                            for k in keys))
    w = worst(rows)
    lines.append(f"{'worst':<32}" + "".join(f"{100 * w[k]:>13.2f}%" for k in keys))
    lines.append(f"{'target':<32}" + "".join(f"{'+-' + format(100 * TARGETS[k], 'g') + '%':>14}" if k in TARGETS
                                            else f"{'':>14}" for k in keys))
    return "\n".join(lines)
