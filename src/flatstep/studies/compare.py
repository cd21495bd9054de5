r"""Every controller on one scenario: the same plant, drive, sensors and observer; the numbers a user compares.

Metrics of a run (:func:`metrics`), with :math:`e = \theta - \theta^*` and the plan's move :math:`[t_0, t_f]`:

* ``move_max``, ``move_rms``: :math:`\max|e|` and :math:`\sqrt{\overline{e^2}}` over the control instants in
  :math:`[t_0, t_f]` [rad];
* ``final``: :math:`|e|` at the end of the horizon [rad];
* ``settling_time``: the time after :math:`t_f` from which :math:`|e|` stays within ``band`` to the end of
  the horizon [s] (``None`` if it is still outside at the end); ``band`` is one encoder count when the
  scenario has an encoder;
* ``peak_voltage``: :math:`\max(|v_a|, |v_b|)` as applied [V]; ``peak_current``: :math:`\max(|i_a|, |i_b|)` [A];
* ``rms_current``: the RMS phase current :math:`\sqrt{\frac{1}{T}\int\frac{i_a^2 + i_b^2}{2}dt}` [A];
* ``copper_loss``: :math:`R\int(i_a^2 + i_b^2)\,dt` [J], with the plant's :math:`R`.

The voltage, current and loss figures are taken from :math:`t_0` on: every run starts at the plan's start
equilibrium (current :math:`\rho_1` along the rotor's d axis), and the d-q controllers first bring
:math:`i_d` to 0, a start-up transient of the simulation that says nothing about the move. Time integrals are
trapezoids over the control instants.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any, Callable, Optional, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..control.spec import ControllerSpec, is_controller
from ..control.tuning import CONTROLLER_TYPES, FEEDFORWARD_TYPES, SMC_TYPES
from ..engine.result import STATUSES, SimResult
from ..errors import RunError
from ..plan.protocol import Plan
from .batch import run_batch
from .calibrate import Calibration, check_drive
from .calibrate import calibrate as calibrate_unit
from .robustness import encoder_count, perturbed, plant_errors
from .scenario import Scenario
from .scenario_file import Robustness

METRICS = ("move_max", "move_rms", "final", "settling_time", "peak_voltage", "peak_current", "rms_current",
           "copper_loss")
#: Series a robustness run keeps for the metrics and the figures.
KEEP = ("t", "theta_error", "ia", "ib", "va", "vb")
#: How the types of :data:`~flatstep.control.tuning.FEEDFORWARD_TYPES` learn their torques: ``None``, the
#: scenario's ``[feedforward]`` table and nominal model on every plant; ``"each"``, each plant calibrated on its
#: own drive (:func:`unit_scenario`).
CALIBRATE_MODES = (None, "each")
#: The status of a row that did not run because its plant's calibration failed (``calibrate="each"``).
CALIBRATION_FAILED = "calibration_failed"


def _trapezoid(f: NDArray[np.float64], t: NDArray[np.float64]) -> float:
    """The trapezoid-rule integral of samples ``f`` over times ``t`` (0 for a single sample)."""
    return float(0.5 * np.sum((f[1:] + f[:-1]) * np.diff(t))) if t.size > 1 else 0.0


def metrics(t: ArrayLike, theta_error: ArrayLike, ia: ArrayLike, ib: ArrayLike, va: ArrayLike, vb: ArrayLike,
            plan: Plan, *, band: float, R: float) -> dict[str, Optional[float]]:
    """The comparison metrics (module docstring) of one run's time series (arrays over the control instants)."""
    ts, e = np.asarray(t, dtype=float), np.abs(np.asarray(theta_error, dtype=float))
    i_a, i_b, v_a, v_b = (np.asarray(a, dtype=float) for a in (ia, ib, va, vb))
    if not band > 0:
        raise ValueError(f"band={band!r} rad must be > 0 (the settling band)")
    move = (ts >= plan.t0) & (ts <= plan.tf)
    if not np.any(move):
        raise ValueError(f"no sample in the move [t0, tf] = [{plan.t0}, {plan.tf}] s: "
                         f"the horizon ends at {ts[-1]} s")
    after = ts >= plan.tf
    outside = np.flatnonzero(e[after] > band)
    t_after = ts[after]
    if outside.size == 0:
        settling: Optional[float] = 0.0
    elif outside[-1] == t_after.size - 1:
        settling = None
    else:
        settling = float(t_after[outside[-1] + 1] - plan.tf)
    w = ts >= plan.t0
    i2 = i_a[w] ** 2 + i_b[w] ** 2
    duration = ts[w][-1] - ts[w][0]
    return {
        "move_max": float(np.max(e[move])),
        "move_rms": float(np.sqrt(np.mean(e[move] ** 2))),
        "final": float(e[-1]),
        "settling_time": settling,
        "peak_voltage": float(np.max(np.abs(np.concatenate([v_a[w], v_b[w]])))),
        "peak_current": float(np.max(np.abs(np.concatenate([i_a[w], i_b[w]])))),
        "rms_current": (float(np.sqrt(_trapezoid(i2 / 2, ts[w]) / duration)) if duration > 0
                        else float(np.sqrt(np.mean(i2 / 2)))),
        "copper_loss": R * _trapezoid(i2, ts[w]),
    }


