"""Benchmarks: each compares implementations side by side in one run and prints medians and ratios.

``flatstep bench [--which a,b,c,d] [--repeat N]`` (docs/benchmarks.md keeps every figure with its command):

a. planning + feedforward of the paper's move at 401 points: flatstep (C core, NumPy) against python-control's
   ``flatsys.point_to_point`` + ``traj.eval`` on the same flat system and the same trajectory;
b. the paper's 60 ms closed loop (Fig. 1): the C engine against scipy LSODA and python-control's
   ``input_output_response``, each checked against the exact solution;
c. one controller step: a C driver (ns per call; instructions per call by callgrind) against the binding and
   the Python reference;
d. batch throughput: 60 ms closed-loop runs per second at 20 kHz sampled control, one thread against all cores.

The machine may be shared: the cases of a benchmark take turns in every round, medians are quoted, and the
ratios measured in the same run are the figures that mean something. Clocks are read here, never in the library.
"""
from __future__ import annotations

import math
import os
import re
import shutil
import statistics
import subprocess
import tempfile
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np
from numpy.polynomial import Polynomial

from .flat import FlatFlag, flat_to_state, state_to_flat
from .motor import MotorParams, rhs, torque
from .plan import PAPER_PLAN, RestToRest
from .scenario import PAPER_SCENARIOS
from .simulate import simulate

ROOT = Path(__file__).resolve().parents[2]
WHICH = ("a", "b", "c", "d")


@dataclass
class Target:
    """A goal of issue 3: ``value`` compared with ``limit`` (at least or at most)."""

    what: str
    value: float
    limit: float
    at_least: bool
    unit: str = ""

    @property
    def met(self) -> bool:
        return self.value >= self.limit if self.at_least else self.value <= self.limit

    def describe(self) -> str:
        sign = ">=" if self.at_least else "<="
        head = f"{self.what} = {self.value:.4g}{self.unit} (target {sign} {self.limit:g}{self.unit})"
        if self.met:
            return f"{head}: met"
        factor = self.limit / self.value if self.at_least else self.value / self.limit
        return f"{head}: MISSED by a factor {factor:.2f}"


@dataclass
class Report:
    """One benchmark's medians (seconds per ``unit``), ratios against ``baseline``, checks and targets."""

    key: str
    title: str
    unit: str
    times: dict[str, float]
    baseline: str
    checks: list[tuple[str, float, str]] = field(default_factory=list)
    targets: list[Target] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def ratio(self, case: str) -> float:
        """How many times faster ``case`` is than the baseline."""
        return self.times[self.baseline] / self.times[case]

    def format(self) -> str:
        width = max(len(name) for name in self.times) + 2
        lines = [f"({self.key}) {self.title}",
                 f"  {'case':<{width}}{'median per ' + self.unit:>18}{'speed-up vs baseline':>24}"]
        for name, seconds in self.times.items():
            mark = "  (baseline)" if name == self.baseline else ""
            lines.append(f"  {name:<{width}}{_duration(seconds):>18}{self.ratio(name):>23.1f}x{mark}")
        lines += [f"  check: {what} = {value:.3g}{unit}" for what, value, unit in self.checks]
        lines += [f"  target: {t.describe()}" for t in self.targets]
        lines += [f"  note: {note}" for note in self.notes]
        return "\n".join(lines)


def _duration(seconds: float) -> str:
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if seconds >= scale:
            return f"{seconds / scale:.4g} {unit}"
    return f"{seconds / 1e-9:.4g} ns"


def _clock(fn: Callable[[], Any], loops: int) -> float:
    start = time.perf_counter()
    for _ in range(loops):
        fn()
    return time.perf_counter() - start


