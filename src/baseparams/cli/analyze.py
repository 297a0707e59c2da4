"""``baseparams analyze MODEL``: the base-parameter analysis (a report, JSON, figures; a sweep over files).

Its flags are :func:`baseparams.analyze`'s keywords (``--no-verify`` is ``verify=False``,
``--paper-only`` ``extended=False``), the model's :func:`baseparams.load`'s.
"""

from __future__ import annotations

import json
import sys

from ..enums import Rows, Status
from ..errors import BaseparamsError, NoMovingBodiesError
from . import common
from .common import (
    EXIT_INPUT,
    EXIT_OK,
    STATUS_EXIT,
    Progress,
    data_files,
    emit,
    input_files,
    no_moving_bodies,
    write_html,
)
from .parser import choices, flag_message, flag_notes, model_args

#: the flags named otherwise than :func:`baseparams.analyze`'s keywords (both inverted: ``verify=False``)
KEYWORDS = {"no_verify": "verify", "paper_only": "extended"}
#: the flags that only say how the result is printed, or a sweep over files, or the symbolic analysis
CLI_ONLY = frozenset({"json", "verbose", "scheduler", "workers", "symbolic", "latex", "values", "codegen"})


def add_parser(sub) -> None:
    """The ``analyze`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command's subparsers.
    """
    s = sub.add_parser("analyze", help="base parameters of a robot (certified)")
    model_args(s)
    s.add_argument("--no-verify", action="store_true", help="skip the numerical certification")
    _analysis_choice_args(s)
    s.add_argument("--convention", metavar=choices("convention"), default="khalil",
                   help="convention of the regrouped expressions (default khalil)")
    s.add_argument("--form", metavar=choices("form"), default="auto",
                   help="how the regrouped expressions are written: expanded (standard parameters only), "
                        "recursive (a body's own parameters and its children's regrouped ones, e.g. link3.MR: "
                        "linear size on deep trees), auto (default: recursive for trees of 200 bodies or more)")
    s.add_argument("-v", "--verbose", action="store_true",
                   help="progress lines on stderr from the start (without -v they show once a run takes over 2 s)")
    s.add_argument("--output", metavar="FILE", help="write the report to FILE")
    s.add_argument("--html", metavar="FILE", help="a self-contained HTML report: the robot in 3D, each body's "
                                                  "parameters classed, the base parameters, the certification")
    s.add_argument("--plot", metavar="FILE", help="a static figure (PNG/SVG/PDF; matplotlib): the robot at q = 0, the "
                                                  "parameter grid by class, the singular values")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="MODEL a glob (a design sweep): a Dask scheduler (default: a local cluster)")
    s.add_argument("--workers", type=int, metavar="N", help="MODEL a glob: local cluster size")
    _symbolic_args(s)
    s.set_defaults(func=run)


def keywords(args) -> dict:
    """The flags as :func:`baseparams.analyze`'s keywords.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    dict
        ``samples``, ``seed``, ``verify``, ``extended``, ``rows``, ``convention``, ``literal``, ``form``.
    """
    return {"samples": args.samples, "seed": args.seed, "verify": not args.no_verify, "extended": not args.paper_only,
            "rows": args.rows, "convention": args.convention, "literal": args.literal, "form": args.form}


def run(args) -> int:
    """``baseparams analyze MODEL``: the base-parameter analysis, as a text report or JSON.

    Writes the report (:func:`~baseparams.analysis.format_report`, or
    :meth:`~baseparams.analysis.Analysis.to_json` with ``--json``) to stdout or ``--output``, made
    as it is written (:func:`~baseparams.analysis.report_lines`, :func:`~baseparams.analysis.json_chunks`);
    an undecided or failed certification is also one line on stderr.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`baseparams.cli.build_parser`): the model options and ``no_verify``,
        ``paper_only``, ``rows``, ``convention``, ``verbose``, ``output``.

    Returns
    -------
    int
        The exit code (module doc): :data:`EXIT_OK` for certified, completed or unverified
        (and a model without moving bodies), :data:`EXIT_UNDECIDED`, :data:`EXIT_FAILED`.

    Raises
    ------
    BaseparamsError
        Bad input (the model, the options, an unwritable ``--output``).
    """
    from ..analysis import analyze, json_chunks, report_lines, size_notes

    if any(ch in args.model for ch in "*?["):
        for opt in ("plot", "html", "symbolic"):
            if getattr(args, opt):
                raise BaseparamsError(f"--{opt} applies to one model, not to a sweep over files")
        return _analyze_sweep(args)
    if args.symbolic or args.latex or args.codegen:
        for opt in ("plot", "html"):
            if getattr(args, opt):
                raise BaseparamsError(f"--{opt} draws the numerical analysis: run it without --symbolic "
                                      f"(the table at its values)")
        if (args.latex or args.codegen) and not args.symbolic:
            raise BaseparamsError("--latex and --codegen need --symbolic")
        from .symbolic import analyze_symbolic

        return analyze_symbolic(args)
    try:
        robot = common.load_robot(args)
    except NoMovingBodiesError as exc:
        return no_moving_bodies(args, exc)
    with Progress(args.verbose) as progress:
        result = analyze(robot, **keywords(args), progress=progress)
        for note in size_notes(result):  # before the writing, which takes the time
            print(f"baseparams: {flag_message(note, 'analyze')}", file=sys.stderr)
        if args.html:
            from ..report.html import analysis_html

            progress("writing the HTML report")
            write_html(args.html, analysis_html(result), input_files(args))
        if args.plot:
            from ..report.plots import analysis_plot

            progress("drawing the figure")
            analysis_plot(result, args.plot, input_files(args), "plot=")
            print(f"baseparams: plot written to {args.plot}", file=sys.stderr)
    emit(args, json_chunks(result) if args.json else _pieces(flag_notes(x, "analyze") for x in report_lines(result)))
    status = result.status
    if status in (Status.UNDECIDED, Status.FAILED):
        why = flag_message(result.certificate.message, "analyze")
        print(f"baseparams: certification {status.upper()}: {why}", file=sys.stderr)
    return STATUS_EXIT[status]


