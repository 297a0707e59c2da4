"""``baseparams simulate``: its flags as :func:`baseparams.simulate`'s keywords, one line printed.

The simulation's modules are imported when the command runs.
"""

from __future__ import annotations

from ..display import counted
from . import common
from .common import EXIT_OK
from .parser import ident_args, model_args

#: the flags named otherwise than :func:`baseparams.simulate`'s keywords
KEYWORDS = {"samples": "analysis_samples"}
#: the flags that only say how the result is printed
CLI_ONLY = frozenset({"json"})


def add_parser(sub) -> None:
    """The ``simulate`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command's subparsers.
    """
    s = sub.add_parser("simulate", help="write a synthetic joint log with known parameters (tests, demos)")
    model_args(s)
    s.add_argument("out", help="output log (.csv or .npz); the true parameters go to OUT.truth.json")
    s.add_argument("--duration", type=float, default=None, help="seconds (default 20; not with --trajectory)")
    s.add_argument("--rate", type=float, default=None, help="sampling rate in Hz (default 500; not with --trajectory)")
    s.add_argument("--amplitude", type=float, default=None,
                   help="joint excursion in rad (default 0.5; for a robot with loops the largest of 0.8, 0.4, 0.2, "
                        "0.1 x its sampling box's half-width whose loops close; not with --trajectory)")
    s.add_argument("--noise", type=float, default=0.0, help="torque noise standard deviation (default 0)")
    s.add_argument("--robots", type=int, metavar="N",
                   help="a fleet: N logs in the folder OUT, one robot each with its own inertias (10 %% spread)")
    s.add_argument("--trajectory", metavar="FILE", help="simulate this trajectory (t, q_, dq_, ddq_ columns: "
                                                        "'baseparams excite --out') instead of a random one")
    ident_args(s)
    s.set_defaults(func=run)


def keywords(args) -> dict:
    """The flags as :func:`baseparams.simulate`'s keywords (the trajectory and the output among them).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    dict
        One keyword per flag.
    """
    return {"trajectory": args.trajectory, "duration": args.duration, "rate": args.rate, "amplitude": args.amplitude,
            "noise": args.noise, "seed": args.seed, "rotor": args.rotor, "friction": args.friction,
            "convention": args.convention, "analysis_samples": args.samples, "robots": args.robots, "out": args.out}


def run(args) -> int:
    """``baseparams simulate MODEL OUT``: a synthetic joint log with known parameters and noise.

    The excitation is a random finite Fourier series per joint (``--duration``, ``--rate``,
    ``--amplitude``, ``--seed``), or the trajectory of ``--trajectory FILE`` (``baseparams excite
    --out``: ``t, q_, dq_, ddq_`` columns); the torques are the model's own inertias plus drive terms
    (rotor inertia: the model's armature, else drawn; friction drawn), plus Gaussian noise
    (``--noise``). ``OUT`` (``.csv`` or ``.npz``, the default layout) and ``OUT.truth.json``:
    the true model parameters under their names, to compare an identification with. ``--robots N``:
    a fleet, ``N`` logs in the folder ``OUT``. Everything is :func:`baseparams.workflow.simulate`.

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
    from ..workflow import simulate

    robot = common.load_robot(args)
    log, truth = simulate(robot, **keywords(args))
    if args.robots:
        print(f"{args.out}: {counted(len(log), 'log')}, one robot each (true parameters beside each log)")
        return EXIT_OK
    why = "within the coupled joints' sampling box" if robot.only_couplings else "whose loops close"
    amp = (f", excursion {truth['amplitude']:.3g} (the largest of the defaults {why})"
           if robot.has_loops and "amplitude" in truth and args.amplitude is None else "")
    base = " and the floating base" if log.floating else ""
    print(f"{args.out}: {log.n_samples} samples of {log.n_joints} joints{base}{amp}; true parameters in "
          f"{args.out}.truth.json")
    return EXIT_OK
