"""Command-line front end: ``baseparams robots``, ``baseparams analyze MODEL``, ...

Exit codes (scripts rely on them): 0 the result is certified (or completed, or unverified on
request with ``--no-verify``); 2 bad input, printed as one line (``baseparams: error: ...``);
3 certification UNDECIDED (no gap of the spectrum decides the rank: the message lists the clusters,
the candidate counts and what would help; a gap too small to decide literally is decided by
practical identifiability, at a gap of the directions' effects, unless ``--literal``);
4 certification FAILED (a DRNG column is not in the numerical nullspace); 130 interrupted.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import time
from pathlib import Path

import numpy as np

from ..arguments import CHOICES, IDENTIFY
from ..enums import Convention, MocapWelds, Rows, Status, values
from ..errors import BaseparamsError, NoMovingBodiesError
from ..workflow import Inputs
from . import common
from .common import (
    EXIT_FAILED,
    EXIT_INPUT,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_UNDECIDED,
    STATUS_EXIT,
    Progress,
    data_files,
    emit,
    floating_hint,
    input_files,
    is_symbolic,
    no_moving_bodies,
    write_html,
    write_output,
)

__all__ = ["EXIT_FAILED", "EXIT_INPUT", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_UNDECIDED", "Progress", "build_parser",
           "cmd_analyze", "cmd_excite", "cmd_identify", "cmd_predict", "cmd_regressor", "cmd_robots", "cmd_simulate",
           "floating_hint", "main", "preflight"]


def cmd_robots(args) -> int:
    """``baseparams robots``: list the built-in robots, one line each (bodies, dofs, description).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (unused: the command takes no options).

    Returns
    -------
    int
        The exit code, 0.
    """
    from ..robots import BUILTINS

    for name, (factory, text) in BUILTINS.items():
        r = factory()
        print(f"{name:<10s} {r.n:3d} bodies {r.dof:3d} dofs  {text}")
    try:
        from ..symbolic import builtin_tables, load_symbolic
    except ImportError:
        print("(symbolic robots: install the extra 'symbolic' (SymPy) to list them)")
        return 0
    print("\nsymbolic geometry ('baseparams analyze NAME --symbolic'; without --symbolic: at the listed values):")
    for name, text in builtin_tables().items():
        r = load_symbolic(name)
        print(f"{name:<24s} {r.n:3d} bodies  {text}")
    return 0


def cmd_regressor(args) -> int:
    """``baseparams regressor MODEL``: time the TP regressor on random states (or ``--states FILE``).

    With ``--states FILE`` the states come from a file (``q_``, ``dq_``, ``ddq_<joint>`` columns,
    the log or the excite layout) and ``--out`` saves the regressor ``(S, m, 10 n)``: NPZ arrays
    ``Y`` (that shape), ``columns`` (parameter names), ``joints``, ``t``; CSV/TSV/Parquet one row
    per (sample, joint), columns ``sample, joint`` and one per parameter (row ``s * m + j`` is
    ``Y[s, j]``).

    For a robot with loops, the closed-loop regressor with respect to its independent (actuated)
    coordinates on loop-closed samples. Prints its shape and time (or one JSON object with
    ``--json``); columns in the ``paper`` convention (spatial pseudo-inertia at q = 0).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`build_parser`): ``model``, ``floating``, ``gravity``,
        ``strict_inertia``, ``samples`` (default 100), ``seed``, ``json``, ``states``, ``out``.

    Returns
    -------
    int
        The exit code: :data:`EXIT_OK` (also for a model without moving bodies).

    Raises
    ------
    BaseparamsError
        Bad input, or no sample closes the loops.
    """
    from ..numerics import closed_samples, sample_states
    from ..regressor import closed_regressor, regressor

    if args.out and not args.states:
        raise BaseparamsError("--out saves the regressor of --states FILE; give the states")
    try:
        robot = common.load_robot(args)
    except NoMovingBodiesError as exc:
        return no_moving_bodies(args, exc)
    if args.states:
        return _regressor_states(args, robot)
    rng = np.random.default_rng(args.seed)
    args.samples = args.samples or 100
    t0 = time.perf_counter()
    extra = ""
    if robot.has_loops:
        cs = closed_samples(robot, args.samples, rng)
        if cs.kept == 0:
            raise BaseparamsError(f"robot {robot.name!r}: none of {args.samples} samples closed the loops; check "
                                  f"the independent joints' limits")
        y = closed_regressor(robot, cs)
        kept = cs.kept
        extra = (f"; loops closed: {kept} of {args.samples} samples kept ({cs.not_converged} outside the "
                 f"workspace, {cs.branch_jumps} off the reference branch or past a singular configuration, "
                 f"{cs.ill_conditioned} ill-conditioned)")
        rows = f"{len(robot.actuated)} actuated coordinates"
    else:
        q, dq, ddq = sample_states(robot, args.samples, rng)
        y = regressor(robot, q, dq, ddq)
        kept = args.samples
        rows = f"{robot.dof} dofs"
    dt = time.perf_counter() - t0
    out = {"model": robot.name, "samples": args.samples, "kept": kept, "shape": list(y.shape),
           "closed_loops": robot.has_loops, "seconds": dt, "convention": "paper (spatial pseudo-inertia at q = 0)"}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{robot.name}: TP regressor {y.shape} (samples, {rows}, 10 x bodies) in {dt * 1e3:.2f} ms; "
              f"columns: paper convention (spatial pseudo-inertia at q = 0){extra}")
    return EXIT_OK


def cmd_analyze(args) -> int:
    """``baseparams analyze MODEL``: the base-parameter analysis, as a text report or JSON.

    Writes the report (:func:`~baseparams.analysis.format_report`, or
    :meth:`~baseparams.analysis.Analysis.to_json` with ``--json``) to stdout or ``--output``;
    an undecided or failed certification is also one line on stderr.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`build_parser`): the model options and ``no_verify``,
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
    from ..analysis import analyze, format_report

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
        result = analyze(robot, samples=args.samples, seed=args.seed, verify=not args.no_verify,
                         extended=not args.paper_only, rows=args.rows, convention=args.convention, progress=progress,
                         literal=args.literal, form=args.form)
        text = json.dumps(result.to_json(), indent=2) if args.json else format_report(result)
        if args.html:
            from ..report.html import analysis_html

            progress("writing the HTML report")
            write_html(args.html, analysis_html(result), input_files(args))
        if args.plot:
            from ..report.plots import analysis_plot

            progress("drawing the figure")
            write_output(args.plot, lambda tmp: analysis_plot(result, tmp), args, "--plot")
            print(f"baseparams: plot written to {args.plot}", file=sys.stderr)
    emit(args, text)
    status = result.status
    if status in (Status.UNDECIDED, Status.FAILED):
        print(f"baseparams: certification {status.upper()}: {result.certificate.message}", file=sys.stderr)
    return STATUS_EXIT[status]


