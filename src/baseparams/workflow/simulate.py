"""``baseparams.simulate``: a synthetic joint log with known parameters (the ``simulate`` command's implementation).

:func:`check_simulate` holds every rule of its keywords that needs no model; :func:`simulate`
calls it first and the command line's preflight calls it before the model loads.
"""

from __future__ import annotations

import math
import os

from ..arguments import IDENTIFY
from ..display import counted
from ..errors import BaseparamsError
from ..model import Robot
from .inputs import input_files, robot_of
from .outputs import check_outputs

#: simulate's numeric keywords (each in :data:`baseparams.arguments.RANGES`)
NUMBERS = ("duration", "rate", "amplitude", "noise", "seed", "analysis_samples", "robots")

#: the random motion's keywords (None: a given trajectory's own, else these defaults; amplitude's depends on the robot)
RANDOM_MOTION = {"duration": 20.0, "rate": 500.0, "amplitude": None}


def simulate(model, trajectory=None, *, duration: float | None = None, rate: float | None = None,
             amplitude: float | None = None,
             noise: float = 0.0, seed: int = 0, rotor: bool = False, friction=IDENTIFY["friction"],
             convention: str = "khalil", analysis_samples: int | None = None, robots: int | None = None, out=None):
    """A synthetic joint log with known parameters: ``baseparams simulate`` (record, without a robot).

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot (a tree, fixed or floating base: docs/guides/log-layout.md; loops closed by the
        actuated joints); its own inertias are the true parameters.
    trajectory : Excitation, str, path or tuple, optional
        The motion: a designed :class:`Excitation`, its file (``excite --out``) or ``(t (S,), q,
        dq, ddq (S, m))``; default a random Fourier series (``duration``, ``rate``, ``amplitude``).
    duration, rate : float, optional
        Without ``trajectory``: length [s] (default 20) and sampling rate [Hz] (default 500).
    amplitude : float, optional
        Without ``trajectory``: joint excursion [rad or m] (default 0.5, within a loop robot's
        sampling box). These three are refused with a ``trajectory``: its own times and
        positions say them.
    noise : float
        Standard deviation of the Gaussian torque noise [N m], ``>= 0``.
    seed : int
        Seed of the trajectory, the drive parameters (the same with and without ``trajectory``) and
        the noise.
    rotor : bool
        Rotor inertias (the model's armature, else drawn).
    friction : str or iterable of str
        ``"viscous,coulomb,offset"`` (default), any of them, or ``"none"``.
    convention : str
        Convention of the true base parameters.
    analysis_samples : int, optional
        Random states of the base-parameter analysis.
    robots : int, optional
        A fleet (``--robots N``): ``robots`` logs written into the folder ``out``, one robot each
        with its bodies' inertias spread by 10 % (:func:`baseparams.fleet.simulate_fleet`).
    out : str or path, optional
        Also write the log there (``.csv``, ``.tsv`` or ``.npz``) and the truth to ``OUT.truth.json``
        (atomically, never onto an input); with ``robots``, the folder of the fleet's logs.

    Returns
    -------
    log : JointLog
        ``t``, ``q``, ``dq``, ``tau`` of the measured joints (what :func:`identify` takes); with
        ``robots``: the list of the log files written.
    truth : dict
        ``{"model", "convention", "noise", "parameters": [{"name", "value"}], "drives"}``
        (``Identification.compare_truth(truth)``); with ``robots``: None (each log's truth is beside
        it, ``<log>.truth.json``).

    Raises
    ------
    BaseparamsError
        Bad options (a trajectory for a floating base; a random motion of fewer samples than
        ``identify`` filters, :func:`~baseparams.ident.preprocess.shortest_log`), loops the
        trajectory does not close, an unwritable output.
    """
    from ..ident.drives import friction_terms

    kw = {"duration": duration, "rate": rate, "amplitude": amplitude, "noise": noise, "seed": seed, "rotor": rotor,
          "friction": friction, "convention": convention, "analysis_samples": analysis_samples, "robots": robots,
          "out": out}
    trajectory, inputs = check_simulate(model, trajectory, kw)
    duration = RANDOM_MOTION["duration"] if duration is None else duration
    rate = RANDOM_MOTION["rate"] if rate is None else rate
    robot = robot_of(model, "simulate")
    options = {"duration": duration, "rate": rate, "amplitude": amplitude, "noise": noise, "seed": seed,
               "rotor": rotor, "friction": friction_terms(friction), "convention": convention,
               "samples": analysis_samples}
    if robots is not None:
        return _fleet(robot, trajectory, out, robots, inputs, **options), None
    log, truth = _simulated(robot, trajectory, **options)
    if out is not None:
        import json

        from ..files import write_text
        from ..io.logs import write_log

        write_log(out, log, inputs, "out=")
        write_text(os.fspath(out) + ".truth.json", json.dumps(truth, indent=2) + "\n", inputs, "out=")
    return log, truth