def race(cases: dict[str, Callable[[], Any]], repeat: int, min_time: float = 0.02,
         per: Optional[dict[str, int]] = None) -> tuple[dict[str, float], dict[str, Any]]:
    """Median seconds per unit of work of each case, and each case's result (from its first, untimed call).

    The cases take turns in every one of ``repeat`` rounds, so a change of load on a shared machine hits them
    all alike; each sample loops its case until it lasts about ``min_time``. ``per[name]`` is the number of
    units one call does (e.g. samples), default 1.
    """
    if repeat < 1:
        raise ValueError(f"repeat={repeat!r} must be >= 1")
    results = {name: fn() for name, fn in cases.items()}
    loops = {name: max(1, math.ceil(min_time / max(_clock(fn, 1), 1e-9))) for name, fn in cases.items()}
    samples: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(repeat):
        for name, fn in cases.items():
            samples[name].append(_clock(fn, loops[name]) / loops[name])
    per = per or {}
    return {name: statistics.median(s) / per.get(name, 1) for name, s in samples.items()}, results


def _core_module():
    """The C binding, or None when it is not built."""
    try:
        from . import _core
    except ImportError:
        return None
    return _core


# ----------------------------------------------------------------------------------------------- (a) planning

def psi_span_family(flag_lengths: tuple[int, ...], t0: float, tf: float):
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
        def __init__(self) -> None:
            super().__init__(degree + 1)
            self.nvars = len(flag_lengths)
            self.polys = []  # polys[var][j][k]: k-th tau-derivative of basis function j of output var
            for k in flag_lengths:
                rows = [[p.deriv(d)(0.0) for p in powers] for d in range(k, 5)]
                rows += [[p.deriv(d)(1.0) for p in powers] for d in range(k, 6)]
                N = scipy.linalg.null_space(np.array(rows))
                self.polys.append([[Polynomial(N[:, j]).deriv(d) for d in range(k)] for j in range(N.shape[1])])
            self.coef_length = [len(p) for p in self.polys]
            self.coef_offset = [int(o) for o in np.cumsum([0] + self.coef_length[:-1])]

        def eval_deriv(self, i, k, t, var=None):
            return self.polys[var][i][k]((t - t0) / T) / T**k

    return PsiSpanFamily()


def stepper_flat_system(motor: MotorParams, load_torque: float = 0.0):
    """The stepper as a python-control ``FlatSystem`` whose maps are flatstep's :func:`state_to_flat` and
    :func:`flat_to_state`; flat flag ``[[rho, rho'], [theta, theta', theta'', theta''']]``."""
    from control.flatsys import FlatSystem

    def forward(x, u, params=None):
        f = state_to_flat(x, u, motor, load_torque)
        return [np.array([f.rho, f.drho]), np.array([f.theta, f.dtheta, f.ddtheta, f.dddtheta])]

    def reverse(zflag, params=None):
        (rho, drho), (theta, dtheta, ddtheta, dddtheta) = zflag
        return flat_to_state(FlatFlag(rho, drho, theta, dtheta, ddtheta, dddtheta), motor, load_torque)

    def updfcn(t, x, u, params=None):
        return rhs(t, x, u, motor, load_torque)

    return FlatSystem(forward, reverse, updfcn, inputs=("va", "vb"), outputs=("ia", "ib", "omega", "theta"),
                      states=("ia", "ib", "omega", "theta"), name="pm_stepper")


def control_point_to_point(motor: MotorParams, plan: RestToRest, basis=None) -> Callable[[np.ndarray], tuple]:
    """python-control's plan of ``plan``'s move (rest to rest, u = R i at both ends): a function of the times
    that solves ``point_to_point`` and evaluates the trajectory, returning the states and inputs."""
    from control import flatsys

    system = stepper_flat_system(motor)
    x0, xf = plan.x0(motor.Nr), plan.xf(motor.Nr)
    u0, uf = motor.R * x0[:2], motor.R * xf[:2]
    basis = basis if basis is not None else psi_span_family((2, 4), plan.t0, plan.tf)

    def plan_and_eval(t: np.ndarray) -> tuple:
        traj = flatsys.point_to_point(system, [plan.t0, plan.tf], x0, u0, xf, uf, basis=basis)
        return traj.eval(t)

    return plan_and_eval