def lazy_command(module: str, name: str, usage: str):
    """A command's handler that imports ``baseparams.cli.<module>`` only when the command runs.

    Parameters
    ----------
    module : str
        The submodule holding the handler (``identify``, ``simulate``, ``excite``).
    name : str
        The handler's name there.
    usage : str
        The command line it serves, for its docstring.

    Returns
    -------
    callable
        ``run(args: argparse.Namespace) -> int``: the handler's exit code.
    """

    def run(args) -> int:
        return getattr(importlib.import_module(f"{__name__}.{module}"), name)(args)

    run.__name__ = run.__qualname__ = name
    run.__doc__ = (f"``{usage}``: :func:`{__name__}.{module}.{name}`, imported when it runs.\n\n"
                   "    Parameters\n    ----------\n    args : argparse.Namespace\n        The parsed command line.\n\n"
                   "    Returns\n    -------\n    int\n        The exit code.\n    ")
    return run


cmd_identify = lazy_command("identify", "cmd_identify", "baseparams identify MODEL DATA")
cmd_predict = lazy_command("identify", "cmd_predict", "baseparams predict MODEL RESULT LOG")
cmd_simulate = lazy_command("simulate", "cmd_simulate", "baseparams simulate MODEL OUT")
cmd_excite = lazy_command("excite", "cmd_excite", "baseparams excite MODEL")


def _predict_parser(sub, model_args) -> None:
    """The ``predict`` subcommand's arguments."""
    s = sub.add_parser("predict", help="predict joint torques of a log from a saved identification (identify --save); "
                                       "from currents: the joint-side torques and the motors' currents")
    model_args(s)
    s.add_argument("result", help="the saved identification (RESULT.json from 'identify --save')")
    s.add_argument("log", help="the log or trajectory: t, q_<joint>, [dq_<joint>, ddq_<joint>], [tau_<joint>] "
                               "(CSV/TSV, NPZ, Parquet, a ROS 2 bag); rates it lacks are derived as identify does")
    s.add_argument("--columns", metavar="MAP", help="a TOML mapping file for any other layout (or a bag's topic)")
    s.add_argument("--out", metavar="FILE", help="write t, tau_<joint> per log sample (.csv, .tsv or .parquet); a "
                                                 "result from currents: also cur_<joint> [A]")
    s.add_argument("--raw-states", action="store_true",
                   help="the model's torques on the states as logged (default: on the states low-passed at the "
                        "identification's cutoff, as it was fitted)")
    s.add_argument("--score-cutoff", type=float, metavar="HZ",
                   help="also score against the measured torques low-passed at HZ (zero-phase Butterworth order 4)")
    s.add_argument("--allow-units", action="store_true",
                   help="go on when the log's states look in other units (deg, deg/s, rpm, ms, us, ns); refused "
                        "otherwise")
    s.set_defaults(func=cmd_predict)


