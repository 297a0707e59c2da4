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

``load(model, floating=False, gravity=None, strict_inertia=False, mocap_welds='drop')``
    A :class:`Robot` from a built-in name (``baseparams.robots.BUILTINS``) or a file (URDF,
    URDF+, MJCF); notes about the file are :class:`ModelWarning` warnings.
``analyze(robot, *, samples=None, seed=0, verify=True, rows="all", convention="khalil", ...)``
    DRNG, numerical certification, regrouping: an :class:`Analysis` (``baseparams analyze``).
``analyze_symbolic(table, *, convention="khalil", seed=0, verify=True)``
    Base parameters as formulas in a DH table's symbols (``analyze --symbolic``; SymPy, the
    extra ``symbolic``, imported only then).
``regressor(robot, q, dq, ddq)``
    The TP regressor ``(S, dof, 10 n)``, ``paper`` convention (``baseparams regressor``).
``excite(model, *, harmonics=5, period=None, rate=1000.0, criterion="cond", drives=False, ..., out=None)``
    Design an excitation trajectory: an :class:`Excitation` (``.trajectory``, ``.save(path)``).
``simulate(model, trajectory=None, *, noise=0.0, seed=0, rotor=False, ..., out=None)``
    Record without a robot: ``(log, truth)``, a synthetic joint log with the model's own
    parameters as the truth.
``identify(model, log, *, holdout=None, validate=None, method="auto", friction=..., ..., save=None)``
    Base-parameter and drive values from a joint log: an :class:`Identification`
    (``.values``, ``.std``, ``.save(path)``, ``Identification.load(path, robot)``,
    ``.predict(log)``, ``.compare_truth(truth)``).
``predict(model, result, log, *, raw_states=False)``
    Joint torques ``(S, m)`` of a log from an identification or its saved file.
``identify_payload(model, log, *, link, result=None, validate=None, save=None, urdf=None, mjcf=None, ...)``
    What the robot carries on a link: a :class:`Payload` (``.mass``, ``.com``, ``.inertia_com`` in
    the link's frame, ``.sigma()``, ``.identified()``, ``.to_json()``, ``.predict(log)``,
    ``.save(path)``, ``SavedPayload.load(path, robot)``), the robot known from its model file or a
    saved identification (``baseparams payload``).
``excite(model, payload=LINK, ...)``
    A short excitation that identifies a payload on a link best (``excite --payload LINK``).
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
``baseparams.ident.ident_model``, ``baseparams.ident.accumulate`` and ``fit``),
``baseparams.excitation`` (the excitation designer's parts), ``baseparams.fleet`` (many logs on
Dask). ``dir(baseparams)`` lists these and the names above. The name
``baseparams.regressor`` is the function above; the subpackage of the same name is imported as
usual (``from baseparams.regressor import regressor_tensor``).
"""

from __future__ import annotations

import importlib as _importlib
import os as _os
import warnings as _warnings

from . import startup as _startup  # first: Ctrl-C while the package imports says one line, not a traceback

# isort: split
# the subpackage first: importing it later would rebind ``baseparams.regressor`` to the module
from . import regressor as _regressor_pkg  # noqa: F401  (numpy only)
from .analysis import Analysis, analyze, regressor
from .errors import BaseparamsError, ModelError, ModelWarning
from .model import CONVENTIONS, Inertia, Robot, RobotBuilder, pose

# excite and simulate (and the helpers identify and predict share with them) have one
# implementation, baseparams.workflow: also the CLI's
from .workflow import excite, identify, identify_payload, predict, simulate

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
    "identify_payload",
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
         xacro_args=None, package_path=None, mocap_welds: str = "drop") -> Robot:
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
    mocap_welds : {'drop', 'keep'}
        MJCF: the welds and connects to mocap bodies, control devices the simulation moves
        (Meta-World's and gymnasium's Fetch hands are welded to one, for actuation). ``drop``
        (default): left out, with a note, so the arm is the tree its users drive; ``keep``: loop
        joints to the world, placed where the hand is at the reference (``--mocap-welds``).

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
                              mocap_welds=mocap_welds)
    for note in notes:
        _warnings.warn(note, ModelWarning, stacklevel=2)
    return robot


# ---------------------------------------------------------------- the whole loop: excite, simulate, identify, predict
#: the classes of the loop's results, imported on first use (``baseparams.Identification``)
_LAZY = {"Excitation": "excitation.result", "Identification": "ident", "Payload": "ident.payload",
         "PayloadOptions": "ident.payload", "SavedPayload": "ident.payload"}


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
    if name == "__version__":  # looked up on first use (baseparams.version)
        from .version import version

        return version()
    if name in _LAZY:
        return getattr(_importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    # the public names and documented subpackages: not the helpers a submodule import binds
    # (``baseparams.display``), nor ``annotations`` or private names
    return sorted(set(__all__) | set(_SUBMODULES) | {n for n in globals() if n.startswith("__")})


_startup.done()  # the package imported: interrupts are the caller's again
