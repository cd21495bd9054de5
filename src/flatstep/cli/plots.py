"""Figures: the paper's panels for one closed-loop run."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..engine.result import SimResult  # noqa: E402
from ..plan.rest_to_rest import RestToRest  # noqa: E402

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


def plot_run(result: SimResult, title: str = "", path: str | Path | None = None) -> Figure:
    """Plot a run in the paper's panels (solid: closed loop, dashed: plan / feedforward).

    Returns the figure; writes it to ``path`` (PNG, 150 dpi) when given.
    """
    series = result.series()
    fig, axes = plt.subplots(4, 2, figsize=(10, 10), sharex=True, constrained_layout=True)
    for ax, (name, ref, label) in zip(axes.flat, PANELS, strict=True):  # one panel each
        ax.plot(result.t, series[name], lw=1.4, label="closed loop")
        if ref is not None:
            ax.plot(result.t, series[ref], "--", lw=1.0, color="k", label="plan / feedforward")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    axes[0, 0].legend(loc="best", fontsize=8)
    return _finish(fig, title, path)


def plot_traces(ax: Axes, rows: list[dict[str, Any]], scale: float, plan: RestToRest, lw: float = 0.7) -> None:
    """Draw the tracking-error trace of every successful batch row on ``ax``, with the move shaded.

    The rows' ``series_theta_error`` against ``series_t``, divided by ``scale``.
    """
    for row in rows:
        if row["error"] is None:
            ax.plot(row["series_t"], np.asarray(row["series_theta_error"]) / scale, lw=lw, alpha=0.7)
    ax.axvspan(plan.t0, plan.tf, color="0.92", zorder=0)


def plot_robustness(study: dict[str, Any], count: float | None, plan: RestToRest, title: str = "",
                    path: str | Path | None = None) -> Figure:
    """Tracking-error traces of every plant of a robustness study, one panel per gain set.

    Dotted lines at +-1 count (the move target), dashed at +-0.5 count (the at-rest target).
    """
    sets = study["sets"]
    fig, axes = plt.subplots(len(sets), 1, figsize=(9, 3.6 * len(sets)), constrained_layout=True, squeeze=False)
    scale, unit = (count, "counts") if count else (1.0, "rad")
    for ax, (label, s) in zip(axes[:, 0], sets.items(), strict=True):  # one panel per gain set
        plot_traces(ax, s["rows"], scale, plan)
        if count:
            for y, ls in ((1, ":"), (-1, ":"), (0.5, "--"), (-0.5, "--")):
                ax.axhline(y, color="k", ls=ls, lw=0.8)
        w = s.get("worst_counts", s["worst_rad"])
        st = s["statuses"]
        ax.set_title(f"{label}: {st['ok']}/{s['runs']} runs ok, {st['lost']} lost their move, {st['fault']} faulted; "
                     f"worst move {w.get('move', np.nan):.3g}, rest {w.get('rest', np.nan):.3g} {unit}", fontsize=10)
        ax.set_ylabel(rf"$\theta - \theta^*$ [{unit}]")
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("t [s] (shaded: the move)")
    return _finish(fig, title, path)
