r"""Anti-cogging calibration: the detent, the Coulomb friction and the load, from a drive's own sensors.

**The move.** The drive runs a slow rest-to-rest move over ``periods`` detent periods, then back
(:func:`calibration_moves`), under a controller that knows no torque beyond eq. (1) (the cascade by default, as
firmware runs it before its anti-cogging table exists). Its peak speed puts the detent's frequency
:math:`hN_r\dot\theta` at a quarter of the loop's :math:`\omega_n` (:func:`~flatstep.control.tuning.bandwidths`),
so that the loop follows the detent; much slower, the quantized encoder's limit cycle reverses the rotor within
each count and the Coulomb friction it sees is no longer a sign of the mean speed.

**The fit.** Only what the drive measures is used: the ADC currents and the encoder angle (the recording of
:func:`~flatstep.studies.record.recording_from_result`) and the applied voltages. With
:math:`i_q = i_b\cos N_r\theta - i_a\sin N_r\theta`, the shaft equation

.. math::
    i_q = \frac{J}{K_m}\ddot\theta + \frac{B}{K_m}\dot\theta + \frac{\tau}{K_m}
          + \frac{T_d\cos\varphi_d}{K_m}\sin hN_r\theta + \frac{T_d\sin\varphi_d}{K_m}\cos hN_r\theta
          + \frac{T_c}{K_m}\operatorname{sign}\dot\theta

is linear in its six coefficients. Every term is passed through the same zero-phase low-pass filter (the method
of :mod:`flatstep.studies.identify`), which averages out the encoder's quantization and the ADC's; the rows kept
are those where the filtered speed exceeds :data:`MOVING_FRACTION` of the peak. :math:`K_m` itself, which turns
the current coefficients into torques, comes from the electrical equations of the same recording (the back EMF,
:func:`flatstep.studies.identify`'s electrical fit), not from the controller's nominal model, so that the table
holds torques in N m that stay true when the nominal :math:`K_m` is off. A fit the recording cannot support is
refused (:mod:`.identify_checks`: the current noise's share, the estimates' ranges), and so is a back-EMF
:math:`K_m` more than :data:`KM_MODEL_FACTOR` from the model's, with which the move ran as planned.

**The result** is a :class:`~flatstep.model.torque_model.TorqueModel`, written as the scenario file's
``[feedforward]`` table (:meth:`Calibration.as_toml`, :func:`merged_scenario`), which the ``_ff`` controller types
and the cascade's anti-cogging read.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass, replace
from statistics import NormalDist
from typing import Any

import numpy as np
import tomlkit
import tomlkit.exceptions
import tomlkit.items

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from ..control.tuning import CONTROLLER_TYPES, FEEDFORWARD_TYPES, bandwidths
from ..engine.simulate import simulate
from ..model.torque_model import TorqueModel
from ..plan.rest_to_rest import RestToRest, psi
from ..validate import InputError, check_count, check_integer, check_nonnegative, check_positive
from ..validate.limits import MIN_PERIODS_PER_MOVE
from ..validate.ranges import QUANTITIES
from .identify import _electrical
from .identify_checks import check_estimates, check_noise_share
from .identify_ls import Fit, fit
from .record import Recording, recording_from_result
from .scenario import Scenario

#: The rows of the fit: filtered speed above this fraction of the move's peak speed.
MOVING_FRACTION = 0.3
#: The peak speed's detent frequency, as a fraction of the loop's omega_n.
DETENT_FRACTION_OF_WN = 0.25
#: The filter's cutoff, in multiples of the detent frequency at the peak speed.
CUTOFF_OVER_DETENT = 4.0
#: The electrical fit's cutoff [Hz] (that of :func:`flatstep.studies.identify.identify`).
ELECTRICAL_CUTOFF = 200.0
#: How far the back-EMF Km may be from the model's that ran the move (a factor either way).
KM_MODEL_FACTOR = 2.0
#: Rest before and after each move [s].
REST = 0.05
#: The controller types a calibration may run: any that needs no torque model.
CALIBRATION_TYPES = tuple(k for k in CONTROLLER_TYPES if k not in FEEDFORWARD_TYPES)
HINT = "cover more detent periods (periods) or change the move's peak_speed"
DRIVE_HINT = "calibrate on a scenario with a sampled drive ([drive] control_rate) and its [sensors]"
_PSI_PEAK = float(np.max(psi(np.linspace(0.0, 1.0, 2001), 0.0, 1.0, 1)))  # peak speed of a unit move in unit time


@dataclass(frozen=True)
class Calibration:
    """What a calibration found: the torque model, and the estimates behind it.

    Parameters
    ----------
    torques : TorqueModel
        The ``[feedforward]`` table: detent amplitude, harmonic and phase, Coulomb friction, load.
    estimates : dict of str to float
        Every estimate: ``Km`` [V s/rad] (electrical fit), ``J`` [kg m^2], ``B`` [N m s/rad], ``load`` [N m],
        ``detent_torque`` [N m], ``detent_phase`` [rad], ``coulomb_torque`` [N m].
    std : dict of str to float
        Standard errors of ``estimates`` (the residuals' correlation and Km's own uncertainty allowed for).
    settings : dict
        The move and fit: controller, periods, peak speed, cutoff, samples.
    source : str
        The scenario's name.
    """

    torques: TorqueModel
    estimates: dict[str, float]
    std: dict[str, float]
    settings: dict[str, Any]
    source: str

    def as_toml(self) -> str:
        """The ``[feedforward]`` table of a scenario file (the keys :class:`TorqueModel` reads)."""
        t = self.torques
        return (f"# calibrated by 'flatstep calibrate' on {self.source} ({self.settings['controller']}, "
                f"{self.settings['periods']} detent periods each way at {self.settings['peak_speed']:.4g} rad/s)\n"
                "[feedforward]\n"
                f"detent_torque = {t.detent_torque:.6g}\n"
                f"detent_harmonic = {t.detent_harmonic}\n"
                f"detent_phase = {t.detent_phase:.6g}\n"
                f"coulomb_torque = {t.coulomb_torque:.6g}\n"
                f"coulomb_speed = {t.coulomb_speed:.6g}\n"
                f"load = {t.load:.6g}\n")

    def as_dict(self) -> dict[str, Any]:
        """Everything, for JSON."""
        return {"source": self.source, "feedforward": self.torques.as_dict(), "estimates": self.estimates,
                "std": self.std, "settings": self.settings}


def check_drive(scenario: Scenario) -> None:
    """Refuse a scenario whose drive cannot calibrate: no sampled loop, no sensors, or a load that varies."""
    if not isinstance(scenario, Scenario):
        raise ValueError(f"scenario={scenario!r} is not a Scenario")
    if scenario.loop is None:
        raise ValueError(f"scenario {scenario.name!r} has no drive loop: a calibration runs on a sampled drive and "
                         f"reads its sensors; {DRIVE_HINT}")
    if scenario.loop.sensors is None:
        raise ValueError(f"scenario {scenario.name!r} has no [sensors]: a calibration reads the drive's own encoder "
                         f"and current ADC, not the plant's state; {DRIVE_HINT}")
    if scenario.simulated_plant.constant_load is None:
        raise ValueError(f"scenario {scenario.name!r}: the plant's load is a function of time; a calibration "
                         "estimates a constant load (give a constant [load] torque)")


def _move(scenario: Scenario, periods: int, peak_speed: float | None, h: int) -> tuple[float, float, float]:
    """The calibration move's peak speed [rad/s] (default or checked), distance [rad] and duration [s]."""
    loop, motor = scenario.loop, scenario.motor
    assert loop is not None  # check_drive
    if peak_speed is None:
        _, wn = bandwidths(loop.control_period, loop.compute_delay)
        peak_speed = DETENT_FRACTION_OF_WN * wn / (h * motor.Nr)
    peak_speed = check_positive("peak_speed", peak_speed, unit=" rad/s")
    distance = periods * 2.0 * math.pi / (h * motor.Nr)
    duration = _PSI_PEAK * distance / peak_speed
    shortest = MIN_PERIODS_PER_MOVE * loop.control_period
    longest = QUANTITIES["time"].high / 4.0  # both moves with their rests within the time range
    if not shortest <= duration <= longest:
        raise InputError("peak_speed", peak_speed, f"peak_speed={peak_speed!r} rad/s makes the calibration move "
                         f"({periods} detent periods, {distance:.4g} rad) last {duration:.4g} s; it must last from "
                         f"{shortest:.4g} s ({MIN_PERIODS_PER_MOVE} control periods) to {longest:.4g} s: give a peak "
                         f"speed from {_PSI_PEAK * distance / longest:.4g} to {_PSI_PEAK * distance / shortest:.4g} "
                         "rad/s, or leave the default")
    return peak_speed, distance, duration


