"""The loop's first steps as functions: design an excitation, record it without a robot.

:func:`excite` and :func:`simulate` are ``baseparams.excite`` and ``baseparams.simulate`` (the front
door re-exports them) and the one implementation behind the commands ``baseparams excite`` and
``baseparams simulate``: the command line parses its flags into these keywords (one keyword per
flag) and prints. Defaults, the checks of the options, and the outputs (checked before the work,
written atomically, never onto an input) live here only.
"""

from __future__ import annotations

import os
import warnings

from .analysis import Analysis, analyze
from .errors import BaseparamsError, ModelWarning
from .model import Robot

#: the default friction terms of ``simulate`` and ``identify`` (the CLI's ``--friction``)
FRICTION = ("viscous", "coulomb", "offset")


def robot_of(model, what: str) -> Robot:
    """``model`` as a Robot: a Robot, an Analysis's robot, or a built-in name / robot file.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The model; a name or file is loaded (:func:`baseparams.loading.load_model`, its notes as
        :class:`~baseparams.errors.ModelWarning` warnings).
    what : str
        The calling function, for messages.

    Returns
    -------
    Robot
        The robot.

    Raises
    ------
    BaseparamsError
        Another type, or what loading raises.
    """
    if isinstance(model, Robot):
        return model
    if isinstance(model, Analysis):
        return model.robot
    if isinstance(model, (str, os.PathLike)):
        from .loading import load_model

        robot, notes = load_model(os.fspath(model))
        for note in notes:
            warnings.warn(note, ModelWarning, stacklevel=3)
        return robot
    from .arguments import ArgumentTypeError

    raise ArgumentTypeError(f"{what}: model must be a Robot, an Analysis, a built-in name or a robot file, "
                            f"got {type(model).__name__}")


def input_files(*items) -> list[str]:
    """The items that are existing files (the run's inputs, which outputs must not overwrite).

    Parameters
    ----------
    *items : object
        Anything; paths of existing files are kept.

    Returns
    -------
    list of str
        The existing files among ``items``.
    """
    out = [os.fspath(x) for x in items if isinstance(x, (str, os.PathLike)) and os.path.isfile(x)]
    if items and isinstance(items[0], (str, os.PathLike)) and os.path.isfile(items[0]):
        from .io.sources import model_files  # a model file's own inputs: includes, assets, meshes

        out += [str(f) for f in model_files(items[0])[1:]]
    return out


def friction_of(friction) -> tuple[str, ...]:
    """``"viscous,coulomb"``, ``"none"`` or an iterable of names, as a tuple.

    Parameters
    ----------
    friction : str or iterable of str
        The friction terms.

    Returns
    -------
    tuple of str
        The names (empty for ``"none"``).
    """
    if isinstance(friction, str):
        return () if friction.strip().lower() in ("", "none") else tuple(x.strip() for x in friction.split(",")
                                                                         if x.strip())
    if not isinstance(friction, (list, tuple, set, frozenset)) or not all(isinstance(x, str) for x in friction):
        from .arguments import ArgumentTypeError

        raise ArgumentTypeError(f"friction= must be 'viscous,coulomb,offset', 'none' or a sequence of those names, "
                                f"got {type(friction).__name__}")
    return tuple(friction)


