"""baseparams: base inertial parameters of robots from geometry (PGA / TP model / DRNG).

Which inertial parameters of a robot can be identified (the *base parameters*), why, and how
they regroup::

    >>> import baseparams
    >>> robot = baseparams.load("puma560")
    >>> result = baseparams.analyze(robot)
    >>> result
    <Analysis puma560: nullity 24, 36 base parameters (khalil), certified>

The front door
--------------
One function per subcommand of the command line, with its flags as keywords (``--base-frequency``
is ``base_frequency=``, ``--analysis-samples`` is ``analysis_samples=``); a ``model`` is a
:class:`Robot`, an :class:`Analysis`, a built-in name or a robot file.

load(model, floating=False, gravity=None, strict_inertia=False)
    A :class:`Robot` from a built-in name (``baseparams.robots.BUILTINS``) or a file (URDF,
    URDF+, MJCF); notes about the file are :class:`ModelWarning` warnings.
analyze(robot, *, samples=None, seed=0, verify=True, rows="all", convention="khalil", ...)
    DRNG, numerical certification, regrouping: an :class:`Analysis` (``baseparams analyze``).
analyze_symbolic(table, *, convention="khalil", seed=0, verify=True)
    Base parameters as formulas in a DH table's symbols (``analyze --symbolic``; SymPy, the
    extra ``symbolic``, imported only then).
regressor(robot, q, dq, ddq)
    The TP regressor ``(S, dof, 10 n)``, ``paper`` convention (``baseparams regressor``).
excite(model, *, harmonics=5, period=None, rate=1000.0, criterion="cond", drives=False, ..., out=None)
    Design an excitation trajectory: an :class:`Excitation` (``.trajectory``, ``.save(path)``).
simulate(model, trajectory=None, *, noise=0.0, seed=0, rotor=False, ..., out=None)
    Record without a robot: ``(log, truth)``, a synthetic joint log with the model's own
    parameters as the truth.
identify(model, log, *, holdout=None, validate=None, method="auto", friction=..., ..., save=None)
    Base-parameter and drive values from a joint log: an :class:`Identification`
    (``.values``, ``.std``, ``.save(path)``, ``Identification.load(path, robot)``,
    ``.predict(log)``, ``.compare_truth(truth)``).
predict(model, result, log, *, raw_states=False)
    Joint torques ``(S, m)`` of a log from an identification or its saved file.
Robot, RobotBuilder, Inertia, pose
    Build a robot in code (see :class:`RobotBuilder`).
CONVENTIONS
    Parameter conventions: ``paper`` (spatial pseudo-inertia entries in the world frame at
    q = 0, what the regressor multiplies), ``khalil``, ``pinocchio``, ``idyntree``, ``rpna``
    (link frames; ``baseparams.model.inertia``). Every parameter vector says its convention.
    The named choices (conventions, measured rows, statuses, joint types, DRNG provenance) are
    the enums of ``baseparams.enums``, equal to their strings.
BaseparamsError, ModelError
    Errors on bad input (``ModelError``: an invalid model).

``import baseparams`` loads NumPy and the model only: SciPy, MuJoCo, cvxpy, SymPy, matplotlib
and Dask are imported by the functions that need them. Everything else lives in submodules,
imported on first use: ``baseparams.robots``, ``baseparams.io`` (readers, URDF export,
Pinocchio interop), ``baseparams.nullspace`` (DRNG, certification), ``baseparams.base``
(regrouping), ``baseparams.numerics``, ``baseparams.pga``, ``baseparams.kinematics``,
``baseparams.model``, ``baseparams.symbolic`` (``SymbolicBuilder``, DH tables),
``baseparams.ident`` (the identification's building blocks: ``ident_model``, ``accumulate``,
``fit``), ``baseparams.excitation`` (the excitation designer's parts), ``baseparams.fleet``
(many logs on Dask). ``dir(baseparams)`` lists these and the names above. The name
``baseparams.regressor`` is the function above; the subpackage of the same name is imported as
usual (``from baseparams.regressor import regressor_tensor``).
"""

from __future__ import annotations

import importlib as _importlib
import os as _os
import warnings as _warnings

