"""Ctrl-C while the package is still being imported: one line, not a traceback.

The command line's handler (:class:`~baseparams.interrupts.Interrupts`) is installed when ``main`` runs;
before that, ``baseparams ...`` spends ~0.2 s importing numpy and the package, and an interrupt there
was a 40-line traceback. Importing this module (stdlib only, first in the package) makes an
uncaught :class:`KeyboardInterrupt` print one line until :func:`done` (the end of the package's own
imports; the exit status stays the interrupt's). Other exceptions reach the previous hook unchanged.
"""

from __future__ import annotations

import sys

_previous = None


def _hook(kind, value, tb) -> None:
    if issubclass(kind, KeyboardInterrupt):
        sys.stderr.write("baseparams: interrupted while starting (nothing was written)\n")
        return
    (_previous or sys.__excepthook__)(kind, value, tb)


def begin() -> None:
    """Install the one-line hook (idempotent)."""
    global _previous
    if sys.excepthook is not _hook:
        _previous, sys.excepthook = sys.excepthook, _hook


def done() -> None:
    """Restore the previous hook: the imports finished."""
    global _previous
    if sys.excepthook is _hook:
        sys.excepthook = _previous or sys.__excepthook__
    _previous = None


begin()
