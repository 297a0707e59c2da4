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
    input_files,
)


def cmd_identify(args) -> int:
    """``baseparams identify MODEL DATA``: base-parameter and drive values from a joint log.

    Parses nothing itself: the flags become the identification's options (:func:`options_of`,
    checked by the preflight), its inputs and its outputs (:func:`inputs_of`, :func:`outputs_of`),
    and :func:`baseparams.workflow.identify_command` checks the inputs and every output before the
    fit, streams large logs, and writes the outputs; a glob of logs is a fleet
    (:func:`baseparams.fleet.identify_fleet`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        :data:`EXIT_OK` (a fleet: :func:`_fleet_exit`).

    Raises
    ------
    BaseparamsError
        Bad input (model, data, options).
    """
    from ..ident.report import format_identification
    from ..workflow import Reporter, identify_command

    robot = common.load_robot(args)
    files = data_files(args.data)
    if len(files) > 1 or args.per_file or args.pooled:
        if args.joints:
            raise BaseparamsError("--joints applies to one log, not to a fleet of logs")
        if args.save or args.truth:
            raise BaseparamsError("--save and --truth apply to one log, not to a fleet (--per-file / --pooled)")
        return _identify_fleet(args, robot, files)
    with Progress(args.verbose) as progress:
        t0 = time.perf_counter()
        result = identify_command(robot, files[0], options_of(args), inputs_of(args), outputs_of(args),
                                  Reporter(progress=progress, notes=_print_note, cli=True))
        progress(f"identified in {time.perf_counter() - t0:.2f} s")
    emit(args, json.dumps(result.to_json(), indent=2) if args.json else format_identification(result))
    return EXIT_OK


def _print_note(line: str) -> None:
    """A note of the run on stderr (``baseparams: note: ...``; an output written: ``baseparams: ... written to``)."""
    print(f"baseparams: {'' if ' written to ' in line else 'note: '}{line}", file=sys.stderr)


def options_of(args):
    """The ``identify`` flags that are options of the identification, as one checked object (one field per flag).

    Built once per run (the preflight's, kept on ``args``): its errors name the flags
    (:meth:`baseparams.ident.options.IdentOptions.from_flags`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    IdentOptions
        The options.

    Raises
    ------
    BaseparamsError
        An option the identification refuses (``--prior-weight`` without ``--method physical``,
        an unknown ``--terms`` or ``--friction`` name, a bad ``--coupling``).
    """
    if getattr(args, "options", None) is not None:
        return args.options
    from ..ident.options import IdentOptions

    args.options = IdentOptions.from_flags(
        method=args.method, rotor=args.rotor, friction=args.friction, coulomb_width=args.coulomb_width,
        couplings=tuple(args.coupling or ()), holdout=args.holdout, cutoff=args.cutoff, decimate=args.decimate,
        min_speed=args.min_speed, prior_weight=args.prior_weight, convention=args.convention,
        covariance=args.covariance, score_cutoff=args.score_cutoff, allow_units=args.allow_units,
        literal=args.literal, terms=args.terms, analysis_samples=args.samples, seed=args.seed, effort=args.effort,
        gain_anchor=args.gain_anchor)
    return args.options


def inputs_of(args):
    """The ``identify`` flags of what is read besides the model and the log (one field per flag).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    Inputs
        :class:`baseparams.workflow.Inputs`.
    """
    from ..workflow import Inputs

    return Inputs(validate=args.validate, columns=args.columns, joints=args.joints, weld=args.weld,
                  stream=args.stream, truth=args.truth, source=args.model)