def check_simulate(model, trajectory, keywords: dict) -> tuple:
    """Every rule of :func:`simulate`'s keywords that needs no model: types, ranges, sizes, the outputs.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The model as given (a file's inputs are never overwritten).
    trajectory : Excitation, str, path, tuple or None
        The motion as given.
    keywords : dict
        :func:`simulate`'s other keywords; those missing take their defaults.

    Returns
    -------
    trajectory : object
        The trajectory, arrays checked (``(t, q, dq, ddq)``) or as given.
    inputs : list of str
        The run's input files.

    Raises
    ------
    BaseparamsError
        The first keyword refused, in one line naming it.
    """
    from ..arguments import ArgumentError, ArgumentTypeError, check_flags, check_keywords, check_samples, check_total
    from ..ident.drives import friction_terms

    given = [n for n in RANDOM_MOTION if keywords.get(n) is not None]
    if trajectory is not None and given:
        one = len(given) == 1
        raise ArgumentError(f"simulate: {' and '.join(n + '=' for n in given)} {'sets' if one else 'set'} the random "
                            "motion, not a given trajectory= (its own times and positions say them): leave "
                            f"{'it' if one else 'them'} out, or the trajectory")
    k = {"robots": None, "out": None, **keywords}
    k.update({n: v for n, v in RANDOM_MOTION.items() if k.get(n) is None})
    check_keywords("simulate", **{n: k[n] for n in NUMBERS if n in k})
    check_flags("simulate", **{n: k[n] for n in ("rotor",) if n in k})
    if "friction" in k:
        friction_terms(k["friction"])
    if trajectory is None:
        per_log = k["duration"] * k["rate"]
        check_samples(per_log, 16, "simulate: duration= x rate=")
        _check_identifiable(k["duration"], k["rate"])
        if k["robots"] is not None:
            check_total(k["robots"] * per_log, "simulate: robots= x duration= x rate=")
    elif isinstance(trajectory, (tuple, list)):
        trajectory = _checked_arrays(trajectory)
    elif not isinstance(trajectory, (str, os.PathLike)) and not hasattr(trajectory, "trajectory"):
        raise ArgumentTypeError(f"simulate: trajectory= must be an Excitation, its file or (t, q, dq, ddq), got "
                                f"{type(trajectory).__name__}")
    inputs = input_files(model, trajectory)
    if k["robots"] is None:
        check_outputs("simulate", inputs, out=k["out"])
        if k["out"] is not None:
            from ..files import check_output

            check_output(os.fspath(k["out"]) + ".truth.json", inputs, "out=")
    elif k["out"] is not None:
        from ..arguments import check_path

        check_path(k["out"], "simulate: out=")
    return trajectory, inputs


def _check_identifiable(duration: float, rate: float) -> None:
    """Refuse a random motion too short for ``identify``: its low-pass's own rule.

    :func:`~baseparams.ident.preprocess.shortest_log` at the highest cutoff ``identify`` chooses by
    itself: a shorter log is refused there whatever its motion (and the random motion, scaled to its
    excursion over a fraction of its period, is far faster than a robot moves).
    """
    from ..arguments import ArgumentError
    from ..display import counted
    from ..ident.preprocess import CUTOFF_CAP, CUTOFF_DIVISOR, EDGE_PERIODS, shortest_log

    n, least = int(round(duration * rate)), shortest_log(rate)  # the samples fourier_trajectory makes
    if n < least:
        raise ArgumentError(
            f"simulate: duration={duration:g} at rate={rate:g} makes {counted(n, 'sample')}, too few to identify: "
            f"identify's low-pass (cutoff at most min(fs/{CUTOFF_DIVISOR:g}, {CUTOFF_CAP:g} Hz) = "
            f"{min(rate / CUTOFF_DIVISOR, CUTOFF_CAP):g} Hz) takes {EDGE_PERIODS:g} cutoff periods at each end and "
            f"refuses a log of fewer than {least} samples; duration={math.ceil(1e3 * least / rate) / 1e3:g} or more at "
            f"{rate:g} Hz "
            f"(the default: {RANDOM_MOTION['duration']:g} s)")


