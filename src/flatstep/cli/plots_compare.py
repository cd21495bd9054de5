"""Figures of a controller comparison: overlaid runs on one plant, and every plant of a robustness study."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..engine.result import SimResult
from ..plan.protocol import Plan
from .plots import _finish, count_lines, plot_traces, plt

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def _clip_to_move(ax: Axes, results: dict[str, SimResult], name: str, plan: Plan, unit: str) -> None:
    """Set the y axis to the range of ``name`` from the move's start on; mark what it cuts off before.

    A start-up transient (a controller pulling the current to its own set-point in the first periods) would
    otherwise set the axis and flatten the move.
    """
    lo, hi, spike = np.inf, -np.inf, (0.0, 0.0)
    for r in results.values():
        y, during = getattr(r, name), r.t >= plan.t0
        lo, hi = min(lo, float(np.min(y[during]))), max(hi, float(np.max(y[during])))
        early = np.flatnonzero(~during)
        if early.size and np.max(np.abs(y[early])) > abs(spike[1]):
            k = early[np.argmax(np.abs(y[early]))]
            spike = (float(r.t[k]), float(y[k]))
    pad = 0.08 * max(hi - lo, 1e-12)
    lo, hi = lo - pad, hi + pad
    if not lo <= spike[1] <= hi:
        ax.set_ylim(lo, hi)
        top = spike[1] > hi
        ax.annotate(f"start-up spike to {spike[1]:.3g} {unit} at t = {spike[0] * 1e3:.2g} ms (clipped)",
                    xy=(spike[0], hi if top else lo), xytext=(0.03, 0.85 if top else 0.12),
                    textcoords="axes fraction", fontsize=7, arrowprops=dict(arrowstyle="->", lw=0.7),
                    bbox=dict(boxstyle="round", fc="white", ec="0.7"))


def plot_overlay(results: dict[str, SimResult], plan: Plan, count: float | None = None, title: str = "",
                 path: str | Path | None = None) -> Figure:
    """Overlay the controllers' runs; shaded: the move.

    The panels are the tracking error (whole, and zoomed to +-5 counts, with the targets' lines, or to 3x the
    smallest error), the current norm and the phase voltage va; the last two are scaled to the move, a start-up
    spike marked as clipped (:func:`_clip_to_move`).
    """
    fig, axes = plt.subplots(4, 1, figsize=(11, 11), sharex=True, constrained_layout=True)
    scale, unit = (count, "counts") if count else (1.0, "rad")
    for i, (label, r) in enumerate(results.items()):
        ls = ("-", "--", ":")[i // 10 % 3]   # the colour cycle has 10 colours
        for ax in axes[:2]:
            ax.plot(r.t, r.theta_error / scale, ls=ls, lw=1.1, label=label)
        axes[2].plot(r.t, r.rho, ls=ls, lw=1.1, label=label)
        axes[3].plot(r.t, r.va, ls=ls, lw=0.9, label=label)
    lim = 5.0 if count else 3 * min(max(np.max(np.abs(r.theta_error)), 1e-12) for r in results.values())
    axes[1].set_ylim(-lim, lim)
    if count:
        count_lines(axes[1])
        handles = [h for h in axes[1].get_lines() if h.get_label().startswith("+-")]
        axes[1].legend(handles=handles, loc="upper left", fontsize=7)
    _clip_to_move(axes[2], results, "rho", plan, "A")
    _clip_to_move(axes[3], results, "va", plan, "V")
    labels = (rf"$\theta - \theta^*$ [{unit}]", f"zoom [{unit}]", r"$\rho = |i|$ [A]", "$v_a$ [V]")
    for ax, label in zip(axes, labels, strict=True):  # one label per panel
        ax.axvspan(plan.t0, plan.tf, color="0.92", zorder=0)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[3].set_xlabel("t [s] (shaded: the move)")
    axes[0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return _finish(fig, title, path)


def plot_plants(study: dict[str, dict[str, Any]], labels: dict[str, str], plan: Plan,
                count: float | None = None, title: str = "", path: str | Path | None = None) -> Figure:
    """One panel per controller: the tracking error on every plant of a robustness study.

    The study is :func:`flatstep.studies.compare.compare_worst`'s; each panel's title gives the worst move error.
    """
    fig, axes = plt.subplots(len(study), 1, figsize=(9, 2.8 * len(study)), sharex=True, constrained_layout=True,
                             squeeze=False)
    scale, unit = (count, "counts") if count else (1.0, "rad")
    for ax, (kind, s) in zip(axes[:, 0], study.items(), strict=True):  # one panel per controller
        plot_traces(ax, s["rows"], scale, plan, lw=0.6)
        if count:
            count_lines(ax)
        worst = s["worst"].get("move_max", np.nan) if s["worst"] else np.nan
        st = s["statuses"]
        ax.set_title(f"{labels.get(kind, kind)}: {st['ok']}/{s['runs']} runs ok, {st['lost']} lost their move, "
                     f"{st['fault']} faulted" + (f", {s['failed']} without a result" if s["failed"] else "")
                     + f"; worst max error during the move {worst / scale:.3g} {unit}", fontsize=10)
        ax.set_ylabel(rf"$\theta - \theta^*$ [{unit}]")
        ax.grid(True, alpha=0.3)
    if count:
        axes[0, 0].legend(loc="upper left", fontsize=7)
    axes[-1, 0].set_xlabel("t [s] (shaded: the move)")
    return _finish(fig, title, path)
