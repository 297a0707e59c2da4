"""The loop as functions: design an excitation, record it without a robot, identify, predict.

:func:`excite`, :func:`simulate`, :func:`identify` and :func:`predict` are ``baseparams.excite``,
``baseparams.simulate``, ``baseparams.identify`` and ``baseparams.predict`` (the front door
re-exports them) and the one implementation behind the commands of those names: the command line
parses its flags into these keywords (one keyword per flag) and prints. The identification's
options are one checked object (:class:`~baseparams.ident.options.IdentOptions`, its defaults
:data:`baseparams.arguments.IDENTIFY`'s); the other checks and the outputs (checked before the work, written atomically,
never onto an input) live here.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

from .analysis import Analysis, analyze
from .arguments import IDENTIFY
from .errors import BaseparamsError, ModelWarning
from .model import Robot

if TYPE_CHECKING:  # the identification is imported by the functions that run it
    from .ident.options import IdentOptions


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
    from .arguments import (
        ArgumentError,
        ArgumentTypeError,
        brief,
        check_flags,
        check_keywords,
        check_path,
        check_progress,
    )
    from .excitation import design_excitation
    from .excitation.limits import given_limits

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
    _check_suffixes(False, plot=plot)
    check_progress(progress, "excite")
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
             noise: float = 0.0, seed: int = 0, rotor: bool = False, friction=IDENTIFY["friction"],
             convention: str = "khalil", analysis_samples: int | None = None, robots: int | None = None, out=None):
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
    from .ident.drives import friction_terms

    check_keywords("simulate", duration=duration, rate=rate, amplitude=amplitude, noise=noise, seed=seed,
                   analysis_samples=analysis_samples, robots=robots)
    check_flags("simulate", rotor=rotor)
    check_path(out, "simulate: out=", optional=True)
    if trajectory is None:
        check_samples(duration * rate, 16, "simulate: duration x rate")
    elif isinstance(trajectory, (tuple, list)):
        trajectory = _checked_arrays(trajectory)
    elif not isinstance(trajectory, (str, os.PathLike)) and not hasattr(trajectory, "trajectory"):
        from .arguments import ArgumentTypeError

        raise ArgumentTypeError(f"simulate: trajectory= must be an Excitation, its file or (t, q, dq, ddq), got "
                                f"{type(trajectory).__name__}")
    robot = robot_of(model, "simulate")
    inputs = input_files(model, trajectory)
    if robots is not None:
        return _fleet(robot, trajectory, out, robots, inputs, duration=duration, rate=rate, amplitude=amplitude,
                      noise=noise, seed=seed, rotor=rotor, friction=friction_terms(friction), convention=convention,
                      samples=analysis_samples), None
    _check_outputs(inputs, out=out)
    log, truth = _simulated(robot, trajectory, duration=duration, rate=rate, amplitude=amplitude, noise=noise,
                            seed=seed, rotor=rotor, friction=friction_terms(friction), convention=convention,
                            samples=analysis_samples)
    if out is not None:
        import json

        from .files import write_text
        from .io.logs import write_log

        write_log(out, log, inputs, "out")
        write_text(os.fspath(out) + ".truth.json", json.dumps(truth, indent=2) + "\n", inputs, "out")
    return log, truth


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


# ---------------------------------------------------------------------------------------------- identify, predict
#: logs larger than this [MB] are streamed from their file by default (``stream="auto"``)
STREAM_MIN_MB = 64.0


def _opt(name: str, cli: bool) -> str:
    """An option's name in messages: ``--name`` for the command line, ``name=`` in Python."""
    return f"--{name.replace('_', '-')}" if cli else f"{name}="


def _log_of(log, robot: Robot, columns, require_tau: bool = True, subset: bool = False, name: str = "log"):
    """``log`` as a JointLog: a JointLog (values checked), or a log file read for ``robot`` (``read_log``)."""
    from .arguments import ArgumentTypeError
    from .jointlog import JointLog

    if isinstance(log, (str, os.PathLike)):
        from .io.logs import read_log

        return read_log(log, robot, columns=columns, allow_subset=subset or not require_tau, require_tau=require_tau)
    if not isinstance(log, JointLog):
        raise ArgumentTypeError(f"{name} must be a JointLog or a log file's path, got {type(log).__name__}")
    if columns is not None:
        raise BaseparamsError(f"columns= maps the columns of a log file; {name} is a JointLog already")
    return log.checked()


