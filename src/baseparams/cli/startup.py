"""Imported first by :mod:`baseparams.cli`: Ctrl-C during its imports says one line (:mod:`baseparams.startup`).

Only when the process is the command line (``baseparams ...`` or ``python -m baseparams ...``), until ``main``
installs its handler (:class:`~baseparams.interrupts.Interrupts`); a program importing :mod:`baseparams.cli` keeps
its own hook.
"""

import os
import sys

from .. import startup

if os.path.basename(sys.argv[0]) == "baseparams" or sys.argv[0].endswith(os.path.join("baseparams", "__main__.py")):
    startup.begin()