def _regressor_states(args, robot) -> int:
    """``regressor MODEL --states FILE [--out FILE]``: the TP regressor of given states, saved."""
    from ..analysis import regressor
    from ..base.regroup import parameter_names
    from ..io.logs import read_log
    from ..tables import check_table_path, write_columns

    check_table_path(args.out, input_files(args), "--out")
    if robot.floating:
        raise BaseparamsError(f"--states: robot {robot.name!r} has a floating base, whose coordinates are not "
                              f"columns of a states file; use baseparams.regressor in Python")
    coords = robot.measured_coords
    joints = robot.coordinate_names(coords)
    log = read_log(args.states, robot, allow_subset=True, require_tau=False, require_time=False)
    missing = [j for j in joints if j not in log.joints]
    if missing:
        raise BaseparamsError(f"--states {args.states}: no q_ columns for {missing} (states need q_<joint>, and "
                              f"dq_, ddq_ or a time column t, for the {'actuated ' if robot.has_loops else ''}joints "
                              f"{joints})")
    q, dq, ddq = log.q, log.dq, log.ddq
    if dq is None or ddq is None:  # rates the file lacks: derived as identify derives them (needs time)
        from ..ident.preprocess import log_states

        if log.t is None or not np.all(np.isfinite(log.t)):
            raise BaseparamsError(f"--states {args.states}: no {'dq_ and ' if dq is None else ''}ddq_ columns and no "
                                  "time column t to derive them from")
        q, dq, ddq, notes = log_states(log, None)
        for note in notes[1:]:
            print(f"baseparams: note: {note}", file=sys.stderr)
    cols = [log.joints.index(j) for j in joints]
    t0 = time.perf_counter()
    y = regressor(robot, q[:, cols], dq[:, cols], ddq[:, cols])
    dt = time.perf_counter() - t0
    names = parameter_names(robot, "paper")
    if args.out:
        if Path(args.out).suffix.lower() == ".npz":
            write_columns(args.out, {"Y": y, "columns": np.array(names), "joints": np.array(joints), "t": log.t},
                          input_files(args))
        else:
            s, m, p = y.shape
            table = {"sample": np.repeat(np.arange(s), m), "joint": np.tile(np.array(joints), s)}
            table.update({n: y[:, :, k].reshape(-1) for k, n in enumerate(names)})
            write_columns(args.out, table, input_files(args))
    out = {"model": robot.name, "states": args.states, "samples": int(y.shape[0]), "shape": list(y.shape),
           "seconds": dt, "out": args.out, "convention": "paper (spatial pseudo-inertia at q = 0)"}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{robot.name}: TP regressor {y.shape} (samples, joints, 10 x bodies) of {args.states} in "
              f"{dt * 1e3:.2f} ms" + (f", written to {args.out}" if args.out else ""))
    return EXIT_OK


def _regressor_args(s) -> None:
    """``regressor``'s ``--states`` and ``--out`` (and its function)."""
    s.set_defaults(func=cmd_regressor)
    s.add_argument("--states", metavar="FILE",
                   help="states from a file (CSV/TSV, NPZ, Parquet: q_<joint>, dq_<joint>, ddq_<joint>, as a log or "
                        "'excite --out'; loops: the actuated joints) instead of random samples")
    s.add_argument("--out", metavar="FILE", help="with --states: save the regressor: .npz (Y (S, m, 10 n), columns, "
                                                 "joints, t) or .csv/.tsv/.parquet (one row per sample and joint: "
                                                 "sample, joint, one column per parameter)")


def _ident_args(s) -> None:
    """Options shared by ``identify`` and ``simulate``."""
    s.add_argument("--friction", default=",".join(IDENTIFY["friction"]),
                   help="friction terms per joint: any of viscous, coulomb, offset, comma-separated, or none "
                        "(default all three)")
    s.add_argument("--rotor", action="store_true", help="model each joint's rotor inertia Ia (MJCF armature)")
    s.add_argument("--convention", choices=values(Convention), default=str(Convention.KHALIL),
                   help="convention of the base parameters' names and values (default khalil)")


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


def _mocap_args(s: argparse.ArgumentParser) -> None:
    """``--mocap-welds {drop,keep}``: an MJCF file's welds and connects to mocap bodies left out or kept."""
    s.add_argument("--mocap-welds", choices=values(MocapWelds), default=str(MocapWelds.DROP),
                   help="MJCF: the welds and connects to mocap bodies, control devices the simulation moves "
                        "(Meta-World's and Fetch's hands): drop (default: left out, with a note) or keep (loop "
                        "joints to the world)")
    s.add_argument("--drop-mocap-welds", dest="mocap_welds", action="store_const", const=str(MocapWelds.DROP),
                   help=argparse.SUPPRESS)  # the previous flag: now the default


