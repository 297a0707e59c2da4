"""Command-line front end: ``baseparams robots``, ``baseparams analyze MODEL``, ...

The command line parses and prints: its parser (:mod:`baseparams.cli.parser`) asks each command's
module (:mod:`~baseparams.cli.robots`, :mod:`~baseparams.cli.analyze`, :mod:`~baseparams.cli.regressor`,
:mod:`~baseparams.cli.identify`, :mod:`~baseparams.cli.predict`, :mod:`~baseparams.cli.simulate`,
:mod:`~baseparams.cli.excite`, :mod:`~baseparams.cli.payload`) for its subcommand, its flags' keywords and
its ``run``; the preflight (:mod:`baseparams.cli.preflight`) asks the library's rules before any work; every
message names the options by the command's flags (:func:`baseparams.cli.parser.flag_message`).

Exit codes (scripts rely on them): 0 the result is certified (or completed, or unverified on
request with ``--no-verify``); 2 bad input, printed as one line (``baseparams: error: ...``);
3 certification UNDECIDED (no gap of the spectrum decides the rank: the message lists the clusters,
the candidate counts and what would help; a gap too small to decide literally is decided by
practical identifiability, at a gap of the directions' effects, unless ``--literal``);
4 certification FAILED (a DRNG column is not in the numerical nullspace); 130 interrupted (Ctrl-C),
143 terminated (SIGTERM): either stops the run where it is, and a file being written is removed.
"""

from __future__ import annotations

import sys

from . import startup as _cli_startup  # noqa: F401  (first: Ctrl-C during the command line's imports: one line)

# isort: split
import numpy as np

from .. import startup
from ..errors import BaseparamsError
from ..interrupts import EXIT_TERMINATED, Interrupts, Terminated
from .analyze import run as cmd_analyze
from .common import (
    EXIT_FAILED,
    EXIT_INPUT,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_UNDECIDED,
    Progress,
    floating_hint,
)
from .excite import run as cmd_excite
from .identify import run as cmd_identify
from .parser import build_parser, flag_message
from .payload import run as cmd_payload
from .predict import run as cmd_predict
from .preflight import preflight
from .regressor import run as cmd_regressor
from .robots import run as cmd_robots
from .simulate import run as cmd_simulate

__all__ = ["EXIT_FAILED", "EXIT_INPUT", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_UNDECIDED", "Progress", "build_parser",
           "cmd_analyze", "cmd_excite", "cmd_identify", "cmd_payload", "cmd_predict", "cmd_regressor", "cmd_robots",
           "cmd_simulate", "floating_hint", "main", "preflight"]


def _one_line_notes() -> None:
    """A library note raised as a warning (numba cannot cache) reaches stderr as ``baseparams: note: ...``."""
    import warnings

    from ..regressor.compiled import CompileCacheWarning

    default = warnings.formatwarning
    if getattr(default, "baseparams", False):
        return

    def fmt(message, category, filename, lineno, line=None):
        if issubclass(category, CompileCacheWarning):
            return f"baseparams: note: {message}\n"
        return default(message, category, filename, lineno, line)

    fmt.baseparams = True
    warnings.formatwarning = fmt


def _linalg_message(args, exc: Exception) -> str:
    """One line for a numerical failure (an SVD that did not converge...): the input's numbers are to blame."""
    what = getattr(args, "model", None) or getattr(args, "command", "baseparams")
    return (f"{what}: the linear algebra failed ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__}); "
            "the model's or the log's numbers are beyond what floating point handles (huge, tiny or badly scaled)")


def main(argv: list[str] | None = None) -> int:
    """Run the ``baseparams`` command line.

    Bad input (a :class:`BaseparamsError`, a missing ``--output`` folder, a number out of its
    range: :mod:`baseparams.arguments`) is one line on stderr, ``baseparams: error: ...``; a flag
    argparse cannot parse (``--samples x``) is argparse's usage error (``SystemExit`` with status 2).

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit code (module doc): :data:`EXIT_OK`, :data:`EXIT_INPUT`,
        :data:`EXIT_UNDECIDED`, :data:`EXIT_FAILED`, :data:`EXIT_INTERRUPTED` (Ctrl-C) or
        :data:`baseparams.interrupts.EXIT_TERMINATED` (SIGTERM); 0 on a
        broken pipe (e.g. piped into ``head``).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    _one_line_notes()
    try:
        with Interrupts():  # SIGTERM unwinds like Ctrl-C: every output's temporary file removed
            startup.done()
            preflight(args)
            return args.func(args)
    except BaseparamsError as exc:
        print(f"baseparams: error: {flag_message(str(exc), args.command)}", file=sys.stderr)
        return EXIT_INPUT
    except np.linalg.LinAlgError as exc:
        print(f"baseparams: error: {_linalg_message(args, exc)}", file=sys.stderr)
        return EXIT_INPUT
    except BrokenPipeError:  # e.g. piped into head
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("baseparams: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated:
        print("baseparams: terminated (SIGTERM)", file=sys.stderr)
        return EXIT_TERMINATED
