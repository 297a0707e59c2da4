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
                              strict_inertia=getattr(args, "strict_inertia", False),
                              xacro_args=getattr(args, "xacro_args", None),
                              package_path=getattr(args, "package_path", None))
    for note in notes:
        print(f"baseparams: note: {note}", file=sys.stderr)
    hint = floating_hint(robot) if Path(args.model).is_file() and not getattr(args, "floating", False) else ""
    if hint:
        print(f"baseparams: note: {hint}", file=sys.stderr)
    return robot


#: names of joints on a fixed root that suggest the base moves (a leg's hip, a wheel)
_MOBILE_WORDS = ("wheel", "leg", "hip", "haa", "hfe", "foot", "caster")


def floating_hint(robot) -> str:
    """A hint to pass ``--floating`` when a fixed root carries legs or wheels ('' when not).

    Parameters
    ----------
    robot : Robot
        A robot read with a fixed base.

    Returns
    -------
    str
        One line when the root link carries three or more chains, or chains whose joints are
        named like legs or wheels; else ''.
    """
    if robot.floating or robot.n == 0:
        return ""
    roots = [k for k in range(robot.n) if robot.parent[k] < 0]
    names = [robot.joint_names[k].lower() for k in roots]
    mobile = [n for n in names if any(w in n for w in _MOBILE_WORDS)]
    if len(roots) < 3 and not mobile:
        return ""
    return (f"the fixed root link carries {len(roots)} chains ({', '.join(robot.joint_names[k] for k in roots[:4])}"
            f"{', ...' if len(roots) > 4 else ''}): if they are legs or wheels the base moves: pass --floating to "
            f"attach it by a free joint")


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
    from .files import write_text

    try:
        write_text(out, text + "\n", _inputs(args), "--output")
    except OSError as exc:
        raise BaseparamsError(f"--output {out}: cannot write ({exc.strerror or exc})") from None
    if not args.json:
        print(f"report written to {out}")


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
    from .numerics import closed_samples, sample_states
    from .regressor import closed_regressor, regressor

    if args.out and not args.states:
        raise BaseparamsError("--out saves the regressor of --states FILE; give the states")
    try:
        robot = _robot(args)
    except NoMovingBodiesError as exc:
        return _no_moving_bodies(args, exc)
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
            _write_html(args.html, analysis_html(result), _inputs(args))
        if args.plot:
            from .report.plots import analysis_plot

            progress("drawing the figure")
            _write(args.plot, lambda tmp: analysis_plot(result, tmp), args, "--plot")
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
    if subset and (args.urdf or args.mjcf):
        raise BaseparamsError(f"{'--urdf' if args.urdf else '--mjcf'} with --joints: writing a sub-chain's values "
                              "into the whole robot's file is not supported; identify every moving joint to export")
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
    truth = _results_check(args, files)  # --save, --truth: checked before the fit
    if len(files) > 1 or args.per_file or args.pooled:
        if args.joints:
            raise BaseparamsError("--joints applies to one log, not to a fleet of logs")
        return _identify_fleet(args, robot, files)
    with Progress(args.verbose) as progress:
        t0 = time.perf_counter()
        result = _identify_streamed(args, robot, files, couplings, progress)
        if result is None:
            progress(f"reading {args.data}")
            log, val, robot = _read_identification_logs(args, robot, files[0])
            progress(f"identifying ({args.method}) on {log.n_samples} samples")
            t0 = time.perf_counter()
            result = identify(robot, log, validation=val, progress=progress, **_identify_kwargs(args, couplings))
            if args.predictions:
                _write_predictions(args, result, log, val, files)
        progress(f"identified in {time.perf_counter() - t0:.2f} s")
        if args.save:
            result.save(args.save, inputs=[args.model, *files, args.validate, args.columns, args.truth], what="--save")
            progress(f"result saved to {args.save}")
        if args.urdf:
            _write_identified_urdf(args, robot, result)
        if args.mjcf:
            _write_identified_mjcf(args, result, log)
        if args.plot:
            from .report.plots import torque_plot

            _write(args.plot, lambda tmp: torque_plot(result, tmp), args, "--plot")
            progress(f"plot written to {args.plot}")
        if args.html:
            from .report.html import identification_html

            _write_html(args.html, identification_html(result), _inputs(args))
    _emit(args, _with_truth(args, result, truth, format_identification))
    return EXIT_OK


