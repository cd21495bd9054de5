"""Figures of a controller comparison: overlaid runs on one plant, and every plant of a robustness study."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..engine.result import SimResult
from ..plan.rest_to_rest import RestToRest
from .plots import _finish, plot_traces, plt

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def plot_overlay(results: dict[str, SimResult], plan: RestToRest, count: float | None = None, title: str = "",
                 path: str | Path | None = None) -> Figure:
    """Overlay the controllers' runs; shaded: the move.

    The panels are the tracking error (whole, and zoomed to +-5 counts or to 3x the smallest error), the current
    norm and the phase voltage va.
    """
    fig, axes = plt.subplots(4, 1, figsize=(9, 11), sharex=True, constrained_layout=True)
    scale, unit = (count, "counts") if count else (1.0, "rad")
    for label, r in results.items():
        for ax in axes[:2]:
            ax.plot(r.t, r.theta_error / scale, lw=1.1, label=label)
        axes[2].plot(r.t, r.rho, lw=1.1, label=label)
        axes[3].plot(r.t, r.va, lw=0.9, label=label)
    lim = 5.0 if count else 3 * min(max(np.max(np.abs(r.theta_error)), 1e-12) for r in results.values())
    axes[1].set_ylim(-lim, lim)
    labels = (rf"$\theta - \theta^*$ [{unit}]", f"zoom [{unit}]", r"$\rho = |i|$ [A]", "$v_a$ [V]")
    for ax, label in zip(axes, labels, strict=True):  # one label per panel
        ax.axvspan(plan.t0, plan.tf, color="0.92", zorder=0)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[3].set_xlabel("t [s] (shaded: the move)")
    axes[0].legend(fontsize=8)
    return _finish(fig, title, path)


def plot_plants(study: dict[str, dict[str, Any]], labels: dict[str, str], plan: RestToRest,
                count: float | None = None, title: str = "", path: str | Path | None = None) -> Figure:
    """One panel per controller: the tracking error on every plant of a robustness study.

    The study is :func:`flatstep.studies.compare.compare_worst`'s; each panel's title gives the worst move error.
    """
    fig, axes = plt.subplots(len(study), 1, figsize=(9, 2.8 * len(study)), sharex=True, constrained_layout=True,
                             squeeze=False)
    scale, unit = (count, "counts") if count else (1.0, "rad")
    for ax, (kind, s) in zip(axes[:, 0], study.items(), strict=True):  # one panel per controller
        plot_traces(ax, s["rows"], scale, plan, lw=0.6)
        worst = s["worst"].get("move_max", np.nan) if s["worst"] else np.nan
        st = s["statuses"]
        ax.set_title(f"{labels.get(kind, kind)}: {st['ok']}/{s['runs']} runs ok, {st['lost']} lost their move, "
                     f"{st['fault']} faulted; worst max error during the move {worst / scale:.3g} {unit}", fontsize=10)
        ax.set_ylabel(rf"$\theta - \theta^*$ [{unit}]")
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("t [s] (shaded: the move)")
    return _finish(fig, title, path)
