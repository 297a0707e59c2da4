"""``python -m baseparams.cli ...``: the command line, as ``python -m baseparams``."""

import sys

from . import main

if __name__ == "__main__":
    sys.exit(main())
