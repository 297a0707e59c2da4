"""Command-line front end: ``baseparams robots``, ``baseparams analyze MODEL``, ...

Errors in the user's input are printed as one line (``baseparams: error: ...``), exit 2.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from . import __version__
from .errors import BaseparamsError


def _robot(args) -> "Robot":  # noqa: F821
    from .io.load import load_model

    robot, notes = load_model(args.model, floating=getattr(args, "floating", False), gravity=args.gravity,
                              strict_inertia=getattr(args, "strict_inertia", False))
    for note in notes:
        print(f"baseparams: note: {note}", file=sys.stderr)
    return robot


def cmd_robots(args) -> int:
    from .robots import BUILTINS

    for name, (factory, text) in BUILTINS.items():
        r = factory()
        print(f"{name:<10s} {r.n:3d} bodies {r.dof:3d} dofs  {text}")
    return 0


def cmd_regressor(args) -> int:
    from .numerics import sample_states
    from .regressor import regressor

    robot = _robot(args)
    rng = np.random.default_rng(args.seed)
    args.samples = args.samples or 100
    q, dq, ddq = sample_states(robot, args.samples, rng)
    t0 = time.perf_counter()
    y = regressor(robot, q, dq, ddq)
    dt = time.perf_counter() - t0
    out = {"model": robot.name, "samples": args.samples, "shape": list(y.shape),
           "seconds": dt, "convention": "paper (spatial pseudo-inertia at q = 0)"}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{robot.name}: TP regressor {y.shape} (samples, dofs, 10 x bodies) in {dt * 1e3:.2f} ms; "
              f"columns: paper convention (spatial pseudo-inertia at q = 0)")
    return 0


def cmd_analyze(args) -> int:
    from .analysis import analyze, format_report

    robot = _robot(args)
    result = analyze(robot, samples=args.samples, seed=args.seed, verify=not args.no_verify,
                     extended=not args.paper_only, rows=args.rows, convention=args.convention,
                     progress=sys.stderr if args.verbose else None)
    text = json.dumps(result.to_json(), indent=2) if args.json else format_report(result)
    if args.output:
        with open(args.output, "w") as fh:
            fh.write(text + "\n")
        if not args.json:
            print(f"report written to {args.output}")
    else:
        print(text)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="baseparams", description=(
        "Which inertial parameters of a robot are identifiable (base parameters), why, and how "
        "they regroup: the tetrahedral-point model and DRNG, certified by exact numerics."))
    p.add_argument("--version", action="version", version=f"baseparams {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("robots", help="list the built-in robots")
    s.set_defaults(func=cmd_robots)

    def model_args(s):
        s.add_argument("model", help="built-in robot name (see 'baseparams robots') or a robot file: "
                                     "URDF / URDF+ (.urdf) or MJCF (.xml)")
        s.add_argument("--floating", action="store_true",
                       help="attach the file's root link to the world by a floating (free) joint")
        s.add_argument("--strict-inertia", action="store_true",
                       help="refuse files with physically infeasible inertias of moving links (by "
                            "default they are noted and the analysis goes on: the base-parameter "
                            "structure does not depend on the values)")
        s.add_argument("--allow-infeasible-inertia", action="store_true", help=argparse.SUPPRESS)
        s.add_argument("--gravity", nargs=3, type=float, metavar=("GX", "GY", "GZ"),
                       help="gravity in the world frame [m/s^2] (default: the model's, 0 0 -9.81)")
        s.add_argument("--samples", type=int, default=None,
                       help="random samples for the numerical method (default: 100 for trees, "
                            "5000 actuated samples for closed loops, as the paper)")
        s.add_argument("--seed", type=int, default=0, help="random seed")
        s.add_argument("--json", action="store_true", help="print one JSON object")

    s = sub.add_parser("analyze", help="base parameters of a robot (certified)")
    model_args(s)
    s.add_argument("--no-verify", action="store_true", help="skip the numerical certification")
    s.add_argument("--paper-only", action="store_true",
                   help="the paper's three principles only (no extended rules R-A, R-B, R-L1, R-L2)")
    s.add_argument("--rows", choices=("all", "joints", "base"), default="all",
                   help="measured generalized forces: all (default), joint torques only, or the "
                        "floating base's wrench only")
    s.add_argument("--convention", choices=("khalil", "paper", "pinocchio", "idyntree", "rpna"),
                   default="khalil", help="convention of the regrouped expressions (default khalil)")
    s.add_argument("-v", "--verbose", action="store_true", help="progress lines on stderr")
    s.add_argument("--output", metavar="FILE", help="write the report to FILE")
    s.set_defaults(func=cmd_analyze)

    s = sub.add_parser("regressor", help="compute the TP regressor on random samples")
    model_args(s)
    s.set_defaults(func=cmd_regressor)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "samples", None) is not None and args.samples < 1:
        parser.error("--samples must be at least 1")
    try:
        return args.func(args)
    except BaseparamsError as exc:
        print(f"baseparams: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. piped into head
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("baseparams: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
