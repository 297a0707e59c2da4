"""Command-line front end: ``baseparams robots``, ``baseparams analyze MODEL``, ...

Exit codes (scripts rely on them): 0 the result is certified (or completed, or unverified on
request with ``--no-verify``); 2 bad input, printed as one line (``baseparams: error: ...``);
3 certification UNDECIDED (the numerics could not decide the rank: the message says what would
help); 4 certification FAILED (a DRNG column is not in the numerical nullspace); 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
import sys
import threading
import time
from pathlib import Path

import numpy as np

from . import __version__
from .enums import Convention, Rows, Status, values
from .errors import BaseparamsError, NoMovingBodiesError

#: exit codes (see the module doc)
EXIT_OK, EXIT_INPUT, EXIT_UNDECIDED, EXIT_FAILED, EXIT_INTERRUPTED = 0, 2, 3, 4, 130
_STATUS_EXIT = {Status.CERTIFIED: EXIT_OK, Status.COMPLETED: EXIT_OK, Status.UNVERIFIED: EXIT_OK,
                Status.UNDECIDED: EXIT_UNDECIDED, Status.FAILED: EXIT_FAILED}

#: seconds after which a run without ``-v`` starts showing its progress lines on stderr
PROGRESS_AFTER_S = 2.0


class Progress:
    """Progress lines on stderr (``baseparams: STEP [elapsed]``) for long runs.

    With ``verbose`` every line is printed. Otherwise the lines are held back until the run has
    taken :data:`PROGRESS_AFTER_S` seconds: then the current step is printed (a timer thread, so a
    long step shows even before the next line) and every later line as it comes; a short run stays
    quiet. Callable with one line, or usable as the text stream that
    :func:`baseparams.analysis.analyze` writes to (``write``, ``flush``). A context manager: leaving
    it stops the timer.

    Parameters
    ----------
    verbose : bool
        Print every line from the start (``-v``).
    after : float, optional
        Seconds before the lines show without ``verbose`` (default :data:`PROGRESS_AFTER_S`).
    """

    def __init__(self, verbose: bool, after: float | None = None):
        self.t0 = time.perf_counter()
        self.shown = bool(verbose)
        self.last: str | None = None
        self.lock = threading.Lock()
        self.timer = None
        if not verbose:
            self.timer = threading.Timer(PROGRESS_AFTER_S if after is None else after, self._late)
            self.timer.daemon = True
            self.timer.start()

    def _print(self, msg: str) -> None:
        print(f"baseparams: {msg} [{time.perf_counter() - self.t0:.1f} s]", file=sys.stderr, flush=True)

    def _late(self) -> None:
        with self.lock:
            self.shown = True
            if self.last is not None:
                self._print(f"{self.last} ...")

    def __call__(self, msg: str) -> None:
        """One progress line: printed now if lines show, else held as the current step."""
        with self.lock:
            self.last = msg
            if self.shown:
                self._print(msg)

    def write(self, text: str) -> int:
        """Take text written as to a stream: each non-empty line is a progress line.

        Parameters
        ----------
        text : str
            The text (``[baseparams]`` prefixes dropped).

        Returns
        -------
        int
            ``len(text)``, as a stream's ``write``.
        """
        for line in text.splitlines():
            if line.strip():
                self(line.removeprefix("[baseparams] ").strip())
        return len(text)

    def flush(self) -> None:
        """Nothing to flush: lines are printed as they come."""

    def close(self) -> None:
        """Stop the timer (no line is printed after this)."""
        with self.lock:
            self.shown = False
        if self.timer is not None:
            self.timer.cancel()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _robot(args) -> Robot:  # noqa: F821
    from .loading import load_model

    if _is_symbolic(args.model):  # a DH table with symbols: analysed numerically at its values
        return _symbolic_robot(args)
    robot, notes = load_model(args.model, floating=getattr(args, "floating", False), gravity=args.gravity,
                              strict_inertia=getattr(args, "strict_inertia", False))
    for note in notes:
        print(f"baseparams: note: {note}", file=sys.stderr)
    return robot


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
    from .robots import BUILTINS

    for name, (factory, text) in BUILTINS.items():
        r = factory()
        print(f"{name:<10s} {r.n:3d} bodies {r.dof:3d} dofs  {text}")
    try:
        from .symbolic import builtin_tables, load_symbolic
    except ImportError:
        print("(symbolic robots: install the extra 'symbolic' (SymPy) to list them)")
        return 0
    print("\nsymbolic geometry ('baseparams analyze NAME --symbolic'; without --symbolic: at the listed values):")
    for name, text in builtin_tables().items():
        r = load_symbolic(name)
        print(f"{name:<24s} {r.n:3d} bodies  {text}")
    return 0


def _no_moving_bodies(args, exc: NoMovingBodiesError) -> int:
    """A model whose links are all welded to the world: an empty, trivially certified result."""
    name = Path(args.model).stem
    hint = "" if getattr(args, "floating", False) else "; --floating attaches the root link by a free joint"
    msg = (f"{exc}: every link is welded to the world, so no measurement sees any inertial parameter "
           f"(0 standard, 0 base parameters){hint}")
    if args.json:
        _emit(args, json.dumps({"model": name, "n_bodies": 0, "n_params": 0, "nullity": 0, "n_base": 0,
                                "certified": True, "status": Status.CERTIFIED, "message": msg,
                                "base_parameters": [], "unidentifiable": []}, indent=2))
    else:
        _emit(args, f"{name}: {msg}")
    return EXIT_OK


def _emit(args, text: str) -> None:
    out = getattr(args, "output", None)
    if not out:
        print(text)
        return
    try:
        with open(out, "w") as fh:
            fh.write(text + "\n")
    except OSError as exc:
        raise BaseparamsError(f"--output {out}: cannot write ({exc.strerror or exc})") from None
    if not args.json:
        print(f"report written to {out}")


def cmd_regressor(args) -> int:
    """``baseparams regressor MODEL``: time the TP regressor on random states.

    For a robot with loops, the closed-loop regressor with respect to its independent (actuated)
    coordinates on loop-closed samples. Prints its shape and time (or one JSON object with
    ``--json``); columns in the ``paper`` convention (spatial pseudo-inertia at q = 0).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`build_parser`): ``model``, ``floating``, ``gravity``,
        ``strict_inertia``, ``samples`` (default 100), ``seed``, ``json``.

    Returns
    -------
    int
        The exit code: :data:`EXIT_OK` (also for a model without moving bodies).

    Raises
    ------
    BaseparamsError
        Bad input, or no sample closes the loops.
    """
    from .numerics import closed_samples, sample_states
    from .regressor import closed_regressor, regressor

    try:
        robot = _robot(args)
    except NoMovingBodiesError as exc:
        return _no_moving_bodies(args, exc)
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
                 f"workspace, {cs.branch_jumps} left the assembly mode, {cs.ill_conditioned} ill-conditioned)")
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
    from .analysis import analyze, format_report

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
        return _analyze_symbolic(args)
    try:
        robot = _robot(args)
    except NoMovingBodiesError as exc:
        return _no_moving_bodies(args, exc)
    with Progress(args.verbose) as progress:
        result = analyze(robot, samples=args.samples, seed=args.seed, verify=not args.no_verify,
                         extended=not args.paper_only, rows=args.rows, convention=args.convention, progress=progress)
        text = json.dumps(result.to_json(), indent=2) if args.json else format_report(result)
        if args.html:
            from .report.html import analysis_html

            progress("writing the HTML report")
            _write_html(args.html, analysis_html(result))
        if args.plot:
            from .report.plots import analysis_plot

            progress("drawing the figure")
            analysis_plot(result, args.plot)
            print(f"baseparams: plot written to {args.plot}", file=sys.stderr)
    _emit(args, text)
    status = result.status
    if status in (Status.UNDECIDED, Status.FAILED):
        print(f"baseparams: certification {status.upper()}: {result.certificate.message}", file=sys.stderr)
    return _STATUS_EXIT[status]


def _friction(text: str) -> tuple[str, ...]:
    """``--friction viscous,coulomb,offset`` (or ``none``) as a tuple."""
    return () if text.strip().lower() in ("", "none") else tuple(x.strip() for x in text.split(",") if x.strip())


def _read_identification_logs(args, robot, path):
    """The training log, the validation log (or None) and the robot (a sub-chain with ``--joints``)."""
    from .io.logs import read_log

    subset = bool(args.joints)
    log = read_log(path, robot, columns=args.columns, allow_subset=subset)
    val = read_log(args.validate, robot, columns=args.columns, allow_subset=subset) if args.validate else None
    if args.weld and not subset:
        raise BaseparamsError("--weld applies with --joints (the joints to identify; the others are welded)")
    if subset and args.urdf:
        raise BaseparamsError("--urdf with --joints: writing a sub-chain's values into the whole robot's file is "
                              "not supported; identify every moving joint to export")
    if not subset:
        return log, val, robot
    from .ident.subchain import parse_welds, subchain

    joints = [j.strip() for j in args.joints.split(",") if j.strip()]
    welds = parse_welds(args.weld)
    small, log, notes = subchain(robot, log, joints, welds)
    if val is not None:
        val = subchain(robot, val, joints, welds)[1]
    for note in notes:
        print(f"baseparams: note: {note}", file=sys.stderr)
    return log, val, small


def cmd_identify(args) -> int:
    """``baseparams identify MODEL DATA``: base-parameter and drive values from a joint log.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line: the model options and ``data``, ``columns``, ``validate``,
        ``holdout``, ``method``, ``friction``, ``rotor``, ``coulomb_width``, ``coupling``,
        ``cutoff``, ``decimate``, ``min_speed``, ``prior_weight``, ``convention``, ``plot``,
        ``urdf``, ``output``.

    Returns
    -------
    int
        :data:`EXIT_OK`.

    Raises
    ------
    BaseparamsError
        Bad input (model, data, options).
    """
    from .ident.drives import MotorCoupling
    from .ident.pipeline import identify
    from .ident.report import format_identification

    couplings = tuple(MotorCoupling.parse(text) for text in args.coupling or ())
    robot = _robot(args)
    files = _data_files(args.data)
    if len(files) > 1 or args.per_file or args.pooled:
        if args.joints:
            raise BaseparamsError("--joints applies to one log, not to a fleet of logs")
        return _identify_fleet(args, robot, files)
    with Progress(args.verbose) as progress:
        progress(f"reading {args.data}")
        log, val, robot = _read_identification_logs(args, robot, files[0])
        progress(f"identifying ({args.method}) on {log.n_samples} samples")
        t0 = time.perf_counter()
        result = identify(robot, log, method=args.method, rotor=args.rotor, friction=_friction(args.friction),
                          coulomb_width=args.coulomb_width, holdout=args.holdout, validation=val, cutoff=args.cutoff,
                          decimate=args.decimate, min_speed=args.min_speed, prior_weight=args.prior_weight,
                          convention=args.convention, couplings=couplings, progress=progress)
        progress(f"identified in {time.perf_counter() - t0:.2f} s")
        if args.urdf:
            _write_identified_urdf(args, robot, result)
        if args.plot:
            from .report.plots import torque_plot

            torque_plot(result, args.plot)
            progress(f"plot written to {args.plot}")
        if args.html:
            from .report.html import identification_html

            _write_html(args.html, identification_html(result))
    _emit(args, json.dumps(result.to_json(), indent=2) if args.json else format_identification(result))
    return EXIT_OK


def _write_html(path: str, page: str) -> None:
    """``--html FILE``: write a self-contained report, or one line saying why not."""
    try:
        Path(path).write_text(page)
    except OSError as exc:
        raise BaseparamsError(f"--html {path}: cannot write ({exc.strerror or exc})") from None
    print(f"baseparams: HTML report written to {path}", file=sys.stderr)


def _data_files(pattern: str) -> list[str]:
    """``DATA``: a file, a folder (a ROS 2 bag), or a glob pattern (``**`` recursive), sorted."""
    import glob

    if any(ch in pattern for ch in "*?["):
        files = sorted(glob.glob(pattern, recursive=True))
        if not files:
            raise BaseparamsError(f"no file matches {pattern!r}")
        return files
    return [pattern]


def _identify_fleet(args, robot, files: list[str]) -> int:
    """``identify`` over many logs on Dask (``--per-file`` / ``--pooled``)."""
    from .fleet import identify_fleet
    from .ident.model import ident_model

    for opt in ("validate", "holdout", "plot", "urdf", "columns"):
        if getattr(args, opt):
            raise BaseparamsError(f"--{opt} applies to one log; with several (a fleet) use --per-file / --pooled")
    from .analysis import analyze

    model = ident_model(analyze(robot, convention=args.convention), args.rotor, _friction(args.friction),
                        args.coulomb_width)
    per_file = args.per_file or not args.pooled
    res = identify_fleet(model, files, per_file=per_file, pooled=args.pooled or len(files) == 1, method=args.method,
                         scheduler=args.scheduler, workers=args.workers, cutoff=args.cutoff, min_speed=args.min_speed,
                         progress=lambda line: print(f"baseparams: {line}", file=sys.stderr))
    if args.json:
        _emit(args, json.dumps(res.to_json(), indent=2))
        return _fleet_exit(args, res, files)
    skipped = [s for s in res.skipped if s["stage"] == "read"]
    lines = [f"{robot.name}: {len(files)} logs, {len(res.files)} used, {len(skipped)} skipped; "
             f"{sum(f['used'] for f in res.files)} samples used ({args.method}); {model.n_params} model parameters"]
    lines += [f"skipped: {s['error']}" for s in res.skipped]
    if res.spread is not None:
        rel = res.spread["std"] / np.maximum(np.abs(res.spread["mean"]), 1e-300)
        worst = np.argsort(rel)[::-1][:5]
        lines.append("largest spread across the fleet (std / |mean|): "
                     + ", ".join(f"{model.names[k]} {rel[k]:.3g}" for k in worst))
    if res.pooled is not None:
        lines.append("pooled estimate:")
        lines += [f"  {n:<20s} {v:14.6g} {s:11.3g}" for n, v, s in
                  zip(model.names, res.pooled.theta, res.pooled.estimate.std)]
    _emit(args, "\n".join(lines))
    return _fleet_exit(args, res, files)


def _fleet_exit(args, res, files: list[str]) -> int:
    """``--strict``: a fleet with a skipped log is an error (one line); otherwise the skips are reported only."""
    if args.strict and res.skipped:
        print(f"baseparams: error: --strict: {len(res.skipped)} of {len(files)} logs skipped "
              f"(first: {res.skipped[0]['error']})", file=sys.stderr)
        return EXIT_INPUT
    return EXIT_OK


def _write_identified_urdf(args, robot, result) -> None:
    """``--urdf FILE``: the model file with the physically consistent inertias."""
    from .io.urdf import write_urdf

    if result.fit.physical is None:
        raise BaseparamsError("--urdf needs --method physical: least squares gives base parameters, not bodies")
    if Path(args.model).suffix.lower() != ".urdf":
        raise BaseparamsError(f"--urdf needs a URDF model file, got {args.model}")
    write_urdf(args.model, args.urdf, robot, result.fit.physical.pi, "paper")


def cmd_simulate(args) -> int:
    """``baseparams simulate MODEL OUT``: a synthetic joint log with known parameters and noise.

    The excitation is a random finite Fourier series per joint (``--duration``, ``--rate``,
    ``--amplitude``, ``--seed``), or the trajectory of ``--trajectory FILE`` (``baseparams excite
    --out``: ``t, q_, dq_, ddq_`` columns); the torques are the model's own inertias plus drive terms
    (rotor inertia: the model's armature, else drawn; friction drawn), plus Gaussian noise
    (``--noise``). ``OUT`` (``.csv`` or ``.npz``, the default layout) and ``OUT.truth.json``:
    the true model parameters under their names, to compare an identification with.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        :data:`EXIT_OK`.

    Raises
    ------
    BaseparamsError
        Bad options, or an output that cannot be written.
    """
    from .ident.simulate import simulate_log
    from .io.logs import write_log

    robot = _robot(args)
    if args.robots:
        from .fleet import simulate_fleet

        paths = simulate_fleet(robot, args.out, args.robots, duration=args.duration, rate=args.rate, noise=args.noise,
                               seed=args.seed, friction=_friction(args.friction))
        print(f"{args.out}: {len(paths)} logs, one robot each (true parameters beside each log)")
        return EXIT_OK
    trajectory = None
    if args.trajectory:
        from .excite import read_trajectory

        trajectory = read_trajectory(args.trajectory, robot)
    log, truth = simulate_log(robot, duration=args.duration, rate=args.rate, amplitude=args.amplitude,
                              noise=args.noise, seed=args.seed, rotor=args.rotor, friction=_friction(args.friction),
                              convention=args.convention, trajectory=trajectory)
    write_log(args.out, log)
    truth_path = Path(str(args.out) + ".truth.json")
    truth_path.write_text(json.dumps(truth, indent=2) + "\n")
    print(f"{args.out}: {log.n_samples} samples of {len(log.joints)} joints; true parameters in {truth_path}")
    return EXIT_OK


def _ident_args(s) -> None:
    """Options shared by ``identify`` and ``simulate``."""
    s.add_argument("--friction", default="viscous,coulomb,offset",
                   help="friction terms per joint: any of viscous, coulomb, offset, comma-separated, or none "
                        "(default all three)")
    s.add_argument("--rotor", action="store_true", help="model each joint's rotor inertia Ia (MJCF armature)")
    s.add_argument("--convention", choices=values(Convention), default=str(Convention.KHALIL),
                   help="convention of the base parameters' names and values (default khalil)")


def _analyze_sweep(args) -> int:
    """``analyze 'models/*.urdf'``: every matching file on Dask, one line (or JSON object) each."""
    from .fleet import analyze_fleet

    files = _data_files(args.model)
    results = analyze_fleet(files, scheduler=getattr(args, "scheduler", None), workers=getattr(args, "workers", None),
                            floating=args.floating, convention=args.convention, rows=args.rows,
                            progress=(lambda line: print(f"baseparams: {line}", file=sys.stderr)) if args.verbose
                            else None)
    if args.json:
        _emit(args, json.dumps(results, indent=2))
    else:
        _emit(args, "\n".join(f"{r['path']}: error: {r['error']}" if "error" in r else
                              f"{r['path']}: {r['status']}, nullity {r['nullity']}, {r['n_base']} base parameters"
                              for r in results))
    statuses = [Status(r["status"]) for r in results if "error" not in r]
    if any("error" in r for r in results):
        return EXIT_INPUT
    return max((_STATUS_EXIT[s] for s in statuses), default=EXIT_OK)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``baseparams`` command.

    Returns
    -------
    argparse.ArgumentParser
        Subcommands ``robots``, ``analyze``, ``regressor``, ``identify``, ``simulate`` and
        ``excite``; each sets ``func`` to its ``cmd_*`` function.
    """
    p = argparse.ArgumentParser(prog="baseparams", description=(
        "Which inertial parameters of a robot are identifiable (base parameters), why, and how "
        "they regroup: the tetrahedral-point model and DRNG, certified by exact numerics."))
    p.add_argument("--version", action="version", version=f"baseparams {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("robots", help="list the built-in robots")
    s.set_defaults(func=cmd_robots)

    def model_args(s):
        s.add_argument("model", help="built-in robot name (see 'baseparams robots') or a robot file: "
                                     "URDF / URDF+ (.urdf) or MJCF (.xml); for analyze, a glob pattern runs a "
                                     "sweep over many files on Dask")
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
    s.add_argument("--rows", choices=values(Rows), default=str(Rows.ALL),
                   help="measured generalized forces: all (default), joint torques only, or the "
                        "floating base's wrench only")
    s.add_argument("--convention", choices=values(Convention),
                   default=str(Convention.KHALIL), help="convention of the regrouped expressions (default khalil)")
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

    s = sub.add_parser("regressor", help="compute the TP regressor on random samples")
    model_args(s)
    s.set_defaults(func=cmd_regressor)
    _identify_parser(sub, model_args)
    _simulate_parser(sub, model_args)
    _excite_parser(sub, model_args)
    return p


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
    s.add_argument("--method", choices=("ols", "wls", "physical"), default="wls",
                   help="ordinary, weighted (per-joint noise; default) or physically consistent least squares")
    _ident_args(s)
    s.add_argument("--coulomb-width", type=float, metavar="W", help="smooth Coulomb friction tanh(dq / W) [rad/s]")
    s.add_argument("--coupling", action="append", metavar="NAME:JOINT=W,JOINT=W",
                   help="a motor driving several joints (coupled wrist): its velocity is sum W dq_JOINT, its torque "
                        "reaches each JOINT times W; adds Iam_NAME, Fvm_NAME, Fcm_NAME (with --rotor, viscous, "
                        "coulomb); repeatable")
    s.add_argument("--cutoff", type=float, metavar="HZ", help="low-pass cutoff (default from the sampling rate)")
    s.add_argument("--decimate", type=int, metavar="K", help="keep every K-th sample after filtering")
    s.add_argument("--min-speed", type=float, metavar="V", help="drop samples where a joint is slower than V rad/s")
    s.add_argument("--prior-weight", type=float, metavar="W", help="physical: weight of the file's inertias")
    s.add_argument("--joints", metavar="A,B,...",
                   help="identify only these joints; every other joint is welded (at its logged position if it "
                        "does not move, at --weld, or at 0)")
    s.add_argument("--weld", action="append", metavar="JOINT=VALUE",
                   help="with --joints: weld JOINT at VALUE (rad or m); repeatable")
    s.add_argument("--per-file", action="store_true",
                   help="several logs (a glob such as 'logs/robot-*/*.parquet'): one estimate per log and the "
                        "spread across them, on Dask")
    s.add_argument("--pooled", action="store_true", help="several logs: one estimate from all of them, on Dask")
    s.add_argument("--strict", action="store_true",
                   help="several logs: exit 2 when any log was skipped (default: report it, go on with the rest)")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="a Dask scheduler (default DASK_SCHEDULER_ADDRESS, else a local cluster for this run)")
    s.add_argument("--workers", type=int, metavar="N", help="local cluster size (default: one per core)")
    s.add_argument("--plot", metavar="FILE", help="measured vs predicted torques per joint (PNG/SVG; matplotlib)")
    s.add_argument("--html", metavar="FILE", help="a self-contained HTML report: torques, residuals, values, %%sigma")
    s.add_argument("--urdf", metavar="FILE", help="physical: write the model with the identified inertias")
    s.add_argument("-v", "--verbose", action="store_true",
                   help="progress lines on stderr from the start (without -v they show once a run takes over 2 s)")
    s.add_argument("--output", metavar="FILE", help="write the report to FILE")
    s.set_defaults(func=cmd_identify)


def _simulate_parser(sub, model_args) -> None:
    """The ``simulate`` subcommand's arguments."""
    s = sub.add_parser("simulate", help="write a synthetic joint log with known parameters (tests, demos)")
    model_args(s)
    s.add_argument("out", help="output log (.csv or .npz); the true parameters go to OUT.truth.json")
    s.add_argument("--duration", type=float, default=20.0, help="seconds (default 20)")
    s.add_argument("--rate", type=float, default=500.0, help="sampling rate in Hz (default 500)")
    s.add_argument("--amplitude", type=float, default=0.5, help="joint excursion in rad (default 0.5)")
    s.add_argument("--noise", type=float, default=0.0, help="torque noise standard deviation (default 0)")
    s.add_argument("--robots", type=int, metavar="N",
                   help="a fleet: N logs in the folder OUT, one robot each with its own inertias (10 %% spread)")
    s.add_argument("--trajectory", metavar="FILE", help="simulate this trajectory (t, q_, dq_, ddq_ columns: "
                                                        "'baseparams excite --out') instead of a random one")
    _ident_args(s)
    s.set_defaults(func=cmd_simulate)


def _keepout(text: str | None):
    """``--keepout LINK:Z`` as ``(link, z)``, or None."""
    if not text:
        return None
    link, sep, z = text.rpartition(":")
    try:
        return (link, float(z)) if sep and link else float("x")
    except ValueError:
        raise BaseparamsError(f"--keepout expects LINK:Z (e.g. panda_link7:0.3), got {text!r}") from None


def cmd_excite(args) -> int:
    """``baseparams excite MODEL``: design an excitation trajectory (:mod:`baseparams.excite`).

    Progress lines go to stderr; the summary (or ``--json``) to stdout or ``--output``; the
    trajectory to ``--out`` (CSV ``t, q_<joint>, dq_<joint>, ddq_<joint>``, what ``baseparams
    simulate --trajectory`` and a controller read) and a plot to ``--plot``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line: the model options and ``harmonics``, ``period`` or
        ``base_frequency``, ``rate``, ``criterion``, ``drives``, ``rotor``, ``acceleration``,
        ``torque``, ``starts``, ``grid``, ``out``, ``plot``, ``output``.

    Returns
    -------
    int
        :data:`EXIT_OK`.

    Raises
    ------
    BaseparamsError
        Bad input: the model (no actuated coordinate, a singular reference), infeasible limits,
        options, unwritable outputs.
    """
    from .excite import design_excitation

    try:
        robot = _robot(args)
    except NoMovingBodiesError as exc:
        raise BaseparamsError(f"{exc}: no actuated coordinate to excite") from None
    f = 1.0 / args.period if args.period else (args.base_frequency or 0.1)
    if args.period is not None and not args.period > 0:
        raise BaseparamsError(f"--period must be > 0 seconds, got {args.period}")
    acc = [float(x) for x in args.acceleration.split(",")] if args.acceleration else None
    result = design_excitation(robot, harmonics=args.harmonics, base_frequency=f, rate=args.rate,
                               criterion=args.criterion, drives=args.drives, rotor=args.rotor,
                               acceleration=None if acc is None else (acc[0] if len(acc) == 1 else acc),
                               torque=args.torque, starts=args.starts, seed=args.seed, grid=args.grid,
                               keepout=_keepout(args.keepout),
                               progress=lambda msg: print(f"baseparams: {msg}", file=sys.stderr))
    if args.out:
        result.to_csv(args.out)
        print(f"baseparams: trajectory written to {args.out}", file=sys.stderr)
    if args.plot:
        from .report.plots import trajectory_plot

        trajectory_plot(result, args.plot)
        print(f"baseparams: plot written to {args.plot}", file=sys.stderr)
    _emit(args, json.dumps(result.to_json(), indent=2) if args.json else result.summary())
    return EXIT_OK


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
    s.add_argument("--acceleration", metavar="A[,A...]",
                   help="acceleration limit(s) in rad/s^2 (one for all joints, or one per designed joint)")
    s.add_argument("--torque", action="store_true", help="keep the model's own torques within the effort limits")
    s.add_argument("--keepout", metavar="LINK:Z", help="keep LINK's frame origin at or above the height Z [m, world z] "
                                                        "(a floor or a table)")
    s.add_argument("--starts", type=int, default=4, help="random starts of the optimisation (default 4)")
    s.add_argument("--grid", type=int, default=200, help="samples per period while optimising (default 200)")
    s.add_argument("--out", metavar="FILE", help="write the trajectory (CSV: t, q_, dq_, ddq_ per joint)")
    s.add_argument("--plot", metavar="FILE", help="plot q, dq, ddq per joint against the limits (PNG/SVG)")
    s.add_argument("--output", metavar="FILE", help="write the summary to FILE")
    s.set_defaults(func=cmd_excite)


def _is_symbolic(model: str) -> bool:
    """A DH table file or a built-in symbolic robot's name (``*-symbolic``)."""
    return model.endswith(".dh") or (model.lower().endswith("-symbolic") and not Path(model).exists())


def _load_symbolic(args):
    try:
        from .symbolic import load_symbolic
    except ImportError:
        raise BaseparamsError("symbolic robots need SymPy: pip install 'baseparams[symbolic]'") from None
    robot = load_symbolic(args.model)
    if args.gravity is not None:
        raise BaseparamsError(f"{args.model}: a symbolic robot's gravity is in its table (the 'gravity' line)")
    return robot


def _symbolic_robot(args):
    """The numeric robot of a symbolic table at its ``values`` (``--values`` overrides)."""
    vals = dict(v.split("=", 1) for v in (args.values or []) if "=" in v)
    bad = [v for v in (args.values or []) if "=" not in v]
    if bad:
        raise BaseparamsError(f"--values {bad[0]}: expected NAME=NUMBER")
    robot = _load_symbolic(args)
    try:
        vals = {k: float(v) for k, v in vals.items()}
    except ValueError as exc:
        raise BaseparamsError(f"--values: {exc}") from None
    return robot.to_robot(vals)


def _analyze_symbolic(args) -> int:
    """``analyze TABLE --symbolic [--json | --latex] [--codegen FILE]``: base parameters as formulas."""
    robot = _load_symbolic(args)
    from .symbolic import probe, symbolic_analysis
    from .symbolic.report import codegen, format_symbolic, symbolic_json, symbolic_latex

    if args.verbose:
        print(f"baseparams: {robot.name}: DRNG on the symbolic geometry, exact regrouping"
              + ("" if args.no_verify else ", checks against the numerical analysis"), file=sys.stderr)
    result = symbolic_analysis(robot, convention=args.convention, seed=args.seed, check=not args.no_verify)
    if not args.no_verify:
        if args.verbose:
            print(f"baseparams: probing {len(result.conditions) + len(robot.symbols)} conditions", file=sys.stderr)
        probe(result)
    if args.codegen:
        try:
            Path(args.codegen).write_text(codegen(result))
        except OSError as exc:
            raise BaseparamsError(f"--codegen {args.codegen}: cannot write ({exc.strerror or exc})") from None
        print(f"baseparams: regrouping code written to {args.codegen}", file=sys.stderr)
    if args.json:
        _emit(args, json.dumps(symbolic_json(result), indent=2))
    else:
        _emit(args, symbolic_latex(result) if args.latex else format_symbolic(result))
    return EXIT_OK


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

    from .regressor.compiled import CompileCacheWarning

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

    Bad input (a :class:`BaseparamsError`, a missing ``--output`` folder) is one line on
    stderr, ``baseparams: error: ...``; bad arguments (``--samples`` < 1, ``--seed`` < 0) are
    argparse's usage errors (``SystemExit`` with status 2).

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
    if getattr(args, "samples", None) is not None and args.samples < 1:
        parser.error("--samples must be at least 1")
    if getattr(args, "seed", 0) < 0:
        parser.error("--seed must be a non-negative integer")
    out = getattr(args, "output", None)
    if out and not Path(out).resolve().parent.is_dir():
        print(f"baseparams: error: --output {out}: the folder {Path(out).resolve().parent} does not exist",
              file=sys.stderr)
        return EXIT_INPUT
    try:
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


if __name__ == "__main__":
    sys.exit(main())
