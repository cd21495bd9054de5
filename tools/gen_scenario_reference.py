"""Write docs/scenario-reference.md, the scenario file reference, from flatstep.studies.scenario_keys.

Run ``python tools/gen_scenario_reference.py`` after changing a table or key; ``--check`` exits 1 when the committed
page differs from the code (tests/test_scenario_reference.py runs the same comparison).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from flatstep.studies.scenario_keys import markdown_reference

DOC = Path(__file__).resolve().parent.parent / "docs" / "scenario-reference.md"


def main() -> int:
    """Write the page, or with ``--check`` compare it; returns the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare the committed page instead of writing it")
    args = parser.parse_args()
    text = markdown_reference()
    if args.check:
        same = DOC.exists() and DOC.read_text() == text
        print(f"{DOC}: {'up to date' if same else 'differs from the code: run tools/gen_scenario_reference.py'}")
        return 0 if same else 1
    DOC.write_text(text)
    print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
