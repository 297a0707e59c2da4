"""``baseparams payload MODEL LOG --link LINK``: its flags parsed into :func:`baseparams.identify_payload`'s keywords.

One keyword per flag (:func:`keywords`); the rules are :mod:`baseparams.workflow.payload`'s
(``check_payload``, which the preflight asks before the model loads); this module prints the
report (or ``--json``) and the notes of what was written. ``excite --payload LINK`` is
:mod:`baseparams.cli.excite`'s.
"""

from __future__ import annotations

import json
import sys

from ..arguments import PAYLOAD, PAYLOAD_CHOICES
from . import common
from .common import EXIT_OK, emit
from .parser import model_args

#: the flags named otherwise than :func:`baseparams.identify_payload`'s keywords
KEYWORDS = {"samples": "analysis_samples"}
#: the flags that only say how the result is printed
CLI_ONLY = frozenset({"json"})
#: the choices of this command's options (not :data:`baseparams.arguments.CHOICES`: ``--method ls``, ``--rotor fit``)
CHOICES = PAYLOAD_CHOICES


def _choices(name: str) -> str:
    return "{" + ",".join(CHOICES[name]) + "}"


def add_parser(sub) -> None:
    """The ``payload`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command's subparsers.
    """
    s = sub.add_parser("payload", help="identify a payload on a link (mass, centre of mass, inertia) from a log, the "
                                       "robot known from its file or a saved identification")
    model_args(s)
    s.add_argument("log", help="the log with the payload: t, q_<joint>, [dq_<joint>], tau_<joint> of every joint "
                               "(CSV/TSV, NPZ, Parquet, a ROS 2 bag)")
    s.add_argument("--link", required=True, help="the link the payload is fixed to (or its joint's name)")
    s.add_argument("--result", metavar="RESULT.json",
                   help="a saved identification of the robot without the payload ('identify --save'; identify with "
                        "--rotor when the drives have rotor inertia): the known robot is its prediction (default: the "
                        "model file's rigid body and armature)")
    s.add_argument("--validate", metavar="LOG", help="another log with the payload: every sample predicted, RMS per "
                                                     "joint")
    s.add_argument("--columns", metavar="MAP", help="a TOML mapping file for any other log layout")
    s.add_argument("--method", metavar=_choices("method"), default=PAYLOAD["method"],
                   help="physical: a realizable body (cvxpy, Clarabel: extra 'ident'); ls: least squares; auto "
                        "(default): physical when installed")
    s.add_argument("--friction", default=",".join(PAYLOAD["friction"]),
                   help="friction terms fitted per moving joint (default viscous,coulomb,offset; 'none')")
    s.add_argument("--rotor", metavar=_choices("rotor"), default=PAYLOAD["rotor"],
                   help="the moving joints' rotor inertia: the file's (or the identification's), fitted, or auto "
                        "(default: fitted when the file / identification has none)")
    s.add_argument("--offsets", metavar=_choices("offsets"), default=PAYLOAD["offsets"],
                   help="the moving joints' torque offsets (with offset among --friction): kept when blocked "
                        "cross-validation on the log says so (auto, default), or always fitted (fit)")
    s.add_argument("--coulomb-width", type=float, metavar="RAD_S", help="smooth Coulomb friction tanh(dq / w)")
    s.add_argument("--min-speed", type=float, metavar="RAD_S",
                   help="a joint's samples slower than this are not fitted on its row (default: --slow-fraction of "
                        "its peak speed)")
    s.add_argument("--slow-fraction", type=float, default=PAYLOAD["slow_fraction"], metavar="F",
                   help="the default --min-speed as a fraction of each joint's peak speed (default 0.1)")
    s.add_argument("--still", type=float, default=PAYLOAD["still"], metavar="RAD",
                   help="a joint whose logged range is below this does not move (default 0.02 rad)")
    s.add_argument("--cutoff", type=float, metavar="HZ", help="low-pass cutoff (default from the log)")
    s.add_argument("--decimate", type=int, metavar="K", help="decimation factor (default from the rate and cutoff)")
    s.add_argument("--covariance", metavar=_choices("covariance"), default=PAYLOAD["covariance"],
                   help="standard deviations: hac, for correlated residuals (default), or white (the least-squares "
                        "formula)")
    s.add_argument("--memory-mb", type=float, default=PAYLOAD["memory_mb"], metavar="MB",
                   help="the largest regressor formed at once (default 512; the log is held whole)")
    s.add_argument("--prior", metavar="FILE.json",
                   help="hold what the motion does not identify at this payload: {\"mass\": kg, \"com\": [3] m, "
                        "\"inertia_com\": [[3x3]] kg m^2} in LINK's frame (or a saved payload's JSON)")
    s.add_argument("--predictions", metavar="FILE.csv", help="with --validate: the torques predicted with the payload "
                                                             "at every sample of that log (t, tau_<joint>)")
    s.add_argument("--save", metavar="FILE.json", help="write the result's JSON")
    s.add_argument("--urdf", metavar="FILE.urdf", help="write the URDF model with the payload as a fixed link")
    s.add_argument("--mjcf", metavar="FILE.xml", help="write the model as MJCF with the payload as a body")
    s.add_argument("--output", metavar="FILE", help="write the report to FILE")
    s.set_defaults(func=run)


def keywords(args) -> dict:
    """The flags as :func:`baseparams.identify_payload`'s keywords (one per flag).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    dict
        Every keyword but the model and the log.
    """
    names = ("link", "result", "validate", "columns", "method", "friction", "rotor", "offsets", "coulomb_width",
             "min_speed", "slow_fraction", "still", "cutoff", "decimate", "covariance", "memory_mb", "prior", "seed",
             "save", "urdf", "mjcf", "predictions")
    return {**{n: getattr(args, n) for n in names}, "analysis_samples": args.samples}


def run(args) -> int:
    """``baseparams payload MODEL LOG --link LINK``: :func:`baseparams.identify_payload` of the flags.

    Progress lines and the notes of what was written (and WARNINGs) go to stderr; the report (or
    ``--json``) to stdout or ``--output``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`add_parser`).

    Returns
    -------
    int
        :data:`EXIT_OK`.

    Raises
    ------
    BaseparamsError
        Bad input (model, log, result, options, outputs).
    """
    from ..workflow.payload import identify_payload
    from .parser import flag_message, flag_notes

    robot = common.load_robot(args)
    out = identify_payload(robot, args.log, **keywords(args), _source=args.model,
                           progress=lambda msg: print(f"baseparams: {flag_message(msg, 'payload')}", file=sys.stderr))
    for n in out.notes:
        if n.startswith(("--urdf", "--mjcf", "urdf=", "mjcf=", "result saved", "predictions of", "WARNING")):
            print(f"baseparams: {flag_message(n, 'payload')}", file=sys.stderr)
    emit(args, json.dumps(out.to_json(), indent=2) if args.json else flag_notes(out.summary(), "payload"))
    return EXIT_OK
