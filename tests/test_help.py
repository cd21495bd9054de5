"""The command line's help: every command listed and described, plain text, every measurement mode explained."""
import re

import pytest

from flatstep.cli.main import DESCRIPTION, build_parser, main
from flatstep.control.smc import MEASUREMENTS


def commands():
    """The subcommands the parser really has."""
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return list(sub.choices)


def test_top_level_help_lists_every_command(capsys):
    assert main(["--help"]) == 0
    text = capsys.readouterr().out
    names = commands()
    assert {"reproduce", "simulate", "design", "robustness", "compare", "identify", "bench"} <= set(names)
    listed = DESCRIPTION.split("Commands:")[1].split("'flatstep COMMAND --help'")[0]
    assert set(re.findall(r"(\w+) \(", listed)) == set(names)
    assert all(f"{code} " in DESCRIPTION for code in (0, 1, 2, 3, 4, 5, 130))
    assert "``" not in text and ":func:" not in text and ":data:" not in text


@pytest.mark.parametrize("name", commands())
def test_every_command_has_a_plain_description(name, capsys):
    assert main([name, "--help"]) == 0
    text = capsys.readouterr().out
    head = text.split("\n\n")[1]   # usage, then the description, then the arguments
    assert not head.startswith(("positional arguments", "options")), f"flatstep {name} --help has no description"
    assert "``" not in text and ":func:" not in text and "%%" not in text


def test_simulate_help_explains_every_measurement_mode(capsys):
    main(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for mode in MEASUREMENTS:
        assert re.search(rf"\b{mode}: ", text), mode


def test_help_starts_without_scipy_signal():
    """`flatstep --help` and `flatstep plan --help` do not import scipy.signal (a second of start-up)."""
    import subprocess
    import sys

    code = ("import sys; from flatstep.cli.main import main\n"
            "for argv in (['--help'], ['plan', '--help'], ['simulate', '--help']):\n"
            "    try:\n        main(argv)\n    except SystemExit:\n        pass\n"
            "print('scipy.signal' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip().splitlines()[-1] == "False", out.stderr
