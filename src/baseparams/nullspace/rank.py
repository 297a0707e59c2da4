"""The exact rank of a column set in O(n): block-triangular elimination, leaves to root."""

from __future__ import annotations

import heapq

import numpy as np

from .columns import Columns


def per_body(rtol: float | np.ndarray, n: int) -> np.ndarray:
    """A relative threshold per body ``(n,)`` from one number or an array of them.

    Parameters
    ----------
    rtol : float or ndarray, shape ``(n,)``
        The threshold of every body, or of each.
    n : int
        Number of bodies.

    Returns
    -------
    ndarray, shape ``(n,)``
        A fresh array.
    """
    return np.array(np.broadcast_to(np.asarray(rtol, dtype=float), (n,)))


def block_rank(cols: Columns, n: int, rtol: float | np.ndarray = 1e-10) -> int:
    """Exact rank of the columns in O(n): block-triangular elimination, leaves to root.

    Each column lives on blocks ``{child, parent}`` with ``parent < child``. Per body, the
    rank of its diagonal block (child parts plus vectors pushed up from its children)
    counts; combinations vanishing there are pushed to lower blocks. All diagonal blocks are
    checked at once (batched SVD); only when one is rank-deficient does the general
    block-by-block elimination (:func:`_elimination_rank`) run. Loop columns (blocks
    ``{successor, predecessor}``, predecessor < successor) fit the same scheme. Single-body
    columns are first reduced to an orthonormal basis per body (:func:`_reduce_pure`), so a
    translation chain's redundant columns do not cascade.

    Parameters
    ----------
    cols : Columns
        ``k`` columns in compact form (blocks on ``child``, ``parent`` and ``extra``, each
        lower than ``child``), ``paper`` convention.
    n : int
        Number of moving bodies (``B`` has ``10 n`` rows).
    rtol : float or ndarray, shape ``(n,)``, default 1e-10
        Singular-value threshold of each diagonal block, relative to its norm (to the largest
        entry of ``h`` in the elimination); one per body (e.g. raised to the rounding of
        :func:`baseparams.model.scale.decision_frames`) or one for all.

    Returns
    -------
    int
        The rank of ``B (10 n, k)`` (:func:`~.columns.to_sparse`), computed without forming it.
    """
    rtol = per_body(rtol, n)
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
    ranks = np.sum(sv > (rtol * np.maximum(scale, 1e-300))[:, None], axis=1)
    if np.all(ranks == counts):
        return int(ranks.sum())
    return _elimination_rank(cols, n, rtol, ranks, counts, order, starts)


def _reduce_pure(cols: Columns, rtol: np.ndarray) -> Columns:
    """A column set of the same span, cheaper to rank (elementary column operations only).

    From the highest body down: the single-body ("pure") columns of body ``b`` become an
    orthonormal basis ``Q`` of their span; the two-block columns ``(h on b, hp on p)`` sharing a
    parent ``p`` are rotated by the right singular vectors of their child parts off ``Q``, and
    each combination whose child part lies in ``span Q`` is replaced by its parent part alone, a
    new pure column of ``p``. Without this a translation chain's redundant pure columns cascade
    through the elimination (quadratic in the depth). ``rtol``: per body.
    """
    pure_mask = (cols.parent < 0) & (cols.extra < 0) & ~cols.has_more()
    if not pure_mask.any():
        return cols
    tol = rtol * max(float(np.abs(cols.h).max()), 1e-300)  # (n,)
    pure = _pure_bases(cols, pure_mask, tol)
    fresh = set(pure)  # bodies whose pure list is still the batched orthonormal basis
    order, span_of = _two_block_groups(cols, pure_mask)
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
        basis = _orthonormal(pure.pop(bb), bb in fresh, tol[bb])
        out_h.append(basis.T)
        out_b += [bb] * basis.shape[1]
        if bb not in span_of or basis.shape[1] == 0:
            continue
        idx = order[span_of[bb][0]: span_of[bb][1]]
        for p in sorted(set(cols.parent[idx].tolist())):  # not np.unique: it imports numpy.ma
            grp = idx[cols.parent[idx] == p]
            split = _split_off_span(cols, grp, basis, tol[bb])
            if split is None:
                continue
            touched[grp] = True
            hn, hpn, hp_pure = split
            new_two += [(hn[j], bb, int(p), hpn[j]) for j in range(len(hn))]
            p = int(p)
            if p not in pure:
                heapq.heappush(heap, -p)
            pure.setdefault(p, []).extend(hp_pure)
            fresh.discard(p)
    return _reduced_columns(cols, ~pure_mask & ~touched, out_h, out_b, new_two)