class _Parser(argparse.ArgumentParser):
    """argparse's parser whose errors are one line, as every other error (``baseparams: error: ...``, exit 2)."""

    def error(self, message: str):
        """Print the error on one line (``--help`` shows the usage) and exit 2.

        Parameters
        ----------
        message : str
            argparse's message (``argument --starts: invalid int value: '1.5'``).
        """
        prog = self.prog.split(" ", 1)[1] + " " if " " in self.prog else ""
        self.exit(2, f"baseparams: error: {prog}{message} (see {self.prog} --help)\n")


class _Version(argparse.Action):
    """``--version``: the version looked up when asked for (:func:`baseparams.version.version`), not at start-up."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        from ..version import version

        print(f"baseparams {version()}")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``baseparams`` command.

    Returns
    -------
    argparse.ArgumentParser
        Subcommands ``robots``, ``analyze``, ``regressor``, ``identify``, ``predict``, ``simulate`` and
        ``excite``; each sets ``func`` to its ``cmd_*`` function.
    """
    p = _Parser(prog="baseparams", description=(
        "Which inertial parameters of a robot are identifiable (base parameters), why, and how "
        "they regroup: the tetrahedral-point model and DRNG, certified by exact numerics."))
    p.add_argument("--version", action=_Version, help="show program's version number and exit")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("robots", help="list the built-in robots")
    s.set_defaults(func=cmd_robots)

    def model_args(s):
        s.add_argument("model", help=MODEL_HELP[s.prog.split()[-1]])
        s.add_argument("--floating", action="store_true",
                       help="attach the file's root link to the world by a floating (free) joint")
        s.add_argument("--strict-inertia", action="store_true",
                       help="refuse files with physically infeasible inertias of moving links (by "
                            "default they are noted and the analysis goes on: the base-parameter "
                            "structure does not depend on the values)")
        s.add_argument("--allow-infeasible-inertia", action="store_true", help=argparse.SUPPRESS)
        _mocap_args(s)
        s.add_argument("--gravity", nargs=3, type=float, metavar=("GX", "GY", "GZ"),
                       help="gravity in the world frame [m/s^2] (default: the model's, 0 0 -9.81)")
        _xacro_args(s)
        _samples_args(s)
        s.add_argument("--seed", type=int, default=0, help="random seed")
        s.add_argument("--json", action="store_true", help="print one JSON object")

    s = sub.add_parser("analyze", help="base parameters of a robot (certified)")
    model_args(s)
    s.add_argument("--no-verify", action="store_true", help="skip the numerical certification")
    _analysis_choice_args(s)
    s.add_argument("--convention", choices=values(Convention),
                   default=str(Convention.KHALIL), help="convention of the regrouped expressions (default khalil)")
    s.add_argument("--form", choices=("auto", "expanded", "recursive"), default="auto",
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
    s.set_defaults(func=cmd_analyze)

    s = sub.add_parser("regressor", help="compute the TP regressor on random samples (or --states FILE)")
    model_args(s)
    _regressor_args(s)
    _identify_parser(sub, model_args)
    _predict_parser(sub, model_args)
    _simulate_parser(sub, model_args)
    _excite_parser(sub, model_args)
    return p


#: each subcommand's help for its MODEL argument
_MODEL_FILES = ("built-in robot name (see 'baseparams robots') or a robot file: URDF / URDF+ (.urdf), ROS xacro "
                "(.xacro) or MJCF (.xml)")


MODEL_HELP = {
    "analyze": f"{_MODEL_FILES}, or a DH table (.dh, '*-symbolic'); a glob pattern ('models/*.urdf') runs a sweep "
               "over many files on Dask",
    "regressor": f"{_MODEL_FILES}: the robot whose TP regressor is computed",
    "identify": f"{_MODEL_FILES}: the robot the log was recorded on (--urdf needs a .urdf file, --mjcf a file)",
    "predict": f"{_MODEL_FILES}: the robot the saved identification belongs to (its fingerprint is checked)",
    "simulate": f"{_MODEL_FILES}: the robot simulated (its own inertias are the true parameters)",
    "excite": f"{_MODEL_FILES}: the robot (its joint limits are read from the file)",
}


#: the subcommands whose ``--samples`` was renamed ``--analysis-samples`` (it reads as log samples there)
RENAMED_SAMPLES = ("identify", "predict", "simulate", "excite")


def _xacro_args(s) -> None:
    """``--xacro-arg`` and ``--package-path``: a .xacro model's arguments and ROS packages."""
    s.add_argument("--xacro-arg", action="append", dest="xacro_args", metavar="NAME:=VALUE",
                   help="an argument of a .xacro model (repeatable)")
    s.add_argument("--package-path", action="append", metavar="DIR",
                   help="a folder of ROS packages for a .xacro model's $(find PKG) and package:// (repeatable; "
                        "then BASEPARAMS_PACKAGE_PATH and ROS_PACKAGE_PATH, os.pathsep-separated)")


def _samples_args(s) -> None:
    """``--samples`` (analyze, regressor) or ``--analysis-samples`` (identify, simulate, excite)."""
    if s.prog.split()[-1] not in RENAMED_SAMPLES:
        s.add_argument("--samples", type=int, default=None,
                       help="random samples for the numerical method (default: 100 for trees, "
                            "5000 actuated samples for closed loops, as the paper)")
        return
    s.add_argument("--analysis-samples", dest="samples", type=int, default=None, metavar="N",
                   help="random states of the base-parameter analysis the model is built on (default: 100 for "
                        "trees, 5000 actuated samples for closed loops); not the log's samples")
    s.add_argument("--samples", dest="old_samples", type=int, default=None, help=argparse.SUPPRESS)


def _identify_parser(sub, model_args) -> None:
    """The ``identify`` subcommand's arguments."""
    s = sub.add_parser("identify", help="identify base-parameter and drive values from a joint log")
    model_args(s)
    s.add_argument("data", help="the log: CSV/TSV, NPZ, Parquet or a ROS 2 bag (JointState); default layout: "
                                "t, q_<joint>, [dq_<joint>, ddq_<joint>], tau_<joint>; a glob pattern for "
                                "several logs (a fleet, on Dask)")
    s.add_argument("--columns", metavar="MAP", help="a TOML mapping file for any other layout (or a bag's topic)")
    held = s.add_mutually_exclusive_group()
    held.add_argument("--validate", metavar="DATA2", help="validate on another log")
    held.add_argument("--holdout", type=float, metavar="SECONDS", help="validate on the log's last SECONDS")
    s.add_argument("--method", choices=CHOICES["method"], default=IDENTIFY["method"],
                   help="auto (default): least squares with the model file's parameters as a prior (terms the data "
                        "determine keep their fitted values), the weighting and the prior's weight chosen by blocked "
                        "cross-validation on the training data; ols, wls (per-joint noise) or physical (physically "
                        "consistent) least squares")
    _ident_args(s)
    _model_class_args(s)
    s.add_argument("--coupling", action="append", metavar="NAME:JOINT=W,JOINT=W",
                   help="a motor driving several joints (coupled wrist): its velocity is sum W dq_JOINT, its torque "
                        "reaches each JOINT times W; adds Iam_NAME, Fvm_NAME, Fcm_NAME (with --rotor, viscous, "
                        "coulomb); repeatable")
    s.add_argument("--effort", choices=CHOICES["effort"], default=IDENTIFY["effort"],
                   help="what the log's effort is: torque (tau_<joint>), current (cur_<joint> [A]: motor currents "
                        "with unknown gains, identified with the parameters; their common scale from --gain-anchor), "
                        "or auto (default: currents when the log has them and no torques)")
    s.add_argument("--gain-anchor", metavar="JOINT=K[,JOINT=K]",
                   help="currents: the catalogue gain K [N m/A at the joint side] of JOINT's motor, fixing every "
                        "gain's scale (several: their geometric mean); default the model file's masses")
    s.add_argument("--cutoff", type=float, metavar="HZ", help="low-pass cutoff (default from the sampling rate)")
    s.add_argument("--decimate", type=int, metavar="K", help="keep every K-th sample after filtering")
    s.add_argument("--min-speed", type=float, metavar="V", help="drop samples where a joint is slower than V rad/s")
    s.add_argument("--prior-weight", type=float, metavar="W", help="physical: weight of the file's inertias")
    s.add_argument("--joints", metavar="A,B,...",
                   help="identify only these joints; every other joint is welded (at its logged position if it "
                        "does not move, at --weld, or at 0)")
    s.add_argument("--weld", action="append", metavar="JOINT=VALUE",
                   help="with --joints: weld JOINT at VALUE (rad or m); repeatable")
    s.add_argument("--allow-units", action="store_true",
                   help="go on when the log's units look wrong (deg/s, ms, mN m, absurd samples); refused otherwise")
    s.add_argument("--covariance", choices=CHOICES["covariance"], default=IDENTIFY["covariance"],
                   help="standard deviations: hac (default; Newey-West, true when residuals are correlated) or "
                        "white (the least-squares formula, residuals taken as uncorrelated)")
    s.add_argument("--score-cutoff", type=float, metavar="HZ",
                   help="validation: also score against the measured torques low-passed at HZ (zero-phase "
                        "Butterworth order 4); the main figure is against the raw measured torques")
    s.add_argument("--predictions", metavar="FILE",
                   help="write the predicted torques at every validation sample (t, tau_<joint>; .csv, .tsv or "
                        ".parquet)")
    _log_size_args(s)
    s.add_argument("--plot", metavar="FILE", help="measured vs predicted torques per joint (PNG/SVG; matplotlib)")
    s.add_argument("--html", metavar="FILE", help="a self-contained HTML report: torques, residuals, values, %%sigma")
    _export_args(s)
    s.add_argument("--save", metavar="RESULT.json", help="save the result (values, std, options, the model's "
                                                         "fingerprint) for 'baseparams predict'")
    s.add_argument("--truth", metavar="TRUTH.json", help="compare with the true parameters of 'baseparams simulate' "
                                                         "(OUT.truth.json): true, estimate, error, z per term")
    s.add_argument("-v", "--verbose", action="store_true",
                   help="progress lines on stderr from the start (without -v they show once a run takes over 2 s)")
    s.add_argument("--output", metavar="FILE", help="write the report to FILE")
    s.set_defaults(func=cmd_identify)


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


def _model_class_args(s) -> None:
    """``identify``'s options of the model class: smooth Coulomb, model terms, the literal geometry."""
    s.add_argument("--coulomb-width", type=float, metavar="W", help="smooth Coulomb friction tanh(dq / W) [rad/s]")
    s.add_argument("--terms", default=IDENTIFY["terms"], metavar="TERMS",
                   help="model terms beyond rigid bodies and linear friction: auto (default: pre-sliding friction "
                        "'dahl', mounting 'tilt', per-joint 'delay', torque-sensor 'scale', each kept when blocked "
                        "cross-validation on the training data says so; the report lists every one kept or "
                        "rejected and why), none (the linear model alone), or names to force (dahl,tilt; add auto "
                        "to also try the others)")
    s.add_argument("--literal", action="store_true",
                   help="the model exactly as the file states it (analyze --literal): by default geometry within "
                        "1e-3 of a right angle or zero is taken as that value when the directions it adds are not "
                        "identifiable in practice, and those directions are not fitted")


def _log_size_args(s) -> None:
    """``identify``'s options for long logs (streamed) and many logs (a fleet on Dask)."""
    s.add_argument("--stream", choices=("auto", "on", "off"), default=Inputs.stream,
                   help="read a CSV/TSV/Parquet log block by block, in memory independent of its length, with the "
                        "same result: auto (default) above 64 MB, on, off (read it whole)")
    s.add_argument("--per-file", action="store_true",
                   help="several logs (a glob such as 'logs/robot-*/*.parquet'): one estimate per log and the "
                        "spread across them, on Dask")
    s.add_argument("--pooled", action="store_true", help="several logs: one estimate from all of them, on Dask")
    s.add_argument("--strict", action="store_true",
                   help="several logs: exit 2 when any log was skipped (default: report it, go on with the rest)")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="a Dask scheduler (default DASK_SCHEDULER_ADDRESS, else a local cluster for this run)")
    s.add_argument("--workers", type=int, metavar="N", help="local cluster size (default: one per core)")