__version__ = "0.1.0"

# the subpackage first: importing it later would rebind ``baseparams.regressor`` to the module
from . import regressor as _regressor_pkg  # noqa: F401  (numpy only)
from .analysis import Analysis, analyze, regressor
from .arguments import ArgumentTypeError
from .errors import BaseparamsError, ModelError
from .model import CONVENTIONS, Inertia, Robot, RobotBuilder, pose

__all__ = [
    "CONVENTIONS",
    "Analysis",
    "BaseparamsError",
    "Excitation",
    "Identification",
    "Inertia",
    "ModelError",
    "ModelWarning",
    "Robot",
    "RobotBuilder",
    "__version__",
    "analyze",
    "analyze_symbolic",
    "excite",
    "identify",
    "load",
    "pose",
    "predict",
    "regressor",
    "simulate",
]

#: the documented subpackages, imported on first use (``dir(baseparams)`` shows these and ``__all__``)
_SUBMODULES = ("analysis", "base", "cli", "enums", "errors", "excitation", "fleet", "ident", "io", "kinematics",
               "model", "nullspace", "numerics", "pga", "robots", "symbolic")


class ModelWarning(UserWarning):
    """A note about a loaded model that does not stop the analysis.

    A physically infeasible inertia (the base-parameter structure does not depend on the
    values), a loop robot assembled or re-referenced because the file's q = 0 is not assembled
    (or is singular), or a warning of the file's reader.
    """


def load(model: str | _os.PathLike, floating: bool = False, gravity=None, strict_inertia: bool = False,
         xacro_args=None, package_path=None) -> Robot:
    """A robot from a built-in name or a file.

    Parameters
    ----------
    model : str or path
        A built-in name (``baseparams.robots.BUILTINS``: ``puma560``, ``go2``,
        ``four-bar``, ...) or a file: URDF / URDF+ (``.urdf``, loop joints and couplings
        included), a ROS xacro file (``.xacro``, e.g. ``robot.urdf.xacro``: expanded safely
        first, extra ``baseparams[xacro]``) or MJCF (``.xml``, ``.mjcf``, read through MuJoCo).
    floating : bool
        Attach the file's root link to the world by a floating (free) joint (files only).
    gravity : array_like, shape ``(3,)``, optional
        Gravity in the world frame [m/s^2]; default ``(0, 0, -9.81)``, for MJCF the model's.
    strict_inertia : bool
        Refuse physically infeasible inertias of moving links (:class:`ModelError`) instead of
        warning.
    xacro_args : mapping or iterable of str, optional
        A xacro file's arguments: ``{"NAME": "VALUE"}`` or ``["NAME:=VALUE", ...]``.
    package_path : str, path or list of them, optional
        Folders where a xacro file's ``$(find PKG)`` and ``package://PKG`` are looked up, before
        the ``BASEPARAMS_PACKAGE_PATH`` and ``ROS_PACKAGE_PATH`` variables.

    Returns
    -------
    Robot
        Bodies in depth-first order, each body's frame its joint frame; fixed joints merged;
        a robot with loops assembled at q = 0 (re-referenced if the file's q = 0 is not).

    Warns
    -----
    ModelWarning
        One per note about the model (the CLI prints the same notes as
        ``baseparams: note: ...``): infeasible inertias, loops assembled, reader warnings.

    Raises
    ------
    BaseparamsError
        No such file or built-in, an unknown file type, ``floating`` for a built-in.
    ModelError
        An invalid model (names the file, element and problem); ``NoMovingBodiesError`` when
        every link is welded to the world.

    Examples
    --------
    >>> robot = load("puma560")
    >>> robot.n, robot.dof
    (6, 6)
    """
    from .loading import load_model

    robot, notes = load_model(model, floating=floating, gravity=gravity, strict_inertia=strict_inertia,
                              xacro_args=xacro_args, package_path=package_path)
    for note in notes:
        _warnings.warn(note, ModelWarning, stacklevel=2)
    return robot