def excite(model, *, harmonics: int = 5, period: float | None = None, base_frequency: float | None = None,
           rate: float = 1000.0, criterion: str = "cond", drives: bool = False, rotor: bool = False,
           position=None, velocity=None, acceleration=None, effort=None, torque: bool = False, keepout=None,
           margin: float = 0.0, starts: int = 4, grid: int = 200, seed: int = 0, analysis_samples: int | None = None,
           limits=None, max_iter: int = 150, out=None, plot=None, progress=None):
    """Design an excitation trajectory: ``baseparams excite`` (:mod:`baseparams.excitation`).

    A finite Fourier series per designed coordinate, at rest at both ends, within the model's joint
    limits (or those given), optimised for the condition number of the identification regressor (or
    D-optimality).

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot (a built-in name or a robot file is loaded; its joint limits are the file's).
    harmonics, rate, criterion, drives, rotor, torque, margin, starts, grid, seed
        As the CLI's flags (:func:`baseparams.excitation.design_excitation`): harmonics per joint,
        the controller's rate [Hz], ``cond`` or ``logdet``, friction (and rotor) columns, the
        model's own torques within the effort limits, the fraction of each position range kept
        free, random starts, design-grid samples per period, the starts' seed.
    period, base_frequency : float, optional
        The period [s] or its inverse [Hz] (one of them; default 10 s).
    position : pair, sequence of pairs or dict, optional
        Position limits ``(lower, upper)`` [rad or m]: one pair for every designed joint, one per
        joint in order, or ``{joint: (lower, upper)}`` (``--position``); the model's elsewhere.
    velocity, acceleration, effort : float, sequence or dict, optional
        Velocity [rad/s], acceleration [rad/s^2] and effort [N m] limits, the same ways
        (``--velocity``, ``--acceleration``, ``--effort``; effort matters with ``torque``).
    keepout : tuple of (str, float), or sequence of them, optional
        ``(link, z_min)`` per link: its frame origin stays at or above ``z_min`` [m, world z] at
        every sample (``--keepout LINK:Z``, repeatable). Frame origins only: link geometry and
        self-collision are not checked.
    analysis_samples : int, optional
        Random states of the base-parameter analysis the model is built on.
    limits : array_like, shape ``(m, 4)``, optional
        ``[lower, upper, velocity, effort]`` per designed coordinate, overriding the model's
        (NaN keeps it); ``position``, ``velocity`` and ``effort`` override these.
    max_iter : int
        SLSQP iterations per start (Python only).
    out : str or path, optional
        Also write the trajectory there (``.csv``/``.tsv``: ``t, q_, dq_, ddq_``; checked before the
        design, written atomically).
    plot : str or path, optional
        Also plot ``q, dq, ddq`` per joint against the limits there (matplotlib, extra ``plot``).
    progress : callable, optional
        Called with one line of text per start.

    Returns
    -------
    Excitation
        The trajectory at ``rate`` over one period (``.trajectory``, ``.save(path)``, ``.summary()``):
        what :func:`simulate` and a robot controller take.

    Raises
    ------
    BaseparamsError
        Bad options or model, infeasible limits (naming the constraint that binds), an output
        that cannot be written.
    """
    from .excitation import design_excitation
    from .excitation.limits import given_limits

    _check_excite(harmonics, period, base_frequency, rate, criterion, drives, rotor, acceleration, torque, margin,
                  starts, grid, seed, analysis_samples, max_iter, out, plot, progress)
    if period is not None and base_frequency is not None:
        raise BaseparamsError("excite: give period or base_frequency, not both")
    if period is not None and not period > 0:
        raise BaseparamsError(f"excite: period must be > 0 seconds, got {period}")
    robot = robot_of(model, "excite")
    inputs = input_files(model)
    _check_outputs(inputs, out=out, plot=plot)
    target = model if isinstance(model, Analysis) and analysis_samples is None else robot
    if analysis_samples is not None:
        target = analyze(robot, samples=analysis_samples, seed=seed)
    f = 1.0 / period if period is not None else (0.1 if base_frequency is None else base_frequency)
    result = design_excitation(target, harmonics=harmonics, base_frequency=f, rate=rate, criterion=criterion,
                               drives=drives, rotor=rotor, limits=given_limits(robot, limits, position, velocity,
                                                                               effort),
                               acceleration=acceleration, torque=torque, starts=starts, seed=seed, grid=grid,
                               max_iter=max_iter, keepout=keepout, margin=margin, progress=progress)
    if out is not None:
        result.save(out, inputs, "out")
    if plot is not None:
        from .files import atomic_path
        from .report.plots import trajectory_plot

        with atomic_path(plot, inputs, "plot") as tmp:
            trajectory_plot(result, tmp, robot)
    return result


def _check_outputs(inputs: list[str], **outputs) -> None:
    """Each given output can be written and is no input (before any work)."""
    from .files import check_output

    for what, path in outputs.items():
        if path is not None:
            check_output(path, inputs, what)


def simulate(model, trajectory=None, *, duration: float = 20.0, rate: float = 500.0, amplitude: float | None = None,
             noise: float = 0.0, seed: int = 0, rotor: bool = False, friction=FRICTION, convention: str = "khalil",
             analysis_samples: int | None = None, robots: int | None = None, out=None):
    """A synthetic joint log with known parameters: ``baseparams simulate`` (record, without a robot).

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot (a tree, fixed or floating base: README "Log layout"; loops closed by the
        actuated joints); its own inertias are the true parameters.
    trajectory : Excitation, str, path or tuple, optional
        The motion: a designed :class:`Excitation`, its file (``excite --out``) or ``(t (S,), q,
        dq, ddq (S, m))``; default a random Fourier series (``duration``, ``rate``, ``amplitude``).
    duration, rate : float
        Without ``trajectory``: length [s] and sampling rate [Hz].
    amplitude : float, optional
        Without ``trajectory``: joint excursion [rad or m] (default 0.5, within a loop robot's
        sampling box).
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
        Bad options (a trajectory for a floating base), loops the trajectory does not close, an
        unwritable output.
    """
    from .arguments import check_flags, check_keywords, check_path, check_samples

    check_keywords("simulate", duration=duration, rate=rate, amplitude=amplitude, noise=noise, seed=seed,
                   analysis_samples=analysis_samples, robots=robots)
    check_flags("simulate", rotor=rotor)
    check_path(out, "simulate: out=", optional=True)
    if trajectory is None:
        check_samples(duration * rate, 16, "simulate: duration x rate")
    elif isinstance(trajectory, (tuple, list)):
        trajectory = _checked_arrays(trajectory)
    robot = robot_of(model, "simulate")
    inputs = input_files(model, trajectory)
    if robots is not None:
        return _fleet(robot, trajectory, out, robots, inputs, duration=duration, rate=rate, amplitude=amplitude,
                      noise=noise, seed=seed, rotor=rotor, friction=friction_of(friction), convention=convention,
                      samples=analysis_samples), None
    _check_outputs(inputs, out=out)
    log, truth = _simulated(robot, trajectory, duration=duration, rate=rate, amplitude=amplitude, noise=noise,
                            seed=seed, rotor=rotor, friction=friction_of(friction), convention=convention,
                            samples=analysis_samples)
    if out is not None:
        import json

        from .files import atomic_path, write_text
        from .io.logs import write_log

        with atomic_path(out, inputs, "out") as tmp:
            write_log(tmp, log)
        write_text(os.fspath(out) + ".truth.json", json.dumps(truth, indent=2) + "\n", inputs, "out")
    return log, truth


