"""Whether a run is consistent and affordable, checked before anything runs.

Consistency: the run starts at ``t = 0``, so ``0 <= t0 < tf <= t_end`` (a horizon that ends before the move
would cut it short without a word), and a sampled controller needs a control period well below the move's
duration (at least :data:`MIN_PERIODS_PER_MOVE` periods over ``tf - t0``).

Resources: a run is refused up front, with the estimate and how to lower it, when it would

* return more than :data:`MAX_RESULT_BYTES` of time series (:data:`BYTES_PER_SAMPLE` per returned sample);
* take more than :data:`MAX_STEPS` plant integration steps on the C core (control periods x RK4 substeps, or x
  PWM segments in switched mode; about 10 s on one core of a 2020s PC) or :data:`MAX_STEPS_REFERENCE` on the
  readable Python reference loop, about 800x slower per step.

docs/errors.md lists these limits. They are module constants: a user who really needs a larger run may raise them
(``flatstep.validate.limits.MAX_STEPS = ...``), knowingly.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

from .checks import InputError

#: Fewest control periods a sampled controller gets over the move ``[t0, tf]``.
MIN_PERIODS_PER_MOVE = 10
#: Bytes of results per returned sample (about 22 float64 series and the engine's working arrays).
BYTES_PER_SAMPLE = 256
#: Largest result of one run [bytes] (1 GiB: about 4.2 million samples).
MAX_RESULT_BYTES = 1 << 30
#: Most plant integration steps of one run on the C core (about 85 ns each with the sliding controller: 10 s).
MAX_STEPS = 100_000_000
#: Most plant integration steps of one run on the Python reference loop (``engine="python"``, about 70 us each: 15 s).
MAX_STEPS_REFERENCE = 200_000
#: Most time samples of one move in the time-optimal planner (flatstep.plan.time_optimal; about 1 s of work).
MAX_PLAN_SAMPLES = 2_000_000
#: Most moves of one time-optimal waypoint sequence in a plan file (under 1 ms of planning each in C).
MAX_OPTIMAL_MOVES = 1000
#: Shortest move the time-optimal planner plans [rad] (far below any encoder's count; a shorter move is a hold).
MIN_MOVE_DISTANCE = 1e-7
#: Shortest and longest smoothing width a time-optimal plan may be given [s] (the defaults are 1/4 to 4 times L/R,
#: 0.1-50 ms for NEMA 14-23 motors).
MIN_SMOOTHING_WIDTH = 1e-6
MAX_SMOOTHING_WIDTH = 1.0
#: Most smoothing widths one time-optimal plan may try (csrc/time_optimal.h ``TO_MAX_WIDTHS``).
MAX_SMOOTHING_WIDTHS = 8
#: Largest bound a plan's segment table may put on its flat flag, in SI units: on every segment
#: :math:`h^{-k}\sum_j |c_j| (10 - j)!/(10 - j - k)!` for theta's derivatives k = 0..4 and rho's k = 0..1
#: (flatstep.plan.piecewise.PiecewisePlan). Far above any motor's angles, speeds and currents, far below where the
#: flag or the flat maps (products of it with L, Nr, J, Km) overflow to inf.
MAX_FLAG_BOUND = 1e30
#: Segments of one PWM period in switched mode (csrc/drive.h ``DRIVE_PWM_SEGMENTS``).
PWM_SEGMENTS = 9


@dataclass(frozen=True)
class RunEstimate:
    """What a run would cost: returned samples, result memory [bytes], plant integration steps, PWM periods."""

    samples: int
    result_bytes: int
    steps: int
    pwm_periods: int


def _fmt_bytes(n: float) -> str:
    """``n`` bytes in KiB, MiB, GiB, TiB or PiB."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024.0:
            return f"{n:.3g} {unit}"
        n /= 1024.0
    return f"{n:.3g} PiB"


def check_timing(t0: float, tf: float, t_end: float, control_period: Optional[float] = None) -> None:
    """Raise an :class:`InputError` unless ``0 <= t0 < tf <= t_end`` and the move spans enough control periods."""
    if t0 < 0.0:
        raise InputError("t0", t0, f"t0={t0!r} s is before the run starts (t = 0): the move must start at t0 >= 0")
    if not tf > t0:
        raise InputError("tf", tf, f"tf={tf!r} s must be greater than t0={t0!r} s")
    if t_end < tf:
        raise InputError("t_end", t_end, f"t_end={t_end!r} s ends before the move does (tf={tf!r} s): the run would "
                                         f"cut the move short; give t_end >= {tf!r} s")
    if control_period is not None and tf - t0 < MIN_PERIODS_PER_MOVE * control_period:
        raise InputError("control_period", control_period,
                         f"control_period={control_period!r} s is too long for a move of {tf - t0:.6g} s: a sampled "
                         f"controller needs at least {MIN_PERIODS_PER_MOVE} periods over the move; give a control "
                         f"rate of at least {MIN_PERIODS_PER_MOVE / (tf - t0):.6g} Hz or a longer move")


