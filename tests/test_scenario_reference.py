"""docs/scenario-reference.md is the code's: generated from flatstep.studies.scenario_keys, which the loader reads."""
from pathlib import Path

import pytest

from flatstep.plan.sequence import PLANNERS
from flatstep.studies.scenario_file import read_scenario_file
from flatstep.studies.scenario_keys import KEYS, PLANNER_KEYS, markdown_reference

DOC = Path(__file__).resolve().parent.parent / "docs" / "scenario-reference.md"


def test_the_committed_reference_is_the_generated_one():
    assert DOC.read_text() == markdown_reference(), "run python tools/gen_scenario_reference.py"


def test_every_table_and_key_is_listed():
    text = DOC.read_text()
    for table, keys in KEYS.items():
        assert table == "" or f"## [{table}]" in text
        for key in keys:
            assert f"| `{key}` |" in text, (table, key)


def test_the_planners_keys_are_plan_keys_and_every_plan_key_has_a_planner():
    assert set(PLANNER_KEYS) == set(PLANNERS)
    taken = {k for keys in PLANNER_KEYS.values() for k in keys}
    assert taken == set(KEYS["plan"])


@pytest.mark.parametrize("table", [t for t in KEYS if t not in ("", "plan", "limits")])
def test_the_loader_takes_every_key_of_the_reference(tmp_path, table):
    """A key the page lists is not refused as unknown (its value may still be refused)."""
    for key in KEYS[table]:
        path = tmp_path / "k.toml"
        path.write_text(f"[{table}]\n{key} = []\n")
        try:
            read_scenario_file(path)
        except ValueError as exc:
            assert "unknown key" not in str(exc), (table, key, str(exc))