#: logs larger than this [MB] are streamed from their file by default (``identify --stream auto``)
STREAM_MIN_MB = 64.0


def _identify_kwargs(args, couplings) -> dict:
    """The options :func:`~baseparams.ident.pipeline.identify` and ``identify_stream`` share."""
    return dict(method=args.method, rotor=args.rotor, friction=_friction(args.friction),
                coulomb_width=args.coulomb_width, holdout=args.holdout, cutoff=args.cutoff, decimate=args.decimate,
                min_speed=args.min_speed, prior_weight=args.prior_weight, convention=args.convention,
                couplings=couplings, samples=args.samples, covariance=args.covariance, allow_units=args.allow_units,
                score_cutoff=args.score_cutoff)


def _stream_reason(args, path: str) -> str | None:
    """Why ``identify`` streams the log from its file (a line for ``-v``), or None: read it whole."""
    from .io.logs import STREAM_SUFFIXES, streamable

    mode = getattr(args, "stream", "auto")
    if mode == "off":
        return None
    ok = streamable(path) and (not args.validate or streamable(args.validate))
    if mode == "on":
        if not ok:
            raise BaseparamsError(f"--stream on: only {', '.join(STREAM_SUFFIXES)} logs are streamed, not {path}"
                                  + (f" / {args.validate}" if args.validate else ""))
        if args.joints or getattr(args, "mjcf", None):
            raise BaseparamsError(f"--stream on with {'--joints' if args.joints else '--mjcf'}: the log is read whole "
                                  f"for it (--stream auto)")
        return "--stream on"
    if not ok or args.joints or getattr(args, "mjcf", None):  # --mjcf checks the model on the log's states
        return None
    size = Path(path).stat().st_size / 1e6
    return f"{size:.0f} MB > {STREAM_MIN_MB:g} MB" if size > STREAM_MIN_MB else None


def _identify_streamed(args, robot, files, couplings, progress):
    """``identify`` on a log streamed from its file (``--stream``), or None when it is read whole.

    A log with non-uniform time stamps is read whole after all (said with ``-v``).
    """
    why = _stream_reason(args, files[0])
    if why is None:
        return None
    from .ident.stream import NotStreamable, identify_stream
    from .io.logs import LogStream

    progress(f"streaming {files[0]} block by block ({why}): memory independent of the log's length")
    stream = LogStream(files[0], robot, columns=args.columns)
    other = LogStream(args.validate, robot, columns=args.columns) if args.validate else None
    kwargs = _identify_kwargs(args, couplings)
    try:
        if not args.predictions:
            return identify_stream(robot, stream, validation=other, progress=progress, **kwargs)
        from .io.tables import column_writer

        coords = robot.actuated if robot.has_loops else range(robot.dof)
        names = ["t", *(f"tau_{robot.joint_names[robot.dof_body[c]]}" for c in coords)]
        inputs = [args.model, *files, args.validate, args.columns]
        with column_writer(args.predictions, names, inputs, "--predictions") as write:
            result = identify_stream(robot, stream, validation=other, progress=progress,
                                     predictions=lambda t, tau: write(np.column_stack([t, tau])), **kwargs)
        print(f"baseparams: predictions of {result.validation['samples']} validation samples written to "
              f"{args.predictions}", file=sys.stderr)
        return result
    except NotStreamable as exc:
        progress(f"{exc}")
        return None


def _write_predictions(args, result, log, val, files) -> None:
    """``identify --predictions FILE``: predicted torques at every validation sample, the log's own times."""
    from .io.tables import write_columns

    whole = val if val is not None else log
    tau = result.predict(whole)
    keep = np.ones(whole.n_samples, dtype=bool) if val is not None else whole.t >= whole.t[-1] - args.holdout
    cols = {"t": whole.t[keep], **{f"tau_{j}": tau[keep, k] for k, j in enumerate(result.joints)}}
    write_columns(args.predictions, cols, [args.model, *files, args.validate, args.columns], "--predictions")
    print(f"baseparams: predictions of {int(keep.sum())} validation samples written to {args.predictions}",
          file=sys.stderr)