def _identification_logs(robot: Robot, log, inputs, note):
    """``(log, validation log or None, robot)``: the logs read, restricted to a sub-chain's ``joints``."""
    from .arguments import ArgumentTypeError, brief

    validate, columns, joints, weld = inputs.validate, inputs.columns, inputs.joints, inputs.weld
    weld_ok = weld is None or isinstance(weld, dict) or (isinstance(weld, (list, tuple))
                                                          and all(isinstance(w, str) for w in weld))
    if not weld_ok:
        raise ArgumentTypeError(f"identify: weld= must be {{'JOINT': value}} or ['JOINT=VALUE', ...], got "
                                f"{brief(weld)}")
    val = None if validate is None else _log_of(validate, robot, columns, subset=joints is not None, name="validate")
    log = _log_of(log, robot, columns, subset=joints is not None)
    if joints is None:
        if weld:
            raise BaseparamsError("identify: weld applies with joints (the joints to identify; the others are welded)")
        return log, val, robot
    from .ident.subchain import parse_welds, subchain

    names_ok = isinstance(joints, (list, tuple)) and all(isinstance(j, str) for j in joints)
    if not isinstance(joints, str) and not names_ok:
        raise ArgumentTypeError(f"identify: joints= must be 'A,B' or a sequence of joint names, got {brief(joints)}")
    names = [j.strip() for j in joints.split(",") if j.strip()] if isinstance(joints, str) else list(joints)
    welds = parse_welds(list(weld or ())) if not isinstance(weld, dict) else {k: float(v) for k, v in weld.items()}
    small, log, notes = subchain(robot, log, names, welds)
    if val is not None:
        val = subchain(robot, val, names, welds)[1]
    for n in notes:
        note(n)
    return log, val, small


def _warn(note: str) -> None:
    warnings.warn(note, ModelWarning, stacklevel=4)


@dataclass(frozen=True)
class Inputs:
    """What :func:`identify` reads besides the model, the log and the options (one field per flag).

    Parameters
    ----------
    validate : JointLog, str or path, optional
        Another log to validate on (exclusive with ``holdout``).
    columns : str, path or dict, optional
        A layout mapping for log files (TOML; README "Log layout").
    joints : str or sequence of str, optional
        Identify these joints only (``"A,B"``); every other joint is welded
        (:func:`baseparams.ident.subchain.subchain`).
    weld : dict or sequence of str, optional
        With ``joints``: where to weld others (``{"joint": value}`` or ``["JOINT=VALUE"]``, rad or m).
    stream : {"auto", "on", "off"}
        Stream a CSV/TSV/Parquet log from its file (``auto``: above :data:`STREAM_MIN_MB`).
    truth : dict, str or path, optional
        True parameters of a simulation (``simulate``'s ``OUT.truth.json``): compared per term
        (``result.truth``, the report's last section).
    source : str or path, optional
        The model file, when the model is a loaded Robot and an export needs the file.
    """

    validate: object = None
    columns: object = None
    joints: object = None
    weld: object = None
    stream: str = "auto"
    truth: object = None
    source: object = None

    def __repr__(self) -> str:
        given = [f"{f.name}={getattr(self, f.name)!r:.60}" for f in fields(self)
                 if getattr(self, f.name) is not None and getattr(self, f.name) != f.default]
        return f"Inputs({', '.join(given)})"


