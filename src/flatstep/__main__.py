"""``python -m flatstep``: the command line (:func:`flatstep.cli.main`)."""
import sys

from .cli import main

sys.exit(main())
