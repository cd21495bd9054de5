r"""Recordings: what a drive measures during a run, as the CSV that :func:`flatstep.studies.identify.identify` reads.

One row per control period, at the sampling instants :math:`t_k = k T_s` (uniform):

========  =====  ===========================================================================================
column    unit   what it is
========  =====  ===========================================================================================
``t``     s      the sampling instant :math:`t_k`
``va``    V      phase-a voltage the bridge applies from :math:`t_k` to :math:`t_{k+1}` (the command after
                 bus saturation, held over the period; with a computation delay, the previous command)
``vb``    V      the same for phase b
``ia``    A      phase-a current as the ADC reads it at :math:`t_k` (offset, noise and quantization included)
``ib``    A      the same for phase b
``theta`` rad    rotor angle as the encoder reads it at :math:`t_k` (the centre of its count), multi-turn
========  =====  ===========================================================================================

The first line is the header; columns may come in any order, each named once, and other columns are ignored.
Times must be strictly increasing with a constant step (to 1e-6 of it).
"""
from __future__ import annotations

import csv
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..engine.result import SimResult
from ..loop.sensors import Sensors

Array = NDArray[np.float64]
#: The columns of a recording, in the order they are written.
COLUMNS = ("t", "va", "vb", "ia", "ib", "theta")
#: What each column holds, for messages.
UNITS = {"t": "s", "va": "V", "vb": "V", "ia": "A", "ib": "A", "theta": "rad"}
#: The fewest rows a recording may have.
MIN_ROWS = 200


@dataclass(frozen=True)
class Recording:
    """The sampled series of one run, as a drive measures them (module docstring); ``source`` names them."""

    t: Array
    va: Array
    vb: Array
    ia: Array
    ib: Array
    theta: Array
    source: str = "recording"

    def __post_init__(self) -> None:
        columns = {name: np.asarray(getattr(self, name), dtype=float) for name in COLUMNS}
        n = columns["t"].size
        for name, values in columns.items():
            if values.ndim != 1 or values.size != n:
                raise ValueError(f"{self.source}: column {name!r} has shape {values.shape}; every column must be "
                                 f"one value per row ({n} rows)")
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:
                raise ValueError(f"{self.source}: column {name!r} has a non-finite value {float(values[bad[0]])!r} in "
                                 f"data row {bad[0] + 1} ({bad.size} in all); every value must be a finite number "
                                 f"[{UNITS[name]}]")
            object.__setattr__(self, name, values)
        if n < MIN_ROWS:
            raise ValueError(f"{self.source}: {n} rows is too short; a recording needs at least {MIN_ROWS} rows "
                             "(and about 1 s at a 20 kHz control rate for the accuracy in docs/identification.md)")
        dt = np.diff(columns["t"])
        step = float(np.median(dt))
        off = np.flatnonzero(~(np.abs(dt - step) <= 1e-6 * step)) if step > 0 else np.array([0])
        if step <= 0 or off.size:
            i = int(off[0]) if off.size else 0
            raise ValueError(f"{self.source}: column 't' must increase by a constant step; rows {i + 1} -> {i + 2} "
                             f"step by {dt[i]!r} s where the median step is {step!r} s")

    @property
    def period(self) -> float:
        """The sampling period [s]."""
        return float(self.t[1] - self.t[0])

    @property
    def duration(self) -> float:
        """From the first to the last sample [s]."""
        return float(self.t[-1] - self.t[0])

    def columns(self) -> dict[str, Array]:
        """The series by column name (:data:`COLUMNS`)."""
        return {name: getattr(self, name) for name in COLUMNS}


def recording_from_result(result: SimResult, source: str = "run") -> Recording:
    """What the drive of a sampled run measured: its applied voltages, ADC currents and encoder angle.

    The readings are those of the run's own sensors (``result.meta["sensors"]``: the same noise sequence,
    offsets and quantization); a loop without sensors reads exactly.

    Parameters
    ----------
    result : SimResult
        A run of the sampled drive loop (``simulate(..., loop=DriveLoop(...))``).
    source : str
        A name for messages.

    Returns
    -------
    Recording
        The series at the control instants.
    """
    if "control_period" not in result.meta:
        raise ValueError(f"{source}: a recording needs a sampled drive (a scenario with [drive] control_rate, or "
                         "simulate(..., loop=DriveLoop(...))): a continuous-time run has no drive that measures")
    sensors = _sensors(result.meta.get("sensors"))
    i = np.array([result.ia, result.ib])
    if sensors is not None:
        i = sensors.read_currents(i, sensors.noise(result.t.size).T)
        theta = sensors.read_angle(result.theta)
    else:
        theta = result.theta
    return Recording(t=result.t, va=result.va, vb=result.vb, ia=i[0], ib=i[1], theta=theta, source=source)


def _sensors(meta: Any) -> Sensors | None:
    """The run's :class:`~flatstep.loop.sensors.Sensors` from its metadata (``None``: exact readings)."""
    if meta is None:
        return None
    return Sensors(**{**meta, "current_offset": tuple(meta["current_offset"])})


def write_recording(path: str | Path, recording: Recording) -> None:
    """Write ``recording`` as CSV (the columns of :data:`COLUMNS`, a header line, 12 significant digits)."""
    data = np.column_stack([getattr(recording, name) for name in COLUMNS])
    np.savetxt(path, data, fmt="%.12g", delimiter=",", header=",".join(COLUMNS), comments="")


def read_recording(path: str | Path) -> Recording:
    """Read a recording's CSV file; a ValueError names the file, the column or row, and what is valid."""
    path = Path(path)
    where = str(path)
    try:
        with open(path, newline="") as fh:
            header = [h.strip() for h in next(csv.reader([fh.readline()]), [])]
            with warnings.catch_warnings():  # a header alone is refused below as too short, not warned about
                warnings.simplefilter("ignore", UserWarning)
                data = np.loadtxt(fh, delimiter=",", ndmin=2) if header else np.empty((0, 0))
    except FileNotFoundError:
        raise ValueError(f"{where}: no such recording file") from None
    except (UnicodeDecodeError, csv.Error, ValueError) as exc:
        raise ValueError(f"{where}: not a CSV file of numbers under one header line: {exc}") from None
    twice = sorted({c for c in header if header.count(c) > 1})
    if twice:
        raise ValueError(f"{where}: column(s) {twice} appear more than once in the header {header}; each column "
                         "must be named once (which one holds the data would be a guess)")
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise ValueError(f"{where}: missing column(s) {missing} in the header {header}; a recording has the columns "
                         f"{list(COLUMNS)} ({', '.join(f'{c} [{u}]' for c, u in UNITS.items())})")
    if data.size and data.shape[1] != len(header):
        raise ValueError(f"{where}: the data rows have {data.shape[1]} fields; the header has {len(header)}")
    if data.size == 0:
        data = np.empty((0, len(header)))
    return Recording(**{c: data[:, header.index(c)] for c in COLUMNS}, source=where)
