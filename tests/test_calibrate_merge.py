"""``flatstep calibrate --merge`` edits the scenario as TOML, whichever way [feedforward] is spelled, and never
writes over its input unless ``--in-place`` asks for it."""
import re
import sys
from pathlib import Path

import pytest

from flatstep.model.torque_model import TorqueModel
from flatstep.studies.calibrate import Calibration, merged_scenario
from flatstep.studies.scenario_file import load_scenario

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
TABLE = TorqueModel(detent_torque=0.0123, detent_harmonic=4, detent_phase=0.05, coulomb_torque=0.003,
                    coulomb_speed=0.1, load=0.021)
#: What the merged table must hold: the keys Calibration.as_toml writes.
WRITTEN = {k: TABLE.as_dict()[k] for k in ("detent_torque", "detent_harmonic", "detent_phase", "coulomb_torque",
                                           "coulomb_speed", "load")}
CAL = Calibration(torques=TABLE, estimates={}, std={}, source="test",
                  settings={"controller": "cascade", "periods": 16, "peak_speed": 1.5})

HEAD = '''# A scenario (head comment)
name = "merge-test"  # the name
t_end = 0.1

[plan]
theta1 = 0.0  # start
theta2 = 0.5
tf = 0.07

'''
TAIL = '''
# the drive below is ours (a comment above the next table)
[drive]
control_rate = 20000.0  # 20 kHz
'''
#: The old table, spelled each way TOML allows, and the lines that belong to it (removed with it).
SPELLINGS = {
    "table": "# what the old table knew\n[feedforward]\ndetent_torque = 0.015  # old\nload = 0.02\n",
    "spaced header": "[ feedforward ]   # spaced\ndetent_torque = 0.015\nload = 0.02\n",
    "quoted header": '["feedforward"]\ndetent_torque = 0.015\nload = 0.02\n',
    "inline table": "feedforward = { detent_torque = 0.015, load = 0.02 }  # inline\n",
    "dotted keys": "feedforward.detent_torque = 0.015  # dotted\nfeedforward.load = 0.02\n",
}


def _comments(text):
    """The comment lines and trailing comments of ``text``, in order (those of the calibrated table left out)."""
    out = []
    for line in text.splitlines():
        if "#" in line and not line.startswith("# calibrated by"):
            out.append(line[line.index("#"):].strip())
    return out


@pytest.mark.parametrize("spelling", SPELLINGS)
def test_every_spelling_round_trips_with_the_new_table_and_comments(spelling):
    old = SPELLINGS[spelling]
    # dotted keys and inline tables live among the top-level keys, before the first table
    text = (old + HEAD if spelling in ("inline table", "dotted keys") else HEAD + old) + TAIL
    tomllib.loads(text)  # the input is valid TOML
    merged = merged_scenario(text, CAL)
    doc = tomllib.loads(merged)  # and so is the output
    assert doc["feedforward"] == pytest.approx(WRITTEN)
    assert doc["plan"] == {"theta1": 0.0, "theta2": 0.5, "tf": 0.07}
    assert doc["drive"] == {"control_rate": 20000.0} and doc["name"] == "merge-test"
    assert merged.count("feedforward") == 1  # the old table is gone, whichever way it was written
    kept = [c for c in _comments(text) if c not in _comments(old)]
    assert _comments(merged) == kept  # every other comment, unchanged and in order
    assert "# the drive below is ours (a comment above the next table)\n[drive]" in merged


def test_a_file_without_the_table_gets_it_appended():
    merged = merged_scenario(HEAD + TAIL, CAL)
    assert merged.startswith(HEAD + TAIL.rstrip("\n"))
    assert tomllib.loads(merged)["feedforward"] == pytest.approx(WRITTEN)


def test_the_example_keeps_everything_above_its_table():
    source = (EXAMPLES / "compare-nema17-fast.toml").read_text()
    merged = merged_scenario(source, CAL)
    above = source.split("# What the")[0]  # the comment right above [feedforward] described the old table
    assert merged.startswith(above.rstrip("\n"))
    assert tomllib.loads(merged)["robustness"] == tomllib.loads(source)["robustness"]


def test_not_toml_is_refused():
    with pytest.raises(ValueError, match="not TOML"):
        merged_scenario("[plan\n", CAL)


@pytest.fixture(scope="module")
def merged_run(tmp_path_factory):
    """One calibration on a copy of the NEMA 17 example with its [feedforward] spelled as an inline table."""
    from flatstep.cli.main import main

    d = tmp_path_factory.mktemp("merge")
    text = (EXAMPLES / "compare-nema17-fast.toml").read_text()
    table = text[text.index("[feedforward]"):]
    inline = "feedforward = { " + ", ".join(line for line in table.splitlines()[1:] if line.strip()) + " }\n"
    head, rest = text.split("\n[motor]", 1)
    source = d / "s.toml"
    source.write_text(f"{head}\n{inline}\n[motor]{rest[:rest.index('# What the')]}")
    assert main(["calibrate", str(source), "--merge", str(d / "new.toml"), "--out", str(d / "ff.toml")]) == 0
    return d, source.read_text()


def test_merge_writes_a_new_file_and_leaves_the_scenario_alone(merged_run):
    d, before = merged_run
    assert (d / "s.toml").read_text() == before
    scenario, _ = load_scenario(d / "new.toml")
    assert scenario.torques.detent_torque == pytest.approx(0.015, rel=0.05)
    assert (d / "ff.toml").read_text() in (d / "new.toml").read_text()


def test_merge_again_replaces_its_own_file_but_not_a_users(cli, merged_run):
    d, _ = merged_run
    user = d / "user.toml"
    user.write_text("name = 'mine'\n")
    run = cli(["calibrate", "s.toml", "--merge", "user.toml", "--periods", "8"], cwd=d)
    assert run.returncode == 2 and re.search("user.toml: exists and is not a file flatstep wrote", run.stderr)
    assert user.read_text() == "name = 'mine'\n"
    run = cli(["calibrate", "s.toml", "--merge", "new.toml", "--periods", "8"], cwd=d)
    assert run.returncode == 0, run.stderr
    assert "8 detent periods" in (d / "new.toml").read_text()


def test_in_place_is_the_one_way_to_write_the_scenario(cli, merged_run):
    d, before = merged_run
    path = d / "inplace.toml"
    path.write_text(before)
    run = cli(["calibrate", "inplace.toml", "--in-place", "--periods", "8"], cwd=d)
    assert run.returncode == 0, run.stderr
    after = path.read_text()
    assert after != before and after.count("feedforward") == 1
    assert load_scenario(path)[0].torques.detent_torque == pytest.approx(0.015, rel=0.05)
    assert not list(d.glob(".*flatstep-tmp"))  # written through a temporary file, which is gone
