"""``python -m flatstep``: the command line (:func:`flatstep.cli.main`)."""
import sys

try:
    from .cli import main
except KeyboardInterrupt:  # Ctrl-C while the modules load: the same exit as during a run
    print("flatstep: interrupted", file=sys.stderr)
    sys.exit(130)

sys.exit(main())