def _pure_bases(cols: Columns, pure_mask: np.ndarray, tol: np.ndarray) -> dict[int, list[np.ndarray]]:
    """Body -> orthonormal basis (a list of 10-vectors) of the span of its pure columns.

    For every body with some, at once (batched SVD over padded blocks); ``tol`` per body.
    """
    pk = np.flatnonzero(pure_mask)
    pk = pk[np.argsort(cols.child[pk], kind="stable")]
    pb, pc = np.unique(cols.child[pk], return_counts=True)
    slot = np.arange(len(pk)) - np.repeat(np.r_[0, np.cumsum(pc)[:-1]], pc)
    blocks = np.zeros((len(pb), 10, pc.max()))
    blocks[np.repeat(np.arange(len(pb)), pc), :, slot] = cols.h[pk]
    u, sv, _ = np.linalg.svd(blocks, full_matrices=False)
    return {int(bb): list((u[k][:, sv[k] > tol[bb]]).T) for k, bb in enumerate(pb)}


def _two_block_groups(cols: Columns, pure_mask: np.ndarray) -> tuple[np.ndarray, dict[int, tuple[int, int]]]:
    """The two-block columns sorted by child body, and body -> its ``[start, stop)`` in them."""
    two = np.flatnonzero(~pure_mask & (cols.extra < 0) & ~cols.has_more())
    order = two[np.argsort(cols.child[two], kind="stable")]
    bodies, first = np.unique(cols.child[order], return_index=True)
    span_of = {int(bb): (int(i), int(j)) for bb, i, j in zip(bodies, first, np.r_[first[1:], len(order)])}
    return order, span_of


def _orthonormal(vectors: list[np.ndarray], fresh: bool, tol: float) -> np.ndarray:
    """``(10, r)`` orthonormal basis of the span of ``vectors`` (as is when ``fresh``: already one)."""
    vecs = np.array(vectors).reshape(-1, 10).T
    if fresh:
        return vecs
    u, sv, _ = np.linalg.svd(vecs, full_matrices=False)
    return u[:, sv > tol]


def _split_off_span(cols: Columns, grp: np.ndarray, basis: np.ndarray, tol: float):
    """Rotate the two-block columns ``grp`` (one child, one parent) to split off ``span basis``.

    The rotation is by the right singular vectors of their child parts off ``span basis``: None
    when none of their combinations has its child part in the span, else ``(child parts, parent
    parts)`` of the ``r`` combinations kept as two-block columns, and the parent parts of the
    others (new pure columns of the parent).
    """
    h, hp = cols.h[grp], cols.hp[grp]
    res = h - (h @ basis) @ basis.T
    _, rs, vt = np.linalg.svd(res.T, full_matrices=True)  # vt (k, k)
    r = int(np.sum(rs > tol))
    if r == len(grp):
        return None
    hn, hpn = vt @ h, vt @ hp
    return hn[:r], hpn[:r], hpn[r:]


def _reduced_columns(cols: Columns, keep: np.ndarray, out_h: list[np.ndarray], out_b: list[int],
                     new_two: list[tuple[np.ndarray, int, int, np.ndarray]]) -> Columns:
    """The kept columns, then the pure bases ``out_h`` of bodies ``out_b``, then ``new_two``."""
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
    if cols.more[k] is not None:
        for body, h in zip(*cols.more[k]):
            v[int(body)] = v.get(int(body), 0) + h
    return v


