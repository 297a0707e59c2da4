"""``baseparams excite``: its flags parsed into :func:`baseparams.workflow.excite`'s keywords, the summary printed.

Imported by :func:`baseparams.cli.main` only when the command runs.
"""

from __future__ import annotations

import json
import sys

from ..errors import BaseparamsError, NoMovingBodiesError
from . import common
from .common import EXIT_OK, emit


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
        if not abs(out[-1][1]) <= 1e6:
            raise BaseparamsError(f"--keepout {text}: the height Z must be a finite number in [-1e6, 1e6] m")
    return out


def _number(text: str, flag: str, pair: bool):
    """One value of a limit flag: a number, or with ``pair`` ``LO:HI``."""
    import math

    try:
        if not pair:
            value = float(text)
            if not math.isfinite(value):
                raise ValueError
            return value
        lo, sep, hi = text.partition(":")
        if not sep or not (math.isfinite(float(lo)) and math.isfinite(float(hi))):
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


def cmd_excite(args) -> int:
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
    result = excite(robot, harmonics=args.harmonics, period=args.period, base_frequency=args.base_frequency,
                    rate=args.rate, criterion=args.criterion, drives=args.drives, rotor=args.rotor,
                    torque=args.torque, margin=args.margin, starts=args.starts, grid=args.grid, seed=args.seed,
                    analysis_samples=args.samples, out=args.out, plot=args.plot, **limit_flags(args),
                    payload=args.payload, payload_noise=args.payload_noise,
                    progress=lambda msg: print(f"baseparams: {msg}", file=sys.stderr))
    for path, what in ((args.out, "trajectory"), (args.plot, "plot")):
        if path:
            print(f"baseparams: {what} written to {path}", file=sys.stderr)
    emit(args, json.dumps(result.to_json(), indent=2) if args.json else result.summary())
    return EXIT_OK
