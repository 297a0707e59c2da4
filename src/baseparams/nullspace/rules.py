"""Extended principles: the rules that close the paper's gaps (``docs/extended-rules.md``).

One mechanism: a change ``dN`` of pseudo-inertias is in the regressor nullspace iff its kinetic
term ``T = 1/2 tr(dg dN dg^T)`` vanishes on every motion and its potential
``V = -gbar^T g(q) dN e4`` is constant. With the exact motion spans of
:mod:`.subspaces` both conditions are linear at q = 0:

- **R-A fixed vectors** (every body): ``sym(f, v)`` for ``f`` fixed and any ``v``; across a loop
  joint, ``sym`` of the vectors both bodies move alike (``+`` successor, ``-`` predecessor);
- **R-B sliding points**: ``sym(a, b)`` for ``a`` sliding along ``d`` and ``b`` level in ``d``,
  ``d`` the one line a point can slide along (the P directions of the path, all parallel);
- **R-L1 parallelograms** (loops): a 4-cycle of parallel R joints whose joint points form a
  parallelogram at q = 0: opposite links keep their relative orientation on that assembly mode
  (fixed root: coupler translations and rocker-to-crank transfers; moving root: direction
  transfers and a three-body rocker-to-crank transfer compensated on the root);
- **R-L2 level chains** (loops): a direction ``x`` that stays ``⟂ e`` (level in ``e``, loop-aware)
  and is shared along a chain of bodies (R or P joints along ``x``) from a point ``A`` to a point
  ``B`` whose ``e``-coordinates never change: ``Σ_j sym(x, x × r_j)`` over the chain is null
  (``r_j`` the chain's segment in body ``j``; the symmetric 2PRS-1PSR: +1);

R-A and R-B are followed by the gravity filter: keep the combinations whose ``dN e4`` is level in gravity
(the potential never changes). Columns are in the paper's convention (spatial pseudo-inertia at
q = 0, ``hat`` order) and carry their provenance; they are redundant with each other and with the
paper's principles, so :func:`.rank.block_rank` decides the rank.
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from ..enums import Source
from ..model.inertia import hat as hat10
from ..model.inertia import unhat
from ..model.robot import Robot
from ..pga.core import hat
from ..pga.linalg import cross3, null_rows, nullspace, rowspace, span_rows, sym
from .columns import Columns, on_bodies, sym_params
from .principles import compound_shared, world_axes
from .spatial import spatial_parallelogram_columns
from .subspaces import MotionSpans, motion_spans

#: provenance of the rules' columns
RA, RB, RL1, RL2, RL3 = Source.R_A, Source.R_B, Source.R_L1, Source.R_L2, Source.R_L3


def _independent(syms: np.ndarray, tol: float) -> np.ndarray:
    """An orthonormal basis ``(r, 10)`` of the parameter vectors ``hat(syms)``."""
    if len(syms) == 0:
        return np.zeros((0, 10))
    return rowspace(hat10(syms), tol)


def _describe(v: np.ndarray) -> str:
    x, y, z, w = (float(c) for c in v)
    if abs(w) > 1e-9:
        a, b, c = (round(t / w, 12) + 0.0 for t in (x, y, z))
        return f"point ({a:.4g}, {b:.4g}, {c:.4g})"
    n = (x * x + y * y + z * z) ** 0.5
    a, b, c = (round(t / n, 12) + 0.0 for t in (x, y, z))
    return f"direction ({a:.4g}, {b:.4g}, {c:.4g})"


class _Label:
    """A provenance label formatted on demand.

    Labels are built for every column and read rarely (``DRNGResult.provenance``), so the
    formatting is deferred.
    """

    __slots__ = ("fn", "args")

    def __init__(self, fn, *args) -> None:
        self.fn, self.args = fn, args

    def __str__(self) -> str:
        return self.fn(*self.args)

    __repr__ = __str__


def _fixed_label(f: np.ndarray) -> str:
    return "sym(f, v), f fixed: " + "; ".join(_describe(v) for v in f)


def _sliding_label(d: np.ndarray, dim: int) -> str:
    return f"sym(a, b), a sliding along ({', '.join(f'{c + 0:.4g}' for c in d)}), {dim}-dimensional"


def _singles(hs: list[np.ndarray], bodies, rule: int, labels: list[str]) -> Columns:
    """One-body columns for many bodies at once: basis ``hs[k] (r_k, 10)`` on ``bodies[k]``."""
    counts = np.array([len(h) for h in hs], dtype=int)
    if counts.sum() == 0:
        return Columns.empty()
    body = np.repeat(np.asarray(bodies, dtype=int), counts)
    m = len(body)
    return Columns(np.concatenate(hs), body, np.full(m, -1), np.full(m, rule), body.copy(),
                   np.repeat(np.array(labels, dtype=object), counts))


def _sym_columns(ms: MotionSpans, bodies: np.ndarray, a: np.ndarray, b: np.ndarray) -> list[np.ndarray]:
    """Gravity-filtered ``sym(a_k[i], b_k[j])`` of each body ``bodies[k]``, as an orthonormal basis ``(r_k, 10)``.

    The basis spans the combinations whose potential is constant (gravity filter). ``a, b (m, 4,
    4)``: vectors as rows, padded with zero rows. Batched: three SVD calls for all bodies.
    """
    m = len(bodies)
    syms = sym(a[:, :, None], b[:, None, :]).reshape(m, 16, 4, 4)  # zero for padding
    g = ms.robot.gravity
    if np.linalg.norm(g) > ms.tol:
        c = np.einsum("a,mkab->mkb", g / np.linalg.norm(g), ms.padded[bodies])  # rows g^T X, padded
        _, sv, vt = np.linalg.svd(np.einsum("mra,mka->mrk", c, syms[..., :, 3]), full_matrices=True)
        rk = np.sum(sv > ms.tol, axis=1)
        coef = vt * (np.arange(16)[None, :, None] >= rk[:, None, None])  # nullspace rows only
        syms = np.einsum("mck,mkab->mcab", coef, syms)
    _, sv, vt = np.linalg.svd(hat10(syms), full_matrices=False)  # (m, 10, 10)
    rk = np.sum(sv > ms.tol, axis=1)
    return [vt[k, : rk[k]] for k in range(m)]


def _padded(vectors: list[np.ndarray]) -> np.ndarray:
    out = np.zeros((len(vectors), 4, 4))
    for k, v in enumerate(vectors):
        out[k, : len(v)] = v
    return out


def fixed_vector_columns(robot: Robot, ms: MotionSpans | None = None) -> Columns:
    """R-A: ``sym(f, v)`` on every body ``i`` with ``f`` fixed (``∩ ker S_j`` on its path), gravity filtered.

    Principle 2 applied beyond the first body (``docs/extended-rules.md``, R-A).
    Closes gravity zero (Puma560's axis-1/axis-2 intersection: +2), translation stages (every
    direction fixed) and a U joint at the base with its first axis along gravity
    (``docs/paper-corrections.md``, cases 1, 3, 4). Batched over bodies; single-body columns.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    ms : MotionSpans, optional
        The robot's motion spans (:func:`.subspaces.motion_spans`); built (default tolerance)
        when not given. Their ``tol`` is the rule's tolerance.

    Returns
    -------
    Columns
        The columns with provenance (R-A fixed vectors), blocks in the ``paper`` convention
        (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world
        frame at q = 0).
    """
    ms = motion_spans(robot) if ms is None else ms
    bodies = np.array([i for i in range(robot.n) if ms.span[i] is not None and len(ms.fixed(i))], dtype=int)
    if not len(bodies):
        return Columns.empty()
    anything = np.broadcast_to(np.eye(4), (len(bodies), 4, 4))
    hs = _sym_columns(ms, bodies, _padded([ms.fixed(i) for i in bodies]), anything)
    labels = [_Label(_fixed_label, ms.fixed(i)) for i in bodies]
    return _singles(hs, bodies, RA, labels)


def _readable(basis: np.ndarray) -> np.ndarray:
    """A basis of the same span with points first (one point, then directions), for labels."""
    if len(basis) == 0:
        return basis
    w = basis[:, 3]
    if np.abs(w).max() < 1e-9:
        return basis
    k = int(np.argmax(np.abs(w)))
    p = basis[k] / basis[k, 3]
    rest = basis - np.outer(basis[:, 3], p)
    dirs = rowspace(rest, 1e-9)
    return np.concatenate([p[None], dirs]) if len(dirs) else p[None]


def slide_directions(robot: Robot, tol: float = 1e-9) -> np.ndarray:
    """The only line a non-fixed point of each body can slide along ``(n, 3)`` (zero: none).

    A point's velocity gets ``p_j(q)`` from every P joint ``j`` on the path and a rotating part
    from the R joints; free rotations alone never move a point along a straight line, so a
    sliding point needs a P joint, and all P directions on the path must be that line. Bodies
    with no P joint on their path, or two non-parallel ones, get zero (R-B has nothing to add
    there beyond R-A's fixed vectors). A compound joint contributes its pure translations; a
    free (F) joint, and everything below it, gets zero.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Two P directions are parallel when the squared norm of their cross product is at most
        ``tol**2``.

    Returns
    -------
    ndarray, shape ``(n, 3)``
        The slide direction of each body (a P axis of its path, world frame at q = 0), or zero.
    """
    s = robot.screws
    pdir = s[robot.q_index, 3:] / np.maximum(np.linalg.norm(s[robot.q_index, 3:], axis=1, keepdims=True), 1e-300)
    pd = pdir.tolist()
    par = robot.parent.tolist()
    out: list[tuple[float, float, float] | None] = []  # None: conflict
    zero = (0.0, 0.0, 0.0)
    tol2 = tol * tol
    for i, t in enumerate(robot.jtype):
        p = par[i]
        d = out[p] if p >= 0 else zero
        if d is not None and t in ("P", "C"):
            k0 = int(robot.q_index[i])
            rows = [pd[i]] if t == "P" else [tuple(s[k0 + k, 3:]) for k in range(int(robot.ndofs[i]))
                                             if not np.any(s[k0 + k, :3])]  # a C joint's slides
            for v in rows:
                if d is None:
                    break
                if d == zero:
                    d = tuple(v)
                else:
                    cx, cy, cz = d[1] * v[2] - d[2] * v[1], d[2] * v[0] - d[0] * v[2], d[0] * v[1] - d[1] * v[0]
                    if cx * cx + cy * cy + cz * cz > tol2:
                        d = None
        elif t == "F":
            d = None
        out.append(d)
    return np.array([zero if d is None else d for d in out], dtype=float).reshape(robot.n, 3)


def sliding_columns(robot: Robot, ms: MotionSpans | None = None) -> Columns:
    """R-B: ``sym(a, b)`` with ``a`` sliding along ``d`` and ``b`` level in ``d``, gravity filtered.

    Velocity of ``a`` always along ``d``, of ``b`` always ``⟂ d``; ``d`` from
    :func:`slide_directions` (``docs/extended-rules.md``, R-B). Closes a fixed axis
    beyond the base (a lift followed by coaxial R joints along gravity: +2 per turning body;
    ``docs/paper-corrections.md``, case 2). Batched over bodies; single-body columns, only on
    bodies where something slides that is not fixed.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    ms : MotionSpans, optional
        The robot's motion spans (:func:`.subspaces.motion_spans`); built (default tolerance)
        when not given. Their ``tol`` is the rule's tolerance.

    Returns
    -------
    Columns
        The columns with provenance (R-B sliding points), blocks in the ``paper`` convention
        (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world
        frame at q = 0).
    """
    ms = motion_spans(robot) if ms is None else ms
    dirs = slide_directions(robot, ms.tol)
    bodies = np.array([i for i in np.flatnonzero(np.any(dirs, axis=1)) if ms.span[i] is not None], dtype=int)
    if not len(bodies):
        return Columns.empty()
    d = dirs[bodies]
    x = ms.padded[bodies]  # (m, 12, 3, 4)
    proj = np.eye(3) - np.einsum("ma,mb->mab", d, d)
    _, sv, vt = np.linalg.svd(np.einsum("mab,mkbc->mkac", proj, x).reshape(len(bodies), -1, 4))
    ra = np.sum(sv > ms.tol, axis=1)
    nfix = np.array([len(ms.fixed(i)) for i in bodies])
    keep = 4 - ra > nfix  # something slides that is not fixed
    if not keep.any():
        return Columns.empty()
    bodies, d, vt, ra, x = bodies[keep], d[keep], vt[keep], ra[keep], x[keep]
    a = vt * (np.arange(4)[None, :, None] >= ra[:, None, None])  # sliding space rows (padded)
    _, lsv, lvt = np.linalg.svd(np.einsum("ma,mkab->mkb", d, x))
    rl = np.sum(lsv > ms.tol, axis=1)
    b = lvt * (np.arange(4)[None, :, None] >= rl[:, None, None])  # level space rows (padded)
    hs = _sym_columns(ms, bodies, a, b)
    labels = [_Label(_sliding_label, dd, 4 - r) for dd, r in zip(d, ra)]
    return _singles(hs, bodies, RB, labels)


# ------------------------------------------------------------------------------ loops: R-L1
def _path_to(robot: Robot, b: int, stop: int) -> list[int]:
    out = []
    while b != stop:
        out.append(b)
        b = int(robot.parent[b])
    return out


def _ancestors(robot: Robot, b: int) -> list[int]:
    out = [b]
    while b >= 0:
        b = int(robot.parent[b])
        out.append(b)
    return out


def _cycle(robot: Robot, lj) -> tuple[int, list[int], list[int]]:
    """A loop joint's cycle: ``(root, down, up)``.

    ``root`` the lowest common ancestor of its two bodies (``-1``: the base), ``down`` the bodies
    from below the root to the successor, ``up`` from the predecessor up to below the root.
    """
    anc_c, anc_p = _ancestors(robot, lj.child), _ancestors(robot, lj.parent)
    lca = next(a for a in anc_c if a in anc_p)
    return lca, _path_to(robot, lj.child, lca)[::-1], _path_to(robot, lj.parent, lca)


def parallelograms(robot: Robot, tol: float = 1e-7) -> list[dict]:
    """Loop 4-cycles of parallel R joints whose joint points form a parallelogram at q = 0.

    The assembly mode is the parallelogram one (``P1 - P0 = P2 - P3``: crank and rocker stay
    parallel); a flattened (collinear) reference, where both modes meet, is not accepted. Only
    R loop joints closing a cycle of four links through R tree joints are examined.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-7
        Axes are parallel when the norm of their cross product (unit first axis) is at most
        ``tol``; the sides must match, and be nonzero, to ``tol`` times the longer side.

    Returns
    -------
    list of dict
        Per parallelogram, ``links [L0, L1, L2, L3]`` (``L0`` the cycle's root, ``-1`` for the
        fixed base), ``points (4, 3)`` with ``points[j]`` the joint between ``L_j`` and
        ``L_{j+1}`` (world frame at q = 0), the common ``axis (3,)`` and ``loop`` (the loop
        joint's name).
    """
    out = []
    axw = world_axes(robot)
    org = robot.M0[:, :3, 3]
    for lj in robot.loops:
        if lj.type != "R":
            continue
        lca, down, up = _cycle(robot, lj)
        if len(down) + len(up) != 3 or any(robot.jtype[b] != "R" for b in down + up):
            continue
        links = [lca] + down + up
        # joint between L_j and L_{j+1}: tree joints going down, the loop joint, tree joints going up
        joints = [(org[b], axw[b]) for b in down]
        joints.append((lj.M[:3, 3], lj.M[:3, :3] @ lj.axes[0]))
        joints += [(org[b], axw[b]) for b in up]
        axis = joints[0][1] / np.linalg.norm(joints[0][1])
        if any(np.linalg.norm(np.cross(axis, a)) > tol for _, a in joints):
            continue
        pts = np.array([p - axis * (axis @ p) for p, _ in joints])  # projected to the plane ⟂ axis
        side1, side2 = pts[1] - pts[0], pts[2] - pts[1]
        scale = max(np.linalg.norm(side1), np.linalg.norm(side2), 1e-300)
        if np.linalg.norm(side1 - (pts[2] - pts[3])) > tol * scale:
            continue
        if min(np.linalg.norm(side1), np.linalg.norm(side2)) < tol * scale or \
                np.linalg.norm(np.cross(side1, side2)) < 1e-6 * scale**2:
            continue  # degenerate or flattened: the assembly mode is not decided at q = 0
        out.append({"links": links, "points": np.array([p for p, _ in joints]), "axis": axis, "loop": lj.name})
    return out


def _pair(h_a: np.ndarray, a: int, h_b: np.ndarray, b: int, label: str, rule: int = RL1) -> Columns:
    """Columns ``+h_a`` on body ``a``, ``+h_b`` on body ``b`` (``b`` may be ``-1``: dropped)."""
    m = len(h_a)
    if b < 0 or a > b:
        hi, lo, hh, hl = a, b, h_a, h_b
    else:
        hi, lo, hh, hl = b, a, h_b, h_a
    return Columns(hh, np.full(m, hi), np.full(m, lo), np.full(m, rule), np.full(m, hi),
                   np.full(m, label, dtype=object), hl if lo >= 0 else np.zeros_like(hh))


def parallelogram_columns(robot: Robot) -> Columns:
    """R-L1: for each parallelogram (:func:`parallelograms`), opposite links keep their relative orientation.

    Opposite links are ``L0, L2`` (and ``L1, L3``). With the fixed base as
    ``L0``: ``sym(f, v)`` on the coupler ``L2`` for every direction ``f`` (it only translates),
    and every parameter of the rocker ``L3`` transfers to the crank ``L1`` (``+dN`` on ``L3``,
    ``-T^-1 dN T^-T`` on ``L1``, ``T`` the translation by ``P3 - P0``: ``g_3 = T g_1 T^-1``).
    With a moving ``L0``: the direction transfers ``sym(f_a, f_b)`` between opposite links, and
    a three-body rocker-to-crank transfer compensated on the root (:func:`_moving_root_transfer`).
    Closes ``docs/paper-corrections.md`` case 5 (a parallelogram four-bar: 27 of 30).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).

    Returns
    -------
    Columns
        The columns with provenance (R-L1 parallelograms), blocks in the ``paper`` convention
        (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world
        frame at q = 0).
    """
    e = np.eye(4)
    dirs = sym(e[:3, None], e[None, :3]).reshape(-1, 4, 4)
    dir_basis = rowspace(hat10(dirs), 1e-12)  # the 6 direction-direction parameters
    parts = []
    for par in parallelograms(robot):
        l0, l1, l2, l3 = par["links"]
        p = par["points"]
        name = par["loop"]
        if l0 < 0:
            h = _independent(sym(e[:3, None], e[None]).reshape(-1, 4, 4), 1e-12)  # sym(direction, anything): 9
            label = f"parallelogram (loop {name!r}): the coupler only translates, sym(f, v) for every direction f"
            parts.append(_singles([h], [l2], RL1, [label]))
            t = np.eye(4)
            t[:3, 3] = p[3] - p[0]
            ti = np.linalg.inv(t)
            dn = unhat(np.eye(10))
            moved = hat10(ti @ dn @ ti.T)
            label = f"parallelogram (loop {name!r}): rocker parameters transfer to the crank"
            parts.append(_pair(hat10(dn), l3, -moved, l1, label))
        else:
            label = f"parallelogram (loop {name!r}): direction transfer between the coupler and the root link"
            parts.append(_pair(dir_basis, l2, -dir_basis, l0, label))
            parts.append(_moving_root_transfer(p, par["axis"], l0, l1, l3, name))
    return Columns.concat(parts)


def _moving_root_transfer(p: np.ndarray, axis: np.ndarray, l0: int, l1: int, l3: int, name: str) -> Columns:
    """Rocker-to-crank transfer when the root link ``L0`` moves (``g_3 = g_0 T h_1 T^-1``).

    With ``dN' = T^-1 dN T^-T`` and ``w = dN' e4`` shared by ``L0`` and ``L1`` (on the axis of
    their joint, so ``dg_1 w = dg_0 w``), the Lagrangian of ``dN`` on ``L3`` equals that of ``dN'``
    on ``L1`` plus ``sym(w, t) + m' t t^T`` on ``L0`` (``t = (P3 - P0, 0)``, ``m' = dN'_44``): a
    three-body column. Derivation: ``g_0 T h_1 = g_1 + g_0 tau`` with ``tau = T - I``.
    """
    t = np.eye(4)
    t[:3, 3] = p[3] - p[0]
    tbar = np.r_[p[3] - p[0], 0.0]
    shared = np.array([np.r_[p[0], 1.0], np.r_[axis, 0.0]])  # points and direction of joint L0-L1
    basis = unhat(np.eye(10))  # (10, 4, 4)
    comp = np.eye(4) - shared.T @ np.linalg.pinv(shared.T)  # projector off the shared space
    coef = nullspace(np.einsum("ab,kb->ka", comp, basis[:, :, 3]).T, 1e-12)
    dnp = np.einsum("rk,kab->rab", coef, basis)  # dN' with dN' e4 shared
    dn = t @ dnp @ t.T
    w = dnp[:, :, 3]
    root = np.einsum("ka,b->kab", w, tbar)
    root = root + np.swapaxes(root, -1, -2) + dnp[:, 3, 3, None, None] * np.outer(tbar, tbar)
    m = len(dnp)
    hi, lo = max(l1, l3), min(l1, l3)
    h_hi, h_lo = (hat10(dn), -hat10(dnp)) if l3 > l1 else (-hat10(dnp), hat10(dn))
    label = f"parallelogram (loop {name!r}): rocker parameters transfer to the crank, root link compensates"
    return Columns(h_hi, np.full(m, hi), np.full(m, lo), np.full(m, RL1), np.full(m, hi),
                   np.full(m, label, dtype=object), h_lo, np.full(m, l0), -hat10(root))


def loop_shared_columns(robot: Robot, tol: float = 1e-9) -> Columns:
    """R-A across loop joints: vectors shared by a loop joint's two bodies (``g_c v = g_p v``).

    Besides the joint's own points (principle 1: R ``{O, z}``, U/S ``{O}``, P directions), every
    vector fixed by all joint screws between the loop's root link and either body is shared (both
    bodies move it as the root does); e.g. a spherical loop joint closing a planar linkage also
    shares the plane's normal direction. ``sym(a, b)`` of shared vectors: ``+`` on the successor,
    ``-`` on the predecessor. Loops whose root path fixes nothing are skipped.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Absolute singular-value threshold of the fixed vectors and of the shared span.

    Returns
    -------
    Columns
        The columns with provenance (R-A fixed vectors, joint ``n + l`` for loop joint ``l``),
        blocks in the ``paper`` convention (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ
        MX MY MZ M`` of each body, world frame at q = 0).
    """
    screws = hat(robot.screws)
    qi, nd = robot.q_index, robot.ndofs
    e = np.eye(4)
    parts = []
    for k, lj in enumerate(robot.loops):
        _, down, up = _cycle(robot, lj)
        bodies = down[::-1] + up
        js = [j for b in bodies for j in range(qi[b], qi[b] + nd[b])]
        fix = nullspace(screws[js].reshape(-1, 4), tol) if js else e
        own = _shared_vectors(lj.type, lj.M[:3, 3], _loop_axis(lj))
        if len(fix) == 0:
            continue
        shared = rowspace(np.concatenate([own, fix]), tol)
        h = _independent(sym(shared[:, None], shared[None]).reshape(-1, 4, 4), tol)
        label = (f"shared across loop joint {lj.name!r} ({lj.type}), fixed relative to the loop's root: "
                 + "; ".join(_describe(v) for v in _readable(shared)))
        m = len(h)
        parts.append(Columns(h, np.full(m, lj.child), np.full(m, lj.parent), np.full(m, RA),
                             np.full(m, robot.n + k), np.full(m, label, dtype=object)))
    return Columns.concat(parts)


# ------------------------------------------------------------------------------ loops: R-L2
def _loop_axis(lj) -> np.ndarray:
    """A loop joint's first axis in world coordinates at q = 0 ``(3,)`` (zero if it has none)."""
    return lj.M[:3, :3] @ lj.axes[0] if len(lj.axes) else np.zeros(3)


