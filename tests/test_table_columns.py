"""The command line's tables keep their columns aligned when a controller's name is long."""
from __future__ import annotations

from flatstep.cli.columns import name_width
from flatstep.cli.compare import COLUMNS, table
from flatstep.cli.tune import header, row
from flatstep.control.spec import LABELS
from flatstep.studies.tune import Evaluation

LONG = "cascade+feedforward+observer_torques+voltage_feedforward"
METRICS = {"move_max": 1.2e-3, "move_rms": 4e-4, "final": 1e-5, "settling_time": 0.012, "peak_voltage": 11.5,
           "peak_current": 0.9, "rms_current": 0.5, "copper_loss": 2e-3}


def test_name_width_fits_the_longest_name_and_keeps_the_short_tables_width():
    assert name_width(["smc", "cascade"], "controller", 22) == 22
    assert name_width([LONG], "law", 40) == len(LONG) + 2
    assert name_width([], "controller", 0) == len("controller") + 2


def test_compare_table_sizes_the_name_column_to_the_longest_label():
    """Every row's cells end where the header's heads end: the name column is as wide as the longest label."""
    label = LABELS.get(LONG, LONG)  # the name the table prints
    assert len(label) > 22  # longer than the table's old fixed column
    lines = table({"smc": METRICS, LONG: METRICS}, count=None).splitlines()
    head = lines[0][:lines[0].index("   [angles")]
    width = len(head) - 11 * len(COLUMNS)
    assert width == len(label) + 2
    assert lines[2].startswith(label + "  ")
    for line in lines[1:]:
        assert len(line) == len(head)  # every cell under its head
        assert line[width - 2:width] == "  " and line[width] == " "


def test_tuner_rows_line_up_with_their_header_at_any_width():
    ev = Evaluation({}, 1e-3, 11.0, 2e-3, 0.01, 0, 8)
    width = name_width([LONG], "law", 40)
    head, line = header(None, width), row(LONG, ev, None, width=width)
    assert line.startswith(LONG + "  ")
    assert width + 11 == head.index("worst move") + len("worst move")  # the first cell ends under its head
    assert line[width:width + 11].strip() == f"{1e-3:.3e}"
