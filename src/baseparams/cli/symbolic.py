"""``baseparams analyze TABLE --symbolic``: the base parameters as formulas (SymPy).

Imported by :func:`baseparams.cli.cmd_analyze` only when ``--symbolic`` is given.
"""

from __future__ import annotations

import json
import sys

from ..errors import BaseparamsError
from .common import EXIT_OK, Progress, emit, input_files, load_symbolic_table


def analyze_symbolic(args) -> int:
    """``analyze TABLE --symbolic [--json | --latex] [--codegen FILE]``: base parameters as formulas.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        :data:`~baseparams.cli.common.EXIT_OK`.
    """
    robot = load_symbolic_table(args)
    from ..symbolic import probe, symbolic_analysis
    from ..symbolic.analyze import TIME_LIMIT_S
    from ..symbolic.report import codegen, format_symbolic, symbolic_json, symbolic_latex

    with Progress(args.verbose) as progress:
        progress(f"{robot.name}: DRNG on the symbolic geometry, exact regrouping"
                 + ("" if args.no_verify else ", checks against the numerical analysis"))
        result = symbolic_analysis(robot, convention=args.convention, seed=args.seed, check=not args.no_verify,
                                   progress=progress, max_seconds=TIME_LIMIT_S)
        if not args.no_verify:
            progress(f"probing {len(result.conditions) + len(robot.symbols)} conditions")
            probe(result)
    if args.codegen:
        from ..files import write_text

        try:
            write_text(args.codegen, codegen(result), input_files(args), "--codegen")
        except OSError as exc:
            raise BaseparamsError(f"--codegen {args.codegen}: cannot write ({exc.strerror or exc})") from None
        print(f"baseparams: regrouping code written to {args.codegen}", file=sys.stderr)
    if args.json:
        emit(args, json.dumps(symbolic_json(result), indent=2))
    else:
        emit(args, symbolic_latex(result) if args.latex else format_symbolic(result))
    return EXIT_OK
