"""R-L4 spatial parallelograms: a platform that only translates, rod pairs that move as translated copies.

A Delta robot: arms on the base, each carrying a pair of rods (universal joints on the arm, ball
joints on a common platform). A **pair** is two rods ``A``, ``B`` on one body (the arm: the world
or a moving body) by universal joints with the same axes, both closed on one body ``P`` (the
platform) at points, such that at the reference the rods are parallel and of equal length:
``a2 - a1 = b2 - b1`` (``a1``, ``b1`` their joints on the arm, ``a2``, ``b2`` on the platform),
with the spacing ``d = b1 - a1 = b2 - a2`` fixed on the arm (:meth:`.subspaces.MotionSpans.fixed`).

If the platform keeps its orientation, each pair is a parallelogram at every configuration (two
opposite sides equal and parallel: ``d`` on the arm and on the platform), so rod ``B`` moves as rod
``A`` translated by ``d`` (the same universal-joint angles: the same rod direction, the same axes):
``g_B = T_d g_A T_d^-1`` with ``T_d`` the translation by ``d``. That the platform keeps its
orientation is checked at the reference on the closed-loop kinematics: its angular velocity is
zero for every admissible velocity (``omega_P G = 0``), and its translation determines the
configuration (``v_P G`` of full rank, the mechanism's degrees of freedom). The pure translations of
the platform, each arm solving its one equation, then form a family of the mechanism's dimension
through the reference, which is therefore the whole branch the samples continue on.

Columns (``docs/extended-rules.md``, "R-L4"):

* the platform translates: its kinetic energy is ``1/2 m |p'|^2`` and its potential sees only its
  mass and the constant ``gbar^T integral(x)``: the nine entries other than the mass are null
  (``sym(e_i, e_j)`` and ``sym(e_i, e4)``);
* rod ``B`` transfers to rod ``A``: ``dN`` on ``B`` and ``-T dN T^T`` on ``A`` (``T`` the translation by
  ``-d``) for the ten entries of ``dN``: the energies of ``B`` with ``dN`` are those of ``A`` with
  ``T dN T^T`` (``T_d`` has no rotation, so the kinetic term is unchanged, and the potential changes
  by the constant ``gbar^T d m``).
"""

from __future__ import annotations

import numpy as np

from ..enums import Source
from ..model.inertia import hat as hat10
from ..model.inertia import unhat
from ..model.robot import Robot
from .columns import Columns, on_bodies, sym_params
from .subspaces import MotionSpans, motion_spans

RL4 = Source.R_L4


def _platform_points(robot: Robot) -> dict[tuple[int, int], np.ndarray]:
    """``(rod, platform) -> point (3,)``: ball joints (tree or assembled loop joints) between two bodies."""
    out = {}
    for i, t in enumerate(robot.jtype):
        if t == "S" and robot.parent[i] >= 0:
            out[(int(robot.parent[i]), i)] = robot.M0[i, :3, 3]
    for lj in robot.loops:
        if lj.type == "S" and lj.parent >= 0 and lj.M_child is None:
            out[(lj.parent, lj.child)] = lj.M[:3, 3]
            out[(lj.child, lj.parent)] = lj.M[:3, 3]
    return out


def _rod_axes(robot: Robot, i: int) -> np.ndarray:
    """A universal joint's two axes in the world at the reference ``(2, 3)``."""
    return np.einsum("ij,kj->ki", robot.M0[i, :3, :3], robot.axes[i])