def result_metrics(result: SimResult, plan: Plan, *, band: float, R: float) -> dict[str, Optional[float]]:
    """:func:`metrics` of a :class:`~flatstep.engine.result.SimResult`."""
    return metrics(result.t, result.theta_error, result.ia, result.ib, result.va, result.vb, plan, band=band, R=R)


def default_band(scenario: Scenario) -> float:
    """One encoder count, or 1e-3 of the move (at least 1e-6 rad) without an encoder."""
    count = encoder_count(scenario)
    if count is not None:
        return count
    return max(1e-3 * abs(scenario.plan.theta2 - scenario.plan.theta1), 1e-6)


def _check_kinds(kinds: Sequence[str]) -> tuple[str, ...]:
    """``kinds`` as a tuple, or a ValueError if it is empty or names an unknown controller type."""
    bad = [k for k in kinds if not is_controller(k)]
    if bad or not kinds:
        raise ValueError(f"controllers {bad or list(kinds)!r} are not controller types; "
                         f"valid: {list(CONTROLLER_TYPES)}, or law+option+...")
    return tuple(kinds)


def scenario_kinds(scenario: Scenario) -> tuple[str, ...]:
    """Every controller type the scenario can run (any plan): all, less the ``_ff`` ones without a torque model."""
    return tuple(k for k in CONTROLLER_TYPES if scenario.torques is not None or k not in FEEDFORWARD_TYPES)


def check_calibrate(calibrate: Optional[str], scenario: Scenario, kinds: Sequence[str]) -> Optional[str]:
    """``calibrate`` if it is a mode of :data:`CALIBRATE_MODES` that can apply to the scenario and ``kinds``.

    ``"each"`` needs a drive that can calibrate (:func:`~flatstep.studies.calibrate.check_drive`, whose error is
    raised) and at least one type that reads the calibration.
    """
    if calibrate not in CALIBRATE_MODES:
        raise ValueError(f"calibrate={calibrate!r} is not a calibration mode; valid: {list(CALIBRATE_MODES)}")
    if calibrate is None:
        return None
    if not any(k in FEEDFORWARD_TYPES for k in kinds):
        raise ValueError(f"calibrate={calibrate!r} changes only the types that read a calibration "
                         f"({list(FEEDFORWARD_TYPES)}), and the controllers {list(kinds)!r} name none")
    check_drive(scenario)
    return calibrate


def unit_scenario(scenario: Scenario, calibration: Calibration, **changes: Any) -> Scenario:
    """``scenario`` run by a drive that calibrated its own motor (its table and back-EMF ``Km``).

    The calibrated ``[feedforward]`` table replaces the scenario's, and the calibration's back-EMF ``Km`` the
    model's (the law's maps, the observer's model, the cascade's q current and back EMF). The plant is unchanged; so
    are the scenario's SMC gains (designed for the model's uncertainty, not its values). ``changes`` are further
    fields set in the same step (``controller_type``: a type that reads a calibration may be set here on a scenario
    that has no ``[feedforward]`` of its own).
    """
    return replace(scenario, torques=calibration.torques,
                   motor=scenario.motor.replace(Km=calibration.estimates["Km"]), **changes)


