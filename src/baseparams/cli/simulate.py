"""``baseparams simulate``: its flags as :func:`baseparams.workflow.simulate`'s keywords, one line printed.

Imported by :func:`baseparams.cli.main` only when the command runs.
"""

from __future__ import annotations

from ..errors import BaseparamsError
from . import common
from .common import EXIT_OK


def cmd_simulate(args) -> int:
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

    if args.amplitude is not None and not args.amplitude > 0:
        raise BaseparamsError(f"--amplitude must be > 0 rad, got {args.amplitude}")
    robot = common.load_robot(args)
    log, truth = simulate(robot, args.trajectory, duration=args.duration, rate=args.rate, amplitude=args.amplitude,
                          noise=args.noise, seed=args.seed, rotor=args.rotor, friction=args.friction,
                          convention=args.convention, analysis_samples=args.samples, robots=args.robots, out=args.out)
    if args.robots:
        print(f"{args.out}: {len(log)} logs, one robot each (true parameters beside each log)")
        return EXIT_OK
    why = "within the coupled joints' sampling box" if robot.only_couplings else "whose loops close"
    amp = (f", excursion {truth['amplitude']:.3g} (the largest of the defaults {why})"
           if robot.has_loops and "amplitude" in truth and args.amplitude is None else "")
    base = " and the floating base" if log.floating else ""
    print(f"{args.out}: {log.n_samples} samples of {log.n_joints} joints{base}{amp}; true parameters in "
          f"{args.out}.truth.json")
    return EXIT_OK