def _checked_arrays(trajectory) -> tuple:
    """``(t (S,), q, dq, ddq (S, m))`` checked: numbers, finite, shapes that agree, time increasing."""
    import numpy as np

    from ..arguments import ArgumentError, ArgumentTypeError, check_array

    if len(trajectory) != 4:
        raise ArgumentTypeError(f"simulate: trajectory= must be an Excitation, its file or (t, q, dq, ddq), got "
                                f"{counted(len(trajectory), 'item')}")
    t = check_array(trajectory[0], "simulate: trajectory t", 1)
    arrays = [check_array(x, f"simulate: trajectory {n}", 2) for n, x in zip(("q", "dq", "ddq"), trajectory[1:])]
    if any(a.shape != arrays[0].shape or len(a) != len(t) for a in arrays):
        raise ArgumentError(f"simulate: trajectory shapes differ: t {t.shape}, q, dq, ddq "
                            f"{[a.shape for a in arrays]} (S,) and (S, m)")
    if len(t) > 1 and not np.all(np.diff(t) > 0):
        raise ArgumentError("simulate: trajectory t must be strictly increasing")
    return (t, *arrays)


def _trajectory_of(robot: Robot, trajectory):
    """A trajectory given as a file, an Excitation or arrays, as ``(t, q, dq, ddq)`` arrays (or None).

    A file is read by the reader identify reads logs with (its checks); arrays are checked as it
    checks a log's values, so that the log written is one identify reads.
    """
    from ..ident.simulate import check_trajectory

    check_trajectory(robot, trajectory)
    if isinstance(trajectory, (str, os.PathLike)):
        from ..excitation import read_trajectory

        return read_trajectory(trajectory, robot)
    trajectory = getattr(trajectory, "trajectory", trajectory)  # an Excitation's samples
    if trajectory is not None:
        _check_plausible(robot, trajectory[1])
    return trajectory


def _check_plausible(robot: Robot, q) -> None:
    """Positions a log reader would refuse (an angle beyond 4 pi, a translation beyond 10 m): one line, naming them."""
    import numpy as np

    from ..arguments import ArgumentError
    from ..excitation.limits import design_coordinates
    from ..io.logs import MAX_ANGLE, MAX_TRAVEL, coordinate_kinds, unbounded_joints

    names = robot.coordinate_names(design_coordinates(robot))
    if q.shape[1] != len(names):
        raise ArgumentError(f"simulate: trajectory= has {counted(q.shape[1], 'column')} of q for the "
                            f"{counted(len(names), 'coordinate')} "
                            f"{names}")
    kinds = coordinate_kinds(robot)
    free = unbounded_joints(robot)  # continuous joints turn any number of times (the reader's rule)
    limit = np.array([MAX_TRAVEL if kinds.get(n) == "P" else np.inf if n in free else MAX_ANGLE for n in names])
    bad = np.abs(q) > limit
    if bad.any():
        k = int(np.argmax(bad.any(axis=0)))
        i = int(np.argmax(bad[:, k]))
        unit = "m" if kinds.get(names[k]) == "P" else "rad"
        raise ArgumentError(f"simulate: trajectory= q of {names[k]!r}, sample {i}: |q| = {abs(q[i, k]):.4g} {unit} > "
                            f"{limit[k]:.4g}: a log identify would refuse (degrees? millimetres?)")


def _simulated(robot: Robot, trajectory, **kw):
    """:func:`~baseparams.ident.simulate.simulate_log` of a trajectory given as a file, an Excitation or arrays."""
    from ..ident.simulate import simulate_log

    return simulate_log(robot, trajectory=_trajectory_of(robot, trajectory), **kw)


def _fleet(robot: Robot, trajectory, out, robots: int, inputs: list[str], **kw) -> list:
    """``simulate(..., robots=N)``: the fleet's logs in the folder ``out``."""
    from ..fleet import simulate_fleet

    if out is None:
        raise BaseparamsError("simulate: robots= writes a fleet of logs: give out= (a folder)")
    if os.path.isfile(out) or os.fspath(out) in inputs:
        raise BaseparamsError(f"simulate: with robots=, out= is a folder for the fleet's logs; {out} is a file")
    return simulate_fleet(robot, out, robots, trajectory=_trajectory_of(robot, trajectory), **kw)
