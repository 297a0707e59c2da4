"""Imported first by :mod:`baseparams.cli`: Ctrl-C during its imports says one line (:mod:`baseparams.startup`).

Until ``main`` installs its handler (:class:`~baseparams.interrupts.Interrupts`).
"""

from .. import startup

startup.begin()