@dataclass(frozen=True)
class Outputs:
    """The files :func:`identify` writes (each checked before the fit, written atomically, never onto an input).

    Parameters
    ----------
    save : str or path, optional
        The result (``Identification.save``: versioned JSON).
    predictions : str or path, optional
        The predicted torques at every validation sample (``t, tau_<joint>``; CSV, TSV or Parquet
        by the suffix).
    urdf, mjcf : str or path, optional
        The identified bodies and drive terms written into a copy of the model file (URDF; MJCF
        through MuJoCo, checked by its inverse dynamics): need ``method="physical"`` and the
        model file.
    html, plot : str or path, optional
        A self-contained HTML report; a static figure of the torques (matplotlib).
    """

    save: object = None
    predictions: object = None
    urdf: object = None
    mjcf: object = None
    html: object = None
    plot: object = None

    def __repr__(self) -> str:
        return f"Outputs({', '.join(f'{k}={os.fspath(v)!r}' for k, v in self.given().items())})"

    def given(self) -> dict:
        """The outputs asked for.

        Returns
        -------
        dict
            ``{name: path}`` of the outputs that are not None, in field order.
        """
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}


@dataclass(frozen=True)
class Reporter:
    """How a run talks: progress lines, notes, and options named as flags or keywords.

    Parameters
    ----------
    progress : callable, optional
        Called with one line of text per step.
    notes : callable, optional
        Called with each note about the data and the outputs (default: :class:`ModelWarning` warnings).
    cli : bool
        Name options as command-line flags in messages.
    """

    progress: object = None
    notes: object = None
    cli: bool = False

    def __repr__(self) -> str:
        return f"<Reporter {'flags' if self.cli else 'keywords'}{', progress' if self.progress else ''}>"

    def say(self, line: str) -> None:
        """A progress line (nothing without ``progress``).

        Parameters
        ----------
        line : str
            The line.
        """
        if self.progress is not None:
            self.progress(line)

    def note(self, line: str) -> None:
        """A note (``notes``, else a :class:`ModelWarning`).

        Parameters
        ----------
        line : str
            The note.
        """
        (self.notes or _warn)(line)


def identify(model, log, *, validate=None, holdout: float | None = IDENTIFY["holdout"],
             method: str = IDENTIFY["method"], friction=IDENTIFY["friction"], rotor: bool = IDENTIFY["rotor"],
             coulomb_width: float | None = IDENTIFY["coulomb_width"], couplings=IDENTIFY["couplings"],
             cutoff: float | None = IDENTIFY["cutoff"], decimate: int | None = IDENTIFY["decimate"],
             min_speed: float | None = IDENTIFY["min_speed"], prior_weight: float | None = IDENTIFY["prior_weight"],
             convention: str = IDENTIFY["convention"], covariance: str = IDENTIFY["covariance"],
             score_cutoff: float | None = IDENTIFY["score_cutoff"], allow_units: bool = IDENTIFY["allow_units"],
             columns=None, joints=None, weld=None, analysis_samples: int | None = IDENTIFY["analysis_samples"],
             literal: bool = IDENTIFY["literal"], terms=IDENTIFY["terms"], stream: str = Inputs.stream, save=None,
             predictions=None, urdf=None, mjcf=None, html=None, plot=None, truth=None, seed: int = IDENTIFY["seed"],
             effort: str = IDENTIFY["effort"], gain_anchor: str | None = IDENTIFY["gain_anchor"], progress=None):
    """Identify base-parameter and drive values from a joint log: ``baseparams identify``.

    One keyword per flag of the command. The identification's options become one
    :class:`~baseparams.ident.options.IdentOptions` (checked at once; their defaults are
    :data:`baseparams.arguments.IDENTIFY`'s);
    the inputs, outputs and progress go to :func:`identify_command`, the implementation the
    command calls too.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot the log was recorded on (a floating base's pose in the log; loops closed by the
        actuated joints; a file for ``urdf``/``mjcf``).
    log : JointLog, str or path
        The log (:func:`simulate`, or a file: CSV/TSV, NPZ, Parquet, a ROS 2 bag; README "Log layout").
    holdout, method, friction, rotor, coulomb_width, couplings, cutoff, decimate, min_speed, prior_weight, \
convention, covariance, score_cutoff, allow_units, analysis_samples, literal, terms, seed, effort, gain_anchor
        The identification's options (:class:`~baseparams.ident.options.IdentOptions`: the
        hold-out [s], the estimator, the drive model, the filter, the second validation score's
        cutoff [Hz], the analysis' random states and seed, the model terms; torques or motor
        currents with unknown gains, the gains' anchor ``JOINT=K``).
    validate, columns, joints, weld, stream, truth
        What is read besides the log (:class:`Inputs`).
    save, predictions, urdf, mjcf, html, plot
        What is written (:class:`Outputs`).
    progress : callable, optional
        Called with one line of text per step.

    Returns
    -------
    Identification
        Values, standard deviations, validation (``.predict(log)``, ``.save(path)``,
        ``.compare_truth(truth)``, ``.to_json()``), and ``truth`` when given.

    Raises
    ------
    BaseparamsError
        Bad data (a floating base without its pose), options or outputs, data that do not excite
        the model.
    """
    from .arguments import check_keywords
    from .ident.options import IdentOptions

    check_keywords("identify", min_speed=min_speed)  # one speed, as the flag (ident.identify also takes one per joint)
    options = IdentOptions(method=method, rotor=rotor, friction=friction, coulomb_width=coulomb_width,
                           couplings=couplings, holdout=holdout, cutoff=cutoff, decimate=decimate, min_speed=min_speed,
                           prior_weight=prior_weight, convention=convention, covariance=covariance,
                           score_cutoff=score_cutoff, allow_units=allow_units, literal=literal, terms=terms,
                           analysis_samples=analysis_samples, seed=seed, effort=effort, gain_anchor=gain_anchor)
    inputs = Inputs(validate=validate, columns=columns, joints=joints, weld=weld, stream=stream, truth=truth)
    outputs = Outputs(save=save, predictions=predictions, urdf=urdf, mjcf=mjcf, html=html, plot=plot)
    return identify_command(model, log, options, inputs, outputs, Reporter(progress=progress))


