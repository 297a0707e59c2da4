"""DRNG's columns from the paper's three principles, with the paper's slips fixed.

Every nullspace column here is "``+h`` on body ``i``'s block, ``-h`` on its parent's block"
(or ``+h`` on body ``i`` alone), with ``h = hat(S)`` and ``S`` a symmetric 4x4 built from
points of the spatial assignment (the world frame at q = 0, so a shared point has the same
coordinates in parent and child, Sec. "Spatial assignment"). Columns are in the paper's
parameter convention (spatial pseudo-inertia at q = 0, hat order per body).

Principles (with ``O`` a joint point, ``z`` an axis direction, ``x, y`` directions
perpendicular to it, ``sym(a, b) = a b^T + b a^T``):

1. shared points (eq. "null space"): R ``{O, z}``, P ``{x, y, z}``, U/S ``{O}``; all
   products of pairs; **parent block negative** (E1 fixed). A compound joint (C): a basis of
   the vectors every one of its screws leaves fixed (:func:`compound_shared`); nothing else of
   the paper's principles is emitted for C (numerical completion covers the rest).
2. fixed points, joints on the fixed base: S/U ``sym(O, x|y|z)`` **only when G = 0** (E2
   fixed); P ``sym(O, x|y|z)``; R ``sym(z, x|y)``, plus ``sym(O, x|y)`` when gravity is zero
   or along the axis.
3. planar rotations (PRI with E5 fixed: a child is planar when its R axis is parallel to the
   parent's planar direction ``d_pr``, or it is a P joint): R ``xx^T - yy^T``, ``sym(x, y)``
   and, off the base, ``sym(z, x|y)``; P off the base ``sym(d_pr, O)`` and, when it slides
   along ``d_pr``, the transfers ``sym(O, x|y)`` to the parent. Zero vectors (``d_pr = 0``)
   are not emitted.

No stale block is re-appended (E3). Everything is vectorised over joints.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..enums import Source
from ..model.robot import Robot
from ..pga.core import hat
from ..pga.linalg import cross3, nullspace, perp_basis
from .columns import Columns, outer_params, sym_params


def _dir(v: np.ndarray) -> np.ndarray:
    return np.concatenate([v, np.zeros(v.shape[:-1] + (1,))], axis=-1)


def _pt(v: np.ndarray) -> np.ndarray:
    return np.concatenate([v, np.ones(v.shape[:-1] + (1,))], axis=-1)


def planar_rotations(robot: Robot, tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """PRI with E5 fixed: ``is_pr (n,)`` bool and ``d_pr (n, 3)`` (zero for pure translation).

    The paper's Algorithm "PRI" (planar rotations indicator), O(n): an R or P joint on the fixed
    base is planar; a child of a planar body is planar when its R axis is parallel to the
    parent's planar direction ``d_pr`` (E5: not the parent's joint direction, zero for a P
    parent), or it is a P joint.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Axes are parallel when the squared norm of their cross product is at most ``tol**2``; a
        planar direction whose squared norm is at most ``tol**2`` counts as zero.

    Returns
    -------
    is_pr : ndarray of bool, shape ``(n,)``
        Whether body ``i`` moves in planar rotations.
    d_pr : ndarray, shape ``(n, 3)``
        The planar direction (the rotation axis, world frame at q = 0); zero for pure
        translation and for bodies that are not planar.
    """
    n = robot.n
    is_pr = [False] * n
    d_pr = [(0.0, 0.0, 0.0)] * n
    axes_w = world_axes(robot).tolist()
    par = robot.parent.tolist()
    tol2 = tol * tol
    for i, t in enumerate(robot.jtype):  # O(n) scalar recursion in plain Python floats
        if t != "R" and t != "P":
            continue
        ld = axes_w[i] if t == "R" else (0.0, 0.0, 0.0)
        p = par[i]
        if p < 0:
            is_pr[i], d_pr[i] = True, tuple(ld)
        elif is_pr[p]:
            a, b = ld, d_pr[p]
            cx, cy, cz = a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]
            if cx * cx + cy * cy + cz * cz <= tol2:
                is_pr[i] = True
                d_pr[i] = b if (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]) > tol2 else tuple(ld)
    return np.array(is_pr, dtype=bool), np.array(d_pr, dtype=float).reshape(n, 3)


@lru_cache(maxsize=16)  # robots compare by identity and are immutable
def world_axes(robot: Robot) -> np.ndarray:
    """First joint axis of every body in world coordinates at q = 0 ``(n, 3)``.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies); robots compare by identity and are immutable.

    Returns
    -------
    ndarray, shape ``(n, 3)``
        The first axis of each R, P or U joint, world frame at q = 0 (zero if none; read-only,
        cached per robot).
    """
    first = np.array([a[0] if (len(a) and t in ("R", "P", "U")) else (0.0, 0.0, 0.0)
                      for a, t in zip(robot.axes, robot.jtype)], dtype=float).reshape(-1, 3)
    out = np.einsum("nij,nj->ni", robot.M0[:, :3, :3], first)
    out.flags.writeable = False
    return out


def compound_shared(robot: Robot, i: int, tol: float = 1e-9) -> np.ndarray:
    """Vectors ``(r, 4)`` (orthonormal rows) that every screw of body ``i``'s joint leaves fixed.

    The common kernel of its world screws ``hat(S_k)`` on homogeneous 4-vectors (points and
    directions both bodies move alike, whatever the joint's coordinates): principle 1's shared
    points of a compound (C) joint.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    i : int
        The body whose joint is examined.
    tol : float, default 1e-9
        Absolute singular-value threshold of the common kernel
        (:func:`baseparams.pga.linalg.nullspace`).

    Returns
    -------
    ndarray, shape ``(r, 4)``
        Orthonormal rows, homogeneous coordinates in the world frame at q = 0.
    """
    k0, nd = int(robot.q_index[i]), int(robot.ndofs[i])
    return nullspace(hat(robot.screws[k0:k0 + nd]).reshape(-1, 4), tol)


def _compound_columns(robot: Robot, tol: float) -> Columns:
    parts = []
    for i in np.flatnonzero(np.array(robot.jtype) == "C"):
        v = compound_shared(robot, int(i), tol)
        hs, labels = [], []
        for a in range(len(v)):
            for b in range(a, len(v)):
                hs.append(outer_params(v[a][None])[0] if a == b else sym_params(v[a][None], v[b][None])[0])
                labels.append(f"v{a} v{b} (common kernel)")
        if hs:
            m = len(hs)
            parts.append(Columns(np.array(hs), np.full(m, i), np.full(m, robot.parent[i]),
                                 np.full(m, Source.SHARED_POINTS), np.full(m, i), np.array(labels, dtype=object)))
    return Columns.concat(parts)


def _cols(h, child, parent, principle, labels) -> Columns:
    """Assemble columns: ``h (m, c, 10)`` for m joints x c kinds -> flat."""
    m, c = h.shape[:2]
    child = np.repeat(child, c)
    return Columns(h.reshape(m * c, 10), child, np.repeat(parent, c),
                   np.full(m * c, principle), child.copy(), np.tile(np.array(labels, dtype=object), m))


def drng_columns(robot: Robot, tol: float = 1e-9) -> Columns:
    """All DRNG columns (corrected), vectorised over joints of each type.

    The paper's principles 1, 2 and 3, then principle 1 across the loop joints, in that order
    (Algorithm "DRNG" with E1-E5 fixed).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Geometric tolerance passed to each principle (parallel axes, zero gravity, zero
        directions, compound joints' kernels).

    Returns
    -------
    Columns
        The columns with provenance (shared points, fixed points, planar rotations), blocks in
        the ``paper`` convention (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M``
        of each body, world frame at q = 0).
    """
    return Columns.concat([shared_point_columns(robot, tol), fixed_point_columns(robot, tol),
                           planar_rotation_columns(robot, tol), loop_columns(robot)])


def _joint_data(robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Joint types ``(n,)``, parents ``(n,)``, joint origins ``(n, 3)`` and first world axes ``(n, 3)``.

    All at q = 0.
    """
    return np.array(robot.jtype), robot.parent, robot.M0[:, :3, 3], world_axes(robot)


def shared_point_columns(robot: Robot, tol: float = 1e-9) -> Columns:
    """Principle 1, shared points of every tree joint.

    R ``{O, z}``, P ``{x, y, z}``, U/S ``{O}``, compound joints their common kernel
    (:func:`compound_shared`); every product of pairs, ``+`` on the child and **parent block
    negative** (eq. "null space", E1 fixed; none for the fixed base).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Tolerance of the compound joints' common kernel (:func:`compound_shared`).

    Returns
    -------
    Columns
        The columns with provenance (shared points), blocks in the ``paper`` convention
        (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world
        frame at q = 0).
    """
    jt, par, org, axw = _joint_data(robot)
    e = np.eye(3)
    parts: list[Columns] = []
    r = np.flatnonzero(jt == "R")
    if len(r):
        o, z = _pt(org[r]), _dir(axw[r])
        h = np.stack([outer_params(o), sym_params(o, z), outer_params(z)], axis=1)
        parts.append(_cols(h, r, par[r], Source.SHARED_POINTS, ["O O", "O z", "z z"]))
    p = np.flatnonzero(jt == "P")
    if len(p):
        pairs = [(a, b) for a in range(3) for b in range(a, 3)]
        blocks = [outer_params(_dir(e[a])) if a == b else sym_params(_dir(e[a]), _dir(e[b])) for a, b in pairs]
        h = np.stack([np.broadcast_to(blk, (len(p), 10)) for blk in blocks], axis=1)
        parts.append(_cols(h, p, par[p], Source.SHARED_POINTS, [f"{'xyz'[a]} {'xyz'[b]}" for a, b in pairs]))
    us = np.flatnonzero((jt == "U") | (jt == "S"))
    if len(us):
        parts.append(_cols(outer_params(_pt(org[us]))[:, None], us, par[us], Source.SHARED_POINTS, ["O O"]))
    parts.append(_compound_columns(robot, tol))
    return Columns.concat(parts)


def fixed_point_columns(robot: Robot, tol: float = 1e-9) -> Columns:
    """Principle 2, fixed points of the joints on the fixed base.

    S/U ``sym(O, x|y|z)`` only when gravity is zero (eq. "U/S fixed", E2 fixed), P
    ``sym(O, x|y|z)`` (eq. "P fixed"), R ``sym(z, x|y)`` plus ``sym(O, x|y)`` when gravity is
    zero or along the axis (eq. "R fixed"). Single-body columns on the child.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Gravity of norm at most ``tol`` is zero; a (unit) axis is along gravity when the norm of
        their cross product is at most ``tol * max(1, |g|)``.

    Returns
    -------
    Columns
        The columns with provenance (fixed points), blocks in the ``paper`` convention
        (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world
        frame at q = 0).
    """
    jt, par, org, axw = _joint_data(robot)
    g = robot.gravity
    g_zero = np.linalg.norm(g) <= tol
    e = np.eye(3)
    parts: list[Columns] = []
    base = par < 0
    sel = np.flatnonzero(base & ((jt == "U") | (jt == "S")))
    if len(sel) and g_zero:  # E2: only when the fixed point has zero acceleration
        o = _pt(org[sel])
        h = np.stack([sym_params(o, np.broadcast_to(_dir(e[k]), o.shape)) for k in range(3)], axis=1)
        parts.append(_cols(h, sel, np.full(len(sel), -1), Source.FIXED_POINTS, ["O x", "O y", "O z"]))
    sel = np.flatnonzero(base & (jt == "P"))
    if len(sel):
        o = _pt(org[sel])
        h = np.stack([sym_params(o, np.broadcast_to(_dir(e[k]), o.shape)) for k in range(3)], axis=1)
        parts.append(_cols(h, sel, np.full(len(sel), -1), Source.FIXED_POINTS, ["O x", "O y", "O z"]))
    sel = np.flatnonzero(base & (jt == "R"))
    if len(sel):
        o, z = _pt(org[sel]), _dir(axw[sel])
        x, y = (_dir(v) for v in perp_basis(axw[sel]))
        h = np.stack([sym_params(z, x), sym_params(z, y)], axis=1)
        parts.append(_cols(h, sel, np.full(len(sel), -1), Source.FIXED_POINTS, ["z x", "z y"]))
        across = np.linalg.norm(cross3(axw[sel], np.broadcast_to(g, axw[sel].shape)), axis=1)
        along = g_zero | (across <= tol * max(1.0, np.linalg.norm(g)))
        if along.any():
            s2 = sel[along]
            h = np.stack([sym_params(o[along], x[along]), sym_params(o[along], y[along])], axis=1)
            parts.append(_cols(h, s2, np.full(len(s2), -1), Source.FIXED_POINTS, ["O x", "O y"]))
    return Columns.concat(parts)


def planar_rotation_columns(robot: Robot, tol: float = 1e-9) -> Columns:
    """Principle 3, planar rotations (E5 fixed, see :func:`planar_rotations`).

    R ``xx^T - yy^T``, ``sym(x, y)`` (eq. "planar rotation xx yy", "planar rotation xy") and, off
    the base, ``sym(z, x|y)`` ("planar rotation zx", "zy"); P off the base ``sym(d_pr, O)``
    (eq. "planar rotation Oz") and, when it slides along ``d_pr``, the transfers ``sym(O, x|y)``
    to the parent (eq. "Ox planar rotations", "Oy planar rotations"). Zero vectors
    (``d_pr = 0``) are not emitted.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Parallel axes and zero directions (:func:`planar_rotations`); a P joint slides along
        ``d_pr`` when the cross product of its axis and ``d_pr`` has norm at most ``tol``.

    Returns
    -------
    Columns
        The columns with provenance (planar rotations), blocks in the ``paper`` convention
        (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world
        frame at q = 0).
    """
    jt, par, org, axw = _joint_data(robot)
    base = par < 0
    parts: list[Columns] = []
    is_pr, d_pr = planar_rotations(robot, tol)
    has_d = np.linalg.norm(d_pr, axis=1) > tol
    sel = np.flatnonzero(is_pr & (jt == "R"))
    if len(sel):
        z = _dir(d_pr[sel])
        x, y = (_dir(v) for v in perp_basis(d_pr[sel]))
        h = np.stack([outer_params(x) - outer_params(y), sym_params(x, y)], axis=1)
        parts.append(_cols(h, sel, np.full(len(sel), -1), Source.PLANAR_ROTATIONS, ["x x - y y", "x y"]))
        off = ~base[sel]
        if off.any():
            h = np.stack([sym_params(z[off], x[off]), sym_params(z[off], y[off])], axis=1)
            parts.append(_cols(h, sel[off], np.full(off.sum(), -1), Source.PLANAR_ROTATIONS, ["z x", "z y"]))
    sel = np.flatnonzero(is_pr & (jt == "P") & ~base & has_d)
    if len(sel):
        o, d = _pt(org[sel]), _dir(d_pr[sel])
        parts.append(_cols(sym_params(d, o)[:, None], sel, np.full(len(sel), -1), Source.PLANAR_ROTATIONS, ["d_pr O"]))
        slide = np.linalg.norm(cross3(axw[sel], d_pr[sel]), axis=1) <= tol
        if slide.any():
            s2 = sel[slide]
            x, y = (_dir(v) for v in perp_basis(d_pr[s2]))
            h = np.stack([sym_params(o[slide], x), sym_params(o[slide], y)], axis=1)
            parts.append(_cols(h, s2, par[s2], Source.PLANAR_ROTATIONS, ["O x (transfer)", "O y (transfer)"]))
    return Columns.concat(parts)


def loop_columns(robot: Robot) -> Columns:
    """Principle 1 for loop joints (E4 fixed: loop ``l`` is joint ``n + l``, its own block).

    Shared points from the loop frame at q = 0: R ``{O, z}``, P ``{x, y, z}``, U/S ``{O}``,
    fixed ``{O, x, y, z}``; successor block ``+``, predecessor block ``-`` (none for the world).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).

    Returns
    -------
    Columns
        The columns with provenance (shared points, joint ``n + l``), blocks in the ``paper``
        convention (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body,
        world frame at q = 0).
    """
    parts = []
    e = np.eye(4)
    for k, lj in enumerate(robot.loops):
        o = np.r_[lj.M[:3, 3], 1.0]
        r = lj.M[:3, :3]
        if lj.type == "R":
            pts, names = [o, np.r_[r @ lj.axes[0], 0.0]], ["O", "z"]
        elif lj.type == "P":
            pts, names = [e[0], e[1], e[2]], ["x", "y", "z"]
        elif lj.type in ("U", "S"):
            pts, names = [o], ["O"]
        else:  # fixed: every point is shared
            pts, names = [o, e[0], e[1], e[2]], ["O", "x", "y", "z"]
        hs, labels = [], []
        for a in range(len(pts)):
            for b in range(a, len(pts)):
                hs.append(outer_params(pts[a][None])[0] if a == b else sym_params(pts[a][None], pts[b][None])[0])
                labels.append(f"{names[a]} {names[b]} (loop)")
        m = len(hs)
        parts.append(Columns(np.array(hs), np.full(m, lj.child), np.full(m, lj.parent),
                             np.full(m, Source.SHARED_POINTS), np.full(m, robot.n + k), np.array(labels, dtype=object)))
    return Columns.concat(parts)