def _results_check(args, files: list[str]) -> dict | None:
    """``identify --save/--truth``: refused with several logs; the save path and the truth read now."""
    from .io.tables import check_output_path

    if not (args.save or args.truth):
        return None
    if len(files) > 1 or args.per_file or args.pooled:
        raise BaseparamsError("--save and --truth apply to one log, not to a fleet (--per-file / --pooled)")
    check_output_path(args.save, [args.model, *files, args.validate, args.columns, args.truth], "--save")
    if not args.truth:
        return None
    try:
        truth = json.loads(Path(args.truth).read_text())
    except FileNotFoundError:
        raise BaseparamsError(f"--truth {args.truth}: no such file") from None
    except (OSError, ValueError) as exc:
        raise BaseparamsError(f"--truth {args.truth}: not a JSON truth file ({exc})") from None
    if not isinstance(truth, dict) or not isinstance(truth.get("parameters"), list):
        raise BaseparamsError(f"--truth {args.truth}: no 'parameters' list (write one with 'baseparams simulate': "
                              f"OUT.truth.json)")
    return truth


def _with_truth(args, result, truth: dict | None, text_report) -> str:
    """The report (text or JSON), with the comparison to ``--truth`` when given."""
    from .ident.results import format_truth

    cmp = None if truth is None else result.compare_truth(truth, args.truth)
    if args.json:
        out = result.to_json()
        if cmp is not None:
            out["truth"] = cmp
        return json.dumps(out, indent=2)
    return text_report(result) + ("" if cmp is None else "\n\n" + format_truth(cmp))


def cmd_predict(args) -> int:
    """``baseparams predict MODEL RESULT LOG --out PRED``: torques of a log from a saved identification.

    Writes ``t, tau_<joint>`` (one row per log sample, the log's time stamps; CSV/TSV, or Parquet
    by the suffix) and prints the RMS against the log's measured torques when it has them:
    predicted and measured torques both low-passed with the identification's zero-phase filter
    (parallel filtering, what identify's train and validation RMS compare; ``rms`` in JSON), and
    unfiltered (``rms_raw``, which also holds the sensor noise above the cutoff).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line: the model options and ``result``, ``log``, ``columns``, ``out``,
        ``raw_states``, ``score_cutoff``, ``json``.

    Returns
    -------
    int
        :data:`EXIT_OK`.

    Raises
    ------
    BaseparamsError
        Another robot than the result's, a bad result file, log or output.
    """
    from .ident.pipeline import Identification
    from .io.logs import read_log
    from .io.tables import check_table_path, write_columns

    inputs = [args.model, args.result, args.log, args.columns]
    check_table_path(args.out, inputs, "--out")
    if args.out and Path(args.out).suffix.lower() == ".npz":
        raise BaseparamsError(f"--out {args.out}: predictions are written as .csv, .tsv or .parquet")
    robot = _robot(args)
    ident = Identification.load(args.result, robot)
    log = read_log(args.log, robot, columns=args.columns, allow_subset=True, require_tau=False)
    tau = ident.predict(log, smooth=not args.raw_states)
    joints = ident.joints
    if args.out:
        write_columns(args.out, {"t": log.t, **{f"tau_{j}": tau[:, k] for k, j in enumerate(joints)}}, inputs, "--out")
    out = {"model": robot.name, "result": args.result, "log": args.log, "samples": log.n_samples, "joints": joints,
           "out": args.out, "prediction": "raw states" if args.raw_states else "smooth", "rms": None}
    if log.tau is not None:
        from .ident.pipeline import validation_scores

        s = validation_scores(log, tau, joints, score_cutoff=args.score_cutoff)
        out["rms"] = {"total": s["rms_total"], **s["rms"]}
        if "score_cutoff" in s:
            out["score_cutoff"] = s["score_cutoff"]
            out["rms_lowpassed"] = {"total": s["rms_lowpassed_total"], **s["rms_lowpassed"]}
    if args.json:
        print(json.dumps(out, indent=2))
        return EXIT_OK
    lines = [f"{robot.name}: predicted {len(joints)} joint torques at {log.n_samples} samples"
             + (f", written to {args.out}" if args.out else "")]
    if out["rms"] is not None:
        lines.append(f"RMS vs the raw measured torques at every sample: {out['rms']['total']:.4g} (all joints); "
                     + ", ".join(f"{j} {out['rms'][j]:.3g}" for j in joints))
        if "rms_lowpassed" in out:
            lines.append(f"RMS vs the measured torques low-passed at {out['score_cutoff']:g} Hz (--score-cutoff): "
                         f"{out['rms_lowpassed']['total']:.4g}")
    print("\n".join(lines))
    return EXIT_OK