def identify_command(model, log, options: IdentOptions, inputs: Inputs | None = None, outputs: Outputs | None = None,
                     reporter: Reporter | None = None):
    """Identify base-parameter and drive values from a joint log: what ``baseparams identify`` and :func:`identify` run.

    The options are checked already (:class:`~baseparams.ident.options.IdentOptions`); the inputs
    and every output are checked here before any work, the log is streamed from its file when it
    is large, and every output is written atomically, never onto an input.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot the log was recorded on.
    log : JointLog, str or path
        The log.
    options : IdentOptions
        How to identify.
    inputs : Inputs, optional
        What else is read (default: nothing).
    outputs : Outputs, optional
        What is written (default: nothing).
    reporter : Reporter, optional
        Progress, notes, and how options are named in messages (default: silent, warnings,
        keywords).

    Returns
    -------
    Identification
        As :func:`identify`.

    Raises
    ------
    BaseparamsError
        Bad data, inputs or outputs, data that do not excite the model.
    """
    from dataclasses import replace

    from .arguments import ArgumentTypeError, check_choice, check_path, check_progress
    from .ident.options import IdentOptions

    if not isinstance(options, IdentOptions):
        raise ArgumentTypeError(f"identify: options must be an IdentOptions, got {type(options).__name__}")
    inputs, outputs, reporter = inputs or Inputs(), outputs or Outputs(), reporter or Reporter()
    _check_suffixes(reporter.cli, predictions=outputs.predictions, urdf=outputs.urdf, html=outputs.html,
                    plot=outputs.plot)
    for name in (f.name for f in fields(Outputs)):
        check_path(getattr(outputs, name), f"identify: {name}=", optional=True)
    check_progress(reporter.progress, "identify")
    check_choice("identify", "stream", inputs.stream, ("auto", "on", "off"))
    if inputs.columns is not None and not isinstance(inputs.columns, (str, os.PathLike, dict)):
        raise ArgumentTypeError(f"identify: columns= must be a TOML file, a dict or a topic, got "
                                f"{type(inputs.columns).__name__}")
    robot = robot_of(model, "identify")
    source = inputs.source if inputs.source is not None else (model if isinstance(model, (str, os.PathLike)) else None)
    run = _Run(input_files(source if source is not None else model, log, inputs.validate, inputs.columns,
                           inputs.truth), reporter)
    truth_doc = _checked_outputs(source if source is not None else model, options, inputs, outputs, run)
    result, read = _run_identification(robot, log, options, inputs, outputs, run)
    _write_results(result, read, source, outputs, run)
    if truth_doc is not None:
        result = replace(result, truth=result.compare_truth(truth_doc, os.fspath(inputs.truth)
                                                            if not isinstance(inputs.truth, dict) else "truth"))
    return result


