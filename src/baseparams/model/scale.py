"""The robot's own length scale, for decisions that must not depend on the unit of length.

Scaling every length of a robot by ``s`` (and masses by ``mu``) scales each inertial parameter by
``mu s^u`` with ``u`` its length exponent (:data:`baseparams.model.inertia.LENGTH_POWER`).
Regrouping decides on dimensionless parameters ``pi / L^u``; rank decisions on parameters brought
to an ordinary size (:func:`decision_scale`), so that the structure found does not depend on
whether the file is written in metres or millimetres.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .inertia import LENGTH_POWER
from .robot import Robot


@lru_cache(maxsize=16)  # robots compare by identity and are immutable
def length_scale(robot: Robot) -> float:
    """The robot's typical length ``L`` [m].

    The median nonzero distance between adjacent frame origins at q = 0 (each body's joint
    origin from its parent's, a fixed root's from the world origin, each loop frame from both of
    its bodies' origins). A degree-1 homogeneous function of the geometry (scaling lengths by
    ``s`` scales it by ``s``) that ignores where a floating base happens to stand.

    Parameters
    ----------
    robot : Robot
        The robot (cached by identity: robots are immutable).

    Returns
    -------
    float
        ``L`` in the robot's unit of length; 1 when every distance is zero.
    """
    p = robot.M0[:, :3, 3]
    par = np.asarray(robot.parent)
    tree = par >= 0
    root = ~tree & (np.array(robot.jtype) != "F")
    d = [np.linalg.norm(p[tree] - p[par[tree]], axis=1), np.linalg.norm(p[root], axis=1)]
    for lj in robot.loops:
        o = np.asarray(lj.M)[:3, 3]
        d.append([np.linalg.norm(o - (p[lj.parent] if lj.parent >= 0 else 0.0)), np.linalg.norm(o - p[lj.child])])
        if lj.M_child is not None:
            d.append([np.linalg.norm(np.asarray(lj.M_child)[:3, 3] - p[lj.child])])
    d = np.concatenate([np.asarray(x, dtype=float).ravel() for x in d])
    d = d[np.isfinite(d)]
    if not len(d) or d.max() <= 0:
        return 1.0
    d = np.sort(d[d > 1e-12 * d.max()])  # the median (np.median imports numpy.ma: ~15 ms at start-up)
    return float(0.5 * (d[(len(d) - 1) // 2] + d[len(d) // 2]))


#: typical lengths [m] for which the numerical rank decisions are validated as they are (every
#: example-robot-data, MuJoCo Menagerie, gymnasium and dm_control model lies inside)
METRE_BAND = (0.05, 20.0)


def ordinary_size(robot: Robot) -> bool:
    """True when the robot's :func:`length_scale` lies in :data:`METRE_BAND`.

    Parameters
    ----------
    robot : Robot
        The robot.

    Returns
    -------
    bool
        Whether the numerical rank decisions apply to it as they are.
    """
    lo, hi = METRE_BAND
    return lo <= length_scale(robot) <= hi


def decision_scale(robot: Robot, convention: str) -> np.ndarray:
    """Per-parameter factors ``(L / L_c)^u`` that bring a robot to an ordinary size.

    ``L`` is the robot's :func:`length_scale`, ``L_c`` the same clipped into
    :data:`METRE_BAND` and ``u`` each parameter's length exponent
    (:data:`~baseparams.model.inertia.LENGTH_POWER`). Rank decisions are made on
    ``pi / decision_scale``, an ordinary-sized equivalent of the parameters ``pi``.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    convention : str
        The parameter convention of ``pi`` (:data:`~baseparams.model.inertia.CONVENTIONS`).

    Returns
    -------
    ndarray, shape ``(10 n,)``
        Ones for a robot of ordinary size; for a robot drawn in other units (millimetres,
        micrometres, kilometres) the factors that bring its parameters to an ordinary-sized
        equivalent.
    """
    ell = length_scale(robot)
    lo, hi = METRE_BAND
    return (ell / min(max(ell, lo), hi)) ** np.tile(LENGTH_POWER[convention], robot.n).astype(float)
