r"""Time series of a closed-loop run, its status and its summary numbers.

**Status** (:attr:`SimResult.status`, and the ``status`` key of :meth:`SimResult.summary`, batch rows, compare
and robustness reports):

* ``"lost"``: the move was lost, first at the time ``lost_at``: :math:`|\theta - \theta^*|` exceeded one
  full step, :math:`\pi/(2N_r)` (the angle between two detent positions of a two-phase motor: beyond it the
  rotor settles in another detent, the step an open-loop drive would skip), or the run ends with
  :math:`|\theta - \theta^*|` beyond :func:`arrival_error`, half the plan's *last move* if that is smaller
  than a step (the rotor then rests nearer that move's start than its target: a move shorter than a step, as
  the paper's 0.02 rad, is lost long before it is a full step off); ``lost_at`` is then the start of that last
  excursion. The last move runs from the last rest of the plan at another angle than its end to its end
  (:func:`last_move`, :func:`rest_angles`): :math:`|\theta_2 - \theta_1|` for a rest-to-rest move, 1 rad for a
  waypoint plan 0 -> 1 -> 0 (a round trip returns to its start, but its last move is not of zero length);
* ``"fault"``: the move was kept, but the controller faulted in ``controller_faults`` periods (outside its
  law's domain: it applied 0 V there), the first at ``first_fault_time``;
* ``"ok"``: neither.

A run whose state became non-finite does not return a result: it raises a RuntimeError naming the time.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np
from numpy.typing import NDArray

from ..model.motor import full_step

Array = NDArray[np.float64]
#: A run's statuses, best first (module docstring).
STATUSES = ("ok", "fault", "lost")


#: Two rest angles closer than this, relative to the largest angle (at least 1 rad), are the same rest: the ends of
#: a dwell evaluated on two segments differ by rounding. The C twin is ``BATCH_REST_TOLERANCE`` (csrc/batch.h).
REST_TOLERANCE = 1e-12


def last_move(rests: Sequence[float]) -> float:
    """The length of the last move through the rest angles ``rests`` (in order) [rad]; 0 if it never moves.

    The last move starts at the latest rest whose angle differs from the final one by more than
    :data:`REST_TOLERANCE` (relative to the largest angle, at least 1 rad), so a dwell (two rests at one angle)
    is no move, and a round trip 0 -> 1 -> 0 ends with a move of 1 rad. ``batch_arrival_error`` (csrc/batch.c)
    computes the same.
    """
    if len(rests) < 2:
        return 0.0
    end = float(rests[-1])
    tol = REST_TOLERANCE * max(1.0, max(abs(float(r)) for r in rests))
    for r in reversed(rests[:-1]):
        if abs(end - float(r)) > tol:
            return abs(end - float(r))
    return 0.0


def arrival_error(Nr: int, *rests: float) -> float:
    """The error at the end of a run beyond which its move is lost [rad]: the plan rests at ``rests`` in order.

    One full step, or half the plan's last move (:func:`last_move`) if that is smaller; one full step for a plan
    that never moves. ``arrival_error(Nr, theta1, theta2)`` is the rule of one rest-to-rest move; see the module
    docstring.
    """
    half = 0.5 * last_move(rests)
    return min(full_step(Nr), half) if half > 0 else full_step(Nr)


def rest_angles(plan: Any) -> list[float]:
    """The angles at which ``plan`` rests, in order: its start, each break where theta* stands still, its end.

    A rest-to-rest move (no ``breaks``) rests at ``theta1`` and ``theta2``. A segment table
    (:class:`~flatstep.plan.piecewise.PiecewisePlan`) rests at each break whose speed is at most 1e-9 of its
    fastest break's (a waypoint passed at speed is no rest).
    """
    breaks = getattr(plan, "breaks", None)
    if breaks is None:
        return [float(plan.theta1), float(plan.theta2)]
    f = plan.flag(np.asarray(breaks, dtype=float))
    speed = np.abs(np.asarray(f.dtheta, dtype=float))
    still = speed <= 1e-9 * float(speed.max()) if speed.size else speed == 0
    rests = [float(plan.theta1), *np.asarray(f.theta, dtype=float)[still].tolist(), float(plan.theta2)]
    return rests


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

    @property
    def lost_at(self) -> Optional[float]:
        """The first time the move was lost [s] (module docstring), or ``None``."""
        Nr, plan = self.meta.get("plant", {}).get("motor", {}).get("Nr"), self.meta.get("plan")
        if Nr is None or plan is None:
            raise ValueError("this SimResult has no plant or plan in its metadata (meta['plant'], meta['plan']): "
                             "the full step that decides a lost move is unknown; build results with flatstep.simulate")
        err = np.abs(self.theta_error)
        beyond = np.flatnonzero(err > full_step(int(Nr)))
        if beyond.size:
            return float(self.t[beyond[0]])
        rests = plan.get("rests", (plan["theta1"], plan["theta2"]))  # results built before plans kept their rests
        near = np.flatnonzero(err <= arrival_error(int(Nr), *rests))
        if near.size and near[-1] == err.size - 1:
            return None  # it ends within arrival_error of the target
        return float(self.t[near[-1] + 1]) if near.size else float(self.t[0])

    @property
    def status(self) -> str:
        """``"lost"``, ``"fault"`` or ``"ok"`` (module docstring)."""
        if self.lost_at is not None:
            return "lost"
        return "fault" if self.meta.get("controller_faults", 0) else "ok"

    def summary(self) -> dict[str, Any]:
        """Status, end-of-horizon values and maxima over the horizon (the keys of summary.json)."""
        return {
            "status": self.status,
            "lost_at": self.lost_at,
            "controller_faults": int(self.meta.get("controller_faults", 0)),
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