@dataclass(frozen=True)
class _Run:
    """One identify run: its input files (no output may overwrite one) and its reporter."""

    inputs: list
    reporter: Reporter


#: the suffixes an output may have, by option
SUFFIXES = {"predictions": (".csv", ".tsv", ".parquet"), "urdf": (".urdf",), "html": (".html", ".htm"),
            "plot": (".png", ".svg", ".pdf"), "out": (".csv", ".tsv")}


def _check_suffixes(cli: bool, **paths) -> None:
    """Each output's suffix among :data:`SUFFIXES` (one line naming the option), before any work."""
    from pathlib import Path

    from .arguments import ArgumentError, check_path

    for name, value in paths.items():
        if value is None:
            continue
        check_path(value, _opt(name, cli), optional=True)
        if Path(os.fspath(value)).suffix.lower() not in SUFFIXES[name]:
            raise ArgumentError(f"{_opt(name, cli)} {os.fspath(value)}: expected a {' or '.join(SUFFIXES[name])} "
                                f"file")


def _checked_outputs(source, options: IdentOptions, inputs: Inputs, outputs: Outputs, run: _Run):
    """Every output of :func:`identify` checked before the fit; the truth file read (or None)."""
    from .files import check_output

    cli = run.reporter.cli
    if (outputs.predictions is not None or options.score_cutoff is not None) and options.holdout is None \
            and inputs.validate is None:
        raise BaseparamsError(f"{_opt('predictions', cli)} and {_opt('score_cutoff', cli)} are about validation data: "
                              f"give {_opt('holdout', cli)} SECONDS or {_opt('validate', cli)} FILE (nothing was "
                              f"fitted)")
    for name, path in outputs.given().items():
        check_output(path, run.inputs, _opt(name, cli))
    check_exports(source, options.method, outputs.urdf, outputs.mjcf, inputs.joints, cli)
    truth = inputs.truth
    if truth is None or isinstance(truth, dict):
        return truth
    from .schema import read_truth

    return read_truth(truth, f"{_opt('truth', cli)} {truth}")


def check_exports(source, method: str, urdf=None, mjcf=None, joints=None, cli: bool = False) -> None:
    """Refuse, before any fit, an export that cannot be honoured (``urdf``, ``mjcf``).

    Parameters
    ----------
    source : object
        The model file (a path), or the model as given.
    method : str
        The identification method (exports need ``physical``).
    urdf, mjcf : str or path, optional
        The files to write.
    joints : object, optional
        The sub-chain asked for (exports need every joint).
    cli : bool
        Name options as command-line flags.

    Raises
    ------
    BaseparamsError
        One line saying what would help (nothing was fitted).
    """
    from pathlib import Path

    if (urdf is not None or mjcf is not None) and joints is not None:
        raise BaseparamsError(f"{_opt('urdf' if urdf is not None else 'mjcf', cli)} with {_opt('joints', cli)}: "
                              f"writing a sub-chain's values into the whole robot's file is not supported; identify "
                              f"every moving joint to export")
    if urdf is not None:
        if method != "physical":
            raise BaseparamsError(f"{_opt('urdf', cli)} needs {'--method physical' if cli else 'method=physical'}: "
                                  f"least squares gives base parameters, not bodies (nothing was fitted)")
        path = Path(os.fspath(source)) if isinstance(source, (str, os.PathLike)) else None
        if path is None or path.suffix.lower() != ".urdf" or not path.is_file():
            raise BaseparamsError(f"{_opt('urdf', cli)} writes the model file with the identified inertias: it needs "
                                  f"a URDF model file, got {source if path is not None else type(source).__name__} "
                                  f"(nothing was fitted)")
    if mjcf is not None:
        from .io.mjcf_write import check_mjcf_request

        check_mjcf_request(source, method, mjcf, _opt("mjcf", cli))


