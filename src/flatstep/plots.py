"""Figures: the paper's panels for one closed-loop run."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .result import SimResult  # noqa: E402

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


def plot_run(result: SimResult, title: str = "", path: str | Path | None = None):
    """Plot a run in the paper's panels (solid: closed loop, dashed: plan / feedforward).

    Returns the figure; writes it to ``path`` (PNG, 150 dpi) when given.
    """
    series = result.series()
    fig, axes = plt.subplots(4, 2, figsize=(10, 10), sharex=True, constrained_layout=True)
    for ax, (name, ref, label) in zip(axes.flat, PANELS):
        ax.plot(result.t, series[name], lw=1.4, label="closed loop")
        if ref is not None:
            ax.plot(result.t, series[ref], "--", lw=1.0, color="k", label="plan / feedforward")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    axes[0, 0].legend(loc="best", fontsize=8)
    if title:
        fig.suptitle(title)
    if path is not None:
        fig.savefig(path, dpi=150)
        plt.close(fig)
    return fig
