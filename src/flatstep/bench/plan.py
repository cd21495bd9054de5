"""(a) Planning + feedforward of the paper's move: flatstep (C core, NumPy) against python-control.

python-control plans with ``flatsys.point_to_point`` + ``traj.eval`` on the same flat system and the same
trajectory.
"""
from __future__ import annotations

import warnings
from types import ModuleType
from typing import TYPE_CHECKING, Any, Callable, Optional, Sequence

import numpy as np
from numpy.polynomial import Polynomial
from numpy.typing import ArrayLike, NDArray

from ..model.flat import FlatFlag, flat_to_state, state_to_flat
from ..model.motor import MotorParams, rhs
from ..plan.rest_to_rest import PAPER_PLAN, RestToRest
from .common import Report, Target, core_module, race

if TYPE_CHECKING:  # python-control is optional (the bench extra) and untyped: these are Any to mypy
    from control.flatsys import BasisFamily, FlatSystem

#: A plan's states (4, n) and inputs (2, n).
StatesInputs = tuple[NDArray[np.float64], NDArray[np.float64]]


def psi_span_family(flag_lengths: tuple[int, ...], t0: float, tf: float) -> BasisFamily:
    r"""A ``control.flatsys.BasisFamily`` whose unique point-to-point solution is the paper's psi profile.

    For each flat output whose flag python-control sees up to derivative ``k - 1``: the polynomials of degree
    10 in :math:`\tau = (t - t_0)/(t_f - t_0)` whose derivatives ``k..4`` vanish at :math:`t_0` and ``k..5``
    at :math:`t_f`, the boundary conditions of psi (eq. 17) that the flag does not carry. The space has
    ``2 k`` dimensions, so with python-control's ``2 k`` endpoint conditions the solution is unique, and it is
    psi (the only degree-10 polynomial meeting all eleven conditions).
    """
    import scipy.linalg
    from control.flatsys import BasisFamily

    degree, T = 10, tf - t0
    powers = [Polynomial.basis(p) for p in range(degree + 1)]

    class PsiSpanFamily(BasisFamily):
        """The span of psi's free coefficients for each flat output (see :func:`psi_span_family`)."""

        def __init__(self) -> None:
            super().__init__(degree + 1)
            self.nvars = len(flag_lengths)
            # polys[var][j][k]: k-th tau-derivative of basis function j of output var
            self.polys: list[list[list[Polynomial]]] = []
            for k in flag_lengths:
                rows = [[p.deriv(d)(0.0) for p in powers] for d in range(k, 5)]
                rows += [[p.deriv(d)(1.0) for p in powers] for d in range(k, 6)]
                N = scipy.linalg.null_space(np.array(rows))
                self.polys.append([[Polynomial(N[:, j]).deriv(d) for d in range(k)] for j in range(N.shape[1])])
            self.coef_length = [len(p) for p in self.polys]
            self.coef_offset = [int(o) for o in np.cumsum([0] + self.coef_length[:-1])]

        def eval_deriv(self, i: int, k: int, t: float | NDArray[np.float64],
                       var: Optional[int] = None) -> float | NDArray[np.float64]:
            """The ``k``-th time derivative of basis function ``i`` of flat output ``var`` at times ``t``."""
            assert var is not None, "every flat output has its own basis (nvars is set)"
            return self.polys[var][i][k]((t - t0) / T) / T**k

    return PsiSpanFamily()


def stepper_flat_system(motor: MotorParams, load_torque: float = 0.0) -> FlatSystem:
    """The stepper as a python-control ``FlatSystem`` whose maps are flatstep's.

    The maps are :func:`state_to_flat` and :func:`flat_to_state`; the flat flag is
    ``[[rho, rho'], [theta, theta', theta'', theta''']]``.
    """
    from control.flatsys import FlatSystem

    def forward(x: ArrayLike, u: ArrayLike, params: Optional[dict[str, Any]] = None) -> list[NDArray[np.float64]]:
        """The flat flag of state ``x`` and input ``u``."""
        f = state_to_flat(x, u, motor, load_torque)
        return [np.array([f.rho, f.drho]), np.array([f.theta, f.dtheta, f.ddtheta, f.dddtheta])]

    def reverse(zflag: Sequence[NDArray[np.float64]], params: Optional[dict[str, Any]] = None) -> StatesInputs:
        """The state and input of the flat flag ``zflag``."""
        (rho, drho), (theta, dtheta, ddtheta, dddtheta) = zflag
        return flat_to_state(FlatFlag(rho, drho, theta, dtheta, ddtheta, dddtheta), motor, load_torque)

    def updfcn(t: float, x: ArrayLike, u: ArrayLike, params: Optional[dict[str, Any]] = None) -> NDArray[np.float64]:
        """The state derivative, eq. (1)."""
        return rhs(t, x, u, motor, load_torque)

    return FlatSystem(forward, reverse, updfcn, inputs=("va", "vb"), outputs=("ia", "ib", "omega", "theta"),
                      states=("ia", "ib", "omega", "theta"), name="pm_stepper")