def _stream_reason(log, inputs: Inputs, mjcf, cli: bool) -> str | None:
    """Why the log is streamed from its file (a progress line), or None: read it whole."""
    from .io.logs import STREAM_SUFFIXES, streamable

    validate, joints, stream = inputs.validate, inputs.joints, inputs.stream
    if stream == "off" or not isinstance(log, (str, os.PathLike)):
        return None
    log = os.fspath(log)
    ok = streamable(log) and (validate is None or (isinstance(validate, (str, os.PathLike)) and streamable(validate)))
    if stream == "on":
        if not ok:
            raise BaseparamsError(f"{_opt('stream', cli)} on: only {', '.join(STREAM_SUFFIXES)} logs are streamed, "
                                  f"not {log}" + (f" / {validate}" if validate is not None else ""))
        if joints is not None or mjcf is not None:
            what = _opt("joints" if joints is not None else "mjcf", cli)
            raise BaseparamsError(f"{_opt('stream', cli)} on with {what}: the log is read whole for it "
                                  f"({_opt('stream', cli)} auto)")
        return f"{_opt('stream', cli)} on"
    if not ok or joints is not None or mjcf is not None:  # mjcf checks the model on the log's states
        return None
    from .io.logs import decoded_mb

    size = decoded_mb(log)  # a compressed Parquet file by the numbers it holds
    return f"{size:.0f} MB > {STREAM_MIN_MB:g} MB" if size > STREAM_MIN_MB else None


def _run_identification(robot: Robot, log, options: IdentOptions, inputs: Inputs, outputs: Outputs, run: _Run):
    """The fit: streamed from the log's file, or read whole; predictions written. ``(result, log read or None)``."""
    rep = run.reporter
    why = _stream_reason(log, inputs, outputs.mjcf, rep.cli) if not robot.floating else None
    if why is not None:
        from .ident.stream import NotStreamable

        rep.say(f"streaming {log} block by block ({why}): memory independent of the log's length")
        try:
            return _streamed(robot, log, options, inputs, outputs.predictions, run), None
        except NotStreamable as exc:
            rep.say(f"{exc}")
    from .ident import identify as run_whole

    rep.say(f"reading {log}" if isinstance(log, (str, os.PathLike)) else "checking the log")
    read, val, robot = _identification_logs(robot, log, inputs, rep.note)
    rep.say(f"identifying ({options.method}) on {read.n_samples} samples")
    result = run_whole(robot, read, options, validation=val, progress=rep.progress)
    if outputs.predictions is not None:
        _write_predictions(result, (read, val), options.holdout, outputs.predictions, run)
    return result, read


def _streamed(robot: Robot, log, options: IdentOptions, inputs: Inputs, predictions, run: _Run):
    """The identification streamed from the log's file; the predictions written as they come."""
    from .ident.stream import identify_stream
    from .io.logs import LogStream

    rep = run.reporter
    src = LogStream(log, robot, columns=inputs.columns)
    other = LogStream(inputs.validate, robot, columns=inputs.columns) if inputs.validate is not None else None
    if predictions is None:
        return identify_stream(robot, src, options, validation=other, progress=rep.progress)
    import numpy as np

    from .tables import column_writer

    names = ["t", *(f"tau_{j}" for j in robot.coordinate_names())]
    with column_writer(predictions, names, run.inputs, _opt("predictions", rep.cli)) as write:
        result = identify_stream(robot, src, options, validation=other, progress=rep.progress,
                                 predictions=lambda t, tau: write(np.column_stack([t, tau])))
    rep.note(f"predictions of {result.validation['samples']} validation samples written to {predictions}")
    return result


def _write_predictions(result, logs: tuple, holdout, path, run: _Run) -> None:
    """Predicted torques at every validation sample (``logs``: the log and the validation log or None)."""
    from .tables import write_columns

    log, val = logs
    whole = val if val is not None else log
    tau = result.predict(whole)
    keep = (whole.t >= -float("inf")) if val is not None else whole.t >= whole.t[-1] - holdout
    cols = {"t": whole.t[keep], **{f"tau_{j}": tau[keep, k] for k, j in enumerate(result.joints)}}
    if result.currents is not None:  # from currents: the joint-side torques and the motors' currents
        cur = result.predict_currents(whole)
        cols.update({f"cur_{m}": cur[keep, k] for k, m in enumerate(result.currents.motors)})
    write_columns(path, cols, run.inputs, _opt("predictions", run.reporter.cli))
    run.reporter.note(f"predictions of {int(keep.sum())} validation samples written to {path}")


