"""One entry point for a model given by name: a built-in robot or a robot file.

It sits above both :mod:`.io` (the file readers) and :mod:`baseparams.robots` (the built-ins, some of
which are read from bundled files), so neither of those imports the other's way back.
"""

from __future__ import annotations

from pathlib import Path

from .arguments import ArgumentTypeError
from .errors import BaseparamsError
from .model.robot import Robot
from .robots import BUILTINS, get


def load_model(model: str, floating: bool = False, gravity=None, strict_inertia: bool = False,
               xacro_args=None, package_path=None, mocap_welds: str = "drop") -> tuple[Robot, list[str]]:
    """``(robot, notes)``: ``model`` is a built-in name or a path (``.urdf``, ``.xacro``, ``.xml``/``.mjcf``).

    Files are read by :func:`.io.load.load_file` (gravity, inertia checks and loop assembly are
    described there); ``floating`` applies to files only.

    Parameters
    ----------
    model : str
        A built-in robot's name (case-insensitive; ``baseparams robots`` lists them) or the
        path of a robot file. An existing file of that name wins over a built-in.
    floating : bool, optional
        Attach the file's root link to the world by a floating (F) joint. Files only.
    gravity : array_like, shape ``(3,)``, optional
        Gravity in the world frame (m/s^2); default: the built-in's own, ``(0, 0, -9.81)`` for
        URDF files, the model's own for MJCF.
    strict_inertia : bool, optional
        Physically infeasible inertias in a file are errors instead of notes.
    xacro_args : mapping or iterable of str, optional
        Arguments of a ``.xacro`` file (``{"NAME": "VALUE"}`` or ``["NAME:=VALUE", ...]``).
    package_path : str, path or list of them, optional
        Folders searched for a xacro file's ``$(find PKG)`` and ``package://PKG``.
    mocap_welds : {'drop', 'keep'}, optional
        MJCF files: the welds and connects to mocap bodies (control devices the simulation moves)
        left out (``drop``, default) or kept as loop joints to the world (``keep``).

    Returns
    -------
    robot : Robot
        The robot (loops assembled and re-referenced if needed).
    notes : list of str
        Messages for the user (empty for a built-in robot).

    Raises
    ------
    BaseparamsError
        ``floating`` with a built-in robot, a model that is neither a file nor a built-in, or
        any error reading the file.
    """
    import os

    if not isinstance(model, (str, os.PathLike)):
        raise ArgumentTypeError(f"model must be a built-in robot's name or a robot file's path, got "
                                f"{type(model).__name__}")
    model = os.fspath(model)
    gravity = check_load({"gravity": gravity, "xacro_args": xacro_args, "package_path": package_path,
                          "floating": floating, "strict_inertia": strict_inertia, "mocap_welds": mocap_welds})
    p = Path(model)
    if model.lower() in BUILTINS and not p.exists():
        if floating:
            raise BaseparamsError("a floating base applies to robot files, not to built-in robots")
        if xacro_args or package_path:
            raise BaseparamsError("xacro arguments and a package path apply to .xacro files, not to built-in robots")
        return get(model, gravity=gravity), []
    if not p.exists():
        raise BaseparamsError(f"{model}: no such file, and not a built-in robot (see 'baseparams robots')")
    from .io.load import load_file  # the readers (and their XML, loop and xacro code) for files only

    return load_file(p, floating=floating, gravity=gravity, strict_inertia=strict_inertia, xacro_args=xacro_args,
                     package_path=package_path, mocap_welds=mocap_welds)


def check_load(keywords: dict):
    """Every rule of :func:`load_model`'s keywords that needs no file (the command line's preflight asks it too).

    Parameters
    ----------
    keywords : dict
        ``gravity``, ``xacro_args``, ``package_path``, ``floating``, ``strict_inertia``,
        ``mocap_welds`` (those missing are not checked).

    Returns
    -------
    ndarray or None
        The gravity, checked (three numbers in range, or None).

    Raises
    ------
    BaseparamsError
        The first keyword refused, in one line naming it.
    """
    import os

    from .arguments import CHOICES, check_choice, check_flags, check_keywords

    gravity = check_keywords("", gravity=keywords.get("gravity"))["gravity"]
    xacro_args, package_path = keywords.get("xacro_args"), keywords.get("package_path")
    if xacro_args is not None and not isinstance(xacro_args, (dict, list, tuple)):
        raise ArgumentTypeError(f"xacro_args= must be {{'NAME': 'VALUE'}} or ['NAME:=VALUE', ...], got "
                                f"{type(xacro_args).__name__}")
    if package_path is not None and not isinstance(package_path, (str, os.PathLike, list, tuple)):
        raise ArgumentTypeError(f"package_path= must be a folder or a list of folders, got "
                                f"{type(package_path).__name__}")
    check_flags("", **{k: keywords[k] for k in ("floating", "strict_inertia") if k in keywords})
    if "mocap_welds" in keywords:
        check_choice("", "mocap_welds", keywords["mocap_welds"], CHOICES["mocap_welds"])
    return gravity