def bench_plan(repeat: int = 7, n: int = 401, min_time: float = 0.02, stock_basis: bool = True) -> Report:
    """(a) The paper's move planned and mapped to states and voltages at ``n`` points."""
    motor, plan = MotorParams.preset("paper"), PAPER_PLAN
    t = np.linspace(plan.t0, plan.tf, n)
    pc = control_point_to_point(motor, plan)
    cases: dict[str, Callable[[], Any]] = {}
    notes = []
    core = _core_module()
    if core is not None:
        cases["flatstep C core, binding (one call)"] = lambda: core.plan_to_state(plan, motor, t)
        cases["flatstep C core, raw lib call"] = _raw_core_plan(core, motor, plan, t)
        cases["flatstep C core, binding (two calls)"] = lambda: core.flat_to_state(core.plan_flag(plan, t), motor)
    else:
        notes.append("the C binding (flatstep._core) is not available: NumPy path only")
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


def _raw_core_plan(core, motor: MotorParams, plan: RestToRest, t: np.ndarray) -> Callable[[], tuple]:
    """The C work of (a) alone: one batch_plan_flat call into buffers allocated once."""
    ffi, lib = core.ffi, core.lib
    m, p = core.motor_struct(motor), core.plan_struct(plan)
    tv, flag = np.ascontiguousarray(t), np.empty((t.size, 6))
    x, v = np.empty((t.size, 4)), np.empty((t.size, 2))
    t_in, flag_out = ffi.from_buffer("double[]", tv), ffi.from_buffer("double[]", flag, require_writable=True)
    x_out = ffi.from_buffer("double[]", x, require_writable=True)
    v_out = ffi.from_buffer("double[]", v, require_writable=True)

    def run() -> tuple:
        lib.batch_plan_flat(p, m, t_in, t.size, 0.0, flag_out, x_out, v_out)
        return x.T, v.T

    return run


def _state_differences(label: str, x, v, x_ref, v_ref) -> list[tuple[str, float, str]]:
    return [(f"{label}: max |theta diff|", float(np.abs(x[3] - x_ref[3]).max()), " rad"),
            (f"{label}: max |omega diff|", float(np.abs(x[2] - x_ref[2]).max()), " rad/s"),
            (f"{label}: max |current diff|", float(np.abs(x[:2] - x_ref[:2]).max()), " A"),
            (f"{label}: max |voltage diff|", float(np.abs(v - v_ref).max()), " V")]


# -------------------------------------------------------------------------------------------- (b) closed loop

def closed_loop_system(motor: MotorParams, controller, load_torque: float = 0.0):
    """The continuous closed loop (plant + the Python reference law, ideal measurement) as a python-control
    ``NonlinearIOSystem`` with no inputs and the state as output."""
    import control

    def updfcn(t, x, u, params=None):
        acc = (torque(x, motor) - motor.B * x[2] - load_torque) / motor.J
        return rhs(t, x, controller.voltages(t, x, acc), motor, load_torque)

    return control.NonlinearIOSystem(updfcn, None, inputs=0, outputs=4, states=4, name="closed_loop")


#: rtol ladder for the equal-accuracy comparison of (b), loosest first; atol = rtol / 100 on every rung.
RTOL_LADDER = (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)


def loosest_tolerance(run: Callable[[float], Any], error: Callable[[Any], float], bound: float,
                      ladder: tuple[float, ...] = RTOL_LADDER) -> tuple[float, float, Any]:
    """The loosest rtol of ``ladder`` (loosest first) whose run has ``error(run(rtol)) <= bound``: returns
    ``(rtol, error, result)``; raises ValueError when no rung is accurate enough."""
    for rtol in ladder:
        result = run(rtol)
        err = error(result)
        if err <= bound:
            return rtol, err, result
    raise ValueError(f"no rtol in {ladder} keeps the error within {bound:g} (last: {err:.3g})")


