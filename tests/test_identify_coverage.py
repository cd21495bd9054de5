import pytest

from flatstep.studies.identify_coverage import CHECKED, cases, coverage_table, reason, run_case


def test_the_grid_is_fixed_and_within_its_ranges():
    grid = cases(40)
    assert grid == cases(40) and grid[:5] == cases(5)
    assert all(0.5 <= abs(c.move) <= 10.0 and 0.2 <= c.duration <= 0.6 and 0.002 <= c.noise <= 0.010
               and all(0.9 <= s <= 1.1 for s in c.scale) for c in grid)
    assert {c.drive for c in grid} == {"nema17", "paper"} and {c.effects for c in grid} == {True, False}
    assert {c.hold for c in grid} == {True, False} and any(c.load == 0 for c in grid) and any(c.load for c in grid)


def test_a_case_is_recorded_identified_and_tabulated():
    row = run_case(cases(2)[1])
    assert row["status"] in ("accepted", "flagged", "refused")
    if row["status"] != "refused":
        assert set(row["covered"]) == set(CHECKED) and abs(row["errors"]["R"]) < 0.05
    table = coverage_table([row, {**row, "status": "refused", "reason": "wide intervals"}])
    assert table.startswith("2 recordings:") and "wide intervals" in table


@pytest.mark.parametrize("message, name", [
    ("x.csv: not exciting enough: the 95% intervals are B +-60%", "wide intervals"),
    ("x.csv: ill-conditioned regressors (condition number 2e4 > 1e4)", "ill-conditioned"),
])
def test_refusals_are_named_by_their_cause(message, name):
    assert reason(message) == name


def test_a_one_way_move_says_its_load_includes_the_coulomb_friction():
    from flatstep.studies.identify import identify
    from flatstep.studies.identify_coverage import recording

    case = cases(6)[5]  # the paper's drive, -5.6 rad, detent and Coulomb friction
    rec, plant = recording(case)
    result = identify(rec, Nr=50)
    (note,) = result.notes
    assert "one direction only (negative)" in note and "load_torque includes the Coulomb friction" in note
    assert "give --detent" in result.flags[0]
    with_coulomb = plant.constant_load - plant.effects.coulomb_torque  # what a negative move sees as its load
    lo, hi = identify(rec, Nr=50, detent=True).interval("load_torque")
    assert lo <= with_coulomb <= hi