# ---------------------------------------------------------------- the whole loop: excite, simulate, identify, predict
#: the classes of the loop's results, imported on first use (``baseparams.Identification``)
_LAZY = {"Excitation": "excitation.result", "Identification": "ident.pipeline"}
#: the default friction terms of ``simulate`` and ``identify`` (the CLI's ``--friction``)
_FRICTION = ("viscous", "coulomb", "offset")


def _robot_of(model, what: str) -> Robot:
    """``model`` as a Robot: a Robot, an Analysis's robot, or a built-in name / robot file (:func:`load`)."""
    if isinstance(model, Robot):
        return model
    if isinstance(model, Analysis):
        return model.robot
    if isinstance(model, (str, _os.PathLike)):
        return load(model)
    raise ArgumentTypeError(f"{what}: model must be a Robot, an Analysis, a built-in name or a robot file, "
                    f"got {type(model).__name__}")


def _trajectory_of(trajectory) -> tuple:
    """``(t (S,), q, dq, ddq (S, m))`` checked: numbers, finite, shapes that agree, time increasing."""
    import numpy as np

    from .arguments import ArgumentError, check_array

    if not isinstance(trajectory, (tuple, list)) or len(trajectory) != 4:
        raise ArgumentTypeError(f"simulate: trajectory= must be an Excitation, its file or (t, q, dq, ddq), got "
                                f"{type(trajectory).__name__}")
    t = check_array(trajectory[0], "simulate: trajectory t", 1)
    arrays = [check_array(x, f"simulate: trajectory {n}", 2) for n, x in zip(("q", "dq", "ddq"), trajectory[1:])]
    if any(a.shape != arrays[0].shape or len(a) != len(t) for a in arrays):
        raise ArgumentError(f"simulate: trajectory shapes differ: t {t.shape}, q, dq, ddq "
                            f"{[a.shape for a in arrays]} (S,) and (S, m)")
    if len(t) > 1 and not np.all(np.diff(t) > 0):
        raise ArgumentError("simulate: trajectory t must be strictly increasing")
    return (t, *arrays)


def _bools(where: str, **flags) -> None:
    """Flags must be booleans (``rotor="no"`` would be true): a TypeError naming the first that is not."""
    from .arguments import check_flags

    check_flags(where, **flags)


def _paths_and_progress(where: str, progress=None, **paths) -> None:
    """Output paths (str or Path, or None) and a progress callable (or None), named when they are not."""
    from .arguments import check_path, check_progress

    for name, value in paths.items():
        check_path(value, f"{where}: {name}=", optional=True)
    check_progress(progress, where)


def _choice(where: str, name: str, value, choices) -> None:
    """A keyword that names one of ``choices``: a TypeError or ValueError naming it."""
    from .arguments import ArgumentError, brief

    if not isinstance(value, str):
        raise ArgumentTypeError(f"{where}: {name}= must be one of {', '.join(choices)}, got {type(value).__name__}")
    if value not in choices:
        raise ArgumentError(f"{where}: {name}= must be one of {', '.join(choices)}, got {brief(value)}")


def _files(*items) -> list[str]:
    """The items that are existing files (the run's inputs, which outputs must not overwrite).

    A model file's own inputs (MJCF includes and assets, xacro includes, meshes) are added after
    the first item.
    """
    out = [_os.fspath(x) for x in items if isinstance(x, (str, _os.PathLike)) and _os.path.isfile(x)]
    if items and isinstance(items[0], (str, _os.PathLike)) and _os.path.isfile(items[0]):
        from .io.sources import model_files

        out += [str(f) for f in model_files(items[0])[1:]]
    return out


def _friction_of(friction) -> tuple[str, ...]:
    """``"viscous,coulomb"``, ``"none"`` or an iterable of names, as a tuple."""
    if isinstance(friction, str):
        return () if friction.strip().lower() in ("", "none") else tuple(x.strip() for x in friction.split(",")
                                                                         if x.strip())
    if not isinstance(friction, (list, tuple, set, frozenset)) or not all(isinstance(x, str) for x in friction):
        raise ArgumentTypeError(f"friction= must be 'viscous,coulomb,offset', 'none' or a sequence of those names, "
                                f"got {type(friction).__name__}")
    return tuple(friction)