def spatial_pairs(robot: Robot, tol: float = 1e-9, ms: MotionSpans | None = None) -> dict[int, list[dict]]:
    """The rod pairs of every platform (see the module doc), before the translation check.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    tol : float, default 1e-9
        Relative tolerance of the geometric checks.
    ms : MotionSpans, optional
        The open tree's motion spans (for the spacing fixed on the arm).

    Returns
    -------
    dict of int to list of dict
        Platform body -> pairs ``{"a", "b": rod bodies, "arm": their parent, "d" (3,): spacing}``.
    """
    points = _platform_points(robot)
    if not points:
        return {}
    ms = motion_spans(robot, tol) if ms is None else ms
    pairs: dict[int, list[dict]] = {}
    rods = [(r, p, x) for (r, p), x in points.items() if robot.jtype[r] == "U"]
    for k, (a, plat, a2) in enumerate(rods):
        for b, plat_b, b2 in rods[k + 1:]:
            if plat_b != plat or robot.parent[a] != robot.parent[b] or a == b:
                continue
            a1, b1 = robot.M0[a, :3, 3], robot.M0[b, :3, 3]
            scale = max(np.linalg.norm(a2 - a1), 1e-300)
            d = b1 - a1
            if (np.linalg.norm(d) <= tol * scale or np.linalg.norm((a2 - a1) - (b2 - b1)) > 1e-7 * scale
                    or np.abs(_rod_axes(robot, a) - _rod_axes(robot, b)).max() > 1e-7):
                continue
            arm = int(robot.parent[a])
            if arm >= 0:
                fix = ms.fixed(arm)
                v = np.r_[d / np.linalg.norm(d), 0.0]
                if not len(fix) or np.linalg.norm(v - fix.T @ (fix @ v)) > 1e-7:
                    continue  # the spacing turns with the arm: not a parallelogram at every configuration
            pairs.setdefault(plat, []).append({"a": a, "b": b, "arm": arm, "d": d})
    return pairs


def _translates(robot: Robot, plat: int, tol: float) -> bool:
    """Whether the platform keeps its orientation on the closed robot (checked at the reference, module doc)."""
    from ..kinematics.loops import close_loops

    cs = close_loops(robot, np.zeros((1, len(robot.actuated))), cond_max=np.inf)
    if not cs.kept:
        return False
    path = robot.support[:, plat] != 0
    lines = robot.screws * path[:, None]  # world screws at the reference of the platform's path
    j = lines.T @ cs.G[0]  # (6, na): the platform's spatial twist per independent velocity
    scale = max(float(np.abs(j).max()), 1e-300)
    w, v = j[:3], j[3:] + np.cross(j[:3].T, robot.M0[plat, :3, 3]).T  # the platform origin's velocity
    m = len(robot.actuated)
    return bool(np.abs(w).max() <= 1e-9 * scale and m <= 3 and np.linalg.matrix_rank(v, 1e-9 * scale) == m)


def spatial_parallelogram_columns(robot: Robot, tol: float = 1e-9, ms: MotionSpans | None = None) -> Columns:
    """R-L4: a translating platform's nine entries and each rod pair's transfer (module doc).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Relative tolerance of the geometric checks.
    ms : MotionSpans, optional
        The open tree's motion spans.

    Returns
    -------
    Columns
        Columns in the ``paper`` convention (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX
        MY MZ M``, world frame at q = 0), provenance ``R-L4 spatial parallelograms``.
    """
    if not robot.loops:
        return Columns.empty()
    parts = []
    e = np.eye(4)
    for plat, pairs in spatial_pairs(robot, tol, ms).items():
        if not _translates(robot, plat, tol):
            continue
        name = robot.names[plat]
        h = np.array([sym_params(e[i], e[j]) for i in range(3) for j in range(i, 4)])  # every entry but the mass
        parts.append(on_bodies([plat], h, RL4, f"{name} only translates"))
        for p in pairs:
            t = np.eye(4)
            t[:3, 3] = -p["d"]  # rod B's frame to rod A's
            moved = np.array([hat10(t @ unhat(u) @ t.T) for u in np.eye(10)])
            label = f"{robot.names[p['b']]} moves as {robot.names[p['a']]} translated ({name} only translates)"
            parts.append(on_bodies([p["b"], p["a"]], np.hstack([np.eye(10), -moved]), RL4, label))
    return Columns.concat(parts)


__all__ = ["spatial_pairs", "spatial_parallelogram_columns"]