def leading_spans(cols: Columns, n: int,
                  rtol: float | np.ndarray = 1e-10) -> tuple[np.ndarray, np.ndarray, Columns | None]:
    """Per body, the span of the columns' leading parts in an echelon form, and its complement.

    The same elimination as :func:`block_rank` (leaves to root, same thresholds), keeping each
    body's diagonal-block basis: with ``Q[b] = [L_b | U_b]`` and ``l_b`` leading directions, ``B``
    has a column echelon form whose parts on body ``b`` at its highest body span ``L_b``, so
    ``sum(l) = rank(B)`` and the block-diagonal ``U = diag(U_b)`` spans a complement of
    ``span(B)`` in ``R^(10 n)`` (``[B_echelon | U]`` is block triangular with invertible diagonal
    blocks).

    Parameters
    ----------
    cols : Columns
        ``k`` columns in compact form (``paper`` convention, or any per-parameter scaling of it).
    n : int
        Number of moving bodies.
    rtol : float or ndarray, shape ``(n,)``, default 1e-10
        Singular-value threshold, as in :func:`block_rank` (one per body, or one for all).

    Returns
    -------
    Q : ndarray, shape ``(n, 10, 10)``
        Orthonormal per body: the first ``lead[b]`` columns span ``L_b``, the others ``U_b``.
    lead : ndarray of int, shape ``(n,)``
        ``l_b``; ``lead.sum()`` equals ``block_rank(cols, n, rtol)``.
    independent : Columns or None
        When no elimination was needed (every diagonal block of full column rank), a column set
        of the same span with exactly ``rank`` linearly independent columns; else ``None``.
    """
    rtol = per_body(rtol, n)
    cols = _reduce_pure(cols, rtol)
    k = len(cols)
    if k == 0:
        return np.tile(np.eye(10), (n, 1, 1)), np.zeros(n, dtype=int), cols
    order = np.argsort(cols.child, kind="stable")
    child = cols.child[order]
    counts = np.bincount(child, minlength=n)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    slot = np.arange(k) - np.repeat(starts, counts)
    blocks = np.zeros((n, 10, counts.max()))
    blocks[child, :, slot] = cols.h[order]
    scale = np.linalg.norm(blocks, axis=(1, 2))
    q, sv, _ = np.linalg.svd(blocks, full_matrices=True)  # q (n, 10, 10)
    ranks = np.sum(sv > (rtol * np.maximum(scale, 1e-300))[:, None], axis=1)
    if np.all(ranks == counts):
        return q, ranks, cols
    lead = ranks.copy()
    _elimination_rank(cols, n, rtol, ranks, counts, order, starts, spans=(q, lead))
    return q, lead, None


def _elimination_rank(cols: Columns, n: int, rtol: np.ndarray, ranks: np.ndarray, counts: np.ndarray,
                      order: np.ndarray, starts: np.ndarray, spans: tuple | None = None) -> int:
    """Exact rank when some diagonal blocks are rank-deficient.

    Eliminate block by block from the highest body down, visiting only the deficient bodies and
    those that receive vectors.

    Vectors are sparse over bodies; at body b, the parts on block b of every vector whose highest
    block is b are ranked, and combinations vanishing there move down to their next highest
    block. A body with a full-rank diagonal block that receives nothing keeps its batched rank.
    ``spans``: ``(Q (n, 10, 10), lead (n,))`` updated in place for the bodies visited
    (:func:`leading_spans`). ``rtol``: per body.
    """
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
        u, sv, vt = np.linalg.svd(mat, full_matrices=True)
        r = int(np.sum(sv > rtol[b] * scale))
        total += r
        if spans is not None:  # leading_spans: body b's diagonal-block basis and leading count
            spans[0][b], spans[1][b] = u, r
        for c in vt[r:]:
            new: dict[int, np.ndarray] = {}
            for coef, v in zip(c, vecs):
                if coef == 0:
                    continue
                for blk, h in v.items():
                    if blk != b:
                        new[blk] = new.get(blk, 0) + coef * h
            new = {blk: h for blk, h in new.items() if np.linalg.norm(h) > rtol[blk] * scale}
            if new:
                top = max(new)
                pending.setdefault(top, []).append(new)
                if top not in queued:
                    queued.add(top)
                    heapq.heappush(heap, -top)
    return total
