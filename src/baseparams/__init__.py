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

load(model, floating=False, gravity=None, strict_inertia=False, drop_mocap_welds=False)
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
``baseparams.ident`` (the identification's building blocks:
``baseparams.ident.model.ident_model``, ``baseparams.ident.pipeline.accumulate`` and ``fit``),
``baseparams.excitation`` (the excitation designer's parts), ``baseparams.fleet`` (many logs on
Dask). ``dir(baseparams)`` lists these and the names above. The name
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
from .errors import BaseparamsError, ModelError, ModelWarning
from .model import CONVENTIONS, Inertia, Robot, RobotBuilder, pose

# excite and simulate (and the helpers identify and predict share with them) have one
# implementation, baseparams.workflow: also the CLI's
from .workflow import FRICTION as _FRICTION
from .workflow import excite, simulate
from .workflow import friction_of as _friction_of
from .workflow import input_files as _files
from .workflow import robot_of as _robot_of

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


def load(model: str | _os.PathLike, floating: bool = False, gravity=None, strict_inertia: bool = False,
         xacro_args=None, package_path=None, drop_mocap_welds: bool = False) -> Robot:
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
    drop_mocap_welds : bool
        MJCF: leave out the welds and connects to mocap bodies (a control device, e.g.
        Meta-World's hand welded to one); by default they are honoured as loops to the world,
        with a note (``--drop-mocap-welds``).

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
                              xacro_args=xacro_args, package_path=package_path,
                              drop_mocap_welds=drop_mocap_welds)
    for note in notes:
        _warnings.warn(note, ModelWarning, stacklevel=2)
    return robot


# ---------------------------------------------------------------- the whole loop: excite, simulate, identify, predict
#: the classes of the loop's results, imported on first use (``baseparams.Identification``)
_LAZY = {"Excitation": "excitation.result", "Identification": "ident.pipeline"}


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
        The robot the log was recorded on (a floating base's pose in the log; loops closed by the
        actuated joints).
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
        Bad data (a floating base without its pose), options or output, data that do not excite the model.
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
