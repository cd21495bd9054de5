"""docs/errors.md states the ranges and limits that the code enforces (no drift between the two)."""
from pathlib import Path

from flatstep.validate import limits
from flatstep.validate.ranges import markdown_table

DOC = (Path(__file__).resolve().parent.parent / "docs" / "errors.md").read_text()


def test_the_ranges_table_is_the_codes():
    assert markdown_table() in DOC


def test_the_limits_are_the_codes():
    assert limits.MAX_STEPS == 100_000_000 and "| `MAX_STEPS` | 1e8" in DOC
    assert limits.MAX_STEPS_REFERENCE == 200_000 and "| `MAX_STEPS_REFERENCE` | 2e5" in DOC
    assert limits.MAX_RESULT_BYTES == 1 << 30 and "| `MAX_RESULT_BYTES` | 1 GiB" in DOC
    assert limits.BYTES_PER_SAMPLE == 256 and "(256)" in DOC
    assert limits.MIN_PERIODS_PER_MOVE == 10 and "at least 10 control periods" in DOC
    assert limits.MAX_PLAN_SAMPLES == 2_000_000 and "| `MAX_PLAN_SAMPLES` | 2e6" in DOC
    assert limits.MAX_OPTIMAL_MOVES == 1000 and "| `MAX_OPTIMAL_MOVES` | 1000" in DOC
    assert limits.MAX_STUDY_STEPS == 50_000_000 and "| `MAX_STUDY_STEPS` | 5e7" in DOC


def test_the_planning_limits_are_the_codes():
    """The planning API's limits are printed from the constants, and the ranges its checks use are in the table."""
    assert limits.plan_limits_markdown() in DOC
    assert "| `MAX_FLAG_BOUND` | 1e+30 |" in DOC and limits.MAX_FLAG_BOUND == 1e30
    assert "| `MAX_SMOOTHING_WIDTHS` | 8 |" in DOC and limits.MAX_SMOOTHING_WIDTHS == 8
    for name in ("speed", "velocity", "acceleration", "jerk", "torque_angle", "fraction"):
        assert f"| `{name}` |" in DOC