def calibration_horizon(scenario: Scenario, *, periods: int = 16, peak_speed: float | None = None,
                        detent_harmonic: int = 4) -> float:
    """The time :func:`calibration_moves` simulates on ``scenario``'s drive [s]: both moves with their rests."""
    check_drive(scenario)
    periods = check_count("periods", periods, why="detent periods each way")
    _, _, duration = _move(scenario, periods, peak_speed, check_integer("detent_harmonic", detent_harmonic))
    return 2.0 * (duration + 2 * REST)


def calibration_moves(scenario: Scenario, *, controller: str = "cascade", periods: int = 16,
                      peak_speed: float | None = None, detent_harmonic: int = 4,
                      current_noise: float | None = None) -> tuple[Recording, float]:
    """Run the calibration's move there and back on ``scenario``'s drive and plant; what its sensors read.

    Parameters
    ----------
    scenario : Scenario
        A sampled-drive scenario with sensors; its plant is the one calibrated, its ``motor`` the controller's model.
    controller : str
        The controller type that runs the move, one of :data:`CALIBRATION_TYPES` (no torque model).
    periods : int
        Detent periods covered each way.
    peak_speed : float, optional
        The move's peak speed [rad/s]; default: the detent frequency at :data:`DETENT_FRACTION_OF_WN` of the
        loop's omega_n. The accuracy of docs/comparison.md ("Calibration") holds at the default; half or twice
        it loses the Coulomb friction's (slower: the encoder's limit cycle; faster: the loop's bandwidth).
    detent_harmonic : int
        :math:`h`, detent periods per electrical period.
    current_noise : float, optional
        The ADC noise [A rms] to use instead of the scenario's sensors' own.

    Returns
    -------
    (Recording, float)
        What the drive measured over both moves, and the peak speed [rad/s].
    """
    check_drive(scenario)
    if controller not in CALIBRATION_TYPES:
        raise ValueError(f"controller={controller!r} cannot run a calibration; valid: {list(CALIBRATION_TYPES)} "
                         "(a type that needs no torque model: the torques are what is calibrated)")
    periods = check_count("periods", periods, why="detent periods each way")
    h = check_integer("detent_harmonic", detent_harmonic)
    loop, motor = scenario.loop, scenario.motor
    assert loop is not None and loop.sensors is not None  # check_drive
    sensors = loop.sensors if current_noise is None else replace(
        loop.sensors, current_noise=check_nonnegative("current_noise", current_noise, unit=" A"))
    peak_speed, distance, duration = _move(scenario, periods, peak_speed, h)
    plant, rho = scenario.simulated_plant, scenario.plan.rho2
    theta, x, elapsed, parts = scenario.plan.theta1, scenario.plan.x0(motor.Nr), 0.0, []
    for k, sign in enumerate((1.0, -1.0)):
        plan = RestToRest(theta1=theta, theta2=theta + sign * distance, rho1=rho, rho2=rho, t0=REST,
                          tf=REST + duration)
        run_loop = replace(loop, sensors=replace(sensors, seed=sensors.seed + k))
        run = replace(scenario, plan=plan, loop=run_loop, controller_type=controller, torques=None,
                      t_end=duration + 2 * REST)
        result = simulate(plant, plan, run.controller(), loop=run_loop, t_end=run.t_end, x0=x)
        if result.status != "ok":  # a lost or faulted move does not follow the planned speed: no calibration
            summary = result.summary()
            raise ValueError(f"scenario {scenario.name!r}: the calibration move {k + 1} of 2 ({controller}) ended "
                             f"with status {result.status!r} (lost at {summary['lost_at']}, "
                             f"{summary['controller_faults']} faulted periods): lower --speed, or check the drive "
                             "(bus, load) and the controller")
        part = recording_from_result(result, source=f"{scenario.name} calibration").columns()
        part["t"] = part["t"] + elapsed
        parts.append({c: v[:-1] for c, v in part.items()})  # the last sample is the next run's first
        x = np.array([result.ia[-1], result.ib[-1], result.omega[-1], result.theta[-1]])
        theta, elapsed = plan.theta2, elapsed + float(result.t[-1])
    cols = {c: np.concatenate([p[c] for p in parts]) for c in parts[0]}
    return Recording(**cols, source=f"{scenario.name} calibration"), peak_speed


