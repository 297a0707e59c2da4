"""``baseparams identify MODEL DATA...``: one log (streamed or read whole), several recordings, or a fleet of logs.

Its flags are :func:`baseparams.identify`'s keywords (:func:`keywords`; ``--coupling`` is
``couplings=``, ``--analysis-samples`` ``analysis_samples=``), which the command calls: several
logs (files or glob patterns) are several recordings of the robot in one identification
(:func:`log_argument`); with ``--per-file`` / ``--pooled`` a fleet
(:func:`baseparams.workflow.identify.identify_logs`, on Dask).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from ..arguments import CHOICES, IDENTIFY
from ..display import counted
from . import common
from .common import EXIT_INPUT, EXIT_OK, Progress, data_files, emit, print_note
from .parser import choices, flag_message, flag_notes, ident_args, model_args

#: the flags named otherwise than :func:`baseparams.identify`'s keywords
KEYWORDS = {"data": "log", "coupling": "couplings", "samples": "analysis_samples"}
#: the flags that only say how the result is printed, or how a fleet of logs is run
CLI_ONLY = frozenset({"json", "verbose", "per_file", "pooled", "strict", "scheduler", "workers"})
#: the flags of :data:`baseparams.workflow.outputs.OUTPUTS` that the command writes itself (the report)
OWN_OUTPUTS = ("output",)

#: :func:`baseparams.identify`'s keywords given by flags (the model's and the log excepted)
IDENTIFY_KEYWORDS = ("validate", "holdout", "method", "friction", "rotor", "coulomb_width", "couplings", "cutoff",
                     "decimate", "min_speed", "prior_weight", "convention", "covariance", "score_cutoff",
                     "allow_units", "columns", "joints", "weld", "analysis_samples", "literal", "terms", "stream",
                     "save", "predictions", "urdf", "mjcf", "html", "plot", "truth", "seed", "effort", "gain_anchor")


def keywords(args) -> dict:
    """The flags as :func:`baseparams.identify`'s keywords (one keyword per flag).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    dict
        The keywords of :data:`IDENTIFY_KEYWORDS`.
    """
    dest = {v: k for k, v in KEYWORDS.items()}
    out = {k: getattr(args, dest.get(k, k)) for k in IDENTIFY_KEYWORDS}
    out["couplings"] = tuple(out["couplings"] or ())
    return out


def is_fleet(args) -> bool:
    """``--per-file`` / ``--pooled``: a fleet of logs on Dask (several logs without them: :func:`log_argument`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    bool
        Whether the run identifies a fleet of logs.
    """
    return bool(args.per_file or args.pooled)


def log_argument(args):
    """``DATA...`` as :func:`baseparams.identify`'s ``log``: one file, or the list of several recordings.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    str or list of str
        The file of one log; the files of several (each file or glob pattern given, in order).
    """
    files = data_files(args.data)
    return files[0] if len(files) == 1 else files


def run(args) -> int:
    """``baseparams identify MODEL DATA...``: base-parameter and drive values from joint logs.

    Parses nothing itself: the flags are :func:`baseparams.identify`'s keywords (:func:`keywords`),
    which checks the inputs and every output before the fit, streams large logs, and writes the
    outputs; several logs are several recordings in one identification (:func:`log_argument`);
    ``--per-file`` / ``--pooled`` a fleet (:func:`baseparams.workflow.identify.identify_logs`).

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
    from ..workflow.identify import Reporter, identify

    robot = common.load_robot(args)
    if is_fleet(args):
        return _identify_fleet(args, robot, data_files(args.data))
    with Progress(args.verbose) as progress:
        t0 = time.perf_counter()
        result = identify(robot, log_argument(args), **keywords(args),
                          progress=lambda line: progress(flag_message(line, "identify")),
                          _reporter=Reporter(notes=lambda line: print_note(line, "identify"), source=args.model))
        progress(f"identified in {time.perf_counter() - t0:.2f} s")
    emit(args, json.dumps(result.to_json(), indent=2) if args.json
         else flag_notes(format_identification(result), "identify"))
    return EXIT_OK


def _identify_fleet(args, robot, files: list[str]) -> int:
    """``identify`` over many logs on Dask (``--per-file`` / ``--pooled``)."""
    from ..workflow.identify import identify_logs

    res = identify_logs(robot, files, keywords(args), per_file=args.per_file or not args.pooled,
                        pooled=args.pooled or len(files) == 1, scheduler=args.scheduler, workers=args.workers,
                        progress=lambda line: print(f"baseparams: {flag_message(line, 'identify')}", file=sys.stderr))
    if args.json:
        emit(args, json.dumps(res.to_json(), indent=2))
        return _fleet_exit(args, res, files)
    model = res.model
    skipped = [s for s in res.skipped if s["stage"] == "read"]
    lines = [f"{robot.name}: {counted(len(files), 'log')}, {len(res.files)} used, {len(skipped)} skipped; "
             f"{counted(sum(f['used'] for f in res.files), 'sample')} used ({args.method}); "
             f"{counted(model.n_params, 'model parameter')}"]
    lines += [f"skipped: {flag_message(s['error'], 'identify')}" for s in res.skipped]
    lines += [f"{f['path']}: {w}" for f in res.files for w in f.get("warnings", ())]  # --allow-units went on
    lines += [f"note: {n}" for n in res.notes]  # what the options leave to the data that a fleet does not try
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
    emit(args, flag_notes("\n".join(lines), "identify"))
    return _fleet_exit(args, res, files)


def _fleet_exit(args, res, files: list[str]) -> int:
    """``--strict``: a fleet with a skipped log is an error (one line); otherwise the skips are reported only."""
    if args.strict and res.skipped:
        print(f"baseparams: error: --strict: {len(res.skipped)} of {counted(len(files), 'log')} skipped "
              f"(first: {flag_message(res.skipped[0]['error'], 'identify')})", file=sys.stderr)
        return EXIT_INPUT
    return EXIT_OK


def add_parser(sub) -> None:
    """The ``identify`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command's subparsers.
    """
    s = sub.add_parser("identify", help="identify base-parameter and drive values from a joint log")
    model_args(s)
    s.add_argument("data", nargs="+", help="the log (CSV/TSV, NPZ, Parquet, ROS 2 bag): t, q_<joint>, [dq_<joint>], "
                   "tau_<joint> (or cur_<joint>: --effort); several logs or a glob: several recordings in one "
                   "identification, each a cross-validation block (a Dask fleet with --per-file / --pooled)")
    s.add_argument("--columns", metavar="MAP", help="a TOML mapping file for any other layout (or a bag's topic)")
    s.add_argument("--validate", metavar="DATA2", help="validate on another log")
    s.add_argument("--holdout", type=float, metavar="SECONDS", help="validate on the log's last SECONDS (not with "
                                                                     "--validate)")
    s.add_argument("--method", metavar=choices("method"), default=IDENTIFY["method"],
                   help="auto (default): least squares with the model file's parameters as a prior (terms the data "
                        "determine keep their fitted values), the weighting and the prior's weight chosen by blocked "
                        "cross-validation on the training data; ols, wls (per-joint noise) or physical (physically "
                        "consistent) least squares")
    ident_args(s, rotor_auto=True)
    _model_class_args(s)
    s.add_argument("--coupling", action="append", metavar="NAME:JOINT=W,JOINT=W",
                   help="a motor driving several joints (coupled wrist): its velocity is sum W dq_JOINT, its torque "
                        "reaches each JOINT times W; adds Iam_NAME, Fvm_NAME, Fcm_NAME (with --rotor, viscous, "
                        "coulomb); repeatable")
    s.add_argument("--effort", metavar=choices("effort"), default=IDENTIFY["effort"],
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
    s.add_argument("--covariance", metavar=choices("covariance"), default=IDENTIFY["covariance"],
                   help="standard deviations: hac (default; Newey-West, true when residuals are correlated) or "
                        "white (the least-squares formula, residuals taken as uncorrelated)")
    s.add_argument("--score-cutoff", type=float, metavar="HZ",
                   help="validation: also score against the measured torques low-passed at HZ (zero-phase "
                        "Butterworth order 4); the main figure is against the raw measured torques")
    s.add_argument("--predictions", metavar="FILE",
                   help="write the predicted torques at every validation sample (t, tau_<joint>; from currents: "
                        "the joint-side torques and cur_<joint> [A]; .csv, .tsv or .parquet)")
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
    s.set_defaults(func=run)


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
    s.add_argument("--stream", metavar=choices("stream"), default=CHOICES["stream"][0],
                   help="read a CSV/TSV/Parquet log block by block, in memory independent of its length, with the "
                        "same result: auto (default) above 64 MB, on, off (read it whole)")
    s.add_argument("--per-file", action="store_true",
                   help="several logs (a glob such as 'logs/robot-*/*.parquet') as a fleet: one estimate per log "
                        "and the spread across them, on Dask")
    s.add_argument("--pooled", action="store_true", help="several logs as a fleet: one estimate from all of them, "
                                                              "on Dask")
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