def _export_args(s) -> None:
    """``identify --urdf`` and ``--mjcf``: the model file written back with the identified values."""
    s.add_argument("--urdf", metavar="FILE", help="physical: write the model with the identified inertias")
    s.add_argument("--mjcf", metavar="FILE", help="physical: write the MJCF or URDF model as MJCF (through MuJoCo's "
                                                  "MjSpec) with the identified inertias, armature, damping and "
                                                  "frictionloss, checked by MuJoCo's inverse dynamics")


def _simulate_parser(sub, model_args) -> None:
    """The ``simulate`` subcommand's arguments."""
    s = sub.add_parser("simulate", help="write a synthetic joint log with known parameters (tests, demos)")
    model_args(s)
    s.add_argument("out", help="output log (.csv or .npz); the true parameters go to OUT.truth.json")
    s.add_argument("--duration", type=float, default=20.0, help="seconds (default 20)")
    s.add_argument("--rate", type=float, default=500.0, help="sampling rate in Hz (default 500)")
    s.add_argument("--amplitude", type=float, default=None,
                   help="joint excursion in rad (default 0.5; for a robot with loops the largest of 0.8, 0.4, 0.2, "
                        "0.1 x its sampling box's half-width whose loops close)")
    s.add_argument("--noise", type=float, default=0.0, help="torque noise standard deviation (default 0)")
    s.add_argument("--robots", type=int, metavar="N",
                   help="a fleet: N logs in the folder OUT, one robot each with its own inertias (10 %% spread)")
    s.add_argument("--trajectory", metavar="FILE", help="simulate this trajectory (t, q_, dq_, ddq_ columns: "
                                                        "'baseparams excite --out') instead of a random one")
    _ident_args(s)
    s.set_defaults(func=cmd_simulate)