def _torque_fit(rec: Recording, Nr: int, h: int, peak_speed: float) -> tuple[Fit, float]:
    """The shaft equation's fit in units of Km (module docstring), and the filter's cutoff [Hz]."""
    fs = 1.0 / rec.period
    fc = min(CUTOFF_OVER_DETENT * h * Nr * peak_speed / (2.0 * math.pi), 0.2 * fs)
    from scipy.signal import butter, sosfiltfilt  # here: scipy.signal takes a second to import, on every command

    sos = butter(4, fc, fs=fs, output="sos")
    th = rec.theta
    omega = np.gradient(sosfiltfilt(sos, th), rec.period)
    iq = rec.ib * np.cos(Nr * th) - rec.ia * np.sin(Nr * th)
    f = sosfiltfilt(sos, np.array([iq, np.sin(h * Nr * th), np.cos(h * Nr * th)]), axis=-1)
    cut = math.ceil(3.0 * fs / fc)
    rows = np.abs(omega) > MOVING_FRACTION * peak_speed
    rows[:cut] = rows[-cut:] = False
    X = np.column_stack([np.gradient(omega, rec.period), omega, np.ones_like(omega), f[1], f[2], np.sign(omega)])
    step = max(1, int(fs / (4.0 * fc)))  # four rows per cutoff period
    keep = np.flatnonzero(rows)[::step]
    names = ["J", "B", "load", "detent_a", "detent_b", "coulomb_torque"]
    return fit([(X[keep], f[0][keep])], names, lags=8, source=rec.source, hint=HINT), fc