def calibrate_units(scenarios: Sequence[Scenario]) -> list[Calibration | str]:
    """Each scenario's plant calibrated on its own drive (the nominal model running the move).

    One :func:`~flatstep.studies.calibrate.calibrate` per scenario, in order; a calibration that fails (its move
    lost or faulted, its fit refused, its run stopped) gives the reason instead, so that the other plants go on.
    """
    out: list[Calibration | str] = []
    for sc in scenarios:
        try:
            out.append(calibrate_unit(sc))
        except (ValueError, RunError) as exc:
            out.append(f"calibration failed: {exc}")
    return out


def _uncalibrated(scenario: Scenario, reason: str) -> dict[str, Any]:
    """A batch row for a run that did not happen because its plant's calibration failed (status and error)."""
    return {"name": scenario.name, "status": CALIBRATION_FAILED, "error": reason, "lost_at": None,
            "controller_faults": 0}


def compare(scenario: Scenario, kinds: Sequence[str] = CONTROLLER_TYPES, *, band: Optional[float] = None,
            bandwidth_scale: float = 1.0, engine: str = "c",
            calibrate: Optional[str] = None) -> dict[str, dict[str, Any]]:
    """Run each controller type on the scenario (its plant, drive, sensors, observer, load and effects).

    With ``calibrate="each"`` the types that read a calibration run with the scenario's plant calibrated on its
    drive (:func:`unit_scenario`; the scenario needs no ``[feedforward]`` of its own). Returns ``{kind: {"metrics":
    ..., "result": SimResult, "faults": n, "status": ..., "lost_at": ..., "error": None}}``; if the calibration
    fails, those types get ``"status": CALIBRATION_FAILED``, the reason in ``"error"``, and no metrics or result.
    """
    band = default_band(scenario) if band is None else band
    kinds = _check_kinds(kinds)
    mode = check_calibrate(calibrate, scenario, kinds)
    unit = calibrate_units([scenario])[0] if mode == "each" else None
    out: dict[str, dict[str, Any]] = {}
    for kind in kinds:
        scale = bandwidth_scale if kind not in SMC_TYPES else 1.0
        if unit is not None and ControllerSpec.parse(kind).needs_torques:
            if isinstance(unit, str):
                out[kind] = {"metrics": None, "result": None, "faults": 0, "status": CALIBRATION_FAILED,
                             "lost_at": None, "error": unit}
                continue
            sc = unit_scenario(scenario, unit, controller_type=kind, bandwidth_scale=scale)
        else:
            sc = replace(scenario, controller_type=kind, bandwidth_scale=scale)
        r = sc.run(engine)
        out[kind] = {"metrics": result_metrics(r, scenario.plan, band=band, R=scenario.simulated_plant.motor.R),
                     "result": r, "faults": int(r.meta.get("controller_faults", 0)), "status": r.status,
                     "lost_at": r.lost_at, "error": None}
    return out


def _worse(a: Optional[float], b: Optional[float]) -> Optional[float]:
    """The worse of two values of a metric: the larger, or ``None`` if either is ``None``.

    Only ``settling_time`` is ever ``None`` (:func:`metrics`): not settled on some plant, the worst case does not
    settle.
    """
    if a is None or b is None:
        return None
    return max(a, b)


