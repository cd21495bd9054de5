"""Figures: the paper's panels for one closed-loop run."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..engine.result import SimResult  # noqa: E402
from ..plan.protocol import Plan

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: (series, reference or None, label) for each panel, in the paper's order.
PANELS = (
    ("ia", "ia_ref", "$i_a$ [A]"),
    ("ib", "ib_ref", "$i_b$ [A]"),
    ("omega", "omega_ref", r"$\omega$ [rad/s]"),
    ("theta", "theta_ref", r"$\theta$, $\theta^*$ [rad]"),
    ("va", "va_ref", "$v_a$ [V]"),
    ("vb", "vb_ref", "$v_b$ [V]"),
    ("theta_error", None, r"$\theta - \theta^*$ [rad]"),
    ("rho_error", None, r"$\rho - \rho^*$ [A]"),
)


def _finish(fig: Figure, title: str, path: str | Path | None) -> Figure:
    """Title the figure and, when a path is given, write it (PNG, 150 dpi) and close it."""
    if title:
        fig.suptitle(title)
    if path is not None:
        fig.savefig(path, dpi=150)
        plt.close(fig)
    return fig


def _round_off(result: SimResult, name: str) -> float | None:
    """The solver's error tolerance on ``name`` (atol + rtol max|signal|) when the run's error stays within 10x it.

    ``None`` for a sampled run, or when the error is larger: then it is a real tracking error. Within the
    tolerance, a continuous run's error is the integration's round-off (the closed loop starts on its plan), and
    its sample-to-sample jitter is not chattering.
    """
    rtol, atol = result.meta.get("rtol"), result.meta.get("atol")
    if rtol is None or atol is None:
        return None
    signal = np.abs(result.theta if name == "theta_error" else result.rho)
    tol = float(atol + rtol * np.max(signal))
    return tol if float(np.max(np.abs(getattr(result, name)))) <= 10 * tol else None


def _round_off_panel(ax: Axes, result: SimResult, name: str, label: str, tol: float) -> None:
    """Draw an error that is round-off in units of a power of ten, inside the band of the solver's tolerance."""
    err = getattr(result, name)
    scale = 10.0 ** np.floor(np.log10(max(float(np.max(np.abs(err))), tol)))
    unit = label[label.index("[") + 1:label.index("]")]
    ax.axhspan(-tol / scale, tol / scale, color="tab:green", alpha=0.15, lw=0,
               label=f"solver tolerance (rtol {result.meta['rtol']:g}, atol {result.meta['atol']:g})")
    ax.plot(result.t, err / scale, lw=0.6, label="closed loop")
    ax.set_ylabel(f"{label[:label.index('[')]}[{scale:.0e} {unit}]")
    peak = float(np.max(np.abs(err)))
    ax.set_ylim(-1.6 * max(tol, peak) / scale, 1.6 * max(tol, peak) / scale)   # the band and the peak, room for notes
    where = "within the solver's tolerance" if peak <= tol else f"{peak / tol:.2g}x the solver's tolerance"
    ax.text(0.02, 0.96, f"integration round-off, not chattering:\n|error| <= {peak:.2g} {unit}, {where}",
            transform=ax.transAxes, va="top", fontsize=7, bbox=dict(boxstyle="round", fc="white", ec="0.7"))
    ax.legend(loc="lower right", fontsize=7)


def plot_run(result: SimResult, title: str = "", path: str | Path | None = None) -> Figure:
    """Plot a run in the paper's panels (solid: closed loop, dashed: plan / feedforward).

    An error panel whose error is within the continuous solver's tolerance (:func:`_round_off`) is drawn as
    round-off: scaled, inside the tolerance band, and said to be round-off. Returns the figure; writes it to
    ``path`` (PNG, 150 dpi) when given.
    """
    series = result.series()
    fig, axes = plt.subplots(4, 2, figsize=(10, 10), sharex=True, constrained_layout=True)
    for ax, (name, ref, label) in zip(axes.flat, PANELS, strict=True):  # one panel each
        ax.grid(True, alpha=0.3)
        tol = _round_off(result, name) if ref is None else None
        if tol is not None:
            _round_off_panel(ax, result, name, label, tol)
            continue
        ax.plot(result.t, series[name], lw=1.4, label="closed loop")
        if ref is not None:
            ax.plot(result.t, series[ref], "--", lw=1.0, color="k", label="plan / feedforward")
        ax.set_ylabel(label)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    axes[0, 0].legend(loc="best", fontsize=8)
    return _finish(fig, title, path)


def count_lines(ax: Axes) -> None:
    """Lines at +-1 encoder count (the target during the move) and +-0.5 count (at rest), labelled."""
    for y, ls, what in ((1.0, ":", "+-1 count: target during the move"), (0.5, "--", "+-0.5 count: target at rest")):
        ax.axhline(y, color="k", ls=ls, lw=0.8, label=what)
        ax.axhline(-y, color="k", ls=ls, lw=0.8)


def plot_traces(ax: Axes, rows: list[dict[str, Any]], scale: float, plan: Plan, lw: float = 0.7) -> None:
    """Draw the tracking-error trace of every successful batch row on ``ax``, with the move shaded.

    The rows' ``series_theta_error`` against ``series_t``, divided by ``scale``.
    """
    for row in rows:
        if row["error"] is None:
            ax.plot(row["series_t"], np.asarray(row["series_theta_error"]) / scale, lw=lw, alpha=0.7)
    ax.axvspan(plan.t0, plan.tf, color="0.92", zorder=0)


def plot_robustness(study: dict[str, Any], count: float | None, plan: Plan, title: str = "",
                    path: str | Path | None = None) -> Figure:
    """Tracking-error traces of every plant of a robustness study, one panel per gain set.

    With an encoder, the errors are in counts, with the targets' lines (:func:`count_lines`); each panel's title
    counts the runs that were ok, lost their move or faulted.
    """
    sets = study["sets"]
    fig, axes = plt.subplots(len(sets), 1, figsize=(9, 3.6 * len(sets)), constrained_layout=True, squeeze=False)
    scale, unit = (count, "counts") if count else (1.0, "rad")
    for ax, (label, s) in zip(axes[:, 0], sets.items(), strict=True):  # one panel per gain set
        plot_traces(ax, s["rows"], scale, plan)
        if count:
            count_lines(ax)
            ax.legend(loc="upper left", fontsize=7)
        w = s.get("worst_counts", s["worst_rad"])
        st = s["statuses"]
        ax.set_title(f"{label}: {st['ok']}/{s['runs']} ok, {st['lost']} lost the move, {st['fault']} faulted; worst "
                     f"|error| {w.get('move', np.nan):.3g} {unit} in the move, {w.get('rest', np.nan):.3g} at rest",
                     fontsize=10)
        ax.set_ylabel(rf"$\theta - \theta^*$ [{unit}]")
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("t [s] (shaded: the move)")
    return _finish(fig, title, path)
