"""``baseparams simulate``: a synthetic joint log with known parameters.

Imported by :func:`baseparams.cli.main` only when the command runs.
"""

from __future__ import annotations

import json

from ..errors import BaseparamsError
from . import common
from .common import EXIT_OK, friction_terms, input_files, write_output


def _amplitude(args, robot) -> float | None:
    """``--amplitude``, or ``None``: the default (0.5 rad; a loop robot's largest excursion whose loops close)."""
    if args.amplitude is not None:
        if not args.amplitude > 0:
            raise BaseparamsError(f"--amplitude must be > 0 rad, got {args.amplitude}")
        return args.amplitude
    return None


def cmd_simulate(args) -> int:
    """``baseparams simulate MODEL OUT``: a synthetic joint log with known parameters and noise.

    The excitation is a random finite Fourier series per joint (``--duration``, ``--rate``,
    ``--amplitude``, ``--seed``), or the trajectory of ``--trajectory FILE`` (``baseparams excite
    --out``: ``t, q_, dq_, ddq_`` columns); the torques are the model's own inertias plus drive terms
    (rotor inertia: the model's armature, else drawn; friction drawn), plus Gaussian noise
    (``--noise``). ``OUT`` (``.csv`` or ``.npz``, the default layout) and ``OUT.truth.json``:
    the true model parameters under their names, to compare an identification with.

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
    from ..ident.simulate import simulate_log
    from ..io.logs import write_log

    robot = common.load_robot(args)
    if args.robots:
        from ..fleet import simulate_fleet

        paths = simulate_fleet(robot, args.out, args.robots, duration=args.duration, rate=args.rate, noise=args.noise,
                               seed=args.seed, friction=friction_terms(args.friction))
        print(f"{args.out}: {len(paths)} logs, one robot each (true parameters beside each log)")
        return EXIT_OK
    trajectory = None
    if args.trajectory:
        from ..excitation import read_trajectory

        trajectory = read_trajectory(args.trajectory, robot)
    log, truth = simulate_log(robot, duration=args.duration, rate=args.rate, amplitude=_amplitude(args, robot),
                              noise=args.noise, seed=args.seed, rotor=args.rotor,
                              friction=friction_terms(args.friction), convention=args.convention, trajectory=trajectory,
                              samples=args.samples)
    from ..files import write_text

    write_output(args.out, lambda tmp: write_log(tmp, log), args, "OUT")
    truth_path = write_text(str(args.out) + ".truth.json", json.dumps(truth, indent=2) + "\n", input_files(args), "OUT")
    amp = (f", excursion {truth['amplitude']:.3g} (the largest of the defaults whose loops close)"
           if robot.has_loops and "amplitude" in truth and args.amplitude is None else "")
    base = " and the floating base" if log.floating else ""
    print(f"{args.out}: {log.n_samples} samples of {log.n_joints} joints{base}{amp}; true parameters in {truth_path}")
    return EXIT_OK
