"""Regrouping a tree's base parameters from a block-sparse nullspace basis, in memory ``O(nnz K)``.

:func:`~.regroup.base_parameters` orthonormalises a dense ``(10 n, k)`` basis and factors it:
cubic time and quadratic memory. For a basis in compact form whose columns are linearly
independent and whose highest body ``c`` carries a block ``H_c`` of full column rank (what
:func:`baseparams.nullspace.rank.leading_spans` returns for a tree), the same regrouping is
computed body by body:

* the dependent parameters: the dense greedy choice (last body first, each body in the
  convention's regrouping order) takes a row when a nullspace vector vanishing on the rows taken
  so far is nonzero there. Every column touches only its highest body ``c`` and lower ones, so
  when body ``c`` is reached the vectors vanishing on the higher bodies' choices are spanned by
  the columns whose highest body is ``c`` or lower, and on ``c``'s rows only ``H_c`` is nonzero:
  the choice is the greedy one on ``H_c``'s rows (dimensionless, orthonormalised);
* ``K = -B_I B_D^-1 = -Z_I`` with ``Z = B B_D^-1`` the dual basis (1 on its own dependent
  parameter, 0 on the others), built from the root up: body ``c``'s columns times
  ``H_c[D_c]^-1``, minus the lower bodies' dual vectors times their entries on those bodies'
  dependent parameters. ``Z_c`` lives on the path from ``c`` to the root: ``K`` has
  ``O(sum of depths)`` nonzeros, the size of the regrouped expressions themselves.

The tolerances and zeroing are those of :func:`~.regroup.base_parameters`, with the rank
decision of the choice made on each body's own block; coefficients snap to decimals of at most 12
significant digits only (:func:`snap_short`: what the expressions print). ``K``, ``E`` and ``T`` are
``scipy.sparse`` CSR matrices (dense arrays for models of at most :data:`DENSE_MAX_PARAMS`
parameters, where importing scipy.sparse costs more than they do) and ``base_basis`` is ``None``
(it would be dense).
"""

from __future__ import annotations

import numpy as np

from ..model import inertia as _inertia
from ..model.inertia import LENGTH_POWER
from ..model.robot import Robot
from ..model.scale import body_rounding, length_scale
from ..nullspace.columns import Columns
from .regroup import NOISE_FACTOR, SNAP_RTOL, ZERO_TOL, BaseParameters, parameter_names


def body_transforms(robot: Robot, convention: str) -> np.ndarray:
    """Per body, the block ``T_i (10, 10)`` with paper parameters ``= T_i @`` convention parameters.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies; ``M0`` maps body frames to the world frame at q = 0).
    convention : str
        The convention of the parameters ``T_i`` multiplies.

    Returns
    -------
    ndarray, shape ``(n, 10, 10)``
        The diagonal blocks of :func:`~.regroup.paper_from` (identities for ``paper``).
    """
    if convention == "paper":
        return np.tile(np.eye(10), (robot.n, 1, 1))
    per = _inertia.from_convention(np.eye(10), convention)  # (10, 4, 4)
    return np.swapaxes(_inertia.hat(_inertia.transform(per[None], robot.M0[:, None])), -1, -2)


#: coefficients snap to a decimal of at most this many significant digits (what the expressions print)
SNAP_DIGITS = 12


#: exact powers of ten 10^-22 .. 10^22 (every one a double)
_POW10 = 10.0 ** np.arange(-22, 23)


