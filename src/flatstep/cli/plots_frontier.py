"""The frontier figure of ``flatstep compare --tuned``: each law's best error against its voltage cap and copper."""
from __future__ import annotations

from pathlib import Path
from typing import Optional

from ..control.tuning import label
from ..studies.frontier import Frontier


def plot_frontier(frontiers: dict[str, Frontier], count: Optional[float], *, title: str, path: Path) -> None:
    """Two panels: worst-of-plants error against the peak-voltage cap, and against the copper loss of each point.

    One curve per controller type; errors in encoder counts (rad without an encoder).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, LogFormatter

    plain = FuncFormatter(lambda v, _: f"{v:.2g}")  # the errors span about a decade: plain numbers, not 1.9x10^0

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    scale = 1.0 / count if count else 1.0
    for kind, fr in frontiers.items():
        pts = [p for p in fr.points if p.best is not None]
        if not pts:
            continue
        err = [p.best.move_max * scale for p in pts if p.best is not None]
        line, = left.plot([p.cap for p in pts], err, "o-", label=label(kind))
        right.plot([p.best.copper * 1e3 for p in pts if p.best is not None], err, "o-", color=line.get_color())
    left.set_xlabel("peak-voltage cap [V]")
    left.set_ylabel(f"worst-of-plants max error during the move [{'counts' if count else 'rad'}]")
    right.set_xlabel("worst-of-plants copper loss from the move's start [mJ]")
    right.set_xscale("log")  # the laws' copper differs by orders of magnitude
    for ax in (left, right):
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    left.yaxis.set_major_formatter(plain)
    left.yaxis.set_minor_formatter(plain)
    right.xaxis.set_major_formatter(LogFormatter())  # plain numbers on the copper axis too
    right.xaxis.set_minor_formatter(LogFormatter(labelOnlyBase=False, minor_thresholds=(1.0, 0.4)))
    handles, labels = left.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=max(1, len(handles)), fontsize=8, frameon=False)
    fig.suptitle(title)
    fig.tight_layout(rect=(0.0, 0.06, 1.0, 1.0))  # room for the legend under the panels, clear of the points
    fig.savefig(path, dpi=110)
    plt.close(fig)
