"""Bad input to ``flatstep identify``, ``flatstep calibrate`` and ``flatstep compare --calibrate-each``.

Every case runs in-process (the ``cli`` fixture) and must exit 2 with one line on stderr that names the flag, file or
column and says why, with no traceback, and must leave every file it was given as it was (an input is never
written over). The files are made once per module; the cases that reach a fit use a 1 s recording.
"""
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from flatstep.studies.excitation import excite
from flatstep.studies.identify_accuracy import preset_plant
from flatstep.studies.record import COLUMNS, write_recording
from flatstep.studies.scenario_file import load_scenario

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _csv(path, columns, header=None):
    """Write ``columns`` (a dict of arrays) as a recording's CSV with ``header`` (default: the dict's keys)."""
    names = header or list(columns)
    np.savetxt(path, np.column_stack(list(columns.values())), fmt="%.12g", delimiter=",", header=",".join(names),
               comments="")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Every input file of the cases, by name; ``dir`` is their directory."""
    d = tmp_path_factory.mktemp("bad")
    rec = excite(preset_plant(load_scenario(EXAMPLES / "nema17-20khz.toml")[0]), seed=3, current_noise=0.005)
    write_recording(d / "rec.csv", rec)
    cols = rec.columns()
    scaled = {"mv": {"va": 1e3, "vb": 1e3}, "ma": {"ia": 1e3, "ib": 1e3}, "counts": {"theta": 1e7 / np.pi}}
    for name, factors in scaled.items():
        _csv(d / f"{name}.csv", {c: v * factors.get(c, 1.0) for c, v in cols.items()})
    _csv(d / "half.csv", {**cols, "theta": cols["theta"] + np.pi / 50})  # zero half an electrical period off
    rng = np.random.default_rng(0)
    _csv(d / "noisy.csv", {**cols, "ia": cols["ia"] + rng.normal(0, 2.0, cols["ia"].size),
                           "ib": cols["ib"] + rng.normal(0, 2.0, cols["ib"].size)})
    _csv(d / "twice.csv", {**cols, "theta2": cols["theta"] * 0}, header=[*COLUMNS, "theta"])
    _csv(d / "noia.csv", {c: v for c, v in cols.items() if c != "ia"})
    nan = dict(cols, ia=cols["ia"].copy())
    nan["ia"][4] = np.nan
    _csv(d / "nan.csv", nan)
    uneven = dict(cols, t=cols["t"].copy())
    uneven["t"][10] += 0.3 * rec.period
    _csv(d / "uneven.csv", uneven)
    _csv(d / "short.csv", {c: v[:50] for c, v in cols.items()})
    _csv(d / "rest.csv", {**cols, "theta": np.zeros_like(cols["theta"])})
    (d / "header.csv").write_text(",".join(COLUMNS) + "\n")
    (d / "binary.csv").write_bytes(b"\x00\xff\x10garbage\x00" * 20)
    (d / "notes.txt").write_text("my notes, not flatstep's\n")
    (d / "outdir").mkdir()
    shutil.copy(EXAMPLES / "compare-nema17-fast.toml", d / "s.toml")
    shutil.copy(EXAMPLES / "nema17-20khz.toml", d / "drive.toml")
    shutil.copy(EXAMPLES / "paper-fig1.toml", d / "nodrive.toml")
    text = (EXAMPLES / "compare-nema17-fast.toml").read_text()
    (d / "nosensors.toml").write_text(text.replace("[sensors]\nencoder_counts = 16384\ncurrent_bits = 12\n"
                                                   "current_range = 3.0\n", ""))
    (d / "norobust.toml").write_text(text.split("\n[robustness]")[0])
    (d / "broken.toml").write_text("[plan\ntf = 1\n")
    (d / "user.toml").write_text("# my own scenario notes\nname = 'mine'\n")
    return d


# (argv, what stderr must say); {name} is the path of a file of the fixture, {dir} its directory.
IDENTIFY = [
    ([], "give a recording"),
    (["{rec.csv}", "--excite", "{drive.toml}"], "give a recording.*got"),
    (["{rec.csv}", "--seeds", "5"], "--seeds is read only with --accuracy.*drop --seeds, or give --accuracy"),
    (["{rec.csv}", "--seed", "1"], "--seed is read only with --excite"),
    (["{rec.csv}", "--record", "{dir}/r.csv"], "--record is read only with --excite"),
    (["{rec.csv}", "--duration", "2"], "--duration is read only with --excite or --accuracy"),
    (["{rec.csv}", "--noise", "0.01"], "--noise is read only with --excite or --accuracy"),
    (["{rec.csv}", "--preset-plant"], "--preset-plant is read only with --excite or --accuracy"),
    (["--accuracy", "{drive.toml}", "--out", "{dir}/m.toml"], "--out is read only with a recording"),
    (["--accuracy", "{drive.toml}", "--nr", "50"], "--nr is read only with a recording"),
    (["{rec.csv}", "--coulomb-speed", "0.5"], "--coulomb-speed sets the Coulomb term that --coulomb estimates"),
    (["--excite", "{drive.toml}"], "--excite needs --record"),
    (["--excite", "{drive.toml}", "--record", "{drive.toml}"], r"--record .*drive.toml: is an input of this run"),
    (["{rec.csv}", "--out", "{rec.csv}"], r"--out .*rec.csv: is an input of this run"),
    (["{rec.csv}", "--out", "{rec.csv}", "--force"], r"--out .*rec.csv: is an input .*even with --force"),
    (["--excite", "{drive.toml}", "--record", "{dir}/r.csv", "--out", "{dir}/r.csv"], r"--out .*r.csv: is an input"),
    (["--excite", "{drive.toml}", "--record", "{notes.txt}"], r"--record .*notes.txt: exists and is not a file "
                                                                "flatstep wrote"),
    (["{rec.csv}", "--out", "{notes.txt}"], r"--out .*notes.txt: exists and is not a file flatstep wrote"),
    (["{rec.csv}", "--out", "{s.toml}"], r"--out .*s.toml: exists and is not a file flatstep wrote"),
    (["{rec.csv}", "--out", "{outdir}"], "--out .*: is a directory"),
    (["{rec.csv}", "--out", "{dir}/missing/m.toml"], "the directory .*missing does not exist"),
    (["{rec.csv}", "--bandwidth", "nan", "100"], "argument --bandwidth: bandwidth=nan is not finite"),
    (["{rec.csv}", "--bandwidth", "-1", "100"], "argument --bandwidth: bandwidth=-1.0 Hz is out of range"),
    (["{rec.csv}", "--bandwidth", "200", "1e9"], "argument --bandwidth: bandwidth=1000000000.0 Hz is out of range"),
    (["{rec.csv}", "--bandwidth", "200", "abc"], "argument --bandwidth: --bandwidth='abc' is not a number"),
    (["{rec.csv}", "--bandwidth", "6000", "100"], "bandwidth 6000.0 Hz must be below a quarter of the sampling rate"),
    (["{rec.csv}", "--confidence", "1.5"], "argument --confidence: confidence=1.5 is out of range"),
    (["{rec.csv}", "--confidence", "0"], "argument --confidence: confidence=0.0 is out of range"),
    (["{rec.csv}", "--nr", "0"], "argument --nr"),
    (["{rec.csv}", "--nr", "1.5"], "argument --nr: --nr='1.5' is not an integer"),
    (["--accuracy", "{drive.toml}", "--seeds", "0"], "argument --seeds"),
    (["--accuracy", "{drive.toml}", "--seeds", "51"], "argument --seeds"),
    (["--excite", "{drive.toml}", "--record", "{dir}/r.csv", "--duration", "0"], "argument --duration"),
    (["--excite", "{drive.toml}", "--record", "{dir}/r.csv", "--duration", "1e9"], "argument --duration"),
    (["--excite", "{drive.toml}", "--record", "{dir}/r.csv", "--noise", "-1"], "argument --noise"),
    (["--excite", "{drive.toml}", "--record", "{dir}/r.csv", "--noise", "nan"], "argument --noise"),
    (["--excite", "{drive.toml}", "--record", "{dir}/r.csv", "--seed", "-1"], "argument --seed"),
    (["{rec.csv}", "--coulomb", "--coulomb-speed", "0"], "argument --coulomb-speed"),
    (["--excite", "{nodrive.toml}", "--record", "{dir}/r.csv"], "has no drive loop"),
    (["--excite", "{dir}/none.toml", "--record", "{dir}/r.csv"], "no such scenario file"),
    (["--accuracy", "{dir}/none.toml"], "no such scenario file"),
    (["--accuracy", "{broken.toml}"], "broken.toml"),
    (["{dir}/none.csv"], "none.csv: no such recording file"),
    (["{twice.csv}"], r"column\(s\) \['theta'\] appear more than once"),
    (["{noia.csv}"], r"missing column\(s\) \['ia'\]"),
    (["{nan.csv}"], "column 'ia' has a non-finite value nan in data row 5"),
    (["{uneven.csv}"], "column 't' must increase by a constant step"),
    (["{short.csv}"], "50 rows is too short"),
    (["{header.csv}"], "0 rows is too short"),
    (["{binary.csv}"], "not a CSV file of numbers"),
    (["{rest.csv}"], r"does not excite \['Km'\]"),
    (["{mv.csv}"], "columns 'va', 'vb' reach .* V, beyond the 10000 V .*are the voltages in mV"),
    (["{ma.csv}"], "columns 'ia', 'ib' reach .* A, beyond the 1000 A .*are the currents in mA"),
    (["{counts.csv}"], "column 'theta' reaches .* rad, beyond the 1e\\+06 rad .*is theta in encoder counts"),
    (["{half.csv}"], "Km = -0.26.* is below the range .*half an electrical period off"),
    (["{noisy.csv}"], "the current noise makes up .* of the power of the filtered"),
]

CALIBRATE = [
    (["{dir}/none.toml"], "no such scenario file"),
    (["{broken.toml}"], "broken.toml"),
    (["{nodrive.toml}"], "has no drive loop"),
    (["{nosensors.toml}"], r"has no \[sensors\]"),
    (["{s.toml}", "--speed", "1e300"], "--speed: peak_speed=1e\\+300 rad/s makes the calibration move"),
    (["{s.toml}", "--speed", "1e-5"], "calibration move of .* at --speed 1e-05"),
    (["{s.toml}", "--speed", "0"], "argument --speed: --speed '0': give a peak speed > 0"),
    (["{s.toml}", "--speed", "-1"], "argument --speed"),
    (["{s.toml}", "--speed", "nan"], "argument --speed: .*not finite"),
    (["{s.toml}", "--speed", "inf"], "argument --speed: .*not finite"),
    (["{s.toml}", "--speed", "fast"], "argument --speed: --speed 'fast'"),
    (["{s.toml}", "--periods", "0"], "argument --periods"),
    (["{s.toml}", "--periods", "257"], "argument --periods"),
    (["{s.toml}", "--periods", "1.5"], "argument --periods"),
    (["{s.toml}", "--harmonic", "0"], "argument --harmonic"),
    (["{s.toml}", "--harmonic", "1001"], "argument --harmonic"),
    (["{s.toml}", "--coulomb-speed", "0"], "argument --coulomb-speed"),
    (["{s.toml}", "--coulomb-speed", "nan"], "argument --coulomb-speed"),
    (["{s.toml}", "--noise", "-1"], "argument --noise"),
    (["{s.toml}", "--noise", "1e4"], "argument --noise"),
    (["{s.toml}", "--controller", "cascade_ff"], "argument --controller: invalid choice"),
    (["{s.toml}", "--merge", "{s.toml}"], r"--merge .*s.toml: is an input of this run"),
    (["{s.toml}", "--merge", "{s.toml}", "--force"], r"--merge .*s.toml: is an input .*even with --force"),
    (["{s.toml}", "--out", "{s.toml}"], r"--out .*s.toml: is an input of this run"),
    (["{s.toml}", "--out", "{dir}/x.toml", "--merge", "{dir}/x.toml"], r"--out .*x.toml: is an input"),
    (["{s.toml}", "--merge", "{user.toml}"], r"--merge .*user.toml: exists and is not a file flatstep wrote"),
    (["{s.toml}", "--merge", "{rec.csv}"], r"--merge .*rec.csv: exists and is not a file flatstep wrote"),
    (["{s.toml}", "--out", "{notes.txt}"], r"--out .*notes.txt: exists and is not a file flatstep wrote"),
    (["{s.toml}", "--merge", "{outdir}"], "--merge .*: is a directory"),
    (["{s.toml}", "--merge", "{dir}/missing/x.toml"], "the directory .*missing does not exist"),
    (["{s.toml}", "--in-place", "--merge", "{dir}/x.toml"], "--in-place merges into .* give one of them"),
    (["{s.toml}", "--in-place", "--out", "{s.toml}"], r"--out .*s.toml: is an input"),
    (["{s.toml}", "--accuracy", "--out", "{dir}/x.toml"], r"writes no table \(drop --out\)"),
    (["{s.toml}", "--accuracy", "--merge", "{dir}/x.toml"], r"writes no table \(drop --merge\)"),
    (["{s.toml}", "--accuracy", "--in-place"], r"writes no table \(drop --in-place\)"),
    (["{s.toml}", "--accuracy", "--speed", "1e300"], "--speed: peak_speed=1e\\+300"),
    (["{s.toml}", "--noise", "1.0"], "the current noise makes up .* of the power of the filtered"),
]

COMPARE = [
    (["{s.toml}", "--calibrate-each", "--controllers", "cascade,microstep"], r"--calibrate-each: .*name none"),
    (["{nosensors.toml}", "--calibrate-each"], r"--calibrate-each: .*has no \[sensors\]"),
    (["{nodrive.toml}", "--calibrate-each"], r"has no \[drive\] control_rate"),
    (["{s.toml}", "--calibrate-each", "--no-robustness", "--samples", "3"], "--samples 3 .*--no-robustness skips it"),
    (["{norobust.toml}", "--calibrate-each", "--samples", "3"], r"--samples 3 .*has no \[robustness\] table"),
    (["{s.toml}", "--calibrate-each", "--controllers", "cascade_ff,cascade_ff"], "give distinct names"),
    (["{s.toml}", "--calibrate-each", "--controllers", "cascade_fff"], "give distinct names among"),
    (["{s.toml}", "--calibrate-each", "--band", "-1"], "--band -1.0: the settling band must be > 0"),
    (["{s.toml}", "--calibrate-each", "--scales", "0", "--controllers", "cascade_ff"], "--scales '0'"),
    (["{s.toml}", "--calibrate-each", "--scales", "2", "--controllers", "dq_smc_i_ff_km"], "--scales '2' sweeps"),
    (["{dir}/none.toml", "--calibrate-each"], "no such scenario file"),
    (["{broken.toml}", "--calibrate-each"], "broken.toml"),
]

CASES = ([("identify", *c) for c in IDENTIFY] + [("calibrate", *c) for c in CALIBRATE]
         + [("compare", *c) for c in COMPARE])


def _argv(argv, d):
    """``argv`` with {name} replaced by the fixture's files and {dir} by their directory."""
    out = []
    for a in argv:
        if a.startswith("{") and "}" in a:
            name, rest = a[1:].split("}", 1)
            a = str(d if name == "dir" else d / name) + rest
        out.append(a)
    return out


def _snapshot(d):
    """Every file of the fixture's directory with its size and modification time (a write changes them)."""
    return {p.name: (p.stat().st_size, p.stat().st_mtime_ns) for p in d.iterdir() if p.is_file()}


@pytest.mark.parametrize("command, argv, message", CASES,
                         ids=[f"{c}-{i}" for i, (c, _, _) in enumerate(CASES)])
def test_refused_naming_the_cause(cli, files, command, argv, message):
    """Exit 2, the cause named on stderr, no traceback, no file written or replaced."""
    before = _snapshot(files)
    run = cli([command, *_argv(argv, files)], cwd=files)
    assert run.returncode == 2, (run.returncode, run.stdout[-500:], run.stderr)
    assert "Traceback" not in run.stderr
    assert re.search(message, run.stderr), run.stderr
    assert _snapshot(files) == before  # nothing written, nothing over an input
    assert not (files / "r.csv").exists() and not (files / "x.toml").exists() and not (files / "m.toml").exists()
