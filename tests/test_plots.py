"""Figures: round-off drawn as round-off, the targets' lines labelled, a start-up spike clipped and marked."""
from types import SimpleNamespace

import numpy as np
import pytest

import flatstep as fs
from flatstep.cli.plots import plot_robustness, plot_run, plt
from flatstep.cli.plots_compare import plot_overlay

COUNT = 2 * np.pi / 16384


@pytest.fixture(scope="module")
def paper_runs():
    return {name: sc.run() for name, sc in fs.PAPER_SCENARIOS.items()}


def texts(ax):
    return " ".join(t.get_text() for t in ax.texts)


def test_round_off_error_panels_say_so(paper_runs):
    fig = plot_run(paper_runs["fig1"])
    theta_ax, rho_ax = fig.axes[6], fig.axes[7]
    assert theta_ax.get_ylabel().endswith("[1e-12 rad]") and rho_ax.get_ylabel().endswith("[1e-11 A]")
    for ax in (theta_ax, rho_ax):
        assert "round-off, not chattering" in texts(ax)
        lo, hi = ax.get_ylim()
        peak = np.max(np.abs(ax.get_lines()[0].get_ydata()))
        assert peak < hi and -peak > lo and hi < 10   # the trace inside a window of a few units of its scale
    plt.close(fig)


def test_a_real_tracking_error_is_not_called_round_off(paper_runs):
    fig = plot_run(paper_runs["fig2"])   # the load leaves 4.6e-4 rad: an error, not round-off
    assert "round-off" not in texts(fig.axes[6]) and fig.axes[6].get_ylabel() == r"$\theta - \theta^*$ [rad]"
    assert np.max(np.abs(fig.axes[6].get_lines()[0].get_ydata())) == pytest.approx(4.5656e-4, rel=1e-3)
    plt.close(fig)


def run_like(va, theta_error_counts):
    """What plot_overlay reads of a result: t, theta_error, rho, va (a start-up spike where va says)."""
    t = np.linspace(0.0, 0.06, 601)
    return SimpleNamespace(t=t, theta_error=theta_error_counts * COUNT * np.sin(300 * t), rho=0.4 + 0 * t,
                           va=va(t))


def test_overlay_clips_the_start_up_spike():
    plan = fs.PAPER_PLAN
    runs = {"steady": run_like(lambda t: 3 + np.sin(200 * t), 0.4),
            "spiky": run_like(lambda t: np.where(t < 1e-3, -24.0, 2 * np.cos(300 * t)), 0.8)}
    fig = plot_overlay(runs, plan, count=COUNT)
    lo, hi = fig.axes[3].get_ylim()
    assert -2.5 < lo < -2.0 and 4.0 < hi < 4.5   # the range from t0 on (-2 .. 4 V), padded by 8 %
    assert "start-up spike to -24 V at t = 0 ms (clipped)" in texts(fig.axes[3])
    assert "clipped" not in texts(fig.axes[2])   # the current norm has no spike
    labels = [t.get_text() for t in fig.axes[1].get_legend().get_texts()]
    assert labels == ["+-1 count: target during the move", "+-0.5 count: target at rest"]
    plt.close(fig)


def test_robustness_figure_counts_lost_runs_and_labels_targets():
    t = np.linspace(0.0, 0.06, 61)
    rows = [{"error": None, "series_t": t, "series_theta_error": k * COUNT * np.sin(50 * t)} for k in (0.3, 900)]
    sets = {"designed": {"rows": rows[:1], "runs": 1, "statuses": {"ok": 1, "lost": 0, "fault": 0},
                         "worst_rad": {"move": 0.3 * COUNT}, "worst_counts": {"move": 0.3, "rest": 0.2}},
            "paper gains": {"rows": rows[1:], "runs": 1, "statuses": {"ok": 0, "lost": 1, "fault": 0},
                            "worst_rad": {"move": 900 * COUNT}, "worst_counts": {"move": 900.0, "rest": 850.0}}}
    fig = plot_robustness({"sets": sets}, COUNT, fs.PAPER_PLAN)
    assert fig.axes[0].get_title().startswith("designed: 1/1 ok, 0 lost")
    assert fig.axes[1].get_title().startswith("paper gains: 0/1 ok, 1 lost the move")
    assert "900 counts in the move, 850 at rest" in fig.axes[1].get_title()
    for ax in fig.axes:
        assert [x.get_text() for x in ax.get_legend().get_texts()] == ["+-1 count: target during the move",
                                                                       "+-0.5 count: target at rest"]
    plt.close(fig)