def calibrate(scenario: Scenario, *, controller: str = "cascade", periods: int = 16, peak_speed: float | None = None,
              detent_harmonic: int = 4, coulomb_speed: float = 0.1, current_noise: float | None = None) -> Calibration:
    r"""Calibrate the detent, the Coulomb friction and the load of ``scenario``'s plant (module docstring).

    Parameters
    ----------
    scenario : Scenario
        A sampled-drive scenario with sensors (its ``[feedforward]`` is not used: the move runs without one).
    controller, periods, peak_speed, detent_harmonic, current_noise
        The move (:func:`calibration_moves`).
    coulomb_speed : float
        :math:`\omega_s` [rad/s] of the table's smooth sign (a choice for the controllers, not an estimate: 0.1
        rad/s keeps the observer's speed noise at rest from flipping it).

    Returns
    -------
    Calibration
        The ``[feedforward]`` table and the estimates. A negative Coulomb estimate (a plant without friction,
        within the noise) is written to the table as 0; ``estimates`` keeps it as found.
    """
    coulomb_speed = check_positive("coulomb_speed", coulomb_speed, unit=" rad/s")
    rec, peak = calibration_moves(scenario, controller=controller, periods=periods, peak_speed=peak_speed,
                                  detent_harmonic=detent_harmonic, current_noise=current_noise)
    Nr, h = scenario.motor.Nr, int(detent_harmonic)
    mech, fc = _torque_fit(rec, Nr, h, peak)
    elec, share = _electrical(rec, Nr, ELECTRICAL_CUTOFF, True, True)
    check_noise_share(share, rec.source)
    km, var_km = float(elec.values[2]), float(elec.covariance[2, 2])
    if not km > 0:
        raise ValueError(f"{rec.source}: the back EMF gives Km = {km!r} V s/rad; a calibration needs Km > 0 (does the "
                         "rotor move? raise peak_speed)")
    model = scenario.motor.Km
    if not 1.0 / KM_MODEL_FACTOR <= km / model <= KM_MODEL_FACTOR:
        raise ValueError(f"{rec.source}: the back EMF gives Km = {km:.6g} V s/rad, {km / model:.3g} times the "
                         f"model's {model:.6g} V s/rad with which the move ran as planned (at most a factor "
                         f"{KM_MODEL_FACTOR:g} either way): the recording contradicts the model; check the current "
                         "sensing (noise, range) and Nr")
    p = km * mech.values
    cov = km**2 * mech.covariance + np.outer(mech.values, mech.values) * var_km  # Km's variance too (delta method)
    v = dict(zip(mech.names, p, strict=True))
    a, b = v.pop("detent_a"), v.pop("detent_b")
    amp = math.hypot(a, b)
    sub = cov[3:5, 3:5]
    g_amp, g_phase = (np.array([a, b]) / amp, np.array([-b, a]) / amp**2) if amp > 0 else (np.zeros(2), np.zeros(2))
    estimates = {"Km": km, **{k: float(x) for k, x in v.items()}, "detent_torque": amp,
                 "detent_phase": math.atan2(b, a)}
    std = {k: math.sqrt(max(float(cov[i, i]), 0.0)) for i, k in enumerate(mech.names) if not k.startswith("detent")}
    std.update(Km=math.sqrt(max(var_km, 0.0)), detent_torque=math.sqrt(max(float(g_amp @ sub @ g_amp), 0.0)),
               detent_phase=math.sqrt(max(float(g_phase @ sub @ g_phase), 0.0)))
    z = NormalDist().inv_cdf(0.975)
    check_estimates({k: v for k, v in estimates.items() if k != "detent_phase"},
                    {k: (estimates[k] - z * std[k], estimates[k] + z * std[k]) for k in estimates}, rec.source, 0.95)
    torques = TorqueModel(detent_torque=amp, detent_harmonic=h, detent_phase=estimates["detent_phase"],
                          coulomb_torque=max(estimates["coulomb_torque"], 0.0), coulomb_speed=coulomb_speed,
                          load=estimates["load"])
    settings = {"controller": controller, "periods": int(periods), "current_noise": current_noise,
                "peak_speed": peak, "cutoff": fc, "samples": int(rec.t.size), "period": rec.period}
    return Calibration(torques=torques, estimates=estimates, std=std, settings=settings, source=scenario.name)