def compare_worst(scenario: Scenario, study: Robustness, kinds: Sequence[str] = CONTROLLER_TYPES, *,
                  band: Optional[float] = None, bandwidth_scale: float = 1.0, calibrate: Optional[str] = None,
                  log: Optional[Callable[[str], None]] = None, **batch_options: Any) -> dict[str, dict[str, Any]]:
    """Each controller on every plant of the study (the controllers keep the nominal model).

    With ``calibrate="each"``, each plant is first calibrated on its own drive (once, shared by every type that
    reads the calibration), and the types of :data:`~flatstep.control.tuning.FEEDFORWARD_TYPES` run on it with
    its own table and ``Km`` (:func:`unit_scenario`); the other types run as without it.

    Returns per kind the worst of each metric over the plants (``"worst"``), the failed runs, the rows with
    the series of :data:`KEEP` for figures, and ``"calibrations"`` (one per plant, or ``None`` for a type that
    read none). A plant whose calibration failed gives the types that read it a row with status
    :data:`CALIBRATION_FAILED` and the reason in ``error`` (counted in ``failed``, and in ``statuses``); its
    calibration is the reason (a ``str``) in ``"calibrations"``. ``batch_options`` go to
    :func:`~flatstep.studies.batch.run_batch` (``engine``, ``workers``, ...); ``log`` is told when the calibrations
    and each controller's batch are done.
    """
    band = default_band(scenario) if band is None else band
    kinds = _check_kinds(kinds)
    mode = check_calibrate(calibrate, scenario, kinds)
    errors = plant_errors(study)
    units: Optional[list[Calibration | str]] = None
    out: dict[str, dict[str, Any]] = {}
    for kind in kinds:
        scale = bandwidth_scale if kind not in SMC_TYPES else 1.0
        calibrated = mode == "each" and ControllerSpec.parse(kind).needs_torques
        if calibrated:
            if units is None:
                units = calibrate_units(perturbed(scenario, errors, "/calibration"))
                if log is not None:
                    lost = sum(isinstance(u, str) for u in units)
                    log(f"{len(units)} plants calibrated, each on its own drive"
                        + (f"; {lost} calibrations failed" if lost else ""))
            plants = perturbed(scenario, errors, f"/{kind}")  # the type is set with the table it needs
            runs = [p if isinstance(u, str) else unit_scenario(p, u, controller_type=kind, bandwidth_scale=scale)
                    for p, u in zip(plants, units, strict=True)]
            todo = [r for r, u in zip(runs, units, strict=True) if not isinstance(u, str)]
            done = iter(run_batch(todo, keep=KEEP, **batch_options) if todo else [])
            rows = [_uncalibrated(r, u) if isinstance(u, str) else next(done)
                    for r, u in zip(runs, units, strict=True)]
        else:
            runs = perturbed(replace(scenario, controller_type=kind, bandwidth_scale=scale), errors, f"/{kind}")
            rows = run_batch(runs, keep=KEEP, **batch_options)
        worst: dict[str, Optional[float]] = {}
        for row, run in zip(rows, runs, strict=True):  # run_batch returns one row per run
            if row["error"] is not None:
                continue
            t, e, ia, ib, va, vb = (row[f"series_{k}"] for k in KEEP)
            m = metrics(t, e, ia, ib, va, vb, scenario.plan, band=band, R=run.simulated_plant.motor.R)
            row["metrics"] = m
            worst = m if not worst else {k: _worse(worst[k], m[k]) for k in METRICS}
        failed = [r["error"] for r in rows if r["error"] is not None]
        statuses = {s: sum(r.get("status") == s for r in rows if r["error"] is None) for s in STATUSES}
        statuses[CALIBRATION_FAILED] = sum(r.get("status") == CALIBRATION_FAILED for r in rows)
        out[kind] = {"worst": worst, "runs": len(rows), "failed": len(failed), "failures": failed,
                     "statuses": statuses, "rows": rows, "calibrations": units if calibrated else None}
        if log is not None:
            log(f"{kind}{'' if bandwidth_scale == 1 or kind in SMC_TYPES else f' x{bandwidth_scale:g}'} on "
                f"{len(rows)} plants{', each calibrated' if calibrated else ''}")
    return out


def bandwidth_sweep(scenario: Scenario, kinds: Sequence[str], scales: Sequence[float], *,
                    study: Optional[Robustness] = None, band: Optional[float] = None,
                    log: Optional[Callable[[str], None]] = None, calibrate: Optional[str] = None,
                    **batch_options: Any) -> dict[float, dict[str, dict[str, Optional[float]]]]:
    """The baselines' metrics with every bandwidth scaled by each factor.

    The metrics are the worst over the study's plants, or those on the scenario's plant without a study: the
    check that the tuning rule does not cripple the baselines. ``calibrate`` is that of :func:`compare_worst`.
    """
    out: dict[float, dict[str, dict[str, Optional[float]]]] = {}
    for scale in scales:
        if study is None:
            res = compare(scenario, kinds, band=band, bandwidth_scale=scale, engine=batch_options.get("engine", "c"),
                          calibrate=calibrate)
            out[float(scale)] = {k: v["metrics"] for k, v in res.items()}
        else:
            res = compare_worst(scenario, study, kinds, band=band, bandwidth_scale=scale, log=log, calibrate=calibrate,
                                **batch_options)
            out[float(scale)] = {k: v["worst"] for k, v in res.items()}
    return out