def _pieces(lines):
    """Lines as consecutive pieces of one text (a newline between lines, none after the last)."""
    for i, line in enumerate(lines):
        yield ("\n" if i else "") + line


def _analyze_sweep(args) -> int:
    """``analyze 'models/*.urdf'``: every matching file on Dask, one line (or JSON object) each."""
    from ..sweep import analyze_fleet

    files = data_files(args.model)
    results = analyze_fleet(files, scheduler=getattr(args, "scheduler", None), workers=getattr(args, "workers", None),
                            floating=args.floating, convention=args.convention, rows=args.rows,
                            progress=(lambda line: print(f"baseparams: {line}", file=sys.stderr)) if args.verbose
                            else None)
    if args.json:
        emit(args, json.dumps(results, indent=2))
    else:
        emit(args, "\n".join(f"{r['path']}: error: {r['error']}" if "error" in r else
                              f"{r['path']}: {r['status']}, nullity {r['nullity']}, {r['n_base']} base parameters"
                              for r in results))
    statuses = [Status(r["status"]) for r in results if "error" not in r]
    if any("error" in r for r in results):
        return EXIT_INPUT
    return max((STATUS_EXIT[s] for s in statuses), default=EXIT_OK)


def _analysis_choice_args(s) -> None:
    """``analyze``'s options of what is analysed: the paper's principles only, the literal geometry, the rows."""
    s.add_argument("--paper-only", action="store_true",
                   help="the paper's three principles only (no extended rules R-A, R-B, R-L1, R-L2, R-M)")
    s.add_argument("--literal", action="store_true",
                   help="the model exactly as the file states it: by default geometry within 1e-3 of a right angle "
                        "or zero (rpy 3.1416, an axis 0 1e-5 1, a quat 0.707107 0 0.707107 0) is taken as that value "
                        "when it lowers the count (the directions it adds are not identifiable in practice; the "
                        "report names each value of the file), and a rank the singular-value gap cannot decide is "
                        "decided by each direction's effect on the torques (below 1e-6 of the torque scale: counted "
                        "out, when that threshold lies in a gap of the effects; else UNDECIDED with the clusters); "
                        "--literal leaves it UNDECIDED")
    s.add_argument("--rows", default=str(Rows.ALL), metavar="ROWS",
                   help="measured generalized forces: all (default); joints (joint torques only); base (the "
                        "floating base's wrench only); joints:NAME,NAME (only these joints' torques); "
                        "base+joints:NAME,... (the base wrench and these); passive:NAME,... (every row but "
                        "these joints': an under-actuated robot)")


def _symbolic_args(s) -> None:
    g = s.add_argument_group("symbolic geometry (MODEL a DH table .dh or a '*-symbolic' built-in; SymPy)")
    g.add_argument("--symbolic", action="store_true",
                   help="the base parameters as formulas in the table's symbols (lengths, offsets)")
    g.add_argument("--latex", action="store_true", help="with --symbolic: a LaTeX table of the formulas")
    g.add_argument("--codegen", metavar="FILE.py", help="with --symbolic: write Python (NumPy) code of the "
                                                        "regrouping K(dimensions)")
    g.add_argument("--values", nargs="+", metavar="NAME=NUMBER",
                   help="without --symbolic: numbers for the table's symbols (default: its 'values' line)")
