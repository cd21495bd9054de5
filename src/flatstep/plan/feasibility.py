"""Feasibility of a plan before anything is simulated: rho > 0, the controller's singularity, limits."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.flat import flat_to_state
from ..model.motor import MotorParams
from ..validate import check_instance, check_integer, check_quantity
from ..validate.limits import MAX_PLAN_SAMPLES
from .protocol import Plan, check_plan


class InfeasiblePlanError(ValueError):
    """A requested plan violates a feasibility condition; ``.report`` says where and by how much."""

    def __init__(self, report: FeasibilityReport) -> None:
        super().__init__(report.describe())
        self.report = report


@dataclass(frozen=True)
class FeasibilityReport:
    r"""Result of :func:`check_feasibility`.

    ``torque_margin`` is the smallest :math:`K_m\rho - |J\ddot\theta + B\dot\theta + \tau|` [N m] along
    the plan, reached at ``worst_time``; ``torque_ratio`` the largest :math:`|A| / K_m\rho` (singular at 1).
    """

    feasible: bool
    min_rho: float
    min_rho_time: float
    torque_margin: float
    torque_ratio: float
    worst_time: float
    peak_voltage: float
    peak_voltage_time: float
    peak_current: float
    peak_current_time: float
    v_max: Optional[float] = None
    i_max: Optional[float] = None
    violations: tuple[str, ...] = field(default_factory=tuple)

    def describe(self) -> str:
        """One line: feasible or not, the violations, the worst rho and torque margin and the peaks."""
        head = "feasible plan" if self.feasible else "infeasible plan: " + "; ".join(self.violations)
        peaks = "" if math.isnan(self.peak_voltage) else (
            f"; peak feedforward |v| {self.peak_voltage:.6g} V at t={self.peak_voltage_time:.6g} s, "
            f"peak |i| {self.peak_current:.6g} A at t={self.peak_current_time:.6g} s")
        return (f"{head} (min rho {self.min_rho:.6g} A at t={self.min_rho_time:.6g} s; torque margin "
                f"{self.torque_margin:.6g} N m, ratio {self.torque_ratio:.4f} at t={self.worst_time:.6g} s{peaks})")

    def raise_if_infeasible(self) -> FeasibilityReport:
        """Return the report if the plan is feasible, else raise :class:`InfeasiblePlanError` with it."""
        if not self.feasible:
            raise InfeasiblePlanError(self)
        return self

    def as_dict(self) -> dict[str, Any]:
        """The report's fields by name (``violations`` as a list), for JSON."""
        d = asdict(self)
        d["violations"] = list(self.violations)
        return d


def _torque_margin(plan: Plan, motor: MotorParams, load_torque: float, t: ArrayLike) -> NDArray[np.float64]:
    """``Km rho* - |J theta*'' + B theta*' + tau|`` [N m] at times ``t``: > 0 where the flat maps are regular."""
    f = plan.flag(t)
    return motor.Km * f.rho - np.abs(motor.J * f.ddtheta + motor.B * f.dtheta + load_torque)


def check_feasibility(plan: Plan, motor: MotorParams, *, load_torque: float = 0.0,
                      v_max: Optional[float] = None, i_max: Optional[float] = None,
                      n: int = 2001) -> FeasibilityReport:
    r"""Check the whole plan before anything is simulated.

    The conditions are :math:`\rho^* > 0` and :math:`|J\ddot\theta^* + B\dot\theta^* + \tau| < K_m\rho^*`
    (where they fail the flat maps and the controller (13) are singular) and, if given, the feedforward phase
    voltages against ``v_max`` and phase currents against ``i_max``. The plan is sampled at ``n`` points over
    [t0, tf] and the worst torque margin is refined by a bounded scalar minimisation around the worst sample.
    """
    check_plan(plan)
    check_instance("motor", motor, MotorParams, "a MotorParams", "e.g. MotorParams.preset('paper')")
    n = check_integer("n", n, low=3, high=MAX_PLAN_SAMPLES, why="samples of the plan, at most "
                      "flatstep.validate.limits.MAX_PLAN_SAMPLES")
    load_torque = check_quantity("load", load_torque, as_name="load_torque")
    if v_max is not None:
        v_max = check_quantity("v_bus", v_max, as_name="v_max")
    if i_max is not None:
        i_max = check_quantity("current", i_max, as_name="i_max")
    t = np.linspace(plan.t0, plan.tf, n)
    f = plan.flag(t)
    margin = _torque_margin(plan, motor, load_torque, t)
    i = int(np.argmin(margin))
    lo, hi = t[max(i - 1, 0)], t[min(i + 1, n - 1)]
    from scipy.optimize import minimize_scalar  # here: scipy.optimize takes most of a command's start-up

    res = minimize_scalar(lambda s: float(_torque_margin(plan, motor, load_torque, s)), bounds=(lo, hi),
                          method="bounded", options={"xatol": 1e-12 * max(1.0, abs(plan.tf))})
    worst_t, worst = (float(res.x), float(res.fun)) if res.fun < margin[i] else (float(t[i]), float(margin[i]))
    wf = plan.flag(worst_t)
    ratio = float(abs(motor.J * wf.ddtheta + motor.B * wf.dtheta + load_torque) / (motor.Km * wf.rho))
    j = int(np.argmin(f.rho))
    violations = []
    if f.rho[j] <= 0:
        violations.append(f"rho*={f.rho[j]:.6g} A <= 0 at t={t[j]:.6g} s (phi undefined)")
    if worst <= 0:
        violations.append(f"torque demand exceeds Km rho* by {-worst:.6g} N m at t={worst_t:.6g} s "
                          "(controller singular); slow the move or raise rho")
    peak_v = peak_v_t = peak_i = peak_i_t = float("nan")
    if not violations:
        x, v = flat_to_state(f, motor, load_torque)
        av, ai = np.max(np.abs(v), axis=0), np.max(np.abs(x[:2]), axis=0)
        k, m = int(np.argmax(av)), int(np.argmax(ai))
        peak_v, peak_v_t, peak_i, peak_i_t = float(av[k]), float(t[k]), float(ai[m]), float(t[m])
        if v_max is not None and peak_v > v_max:
            violations.append(f"feedforward |v|={peak_v:.6g} V exceeds v_max={v_max:.6g} V at t={peak_v_t:.6g} s")
        if i_max is not None and peak_i > i_max:
            violations.append(f"phase current |i|={peak_i:.6g} A exceeds i_max={i_max:.6g} A at t={peak_i_t:.6g} s")
    return FeasibilityReport(feasible=not violations, min_rho=float(f.rho[j]), min_rho_time=float(t[j]),
                             torque_margin=worst, torque_ratio=ratio, worst_time=worst_t,
                             peak_voltage=peak_v, peak_voltage_time=peak_v_t, peak_current=peak_i,
                             peak_current_time=peak_i_t, v_max=v_max, i_max=i_max, violations=tuple(violations))