def _predict_parser(sub, model_args) -> None:
    """The ``predict`` subcommand's arguments."""
    s = sub.add_parser("predict", help="predict joint torques of a log from a saved identification (identify --save)")
    model_args(s)
    s.add_argument("result", help="the saved identification (RESULT.json from 'identify --save')")
    s.add_argument("log", help="the log or trajectory: t, q_<joint>, [dq_<joint>, ddq_<joint>], [tau_<joint>] "
                               "(CSV/TSV, NPZ, Parquet, a ROS 2 bag); rates it lacks are derived as identify does")
    s.add_argument("--columns", metavar="MAP", help="a TOML mapping file for any other layout (or a bag's topic)")
    s.add_argument("--out", metavar="FILE", help="write t, tau_<joint> per log sample (.csv, .tsv or .parquet)")
    s.add_argument("--raw-states", action="store_true",
                   help="the model's torques on the states as logged (default: on the states low-passed at the "
                        "identification's cutoff, as it was fitted)")
    s.add_argument("--score-cutoff", type=float, metavar="HZ",
                   help="also score against the measured torques low-passed at HZ (zero-phase Butterworth order 4)")
    s.set_defaults(func=cmd_predict)


def _regressor_states(args, robot) -> int:
    """``regressor MODEL --states FILE [--out FILE]``: the TP regressor of given states, saved."""
    from .analysis import regressor
    from .base.regroup import parameter_names
    from .io.logs import read_log
    from .io.tables import check_table_path, write_columns

    check_table_path(args.out, [args.model, args.states], "--out")
    if robot.floating:
        raise BaseparamsError(f"--states: robot {robot.name!r} has a floating base, whose coordinates are not "
                              f"columns of a states file; use baseparams.regressor in Python")
    coords = np.asarray(robot.actuated, dtype=int) if robot.has_loops else np.arange(robot.dof)
    joints = [robot.joint_names[robot.dof_body[c]] for c in coords]
    log = read_log(args.states, robot, allow_subset=True, require_tau=False, require_time=False)
    missing = [j for j in joints if j not in log.joints]
    if missing:
        raise BaseparamsError(f"--states {args.states}: no q_ columns for {missing} (states need q_<joint>, and "
                              f"dq_, ddq_ or a time column t, for the {'actuated ' if robot.has_loops else ''}joints "
                              f"{joints})")
    q, dq, ddq = log.q, log.dq, log.ddq
    if dq is None or ddq is None:  # rates the file lacks: derived as identify derives them (needs time)
        from .ident.results import log_states

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
                          [args.model, args.states])
        else:
            s, m, p = y.shape
            table = {"sample": np.repeat(np.arange(s), m), "joint": np.tile(np.array(joints), s)}
            table.update({n: y[:, :, k].reshape(-1) for k, n in enumerate(names)})
            write_columns(args.out, table, [args.model, args.states])
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


