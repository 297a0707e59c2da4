"""``python -m baseparams ...``: the command line (see :mod:`baseparams.cli`)."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