def bench_closed_loop(repeat: int = 5, dt_out: float = 1e-5, rtol: float = 1e-10, bound: float = 1e-8,
                      min_time: float = 0.02, ladder: tuple[float, ...] = RTOL_LADDER) -> Report:
    """(b) Fig. 1's 60 ms closed loop at equal accuracy. Starting on the plan, the ideal-measurement loop keeps
    s1 = s2 = 0, so the exact solution is the plan itself and every engine's error is its distance to theta*(t).

    Each engine runs at the loosest rtol of ``ladder`` (atol = rtol / 100) that keeps max |theta - theta*|
    within ``bound``; the baseline is scipy's LSODA at ``rtol`` (the issue's 1e-10), and LSODA at its own
    loosest passing rtol is shown beside it.
    """
    import control

    sc = PAPER_SCENARIOS["fig1"]
    motor, plan, ctrl = sc.motor, sc.plan, sc.controller()
    T = np.linspace(0.0, sc.t_end, round(sc.t_end / dt_out) + 1)
    theta_exact = plan.flag(T).theta
    x0 = plan.x0(motor.Nr)
    system = closed_loop_system(motor, ctrl)

    def theta_error(res) -> float:
        t, theta = (res.t, res.theta) if hasattr(res, "theta") else (res.time, res.states[3])
        return float(np.abs(theta - plan.flag(t).theta).max())

    engines: dict[str, Callable[[float], Callable[[], Any]]] = {
        "scipy LSODA": lambda r: lambda: simulate(motor, plan, ctrl, engine="scipy", method="LSODA", rtol=r,
                                                  atol=r / 100, dt_out=dt_out, t_end=sc.t_end),
        "python-control LSODA": lambda r: lambda: control.input_output_response(
            system, T, 0, x0, solve_ivp_method="LSODA", solve_ivp_kwargs=dict(rtol=r, atol=r / 100)),
    }
    core = _core_module()
    if core is not None:
        engines["C engine end to end"] = lambda r: lambda: simulate(motor, plan, ctrl, engine="c", rtol=r,
                                                                    atol=r / 100, dt_out=dt_out, t_end=sc.t_end)
    baseline = f"scipy LSODA, rtol {rtol:g} (baseline)"
    cases: dict[str, Callable[[], Any]] = {baseline: engines["scipy LSODA"](rtol)}
    checks, targets, chosen = [], [], {}
    for name, make in engines.items():
        r, err, _ = loosest_tolerance(lambda r: make(r)(), theta_error, bound, ladder)
        chosen[name] = r
        cases[f"{name}, rtol {r:g}"] = make(r)
        checks.append((f"{name}: loosest rtol with max |theta - theta*| <= {bound:g}: rtol {r:g}, error", err, " rad"))
    if core is not None:
        r = chosen["C engine end to end"]
        cases[f"C run loop alone, rtol {r:g}"] = lambda: core.run_continuous(ctrl, motor, 0.0, x0, T, rtol=r,
                                                                             atol=r / 100)
        cases[f"C engine end to end, rtol {rtol:g}"] = engines["C engine end to end"](rtol)
    times, results = race(cases, repeat, min_time)
    for name, res in results.items():
        if not name.startswith("C run loop"):
            targets.append(Target(f"{name}: theta error", theta_error(res), bound, False, " rad"))
        else:
            X, _ = res
            targets.append(Target(f"{name}: theta error", float(np.abs(X[3] - theta_exact).max()), bound, False,
                                  " rad"))
    notes = [f"atol = rtol / 100 on every rung of {ladder}; {T.size} output samples, 0 .. {sc.t_end:g} s; "
             f"error = max |theta - theta*(t)| over the samples (the exact closed-loop angle)"]
    if core is not None:
        e2e, loop = f"C engine end to end, rtol {chosen['C engine end to end']:g}", \
            f"C run loop alone, rtol {chosen['C engine end to end']:g}"
        own = f"scipy LSODA, rtol {chosen['scipy LSODA']:g}"
        targets.insert(0, Target("speed-up of the C engine (end to end, equal accuracy) vs LSODA at rtol "
                                 f"{rtol:g}", times[baseline] / times[e2e], 100, True, "x"))
        targets.insert(1, Target("speed-up of the C run loop alone vs LSODA at rtol "
                                 f"{rtol:g}", times[baseline] / times[loop], 100, True, "x"))
        notes.append(f"against LSODA at its own loosest passing rtol: C end to end {times[own] / times[e2e]:.1f}x, "
                     f"C run loop {times[own] / times[loop]:.1f}x")
    else:
        notes.append("the C engine is not built: scipy and python-control only")
    return Report("b", "the paper's 60 ms closed loop (Fig. 1) at equal accuracy", "run", times, baseline, checks,
                  targets, notes)


