"""``baseparams identify`` (one log streamed or read whole, or a fleet of logs) and ``baseparams predict``.

Imported by :func:`baseparams.cli.main` only when one of these commands runs.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from ..errors import BaseparamsError
from . import common
from .common import (
    EXIT_INPUT,
    EXIT_OK,
    Progress,
    data_files,
    emit,
    friction_terms,
    input_files,
    write_html,
    write_output,
)


def _read_identification_logs(args, robot, path):
    """The training log, the validation log (or None) and the robot (a sub-chain with ``--joints``)."""
    from ..io.logs import read_log

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
    from ..ident.subchain import parse_welds, subchain

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
    from ..ident.drives import MotorCoupling
    from ..ident.pipeline import identify
    from ..ident.report import format_identification

    couplings = tuple(MotorCoupling.parse(text) for text in args.coupling or ())
    robot = common.load_robot(args)
    files = data_files(args.data)
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
            result.save(args.save, inputs=input_files(args), what="--save")
            progress(f"result saved to {args.save}")
        if args.urdf:
            _write_identified_urdf(args, robot, result)
        if args.mjcf:
            _write_identified_mjcf(args, result, log)
        if args.plot:
            from ..report.plots import torque_plot

            write_output(args.plot, lambda tmp: torque_plot(result, tmp), args, "--plot")
            progress(f"plot written to {args.plot}")
        if args.html:
            from ..report.html import identification_html

            write_html(args.html, identification_html(result), input_files(args))
    emit(args, _with_truth(args, result, truth, format_identification))
    return EXIT_OK


#: logs larger than this [MB] are streamed from their file by default (``identify --stream auto``)
STREAM_MIN_MB = 64.0


def _identify_kwargs(args, couplings) -> dict:
    """The options :func:`~baseparams.ident.pipeline.identify` and ``identify_stream`` share."""
    return dict(method=args.method, rotor=args.rotor, friction=friction_terms(args.friction),
                coulomb_width=args.coulomb_width, holdout=args.holdout, cutoff=args.cutoff, decimate=args.decimate,
                min_speed=args.min_speed, prior_weight=args.prior_weight, convention=args.convention,
                couplings=couplings, samples=args.samples, covariance=args.covariance, allow_units=args.allow_units,
                score_cutoff=args.score_cutoff, literal=args.literal, terms=args.terms)


def _stream_reason(args, path: str) -> str | None:
    """Why ``identify`` streams the log from its file (a line for ``-v``), or None: read it whole."""
    from ..io.logs import STREAM_SUFFIXES, streamable

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
    from ..io.logs import decoded_mb

    size = decoded_mb(path)  # a compressed Parquet file by the numbers it holds
    return f"{size:.0f} MB > {STREAM_MIN_MB:g} MB" if size > STREAM_MIN_MB else None


def _identify_streamed(args, robot, files, couplings, progress):
    """``identify`` on a log streamed from its file (``--stream``), or None when it is read whole.

    A log with non-uniform time stamps is read whole after all (said with ``-v``).
    """
    why = _stream_reason(args, files[0])
    if why is None:
        return None
    from ..ident.stream import NotStreamable, identify_stream
    from ..io.logs import LogStream

    progress(f"streaming {files[0]} block by block ({why}): memory independent of the log's length")
    stream = LogStream(files[0], robot, columns=args.columns)
    other = LogStream(args.validate, robot, columns=args.columns) if args.validate else None
    kwargs = _identify_kwargs(args, couplings)
    try:
        if not args.predictions:
            return identify_stream(robot, stream, validation=other, progress=progress, **kwargs)
        from ..io.tables import column_writer

        coords = robot.actuated if robot.has_loops else range(robot.dof)
        names = ["t", *(f"tau_{robot.joint_names[robot.dof_body[c]]}" for c in coords)]
        with column_writer(args.predictions, names, input_files(args), "--predictions") as write:
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
    from ..io.tables import write_columns

    whole = val if val is not None else log
    tau = result.predict(whole)
    keep = np.ones(whole.n_samples, dtype=bool) if val is not None else whole.t >= whole.t[-1] - args.holdout
    cols = {"t": whole.t[keep], **{f"tau_{j}": tau[keep, k] for k, j in enumerate(result.joints)}}
    write_columns(args.predictions, cols, input_files(args), "--predictions")
    print(f"baseparams: predictions of {int(keep.sum())} validation samples written to {args.predictions}",
          file=sys.stderr)


def _results_check(args, files: list[str]) -> dict | None:
    """``identify --save/--truth``: refused with several logs; the save path and the truth read now."""
    from ..io.tables import check_output_path

    if not (args.save or args.truth):
        return None
    if len(files) > 1 or args.per_file or args.pooled:
        raise BaseparamsError("--save and --truth apply to one log, not to a fleet (--per-file / --pooled)")
    check_output_path(args.save, input_files(args), "--save")
    if not args.truth:
        return None
    from ..schema import read_truth

    return read_truth(args.truth, f"--truth {args.truth}")


def _with_truth(args, result, truth: dict | None, text_report) -> str:
    """The report (text or JSON), with the comparison to ``--truth`` when given."""
    from ..ident.results import format_truth

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
    from ..ident.pipeline import Identification
    from ..io.logs import read_log
    from ..io.tables import check_table_path, write_columns

    inputs = input_files(args)
    check_table_path(args.out, inputs, "--out")
    if args.out and Path(args.out).suffix.lower() == ".npz":
        raise BaseparamsError(f"--out {args.out}: predictions are written as .csv, .tsv or .parquet")
    robot = common.load_robot(args)
    ident = Identification.load(args.result, robot)
    log = read_log(args.log, robot, columns=args.columns, allow_subset=True, require_tau=False)
    from ..ident.plausibility import check_prediction_log

    for note in check_prediction_log(ident.model, log, args.allow_units):  # the states' units (no torque needed)
        if "WARNING" in note:
            print(f"baseparams: note: {note}", file=sys.stderr)
    tau = ident.predict(log, smooth=not args.raw_states)
    joints = ident.joints
    if args.out:
        write_columns(args.out, {"t": log.t, **{f"tau_{j}": tau[:, k] for k, j in enumerate(joints)}}, inputs, "--out")
    out = {"model": robot.name, "result": args.result, "log": args.log, "samples": log.n_samples, "joints": joints,
           "out": args.out, "prediction": "raw states" if args.raw_states else "smooth", "rms": None}
    if log.tau is not None:
        from ..ident.pipeline import validation_scores

        s = validation_scores(log, tau, joints, score_cutoff=args.score_cutoff)
        out["rms"] = {"total": s["rms_total"], **s["rms"]}
        edge = _edge_samples(log, (ident.options or {}).get("cutoff"))
        if log.n_samples > 2 * edge + 1 and not args.raw_states:
            inner = np.zeros(log.n_samples, dtype=bool)
            inner[edge:log.n_samples - edge] = True
            si = validation_scores(log, tau, joints, inner)
            out["rms_interior"] = {"total": si["rms_total"], **si["rms"]}
            out["edge_samples"] = edge
        if "score_cutoff" in s:
            out["score_cutoff"] = s["score_cutoff"]
            out["rms_lowpassed"] = {"total": s["rms_lowpassed_total"], **s["rms_lowpassed"]}
    if args.json:
        print(json.dumps(out, indent=2))
        return EXIT_OK
    lines = [f"{robot.name}: predicted {len(joints)} joint torques at {log.n_samples} samples"
             + (f", written to {args.out}" if args.out else "")]
    if out.get("rms_interior") is not None:
        r = out["rms_interior"]
        lines.append(f"RMS vs the raw measured torques: {r['total']:.4g} (all joints) at the "
                     f"{log.n_samples - 2 * out['edge_samples']} samples away from the log's ends; "
                     + ", ".join(f"{j} {r[j]:.3g}" for j in joints)
                     + f" (the first and last {out['edge_samples']} samples carry the low-pass filter's edge "
                       f"transient: with them, {out['rms']['total']:.4g})")
    elif out["rms"] is not None:
        lines.append(f"RMS vs the raw measured torques at every sample: {out['rms']['total']:.4g} (all joints); "
                     + ", ".join(f"{j} {out['rms'][j]:.3g}" for j in joints))
        if "rms_lowpassed" in out:
            lines.append(f"RMS vs the measured torques low-passed at {out['score_cutoff']:g} Hz (--score-cutoff): "
                         f"{out['rms_lowpassed']['total']:.4g}")
    print("\n".join(lines))
    return EXIT_OK


def _edge_samples(log, cutoff) -> int:
    """Samples at each end of a log that carry the smoothing filter's edge transient (2 cutoff periods)."""
    if not cutoff or log.n_samples < 3:
        return 0
    rate = (log.n_samples - 1) / float(log.t[-1] - log.t[0])
    return int(np.ceil(2.0 * rate / float(cutoff)))