def _snap_at(v: np.ndarray, mag: np.ndarray, p: int, rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """``v`` rounded to ``p`` significant digits (``mag``: decimal exponents), and where that is within ``rtol``."""
    sc = p - 1 - mag  # the decimal is D * 10^-sc, D an integer of p digits
    ok = np.abs(sc) <= 22
    e = _POW10[np.clip(sc, -22, 22) + 22]
    d = np.rint(v * e)
    snapped = np.where(sc >= 0, d / e, d * _POW10[np.clip(-sc, -22, 22) + 22])
    return snapped, ok & (np.abs(snapped - v) <= rtol * np.abs(v))


def snap_short(x: np.ndarray, rtol: float | np.ndarray = SNAP_RTOL, digits: int = SNAP_DIGITS) -> np.ndarray:
    """:func:`~.regroup.clean` restricted to decimals of at most ``digits`` significant digits, vectorised.

    An entry within ``rtol`` relative of a decimal of ``k <= digits`` significant digits becomes
    the double nearest that decimal (computed as ``D / 10^s`` or ``D * 10^-s``, one correctly
    rounded operation on exact operands, so the same double as parsing the decimal); other
    entries (``clean`` would move them by less than ``rtol``, to 13-17 digits) stay as they are.

    Parameters
    ----------
    x : ndarray
        Numbers, any shape.
    rtol : float or ndarray
        The largest relative move (:data:`~.regroup.SNAP_RTOL`), or one per entry (``x``'s shape:
        the rounding each entry carries).
    digits : int
        The most significant digits of a snapped value (at most 15).

    Returns
    -------
    ndarray
        A snapped copy, same shape.
    """
    x = np.array(x, dtype=float)
    flat = x.reshape(-1)
    nz = np.flatnonzero(np.isfinite(flat) & (flat != 0))
    v = flat[nz]
    rtol = np.broadcast_to(np.asarray(rtol, dtype=float), x.shape).reshape(-1)[nz]
    with np.errstate(all="ignore"):
        mag = np.floor(np.log10(np.abs(v))).astype(int)
    out = v.copy()
    # a decimal of k <= digits digits is also one of ``digits`` digits: test that first, once for all
    idx = np.flatnonzero(_snap_at(v, mag, digits, rtol)[1])
    for p in range(1, digits + 1):  # the shortest: fewest digits first
        if not len(idx):
            break
        snapped, ok = _snap_at(v[idx], mag[idx], p, rtol[idx])
        out[idx[ok]] = snapped[ok]
        idx = idx[~ok]
    flat[nz] = out
    return x


#: a coefficient's snapping tolerance is at least this many times its bodies'
#: :func:`~baseparams.model.scale.body_rounding`
SNAP_ROUNDING = 10.0


def scaled_blocks(robot: Robot, cols: Columns, convention: str) -> tuple[np.ndarray, ...]:
    """Each column's blocks in dimensionless convention coordinates, and the noise level.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    cols : Columns
        ``k`` columns in compact form (SI ``paper`` convention).
    convention : str
        The convention to regroup in.

    Returns
    -------
    hc, hp, he : ndarray, shape ``(k, 10)``
        The columns' blocks on their highest, lower and extra bodies, in ``convention``
        coordinates scaled by ``L^-u`` (zero where a column has no such body).
    hm : dict of int to tuple
        The further blocks (:attr:`~baseparams.nullspace.columns.Columns.more`) the same way:
        column -> ``(bodies (m,) int, blocks (m, 10))``, for the columns that have some.
    t : ndarray, shape ``(n, 10, 10)``
        :func:`body_transforms`.
    noise : ndarray, shape ``(n,)``
        Per body, the rounding level of its blocks in dimensionless coordinates relative to
        their size: :data:`~.regroup.NOISE_FACTOR` times
        :func:`~baseparams.model.scale.body_rounding` times the
        scaling's ``cond(L^-u)``. (One level for all bodies from the worst body's
        ``cond(L^-u T^-1)`` would grow as ``D^4`` and stop a 3 000-link chain's regrouping at
        its root.)
    """
    t = body_transforms(robot, convention)
    tinv = np.linalg.inv(t)
    power = LENGTH_POWER[convention].astype(float)
    sc = length_scale(robot) ** -power
    st = sc[:, None] * tinv  # (n, 10, 10)
    noise = NOISE_FACTOR * (sc.max() / sc.min()) * body_rounding(robot)

    def blk(bodies: np.ndarray, h: np.ndarray) -> np.ndarray:
        return np.einsum("kij,kj->ki", st[np.maximum(bodies, 0)], h) * (bodies >= 0)[:, None]

    hm = {}
    for j in np.flatnonzero(cols.has_more()).tolist():
        bodies, blocks = np.asarray(cols.more[j][0], dtype=int), np.asarray(cols.more[j][1], dtype=float)
        hm[j] = (bodies, np.einsum("kij,kj->ki", st[bodies], blocks.reshape(-1, 10)))
    return blk(cols.child, cols.h), blk(cols.parent, cols.hp), blk(cols.extra, cols.he), hm, t, noise


def lower_blocks(cols: Columns, hp: np.ndarray, he: np.ndarray, hm: dict, idx: np.ndarray,
                 a: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """The blocks of columns ``idx`` (one highest body) below it, times ``a``: every block, ``more`` included.

    Parameters
    ----------
    cols : Columns
        The columns (their ``parent`` and ``extra`` bodies).
    hp, he : ndarray, shape ``(k, 10)``
        Their scaled blocks on ``parent`` and ``extra`` (:func:`scaled_blocks`).
    hm : dict of int to tuple
        Their scaled further blocks (:func:`scaled_blocks`).
    idx : ndarray of int, shape ``(l,)``
        The columns whose highest body is the same.
    a : ndarray, shape ``(l, l)``
        The factor each column's blocks are combined with (row ``i`` for column ``idx[i]``).

    Returns
    -------
    list of tuple
        ``(body j, sum_i block_i(j) a[i] (10, l))`` per lower body ``j`` the columns touch, ``j``
        ascending.
    """
    out: dict[int, np.ndarray] = {}
    for low, part in ((cols.parent[idx], hp[idx]), (cols.extra[idx], he[idx])):
        for j in sorted(set(low[low >= 0].tolist())):  # not np.unique: it imports numpy.ma
            m = low == j
            out[j] = out[j] + part[m].T @ a[m] if j in out else part[m].T @ a[m]
    if hm:
        for i, col in enumerate(idx.tolist()):
            for j, blk in zip(*hm.get(col, ((), ()))):
                out[int(j)] = out.get(int(j), 0.0) + np.outer(blk, a[i])
    return sorted(out.items())


def choose_all(hc: np.ndarray, child: np.ndarray, n: int, within: tuple[int, ...], tol: float | np.ndarray):
    """Every body's dependent parameters and ``H_c[D_c]^-1``, bodies batched by their column count.

    Parameters
    ----------
    hc : ndarray, shape ``(k, 10)``
        The columns' dimensionless blocks on their highest bodies (:func:`scaled_blocks`).
    child : ndarray of int, shape ``(k,)``
        Each column's highest body.
    n : int
        Number of bodies.
    within : tuple of int
        The convention's regrouping order of a body's ten parameters.
    tol : float or ndarray, shape ``(n,)``
        Relative threshold of a row's new component (as :func:`~.regroup.choose_dependent`),
        for every body or per body.

    Returns
    -------
    order, bounds : ndarray of int
        The columns sorted by body: ``order[bounds[c]:bounds[c + 1]]`` are body ``c``'s.
    dep : list of list of int
        The chosen local rows per body (the greedy choice, as :func:`~.regroup.choose_dependent`).
    ainv : list of ndarray or None
        The inverses of the chosen rows, ``(l_c, l_c)`` per body.

    Raises
    ------
    RuntimeError
        A body's columns are not independent on it.
    """
    tol = np.broadcast_to(np.asarray(tol, dtype=float), (n,))
    order = np.argsort(child, kind="stable")
    bounds = np.searchsorted(child[order], np.arange(n + 1))
    counts = np.diff(bounds)
    dep: list[list[int]] = [[] for _ in range(n)]
    ainv: list[np.ndarray | None] = [None] * n
    for ell in sorted(set(counts[counts > 0].tolist())):  # not np.unique: it imports numpy.ma
        bodies = np.flatnonzero(counts == ell)
        idx = order[bounds[bodies][:, None] + np.arange(ell)]  # (nb, l)
        h = np.swapaxes(hc[idx], 1, 2)  # (nb, 10, l)
        q = np.linalg.svd(h, full_matrices=False)[0]
        scale = np.maximum(np.linalg.norm(q, axis=2).max(axis=1), 1e-300)
        basis = np.zeros((len(bodies), ell, ell))
        count = np.zeros(len(bodies), dtype=int)
        chosen = np.full((len(bodies), ell), -1)
        for r in within:  # Gram-Schmidt twice against the rows taken so far, as _choose
            v = q[:, r, :].copy()
            for _ in range(2):
                v -= np.einsum("bkl,bk->bl", basis, np.einsum("bkl,bl->bk", basis, v))
            nv = np.linalg.norm(v, axis=1)
            take = np.flatnonzero((nv > tol[bodies] * scale) & (count < ell))
            basis[take, count[take]] = v[take] / nv[take, None]
            chosen[take, count[take]] = r
            count[take] += 1
        if np.any(count < ell):
            raise RuntimeError(f"body {int(bodies[np.argmin(count)])}: the nullspace columns are not independent on "
                               f"their highest body")
        inv = np.linalg.inv(np.take_along_axis(h, chosen[:, :, None], axis=1))
        for k, c in enumerate(bodies.tolist()):
            dep[c], ainv[c] = chosen[k].tolist(), inv[k]
    return order, bounds, dep, ainv


def _dual_basis(robot: Robot, cols: Columns, scaled: tuple, within: tuple[int, ...],
                tol: float | np.ndarray) -> tuple[list[list[int]], list[tuple[np.ndarray, np.ndarray]]]:
    """Per body, its dependent parameters (local indices) and dual vectors ``Z_c``.

    ``Z_c`` is ``(bodies (m,), blocks (m, 10, l_c))``: its blocks on the bodies it touches, ``c``
    first, then the bodies on its way to the root.
    """
    n = robot.n
    hc, hp, he, hm = scaled
    order, bounds, dep, ainv = choose_all(hc, cols.child, n, within, tol)
    empty = (np.zeros(0, dtype=int), np.zeros((0, 10, 0)))
    z: list[tuple[np.ndarray, np.ndarray]] = [empty] * n
    for c in range(n):  # parents first: their dual vectors are final when a child needs them
        if not dep[c]:
            continue
        idx = order[bounds[c]:bounds[c + 1]]
        a = ainv[c]
        parts = []  # (bodies, blocks) of the columns' lower blocks, with the dual vectors cancelling them
        for j, zj in lower_blocks(cols, hp, he, hm, idx, a):  # zj (10, l): the columns' blocks on body j
            if dep[j]:  # cancel the entries on body j's dependent parameters (Z_j starts with j)
                bj, vj = z[j]
                blocks = -np.einsum("bik,kl->bil", vj, zj[dep[j]])
                blocks[0] += zj
                parts.append((bj, blocks))
            else:
                parts.append((np.array([j]), zj[None]))
        own = (np.array([c]), (hc[idx].T @ a)[None])
        if len(parts) == 1:
            z[c] = (np.concatenate([own[0], parts[0][0]]), np.concatenate([own[1], parts[0][1]]))
            continue
        b_all = np.concatenate([own[0]] + [p[0] for p in parts])
        v_all = np.concatenate([own[1]] + [p[1] for p in parts])
        uniq, inv = np.unique(b_all[1:], return_inverse=True)
        acc = np.zeros((len(uniq), 10, len(idx)))
        np.add.at(acc, inv, v_all[1:])
        z[c] = (np.r_[c, uniq], np.concatenate([own[1], acc]))
    return dep, z


def _k_entries(n: int, dep_local: list[list[int]], z: list, pos_i: np.ndarray, pos_d: np.ndarray):
    """``(rows, cols, values)`` of ``-Z_I``: the dual vectors' entries on the independent parameters."""
    rows, cls, vals = [], [], []
    for c in range(n):
        if not dep_local[c]:
            continue
        dcols = pos_d[10 * c + np.array(dep_local[c], dtype=int)]
        bodies, blocks = z[c]
        p = pos_i[10 * bodies[:, None] + np.arange(10)]  # (m, 10)
        keep = p >= 0
        rows.append(np.repeat(p[keep], len(dcols)))
        cls.append(np.tile(dcols, int(keep.sum())))
        vals.append(-blocks[keep].ravel())
    if not rows:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros(0)
    return np.concatenate(rows).astype(int), np.concatenate(cls).astype(int), np.concatenate(vals)


def tree_base_parameters(robot: Robot, cols: Columns, convention: str) -> BaseParameters:
    """Regroup into base parameters from independent nullspace columns in compact form (module doc).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    cols : Columns
        ``k`` linearly independent columns spanning the nullspace, SI ``paper`` convention,
        each with a highest body (``child``) whose blocks are linearly independent there
        (:attr:`baseparams.nullspace.structured.StructuredCheck.independent`).
    convention : str
        The parameter convention to regroup in.

    Returns
    -------
    BaseParameters
        ``10 n - k`` base parameters: ``K (nb, k)``, ``E (nb, 10 n)`` and ``T (10 n, 10 n)`` as
        ``scipy.sparse`` CSR matrices (dense arrays up to :data:`DENSE_MAX_PARAMS` parameters),
        ``base_basis`` ``None``; the same names, dependent set and
        coefficients as :func:`~.regroup.base_parameters` on the dense span (up to decisions within
        the tolerances).

    Raises
    ------
    RuntimeError
        The columns are not independent on their highest bodies.
    """
    n, n10 = robot.n, 10 * robot.n
    hc, hp, he, hm, t, noise = scaled_blocks(robot, cols, convention)
    tol = np.maximum(1e-8, noise)
    dep_local, z = _dual_basis(robot, cols, (hc, hp, he, hm), _inertia.SPECS[convention].regroup_order, tol)
    dep = np.array([10 * c + w for c in reversed(range(n)) for w in dep_local[c]], dtype=int)
    keep = np.ones(n10, dtype=bool)  # not np.setdiff1d: it imports numpy.ma (start-up time)
    keep[dep] = False
    ind = np.flatnonzero(keep)
    pos_i = np.full(n10, -1)
    pos_i[ind] = np.arange(len(ind))
    pos_d = np.full(n10, -1)
    pos_d[dep] = np.arange(len(dep))
    rows, cls, vals = _k_entries(n, dep_local, z, pos_i, pos_d)
    rowmax = np.ones(len(ind))
    np.maximum.at(rowmax, rows, np.abs(vals))
    level = np.maximum(noise[ind[rows] // 10], noise[dep[cls] // 10])  # either body's rounding
    keep = np.abs(vals) > np.maximum(ZERO_TOL, level) * rowmax[rows]
    rows, cls, vals = rows[keep], cls[keep], vals[keep]
    power = np.tile(LENGTH_POWER[convention], n).astype(float)
    rounding = SNAP_ROUNDING * body_rounding(robot)
    snap = np.maximum(SNAP_RTOL, np.maximum(rounding[ind[rows] // 10], rounding[dep[cls] // 10]))
    vals = snap_short(vals * length_scale(robot) ** (power[ind][rows] - power[dep][cls]), snap)
    kmat = csr_or_dense(vals, rows, cls, (len(ind), len(dep)))
    # E = [I | K] doubles K's memory (O(sum of depths) nonzeros): a large tree's is made when first read
    e = None if not isinstance(kmat, np.ndarray) else csr_or_dense(
        np.r_[np.ones(len(ind)), vals], np.r_[np.arange(len(ind)), rows], np.r_[ind, dep[cls]], (len(ind), n10))
    if isinstance(kmat, np.ndarray):
        unseen = ~np.any(kmat != 0, axis=0)
    else:
        unseen = np.diff(kmat.tocsc().indptr) == 0
    unid = np.sort(dep[unseen]) if len(dep) else np.zeros(0, dtype=int)
    tb = np.asarray(t, dtype=float).reshape(n, 10, 10)
    tr = (10 * np.arange(n)[:, None, None] + np.arange(10)[None, :, None]) + np.zeros((1, 1, 10), dtype=int)
    tmat = csr_or_dense(tb.ravel(), tr.ravel(), np.transpose(tr, (0, 2, 1)).ravel(), (n10, n10))
    return BaseParameters(convention, parameter_names(robot, convention), ind, dep, kmat, e, unid, None, tmat)


#: below this many parameters the regrouping's matrices are dense arrays: scipy.sparse's import
#: (~50-80 ms) would cost more than the arrays (at most 8 MB for ``T``)
DENSE_MAX_PARAMS = 1000


def csr_or_dense(vals: np.ndarray, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]):
    """The matrix of triplets (duplicates summed): a CSR matrix, or a dense array for small models.

    Parameters
    ----------
    vals : ndarray, shape ``(m,)``
        Values.
    rows, cols : ndarray of int, shape ``(m,)``
        Their positions.
    shape : tuple of int
        The matrix's shape.

    Returns
    -------
    ndarray or scipy.sparse.csr_matrix
        Dense up to :data:`DENSE_MAX_PARAMS` rows and columns, CSR (sorted, no stored zeros) above.
    """
    if shape[1] > DENSE_MAX_PARAMS or shape[0] > DENSE_MAX_PARAMS:
        import scipy.sparse as sp

        out = sp.csr_matrix((vals, (rows, cols)), shape=shape)
        out.eliminate_zeros()
        out.sort_indices()
        return out
    out = np.zeros(shape)
    np.add.at(out, (rows, cols), vals)
    return out
