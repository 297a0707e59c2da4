"""``baseparams payload MODEL LOG --link LINK``: what the robot carries on a link; and ``excite --payload LINK``.

The command's parser (:func:`add_parser`, registered by :func:`baseparams.cli.build_parser` in one
line) and its handler (:func:`cmd_payload`): the flags become :func:`baseparams.identify_payload`'s
keywords (one per flag), the report (or ``--json``) goes to stdout or ``--output``. ``excite
--payload LINK`` (:func:`excite_flags`: its flags, on the ``excite`` parser) is :func:`baseparams.excite`'s
``payload=``.
"""

from __future__ import annotations

import json
import sys

from ..errors import BaseparamsError
from . import common
from .common import EXIT_OK, emit


def add_parser(sub, model_args) -> None:
    """Add the ``payload`` subcommand to the ``baseparams`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands.
    model_args : callable
        Adds the model's arguments (``MODEL``, ``--gravity``, ``--json``, ...) to a subparser (its help:
        ``baseparams.cli.MODEL_HELP["payload"]``).
    """
    s = sub.add_parser("payload", help="identify a payload on a link (mass, centre of mass, inertia) from a log, the "
                                       "robot known from its file or a saved identification")
    model_args(s)
    s.add_argument("log", help="the log with the payload: t, q_<joint>, [dq_<joint>], tau_<joint> of every joint "
                               "(CSV/TSV, NPZ, Parquet, a ROS 2 bag)")
    s.add_argument("--link", required=True, help="the link the payload is fixed to (or its joint's name)")
    s.add_argument("--result", metavar="RESULT.json",
                   help="a saved identification of the robot without the payload ('identify --save'): the known "
                        "robot is its prediction (default: the model file's rigid body and armature)")
    s.add_argument("--validate", metavar="LOG", help="another log with the payload: every sample predicted, RMS per "
                                                     "joint")
    s.add_argument("--columns", metavar="MAP", help="a TOML mapping file for any other log layout")
    s.add_argument("--method", choices=("auto", "physical", "ls"), default="auto",
                   help="physical: a realizable body (cvxpy, Clarabel: extra 'ident'); ls: least squares; auto "
                        "(default): physical when installed")
    s.add_argument("--friction", default="viscous,coulomb,offset",
                   help="friction terms fitted per moving joint (default viscous,coulomb,offset; 'none')")
    s.add_argument("--rotor", choices=("auto", "file", "fit"), default="auto",
                   help="the moving joints' rotor inertia: the file's (or the identification's), fitted, or auto "
                        "(default: fitted when the file / identification has none)")
    s.add_argument("--coulomb-width", type=float, metavar="RAD_S", help="smooth Coulomb friction tanh(dq / w)")
    s.add_argument("--min-speed", type=float, metavar="RAD_S",
                   help="a joint's samples slower than this are not fitted on its row (default: --slow-fraction of "
                        "its peak speed)")
    s.add_argument("--slow-fraction", type=float, default=0.1, metavar="F",
                   help="the default --min-speed as a fraction of each joint's peak speed (default 0.1)")
    s.add_argument("--still", type=float, default=0.02, metavar="RAD",
                   help="a joint whose logged range is below this does not move (default 0.02 rad)")
    s.add_argument("--cutoff", type=float, metavar="HZ", help="low-pass cutoff (default from the log)")
    s.add_argument("--decimate", type=int, metavar="K", help="decimation factor (default from the rate and cutoff)")
    s.add_argument("--covariance", choices=("hac", "white"), default="hac",
                   help="standard deviations: HAC, for correlated residuals (default), or the least-squares formula")
    s.add_argument("--memory-mb", type=float, default=512.0, metavar="MB",
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
    s.set_defaults(func=cmd_payload)


def _prior(path: str | None):
    """``--prior FILE.json``: ``{"mass", "com", "inertia_com"}``, or a saved payload's (its ``payload``)."""
    if path is None:
        return None
    from ..files import read_input_bytes

    try:
        doc = json.loads(read_input_bytes(path, 1 << 20))
    except (ValueError, UnicodeDecodeError) as exc:
        raise BaseparamsError(f"--prior {path}: not JSON ({exc})") from None
    doc = doc.get("payload", doc) if isinstance(doc, dict) else doc
    if not isinstance(doc, dict) or any(doc.get(k) is None for k in ("mass", "com", "inertia_com")):
        raise BaseparamsError(f"--prior {path}: expected an object with mass, com and inertia_com (numbers)")
    return {k: doc[k] for k in ("mass", "com", "inertia_com")}


def cmd_payload(args) -> int:
    """``baseparams payload MODEL LOG --link LINK``: :func:`baseparams.identify_payload` of the flags.

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
    from ..workflow_payload import identify_payload

    robot = common.load_robot(args)
    opts = {"method": args.method, "friction": args.friction, "rotor": args.rotor, "coulomb_width": args.coulomb_width,
            "min_speed": args.min_speed, "slow_fraction": args.slow_fraction, "still": args.still,
            "cutoff": args.cutoff, "decimate": args.decimate, "covariance": args.covariance,
            "prior": _prior(args.prior), "seed": args.seed, "memory_mb": args.memory_mb,
            **({"samples": args.samples} if args.samples else {})}
    out = identify_payload(robot, args.log, link=args.link, result=args.result, validate=args.validate,
                           columns=args.columns, save=args.save, urdf=args.urdf, mjcf=args.mjcf,
                           predictions=args.predictions, source=args.model,
                           progress=lambda msg: print(f"baseparams: {msg}", file=sys.stderr), **opts)
    for n in out.notes:
        if n.startswith(("--urdf", "--mjcf", "result saved", "predictions of", "WARNING")):
            print(f"baseparams: {n}", file=sys.stderr)
    emit(args, json.dumps(out.to_json(), indent=2) if args.json else out.summary())
    return EXIT_OK


def excite_flags(s) -> None:
    """``excite``'s payload flags: ``--payload LINK`` and the predicted sigmas' noise.

    Parameters
    ----------
    s : argparse.ArgumentParser
        The ``excite`` subparser.
    """
    s.add_argument("--payload", metavar="LINK",
                   help="design a short excitation that identifies a payload on LINK best (the joints that carry "
                        "it; default period 5 s, criterion logdet on the payload's columns)")
    s.add_argument("--payload-noise", type=float, default=0.1, metavar="NM",
                   help="with --payload: the torque noise of the predicted standard deviations (default 0.1 N m)")
    s.set_defaults(criterion=None)  # --criterion's default: cond, or logdet with --payload (baseparams.excite)