def _identify_fleet(args, robot, files: list[str]) -> int:
    """``identify`` over many logs on Dask (``--per-file`` / ``--pooled``)."""
    from ..fleet import identify_fleet
    from ..ident.model import ident_model

    for opt in ("validate", "holdout", "plot", "urdf", "mjcf", "columns"):
        if getattr(args, opt):
            raise BaseparamsError(f"--{opt} applies to one log; with several (a fleet) use --per-file / --pooled")
    from ..analysis import analyze

    model = ident_model(analyze(robot, convention=args.convention), args.rotor, friction_terms(args.friction),
                        args.coulomb_width)
    per_file = args.per_file or not args.pooled
    res = identify_fleet(model, files, per_file=per_file, pooled=args.pooled or len(files) == 1, method=args.method,
                         scheduler=args.scheduler, workers=args.workers, cutoff=args.cutoff, min_speed=args.min_speed,
                         progress=lambda line: print(f"baseparams: {line}", file=sys.stderr),
                         covariance=args.covariance)
    if args.json:
        emit(args, json.dumps(res.to_json(), indent=2))
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
    emit(args, "\n".join(lines))
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
    from ..io.urdf import identified_drives, write_urdf

    if result.fit.physical is None:
        raise BaseparamsError("--urdf needs --method physical: least squares gives base parameters, not bodies")
    if Path(args.model).suffix.lower() != ".urdf":
        raise BaseparamsError(f"--urdf needs a URDF model file, got {args.model}")
    drives, couplings = identified_drives(result)
    tilt = next((t for t in result.fit.terms if t.name == "tilt"), None)
    notes = write_urdf(args.model, args.urdf, robot, result.fit.physical.pi, "paper", drives=drives,
                       couplings=couplings, inputs=input_files(args),
                       base_rotation=None if tilt is None else tilt.base_rotation())
    notes += [f"--urdf: not written: {x}" for t in result.fit.terms for x in t.export().get("not", [])]
    for note in notes:
        print(f"baseparams: note: {note}", file=sys.stderr)
    print(f"baseparams: URDF written to {args.urdf}", file=sys.stderr)


def _write_identified_mjcf(args, result, log) -> None:
    """``--mjcf FILE``: a copy of the MJCF model with the identified inertias and drive terms, checked by MuJoCo."""
    from ..io.mjcf_write import identified_mjcf

    for note in identified_mjcf(result, args.model, args.mjcf, log, inputs=input_files(args)):
        print(f"baseparams: note: {note}", file=sys.stderr)
    print(f"baseparams: MJCF written to {args.mjcf}", file=sys.stderr)
