"""(c) One controller step: a C driver against the binding and the Python reference.

The C driver gives ns per call, and instructions per call by callgrind.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np
from numpy.typing import NDArray

from ..control.smc import FlatnessSMC
from ..model.flat import flat_to_state
from ..model.motor import MotorParams
from ..plan.rest_to_rest import PAPER_PLAN
from ..studies.scenario import PAPER_SCENARIOS
from .common import ROOT, Report, Target, core_module, race


def step_inputs(n: int = 1024, seed: int = 1) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Times over the 60 ms horizon and measurements off the paper's plan by a few percent.

    As in benchmarks/smc_step_bench.c: ``t (n,)``, states ``x (4, n)``, accelerations ``(n,)``.
    """
    motor, plan = MotorParams.preset("paper"), PAPER_PLAN
    rng = np.random.default_rng(seed)
    t = 0.06 * (np.arange(n) + 0.5) / n
    flag = plan.flag(t)
    x, _ = flat_to_state(flag, motor)
    x = x + rng.uniform(-1, 1, (4, n)) * np.array([[0.02], [0.02], [0.5], [1e-3]])
    return t, x, flag.ddtheta + 50 * rng.uniform(-1, 1, n)


def build_step_driver(directory: Path) -> Optional[Path]:
    """Compile benchmarks/smc_step_bench.c with csrc/*.c as the binding is compiled (-std=c99 -O2).

    Returns the executable, or None without a C compiler or outside a source checkout.
    """
    cc = shutil.which(os.environ.get("CC", "cc"))
    source = ROOT / "benchmarks" / "smc_step_bench.c"
    if cc is None or not source.exists():
        return None
    exe = directory / "smc_step_bench"
    subprocess.run([cc, "-std=c99", "-O2", f"-I{ROOT / 'csrc'}", *map(str, sorted((ROOT / "csrc").glob("*.c"))),
                    str(source), "-lm", "-o", str(exe)], check=True, capture_output=True)
    return exe


def callgrind_instructions(exe: Path, calls: int, directory: Path, *args: str) -> Optional[float]:
    """Instructions per smc_step call (callees included) counted by valgrind's callgrind; None without valgrind.

    ``args`` go to the driver after CALLS and REPEAT (``"move"``: inputs inside the move only).
    """
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        return None
    out = subprocess.run([valgrind, "--tool=callgrind", f"--callgrind-out-file={directory / 'callgrind.out'}",
                          "--toggle-collect=smc_step", str(exe), str(calls), "1", *args],
                         check=True, capture_output=True, text=True)
    collected = re.search(r"Collected\s*:\s*(\d+)", out.stderr)
    return int(collected.group(1)) / calls if collected else None


def bench_step(repeat: int = 9, calls: int = 200_000, callgrind_calls: int = 10_000, n: int = 1024,
               min_time: float = 0.02) -> Report:
    """(c) One smc_step: the C driver's ns per call and callgrind's instructions per call.

    Beside them, the same law through the binding (per sample of an array) and the Python reference (per call,
    and vectorized).
    """
    sc = PAPER_SCENARIOS["fig1"]
    ctrl = FlatnessSMC(sc.motor, sc.plan, sc.gains, sc.measurement)  # sc.controller(), the paper's law
    t, x, acc = step_inputs(n)
    y = np.vstack([x, acc])
    reference = "Python FlatnessSMC.step (one call)"
    cases: dict[str, Callable[[], Any]] = {reference: lambda: ctrl.step(None, y[:, n // 2], t[n // 2])}
    per = {f"NumPy FlatnessSMC.voltages ({n} samples)": n}
    cases[f"NumPy FlatnessSMC.voltages ({n} samples)"] = lambda: ctrl.voltages(t, x, acc)
    core = core_module()
    if core is not None:
        name = f"C smc_step through the binding ({n} samples)"
        cases[name], per[name] = (lambda: core.smc_voltages(ctrl, t, x, acc)), n
    times, results = race(cases, repeat, min_time, per)
    checks: list[tuple[str, float, str]] = []
    targets: list[Target] = []
    notes: list[str] = []
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
            for label, args in (("", ()), (" inside the move", ("move",))):
                out = subprocess.run([str(exe), str(calls), str(repeat), *args], check=True, capture_output=True,
                                     text=True)
                fields = dict(line.split(" ", 1) for line in out.stdout.splitlines())
                ns = float(fields["ns_per_call"].split()[0])
                times[f"C driver: smc_step loop (-O2){label}"] = ns * 1e-9
                checks.append((f"C driver{label}: steps with a status bit set (OR of bits)",
                               float(fields["status_or"]), ""))
                ir = callgrind_instructions(exe, callgrind_calls, Path(tmp), *args)
                if ir is not None:
                    checks.append((f"callgrind{label}: instructions per smc_step ({callgrind_calls} calls, libm "
                                   "included)", ir, ""))
                if not label:
                    targets.append(Target("C driver: time per smc_step", ns, 100, False, " ns"))
                    if ir is None:
                        notes.append("valgrind not found: no instruction count")
                    else:
                        targets.append(Target("callgrind: instructions per smc_step", ir, 400, False, ""))
            notes.append("the target's inputs are spread over the 60 ms horizon (two thirds at rest, where the plan "
                         "is constant); 'inside the move' is the worst case, every input in (t0, tf)")
    return Report("c", "one controller step (smc_step), perturbed inputs over the 60 ms move", "step", times,
                  reference, checks, targets, notes)
