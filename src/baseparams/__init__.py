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
load(model, floating=False, gravity=None, strict_inertia=False)
    A :class:`Robot` from a built-in name (``baseparams.robots.BUILTINS``) or a file (URDF,
    URDF+, MJCF); notes about the file are :class:`ModelWarning` warnings.
analyze(robot, *, samples=None, seed=0, verify=True, rows="all", convention="khalil", ...)
    DRNG, numerical certification, regrouping: an :class:`Analysis`.
regressor(robot, q, dq, ddq)
    The TP regressor ``(S, dof, 10 n)``, ``paper`` convention.
Robot, RobotBuilder, Inertia, pose
    Build a robot in code (see :class:`RobotBuilder`).
CONVENTIONS
    Parameter conventions: ``paper`` (spatial pseudo-inertia entries in the world frame at
    q = 0, what the regressor multiplies), ``khalil``, ``pinocchio``, ``idyntree``, ``rpna``
    (link frames; ``baseparams.model.inertia``). The named choices (conventions, measured
    rows, statuses, joint types, DRNG provenance) are the enums of ``baseparams.enums``, equal
    to their strings.
BaseparamsError, ModelError
    Errors on bad input (``ModelError``: an invalid model).

Everything else lives in submodules, imported on first use: ``baseparams.robots``,
``baseparams.io`` (readers, URDF export, Pinocchio interop), ``baseparams.nullspace`` (DRNG,
certification), ``baseparams.base`` (regrouping), ``baseparams.numerics``, ``baseparams.pga``,
``baseparams.kinematics``, ``baseparams.model``, ``baseparams.symbolic`` (base parameters as
formulas in a robot's dimensions, from a DH table with symbols; SymPy, the extra ``symbolic``),
``baseparams.ident`` (identification from joint logs: ``from baseparams.ident.pipeline import
identify``; ``baseparams.ident.simulate.simulate_log``), ``baseparams.excite`` (excitation trajectories),
``baseparams.fleet`` (many logs on Dask). ``dir(baseparams)`` lists these and the names above.
The name ``baseparams.regressor`` is the
function above; the subpackage of the same name is imported as usual
(``from baseparams.regressor import regressor_tensor``).
"""

from __future__ import annotations

import importlib as _importlib
import os as _os
import warnings as _warnings

__version__ = "0.1.0"

# the subpackage first: importing it later would rebind ``baseparams.regressor`` to the module
from . import regressor as _regressor_pkg  # noqa: F401  (numpy only)
from .analysis import Analysis, analyze, regressor
from .errors import BaseparamsError, ModelError
from .model import CONVENTIONS, Inertia, Robot, RobotBuilder, pose

__all__ = [
    "CONVENTIONS",
    "Analysis",
    "BaseparamsError",
    "Inertia",
    "ModelError",
    "ModelWarning",
    "Robot",
    "RobotBuilder",
    "__version__",
    "analyze",
    "load",
    "pose",
    "regressor",
]

#: the documented subpackages, imported on first use (``dir(baseparams)`` shows these and ``__all__``)
_SUBMODULES = ("analysis", "base", "cli", "enums", "errors", "excite", "fleet", "ident", "io", "kinematics", "model",
               "nullspace", "numerics", "pga", "robots", "symbolic")


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

    robot, notes = load_model(_os.fspath(model), floating=floating, gravity=gravity, strict_inertia=strict_inertia,
                              xacro_args=xacro_args, package_path=package_path)
    for note in notes:
        _warnings.warn(note, ModelWarning, stacklevel=2)
    return robot


def __getattr__(name: str):
    """Submodules on first use (``baseparams.robots.BUILTINS`` without importing it first)."""
    if name in _SUBMODULES:
        return _importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    # the public names and documented subpackages: not the helpers a submodule import binds
    # (``baseparams.display``), nor ``annotations`` or private names
    return sorted(set(__all__) | set(_SUBMODULES) | {n for n in globals() if n.startswith("__")})
