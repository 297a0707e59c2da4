"""One entry point for the CLI: a built-in robot name or a robot file (URDF/URDF+, MJCF)."""

from __future__ import annotations

import warnings
from pathlib import Path

from ..errors import BaseparamsError
from ..model.robot import Robot


def load_model(model: str, floating: bool = False, gravity=None, strict_inertia: bool = False
               ) -> tuple[Robot, list[str]]:
    """``(robot, notes)``: ``model`` is a built-in name or a path (``.urdf``, ``.xml``/``.mjcf``).

    Gravity defaults to ``(0, 0, -9.81)`` for URDF files and to the model's own for MJCF. Physically infeasible inertias are notes
    (one per link), or errors with ``strict_inertia``. Loop robots whose file is not assembled
    (or singular) at q = 0 are assembled and re-referenced; the notes say so, along with any
    warning raised while reading."""
    from ..kinematics.loops import assemble
    from ..robots import BUILTINS, get

    p = Path(model)
    if model.lower() in BUILTINS and not p.exists():
        if floating:
            raise BaseparamsError("--floating applies to robot files, not to built-in robots")
        return get(model, gravity=gravity), []
    if not p.exists():
        raise BaseparamsError(f"{model}: no such file, and not a built-in robot (see 'baseparams robots')")
    g = (0.0, 0.0, -9.81) if gravity is None else gravity
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        suffix = p.suffix.lower()
        if suffix == ".urdf":
            from .urdf import load_urdf

            robot = load_urdf(p, floating=floating, gravity=g, strict_inertia=strict_inertia)
        elif suffix in (".xml", ".mjcf"):
            from .mjcf import load_mjcf

            robot = load_mjcf(p, gravity=gravity, floating=floating, strict_inertia=strict_inertia)
        else:
            raise BaseparamsError(f"{p}: unknown file type {suffix!r}; expected .urdf, .xml or .mjcf")
    notes = [str(w.message) for w in caught]
    robot, _, note = assemble(robot)
    if note:
        notes.append(f"{p}: {note}")
    return robot, notes
