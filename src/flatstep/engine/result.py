"""Time series of a closed-loop run and its summary numbers."""
from __future__ import annotations

import csv
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass
class SimResult:
    """Closed-loop time series (SI units).

    ``*_ref`` are the planned values, errors are actual - planned. ``s1``, ``s2`` are the sliding variables of
    eq. (12); ``None`` for a controller without them (the baselines), and then left out of :meth:`series`.
    """

    t: Array
    ia: Array
    ib: Array
    omega: Array
    theta: Array
    rho: Array
    phi: Array
    va: Array
    vb: Array
    theta_ref: Array
    omega_ref: Array
    rho_ref: Array
    ia_ref: Array
    ib_ref: Array
    va_ref: Array
    vb_ref: Array
    s1: Optional[Array]
    s2: Optional[Array]
    meta: dict[str, Any]

    @property
    def theta_error(self) -> Array:
        """``theta - theta_ref`` [rad]."""
        return self.theta - self.theta_ref

    @property
    def rho_error(self) -> Array:
        """``rho - rho_ref`` [A]."""
        return self.rho - self.rho_ref

    def series(self) -> dict[str, Array]:
        """All time series by name, errors included."""
        out = {f.name: getattr(self, f.name) for f in fields(self)
               if f.name != "meta" and getattr(self, f.name) is not None}
        out.update(theta_error=self.theta_error, rho_error=self.rho_error)
        return out

    def summary(self) -> dict[str, float]:
        """End-of-horizon values and maxima over the horizon (the keys of summary.json)."""
        return {
            "theta_final": float(self.theta[-1]),
            "ia_final": float(self.ia[-1]),
            "ib_final": float(self.ib[-1]),
            "omega_final": float(self.omega[-1]),
            "max_abs_theta_error": float(np.max(np.abs(self.theta_error))),
            "max_abs_rho_error": float(np.max(np.abs(self.rho_error))),
            "max_abs_va": float(np.max(np.abs(self.va))),
            "max_abs_vb": float(np.max(np.abs(self.vb))),
            "final_theta_error": float(self.theta_error[-1]),
            **self._window_errors(),
        }

    def _window_errors(self) -> dict[str, float]:
        """Max |theta - theta*| during the move [t0, tf] and at rest after it (t > tf), when sampled."""
        plan = self.meta.get("plan")
        if plan is None:
            return {}
        err = np.abs(self.theta_error)
        out: dict[str, float] = {}
        for key, mask in (("max_abs_theta_error_move", (self.t >= plan["t0"]) & (self.t <= plan["tf"])),
                          ("max_abs_theta_error_after", self.t > plan["tf"])):
            if np.any(mask):
                out[key] = float(np.max(err[mask]))
        return out

    def to_csv(self, path: str | Path) -> None:
        """Write every series as a column of a CSV file."""
        series = self.series()
        with open(path, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(series)
            writer.writerows(np.column_stack(list(series.values())).tolist())