def _shared_vectors(jtype: str, origin: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Vectors ``(s, 4)`` a joint's two bodies move alike (principle 1).

    R its axis point and direction; U, S the centre; P every direction; a fixed loop joint
    everything; a free joint nothing.
    """
    pt = np.r_[origin, 1.0]
    e = np.eye(4)
    return {"R": np.array([pt, np.r_[axis, 0.0]]), "P": e[:3], "U": pt[None], "S": pt[None],
            "fixed": e}.get(jtype, np.zeros((0, 4)))


def _joint_shares(robot: Robot) -> list[tuple[int, int, str, np.ndarray, np.ndarray, np.ndarray]]:
    """Every tree and loop joint as ``(a, b, type, origin (3,), axis (3,), shared (s, 4))``.

    ``a`` the predecessor (``-1``: the base), ``shared`` an orthonormal basis of the vectors both
    bodies move alike (R: axis point and direction; U, S: the centre; P: every direction; a
    fixed loop joint: everything; a free joint: nothing).
    """
    axw = world_axes(robot)
    out = []
    spec = [(int(robot.parent[i]), i, robot.jtype[i], robot.M0[i, :3, 3], axw[i]) for i in range(robot.n)]
    spec += [(lj.parent, lj.child, lj.type, lj.M[:3, 3], _loop_axis(lj))
             for lj in robot.loops]
    for k, (a, b, t, o, ax) in enumerate(spec):
        if k < robot.n and t == "C":
            sh = compound_shared(robot, k)
        else:
            sh = rowspace(_shared_vectors(t, o, ax), 1e-12)
        out.append((a, b, t, np.asarray(o, float), np.asarray(ax, float), sh))
    return out


def _cross4(x: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``(x × d, 0)`` for 4-vectors ``(..., 4)`` (their direction parts), broadcasting."""
    out = np.zeros(np.broadcast_shapes(x.shape, d.shape))
    out[..., :3] = cross3(x[..., :3], d[..., :3])
    return out


def _level_spaces(robot: Robot, es: np.ndarray, ms: MotionSpans, joints: list) -> np.ndarray:
    """Loop-aware level spaces for every candidate ``es (C, 3)`` and body at once.

    ``(C, n, 4, 4)`` orthonormal rows padded with zero rows (see :func:`loop_level_spaces`).
    """
    n, tol = robot.n, ms.tol
    live = np.array([s is not None for s in ms.span])
    h = null_rows(np.einsum("ca,nkab->cnkb", es, ms.padded), tol) * live[None, :, None, None]
    edges = [(a, b, sh) for a, b, *_, sh in joints if len(sh)] + [(b, a, sh) for a, b, *_, sh in joints if len(sh)]
    edges = [(a if a >= 0 else n, b, sh) for a, b, sh in edges if b >= 0]
    if not edges:
        return h
    src = np.array([a for a, _, _ in edges])
    dst = np.array([b for _, b, _ in edges])
    s_pad = np.zeros((len(edges), 4, 4))
    for k, (_, _, sh) in enumerate(edges):
        s_pad[k, : len(sh)] = sh
    slot = np.zeros(len(edges), dtype=int)  # which incoming edge of its destination
    seen: dict[int, int] = {}
    for k, b in enumerate(dst.tolist()):
        slot[k] = seen.get(b, 0)
        seen[b] = slot[k] + 1
    rank = np.sum(np.linalg.norm(h, axis=-1) > 0.5, axis=-1)
    eye = np.eye(4)
    for _ in range(n + 2):
        hx = np.concatenate([h, np.broadcast_to(eye, (len(es), 1, 4, 4))], axis=1)[:, src]  # (C, E, 4, 4)
        off = eye - np.swapaxes(hx, -1, -2) @ hx  # projector off each source's level space
        alpha = null_rows(off @ np.swapaxes(s_pad, -1, -2), tol)  # shared combinations that are level
        common = alpha @ s_pad
        z = np.zeros((len(es), n, 1 + max(seen.values()), 4, 4))
        z[:, :, 0] = h
        z[:, dst, 1 + slot] = common
        h_new, r_new = span_rows(z.reshape(len(es), n, -1, 4), tol)
        if not np.any(r_new > rank):
            break
        h, rank = h_new, r_new
    return h


def loop_level_spaces(robot: Robot, e: np.ndarray, ms: MotionSpans | None = None) -> list[np.ndarray]:
    """Loop-aware level spaces ``H_i((e, 0))`` ``(h_i, 4)`` per body.

    The open tree's (exact for the tree, a subset for the closed robot), enlarged to a fixpoint
    by propagation across every tree and loop joint: a vector both bodies move alike that keeps
    its ``e``-coordinate in one body keeps it in the other (``docs/extended-rules.md``,
    R-L2). Safe: everything returned is level on the closed robot.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    e : array_like, shape ``(3,)``
        The direction whose coordinate is kept (world frame at q = 0).
    ms : MotionSpans, optional
        The robot's motion spans (:func:`.subspaces.motion_spans`); built (default tolerance)
        when not given. Their ``tol`` is used for the level spaces.

    Returns
    -------
    list of ndarray
        Per body ``i``, ``(h_i, 4)`` orthonormal rows: homogeneous 4-vectors (points and
        directions, world frame at q = 0) whose ``e``-coordinate never changes.
    """
    ms = motion_spans(robot) if ms is None else ms
    h = _level_spaces(robot, np.asarray(e, float)[None], ms, _joint_shares(robot))[0]
    return [hi[np.linalg.norm(hi, axis=1) > 0.5] for hi in h]


def _candidates(robot: Robot, joints: list, tol: float) -> np.ndarray:
    """Unit directions ``e (C, 3)``: every joint axis and gravity, parallel ones once."""
    v = np.array([ax for *_, ax, _ in joints] + [np.asarray(robot.gravity, float)]).reshape(-1, 3)
    nv = np.linalg.norm(v, axis=1)
    u = v[nv > tol] / nv[nv > tol, None]
    par = np.abs(u @ u.T) > 1.0 - 1e-14  # parallel or anti-parallel
    first = np.argmax(par, axis=1)  # the first of each parallel class
    return u[first == np.arange(len(u))]


class _Level(NamedTuple):
    """Per candidate ``e`` and body: the level directions (all, and those ``⟂ e``), counts, a point.

    The counts of both kinds of direction, and a level point when there is one.
    """

    dirs: np.ndarray  # (C, n, 4, 4) level directions (w = 0), padded with zero rows
    xs: np.ndarray  # (C, n, 4, 4) level directions ⟂ e
    nd: np.ndarray  # (C, n) how many dirs
    nx: np.ndarray  # (C, n) how many xs
    pts: np.ndarray  # (C, n, 4) a level point (zero where none)
    has_pt: np.ndarray  # (C, n)


def level_chain_columns(robot: Robot, ms: MotionSpans | None = None, tol: float = 1e-9) -> Columns:
    """R-L2, level chains (loop robots).

    For a fixed direction ``e`` and a direction ``x`` that stays ``⟂ e`` (level,
    :func:`loop_level_spaces`), shared by a chain of bodies joined by R or P joints along ``x``
    from a level point ``A`` to a level point ``B``:

        Σ_j sym(x, x × r_j) on body j,   r_j = J_j - J_{j-1},  J_0 = A, J_m = B, J_j on joint j,

    is null. Proof: its kinetic term is ``ẋ · d/dt(x × (B - A)) = (B - A)˙ · (ẋ × x)``, and
    ``ẋ × x ∥ e`` (``x`` turns in the plane ``⟂ e``) while ``e · (B - A)`` is constant; direction
    pairs have no potential. Single bodies (``A, B`` on one body: any level direction ``d``
    gives ``sym(x, x × d)``), pairs and triples are emitted; ``e`` runs over the joint axes and
    gravity, all candidates batched. Loop robots only: on trees the level spaces are exact and
    the rule adds nothing beyond R-A and R-B (the special-robot survey). Closes
    ``docs/paper-corrections.md`` case 6 (the symmetric 2PRS-1PSR: +1).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    ms : MotionSpans, optional
        The robot's motion spans (:func:`.subspaces.motion_spans`); built with ``tol`` when not
        given. Their ``tol`` is used for the level spaces.
    tol : float, default 1e-9
        Geometric tolerance (zero axes and directions, singular values of the level spaces).

    Returns
    -------
    Columns
        The columns with provenance (R-L2 level chains), blocks in the ``paper`` convention
        (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world
        frame at q = 0).
    """
    if not robot.loops:
        return Columns.empty()
    ms = motion_spans(robot, tol) if ms is None else ms
    joints = _joint_shares(robot)
    es = _candidates(robot, joints, tol)
    lv = _level_parts(_level_spaces(robot, es, ms, joints), es, tol)
    parts: list[Columns] = []
    singles = _level_single_columns(es, lv, tol)
    if singles is not None:
        parts.append(singles)
    # chains: bodies joined by R or P joints along a level x ⟂ e
    links = [(a, b, o, ax / np.linalg.norm(ax)) for a, b, t, o, ax, _ in joints
             if a >= 0 and t in ("R", "P") and np.linalg.norm(ax) > tol]
    for c in range(len(es)):
        parts += _level_chains(robot, np.r_[es[c], 0.0], _level_edges(links, es[c], lv.nx[c], lv.xs[c]),
                               lv.pts[c], lv.has_pt[c])
    return Columns.concat(parts)


def _level_parts(h: np.ndarray, es: np.ndarray, tol: float) -> _Level:
    """Split the level spaces ``h (C, n, 4, 4)`` into level directions and points."""
    pad = np.einsum("cnk,kl->cnkl", (np.linalg.norm(h, axis=-1) < 0.5).astype(float), np.eye(4))
    h3 = h[..., 3][:, :, None, :]
    dirs = null_rows(np.concatenate([h3, pad], axis=2), tol) @ h  # level directions (w = 0)
    he = np.einsum("cnka,ca->cnk", h[..., :3], es)[:, :, None, :]
    xs = null_rows(np.concatenate([h3, he, pad], axis=2), tol) @ h  # level directions ⟂ e
    nd = np.sum(np.linalg.norm(dirs, axis=-1) > 0.5, axis=-1)
    nx = np.sum(np.linalg.norm(xs, axis=-1) > 0.5, axis=-1)
    kw = np.argmax(np.abs(h[..., 3]), axis=-1)
    wrow = np.take_along_axis(h, kw[..., None, None], axis=2)[:, :, 0]  # (C, n, 4)
    has_pt = np.abs(wrow[..., 3]) > 1e-9
    pts = np.where(has_pt[..., None], wrow / np.where(has_pt, wrow[..., 3], 1.0)[..., None], 0.0)
    return _Level(dirs, xs, nd, nx, pts, has_pt)


def _level_single_columns(es: np.ndarray, lv: _Level, tol: float) -> Columns | None:
    """Single bodies: ``sym(x_a, x_b × d) + sym(x_b, x_a × d)`` for level x's ⟂ e and level d's.

    Returns None when no body has both.
    """
    ci, bi = np.nonzero((lv.nx >= 1) & (lv.nd >= 2))
    if not len(ci):
        return None
    x, d = lv.xs[ci, bi], lv.dirs[ci, bi]
    xd = _cross4(x[:, :, None], d[:, None])  # (m, 4, 4, 4): x_a × d
    m = np.einsum("mai,mbdj->mabdij", x, xd)
    m = m + np.swapaxes(m, -1, -2)
    m = (m + np.swapaxes(m, 1, 2)).reshape(len(ci), -1, 4, 4)
    _, sv, vt = np.linalg.svd(hat10(m), full_matrices=False)
    rk = np.sum(sv > tol, axis=1)
    ks = np.flatnonzero(rk)
    labels = []
    for k in ks:
        ee = np.r_[es[ci[k]], 0.0]
        if lv.nx[ci[k], bi[k]] == 1:
            xl = f"x {_describe(x[k, np.argmax(np.linalg.norm(x[k], axis=1))])}"
        else:
            xl = f"x any direction ⟂ {_describe(ee)}"
        labels.append(f"level chain ⟂ {_describe(ee)} in one body: sym(x, x × d), {xl}, d level")
    return _singles([vt[k, : rk[k]] for k in ks], bi[ks], RL2, labels)


def _level_edges(links: list, e: np.ndarray, nx: np.ndarray,
                 xs: np.ndarray) -> dict[int, list[tuple[int, np.ndarray, np.ndarray]]]:
    """Body -> ``(neighbour, x, joint point)`` for the level R/P ``links`` ⟂ ``e``.

    A link counts when its axis ``x`` is ⟂ ``e`` and level in the predecessor; both directions of
    each joint are listed.
    """
    edges: dict[int, list[tuple[int, np.ndarray, np.ndarray]]] = {}
    for a, b, o, ax in links:
        if abs(ax @ e) > 1e-9 or nx[a] == 0:
            continue
        x = np.r_[ax, 0.0]
        xa = xs[a]
        if np.linalg.norm(x - (x @ xa.T) @ xa) > 1e-7:
            continue
        jp = np.r_[o, 1.0]
        edges.setdefault(a, []).append((b, x, jp))
        edges.setdefault(b, []).append((a, x, jp))
    return edges


def _seg(x, p, q):
    """``sym(x, x × (q - p))`` as one column ``(1, 10)``."""
    return sym_params(x, _cross4(x, q - p))[None]


def _level_chains(robot: Robot, ee: np.ndarray, edges: dict, pts: np.ndarray, has_pt: np.ndarray) -> list[Columns]:
    """The pairs and triples of one candidate ``ee`` along its level ``edges``.

    Pairs ``a - b`` (both with a level point) and triples ``b - a - c2`` (``a`` without one, the
    two joints parallel).
    """
    parts: list[Columns] = []
    for a, nbrs in edges.items():
        for b, x, jp in nbrs:
            empty = max(np.linalg.norm(jp - pts[a]), np.linalg.norm(pts[b] - jp)) <= 1e-9  # a zero column
            if a < b and has_pt[a] and has_pt[b] and not empty:
                label = (f"level chain ⟂ {_describe(ee)}: x {_describe(x)} from {_describe(pts[a])} "
                         f"to {_describe(pts[b])} across the joint at {_describe(jp)}")
                parts.append(_pair(_seg(x, pts[a], jp), a, _seg(x, jp, pts[b]), b, label, RL2))
        if has_pt[a]:
            continue
        for k, (b, x, j1) in enumerate(nbrs):  # a in the middle of a triple b - a - c2
            for c2, x2, j2 in nbrs[k + 1:]:
                if not (has_pt[b] and has_pt[c2]) or abs(abs(x @ x2) - 1.0) > 1e-9:
                    continue
                if max(np.linalg.norm(j1 - pts[b]), np.linalg.norm(j2 - j1), np.linalg.norm(pts[c2] - j2)) <= 1e-9:
                    continue  # every segment empty: a zero column
                body = sorted([(b, _seg(x, pts[b], j1)), (a, _seg(x, j1, j2)), (c2, _seg(x, j2, pts[c2]))],
                              key=lambda t: t[0])
                (lo, hl), (mid, hm), (hi, hh) = body
                label = (f"level chain ⟂ {_describe(ee)}: x {_describe(x)} from {_describe(pts[b])} "
                         f"to {_describe(pts[c2])} through {robot.names[a]!r}")
                parts.append(Columns(hh, np.array([hi]), np.array([mid]), np.array([RL2]), np.array([hi]),
                                     np.array([label], dtype=object), hm, np.array([lo]), hl))
    return parts


# ------------------------------------------------------------------------------ loops: R-L3
def planar_loops(robot: Robot, tol: float = 1e-9) -> list[dict]:
    """Loops whose cycle moves in planes ``⟂ u`` relative to its root link.

    Every tree joint of the cycle is a 1-dof R joint with axis ``∥ u`` or a P joint ``⟂ u`` (at
    least one R), and the loop joint is an R joint ``∥ u`` or closes at a point (S, U): each link
    of the cycle then moves relative to the root link ``L0`` by a rotation about ``u`` and a
    translation ``⟂ u``.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Axes are parallel (perpendicular) when the norm of the cross (dot) product of the unit
        axes is at most ``tol``.

    Returns
    -------
    list of dict
        Per loop, ``links [L0, L1, ..., Lm]`` (``L0`` the cycle's root, ``-1`` for the fixed
        base), ``points (m + 1, 3)`` with ``points[j]`` the joint between ``L_j`` and
        ``L_{j+1}`` (cyclically; world frame at q = 0), ``slides (m + 1,)`` (True where that
        joint is a P joint), the unit ``axis (3,)``, ``loop`` (the loop joint's name) and
        ``index`` (its index in ``robot.loops``).
    """
    out = []
    axw = world_axes(robot)
    org = robot.M0[:, :3, 3]
    for k, lj in enumerate(robot.loops):
        if lj.type not in ("R", "S", "U"):
            continue
        lca, down, up = _cycle(robot, lj)
        tree = down + up
        if not tree or any(robot.jtype[b] not in ("R", "P") or robot.ndofs[b] != 1 for b in tree):
            continue
        unit = {b: axw[b] / max(np.linalg.norm(axw[b]), 1e-300) for b in tree}
        turns = [unit[b] for b in tree if robot.jtype[b] == "R"]
        if lj.type == "R":
            turns.append(_loop_axis(lj) / max(np.linalg.norm(_loop_axis(lj)), 1e-300))
        if not turns:
            continue
        axis = turns[0]
        if any(np.linalg.norm(np.cross(axis, a)) > tol for a in turns) or \
                any(abs(axis @ unit[b]) > tol for b in tree if robot.jtype[b] == "P"):
            continue
        points = [org[b] for b in down] + [lj.M[:3, 3]] + [org[b] for b in up]
        slides = [robot.jtype[b] == "P" for b in down] + [False] + [robot.jtype[b] == "P" for b in up]
        out.append({"links": [lca] + tree, "points": np.array(points), "slides": np.array(slides),
                    "axis": axis, "loop": lj.name, "index": k})
    return out


def planar_loop_columns(robot: Robot, tol: float = 1e-9) -> Columns:
    """R-L3: a planar loop's closure moves the out-of-plane products of inertia around the cycle.

    Relative to the root ``L0`` link ``k`` of a loop of :func:`planar_loops` moves by
    ``x -> R_k x + p_k`` in the plane ``⟂ u``. The out-of-plane part of a link's pseudo-inertia
    (the products ``P = (∫ x_i y)`` of in-plane ``x`` and ``y = u . x``, the moment ``∫ y`` and
    ``∫ y^2``) enters the energy only through ``C = sum_k R_k P_k + p_k ∫ y_k``, ``sum ∫ y`` and
    ``sum ∫ y^2`` (whatever the root does). Around the cycle, joint ``e`` between links ``a``
    and ``b`` gives ``p_b - p_a = (R_a - R_b) r_e`` (R, S, U at the point ``r_e``) or leaves
    ``p_b - p_a`` as it is (P), and these differences sum to zero: so ``+r_e`` on ``P_a`` and
    ``-r_e`` on ``P_b`` for every turning joint, ``+1`` on ``∫ y_b`` and ``-1`` on ``∫ y_a``
    for every sliding one, keep ``C`` and ``sum ∫ y`` (a nullspace direction); without sliding
    joints the same with every ``P`` turned by 90 degrees (``u x r_e``) is a second one. Written
    ``sym(r, u)`` and ``sym(e4, u)`` (the root's block dropped when it is the fixed base, which
    makes every out-of-plane part invisible). Derivation: ``docs/extended-rules.md`` (R-L3).
    Closes Cassie's plantar-rod loops (one direction each) and slider-cranks on a tilted hip.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Parallel-axis tolerance (:func:`planar_loops`).

    Returns
    -------
    Columns
        One or two columns per planar loop over the cycle's links (provenance R-L3 planar
        loops, ``joint`` the loop joint: ``n + l``), blocks in the ``paper`` convention (spatial
        pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at
        q = 0).
    """
    parts = []
    e4 = np.array([0.0, 0.0, 0.0, 1.0])
    for lp in planar_loops(robot, tol):
        u = np.r_[lp["axis"], 0.0]
        links, m = lp["links"], len(lp["links"])
        r = lp["points"] - np.outer(lp["points"] @ u[:3], u[:3])  # joint points projected to the plane
        turned = [r, np.cross(u[:3], r)] if not lp["slides"].any() else [r]
        x = np.zeros((len(turned), m, 10))
        for c, rr in enumerate(turned):
            for e in range(m):  # joint e between links e and e + 1 (cyclically)
                a, b = e, (e + 1) % m
                if lp["slides"][e]:
                    x[c, b] += sym_params(e4, u)
                    x[c, a] -= sym_params(e4, u)
                else:
                    v = np.r_[rr[e], 0.0]
                    x[c, a] += sym_params(v, u)
                    x[c, b] -= sym_params(v, u)
        keep = [i for i, b in enumerate(links) if b >= 0]
        x = x[:, keep]
        x = x[np.linalg.norm(x.reshape(len(x), -1), axis=1) > 0]
        if not len(x):
            continue
        kind = "slider" if lp["slides"].any() else "closure sum R_k L_k = 0"
        label = (f"planar loop {lp['loop']!r} (axes ∥ {_describe(u)}, {kind}): out-of-plane products "
                 "moved around the cycle")
        cols = on_bodies([links[i] for i in keep], x.reshape(len(x), -1), RL3, label)
        parts.append(replace(cols, joint=np.full(len(cols), robot.n + lp["index"])))  # the loop joint
    return Columns.concat(parts)


def locked_bodies(robot: Robot) -> np.ndarray:
    """Bodies the loops and couplings hold still: every coordinate on their path is locked.

    Group the coordinates by the constraints that tie them (a coupling ties its coordinates; a
    loop joint, every coordinate on its two bodies' paths to the root): a group that holds no
    independent coordinate is solved for alone at every configuration, its Jacobian regular at
    the reference (checked when the robot is assembled), so its coordinates never change. A
    body none of whose path coordinates moves (no floating root) never moves (e.g. an arm welded
    at its hand with as many joints as the weld's constraints).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).

    Returns
    -------
    ndarray of bool, shape ``(n,)``
        True for a body held still.
    """
    if not (robot.loops or robot.couplings) or robot.floating:
        return np.zeros(robot.n, dtype=bool)
    dof = robot.dof
    root = list(range(dof))

    def find(k):
        while root[k] != k:
            root[k] = root[root[k]]
            k = root[k]
        return k

    sup = robot.support  # (dof, n): coordinate j moves body i
    groups = [[c.succ, *(k for k, _ in c.terms())] for c in robot.couplings]
    for lj in robot.loops:
        groups.append(list(np.flatnonzero(sup[:, lj.child] != 0)) +
                      ([] if lj.parent < 0 else list(np.flatnonzero(sup[:, lj.parent] != 0))))
    tied = np.zeros(dof, dtype=bool)
    for g in groups:
        tied[g] = True
        for k in g[1:]:
            root[find(int(k))] = find(int(g[0]))
    free = {find(int(k)) for k in robot.actuated}
    locked = np.array([tied[j] and find(j) not in free for j in range(dof)])
    return np.array([bool(np.all(locked[np.flatnonzero(sup[:, i] != 0)])) for i in range(robot.n)])


def locked_body_columns(robot: Robot) -> Columns:
    """R-A on the closed robot: each of a locked body's ten parameters is null (:func:`locked_bodies`).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).

    Returns
    -------
    Columns
        Ten unit columns per locked body (provenance R-A fixed vectors).
    """
    bodies = np.flatnonzero(locked_bodies(robot))
    if not len(bodies):
        return Columns.empty()
    k = 10 * len(bodies)
    child = np.repeat(bodies, 10)
    labels = np.array([f"held still by its loops: {robot.names[b]}" for b in child], dtype=object)
    return Columns(np.tile(np.eye(10), (len(bodies), 1)), child, -np.ones(k, dtype=int), np.full(k, RA),
                   child.copy(), labels, hp=np.zeros((k, 10)))


def rule_columns(robot: Robot, tol: float = 1e-9) -> Columns:
    """The extended-rule columns R-A, R-B, R-L1, R-L2, R-L3, R-L4 for ``robot`` (R-M: :mod:`.coupled`).

    In order: R-A on every body (:func:`fixed_vector_columns`) and across loop joints
    (:func:`loop_shared_columns`), R-B (:func:`sliding_columns`), R-L1
    (:func:`parallelogram_columns`), R-L2 (:func:`level_chain_columns`), R-L3
    (:func:`planar_loop_columns`), R-L4 (:func:`.spatial.spatial_parallelogram_columns`), sharing one
    :func:`.subspaces.motion_spans`. The columns are redundant with each other and with the
    paper's principles: :func:`.rank.block_rank` decides the rank.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Geometric tolerance of the motion spans and the rules that take one (R-L1 uses its own).

    Returns
    -------
    Columns
        The columns with provenance (R-A fixed vectors, R-B sliding points, R-L1
        parallelograms, R-L2 level chains, R-L3 planar loops), blocks in the ``paper`` convention (spatial
        pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at
        q = 0).
    """
    ms = motion_spans(robot, tol)
    return Columns.concat([fixed_vector_columns(robot, ms), locked_body_columns(robot), loop_shared_columns(robot, tol),
                           sliding_columns(robot, ms), parallelogram_columns(robot),
                           level_chain_columns(robot, ms, tol), planar_loop_columns(robot, tol),
                           spatial_parallelogram_columns(robot, tol, ms)])
