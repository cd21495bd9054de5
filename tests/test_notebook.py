"""examples/from-datasheet-to-move.ipynb runs top to bottom in a fresh kernel, and its numbers hold."""
import json
import re
import sys
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")
pytest.importorskip("control")

NOTEBOOK = Path(__file__).resolve().parent.parent / "examples" / "from-datasheet-to-move.ipynb"
KERNEL = "flatstep-test"


@pytest.fixture(scope="module")
def printed(tmp_path_factory):
    """Everything the notebook's code cells print, one string, after executing it on this Python."""
    # A kernel spec that names this interpreter, so that the notebook runs on the flatstep under test and not on
    # whatever a user-wide "python3" kernel points to.
    spec = tmp_path_factory.mktemp("jupyter")
    (spec / "kernels" / KERNEL).mkdir(parents=True)
    (spec / "kernels" / KERNEL / "kernel.json").write_text(json.dumps(
        {"argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
         "display_name": "flatstep test", "language": "python"}))
    mp = pytest.MonkeyPatch()
    mp.setenv("JUPYTER_PATH", str(spec))
    mp.setenv("MPLBACKEND", "Agg")
    try:
        nb = nbformat.read(NOTEBOOK, as_version=4)
        nbclient.NotebookClient(nb, timeout=120, kernel_name=KERNEL,
                                resources={"metadata": {"path": str(tmp_path_factory.mktemp("run"))}}).execute()
    finally:
        mp.undo()
    return "".join(out.get("text", "") for cell in nb.cells if cell.cell_type == "code" for out in cell.outputs
                   if out.output_type == "stream")


def number(printed, pattern):
    """The number after ``pattern`` in the notebook's output."""
    found = re.search(re.escape(pattern) + r"\s*([-+0-9.eE]+)", printed)
    assert found, (pattern, printed)
    return float(found.group(1))


def test_committed_without_outputs():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    code = [cell for cell in nb.cells if cell.cell_type == "code"]
    assert len(code) >= 8
    assert all(not cell.outputs and cell.execution_count is None for cell in code)


def test_datasheet_gives_the_preset(printed):
    assert "equals the preset: True" in printed


def test_infeasible_move_refused_feasible_one_has_margin(printed):
    assert "refused: infeasible plan: torque demand exceeds Km rho*" in printed
    assert 0.0 < number(printed, "feasible plan (min rho 1 A at t=0.01 s; torque margin") < 0.38


def test_drive_run_keeps_its_move_within_the_targets(printed):
    assert "status: ok" in printed
    assert 0.0 < number(printed, "max |theta - theta*| during the move:") < 1.0   # counts
    assert 0.0 < number(printed, "max |theta - theta*| after it:") < 0.5
    assert number(printed, "peak |v|:") < 24.0


def test_robustness_rows(printed):
    rows = re.findall(r"^nema17\[Km([+-]0\.1),J([+-]0\.1)\]\s+(\w+)\s+([0-9.]+) counts$", printed, re.M)
    assert sorted((km, j) for km, j, _, _ in rows) == [("+0.1", "+0.1"), ("+0.1", "-0.1"), ("-0.1", "+0.1"),
                                                       ("-0.1", "-0.1")]
    assert all(status == "ok" for _, _, status, _ in rows)
    assert number(printed, "worst during the move:") == pytest.approx(max(float(r[3]) for r in rows), abs=1e-3)


def test_python_control_reproduces_the_plan(printed):
    assert "inputs ['va', 'vb']" in printed
    assert number(printed, "open loop, feedforward only: max |theta - theta*| =") < 1e-5   # rad, of a 0.05 rad move
    trip = re.search(r"round trip at t = [0-9.]+ s: (\S+) \(state\), (\S+) V \(input\)", printed)
    assert trip and float(trip.group(1)) < 1e-12 and float(trip.group(2)) < 1e-9, printed
