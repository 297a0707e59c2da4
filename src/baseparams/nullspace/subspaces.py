"""Exact q0 subspaces of every body's motion, from the joint screws, base-first (no sampling).

Body ``i`` moves by the 4x4 displacement ``g_i(q) = exp(S_1 q_1) ... exp(S_k q_k)`` (product of
exponentials of the world joint screws at q = 0 on its path, ``docs/extended-rules.md``).
Everything here derives from the *motion span*

    M_i = span{ (g_i(q) - I)[:3, :] : q }  (a subspace of the 3x4 matrices, dimension <= 12),

built exactly by the Krylov recursion ``M <- span{M, M S, M S^2} + span{S, S^2}`` over the
path's single-dof screws (``S^3 = -S`` for a unit rotation, ``S^2 = 0`` for a translation, so
three powers close it; multi-dof joints are their screws in sequence). A homogeneous 4-vector
``v`` of the body (point: ``v4 = 1``, direction: ``v4 = 0``, spatial assignment = world frame at
q = 0) then has

- *fixed* ``v``: ``X v = 0`` for all ``X`` in ``M_i`` (never moves);
- *level* in ``e``: ``e . X v = 0`` (its ``e``-coordinate never changes: velocity always ``⟂ e``;
  with ``e = gravity`` its potential never changes);
- *sliding* along ``d``: ``X v ∥ d`` (velocity always along ``d``).

The displacement span of a covector ``u = (e, 0)`` of the guide is ``{e^T X}``; its level space is
the right nullspace. Cost: O(1) per body, O(N) in all; a body whose span is all 12 dimensions
(most bodies two generic joints from the base) saturates its whole subtree, which is skipped.
For loop robots the spans are those of the open tree: a superset of the closed motion, so every
vector found fixed, level or sliding is so on the closed robot too (safe, maybe incomplete).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..model.robot import Robot
from ..pga.core import hat

SATURATED = 12


@dataclass(frozen=True, eq=False)
class MotionSpans:
    """Every body's motion span ``M_i`` and fixed vectors, as built by :func:`motion_spans`.

    ``M_i = span{(g_i(q) - I)[:3, :] : q}`` (module docstring; ``docs/extended-rules.md``),
    built exactly from the joint screws, world frame at q = 0.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    span : tuple of (ndarray or None)
        ``span[i] (k_i, 3, 4)``: orthonormal basis of body ``i``'s motion span ``M_i`` (Frobenius
        inner product), world frame at q = 0; ``None`` when saturated (``k_i = 12``: nothing of
        the body is fixed, level or sliding).
    tol : float
        The singular-value threshold the spans were built with (reused by the rules).
    fix : tuple of ndarray, optional
        ``fix[i] (f_i, 4)``: orthonormal rows spanning body ``i``'s fixed vectors (empty when
        saturated); see :meth:`fixed`.
    padded : ndarray, shape ``(n, 12, 3, 4)``, optional
        The span bases padded with zero rows (for batched use over bodies).
    """

    robot: Robot
    span: tuple[np.ndarray | None, ...]
    tol: float
    fix: tuple[np.ndarray, ...] = ()
    padded: np.ndarray | None = None  # (n, 12, 3, 4): span bases padded with zero rows

    __repr__ = summary_repr

    def dim(self, i: int) -> int:
        """Dimension ``k_i`` of body ``i``'s motion span (12 when saturated).

        Parameters
        ----------
        i : int
            Body index.

        Returns
        -------
        int
            ``dim M_i``, at most 12.
        """
        s = self.span[i]
        return SATURATED if s is None else s.shape[0]

    def fixed(self, i: int) -> np.ndarray:
        """Fixed vectors of body ``i`` ``(f, 4)``: ``∩_j ker S_j`` over its path.

        Parameters
        ----------
        i : int
            Body index.

        Returns
        -------
        ndarray, shape ``(f, 4)``
            Orthonormal rows: homogeneous 4-vectors (points and directions, world frame at q = 0)
            with ``X v = 0`` for every ``X`` in ``M_i``; none when saturated.
        """
        return self.fix[i]


def motion_spans(robot: Robot, tol: float = 1e-9) -> MotionSpans:
    """Every body's motion span, base-first, batched over the bodies of each depth.

    Spans are padded ``(12, 12)`` row bases (zero rows beyond the dimension); one batched SVD
    per depth and joint coordinate slot. Bodies below a saturated one are saturated. The Krylov
    recursion of the module docstring over the path's screws (exact, no sampling).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies; loops are ignored: the open tree's spans, a superset of
        the closed motion).
    tol : float, default 1e-9
        Absolute singular-value threshold for new span directions and for the fixed vectors.

    Returns
    -------
    MotionSpans
        Every body's span ``M_i`` (``None`` when saturated), its fixed vectors and the padded
        bases ``(n, 12, 3, 4)``, world frame at q = 0.
    """
    n = robot.n
    screws = hat(robot.screws)  # (dof, 4, 4) world twists at q = 0
    qi, nd = robot.q_index, robot.ndofs
    par = robot.parent
    depth = np.zeros(n, dtype=int)
    pl = par.tolist()
    for i in range(n):
        depth[i] = depth[pl[i]] + 1 if pl[i] >= 0 else 0
    basis = np.zeros((n, SATURATED, SATURATED))
    dim = np.zeros(n, dtype=int)
    sat = np.zeros(n, dtype=bool)
    rows = np.arange(SATURATED)
    by_depth = np.argsort(depth, kind="stable")
    bounds = np.searchsorted(depth[by_depth], np.arange(depth.max() + 2))
    for lvl in range(depth.max() + 1):
        lev = by_depth[bounds[lvl]: bounds[lvl + 1]]
        if lvl > 0:
            dead = sat[par[lev]]
            sat[lev[dead]] = True
            lev = lev[~dead]
        if len(lev) == 0:  # every body of this depth saturated: so is everything deeper
            sat[by_depth[bounds[lvl + 1]:]] = True
            break
        cur = basis[par[lev]] if lvl > 0 else np.zeros((len(lev), SATURATED, SATURATED))
        r = dim[par[lev]] if lvl > 0 else np.zeros(len(lev), dtype=int)
        for t in range(int(nd[lev].max())):
            act = np.flatnonzero(nd[lev] > t)
            sc = screws[qi[lev[act]] + t]
            s2 = sc @ sc
            rmax = int(r[act].max())  # rows beyond every body's dimension are zero: drop them
            known = cur[act, :rmax]  # (m, rmax, 12) orthonormal rows, zero-padded
            b = known.reshape(len(act), rmax, 3, 4)
            cand = np.concatenate([b @ sc[:, None], b @ s2[:, None], sc[:, None, :3], s2[:, None, :3]],
                                  axis=1).reshape(len(act), -1, SATURATED)
            cand = cand - (cand @ np.swapaxes(known, 1, 2)) @ known  # only what is new
            _, sv, vt = np.linalg.svd(cand, full_matrices=False)  # vt (m, min(rows, 12), 12)
            # rounding noise can look new at extreme length scales: never more rows than the space
            # holds (a full span is saturated, which only withholds columns, never adds wrong ones)
            add = np.minimum(np.sum(sv > tol, axis=1), SATURATED - r[act])
            mi, ji = np.nonzero(rows[None, : vt.shape[1]] < add[:, None])
            cur[act[mi], r[act[mi]] + ji] = vt[mi, ji]  # appended after each body's current rows
            r[act] = r[act] + add
        basis[lev], dim[lev] = cur, r
        sat[lev] = r >= SATURATED
    live = np.flatnonzero(~sat)
    spans: list[np.ndarray | None] = [None] * n
    fix: list[np.ndarray] = [np.zeros((0, 4))] * n
    if len(live):
        m = basis[live].reshape(len(live), -1, 4)  # every X of the span, stacked: (m, 36, 4)
        _, sv, vt = np.linalg.svd(m, full_matrices=True)
        rk = np.sum(sv > tol, axis=1)
        for k, i in enumerate(live.tolist()):
            spans[i] = basis[i, : dim[i]].reshape(-1, 3, 4)
            fix[i] = vt[k, rk[k]:]
    return MotionSpans(robot, tuple(spans), tol, tuple(fix), basis.reshape(n, SATURATED, 3, 4))
