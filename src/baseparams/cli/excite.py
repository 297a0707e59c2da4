"""``baseparams excite``: design an excitation trajectory, and its options' parsers.

Imported by :func:`baseparams.cli.main` only when the command runs.
"""

from __future__ import annotations

import json
import sys

from ..errors import BaseparamsError, NoMovingBodiesError
from . import common
from .common import EXIT_OK, emit, write_output


def parse_keepout(text: str | None):
    """``--keepout LINK:Z`` as ``(link, z)``, or None.

    Parameters
    ----------
    text : str or None
        The option's value.

    Returns
    -------
    tuple or None
        ``(link, z)``, or None without the option.
    """
    if not text:
        return None
    link, sep, z = text.rpartition(":")
    try:
        value = float(z) if sep and link else float("x")
    except ValueError:
        raise BaseparamsError(f"--keepout expects LINK:Z (e.g. panda_link7:0.3), got {text!r}") from None
    if not abs(value) <= 1e6:
        raise BaseparamsError(f"--keepout {text}: the height Z must be a finite number in [-1e6, 1e6] m")
    return link, value


def parse_acceleration(text: str | None):
    """``--acceleration A[,A...]`` as a float, a list, or None.

    Parameters
    ----------
    text : str or None
        The option's value.

    Returns
    -------
    float, list of float or None
        The limit(s), or None without the option.
    """
    if not text:
        return None
    from ..arguments import check_value

    try:
        acc = [float(x) for x in text.split(",")]
    except ValueError:
        raise BaseparamsError(f"--acceleration expects A or A,A,... in rad/s^2, got {text!r}") from None
    acc = check_value(acc, "acceleration", cli=True).tolist()  # finite, > 0: nan is no limit at all
    return acc[0] if len(acc) == 1 else acc


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
    from ..excitation import design_excitation

    try:
        robot = common.load_robot(args)
    except NoMovingBodiesError as exc:
        raise BaseparamsError(f"{exc}: no actuated coordinate to excite") from None
    f = 1.0 / args.period if args.period else (args.base_frequency or 0.1)
    target = robot
    if args.samples is not None:
        from ..analysis import analyze

        target = analyze(robot, samples=args.samples, seed=args.seed)
    result = design_excitation(target, harmonics=args.harmonics, base_frequency=f, rate=args.rate,
                               criterion=args.criterion, drives=args.drives, rotor=args.rotor,
                               acceleration=parse_acceleration(args.acceleration), torque=args.torque,
                               starts=args.starts, seed=args.seed, grid=args.grid, keepout=parse_keepout(args.keepout),
                               margin=args.margin,
                               progress=lambda msg: print(f"baseparams: {msg}", file=sys.stderr))
    if args.out:
        write_output(args.out, result.to_csv, args, "--out")
        print(f"baseparams: trajectory written to {args.out}", file=sys.stderr)
    if args.plot:
        from ..report.plots import trajectory_plot

        write_output(args.plot, lambda tmp: trajectory_plot(result, tmp, robot), args, "--plot")
        print(f"baseparams: plot written to {args.plot}", file=sys.stderr)
    emit(args, json.dumps(result.to_json(), indent=2) if args.json else result.summary())
    return EXIT_OK
