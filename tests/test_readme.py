"""Every command of README.md works verbatim: its shell lines and its Python blocks, run from a scratch directory.

``make demo`` and ``make test`` are the two lines left out (they build the virtual environment this test runs in;
a fresh clone's ``make test`` runs them). A ``$ command`` line is followed by the output it must print; ``(...)``
there stands for text left out.
"""
import itertools
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import run_cli

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()
BLOCKS = re.findall(r"^```(\w+)\n(.*?)^```", README, re.M | re.S)
MAKE_LINES = ("make demo", "make test")


def shell_commands():
    """The README's shell commands in order, each with the output shown after it (``None``: not shown)."""
    out: list[tuple[str, list[str] | None]] = []
    for lang, body in BLOCKS:
        if lang != "sh":
            continue
        transcript = body.startswith("$ ")   # a block of "$ command" lines, each followed by its output
        for line in body.splitlines():
            if transcript:
                if line.startswith("$ "):
                    out.append((line[2:], []))
                else:
                    out[-1][1].append(line)
            elif line.strip() and not line.startswith(MAKE_LINES):
                out.append((line.split("   #")[0].strip(), None))
    return out


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    """A directory holding a copy of examples/, and a PATH on which ``flatstep`` is this environment's."""
    where = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "examples", where / "examples")
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
           "MPLBACKEND": "Agg"}
    return where, env


def test_readme_has_the_commands_it_promises():
    """The README holds the commands it promises: each main command, three Python blocks or more, no other make line."""
    commands = [c for c, _ in shell_commands()]
    assert len(commands) >= 7
    for name in ("simulate", "design", "robustness", "compare", "identify"):
        assert any(c.startswith(f"flatstep {name}") for c in commands), name
    assert sum(lang == "python" for lang, _ in BLOCKS) >= 3
    assert all(line.startswith(MAKE_LINES) for lang, body in BLOCKS if lang == "sh" for line in body.splitlines()
               if line.startswith("make"))


def _written(command):
    """The files a command names after ``--out`` or ``--record`` (what a later command may read)."""
    argv = shlex.split(command, comments=True)
    return {b for a, b in itertools.pairwise(argv) if a in ("--out", "--record")}


def shell_units():
    """The shell commands in runs that can go apart.

    A command joins the run of an earlier one whose file it reads (``identify nema17.csv`` after
    ``identify --excite ... --record nema17.csv``), else starts its own.
    """
    units: list[list[tuple[str, list[str] | None]]] = []
    for command, shown in shell_commands():
        words = set(shlex.split(command, comments=True))
        home = next((u for u in units if any(words & _written(c) for c, _ in u)), None)
        if home is None:
            units.append(home := [])
        home.append((command, shown))
    return units


#: What a command must leave behind, besides its exit code and output.
LEFT_BEHIND = {"flatstep robustness": lambda where: (where / "out" / "rob" / "robustness.png").stat().st_size > 10_000,
               "flatstep identify nema17.csv": lambda where: "[motor]" in (where / "motor.toml").read_text()}


def test_shell_units_keep_every_command_once_in_order():
    """The units hold every shell command once, in order, and the recording and its fit share one."""
    units = shell_units()
    flat = [c for u in units for c in u]
    assert sorted(flat, key=shell_commands().index) == shell_commands() and len(units) >= 7
    assert all(any(c.startswith(k) for u in units for c, _ in u) for k in LEFT_BEHIND)
    identify = next(u for u in units if any("--record nema17.csv" in c for c, _ in u))
    assert [c.split()[1] for c, _ in identify] == ["identify", "identify"]   # the recording, then its fit


@pytest.mark.parametrize("unit", shell_units(), ids=lambda u: "+".join(shlex.split(c)[1] for c, _ in u))
def test_shell_commands(scratch, unit):
    """Each run of commands in order (the compare runs, several seconds each, go to separate workers)."""
    where, env = scratch
    for command, shown in unit:
        argv = shlex.split(command, comments=True)
        if argv[0] == "flatstep":  # in this process: the same main() the entry point calls, without its start-up
            proc = run_cli(argv[1:], cwd=where)
        else:
            proc = subprocess.run(command, shell=True, cwd=where, env=env, capture_output=True, text=True, timeout=300)
        if shown is None:
            assert proc.returncode == 0, (command, proc.stderr)
        else:
            printed = (proc.stdout + proc.stderr).splitlines()
            assert len(printed) == len(shown), (command, printed, shown)
            for got, want in zip(printed, shown, strict=False):
                head, _, tail = want.partition("(...)")
                assert got.startswith(head) and got.endswith(tail), (command, got, want)
        for start, check in LEFT_BEHIND.items():
            if command.startswith(start):
                assert check(where), command


def test_python_blocks(scratch):
    """The Python blocks, in order in one interpreter (a later block uses the names of an earlier one)."""
    where, env = scratch
    code = "\n".join(body for lang, body in BLOCKS if lang == "python")
    proc = subprocess.run([sys.executable, "-c", code], cwd=where, env=env, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "'status': 'ok'" in lines[0]                     # the continuous run's summary
    error, engine = lines[1].split()
    assert 0.0 < float(error) < 1e-3 and engine == "c"      # the 20 kHz drive's error during the move [rad]
    assert lines[2].count("('ok'") == 3                     # the batch: three loads, each kept its move
    assert len((where / "rows.jsonl").read_text().splitlines()) == 4   # a header and three rows