def _excite_parser(sub, model_args) -> None:
    """The ``excite`` subcommand's arguments."""
    s = sub.add_parser("excite", help="design an excitation trajectory (Fourier series within the joint limits)")
    model_args(s)
    s.add_argument("--harmonics", type=int, default=5, help="harmonics per joint (default 5)")
    per = s.add_mutually_exclusive_group()
    per.add_argument("--period", type=float, metavar="SECONDS", help="period of the trajectory (default 10 s)")
    per.add_argument("--base-frequency", type=float, metavar="HZ", help="base frequency (1 / period)")
    s.add_argument("--rate", type=float, default=1000.0, help="the controller's sampling rate in Hz (default 1000)")
    s.add_argument("--criterion", choices=("cond", "logdet"), default="cond",
                   help="minimise the condition number of the column-scaled regressor (default), or maximise "
                        "log det of the information matrix (D-optimal: smaller standard deviations under noise)")
    s.add_argument("--drives", action="store_true", help="include the friction columns (viscous, Coulomb, offset)")
    s.add_argument("--rotor", action="store_true", help="with --drives: the rotor inertia columns too")
    lim = s.add_argument_group("limits (each: one value for every joint, one per designed joint in order, or "
                               "JOINT=VALUE,...; the model file's where not given)")
    lim.add_argument("--position", metavar="LO:HI[,...]",
                     help="position limits in rad or m (a value starting with '-' after '=': --position=-1.5:1.5)")
    lim.add_argument("--velocity", metavar="V[,...]", help="velocity limits in rad/s or m/s")
    lim.add_argument("--acceleration", metavar="A[,...]", help="acceleration limits in rad/s^2 or m/s^2 (default none)")
    lim.add_argument("--effort", metavar="E[,...]", help="effort limits in N m or N (with --torque)")
    s.add_argument("--torque", action="store_true", help="keep the model's own torques within the effort limits")
    s.add_argument("--keepout", metavar="LINK:Z", action="append",
                   help="keep LINK's frame origin at or above the height Z [m, world z] at every sample (a floor or a "
                        "table; repeatable, one per link; link geometry and self-collision are not checked)")
    s.add_argument("--margin", type=float, default=0.0, metavar="FRACTION",
                   help="keep this fraction of each joint's position range free at both ends (0.05: 5 %% of the "
                        "range from each limit; default 0)")
    s.add_argument("--starts", type=int, default=4, help="random starts of the optimisation (default 4)")
    s.add_argument("--grid", type=int, default=200, help="samples per period while optimising (default 200)")
    s.add_argument("--out", metavar="FILE", help="write the trajectory (CSV: t, q_, dq_, ddq_ per joint)")
    s.add_argument("--plot", metavar="FILE", help="plot q, dq, ddq per joint against the limits (PNG/SVG)")
    s.add_argument("--output", metavar="FILE", help="write the summary to FILE")
    s.set_defaults(func=cmd_excite)