# ------------------------------------------------------------------------------------------- (c) one step

def step_inputs(n: int = 1024, seed: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times over the 60 ms horizon and measurements off the paper's plan by a few percent (as in
    benchmarks/smc_step_bench.c): ``t (n,)``, states ``x (4, n)``, accelerations ``(n,)``."""
    motor, plan = MotorParams.preset("paper"), PAPER_PLAN
    rng = np.random.default_rng(seed)
    t = 0.06 * (np.arange(n) + 0.5) / n
    flag = plan.flag(t)
    x, _ = flat_to_state(flag, motor)
    x = x + rng.uniform(-1, 1, (4, n)) * np.array([[0.02], [0.02], [0.5], [1e-3]])
    return t, x, flag.ddtheta + 50 * rng.uniform(-1, 1, n)


def build_step_driver(directory: Path) -> Optional[Path]:
    """Compile benchmarks/smc_step_bench.c with csrc/*.c as the binding is compiled (-std=c99 -O2); None
    without a C compiler or outside a source checkout."""
    cc = shutil.which(os.environ.get("CC", "cc"))
    source = ROOT / "benchmarks" / "smc_step_bench.c"
    if cc is None or not source.exists():
        return None
    exe = directory / "smc_step_bench"
    subprocess.run([cc, "-std=c99", "-O2", f"-I{ROOT / 'csrc'}", *map(str, sorted((ROOT / "csrc").glob("*.c"))),
                    str(source), "-lm", "-o", str(exe)], check=True, capture_output=True)
    return exe


def callgrind_instructions(exe: Path, calls: int, directory: Path) -> Optional[float]:
    """Instructions per smc_step call (callees included) counted by valgrind's callgrind; None without valgrind."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        return None
    out = subprocess.run([valgrind, "--tool=callgrind", f"--callgrind-out-file={directory / 'callgrind.out'}",
                          "--toggle-collect=smc_step", str(exe), str(calls), "1"],
                         check=True, capture_output=True, text=True)
    collected = re.search(r"Collected\s*:\s*(\d+)", out.stderr)
    return int(collected.group(1)) / calls if collected else None


def bench_step(repeat: int = 9, calls: int = 200_000, callgrind_calls: int = 10_000, n: int = 1024,
               min_time: float = 0.02) -> Report:
    """(c) One smc_step: the C driver's ns per call and callgrind's instructions per call, beside the same
    law through the binding (per sample of an array) and the Python reference (per call, and vectorized)."""
    sc = PAPER_SCENARIOS["fig1"]
    ctrl = sc.controller()
    t, x, acc = step_inputs(n)
    y = np.vstack([x, acc])
    reference = "Python FlatnessSMC.step (one call)"
    cases: dict[str, Callable[[], Any]] = {reference: lambda: ctrl.step(None, y[:, n // 2], t[n // 2])}
    per = {f"NumPy FlatnessSMC.voltages ({n} samples)": n}
    cases[f"NumPy FlatnessSMC.voltages ({n} samples)"] = lambda: ctrl.voltages(t, x, acc)
    core = _core_module()
    if core is not None:
        name = f"C smc_step through the binding ({n} samples)"
        cases[name], per[name] = (lambda: core.smc_voltages(ctrl, t, x, acc)), n
    times, results = race(cases, repeat, min_time, per)
    checks, targets, notes = [], [], []
    if core is not None:
        v_c, status = results[f"C smc_step through the binding ({n} samples)"]
        checks.append(("max |v_C - v_NumPy| on the inputs", float(np.abs(v_c - results[
            f"NumPy FlatnessSMC.voltages ({n} samples)"]).max()), " V"))
        checks.append(("steps with a status bit set", float(np.count_nonzero(status)), ""))
    with tempfile.TemporaryDirectory() as tmp:
        exe = build_step_driver(Path(tmp))
        if exe is None:
            notes.append("no C compiler or no benchmarks/ (not a source checkout): the C driver is skipped")
        else:
            out = subprocess.run([str(exe), str(calls), str(repeat)], check=True, capture_output=True, text=True)
            fields = dict(line.split(" ", 1) for line in out.stdout.splitlines())
            ns = float(fields["ns_per_call"].split()[0])
            times["C driver: smc_step loop (-O2)"] = ns * 1e-9
            checks.append(("C driver: steps with a status bit set (OR of bits)", float(fields["status_or"]), ""))
            targets.append(Target("C driver: time per smc_step", ns, 100, False, " ns"))
            ir = callgrind_instructions(exe, callgrind_calls, Path(tmp))
            if ir is None:
                notes.append("valgrind not found: no instruction count")
            else:
                checks.append((f"callgrind: instructions per smc_step ({callgrind_calls} calls, libm included)",
                               ir, ""))
                targets.append(Target("callgrind: instructions per smc_step", ir, 400, False, ""))
    return Report("c", "one controller step (smc_step), perturbed inputs over the 60 ms move", "step", times,
                  reference, checks, targets, notes)


# ----------------------------------------------------------------------------------------------- (d) batch

def bench_batch(repeat: int = 3, runs: int = 200, control_period: float = 5e-5, substeps: int = 10,
                workers: Optional[int] = None, min_time: float = 0.0) -> Report:
    """(d) Sampled closed-loop runs of 60 ms (controller every ``control_period``, voltage held, plant by RK4
    substeps) per second, each run under its own load torque in [0, 1e-5] N m: the public batch API
    :func:`flatstep.run_batch` on its C batch fast path (one C call per chunk, summaries in C, threads) and on
    its per-run path (``engine="c"`` given: ``simulate`` + ``SimResult.summary`` per run, processes), each on one
    and on ``workers`` workers (default: every core), beside the binding's ``run_sampled`` (one C call per run;
    cffi releases the GIL, so threads run on separate cores) on one and on ``workers`` threads.
    """
    from .batch import run_batch, scenario_grid

    core = _core_module()
    if core is None:
        raise RuntimeError("benchmark (d) needs the C binding (flatstep._core); install flatstep with its C core")
    sc = replace(PAPER_SCENARIOS["fig1"], control_period=control_period, substeps=substeps)
    motor, plan, ctrl = sc.motor, sc.plan, sc.controller()
    workers = workers or os.cpu_count() or 1
    periods = math.ceil(sc.t_end / control_period - 1e-9)
    loads = [float(load) for load in np.linspace(0.0, 1e-5, runs)]
    scenarios = scenario_grid(sc, load_torque=loads)
    x0 = plan.x0(motor.Nr)

    def one(load: float):
        return core.run_sampled(ctrl, motor, load, x0, 0.0, periods, Ts=control_period, substeps=substeps)

    fast1, fast_n = "run_batch, C batch path, 1 worker", f"run_batch, C batch path, {workers} threads"
    slow1, slow_n = "run_batch, per-run path, 1 worker", f"run_batch, per-run path, {workers} processes"
    raw1, raw_n = "binding run_sampled, 1 thread", f"binding run_sampled, {workers} threads"
    with ThreadPoolExecutor(workers) as pool:
        cases = {slow1: lambda: run_batch(scenarios, workers=1, progress=False, engine="c"),
                 slow_n: lambda: run_batch(scenarios, workers=workers, progress=False, engine="c"),
                 fast1: lambda: run_batch(scenarios, workers=1, progress=False),
                 fast_n: lambda: run_batch(scenarios, workers=workers, progress=False),
                 raw1: lambda: [one(load) for load in loads],
                 raw_n: lambda: list(pool.map(one, loads))}
        times, results = race(cases, repeat, min_time, per={name: runs for name in cases})
    rows, slow_rows, raw = results[fast_n], results[slow_n], results[raw_n]
    errors = [row["error"] for row in rows if row["error"]]
    checks = [("runs that failed", float(len(errors)), ""),
              ("rows of the C batch path that differ from the per-run path's",
               float(sum(a != b for a, b in zip(rows, slow_rows))), ""),
              ("max |theta_final(run_batch) - theta_final(binding)| over the runs",
               float(max(abs(row["theta_final"] - X[3, -1]) for row, (X, _, _) in zip(rows, raw))), " rad"),
              ("no-load run: |theta(60 ms) - theta2| (sampled at this period)", abs(raw[0][0][3, -1] - plan.theta2),
               " rad"),
              (f"speed-up of {workers} threads over 1 (C batch path)", times[fast1] / times[fast_n], "x"),
              (f"speed-up of {workers} processes over 1 (per-run path)", times[slow1] / times[slow_n], "x"),
              (f"speed-up of {workers} threads over 1 (binding)", times[raw1] / times[raw_n], "x")]
    targets = [Target(f"runs per second, {fast_n}", 1 / times[fast_n], 1000, True, ""),
               Target(f"runs per second, {slow_n}", 1 / times[slow_n], 1000, True, ""),
               Target(f"runs per second, {raw_n}", 1 / times[raw_n], 1000, True, "")]
    notes = [f"{runs} runs per batch (pool start-up included), {periods} control periods of "
             f"{control_period * 1e6:g} us, {substeps} RK4 substeps each; runs/s: "
             + ", ".join(f"{name} {1 / t:.0f}" for name, t in times.items()),
             "the sampled loop with the paper's law and gains does not hold Fig. 1's move at this rate: see "
             "docs/benchmarks.md (not a cost of the engine: a Python ZOH + RK4 loop gives the same angle)"]
    if errors:
        notes.append(f"first failure: {errors[0]}")
    return Report("d", "batch throughput: 60 ms closed-loop runs, sampled control", "run", times, slow1,
                  checks, targets, notes)


# ------------------------------------------------------------------------------------------------- entry

BENCHMARKS: dict[str, Callable[..., Report]] = {"a": bench_plan, "b": bench_closed_loop, "c": bench_step,
                                                 "d": bench_batch}


def main(which: str = "a,b,c,d", repeat: Optional[int] = None) -> int:
    """Run the chosen benchmarks, print each report; return 0 (targets missed are reported, not errors)."""
    keys = [k.strip() for k in which.split(",") if k.strip()]
    unknown = [k for k in keys if k not in BENCHMARKS]
    if unknown or not keys:
        raise ValueError(f"--which {which!r}: unknown benchmark(s) {unknown}; choose from {','.join(WHICH)}")
    try:
        import control  # noqa: F401
    except ImportError:
        if {"a", "b"} & set(keys):
            raise ValueError("benchmarks a and b compare with python-control: pip install 'flatstep[bench]'")
    print(f"flatstep bench: source {_revision()}, {os.cpu_count()} cores, load average {_load()} at start; "
          f"medians of {repeat or 'the default number of'} rounds; the ratios are the figures to quote\n")
    for key in keys:
        report = BENCHMARKS[key](**({} if repeat is None else {"repeat": repeat}))
        print(report.format(), flush=True)
        print()
    print(f"load average {_load()} at the end (a busy machine inflates times and deflates parallel speed-ups)")
    return 0


def _load() -> str:
    return f"{os.getloadavg()[0]:.2f}" if hasattr(os, "getloadavg") else "unknown"


def _revision() -> str:
    """The git revision of the checkout (``-dirty`` with uncommitted changes), or 'installed package'."""
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"], capture_output=True,
                             text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return "installed package"
    return out.stdout.strip() if out.returncode == 0 else "installed package"
