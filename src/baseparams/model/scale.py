"""The robot's own length scale, for decisions that must not depend on the unit of length.

Scaling every length of a robot by ``s`` (and masses by ``mu``) scales each inertial parameter by
``mu s^u`` with ``u`` its length exponent (:data:`baseparams.model.inertia.LENGTH_POWER`).
Regrouping decides on dimensionless parameters ``pi / L^u``; rank decisions on parameters brought
to an ordinary size (:func:`decision_scale`), so that the structure found does not depend on
whether the file is written in metres or millimetres, and each body's about its own origin
(:func:`decision_frames`), so that it does not depend on how far the body is from the world's.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .inertia import LENGTH_POWER, hat, unhat
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


#: tolerances grow to this many times the rounding they must stand above (``eps * cond`` of a
#: change of coordinates, or :func:`body_rounding`)
NOISE_FACTOR = 1e3


def body_rounding(robot: Robot) -> np.ndarray:
    """Per body, the relative rounding of a nullspace column's block as the body's own origin sees it.

    A block computed in the world frame at q = 0 on a body ``D`` away from the origin carries
    the rounding of its ``D^2`` terms (``sym(p, p)``): about the body's origin that is
    ``eps (1 + D / L)^2`` of the block (``L`` the :func:`length_scale`).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).

    Returns
    -------
    ndarray, shape ``(n,)``
        ``eps (1 + D_b / L)^2``, ``D_b`` body ``b``'s frame origin's distance from the world's at q = 0.
    """
    far = np.linalg.norm(robot.M0[:, :3, 3], axis=1) / length_scale(robot)
    return np.finfo(float).eps * (1.0 + far) ** 2


@lru_cache(maxsize=4)  # robots compare by identity and are immutable; a few MB per 10 000 bodies
def decision_frames(robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per body, the coordinates rank decisions are made in: its parameters about its own origin, ordinary-sized.

    A nullspace column's block on body ``b`` (``paper`` convention: world frame at q = 0) is
    mapped by ``F_b = diag(1 / d) P_b``, ``P_b`` the change of the pseudo-inertia's origin to body
    ``b``'s frame origin at q = 0 (a translation: ``N -> A N A^T``) and ``d`` the
    :func:`decision_scale`. A block-diagonal invertible map keeps every rank, but the world
    frame's blocks of a body ``D`` away from the origin mix entries ``D^2``, ``D`` and 1 (the
    shared points' ``sym(p, p)``, ``sym(a, p)``, ``sym(a, a)``: a condition number ``~D^4``),
    which a relative singular-value threshold cannot tell from rank deficiency (a 0.3 m serial
    chain loses directions from its 1 050th link on); about the body's own origin they are of
    the body's own size. The world blocks' entries carry the rounding of the ``D^2`` terms:
    about the body's origin it is ``eps (1 + D / L)^2`` of the block's size (``L`` the
    :func:`length_scale`), the level below which a decision must not go (``noise``).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies; cached by identity: robots are immutable).

    Returns
    -------
    f : ndarray, shape ``(n, 10, 10)``
        ``F_b``: decision coordinates from ``paper`` (SI, world frame at q = 0) parameters.
    inverse : ndarray, shape ``(n, 10, 10)``
        ``F_b^-1``: back to ``paper`` parameters.
    noise : ndarray, shape ``(n,)``
        :data:`NOISE_FACTOR` times :func:`body_rounding`: the level below which a decision on a
        block must not go.
    """
    d = decision_scale(robot, "paper")[:10]
    o = robot.M0[:, :3, 3]
    basis = unhat(np.eye(10))  # (10, 4, 4): the pseudo-inertia of each unit parameter
    a = np.tile(np.eye(4), (robot.n, 1, 1))
    a[:, :3, 3] = -o  # the world frame's pose in the body-origin frame
    ainv = a.copy()
    ainv[:, :3, 3] = o

    def moved(t: np.ndarray) -> np.ndarray:  # (n, 10, 10): parameters -> parameters about the moved origin
        m = t[:, None] @ basis[None] @ np.swapaxes(t, -1, -2)[:, None]
        return np.swapaxes(hat(m), -1, -2)

    f = moved(a) / d[None, :, None]
    inverse = moved(ainv) * d[None, None, :]
    noise = NOISE_FACTOR * body_rounding(robot)
    return f, inverse, noise
