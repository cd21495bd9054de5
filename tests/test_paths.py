"""The output-path rule (flatstep.validate.paths): never over an input, never over a user's file without force."""
import pytest

from flatstep.validate.paths import check_output


def test_an_input_is_never_replaced_even_with_force(tmp_path):
    scenario = tmp_path / "s.toml"
    scenario.write_text("[motor]\n")
    for force in (False, True):
        with pytest.raises(ValueError, match=r"--record .*s.toml: is an input of this run"):
            check_output(tmp_path / "." / "s.toml", "--record", inputs=[scenario], force=force)
    assert scenario.read_text() == "[motor]\n"


def test_a_users_file_needs_force_and_flatsteps_own_does_not(tmp_path):
    notes, rec, new = tmp_path / "notes.txt", tmp_path / "rec.csv", tmp_path / "new.csv"
    notes.write_text("my notes\n")
    rec.write_text("t,va,vb\n0,1,2\n")
    with pytest.raises(ValueError, match="notes.txt: exists and is not a file flatstep wrote"):
        check_output(notes, "run_batch(out=)")
    assert check_output(notes, "--out", force=True) == notes
    assert check_output(rec, "--out") == rec
    assert check_output(new, "--out") == new
    (tmp_path / "empty.csv").write_text("")
    assert check_output(tmp_path / "empty.csv", "--out").name == "empty.csv"


def test_directories_and_missing_parents_are_refused(tmp_path):
    with pytest.raises(ValueError, match="is a directory"):
        check_output(tmp_path, "--record")
    (tmp_path / "file").write_text("x")
    with pytest.raises(ValueError, match="is not a directory"):
        check_output(tmp_path / "file" / "out.csv", "--record")


def test_the_in_process_runner_gives_the_exit_code_and_streams(cli, tmp_path):
    run = cli(["simulate", "--tf", "nan"], cwd=tmp_path)
    assert run.returncode == 2 and "--tf" in run.stderr and run.stdout == ""
    assert cli(["--version"]).returncode == 0
    with pytest.raises(ValueError, match="does not exist"):
        check_output(tmp_path / "nope" / "out.csv", "--record")
