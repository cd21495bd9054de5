"""Benchmarks (``flatstep bench``), one module each: side by side in one run, medians and ratios.

``flatstep bench [--which a,b,c,d] [--repeat N]`` (docs/benchmarks.md keeps every figure with its command):

a. planning + feedforward of the paper's move at 401 points: flatstep (C core, NumPy) against python-control's
   ``flatsys.point_to_point`` + ``traj.eval`` on the same flat system and the same trajectory;
b. the paper's 60 ms closed loop (Fig. 1) at equal accuracy: the C engine against scipy LSODA and python-control's
   ``input_output_response``, each checked against the exact solution;
c. one controller step: a C driver (ns per call; instructions per call by callgrind) against the binding and
   the Python reference;
d. batch throughput: 60 ms closed-loop runs per second at 20 kHz sampled control, one thread against all cores.

The yardsticks of the time-optimal planners (benchmarks/time_optimal_yardstick.py, docs/planning.md section 6)
live here too, imported by their own names: :mod:`.collocation` (the true minimum time by direct collocation,
CasADi + IPOPT), :mod:`.fair_baselines` (Ruckig with i_d = 0, a trapezoid with field weakening) and
:mod:`.drive_tracking` (a plan on the 20 kHz drive).

The machine may be shared: the cases of a benchmark take turns in every round, medians are quoted, and the
ratios measured in the same run are the figures that mean something. Clocks are read here, never in the library.
"""
from .batch import bench_batch
from .closed_loop import RTOL_LADDER, bench_closed_loop, closed_loop_system, loosest_tolerance
from .common import Report, Target, race
from .plan import bench_plan, control_point_to_point, psi_span_family, stepper_flat_system
from .run import BENCHMARKS, WHICH, main
from .step import bench_step, build_step_driver, callgrind_instructions, step_inputs

__all__ = ["BENCHMARKS", "RTOL_LADDER", "Report", "Target", "WHICH", "bench_batch", "bench_closed_loop", "bench_plan",
           "bench_step", "build_step_driver", "callgrind_instructions", "closed_loop_system", "control_point_to_point",
           "loosest_tolerance", "main", "psi_span_family", "race", "step_inputs", "stepper_flat_system"]