def _trailing_comments(body: list[tuple[Any, Any]]) -> None:
    """Drop the comment lines at the end of a TOML container's ``body`` (those right above the next table).

    A table's last items hold the comments written above the table that follows it; a nested table or an array of
    tables at the end holds them in its own last table.
    """
    while body:
        key, item = body[-1]
        if isinstance(item, tomlkit.items.Table) and not (key is not None and key.is_dotted()):
            body = item.value.body
        elif isinstance(item, tomlkit.items.AoT) and item.body:
            body = item.body[-1].value.body
        else:
            break
    while body and body[-1][0] is None and isinstance(body[-1][1], tomlkit.items.Comment):
        body.pop()


def merged_scenario(text: str, calibration: Calibration) -> str:
    """A scenario file's ``text`` with its ``[feedforward]`` table replaced by the calibrated one (or it appended).

    The file is edited as TOML (:mod:`tomlkit`, which keeps every other key, comment and blank line as written),
    whichever way the old table is spelled: a table ``[feedforward]`` (or ``[ feedforward ]``), an inline table
    ``feedforward = {...}``, or dotted keys ``feedforward.load = ...``. Its keys and the comments inside it go; so do
    the comment lines right above a ``[feedforward]`` header (they described it), while the comment lines at its
    end, above the next table, stay with that table. The calibrated table is appended at the end of the file.

    Raises
    ------
    ValueError
        ``text`` is not TOML (the message names the line), or the result would not read back with the calibrated
        table (which would be a flaw of this function: nothing is written then).
    """
    try:
        doc = tomlkit.parse(text)
    except tomlkit.exceptions.ParseError as exc:
        raise ValueError(f"the scenario file is not TOML: {exc}") from None
    kept: list[tuple[Any, Any]] = []
    for key, item in doc.body:
        if key is None or key.key != "feedforward":
            kept.append((key, item))
            continue
        if isinstance(item, tomlkit.items.Table) and not key.is_dotted():  # a [feedforward] header
            _trailing_comments(kept)
            body = item.value.body
            cut = len(body)
            while cut > 0 and body[cut - 1][0] is None and isinstance(
                    body[cut - 1][1], (tomlkit.items.Comment, tomlkit.items.Whitespace)):
                cut -= 1
            while cut < len(body) and isinstance(body[cut][1], tomlkit.items.Whitespace):
                cut += 1  # the blank line above the old table's header stays, this one would double it
            kept += body[cut:]  # the next table's own comments
    doc.body[:] = kept
    merged = f"{doc.as_string().rstrip()}\n\n{calibration.as_toml()}"
    read = tomllib.loads(merged).get("feedforward")
    if read != tomllib.loads(calibration.as_toml())["feedforward"]:
        raise ValueError(f"merging the calibrated [feedforward] table gave {read!r}, not the calibrated table")
    return merged