#: the optional modules a flag needs, and the extra that installs each
EXTRAS = {"matplotlib": "plot", "cvxpy": "ident", "clarabel": "ident", "pyarrow": "parquet", "rosbags": "ros",
          "dask": "fleet", "distributed": "fleet", "sympy": "symbolic", "xacro": "xacro"}


#: the figure formats ``--plot`` writes (matplotlib's, by suffix)
PLOT_SUFFIXES = (".png", ".svg", ".svgz", ".pdf", ".eps", ".ps", ".jpg", ".jpeg", ".tif", ".tiff", ".webp", ".pgf")


def _need(module: str, why: str) -> None:
    """Raise a one-line error when an optional module is missing (checked by importing it)."""
    import importlib

    try:
        importlib.import_module(module)
    except ImportError:
        raise BaseparamsError(f"{why} needs {module}: pip install 'baseparams[{EXTRAS[module]}]'") from None


def _outputs(args) -> list[tuple[str, str, tuple[str, ...] | None]]:
    """The run's output files: ``(flag, path, allowed suffixes or None)``."""
    cmd = args.command
    out = [("--output", getattr(args, "output", None), None), ("--html", getattr(args, "html", None), None),
           ("--plot", getattr(args, "plot", None), PLOT_SUFFIXES), ("--urdf", getattr(args, "urdf", None), None),
           ("--mjcf", getattr(args, "mjcf", None), (".xml",)), ("--codegen", getattr(args, "codegen", None), None)]
    if cmd == "identify":
        out.append(("--predictions", args.predictions, (".csv", ".tsv", ".parquet", ".pq")))
        out.append(("--save", args.save, None))
    if cmd == "excite":
        out.append(("--out", args.out, (".csv", ".tsv")))
    if cmd == "simulate" and not args.robots:
        out += [("OUT", args.out, (".csv", ".tsv", ".npz")), ("OUT.truth.json", f"{args.out}.truth.json", None)]
    return [(flag, path, suffixes) for flag, path, suffixes in out if path]


def _check_output(flag: str, path: str, suffixes, inputs: list[str]) -> None:
    """One output path: a known suffix, an existing folder, not a folder itself, not an input (links resolved)."""
    from ..files import check_output

    p = Path(path)
    if suffixes and p.suffix.lower() not in suffixes:
        raise BaseparamsError(f"{flag} {path}: the format comes from the suffix: {', '.join(suffixes)}, "
                              f"not {p.suffix or 'none'}")
    check_output(p, inputs, flag)


