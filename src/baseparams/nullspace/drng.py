"""DRNG: the regressor nullspace from the three principles, with the paper's slips fixed.

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

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..model.inertia import PAPER_NAMES
from ..model.inertia import hat as hat10
from ..model.robot import Robot
from ..pga.core import cross3

PAPER = ("shared points", "fixed points", "planar rotations")
#: provenance of a column: the paper's principles, the extended rules (:mod:`.rules`), numerics
EXTENDED = ("R-A fixed vectors", "R-B sliding points", "R-L1 parallelograms", "R-L2 level chains")
#: columns that come from which generalized forces are measured, not from geometry
UNMEASURED = "unmeasured root"
PRINCIPLES = PAPER + EXTENDED + (UNMEASURED, "numerical")


FIELDS = ("h", "child", "parent", "principle", "joint", "label", "hp", "extra", "he")


@dataclass(frozen=True)
class Columns:
    """A set of nullspace columns in compact form (``k`` columns).

    ``h (k, 10)``: the block on body ``child (k,)`` (the column's highest body); ``parent (k,)``
    the other body (``-1``: none) whose block is ``hp (k, 10)`` (default ``-h``: the principles'
    "``+h`` on the child, ``-h`` on the parent"); ``principle (k,)`` index into
    :data:`PRINCIPLES`; ``joint (k,)`` the joint the column comes from (``n + l`` for loop joint
    ``l``; a body for the extended rules); ``label (k,)`` which points or vectors; ``extra (k,)``
    an optional third body (``-1``: none, lower than ``child``) with block ``he (k, 10)``.
    """

    h: np.ndarray
    child: np.ndarray
    parent: np.ndarray
    principle: np.ndarray
    joint: np.ndarray
    label: np.ndarray
    hp: np.ndarray | None = None
    extra: np.ndarray | None = None
    he: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.hp is None:
            object.__setattr__(self, "hp", -np.asarray(self.h))
        if self.extra is None:
            object.__setattr__(self, "extra", -np.ones(len(self.child), dtype=int))
        if self.he is None:
            object.__setattr__(self, "he", np.zeros_like(np.asarray(self.h)))

    @staticmethod
    def empty() -> Columns:
        z = np.zeros(0, dtype=int)
        return Columns(np.zeros((0, 10)), z, z, z, z, np.zeros(0, dtype=object))

    @staticmethod
    def concat(parts: list[Columns]) -> Columns:
        parts = [p for p in parts if len(p.child)]
        if not parts:
            return Columns.empty()
        return Columns(*(np.concatenate([getattr(p, f) for p in parts]) for f in FIELDS))

    def subset(self, keep: np.ndarray) -> Columns:
        return Columns(*(getattr(self, f)[keep] for f in FIELDS))

    def __len__(self) -> int:
        return len(self.child)


def _sym(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``hat(a b^T + b a^T)`` for ``a == b`` gives ``hat(2 a a^T)``: callers use :func:`_outer`."""
    ab = np.einsum("...i,...j->...ij", a, b)
    return hat10(ab + np.swapaxes(ab, -1, -2))


def _outer(a: np.ndarray) -> np.ndarray:
    return hat10(np.einsum("...i,...j->...ij", a, a))


def _perp_basis(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit directions ``(m, 3)`` completing unit ``d (m, 3)`` to an orthonormal frame."""
    helper = np.where(np.abs(d[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    x = cross3(d, np.broadcast_to(helper, d.shape))
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = cross3(d, x)
    return x, y


def _dir(v: np.ndarray) -> np.ndarray:
    return np.concatenate([v, np.zeros(v.shape[:-1] + (1,))], axis=-1)


def _pt(v: np.ndarray) -> np.ndarray:
    return np.concatenate([v, np.ones(v.shape[:-1] + (1,))], axis=-1)


def planar_rotations(robot: Robot, tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """PRI with E5 fixed: ``is_pr (n,)`` bool and ``d_pr (n, 3)`` (zero for pure translation)."""
    n = robot.n
    is_pr = [False] * n
    d_pr = [(0.0, 0.0, 0.0)] * n
    axes_w = _world_axes(robot).tolist()
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


def _world_axes(robot: Robot) -> np.ndarray:
    """First joint axis of every body in world coordinates at q = 0 ``(n, 3)`` (zero if none)."""
    first = np.array([a[0] if (len(a) and t in ("R", "P", "U")) else (0.0, 0.0, 0.0)
                      for a, t in zip(robot.axes, robot.jtype)], dtype=float).reshape(-1, 3)
    return np.einsum("nij,nj->ni", robot.M0[:, :3, :3], first)


def compound_shared(robot: Robot, i: int, tol: float = 1e-9) -> np.ndarray:
    """Vectors ``(r, 4)`` (orthonormal rows) that every screw of body ``i``'s joint leaves fixed:
    the common kernel of its world screws ``hat(S_k)`` on homogeneous 4-vectors (points and
    directions both bodies move alike, whatever the joint's coordinates)."""
    from ..pga.core import hat
    from .subspaces import nullspace

    k0, nd = int(robot.q_index[i]), int(robot.ndofs[i])
    return nullspace(hat(robot.screws[k0:k0 + nd]).reshape(-1, 4), tol)


def _compound_columns(robot: Robot, tol: float) -> Columns:
    parts = []
    for i in np.flatnonzero(np.array(robot.jtype) == "C"):
        v = compound_shared(robot, int(i), tol)
        hs, labels = [], []
        for a in range(len(v)):
            for b in range(a, len(v)):
                hs.append(_outer(v[a][None])[0] if a == b else _sym(v[a][None], v[b][None])[0])
                labels.append(f"v{a} v{b} (common kernel)")
        if hs:
            m = len(hs)
            parts.append(Columns(np.array(hs), np.full(m, i), np.full(m, robot.parent[i]), np.zeros(m, dtype=int),
                                 np.full(m, i), np.array(labels, dtype=object)))
    return Columns.concat(parts)


def _cols(h, child, parent, principle, labels) -> Columns:
    """Assemble columns: ``h (m, c, 10)`` for m joints x c kinds -> flat."""
    m, c = h.shape[:2]
    child = np.repeat(child, c)
    return Columns(h.reshape(m * c, 10), child, np.repeat(parent, c),
                   np.full(m * c, principle), child.copy(), np.tile(np.array(labels, dtype=object), m))


def drng_columns(robot: Robot, tol: float = 1e-9) -> Columns:
    """All DRNG columns (corrected), vectorised over joints of each type."""
    jt = np.array(robot.jtype)
    par = robot.parent
    org = robot.M0[:, :3, 3]
    axw = _world_axes(robot)
    g = robot.gravity
    g_zero = np.linalg.norm(g) <= tol
    e = np.eye(3)
    parts: list[Columns] = []

    # --- Principle 1: shared points ------------------------------------------------------
    r = np.flatnonzero(jt == "R")
    if len(r):
        o, z = _pt(org[r]), _dir(axw[r])
        h = np.stack([_outer(o), _sym(o, z), _outer(z)], axis=1)
        parts.append(_cols(h, r, par[r], 0, ["O O", "O z", "z z"]))
    p = np.flatnonzero(jt == "P")
    if len(p):
        pairs = [(a, b) for a in range(3) for b in range(a, 3)]
        h = np.stack([np.broadcast_to(_outer(_dir(e[a])) if a == b else _sym(_dir(e[a]), _dir(e[b])), (len(p), 10))
                      for a, b in pairs], axis=1)
        parts.append(_cols(h, p, par[p], 0, [f"{'xyz'[a]} {'xyz'[b]}" for a, b in pairs]))
    us = np.flatnonzero((jt == "U") | (jt == "S"))
    if len(us):
        parts.append(_cols(_outer(_pt(org[us]))[:, None], us, par[us], 0, ["O O"]))
    parts.append(_compound_columns(robot, tol))

    # --- Principle 2: fixed points (joints on the fixed base) ----------------------------
    base = par < 0
    none = -np.ones(0, dtype=int)
    sel = np.flatnonzero(base & ((jt == "U") | (jt == "S")))
    if len(sel) and g_zero:  # E2: only when the fixed point has zero acceleration
        o = _pt(org[sel])
        h = np.stack([_sym(o, np.broadcast_to(_dir(e[k]), o.shape)) for k in range(3)], axis=1)
        parts.append(_cols(h, sel, np.full(len(sel), -1), 1, ["O x", "O y", "O z"]))
    sel = np.flatnonzero(base & (jt == "P"))
    if len(sel):
        o = _pt(org[sel])
        h = np.stack([_sym(o, np.broadcast_to(_dir(e[k]), o.shape)) for k in range(3)], axis=1)
        parts.append(_cols(h, sel, np.full(len(sel), -1), 1, ["O x", "O y", "O z"]))
    sel = np.flatnonzero(base & (jt == "R"))
    if len(sel):
        o, z = _pt(org[sel]), _dir(axw[sel])
        x, y = (_dir(v) for v in _perp_basis(axw[sel]))
        h = np.stack([_sym(z, x), _sym(z, y)], axis=1)
        parts.append(_cols(h, sel, np.full(len(sel), -1), 1, ["z x", "z y"]))
        along = g_zero | (np.linalg.norm(cross3(axw[sel], np.broadcast_to(g, axw[sel].shape)), axis=1) <= tol * max(1.0, np.linalg.norm(g)))
        if along.any():
            s2 = sel[along]
            h = np.stack([_sym(o[along], x[along]), _sym(o[along], y[along])], axis=1)
            parts.append(_cols(h, s2, np.full(len(s2), -1), 1, ["O x", "O y"]))

    # --- Principle 3: planar rotations ----------------------------------------------------
    is_pr, d_pr = planar_rotations(robot, tol)
    has_d = np.linalg.norm(d_pr, axis=1) > tol
    sel = np.flatnonzero(is_pr & (jt == "R"))
    if len(sel):
        z = _dir(d_pr[sel])
        x, y = (_dir(v) for v in _perp_basis(d_pr[sel]))
        h = np.stack([_outer(x) - _outer(y), _sym(x, y)], axis=1)
        parts.append(_cols(h, sel, np.full(len(sel), -1), 2, ["x x - y y", "x y"]))
        off = ~base[sel]
        if off.any():
            h = np.stack([_sym(z[off], x[off]), _sym(z[off], y[off])], axis=1)
            parts.append(_cols(h, sel[off], np.full(off.sum(), -1), 2, ["z x", "z y"]))
    sel = np.flatnonzero(is_pr & (jt == "P") & ~base & has_d)
    if len(sel):
        o, d = _pt(org[sel]), _dir(d_pr[sel])
        parts.append(_cols(_sym(d, o)[:, None], sel, np.full(len(sel), -1), 2, ["d_pr O"]))
        slide = np.linalg.norm(cross3(axw[sel], d_pr[sel]), axis=1) <= tol
        if slide.any():
            s2 = sel[slide]
            x, y = (_dir(v) for v in _perp_basis(d_pr[s2]))
            h = np.stack([_sym(o[slide], x), _sym(o[slide], y)], axis=1)
            parts.append(_cols(h, s2, par[s2], 2, ["O x (transfer)", "O y (transfer)"]))
    parts.append(loop_columns(robot))
    return Columns.concat(parts)


def loop_columns(robot: Robot) -> Columns:
    """Principle 1 for loop joints (E4 fixed: loop ``l`` is joint ``n + l``, its own block).

    Shared points from the loop frame at q = 0: R ``{O, z}``, P ``{x, y, z}``, U/S ``{O}``,
    fixed ``{O, x, y, z}``; successor block ``+``, predecessor block ``-`` (none for the world)."""
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
                hs.append(_outer(pts[a][None])[0] if a == b else _sym(pts[a][None], pts[b][None])[0])
                labels.append(f"{names[a]} {names[b]} (loop)")
        m = len(hs)
        parts.append(Columns(np.array(hs), np.full(m, lj.child), np.full(m, lj.parent), np.zeros(m, dtype=int),
                             np.full(m, robot.n + k), np.array(labels, dtype=object)))
    return Columns.concat(parts)


def to_sparse(cols: Columns, n: int) -> sp.csc_matrix:
    """``B (10 n, k)`` as a sparse matrix (paper convention)."""
    k = len(cols)
    rows_c = (10 * cols.child[:, None] + np.arange(10)).ravel()
    cidx = np.repeat(np.arange(k), 10)
    vals_c = cols.h.ravel()
    has_p = cols.parent >= 0
    rows_p = (10 * cols.parent[has_p][:, None] + np.arange(10)).ravel()
    cidx_p = np.repeat(np.flatnonzero(has_p), 10)
    vals_p = cols.hp[has_p].ravel()
    has_e = cols.extra >= 0
    if has_e.any():
        rows_p = np.r_[rows_p, (10 * cols.extra[has_e][:, None] + np.arange(10)).ravel()]
        cidx_p = np.r_[cidx_p, np.repeat(np.flatnonzero(has_e), 10)]
        vals_p = np.r_[vals_p, cols.he[has_e].ravel()]
    b = sp.coo_matrix((np.r_[vals_c, vals_p], (np.r_[rows_c, rows_p], np.r_[cidx, cidx_p])), shape=(10 * n, k))
    return b.tocsc()


def block_rank(cols: Columns, n: int, rtol: float = 1e-10) -> int:
    """Exact rank of the columns in O(n): block-triangular elimination, leaves to root.

    Each column lives on blocks ``{child, parent}`` with ``parent < child``. Per body, the
    rank of its diagonal block (child parts plus vectors pushed up from its children)
    counts; combinations vanishing there are pushed to lower blocks. All diagonal blocks are
    checked at once (batched SVD); only when one is rank-deficient does the general
    block-by-block elimination (:func:`_elimination_rank`) run. Loop columns (blocks
    ``{successor, predecessor}``, predecessor < successor) fit the same scheme.
    """
    cols = _reduce_pure(cols, rtol)
    k = len(cols)
    if k == 0:
        return 0
    order = np.argsort(cols.child, kind="stable")
    child = cols.child[order]
    counts = np.bincount(child, minlength=n)
    mmax = counts.max()
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    slot = np.arange(k) - np.repeat(starts, counts)
    blocks = np.zeros((n, 10, mmax))
    blocks[child, :, slot] = cols.h[order]
    scale = np.linalg.norm(blocks, axis=(1, 2))
    sv = np.linalg.svd(blocks, compute_uv=False)  # (n, min(10, mmax))
    ranks = np.sum(sv > rtol * np.maximum(scale, 1e-300)[:, None], axis=1)
    if np.all(ranks == counts):
        return int(ranks.sum())
    return _elimination_rank(cols, n, rtol, ranks, counts, order, starts)


def _reduce_pure(cols: Columns, rtol: float) -> Columns:
    """A column set of the same span, cheaper to rank (elementary column operations only).

    From the highest body down: the single-body ("pure") columns of body ``b`` become an
    orthonormal basis ``Q`` of their span; the two-block columns ``(h on b, hp on p)`` sharing a
    parent ``p`` are rotated by the right singular vectors of their child parts off ``Q``, and
    each combination whose child part lies in ``span Q`` is replaced by its parent part alone, a
    new pure column of ``p``. Without this a translation chain's redundant pure columns cascade
    through the elimination (quadratic in the depth)."""
    import heapq

    pure_mask = (cols.parent < 0) & (cols.extra < 0)
    if not pure_mask.any():
        return cols
    scale = max(float(np.abs(cols.h).max()), 1e-300)
    fresh: set[int] = set()  # bodies whose pure list is still the batched orthonormal basis
    # the pure span of every body at once (batched SVD over padded blocks)
    pk = np.flatnonzero(pure_mask)
    pk = pk[np.argsort(cols.child[pk], kind="stable")]
    pb, pc = np.unique(cols.child[pk], return_counts=True)
    slot = np.arange(len(pk)) - np.repeat(np.r_[0, np.cumsum(pc)[:-1]], pc)
    blocks = np.zeros((len(pb), 10, pc.max()))
    blocks[np.repeat(np.arange(len(pb)), pc), :, slot] = cols.h[pk]
    u, sv, _ = np.linalg.svd(blocks, full_matrices=False)
    pure: dict[int, list[np.ndarray]] = {int(bb): list((u[k][:, sv[k] > rtol * scale]).T)
                                         for k, bb in enumerate(pb)}
    fresh.update(pure)
    two = np.flatnonzero(~pure_mask & (cols.extra < 0))
    order = two[np.argsort(cols.child[two], kind="stable")]
    bodies, first = np.unique(cols.child[order], return_index=True)
    span_of = {int(bb): (int(i), int(j)) for bb, i, j in zip(bodies, first, np.r_[first[1:], len(order)])}
    touched = np.zeros(len(cols), dtype=bool)
    heap = [-bb for bb in pure]
    heapq.heapify(heap)
    out_h: list[np.ndarray] = []
    out_b: list[int] = []
    new_two: list[tuple[np.ndarray, int, int, np.ndarray]] = []  # (h, child, parent, hp)
    while heap:
        bb = -heapq.heappop(heap)
        if bb not in pure:
            continue
        vecs = np.array(pure.pop(bb)).reshape(-1, 10).T
        if bb in fresh:
            basis = vecs  # already orthonormal
        else:
            u, sv, _ = np.linalg.svd(vecs, full_matrices=False)
            basis = u[:, sv > rtol * scale]  # (10, r)
        out_h.append(basis.T)
        out_b += [bb] * basis.shape[1]
        if bb not in span_of or basis.shape[1] == 0:
            continue
        idx = order[span_of[bb][0]: span_of[bb][1]]
        for p in np.unique(cols.parent[idx]):
            grp = idx[cols.parent[idx] == p]
            h, hp = cols.h[grp], cols.hp[grp]
            res = h - (h @ basis) @ basis.T
            _, rs, vt = np.linalg.svd(res.T, full_matrices=True)  # vt (k, k)
            r = int(np.sum(rs > rtol * scale))
            if r == len(grp):
                continue
            touched[grp] = True
            hn, hpn = vt @ h, vt @ hp
            for j in range(r):
                new_two.append((hn[j], bb, int(p), hpn[j]))
            p = int(p)
            if p not in pure:
                heapq.heappush(heap, -p)
            pure.setdefault(p, []).extend(hpn[r:])
            fresh.discard(p)
    keep = ~pure_mask & ~touched
    parts = [cols.subset(keep)]
    m = len(out_b)
    z = np.zeros(m, dtype=int)
    if m:
        parts.append(Columns(np.concatenate(out_h), np.array(out_b, dtype=int), z - 1, z, z,
                             np.full(m, "", dtype=object)))
    if new_two:
        k = len(new_two)
        z = np.zeros(k, dtype=int)
        parts.append(Columns(np.array([t[0] for t in new_two]), np.array([t[1] for t in new_two]),
                             np.array([t[2] for t in new_two]), z, z, np.full(k, "", dtype=object),
                             np.array([t[3] for t in new_two])))
    return Columns.concat(parts)


def _column_dict(cols: Columns, k: int) -> dict[int, np.ndarray]:
    v = {int(cols.child[k]): cols.h[k]}
    for body, h in ((cols.parent[k], cols.hp[k]), (cols.extra[k], cols.he[k])):
        if body >= 0:
            v[int(body)] = v.get(int(body), 0) + h
    return v


def _elimination_rank(cols: Columns, n: int, rtol: float, ranks: np.ndarray, counts: np.ndarray,
                      order: np.ndarray, starts: np.ndarray) -> int:
    """Exact rank when some diagonal blocks are rank-deficient: eliminate block by block from
    the highest body down, visiting only the deficient bodies and those that receive vectors.

    Vectors are sparse over bodies; at body b, the parts on block b of every vector whose highest
    block is b are ranked, and combinations vanishing there move down to their next highest
    block. A body with a full-rank diagonal block that receives nothing keeps its batched rank."""
    import heapq

    scale = max(float(np.abs(cols.h).max()), 1e-300)
    total = int(ranks.sum())
    pending: dict[int, list[dict[int, np.ndarray]]] = {}
    heap = [-int(b) for b in np.flatnonzero(ranks < counts)]
    heapq.heapify(heap)
    queued = set(-b for b in heap)
    while heap:
        b = -heapq.heappop(heap)
        own = order[starts[b]: starts[b] + counts[b]]
        vecs = [_column_dict(cols, int(k)) for k in own] + pending.pop(b, [])
        total -= int(ranks[b])
        mat = np.stack([v[b] for v in vecs], axis=1)  # (10, m)
        _, sv, vt = np.linalg.svd(mat, full_matrices=True)
        r = int(np.sum(sv > rtol * scale))
        total += r
        for c in vt[r:]:
            new: dict[int, np.ndarray] = {}
            for coef, v in zip(c, vecs):
                if coef == 0:
                    continue
                for blk, h in v.items():
                    if blk != b:
                        new[blk] = new.get(blk, 0) + coef * h
            new = {blk: h for blk, h in new.items() if np.linalg.norm(h) > rtol * scale}
            if new:
                top = max(new)
                pending.setdefault(top, []).append(new)
                if top not in queued:
                    queued.add(top)
                    heapq.heappush(heap, -top)
    return total


@dataclass(frozen=True)
class DRNGResult:
    """The DRNG output: columns with provenance, their exact rank and timing."""

    robot: Robot
    columns: Columns
    rank: int
    seconds: float
    extended: bool = True

    @property
    def n_columns(self) -> int:
        return len(self.columns)

    def sparse(self) -> sp.csc_matrix:
        """``B_null (10 n, k)`` sparse, paper convention."""
        return to_sparse(self.columns, self.robot.n)

    def dense(self) -> np.ndarray:
        return self.sparse().toarray()

    def orthonormal(self, rtol: float = 1e-10) -> np.ndarray:
        """An orthonormal basis ``(10 n, rank)`` of the columns' span."""
        b = self.dense()
        if b.shape[1] == 0:
            return b
        b = b / np.linalg.norm(b, axis=0)
        u, s, _ = np.linalg.svd(b, full_matrices=False)
        return u[:, : int(np.sum(s > rtol * s[0]))]

    def by_principle(self) -> dict[str, int]:
        """Rank contributed by each source, taken in order: the paper's principles 1, 2, 3, then
        the extended rules R-A, R-B, R-L1, R-L2 (those run), then the unmeasured root's own
        parameters (joint-torque rows only)."""
        out, prev = {}, 0
        names = PAPER + (EXTENDED if self.extended else ())
        if np.any(self.columns.principle == PRINCIPLES.index(UNMEASURED)):
            names = names + (UNMEASURED,)
        for name in names:
            k = PRINCIPLES.index(name)
            keep = self.columns.principle <= k
            r = prev if not np.any(self.columns.principle == k) else block_rank(self.columns.subset(keep), self.robot.n)
            out[name] = r - prev
            prev = r
        return out

    @property
    def paper_rank(self) -> int:
        """Rank of the paper's principles alone."""
        return sum(v for k, v in self.by_principle().items() if k in PAPER)

    def provenance(self, k: int) -> str:
        """Human-readable origin of column ``k``."""
        c = self.columns
        names = self.robot.names
        body = names[c.child[k]]
        par = "" if c.parent[k] < 0 else f" / {names[c.parent[k]]}"
        j = int(c.joint[k])
        if j >= self.robot.n:
            lj = self.robot.loops[j - self.robot.n]
            joint = f"loop joint {lj.name!r} ({lj.type})"
        else:
            joint = f"joint {self.robot.joint_names[j]!r} ({self.robot.jtype[j]})"
        if c.principle[k] == PRINCIPLES.index(UNMEASURED):
            return f"{UNMEASURED}: body {body}, {c.label[k]} (no measured row sees the floating root's own parameters)"
        if c.principle[k] >= len(PAPER):
            return f"{PRINCIPLES[c.principle[k]]}: bodies {body}{par}, {c.label[k]}"
        return f"{PRINCIPLES[c.principle[k]]}: {joint}, bodies {body}{par}, points {c.label[k]}"


def unmeasured_columns(robot: Robot, rows: str) -> Columns:
    """Columns that the measured rows add: with joint torques alone (``rows="joints"``) on a
    floating robot, no row sees the floating root's own ten parameters (joint ``j``'s torque is
    its line against the wrenches of the bodies it carries, and no joint carries the root), so
    each is a nullspace direction on its own. With the base wrench alone (``"base"``) nothing is
    added: it sees every direction the full dynamics see (Ayusawa et al. 2014, the paper's
    remark; certification checks it)."""
    from ..numerics import row_mask

    mask = row_mask(robot, rows)
    roots = [i for i in range(robot.n) if robot.jtype[i] == "F"]
    if rows != "joints" or not roots or mask.all():
        return Columns.empty()
    k = 10 * len(roots)
    child = np.repeat(np.array(roots, dtype=int), 10)
    z = np.zeros(k, dtype=int)
    labels = np.array(list(PAPER_NAMES) * len(roots), dtype=object)
    return Columns(np.tile(np.eye(10), (len(roots), 1)), child, z - 1, np.full(k, PRINCIPLES.index(UNMEASURED)),
                   child.copy(), labels, hp=np.zeros((k, 10)))


def drng(robot: Robot, tol: float = 1e-9, extended: bool = True, rows: str = "all") -> DRNGResult:
    """Run DRNG (corrected) on ``robot``: columns with provenance and their exact rank.

    ``extended``: add the rules that close the paper's gaps (:mod:`.rules`: R-A, R-B, R-L1, R-L2);
    ``False`` gives the paper's three principles alone. ``rows``: the measured generalized
    forces (``all``, ``joints``, ``base``; see :func:`unmeasured_columns`)."""
    t0 = time.perf_counter()
    cols = drng_columns(robot, tol)
    if extended:
        from .rules import rule_columns

        cols = Columns.concat([cols, rule_columns(robot, tol)])
    cols = Columns.concat([cols, unmeasured_columns(robot, rows)])
    rank = block_rank(cols, robot.n)
    return DRNGResult(robot, cols, rank, time.perf_counter() - t0, extended)
