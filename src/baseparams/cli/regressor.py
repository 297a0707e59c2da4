"""``baseparams regressor MODEL``: the TP regressor, timed on random states or of a states file.

The regressor of a states file is :func:`baseparams.workflow.states.states_regressor`'s.
"""

from __future__ import annotations

import json
import time

import numpy as np

from ..errors import BaseparamsError, NoMovingBodiesError
from . import common
from .common import EXIT_OK, no_moving_bodies, print_note
from .parser import model_args

#: the flags named otherwise than the keywords they give (``states_regressor(model, states, out=)``)
KEYWORDS: dict = {}
#: the flags that only say how the result is printed
CLI_ONLY = frozenset({"json"})


def add_parser(sub) -> None:
    """The ``regressor`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command's subparsers.
    """
    s = sub.add_parser("regressor", help="compute the TP regressor on random samples (or --states FILE)")
    model_args(s)
    s.set_defaults(func=run)
    s.add_argument("--states", metavar="FILE",
                   help="states from a file (CSV/TSV, NPZ, Parquet: q_<joint>, dq_<joint>, ddq_<joint>, as a log or "
                        "'excite --out'; loops: the actuated joints) instead of random samples")
    s.add_argument("--out", metavar="FILE", help="with --states: save the regressor: .npz (Y (S, m, 10 n), columns, "
                                                 "joints, t) or .csv/.tsv/.parquet (one row per sample and joint: "
                                                 "sample, joint, one column per parameter)")


def run(args) -> int:
    """``baseparams regressor MODEL``: time the TP regressor on random states (or ``--states FILE``).

    With ``--states FILE`` the states come from a file (``q_``, ``dq_``, ``ddq_<joint>`` columns,
    the log or the excite layout) and ``--out`` saves the regressor ``(S, m, 10 n)``: NPZ arrays
    ``Y`` (that shape), ``columns`` (parameter names), ``joints``, ``t``; CSV/TSV/Parquet one row
    per (sample, joint), columns ``sample, joint`` and one per parameter (row ``s * m + j`` is
    ``Y[s, j]``).

    For a robot with loops, the closed-loop regressor with respect to its independent (actuated)
    coordinates on loop-closed samples. Prints its shape and time (or one JSON object with
    ``--json``); columns in the ``paper`` convention (spatial pseudo-inertia at q = 0).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`baseparams.cli.build_parser`): ``model``, ``floating``, ``gravity``,
        ``strict_inertia``, ``samples`` (default 100), ``seed``, ``json``, ``states``, ``out``.

    Returns
    -------
    int
        The exit code: :data:`EXIT_OK` (also for a model without moving bodies).

    Raises
    ------
    BaseparamsError
        Bad input, or no sample closes the loops.
    """
    from ..numerics import closed_samples, sample_states
    from ..regressor import closed_regressor, regressor

    if args.out and not args.states:
        raise BaseparamsError("--out saves the regressor of --states FILE; give the states")
    try:
        robot = common.load_robot(args)
    except NoMovingBodiesError as exc:
        return no_moving_bodies(args, exc)
    if args.states:
        return _states(args, robot)
    rng = np.random.default_rng(args.seed)
    args.samples = args.samples or 100
    t0 = time.perf_counter()
    extra = ""
    if robot.has_loops:
        cs = closed_samples(robot, args.samples, rng)
        if cs.kept == 0:
            raise BaseparamsError(f"robot {robot.name!r}: none of {args.samples} samples closed the loops; check "
                                  f"the independent joints' limits")
        y = closed_regressor(robot, cs)
        kept = cs.kept
        extra = (f"; loops closed: {kept} of {args.samples} samples kept ({cs.not_converged} outside the "
                 f"workspace, {cs.branch_jumps} off the reference branch or past a singular configuration, "
                 f"{cs.ill_conditioned} ill-conditioned)")
        rows = f"{len(robot.actuated)} actuated coordinates"
    else:
        q, dq, ddq = sample_states(robot, args.samples, rng)
        y = regressor(robot, q, dq, ddq)
        kept = args.samples
        rows = f"{robot.dof} dofs"
    dt = time.perf_counter() - t0
    out = {"model": robot.name, "samples": args.samples, "kept": kept, "shape": list(y.shape),
           "closed_loops": robot.has_loops, "seconds": dt, "convention": "paper (spatial pseudo-inertia at q = 0)"}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{robot.name}: TP regressor {y.shape} (samples, {rows}, 10 x bodies) in {dt * 1e3:.2f} ms; "
              f"columns: paper convention (spatial pseudo-inertia at q = 0){extra}")
    return EXIT_OK


def _states(args, robot) -> int:
    """``regressor MODEL --states FILE [--out FILE]``: the TP regressor of given states, saved."""
    from ..workflow.states import states_regressor

    r = states_regressor(robot, args.states, out=args.out, source=args.model,
                         notes=lambda n: print_note(n, "regressor"))
    out = {"model": robot.name, "states": args.states, "samples": int(r.y.shape[0]), "shape": list(r.y.shape),
           "seconds": r.seconds, "out": args.out, "convention": "paper (spatial pseudo-inertia at q = 0)"}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{robot.name}: TP regressor {r.y.shape} (samples, joints, 10 x bodies) of {args.states} in "
              f"{r.seconds * 1e3:.2f} ms" + (f", written to {args.out}" if args.out else ""))
    return EXIT_OK