def control_point_to_point(motor: MotorParams, plan: RestToRest,
                           basis: Optional[BasisFamily] = None) -> Callable[[NDArray[np.float64]], StatesInputs]:
    """python-control's plan of ``plan``'s move (rest to rest, u = R i at both ends).

    Returns a function of the times that solves ``point_to_point`` and evaluates the trajectory, returning the
    states and inputs.
    """
    from control import flatsys

    system = stepper_flat_system(motor)
    x0, xf = plan.x0(motor.Nr), plan.xf(motor.Nr)
    u0, uf = motor.R * x0[:2], motor.R * xf[:2]
    basis = basis if basis is not None else psi_span_family((2, 4), plan.t0, plan.tf)

    def plan_and_eval(t: NDArray[np.float64]) -> StatesInputs:
        """Solve the point-to-point problem and evaluate its trajectory at ``t``."""
        traj = flatsys.point_to_point(system, [plan.t0, plan.tf], x0, u0, xf, uf, basis=basis)
        return traj.eval(t)

    return plan_and_eval


def bench_plan(repeat: int = 7, n: int = 401, min_time: float = 0.02, stock_basis: bool = True) -> Report:
    """(a) The paper's move planned and mapped to states and voltages at ``n`` points."""
    motor, plan = MotorParams.preset("paper"), PAPER_PLAN
    t = np.linspace(plan.t0, plan.tf, n)
    pc = control_point_to_point(motor, plan)
    cases: dict[str, Callable[[], Any]] = {}
    notes: list[str] = []
    core = core_module()
    if core is not None:
        cases["flatstep C core, binding (one call)"] = lambda: core.plan_to_state(plan, motor, t)
        cases["flatstep C core, raw lib call"] = _raw_core_plan(core, motor, plan, t)
        cases["flatstep C core, binding (two calls)"] = lambda: core.flat_to_state(core.plan_flag(plan, t), motor)
    else:
        notes.append("the C binding (flatstep.core) is not available: NumPy path only")
    cases["flatstep NumPy reference"] = lambda: flat_to_state(plan.flag(t), motor)
    baseline = "python-control flatsys, psi basis"
    cases[baseline] = lambda: pc(t)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # python-control warns when its basis cannot meet the conditions
        times, results = race(cases, repeat, min_time)
    x_ref, v_ref = results["flatstep NumPy reference"]
    x_pc, v_pc = results[baseline]
    checks = _state_differences("python-control vs flatstep", x_pc, v_pc, x_ref, v_ref)
    if "flatstep C core, binding (one call)" in results:
        x_c, v_c = results["flatstep C core, binding (one call)"]
        checks += _state_differences("C core vs NumPy", x_c, v_c, x_ref, v_ref)[:1]
        checks.append(("max |v_C - v_NumPy|", float(np.abs(v_c - v_ref).max()), " V"))
    notes.append("python-control meets the endpoint flags by a least-squares solve whose derivative rows scale "
                 "as (tf - t0)^-k: the remaining differences are that solve's rounding")
    if stock_basis:
        from control.flatsys import PolyFamily
        x_s, _ = control_point_to_point(motor, plan, PolyFamily(8, plan.tf))(t)
        notes.append("python-control's stock PolyFamily(8) (the least-norm degree-7 fit of the same endpoint "
                     f"flags) plans a different move: max |theta - theta*| = {np.abs(x_s[3] - x_ref[3]).max():.3g} "
                     "rad; the psi basis makes the two planners compute the same trajectory")
    fastest = next(iter(cases))
    targets = [Target(f"speed-up of '{fastest}' vs python-control", times[baseline] / times[fastest], 1000, True,
                      "x")]
    return Report("a", f"plan + feedforward of the paper's move at {n} points", "plan", times, baseline,
                  checks, targets, notes)


def _raw_core_plan(core: ModuleType, motor: MotorParams, plan: RestToRest,
                   t: NDArray[np.float64]) -> Callable[[], StatesInputs]:
    """The C work of (a) alone: one arrays_plan_flat call into buffers allocated once."""
    ffi, lib = core.ffi, core.lib
    m, p = core.motor_struct(motor), core.plan_struct(plan)
    tv, flag = np.ascontiguousarray(t), np.empty((t.size, 6))
    x, v = np.empty((t.size, 4)), np.empty((t.size, 2))
    t_in, flag_out = ffi.from_buffer("double[]", tv), ffi.from_buffer("double[]", flag, require_writable=True)
    x_out = ffi.from_buffer("double[]", x, require_writable=True)
    v_out = ffi.from_buffer("double[]", v, require_writable=True)

    def run() -> StatesInputs:
        """One ``arrays_plan_flat`` call; the states and voltages as views of the buffers."""
        lib.arrays_plan_flat(p, m, t_in, t.size, 0.0, flag_out, x_out, v_out)
        return x.T, v.T

    return run


def _state_differences(label: str, x: NDArray[np.float64], v: NDArray[np.float64], x_ref: NDArray[np.float64],
                       v_ref: NDArray[np.float64]) -> list[tuple[str, float, str]]:
    """The largest differences of angle, speed, currents and voltages between two plans, as report checks."""
    return [(f"{label}: max |theta diff|", float(np.abs(x[3] - x_ref[3]).max()), " rad"),
            (f"{label}: max |omega diff|", float(np.abs(x[2] - x_ref[2]).max()), " rad/s"),
            (f"{label}: max |current diff|", float(np.abs(x[:2] - x_ref[:2]).max()), " A"),
            (f"{label}: max |voltage diff|", float(np.abs(v - v_ref).max()), " V")]
