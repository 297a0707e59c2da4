"""``baseparams excite``: its flags parsed into :func:`baseparams.excite`'s keywords, the summary printed.

The limit flags' text (``--position LO:HI,...``, ``--keepout LINK:Z``) is parsed here into the
keywords' values; everything else is :func:`baseparams.workflow.excite.excite`'s.
"""

from __future__ import annotations

import json
import sys

from ..errors import BaseparamsError, NoMovingBodiesError
from . import common
from .common import EXIT_OK, emit
from .parser import choices, flag_message, flag_notes, model_args

#: the flags named otherwise than :func:`baseparams.excite`'s keywords
KEYWORDS = {"samples": "analysis_samples"}
#: the flags that only say how the result is printed
CLI_ONLY = frozenset({"json"})


def parse_keepout(texts):
    """``--keepout LINK:Z`` (repeatable) as a list of ``(link, z)``, or None.

    Parameters
    ----------
    texts : str, list of str or None
        The option's values.

    Returns
    -------
    list of tuple or None
        ``[(link, z), ...]``, or None without the option.
    """
    if not texts:
        return None
    out = []
    for text in [texts] if isinstance(texts, str) else texts:
        link, sep, z = text.rpartition(":")
        try:
            out.append((link, float(z)) if sep and link else float("x"))
        except ValueError:
            raise BaseparamsError(f"--keepout expects LINK:Z (e.g. panda_link7:0.3), got {text!r}") from None
    return out


def _number(text: str, flag: str, pair: bool):
    """One value of a limit flag: a number, or with ``pair`` ``LO:HI``."""
    try:
        if not pair:
            return float(text)
        lo, sep, hi = text.partition(":")
        if not sep:
            raise ValueError
        return float(lo), float(hi)
    except ValueError:
        what = "LO:HI" if pair else "a number"
        raise BaseparamsError(f"{flag}: expected {what} per item, got {text!r}") from None


def parse_joint_limit(text: str | None, flag: str, pair: bool = False):
    """A limit flag's value: ``V`` (every joint), ``V,V,...`` (one per designed joint) or ``JOINT=V,...``.

    ``--position`` takes ``LO:HI`` for each ``V`` (``--position=-1:1``: a value starting with ``-``
    follows ``=``).

    Parameters
    ----------
    text : str or None
        The option's value.
    flag : str
        The option, for messages.
    pair : bool
        Values are ``LO:HI`` pairs.

    Returns
    -------
    float, tuple, list, dict or None
        What :func:`baseparams.excitation.limits.joint_values` takes: one value, a list (one per
        joint, in order), ``{joint: value}``; None without the option.
    """
    if not text:
        return None
    items = [x.strip() for x in text.split(",") if x.strip()]
    named = ["=" in x for x in items]
    if any(named) and not all(named):
        raise BaseparamsError(f"{flag}: give every item as JOINT=VALUE or none (one value, or one per joint in "
                              f"order), got {text!r}")
    if all(named) and items:
        pairs = [x.split("=", 1) for x in items]
        return {name.strip(): _number(v.strip(), flag, pair) for name, v in pairs}
    values = [_number(x, flag, pair) for x in items]
    if not values:
        raise BaseparamsError(f"{flag}: no value in {text!r}")
    return values[0] if len(values) == 1 else values


def limit_flags(args) -> dict:
    """The excite flags that set limits, as :func:`baseparams.workflow.excite`'s keywords.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    dict
        ``position``, ``velocity``, ``acceleration``, ``effort`` and ``keepout`` (None when not given).
    """
    return {"position": parse_joint_limit(args.position, "--position", pair=True),
            "velocity": parse_joint_limit(args.velocity, "--velocity"),
            "acceleration": parse_joint_limit(args.acceleration, "--acceleration"),
            "effort": parse_joint_limit(args.effort, "--effort"),
            "keepout": parse_keepout(args.keepout)}


def run(args) -> int:
    """``baseparams excite MODEL``: design an excitation trajectory (:func:`baseparams.workflow.excite`).

    Progress lines go to stderr; the summary (or ``--json``) to stdout or ``--output``; the
    trajectory to ``--out`` (CSV ``t, q_<joint>, dq_<joint>, ddq_<joint>``, what ``baseparams
    simulate --trajectory`` and a controller read) and a plot to ``--plot``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line: the model options and one flag per keyword of
        :func:`baseparams.workflow.excite`, ``--json``, ``--output``.

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
    from ..workflow import excite

    try:
        robot = common.load_robot(args)
    except NoMovingBodiesError as exc:
        raise BaseparamsError(f"{exc}: no actuated coordinate to excite") from None
    result = excite(robot, **keywords(args),
                    progress=lambda msg: print(f"baseparams: {flag_message(msg, 'excite')}", file=sys.stderr))
    for path, what in ((args.out, "trajectory"), (args.plot, "plot")):
        if path:
            print(f"baseparams: {what} written to {path}", file=sys.stderr)
    emit(args, json.dumps(result.to_json(), indent=2) if args.json else flag_notes(result.summary(), "excite"))
    return EXIT_OK


def keywords(args) -> dict:
    """The flags as :func:`baseparams.excite`'s keywords (the limit flags parsed: :func:`limit_flags`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    dict
        One keyword per flag.
    """
    return {"harmonics": args.harmonics, "period": args.period, "base_frequency": args.base_frequency,
            "rate": args.rate, "criterion": args.criterion, "drives": args.drives, "rotor": args.rotor,
            "torque": args.torque, "margin": args.margin, "starts": args.starts, "grid": args.grid, "seed": args.seed,
            "analysis_samples": args.samples, "out": args.out, "plot": args.plot, "payload": args.payload,
            "payload_noise": args.payload_noise, **limit_flags(args)}


def add_parser(sub) -> None:
    """The ``excite`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command's subparsers.
    """
    s = sub.add_parser("excite", help="design an excitation trajectory (Fourier series within the joint limits)")
    model_args(s)
    s.add_argument("--harmonics", type=int, default=5, help="harmonics per joint (default 5)")
    s.add_argument("--period", type=float, metavar="SECONDS", help="period of the trajectory (default 10 s)")
    s.add_argument("--base-frequency", type=float, metavar="HZ", help="base frequency (1 / period; not with --period)")
    s.add_argument("--rate", type=float, default=1000.0, help="the controller's sampling rate in Hz (default 1000)")
    s.add_argument("--criterion", metavar=choices("criterion"),
                   help="minimise the condition number of the column-scaled regressor (default), or maximise "
                        "log det of the information matrix (D-optimal: smaller standard deviations under noise; the "
                        "default with --payload)")
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
    s.add_argument("--payload", metavar="LINK",
                   help="design a short excitation that identifies a payload on LINK best (the joints that carry "
                        "it; default period 5 s, criterion logdet on the payload's columns)")
    s.add_argument("--payload-noise", type=float, metavar="NM",
                   help="with --payload: the torque noise of the predicted standard deviations (default 0.1 N m)")
    s.add_argument("--out", metavar="FILE", help="write the trajectory (CSV: t, q_, dq_, ddq_ per joint)")
    s.add_argument("--plot", metavar="FILE", help="plot q, dq, ddq per joint against the limits (PNG/SVG)")
    s.add_argument("--output", metavar="FILE", help="write the summary to FILE")
    s.set_defaults(func=run)