def outputs_of(args):
    """The ``identify`` flags of the files written (one field per flag).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    Outputs
        :class:`baseparams.workflow.Outputs`.
    """
    from ..workflow import Outputs

    return Outputs(save=args.save, predictions=args.predictions, urdf=args.urdf, mjcf=args.mjcf, html=args.html,
                   plot=args.plot)


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
    from ..ident import Identification
    from ..io.logs import read_log
    from ..tables import check_table_path

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
    cur = _currents(ident, log, args)  # a result from currents: the motors' currents too
    if args.out:
        _write_out(args.out, log.t, {f"tau_{j}": tau[:, k] for k, j in enumerate(joints)}, ident, cur, inputs)
    out = {"model": robot.name, "result": args.result, "log": args.log, "samples": log.n_samples, "joints": joints,
           "out": args.out, "prediction": "raw states" if args.raw_states else "smooth", "rms": None,
           **_current_figures(ident, log, cur)}
    if log.tau is not None:
        from ..ident import validation_scores

        s = validation_scores(log, tau, joints, score_cutoff=args.score_cutoff)
        out["rms"] = {"total": s["rms_total"], **s["rms"]}
        edge = _edge_samples(log, None if ident.options is None else ident.options.cutoff)
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
    print("\n".join(lines + (_current_lines(ident, out) if cur is not None else [])))
    return EXIT_OK


def _current_lines(ident, out: dict) -> list[str]:
    """A result from currents: the currents' RMS line, and what the torques are."""
    lines = []
    if out.get("rms_currents") is not None:
        r = out["rms_currents"]
        lines.append(f"RMS vs the measured currents at every sample: {r['total']:.4g} A (all motors); "
                     + ", ".join(f"{m} {r[m]:.3g}" for m in ident.currents.motors))
    regrouped = any(g["kind"] == "regrouped" for g in ident.currents.groups)
    return lines + ["torques: joint side (the rigid body; motor-side friction and rotor inertia excluded"
                    + (", the regrouped rotor inertias included: see the result's notes)" if regrouped else ")")]


def _write_out(path, t, torques: dict, ident, cur, inputs) -> None:
    """``--out``: ``t``, ``tau_<joint>`` and, for a result from currents, ``cur_<motor>``."""
    from ..tables import write_columns

    extra = {} if cur is None else {f"cur_{m}": cur[:, k] for k, m in enumerate(ident.currents.motors)}
    write_columns(path, {"t": t, **torques, **extra}, inputs, "--out")


def _currents(ident, log, args):
    """A result from currents: the predicted currents ``(S, m)`` [A] (None for a result from torques)."""
    return None if ident.currents is None else ident.predict_currents(log, smooth=not args.raw_states)


def _current_figures(ident, log, cur) -> dict:
    """A result from currents: what its torques are, and its currents' RMS against the log's [A] (None without)."""
    if cur is None:
        return {}
    out = {"torque": "joint side: the rigid body a joint-torque sensor after the gear reads (no motor-side friction "
                     "or rotor inertia)", "rms_currents": None}
    if log.cur is not None:
        from dataclasses import replace

        from ..ident import validation_scores

        s = validation_scores(replace(log, tau=log.cur), cur, list(ident.currents.motors))
        out["rms_currents"] = {"total": s["rms_total"], **s["rms"]}
    return out


def _edge_samples(log, cutoff) -> int:
    """Samples at each end of a log that carry the smoothing filter's edge transient (2 cutoff periods)."""
    if not cutoff or log.n_samples < 3:
        return 0
    rate = (log.n_samples - 1) / float(log.t[-1] - log.t[0])
    return int(np.ceil(2.0 * rate / float(cutoff)))


def _identify_fleet(args, robot, files: list[str]) -> int:
    """``identify`` over many logs on Dask (``--per-file`` / ``--pooled``)."""
    from ..fleet import identify_fleet
    from ..ident.model import model_for

    for opt in ("validate", "holdout", "plot", "urdf", "mjcf", "columns"):
        if getattr(args, opt):
            raise BaseparamsError(f"--{opt} applies to one log; with several (a fleet) use --per-file / --pooled")
    options = options_of(args)
    model = model_for(robot, options)
    per_file = args.per_file or not args.pooled
    res = identify_fleet(model, files, options, per_file=per_file, pooled=args.pooled or len(files) == 1,
                         scheduler=args.scheduler, workers=args.workers,
                         progress=lambda line: print(f"baseparams: {line}", file=sys.stderr))
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
