"""Every command of README.md works verbatim: its shell lines and its Python blocks, run from a scratch directory.

``make demo`` and ``make test`` are the two lines left out (they build the virtual environment this test runs in;
a fresh clone's ``make test`` runs them). A ``$ command`` line is followed by the output it must print; ``(...)``
there stands for text left out.
"""
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
    commands = [c for c, _ in shell_commands()]
    assert len(commands) >= 7
    for name in ("simulate", "design", "robustness", "compare", "identify"):
        assert any(c.startswith(f"flatstep {name}") for c in commands), name
    assert sum(lang == "python" for lang, _ in BLOCKS) >= 3
    assert all(line.startswith(MAKE_LINES) for lang, body in BLOCKS if lang == "sh" for line in body.splitlines()
               if line.startswith("make"))


def test_shell_commands(scratch):
    where, env = scratch
    for command, shown in shell_commands():   # in order: identify reads the recording written before it
        argv = shlex.split(command, comments=True)
        if argv[0] == "flatstep":  # in this process: the same main() the entry point calls, without its start-up
            proc = run_cli(argv[1:], cwd=where)
        else:
            proc = subprocess.run(command, shell=True, cwd=where, env=env, capture_output=True, text=True, timeout=300)
        if shown is None:
            assert proc.returncode == 0, (command, proc.stderr)
            continue
        printed = (proc.stdout + proc.stderr).splitlines()
        assert len(printed) == len(shown), (command, printed, shown)
        for got, want in zip(printed, shown):
            head, _, tail = want.partition("(...)")
            assert got.startswith(head) and got.endswith(tail), (command, got, want)
    assert (where / "out" / "rob" / "robustness.png").stat().st_size > 10_000
    assert "[motor]" in (where / "motor.toml").read_text()


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