def _write_results(result, log, source, outputs: Outputs, run: _Run) -> None:
    """``save``, ``urdf``, ``mjcf``, ``html``, ``plot`` (each checked before the fit; written atomically)."""
    inputs, say, note = run.inputs, run.reporter.say, run.reporter.note
    if outputs.save is not None:
        result.save(outputs.save, inputs, "save")
        say(f"result saved to {outputs.save}")
    if outputs.urdf is not None:
        from .ident.export import identified_drives
        from .io.urdf import write_urdf

        drives, couplings = identified_drives(result)
        tilt = next((t for t in result.fit.terms if t.name == "tilt"), None)
        for n in write_urdf(os.fspath(source), outputs.urdf, result.model.robot, result.fit.physical.pi, "paper",
                            drives=drives, couplings=couplings, inputs=inputs,
                            base_rotation=None if tilt is None else tilt.base_rotation()):
            note(n)
        for n in (x for t in result.fit.terms for x in t.export().get("not", [])):
            note(f"--urdf: not written: {n}")
        note(f"URDF written to {outputs.urdf}")
    if outputs.mjcf is not None:
        from .ident.export import identified_mjcf

        for n in identified_mjcf(result, os.fspath(source), outputs.mjcf, log, inputs=inputs):
            note(n)
        note(f"MJCF written to {outputs.mjcf}")
    if outputs.plot is not None:
        from .files import atomic_path
        from .report.plots import torque_plot

        with atomic_path(outputs.plot, inputs, "plot") as tmp:
            torque_plot(result, tmp)
        say(f"plot written to {outputs.plot}")
    if outputs.html is not None:
        from .files import write_text
        from .report.html import identification_html

        write_text(outputs.html, identification_html(result), inputs, "html")
        say(f"HTML report written to {outputs.html}")


def predict(model, result, log, *, raw_states: bool = False, columns=None, allow_units: bool = False):
    """Joint torques of a log from an identification: ``baseparams predict``.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot the result belongs to (its structure's fingerprint is checked).
    result : Identification, str or path
        The identification, or its saved file (``identify(..., save=...)``, ``--save``).
    log : JointLog, str or path
        The log or trajectory (``tau`` columns optional), e.g. an ``excite`` trajectory file.
    raw_states : bool
        The logged states as they are (default: low-passed at the identification's cutoff).
    columns : str, path or dict, optional
        A layout mapping for a log file.
    allow_units : bool
        Go on when the log's states look in other units (degrees, deg/s, rpm, ms, us, ns), which
        otherwise refuses (:func:`baseparams.ident.plausibility.check_states`).

    Returns
    -------
    ndarray, shape ``(S, m)``
        Predicted torques [N m or N] at every log sample; columns the measured joints
        (``Identification.joints``).

    Raises
    ------
    BaseparamsError
        Another robot than the result's, a bad result file or log.
    """
    from .arguments import ArgumentTypeError, check_flags

    check_flags("predict", raw_states=raw_states, allow_units=allow_units)
    robot = robot_of(model, "predict")
    if not isinstance(result, (str, os.PathLike)) and type(result).__name__ != "Identification":
        raise ArgumentTypeError(f"predict: result must be an Identification or its saved file, got "
                                f"{type(result).__name__}")
    if isinstance(result, (str, os.PathLike)):
        from .ident import Identification

        result = Identification.load(result, robot)
    from .ident.plausibility import check_prediction_log

    log = _log_of(log, robot, columns, require_tau=False)
    for n in check_prediction_log(result.model, log, allow_units):
        if "WARNING" in n:
            warnings.warn(n, ModelWarning, stacklevel=2)
    return result.predict(log, smooth=not raw_states)