def _write_html(path: str, page: str, inputs=()) -> None:
    """``--html FILE``: write a self-contained report (atomically, never onto an input), or one line saying why not."""
    from .files import write_text

    try:
        write_text(path, page, inputs, "--html")
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

    for opt in ("validate", "holdout", "plot", "urdf", "mjcf", "columns"):
        if getattr(args, opt):
            raise BaseparamsError(f"--{opt} applies to one log; with several (a fleet) use --per-file / --pooled")
    from .analysis import analyze

    model = ident_model(analyze(robot, convention=args.convention), args.rotor, _friction(args.friction),
                        args.coulomb_width)
    per_file = args.per_file or not args.pooled
    res = identify_fleet(model, files, per_file=per_file, pooled=args.pooled or len(files) == 1, method=args.method,
                         scheduler=args.scheduler, workers=args.workers, cutoff=args.cutoff, min_speed=args.min_speed,
                         progress=lambda line: print(f"baseparams: {line}", file=sys.stderr),
                         covariance=args.covariance)
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
        if res.pooled_note() is not None:
            lines.append(f"note: {res.pooled_note()}")
        lines += [f"pooled estimate (std: {res.pooled.estimate.covariance}):",
                  f"  {'name':<20s} {'value':>14s} {'std':>11s}"]
        lines += [f"  {n:<20s} {v:14.6g} " + (f"{s:11.3g}" if np.isfinite(s) else f"{'n/a':>11s}") for n, v, s in
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
    from .io.urdf import identified_drives, write_urdf

    if result.fit.physical is None:
        raise BaseparamsError("--urdf needs --method physical: least squares gives base parameters, not bodies")
    if Path(args.model).suffix.lower() != ".urdf":
        raise BaseparamsError(f"--urdf needs a URDF model file, got {args.model}")
    drives, couplings = identified_drives(result)
    for note in write_urdf(args.model, args.urdf, robot, result.fit.physical.pi, "paper", drives=drives,
                           couplings=couplings, inputs=[args.data, args.validate]):
        print(f"baseparams: note: {note}", file=sys.stderr)
    print(f"baseparams: URDF written to {args.urdf}", file=sys.stderr)


def _write_identified_mjcf(args, result, log) -> None:
    """``--mjcf FILE``: a copy of the MJCF model with the identified inertias and drive terms, checked by MuJoCo."""
    from .io.mjcf_write import identified_mjcf

    for note in identified_mjcf(result, args.model, args.mjcf, log, inputs=[args.data, args.validate]):
        print(f"baseparams: note: {note}", file=sys.stderr)
    print(f"baseparams: MJCF written to {args.mjcf}", file=sys.stderr)


def _amplitude(args, robot) -> float | None:
    """``--amplitude``, or ``None``: the default (0.5 rad; a loop robot's largest excursion whose loops close)."""
    if args.amplitude is not None:
        if not args.amplitude > 0:
            raise BaseparamsError(f"--amplitude must be > 0 rad, got {args.amplitude}")
        return args.amplitude
    return None


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
        from .excitation import read_trajectory

        trajectory = read_trajectory(args.trajectory, robot)
    log, truth = simulate_log(robot, duration=args.duration, rate=args.rate, amplitude=_amplitude(args, robot),
                              noise=args.noise, seed=args.seed, rotor=args.rotor, friction=_friction(args.friction),
                              convention=args.convention, trajectory=trajectory, samples=args.samples)
    from .files import write_text

    _write(args.out, lambda tmp: write_log(tmp, log), args, "OUT")
    truth_path = write_text(str(args.out) + ".truth.json", json.dumps(truth, indent=2) + "\n", _inputs(args), "OUT")
    amp = (f", excursion {truth['amplitude']:.3g} (the largest of the defaults whose loops close)"
           if robot.has_loops and "amplitude" in truth and args.amplitude is None else "")
    print(f"{args.out}: {log.n_samples} samples of {len(log.joints)} joints{amp}; true parameters in {truth_path}")
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
        Subcommands ``robots``, ``analyze``, ``regressor``, ``identify``, ``predict``, ``simulate`` and
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
        s.add_argument("model", help=MODEL_HELP[s.prog.split()[-1]])
        s.add_argument("--floating", action="store_true",
                       help="attach the file's root link to the world by a floating (free) joint")
        s.add_argument("--strict-inertia", action="store_true",
                       help="refuse files with physically infeasible inertias of moving links (by "
                            "default they are noted and the analysis goes on: the base-parameter "
                            "structure does not depend on the values)")
        s.add_argument("--allow-infeasible-inertia", action="store_true", help=argparse.SUPPRESS)
        s.add_argument("--gravity", nargs=3, type=float, metavar=("GX", "GY", "GZ"),
                       help="gravity in the world frame [m/s^2] (default: the model's, 0 0 -9.81)")
        _xacro_args(s)
        _samples_args(s)
        s.add_argument("--seed", type=int, default=0, help="random seed")
        s.add_argument("--json", action="store_true", help="print one JSON object")

    s = sub.add_parser("analyze", help="base parameters of a robot (certified)")
    model_args(s)
    s.add_argument("--no-verify", action="store_true", help="skip the numerical certification")
    s.add_argument("--paper-only", action="store_true",
                   help="the paper's three principles only (no extended rules R-A, R-B, R-L1, R-L2, R-M)")
    s.add_argument("--rows", default=str(Rows.ALL), metavar="ROWS",
                   help="measured generalized forces: all (default); joints (joint torques only); base (the "
                        "floating base's wrench only); joints:NAME,NAME (only these joints' torques); "
                        "base+joints:NAME,... (the base wrench and these); passive:NAME,... (every row but "
                        "these joints': an under-actuated robot)")
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
    s.add_argument("--method", choices=("auto", "ols", "wls", "physical"), default="auto",
                   help="auto (default): least squares with the model file's parameters as a prior (terms the data "
                        "determine keep their fitted values), the weighting and the prior's weight chosen by blocked "
                        "cross-validation on the training data; ols, wls (per-joint noise) or physical (physically "
                        "consistent) least squares")
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
    s.add_argument("--allow-units", action="store_true",
                   help="go on when the log's units look wrong (deg/s, ms, mN m, absurd samples); refused otherwise")
    s.add_argument("--covariance", choices=("hac", "white"), default="hac",
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


def _log_size_args(s) -> None:
    """``identify``'s options for long logs (streamed) and many logs (a fleet on Dask)."""
    s.add_argument("--stream", choices=("auto", "on", "off"), default="auto",
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
    """``baseparams excite MODEL``: design an excitation trajectory (:mod:`baseparams.excitation`).

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
    from .excitation import design_excitation

    try:
        robot = _robot(args)
    except NoMovingBodiesError as exc:
        raise BaseparamsError(f"{exc}: no actuated coordinate to excite") from None
    f = 1.0 / args.period if args.period else (args.base_frequency or 0.1)
    target = robot
    if args.samples is not None:
        from .analysis import analyze

        target = analyze(robot, samples=args.samples, seed=args.seed)
    result = design_excitation(target, harmonics=args.harmonics, base_frequency=f, rate=args.rate,
                               criterion=args.criterion, drives=args.drives, rotor=args.rotor,
                               acceleration=_acceleration(args.acceleration), torque=args.torque, starts=args.starts,
                               seed=args.seed, grid=args.grid, keepout=_keepout(args.keepout), margin=args.margin,
                               progress=lambda msg: print(f"baseparams: {msg}", file=sys.stderr))
    if args.out:
        _write(args.out, result.to_csv, args, "--out")
        print(f"baseparams: trajectory written to {args.out}", file=sys.stderr)
    if args.plot:
        from .report.plots import trajectory_plot

        _write(args.plot, lambda tmp: trajectory_plot(result, tmp, robot), args, "--plot")
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


def _inputs(args) -> list[str]:
    """The run's input files (model, logs, mapping, trajectory): outputs must not overwrite them."""
    out = [args.model] if getattr(args, "model", None) and Path(args.model).exists() else []
    if getattr(args, "data", None):
        out += _data_files(args.data)
    out += [getattr(args, k) for k in ("validate", "columns", "trajectory") if getattr(args, k, None)]
    return out


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
    """One output path: a known suffix, an existing folder, not a folder itself, not an input."""
    from .files import refuse_inputs

    p = Path(path)
    if suffixes and p.suffix.lower() not in suffixes:
        raise BaseparamsError(f"{flag} {path}: the format comes from the suffix: {', '.join(suffixes)}, "
                              f"not {p.suffix or 'none'}")
    if p.exists() and not p.is_file():
        raise BaseparamsError(f"{flag} {path}: exists and is not a regular file (a folder?)")
    if not p.resolve().parent.is_dir():
        raise BaseparamsError(f"{flag} {path}: the folder {p.resolve().parent} does not exist")
    refuse_inputs(p, inputs, flag)


def _check_extras(args) -> None:
    """The optional modules the flags need, before any work."""
    cmd = args.command
    if getattr(args, "plot", None):
        _need("matplotlib", "--plot")
    model = getattr(args, "model", None)
    if model and _is_symbolic(model) or getattr(args, "symbolic", False):
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
    files = _data_files(args.data) + ([args.validate] if args.validate else [])
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
    if args.command == "simulate" and not args.noise >= 0:
        raise BaseparamsError(f"--noise is a standard deviation [N m], >= 0; got {args.noise}")
    if args.command == "identify" and args.joints is not None and not [j for j in args.joints.split(",") if j.strip()]:
        raise BaseparamsError("--joints needs joint names: --joints A,B,... (the joints to identify)")
    if args.command == "identify" and args.prior_weight is not None and args.method != "physical":
        raise BaseparamsError(f"--prior-weight applies to --method physical, not {args.method} (the default estimate "
                              "chooses its own pull by cross-validation)")
    if args.command == "identify" and (args.predictions or args.score_cutoff is not None):
        if args.holdout is None and args.validate is None:
            raise BaseparamsError("--predictions and --score-cutoff are about validation data: give --holdout SECONDS "
                                  "or --validate FILE (nothing was fitted)")
        if args.score_cutoff is not None and not args.score_cutoff > 0:
            raise BaseparamsError(f"--score-cutoff must be > 0 Hz, got {args.score_cutoff}")
    if args.command == "identify" and args.urdf:
        if args.method != "physical":
            raise BaseparamsError("--urdf needs --method physical: least squares gives base parameters, not bodies "
                                  "(nothing was fitted)")
        if Path(args.model).suffix.lower() != ".urdf" or not Path(args.model).is_file():
            raise BaseparamsError(f"--urdf writes the model file with the identified inertias: it needs a URDF "
                                  f"model file, got {args.model} (nothing was fitted)")
    if args.command == "identify" and args.mjcf:
        _check_mjcf_flags(args)
    if args.command == "excite":
        _keepout(args.keepout)
        _acceleration(args.acceleration)
        if args.period is not None and not args.period > 0:
            raise BaseparamsError(f"--period must be > 0 seconds, got {args.period}")
        if not 0.0 <= args.margin < 0.5:
            raise BaseparamsError(f"--margin is a fraction of each position range kept free at both ends, in "
                                  f"[0, 0.5); got {args.margin}")


def _check_mjcf_flags(args) -> None:
    """``identify --mjcf``: a physical fit of an MJCF or URDF model file (a URDF through MuJoCo's import)."""
    from .io.mjcf_write import check_mjcf_request

    check_mjcf_request(args.model, args.method, args.mjcf)


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
    inputs = _inputs(args)
    seen: dict[Path, str] = {}
    for flag, path, suffixes in _outputs(args):
        _check_output(flag, path, suffixes, inputs)
        key = Path(path).resolve()
        if key in seen:
            raise BaseparamsError(f"{flag} and {seen[key]} name the same file {path}")
        seen[key] = flag


def _write(path, writer, args, what: str):
    """Write an output atomically, never onto an input: ``writer(tmp_path)`` (:func:`baseparams.files.atomic_path`)."""
    from .files import atomic_path

    with atomic_path(path, _inputs(args), what) as tmp:
        writer(tmp)
    return Path(path)


def _acceleration(text: str | None):
    """``--acceleration A[,A...]`` as a float, a list, or None."""
    if not text:
        return None
    try:
        acc = [float(x) for x in text.split(",")]
    except ValueError:
        raise BaseparamsError(f"--acceleration expects A or A,A,... in rad/s^2, got {text!r}") from None
    return acc[0] if len(acc) == 1 else acc


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
    from .symbolic.analyze import TIME_LIMIT_S
    from .symbolic.report import codegen, format_symbolic, symbolic_json, symbolic_latex

    with Progress(args.verbose) as progress:
        progress(f"{robot.name}: DRNG on the symbolic geometry, exact regrouping"
                 + ("" if args.no_verify else ", checks against the numerical analysis"))
        result = symbolic_analysis(robot, convention=args.convention, seed=args.seed, check=not args.no_verify,
                                   progress=progress, max_seconds=TIME_LIMIT_S)
        if not args.no_verify:
            progress(f"probing {len(result.conditions) + len(robot.symbols)} conditions")
            probe(result)
    if args.codegen:
        from .files import write_text

        try:
            write_text(args.codegen, codegen(result), _inputs(args), "--codegen")
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


if __name__ == "__main__":
    sys.exit(main())