def _check_excite(harmonics, period, base_frequency, rate, criterion, drives, rotor, acceleration, torque, margin,
                  starts, grid, seed, analysis_samples, max_iter, out, plot, progress) -> None:
    """:func:`excite`'s keywords: ranges, types, paths, the progress callable (one line naming the first bad one)."""
    from .arguments import (
        ArgumentError,
        ArgumentTypeError,
        brief,
        check_flags,
        check_keywords,
        check_path,
        check_progress,
    )

    ranged = {} if isinstance(acceleration, dict) else {"acceleration": acceleration}
    check_keywords("excite", harmonics=harmonics, period=period, base_frequency=base_frequency, rate=rate,
                   margin=margin, starts=starts, grid=grid, seed=seed, analysis_samples=analysis_samples,
                   max_iter=max_iter, **ranged)
    check_flags("excite", drives=drives, rotor=rotor, torque=torque)
    if not isinstance(criterion, str):
        raise ArgumentTypeError(f"excite: criterion= must be cond or logdet, got {type(criterion).__name__}")
    if criterion not in ("cond", "logdet"):
        raise ArgumentError(f"excite: criterion= must be cond or logdet, got {brief(criterion)}")
    check_path(out, "excite: out=", optional=True)
    check_path(plot, "excite: plot=", optional=True)
    check_progress(progress, "excite")


def _checked_arrays(trajectory) -> tuple:
    """``(t (S,), q, dq, ddq (S, m))`` checked: numbers, finite, shapes that agree, time increasing."""
    import numpy as np

    from .arguments import ArgumentError, ArgumentTypeError, check_array

    if len(trajectory) != 4:
        raise ArgumentTypeError(f"simulate: trajectory= must be an Excitation, its file or (t, q, dq, ddq), got "
                                f"{len(trajectory)} items")
    t = check_array(trajectory[0], "simulate: trajectory t", 1)
    arrays = [check_array(x, f"simulate: trajectory {n}", 2) for n, x in zip(("q", "dq", "ddq"), trajectory[1:])]
    if any(a.shape != arrays[0].shape or len(a) != len(t) for a in arrays):
        raise ArgumentError(f"simulate: trajectory shapes differ: t {t.shape}, q, dq, ddq "
                            f"{[a.shape for a in arrays]} (S,) and (S, m)")
    if len(t) > 1 and not np.all(np.diff(t) > 0):
        raise ArgumentError("simulate: trajectory t must be strictly increasing")
    return (t, *arrays)


def _trajectory_of(robot: Robot, trajectory):
    """A trajectory given as a file, an Excitation or arrays, as ``(t, q, dq, ddq)`` arrays (or None)."""
    from .ident.simulate import check_trajectory

    check_trajectory(robot, trajectory)
    if isinstance(trajectory, (str, os.PathLike)):
        from .excitation import read_trajectory

        trajectory = read_trajectory(trajectory, robot)
    return getattr(trajectory, "trajectory", trajectory)  # an Excitation's samples


def _simulated(robot: Robot, trajectory, **kw):
    """:func:`~baseparams.ident.simulate.simulate_log` of a trajectory given as a file, an Excitation or arrays."""
    from .ident.simulate import simulate_log

    return simulate_log(robot, trajectory=_trajectory_of(robot, trajectory), **kw)


def _fleet(robot: Robot, trajectory, out, robots: int, inputs: list[str], **kw) -> list:
    """``simulate(..., robots=N)``: the fleet's logs in the folder ``out``."""
    from .fleet import simulate_fleet

    if out is None:
        raise BaseparamsError("simulate: robots= writes a fleet of logs: give out= (a folder)")
    if not (isinstance(robots, int) and robots >= 1):
        raise BaseparamsError(f"simulate: robots is a number of robots >= 1, got {robots!r}")
    if os.path.isfile(out) or os.fspath(out) in inputs:
        raise BaseparamsError(f"simulate: with robots, out is a folder for the fleet's logs; {out} is a file")
    return simulate_fleet(robot, out, robots, trajectory=_trajectory_of(robot, trajectory), **kw)