def estimate(t_end: float, *, control_period: Optional[float] = None, substeps: int = 1, pwm_per_period: int = 0,
             dt_out: Optional[float] = None, extra_samples: int = 0) -> RunEstimate:
    """The cost of a sampled run (``control_period``) or of a continuous one (``dt_out``) to ``t_end``."""
    if control_period is not None:
        periods = max(1.0, math.ceil(t_end / control_period - 1e-9))
        samples = periods + 1
        pwm = periods * pwm_per_period
        steps = pwm * PWM_SEGMENTS if pwm_per_period else periods * substeps
    else:
        samples = t_end / (dt_out or 1e-5) + 1 + extra_samples
        pwm, steps = 0, 0
    big = float(2**62)
    return RunEstimate(int(min(samples, big)), int(min(samples * BYTES_PER_SAMPLE, big)), int(min(steps, big)),
                       int(min(pwm, big)))


def check_resources(cost: RunEstimate, *, engine: str = "c", series: bool = True, what: str = "the run") -> None:
    """Raise an :class:`InputError` if a run of cost ``cost`` is above the limits of this module.

    ``series=False`` for runs that return summaries only (a batch's C path): their memory does not grow with the
    horizon.
    """
    if series and cost.result_bytes > MAX_RESULT_BYTES:
        raise InputError("t_end", cost.samples,
                         f"{what} would return {cost.samples:.4g} samples, about {_fmt_bytes(cost.result_bytes)} of "
                         f"results, above the limit of {_fmt_bytes(MAX_RESULT_BYTES)} (flatstep.validate.limits."
                         "MAX_RESULT_BYTES); shorten t_end, or lengthen the control period (sampled) or dt_out "
                         "(continuous)")
    limit = MAX_STEPS_REFERENCE if engine == "python" else MAX_STEPS
    if cost.steps > limit:
        how = ("lower f_pwm or the control rate, or shorten t_end" if cost.pwm_periods else
               "lower substeps or the control rate, or shorten t_end")
        name = "MAX_STEPS_REFERENCE" if engine == "python" else "MAX_STEPS"
        detail = f" ({cost.pwm_periods:.4g} PWM periods)" if cost.pwm_periods else ""
        raise InputError("substeps", cost.steps,
                         f"{what} would take {cost.steps:.4g} plant integration steps{detail} on engine={engine!r}, "
                         f"above the limit of {limit:.4g} (flatstep.validate.limits.{name}); {how}")


#: Most plant integration steps of one command-line study (compare, robustness) on the C core (about 20 s on 2
#: cores: a batch step with sensors, observer and summaries costs about 0.4 us of one core); larger studies go
#: through :func:`flatstep.run_batch` (docs/scaling.md).
MAX_STUDY_STEPS = 50_000_000


def check_study(runs: int, cost: RunEstimate, *, engine: str = "c", what: str = "the study") -> None:
    """Raise an :class:`InputError` if ``runs`` runs of cost ``cost`` exceed the study limit of ``engine``.

    On the C core the limit is :data:`MAX_STUDY_STEPS`; on the Python reference loop it is
    :data:`MAX_STEPS_REFERENCE`, for the whole study.
    """
    limit = MAX_STEPS_REFERENCE if engine == "python" else MAX_STUDY_STEPS
    total = runs * cost.steps
    if total > limit:
        name = "MAX_STEPS_REFERENCE" if engine == "python" else "MAX_STUDY_STEPS"
        raise InputError("samples", runs, f"{what} is {runs} runs of {cost.steps:.4g} plant integration steps "
                         f"({total:.4g} in all) on engine={engine!r}, above the limit of {limit:.4g} "
                         f"(flatstep.validate.limits.{name}); lower --samples, skip the study (--no-robustness), "
                         "use the C engine, or run it through flatstep.run_batch (docs/scaling.md)")


#: The planning API's limits, for docs/errors.md (:func:`plan_limits_markdown`): name, value, what counts.
PLAN_LIMITS = (
    ("MAX_OPTIMAL_MOVES", lambda: f"{MAX_OPTIMAL_MOVES}",
     "moves (waypoints less one) of one waypoint sequence: `time_optimal_sequence`, `plan_waypoints` (every "
     "family), a plan file; checked before any work"),
    ("MAX_PLAN_SAMPLES", lambda: f"{MAX_PLAN_SAMPLES:.0e}".replace("e+0", "e"),
     "time samples of one time-optimal move; also segments x `samples_per_segment` of `plan_margins` and "
     "`copper_loss`, and the samples `n` of `check_feasibility`"),
    ("MIN_MOVE_DISTANCE", lambda: f"{MIN_MOVE_DISTANCE:g} rad", "the shortest move `time_optimal` plans"),
    ("MIN_SMOOTHING_WIDTH, MAX_SMOOTHING_WIDTH", lambda: f"{MIN_SMOOTHING_WIDTH:g} to {MAX_SMOOTHING_WIDTH:g} s",
     "each smoothing width given to `time_optimal`"),
    ("MAX_SMOOTHING_WIDTHS", lambda: f"{MAX_SMOOTHING_WIDTHS}", "smoothing widths one `time_optimal` call tries"),
    ("MAX_FLAG_BOUND", lambda: f"{MAX_FLAG_BOUND:g}",
     "the bound a `PiecewisePlan`'s coefficients and breaks put on its flat flag (theta and 4 derivatives, rho "
     "and its rate, SI units): a larger table would make `flag()` overflow"),
)


def plan_limits_markdown() -> str:
    """The planning API's limits (:data:`PLAN_LIMITS`) as a Markdown table (docs/errors.md)."""
    rows = ["| limit | value | what counts |", "|---|---|---|"]
    rows += [f"| `{name}` | {value()} | {what} |" for name, value, what in PLAN_LIMITS]
    return "\n".join(rows)