def _log_of(log, robot: Robot, columns, require_tau: bool = True, subset: bool = False, name: str = "log"):
    """``log`` as a JointLog: a JointLog (values checked), or a log file read for ``robot`` (``read_log``)."""
    from .ident.data import JointLog

    if isinstance(log, (str, _os.PathLike)):
        from .io.logs import read_log

        return read_log(log, robot, columns=columns, allow_subset=subset or not require_tau, require_tau=require_tau)
    if not isinstance(log, JointLog):
        raise ArgumentTypeError(f"{name} must be a JointLog or a log file's path, got {type(log).__name__}")
    if columns is not None:
        raise BaseparamsError(f"columns= maps the columns of a log file; {name} is a JointLog already")
    return log.checked()


def _identification_logs(robot: Robot, log, validate, columns, joints, weld):
    """``(log, validation log or None, robot)``: the logs read, restricted to a sub-chain's ``joints``."""
    from .arguments import brief

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
    from .arguments import brief
    from .ident.subchain import parse_welds, subchain

    names_ok = isinstance(joints, (list, tuple)) and all(isinstance(j, str) for j in joints)
    if not isinstance(joints, str) and not names_ok:
        raise ArgumentTypeError(f"identify: joints= must be 'A,B' or a sequence of joint names, got {brief(joints)}")
    names = [j.strip() for j in joints.split(",") if j.strip()] if isinstance(joints, str) else list(joints)
    welds = parse_welds(list(weld or ())) if not isinstance(weld, dict) else {k: float(v) for k, v in weld.items()}
    small, log, notes = subchain(robot, log, names, welds)
    if val is not None:
        val = subchain(robot, val, names, welds)[1]
    for note in notes:
        _warnings.warn(note, ModelWarning, stacklevel=3)
    return log, val, small