def _check_extras(args) -> None:
    """The optional modules the flags need, before any work."""
    cmd = args.command
    if getattr(args, "plot", None):
        _need("matplotlib", "--plot")
    model = getattr(args, "model", None)
    if model and is_symbolic(model) or getattr(args, "symbolic", False):
        _need("sympy", "a symbolic robot (DH table)")
    if model and Path(model).suffix.lower() == ".xacro":
        _need("xacro", f"{model}: a xacro model")
    if cmd == "analyze" and model and any(ch in model for ch in "*?["):
        _need("distributed", "a sweep over files (a glob MODEL)")
    if cmd != "identify":
        return
    if args.method == "physical":
        _need("cvxpy", "--method physical")
        _need("clarabel", "--method physical")
    files = data_files(args.data) + ([args.validate] if args.validate else [])
    if len(files) > 1 + bool(args.validate) or args.per_file or args.pooled:
        _need("distributed", "identification over several logs (a fleet)")
    for f in files:
        suffix = Path(f).suffix.lower()
        if suffix in (".parquet", ".pq"):
            _need("pyarrow", f"{f}: reading Parquet")
        elif suffix in (".mcap", ".db3", ".bag") or Path(f).is_dir():
            _need("rosbags", f"{f}: reading a ROS bag")


def _check_flags(args) -> None:
    """Flags that cannot be honoured, before any work (a fit, an optimisation, a file)."""
    if getattr(args, "old_samples", None) is not None:
        print(f"baseparams: note: {args.command} --samples is deprecated: it is --analysis-samples (the random states "
              f"of the base-parameter analysis, not log samples)", file=sys.stderr)
        if args.samples is None:
            args.samples = args.old_samples
    from ..arguments import check_namespace, check_samples, check_total

    check_namespace(args)  # every numeric flag in its range, named (baseparams.arguments.RANGES)
    if args.command == "simulate" and not args.trajectory:
        per_log = args.duration * args.rate
        check_samples(per_log, 16, "--duration x --rate")
        if args.robots:
            check_total(args.robots * per_log, "--robots x --duration x --rate")
    if args.command == "excite":
        period = args.period if args.period is not None else 1.0 / (args.base_frequency or 0.1)
        check_samples(period * args.rate, 16, f"{'--period' if args.period else '--base-frequency'} and --rate "
                                              f"(one period at the rate)")
    if args.command == "identify" and args.joints is not None and not [j for j in args.joints.split(",") if j.strip()]:
        raise BaseparamsError("--joints needs joint names: --joints A,B,... (the joints to identify)")
    if args.command == "identify":
        from .identify import options_of

        options_of(args)  # every option of the identification checked, named as flags (IdentOptions)
    if args.command == "identify" and (args.urdf or args.mjcf):
        from ..workflow import check_exports

        check_exports(args.model, args.method, args.urdf, args.mjcf, args.joints, cli=True)  # before loading the model
    if args.command == "excite":
        from .excite import limit_flags

        limit_flags(args)  # the syntax of the limit flags, before the model is loaded
        if args.period is not None and not args.period > 0:
            raise BaseparamsError(f"--period must be > 0 seconds, got {args.period}")
        if not 0.0 <= args.margin < 0.5:
            raise BaseparamsError(f"--margin is a fraction of each position range kept free at both ends, in "
                                  f"[0, 0.5); got {args.margin}")


def preflight(args) -> None:
    """Check flags, needed extras and output paths before any long work or write.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`build_parser`).

    Raises
    ------
    BaseparamsError
        A flag that cannot be honoured, a missing optional module (naming the extra), an
        output in a missing folder, onto a folder or onto an input, a suffix of no known format,
        two outputs onto one file.
    """
    _check_flags(args)
    _check_extras(args)
    inputs = input_files(args)
    seen: dict[Path, str] = {}
    for flag, path, suffixes in _outputs(args):
        _check_output(flag, path, suffixes, inputs)
        key = Path(path).resolve()
        if key in seen:
            raise BaseparamsError(f"{flag} and {seen[key]} name the same file {path}")
        seen[key] = flag


def _symbolic_args(s) -> None:
    g = s.add_argument_group("symbolic geometry (MODEL a DH table .dh or a '*-symbolic' built-in; SymPy)")
    g.add_argument("--symbolic", action="store_true",
                   help="the base parameters as formulas in the table's symbols (lengths, offsets)")
    g.add_argument("--latex", action="store_true", help="with --symbolic: a LaTeX table of the formulas")
    g.add_argument("--codegen", metavar="FILE.py", help="with --symbolic: write Python (NumPy) code of the "
                                                        "regrouping K(dimensions)")
    g.add_argument("--values", nargs="+", metavar="NAME=NUMBER",
                   help="without --symbolic: numbers for the table's symbols (default: its 'values' line)")


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
        :data:`EXIT_UNDECIDED`, :data:`EXIT_FAILED` or :data:`EXIT_INTERRUPTED`; 0 on a
        broken pipe (e.g. piped into ``head``).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    _one_line_notes()
    args.samples_flag = "--analysis-samples" if args.command in RENAMED_SAMPLES else "--samples"
    try:
        preflight(args)
        return args.func(args)
    except BaseparamsError as exc:
        print(f"baseparams: error: {exc}", file=sys.stderr)
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
