"""``baseparams predict MODEL RESULT LOG``: torques of a log from a saved identification, and their RMS.

The prediction is :func:`baseparams.workflow.identify.prediction` (what :func:`baseparams.predict`
returns the torques of); this module prints it.
"""

from __future__ import annotations

import json

from . import common
from .common import EXIT_OK, print_note
from .parser import model_args

#: the flags named otherwise than :func:`baseparams.predict`'s keywords
KEYWORDS: dict = {}
#: the flags that only say what is printed (``--score-cutoff``: a second RMS,
#: :meth:`~baseparams.workflow.identify.Prediction.scores`)
CLI_ONLY = frozenset({"json", "score_cutoff"})


def add_parser(sub) -> None:
    """The ``predict`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command's subparsers.
    """
    s = sub.add_parser("predict", help="predict joint torques of a log from a saved identification (identify --save); "
                                       "from currents: the joint-side torques and the motors' currents")
    model_args(s, analysis=False)  # the model is rebuilt from the saved result's options
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
    s.set_defaults(func=run)


def keywords(args) -> dict:
    """The flags as :func:`baseparams.predict`'s keywords.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    dict
        ``raw_states``, ``columns``, ``allow_units``, ``out``.
    """
    return {"raw_states": args.raw_states, "columns": args.columns, "allow_units": args.allow_units, "out": args.out}


def run(args) -> int:
    """``baseparams predict MODEL RESULT LOG --out PRED``: torques of a log from a saved identification.

    Writes ``t, tau_<joint>`` (one row per log sample, the log's time stamps; CSV/TSV, or Parquet
    by the suffix; a result from motor currents: the joint-side torques, and ``cur_<joint>`` the
    currents [A], scored against the log's currents when it has them) and prints the RMS against
    the log's measured torques when it has them
    (:meth:`baseparams.workflow.identify.Prediction.scores`): predicted and measured torques both
    low-passed with the identification's zero-phase filter (parallel filtering, what identify's
    train and validation RMS compare; ``rms`` in JSON), and unfiltered (``rms_raw``, which also
    holds the sensor noise above the cutoff).

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
    from ..workflow.identify import Reporter, prediction

    robot = common.load_robot(args)
    p = prediction(robot, args.result, args.log, **keywords(args),
                   reporter=Reporter(notes=lambda line: print_note(line, "predict"), source=args.model))
    log, joints = p.log, p.result.joints
    out = {"model": robot.name, "result": args.result, "log": args.log, "samples": log.n_samples, "joints": joints,
           "out": args.out, "prediction": "raw states" if args.raw_states else "smooth", "rms": None,
           **(p.scores(args.score_cutoff) or {})}
    if args.json:
        print(json.dumps(out, indent=2))
        return EXIT_OK
    print("\n".join(_lines(robot.name, out, log.n_samples, joints) + _current_lines(p.result, out)))
    return EXIT_OK


def _current_lines(result, out: dict) -> list[str]:
    """A result from currents: the currents' RMS line, and what its torques are (``[]`` for one from torques)."""
    if result.currents is None:
        return []
    lines = []
    if out.get("rms_currents") is not None:
        r = out["rms_currents"]
        lines.append(f"RMS vs the measured currents at every sample: {r['total']:.4g} A (all motors); "
                     + ", ".join(f"{m} {r[m]:.3g}" for m in result.currents.motors))
    regrouped = any(g["kind"] == "regrouped" for g in result.currents.groups)
    return lines + ["torques: joint side (the rigid body; motor-side friction and rotor inertia excluded"
                    + (", the regrouped rotor inertias included: see the result's notes)" if regrouped else ")")]


def _lines(name: str, out: dict, samples: int, joints: list) -> list[str]:
    """The human report of a prediction: what was predicted, its RMS (interior, or every sample)."""
    what = "joint-side torques and motor currents" if "torque" in out else "joint torques"  # "torque": from currents
    lines = [f"{name}: predicted {len(joints)} {what} at {samples} samples"
             + (f", written to {out['out']}" if out["out"] else "")]
    if out.get("rms_interior") is not None:
        r = out["rms_interior"]
        lines.append(f"RMS vs the raw measured torques: {r['total']:.4g} (all joints) at the "
                     f"{samples - 2 * out['edge_samples']} samples away from the log's ends; "
                     + ", ".join(f"{j} {r[j]:.3g}" for j in joints)
                     + f" (the first and last {out['edge_samples']} samples carry the low-pass filter's edge "
                       f"transient: with them, {out['rms']['total']:.4g})")
    elif out["rms"] is not None:
        lines.append(f"RMS vs the raw measured torques at every sample: {out['rms']['total']:.4g} (all joints); "
                     + ", ".join(f"{j} {out['rms'][j]:.3g}" for j in joints))
    if "rms_lowpassed" in out:
        r = out["rms_lowpassed"]
        lines.append(f"RMS vs the measured torques low-passed at {out['score_cutoff']:g} Hz (--score-cutoff) at every "
                     f"sample: {r['total']:.4g} (all joints); " + ", ".join(f"{j} {r[j]:.3g}" for j in joints))
    return lines