def excite(model, *, harmonics: int = 5, period: float | None = None, base_frequency: float | None = None,
           rate: float = 1000.0, criterion: str = "cond", drives: bool = False, rotor: bool = False,
           acceleration=None, torque: bool = False, keepout: tuple[str, float] | None = None, margin: float = 0.0,
           starts: int = 4, grid: int = 200, seed: int = 0, analysis_samples: int | None = None, limits=None,
           max_iter: int = 150, out=None, progress=None):
    """Design an excitation trajectory: ``baseparams excite`` (:mod:`baseparams.excitation`).

    A finite Fourier series per designed coordinate, at rest at both ends, within the model's joint
    limits, optimised for the condition number of the identification regressor (or D-optimality).

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
    acceleration : float or array_like, shape ``(m,)``, optional
        Acceleration limit(s) [rad/s^2].
    keepout : tuple of (str, float), optional
        ``(link, z_min)``: the link's frame origin stays at or above ``z_min`` [m, world z].
    analysis_samples : int, optional
        Random states of the base-parameter analysis the model is built on.
    limits : array_like, shape ``(m, 4)``, optional
        ``[lower, upper, velocity, effort]`` per designed coordinate, overriding the model's.
    max_iter : int
        SLSQP iterations per start (Python only).
    out : str or path, optional
        Also write the trajectory there (``.csv``/``.tsv``: ``t, q_, dq_, ddq_``; checked before the
        design, written atomically).
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
    from .arguments import check_keywords
    from .excitation import design_excitation

    check_keywords("excite", harmonics=harmonics, period=period, base_frequency=base_frequency, rate=rate,
                   margin=margin, starts=starts, grid=grid, seed=seed, analysis_samples=analysis_samples,
                   max_iter=max_iter, acceleration=acceleration)
    _bools("excite", drives=drives, rotor=rotor, torque=torque)
    _choice("excite", "criterion", criterion, ("cond", "logdet"))
    _paths_and_progress("excite", out=out, progress=progress)
    if period is not None and base_frequency is not None:
        raise BaseparamsError("excite: give period or base_frequency, not both")
    if period is not None and not period > 0:
        raise BaseparamsError(f"excite: period must be > 0 seconds, got {period}")
    robot = _robot_of(model, "excite")
    if out is not None:
        from .files import check_output

        check_output(out, _files(model), "out")
    target = model if isinstance(model, Analysis) and analysis_samples is None else robot
    if analysis_samples is not None:
        target = analyze(robot, samples=analysis_samples, seed=seed)
    f = 1.0 / period if period is not None else (0.1 if base_frequency is None else base_frequency)
    result = design_excitation(target, harmonics=harmonics, base_frequency=f, rate=rate, criterion=criterion,
                               drives=drives, rotor=rotor, limits=limits, acceleration=acceleration, torque=torque,
                               starts=starts, seed=seed, grid=grid, max_iter=max_iter, keepout=keepout, margin=margin,
                               progress=progress)
    if out is not None:
        result.save(out, _files(model), "out")
    return result


def simulate(model, trajectory=None, *, duration: float = 20.0, rate: float = 500.0, amplitude: float | None = None,
             noise: float = 0.0, seed: int = 0, rotor: bool = False, friction=_FRICTION, convention: str = "khalil",
             analysis_samples: int | None = None, out=None):
    """A synthetic joint log with known parameters: ``baseparams simulate`` (record, without a robot).

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot (fixed base); its own inertias are the true parameters.
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
        Seed of the trajectory, the drive parameters and the noise.
    rotor : bool
        Rotor inertias (the model's armature, else drawn).
    friction : str or iterable of str
        ``"viscous,coulomb,offset"`` (default), any of them, or ``"none"``.
    convention : str
        Convention of the true base parameters.
    analysis_samples : int, optional
        Random states of the base-parameter analysis.
    out : str or path, optional
        Also write the log there (``.csv``, ``.tsv`` or ``.npz``) and the truth to ``OUT.truth.json``,
        as the CLI does (atomically, never onto an input).

    Returns
    -------
    log : JointLog
        ``t``, ``q``, ``dq``, ``tau`` of the measured joints (what :func:`identify` takes).
    truth : dict
        ``{"model", "convention", "noise", "parameters": [{"name", "value"}], "drives"}``
        (``Identification.compare_truth(truth)``).

    Raises
    ------
    BaseparamsError
        A floating base, bad options, loops the trajectory does not close, an unwritable output.
    """
    from .arguments import check_keywords, check_samples
    from .ident.simulate import simulate_log

    check_keywords("simulate", duration=duration, rate=rate, amplitude=amplitude, noise=noise, seed=seed,
                   analysis_samples=analysis_samples)
    _bools("simulate", rotor=rotor)
    _paths_and_progress("simulate", out=out)
    if trajectory is None:
        check_samples(duration * rate, 16, "simulate: duration x rate")
    robot = _robot_of(model, "simulate")
    inputs = _files(model, trajectory)
    if out is not None:
        from .files import check_output

        check_output(out, inputs, "out")
    if isinstance(trajectory, (str, _os.PathLike)):
        from .excitation import read_trajectory

        trajectory = read_trajectory(trajectory, robot)
    trajectory = getattr(trajectory, "trajectory", trajectory)  # an Excitation's samples
    if trajectory is not None:
        trajectory = _trajectory_of(trajectory)
    log, truth = simulate_log(robot, duration=duration, rate=rate, amplitude=amplitude, noise=noise, seed=seed,
                              rotor=rotor, friction=_friction_of(friction), convention=convention,
                              trajectory=trajectory, samples=analysis_samples)
    if out is not None:
        import json

        from .files import atomic_path, write_text
        from .io.logs import write_log

        with atomic_path(out, inputs, "out") as tmp:
            write_log(tmp, log)
        write_text(_os.fspath(out) + ".truth.json", json.dumps(truth, indent=2) + "\n", inputs, "out")
    return log, truth


def identify(model, log, *, validate=None, holdout: float | None = None, method: str = "auto",
             friction=_FRICTION, rotor: bool = False, coulomb_width: float | None = None, couplings=(),
             cutoff: float | None = None, decimate: int | None = None, min_speed: float | None = None,
             prior_weight: float | None = None, convention: str = "khalil", covariance: str = "hac",
             score_cutoff: float | None = None, allow_units: bool = False, columns=None, joints=None, weld=None,
             analysis_samples: int | None = None, save=None, mjcf=None, progress=None):
    """Identify base-parameter and drive values from a joint log: ``baseparams identify``.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot the log was recorded on (fixed base; loops closed by the actuated joints).
    log : JointLog, str or path
        The log (:func:`simulate`, or a file: CSV/TSV, NPZ, Parquet, a ROS 2 bag; README "Log layout").
    validate : JointLog, str or path, optional
        Another log to validate on (exclusive with ``holdout``).
    holdout : float, optional
        Validate on the log's last ``holdout`` seconds (training: the samples before).
    method : {"auto", "ols", "wls", "physical"}
        The estimator (``physical`` needs the extra ``ident``).
    friction : str or iterable of str
        ``"viscous,coulomb,offset"`` (default), any of them, or ``"none"``.
    rotor : bool
        Model each joint's rotor inertia.
    coulomb_width, cutoff, decimate, min_speed, prior_weight, score_cutoff : optional
        As the CLI's flags (:func:`baseparams.ident.pipeline.identify`): smooth Coulomb width
        [rad/s], low-pass cutoff [Hz], decimation, the slowest joint speed kept [rad/s], the
        physical fit's prior weight, the second validation score's cutoff [Hz].
    couplings : iterable of MotorCoupling or str
        Coupled motors (``"NAME:JOINT=W,JOINT=W"``, the CLI's ``--coupling``).
    convention : str
        Convention of the base parameters' names and values.
    covariance : {"hac", "white"}
        The standard deviations' covariance.
    allow_units : bool
        Go on when the units look wrong.
    columns : str, path or dict, optional
        A layout mapping for log files (TOML; README "Log layout").
    joints : str or sequence of str, optional
        Identify these joints only (``"A,B"``); every other joint is welded
        (:func:`baseparams.ident.subchain.subchain`; where, said as :class:`ModelWarning` warnings).
    weld : dict or sequence of str, optional
        With ``joints``: where to weld others (``{"joint": value}`` or ``["JOINT=VALUE"]``, rad or m).
    analysis_samples : int, optional
        Random states of the base-parameter analysis.
    save : str or path, optional
        Also save the result there (``Identification.save``: versioned JSON; checked before the fit).
    mjcf : str or path, optional
        Also write the identified bodies and drive terms into a copy of the model file as MJCF
        (``--mjcf``: ``method="physical"`` and ``model`` an MJCF or URDF file; checked before the fit;
        :func:`baseparams.io.mjcf_write.identified_mjcf`, its notes as :class:`ModelWarning` warnings).
    progress : callable, optional
        Called with one line of text per step.

    Returns
    -------
    Identification
        Values, standard deviations, validation (``.predict(log)``, ``.save(path)``,
        ``.compare_truth(truth)``, ``.to_json()``).

    Raises
    ------
    BaseparamsError
        A floating base, bad data, options or output, data that do not excite the model.
    """
    from .arguments import check_keywords
    from .ident.drives import MotorCoupling
    from .ident.pipeline import identify as run

    check_keywords("identify", holdout=holdout, coulomb_width=coulomb_width, cutoff=cutoff, decimate=decimate,
                   min_speed=min_speed, prior_weight=prior_weight, score_cutoff=score_cutoff,
                   analysis_samples=analysis_samples)
    _bools("identify", rotor=rotor, allow_units=allow_units)
    _paths_and_progress("identify", save=save, mjcf=mjcf, progress=progress)
    _choice("identify", "method", method, ("auto", "ols", "wls", "physical"))
    _choice("identify", "covariance", covariance, ("hac", "white"))
    if isinstance(couplings, (str, MotorCoupling)):
        couplings = (couplings,)
    if not isinstance(couplings, (list, tuple)) or not all(isinstance(c, (str, MotorCoupling)) for c in couplings):
        raise ArgumentTypeError(f"identify: couplings= must be MotorCoupling objects or 'NAME:JOINT=W,...' texts, "
                                f"got {type(couplings).__name__}")
    if columns is not None and not isinstance(columns, (str, _os.PathLike, dict)):
        raise ArgumentTypeError(f"identify: columns= must be a TOML file, a dict or a topic, got "
                                f"{type(columns).__name__}")
    robot = _robot_of(model, "identify")
    inputs = _files(model, log, validate, columns)
    if save is not None:
        from .files import check_output

        check_output(save, inputs, "save")
    if mjcf is not None:
        from .files import check_output
        from .io.mjcf_write import check_mjcf_request

        check_mjcf_request(model, method, mjcf, "mjcf=")
        check_output(mjcf, inputs, "mjcf")
    couplings = tuple(c if isinstance(c, MotorCoupling) else MotorCoupling.parse(c) for c in couplings)
    log, val, robot = _identification_logs(robot, log, validate, columns, joints, weld)
    result = run(robot, log, method=method, rotor=rotor, friction=_friction_of(friction),
                 coulomb_width=coulomb_width, holdout=holdout, validation=val, cutoff=cutoff,
                 decimate=decimate, min_speed=min_speed, prior_weight=prior_weight, convention=convention,
                 couplings=couplings, progress=progress, samples=analysis_samples, covariance=covariance,
                 allow_units=allow_units, score_cutoff=score_cutoff)
    if save is not None:
        result.save(save, inputs, "save")
    if mjcf is not None:
        from .io.mjcf_write import identified_mjcf

        for note in identified_mjcf(result, _os.fspath(model), mjcf, log, inputs=inputs):
            _warnings.warn(note, ModelWarning, stacklevel=2)
    return result


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
    _bools("predict", raw_states=raw_states, allow_units=allow_units)
    robot = _robot_of(model, "predict")
    if not isinstance(result, (str, _os.PathLike)) and type(result).__name__ != "Identification":
        raise ArgumentTypeError(f"predict: result must be an Identification or its saved file, got "
                                f"{type(result).__name__}")
    if isinstance(result, (str, _os.PathLike)):
        from .ident.pipeline import Identification

        result = Identification.load(result, robot)
    from .ident.plausibility import check_prediction_log

    log = _log_of(log, robot, columns, require_tau=False)
    for note in check_prediction_log(result.model, log, allow_units):
        if "WARNING" in note:
            _warnings.warn(note, ModelWarning, stacklevel=2)
    return result.predict(log, smooth=not raw_states)


def analyze_symbolic(model, *, convention: str = "khalil", seed: int = 0, verify: bool = True):
    """Base parameters as formulas in a robot's dimensions: ``baseparams analyze TABLE --symbolic``.

    Needs SymPy (the extra ``symbolic``), imported here only.

    Parameters
    ----------
    model : SymbolicRobot, str or path
        A DH table (``.dh``), a built-in ``*-symbolic`` name, or a
        :class:`baseparams.symbolic.SymbolicRobot`.
    convention : str
        Convention of the formulas' parameters (default ``khalil``).
    seed : int
        Seed of the random rational points (choice of basis, checks).
    verify : bool
        Check the formulas against the certified numerical analysis and probe the conditions
        under which they change (the CLI's default; ``--no-verify`` is ``verify=False``).

    Returns
    -------
    SymbolicAnalysis
        ``.n_base``, ``.base`` (name -> SymPy formula), ``.conditions`` (with their effect when
        verified).

    Raises
    ------
    BaseparamsError
        SymPy missing (naming the extra), a bad table, a geometry the symbolic rules do not cover.
    """
    try:
        from .symbolic import load_symbolic, probe, symbolic_analysis
    except ImportError:
        raise BaseparamsError("analyze_symbolic needs SymPy: pip install 'baseparams[symbolic]'") from None
    robot = load_symbolic(_os.fspath(model)) if isinstance(model, (str, _os.PathLike)) else model
    result = symbolic_analysis(robot, convention=convention, seed=seed, check=verify)
    if verify:
        probe(result)
    return result


def __getattr__(name: str):
    """Submodules and the loop's result classes on first use (``baseparams.Identification``)."""
    if name in _SUBMODULES:
        return _importlib.import_module(f"{__name__}.{name}")
    if name in _LAZY:
        return getattr(_importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    # the public names and documented subpackages: not the helpers a submodule import binds
    # (``baseparams.display``), nor ``annotations`` or private names
    return sorted(set(__all__) | set(_SUBMODULES) | {n for n in globals() if n.startswith("__")})
