"""A certificate that scales: the regressor's rank on a tree, decided body by body.

For a tree (no loops) whose measured rows include joints' (``rows`` other than ``base``; an
unmeasured joint's diagonal block has no rows and is merged into its parent's, below),
the stacked regressor ``W`` (parameters ``pi / d`` as in :func:`~.certify.certify`) is block
triangular in the body order: joint ``j``'s rows see only the bodies of its subtree, and body
``i``'s columns appear only in the rows of the joints on its path to the root (a floating root's
six base-wrench rows see every body). Row ``k`` at a sample is ``L_k . sum_i X_i pi_i``: the
joint's line against the wrenches ``X_i pi_i`` of the bodies it carries (``X_i (6, 10)``, the
TP regressor's bar lines). The certificate has two parts, neither using DRNG's reasoning:

(a) every DRNG column ``b`` (blocks on two or three bodies) is in the nullspace: the bodies'
    wrenches ``X_i b_i`` are summed up the tree only until they merge, every joint row on the
    way is checked, and above that point every row sees one total wrench, which must vanish
    relative to the size of its terms (else each ancestor's rows are checked);
(b) ``rank(W) >= 10 n - rank(B)``: a block-diagonal complement ``U = diag(U_b)`` of
    ``span(B)`` (:func:`.rank.leading_spans`) has ``W U`` of full column rank. If
    ``W U x = 0``, joint ``j``'s rows involve only ``subtree(j)``, so from the leaves up every
    diagonal block (joint ``j``'s rows x ``W U_j``) of full column rank forces ``x_j = 0``.
    Where one is rank deficient, its null combinations are carried into the parent's block (a
    merged block), and so on; a deficiency left at a root is a null direction of ``W`` outside
    ``span(B)`` (DRNG incomplete, or the samples too few).

(a) gives ``rank(W) <= 10 n - rank(B)``, (b) the reverse, so the nullity is ``rank(B)``. Each
column entering a rank decision is divided by the norm it would have without cancellation
(its magnitude), so a singular value below ``rtol`` is what rounding can produce and one above
it is not: a full-rank block is full rank for the exact ``W`` of these samples, hence for the
regressor. Memory and time are linear in the number of bodies (``S x n x 60`` numbers for the
bodies' wrench maps); no ``(S rows, 10 n)`` matrix is formed.
"""

from __future__ import annotations

import heapq
import time
from dataclasses import dataclass, replace

import numpy as np

from ..display import summary_repr
from ..enums import Status
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..model.scale import decision_scale
from ..numerics import available_bytes as _available_bytes
from ..numerics import row_mask, rows_spec, sample_states
from ..pga import adjoint, commutator, hat, se3_exp, swap
from ..pga.core import screw_exp
from ..regressor.tp import bar_lines
from .columns import Columns
from .drng import DRNGResult
from .rank import leading_spans

#: trees with at least this many bodies are certified by the structured check (``method="auto"``)
STRUCTURED_MIN_BODIES = 40
#: default random states of the structured check: a joint's diagonal block then has ``30 x dofs``
#: rows for at most ten columns, and each DRNG column is checked on 30 generic states
STRUCTURED_SAMPLES = 30
#: numbers per work chunk (bounds the temporaries of the batched products)
CHUNK = 4_000_000


@dataclass(frozen=True, eq=False)
class StructuredCheck:
    """Outcome of :func:`structured_check`: the nullity of a tree's regressor, decided per body.

    Parameters
    ----------
    status : Status
        ``certified`` (both parts hold), ``failed`` (a DRNG column is not in the nullspace) or
        ``undecided`` (a rank deficiency left at a root, or DRNG's rank not reproduced).
    message : str
        What was checked and the margins, or what failed.
    rank_b : int
        ``rank(B)`` of DRNG's columns (echelon form, :func:`.rank.leading_spans`).
    rank_w : int
        The proven lower bound of ``rank(W)``: ``10 n - rank(B) - missing``.
    missing : int
        Directions of the complement left rank deficient at a root (0 when certified).
    blocks : int
        Diagonal blocks after merging (``n`` when none was rank deficient).
    largest : int
        Bodies in the largest merged block (1 when none).
    smallest_sv : float
        Smallest singular value kept over all blocks (columns magnitude-normalised).
    column_residuals : ndarray, shape ``(k,)``
        Per DRNG column (unit norm on ``pi / d``): its worst row group's ``||W b||`` relative to
        the size of its terms.
    worst : float
        ``column_residuals.max()`` (0 without columns).
    samples : int
        Random states used.
    seconds : float
        Wall time of the check.
    independent : Columns or None
        A basis of ``span(B)`` in compact form, SI ``paper`` convention (``rank_b`` linearly
        independent columns), when the echelon form needed no elimination; else ``None``.
    """

    status: Status
    message: str
    rank_b: int
    rank_w: int
    missing: int
    blocks: int
    largest: int
    smallest_sv: float
    column_residuals: np.ndarray
    worst: float
    samples: int
    seconds: float
    independent: Columns | None = None

    __repr__ = summary_repr


def applicable(robot: Robot, rows: str) -> bool:
    """Whether :func:`structured_check` applies: a tree whose joints' rows are measured.

    Parameters
    ----------
    robot : Robot
        The robot.
    rows : str or sequence of str
        The measured generalized forces (``all``, ``joints``, ``base`` or a set of joints,
        :func:`baseparams.numerics.row_mask`).

    Returns
    -------
    bool
        True for a robot without loops or couplings and ``rows`` other than ``base`` (with the
        base wrench alone every body is in one block: the dense check is that). An unmeasured
        joint's block has no rows of its own: it is merged into its parent's, so the check
        holds for any set of measured joints.
    """
    return not robot.has_loops and robot.n > 0 and rows_spec(rows) != "base"


def tree_kinematics(robot: Robot, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray):
    """Poses, twists, accelerations and joint lines of a tree, without the ``(dof, n)`` support.

    The loop of :func:`baseparams.kinematics.tree.forward_kinematics` (product of exponentials,
    world frame), whose state also carries the quadratic support matrix.

    Parameters
    ----------
    robot : Robot
        A tree (``n`` bodies, ``dof`` coordinates; loops ignored).
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Coordinates, velocities, accelerations (a floating root's: twist coordinates,
        quasi-velocities).

    Returns
    -------
    g : ndarray, shape ``(S, n, 4, 4)``
        Body displacements (spatial assignment: identity at q = 0).
    v, a : ndarray, shape ``(S, n, 6)``
        Spatial twists and accelerations, world frame, gravity excluded.
    lines : ndarray, shape ``(S, dof, 6)``
        Current joint lines (a floating root's: the basis ``e_k``).
    """
    s, n = q.shape[0], robot.n
    qi, nd = robot.q_index, robot.ndofs
    g, v, a = np.empty((s, n, 4, 4)), np.empty((s, n, 6)), np.empty((s, n, 6))
    lines = np.empty((s, robot.dof, 6))
    eye, zero6 = np.broadcast_to(np.eye(4), (s, 4, 4)), np.zeros((s, 6))
    for i in range(n):
        p = robot.parent[i]
        h, vh, ah = (eye, zero6, zero6) if p < 0 else (g[:, p], v[:, p], a[:, p])
        sl = slice(qi[i], qi[i] + nd[i])
        if robot.jtype[i] == "F":
            lines[:, sl] = np.eye(6)
            g[:, i], v[:, i], a[:, i] = se3_exp(q[:, sl]), vh + dq[:, sl], ah + ddq[:, sl]
            continue
        for jj in range(sl.start, sl.stop):
            line = adjoint(h, np.broadcast_to(robot.screws[jj], (s, 6)))
            lines[:, jj] = line
            vh = vh + line * dq[:, jj:jj + 1]
            ah = ah + commutator(line, vh) * dq[:, jj:jj + 1] + line * ddq[:, jj:jj + 1]
            h = h @ screw_exp(robot.screws[jj], q[:, jj])
        g[:, i], v[:, i], a[:, i] = h, vh, ah
    return g, v, a, lines


def wrench_maps(robot: Robot, samples: int, seed: int, d10: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each body's wrench map and each joint's line on the random states of the dense check.

    Parameters
    ----------
    robot : Robot
        A tree (``n`` bodies, ``dof`` coordinates).
    samples : int
        Number of random states ``S`` (:func:`baseparams.numerics.sample_states`, seed ``seed``:
        the states the dense check stacks).
    seed : int
        Seed of :func:`numpy.random.default_rng`.
    d10 : ndarray, shape ``(10,)``
        Per-parameter scale (:func:`baseparams.model.scale.decision_scale` of one body): the
        maps act on ``pi / d``.

    Returns
    -------
    X : ndarray, shape ``(n, S, 6, 10)``
        ``X[i, s] @ pi_i`` is body ``i``'s contribution (gravity included) that joint ``k``'s
        line meets: the regressor entry is ``Y[s, k, 10 i:10 i + 10] = lines[k, s] @ X[i, s]``
        for ``k`` on ``i``'s path (``paper`` convention, world frame).
    lines : ndarray, shape ``(dof, S, 6)``
        The joint lines (a floating root's: the basis ``e_k``).
    """
    rng = np.random.default_rng(seed)
    q, dq, ddq = sample_states(robot, samples, rng)
    n = robot.n
    g, v, acc, ln = tree_kinematics(robot, q, dq, ddq)  # one pass: the loop over bodies is the cost
    x = np.empty((n, samples, 6, 10))
    step = max(1, CHUNK // (40 * samples))
    for a in range(0, n, step):
        b = min(a + step, n)
        vh = hat(v[:, a:b])
        pa = (hat(acc[:, a:b]) + vh @ vh) @ g[:, a:b]
        pa[..., :3, 3] -= robot.gravity
        xs = swap(bar_lines(g[:, a:b], pa))  # (S, nb, 10, 6): row entry = line . xs
        x[a:b] = np.transpose(xs, (1, 0, 3, 2)) * d10
    return x, np.ascontiguousarray(np.transpose(ln, (1, 0, 2)))


def _measured_dofs(robot: Robot, rows: str) -> list[np.ndarray]:
    """Per body, its measured coordinates (indices into ``dof``)."""
    mask = row_mask(robot, rows)
    qi, nd = robot.q_index, robot.ndofs
    return [np.arange(qi[i], qi[i] + nd[i])[mask[qi[i]:qi[i] + nd[i]]] for i in range(robot.n)]


def _ratio(num2: np.ndarray, den2: np.ndarray) -> np.ndarray:
    """``sqrt(num2 / den2)``, 0 where both vanish and inf where only the denominator does."""
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.sqrt(num2 / den2)
    return np.where(den2 > 0, r, np.where(num2 > 0, np.inf, 0.0))


def _walk(parts: dict[int, list], par: np.ndarray, lines: np.ndarray, l2: np.ndarray,
          dofs: list[np.ndarray], tol: float) -> float:
    """Worst row residual of one column given as ``body -> [wrench (S, 6), magnitude^2 (S,)]``.

    Bodies are taken highest first (a parent's index is lower than its children's); each one's
    rows see the sum of the wrenches of the column's bodies in its subtree. Once they have all
    merged, a total wrench that vanishes relative to its terms clears every row above.
    """
    worst = 0.0
    while parts:
        x = max(parts)
        w, d2 = parts.pop(x)
        if not parts:
            r = float(_ratio(np.sum(w * w), np.sum(d2)))
            if r <= tol:
                return max(worst, r)
        for m in dofs[x]:
            num = np.sum(np.einsum("sc,sc->s", lines[m], w) ** 2)
            worst = max(worst, float(_ratio(num, np.sum(l2[m] * d2))))
        p = int(par[x])
        if worst > tol:
            return worst
        if p >= 0:
            if p in parts:
                parts[p] = [parts[p][0] + w, parts[p][1] + d2]
            else:
                parts[p] = [w, d2]
    return worst


def _wrenches(x: np.ndarray, bodies: np.ndarray, h: np.ndarray) -> np.ndarray:
    """``X[bodies[k]] @ h[k]`` for every ``k``: ``(k, S, 6)``."""
    return np.einsum("ksce,ke->ksc", x[bodies], h)


def column_residuals(cols: Columns, robot: Robot, x: np.ndarray, lines: np.ndarray,
                     dofs: list[np.ndarray], tol: float) -> np.ndarray:
    """Per column ``b`` (normalised), its worst row group's ``||W b||`` relative to its terms' size.

    Parameters
    ----------
    cols : Columns
        ``k`` columns in compact form, on parameters ``pi / d`` (blocks on ``child``, ``parent``,
        ``extra``).
    robot : Robot
        The tree (its ``parent`` list).
    x : ndarray, shape ``(n, S, 6, 10)``
        Bodies' wrench maps (:func:`wrench_maps`).
    lines : ndarray, shape ``(dof, S, 6)``
        Joint lines (:func:`wrench_maps`).
    dofs : list of ndarray
        Per body, its measured coordinates.
    tol : float
        Residuals above it fail; a column whose total wrench is above it is walked up the tree.

    Returns
    -------
    ndarray, shape ``(k,)``
        For each column and each joint row group (all samples) it reaches: ``||rows @ b||``
        divided by ``sqrt(sum_s |L_k(s)|^2 sum_i |X_i(s)|_F^2 |b_i|^2)`` (the norm without
        cancellation); the worst, or the total wrench's when it clears every row above.
    """
    par = np.asarray(robot.parent, dtype=int)
    norm = np.sqrt(np.sum(cols.h ** 2, 1) + np.sum(cols.hp ** 2 * (cols.parent >= 0)[:, None], 1)
                   + np.sum(cols.he ** 2 * (cols.extra >= 0)[:, None], 1))
    norm = np.where(norm > 0, norm, 1.0)[:, None]
    h, hp, he = cols.h / norm, cols.hp / norm, cols.he / norm
    x2 = np.sum(x * x, axis=(2, 3))  # (n, S)
    l2 = np.sum(lines * lines, axis=2)  # (dof, S)
    out = np.zeros(len(cols))
    common = (cols.extra < 0) & ((cols.parent < 0) | (cols.parent == par[cols.child]))
    walk = ~common
    ptr = np.r_[0, np.cumsum([len(d) for d in dofs])]
    flat = np.concatenate(dofs) if dofs else np.zeros(0, dtype=int)
    idx = np.flatnonzero(common)
    step = max(1, CHUNK // (60 * x.shape[1]))
    for a in range(0, len(idx), step):
        k = idx[a:a + step]
        c, p = cols.child[k], cols.parent[k]
        wc = _wrenches(x, c, h[k])
        cnt = ptr[c + 1] - ptr[c]
        pc = np.repeat(np.arange(len(k)), cnt)
        pd = flat[np.repeat(ptr[c], cnt) + np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)]
        vals = np.einsum("psc,psc->ps", lines[pd], wc[pc])
        num = np.bincount(pc, np.sum(vals ** 2, 1), len(k))
        den = np.bincount(pc, np.sum(l2[pd] * x2[c[pc]], 1), len(k)) * np.sum(h[k] ** 2, 1)
        r_child = _ratio(num, den)
        d2 = x2[c] * np.sum(h[k] ** 2, 1)[:, None]
        hasp = p >= 0
        wc[hasp] += _wrenches(x, p[hasp], hp[k[hasp]])
        d2[hasp] += x2[p[hasp]] * np.sum(hp[k[hasp]] ** 2, 1)[:, None]
        r_tot = _ratio(np.sum(wc ** 2, axis=(1, 2)), np.sum(d2, 1))
        out[k] = np.maximum(r_child, r_tot)
        walk[k[r_tot > tol]] = True
    for j in np.flatnonzero(walk):
        parts: dict[int, list] = {}
        for body, blk in ((cols.child[j], h[j]), (cols.parent[j], hp[j]), (cols.extra[j], he[j])):
            if body >= 0:
                w, d2 = x[body] @ blk, x2[body] * float(blk @ blk)
                parts[int(body)] = [parts[int(body)][0] + w, parts[int(body)][1] + d2] if body in parts else [w, d2]
        out[j] = _walk(parts, par, lines, l2, dofs, tol)
    return out


def diagonal_blocks(q: np.ndarray, lead: np.ndarray, x: np.ndarray, lines: np.ndarray,
                    dofs: list[np.ndarray], rtol: float) -> tuple[np.ndarray, float]:
    """Which diagonal blocks ``rows_j x (W U_j)`` lack full column rank, all bodies batched.

    Parameters
    ----------
    q : ndarray, shape ``(n, 10, 10)``
        Per body ``[L_j | U_j]`` (:func:`.rank.leading_spans`).
    lead : ndarray of int, shape ``(n,)``
        Leading directions per body: ``U_j = q[j][:, lead[j]:]``.
    x : ndarray, shape ``(n, S, 6, 10)``
        Bodies' wrench maps (:func:`wrench_maps`).
    lines : ndarray, shape ``(dof, S, 6)``
        Joint lines.
    dofs : list of ndarray
        Per body, its measured coordinates.
    rtol : float
        Singular values of the magnitude-normalised block at most this are null.

    Returns
    -------
    deficient : ndarray of int
        Bodies whose block is rank deficient (or has fewer rows than columns).
    smallest : float
        Smallest singular value of the full-rank blocks (inf when none has columns).
    """
    n, s = x.shape[:2]
    m = np.array([len(d) for d in dofs])
    x2 = np.sum(x * x, axis=(2, 3))
    l2 = np.sum(lines * lines, axis=2)
    bad, smallest = [], np.inf
    for mj in np.unique(m):
        group = np.flatnonzero(m == mj)
        step = max(1, CHUNK // (max(mj, 1) * s * 20))
        for a in range(0, len(group), step):
            bodies = group[a:a + step]
            if mj == 0:
                bad += [int(b) for b in bodies if lead[b] < 10]
                continue
            li = np.array([dofs[b] for b in bodies])  # (nb, mj)
            blk = np.einsum("bmsc,bsce->bmse", lines[li], x[bodies]).reshape(len(bodies), mj * s, 10)
            mag = np.sqrt(np.einsum("bms,bs->b", l2[li], x2[bodies]))
            blk = (blk @ q[bodies]) / np.where(mag > 0, mag, 1.0)[:, None, None]
            for lj in np.unique(lead[bodies]):
                sub = np.flatnonzero(lead[bodies] == lj)
                if lj == 10:
                    continue
                if mj * s < 10 - lj:
                    bad += bodies[sub].tolist()
                    continue
                sv = np.linalg.svd(blk[sub][:, :, lj:], compute_uv=False)[:, -1]
                ok = (sv > rtol) & (mag[sub] > 0)
                bad += bodies[sub][~ok].tolist()
                if ok.any():
                    smallest = min(smallest, float(sv[ok].min()))
    return np.array(sorted(bad), dtype=int), smallest


def merge_blocks(deficient: np.ndarray, par: np.ndarray, q: np.ndarray, lead: np.ndarray, x: np.ndarray,
                 lines: np.ndarray, dofs: list[np.ndarray], rtol: float) -> tuple[int, dict[int, int], float]:
    """Carry the rank-deficient blocks' null combinations into their parents' blocks, leaves first.

    Parameters
    ----------
    deficient : ndarray of int
        Bodies whose diagonal block lacks full column rank (:func:`diagonal_blocks`).
    par : ndarray of int, shape ``(n,)``
        Parent of each body (``-1``: a root).
    q, lead, x, lines, dofs, rtol
        As for :func:`diagonal_blocks`.

    Returns
    -------
    missing : int
        Null combinations left at roots: directions of the complement ``U`` that ``W`` does not
        see on these samples.
    merged : dict of int to int
        Body -> the body whose block absorbed it (for every body that passed combinations up).
    smallest : float
        Smallest singular value kept in the merged blocks (inf when none).
    """
    x2 = np.sum(x * x, axis=(2, 3))
    l2 = np.sum(lines * lines, axis=2)
    pending: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}
    heap = [-int(b) for b in deficient]
    heapq.heapify(heap)
    queued = set(int(b) for b in deficient)
    missing, merged, smallest = 0, {}, np.inf
    while heap:
        b = -heapq.heappop(heap)
        u = q[b][:, lead[b]:]
        own = np.moveaxis(x[b] @ u, -1, 0)  # (c, S, 6)
        wr = np.concatenate([own] + [w[None] for w, _ in pending.get(b, [])])
        mg = np.concatenate([np.broadcast_to(np.sqrt(x2[b]), (len(own), x2.shape[1]))]
                            + [g[None] for _, g in pending.pop(b, [])])
        li = dofs[b]
        mat = np.einsum("msc,ksc->msk", lines[li], wr).reshape(-1, len(wr))
        mag = np.sqrt(np.einsum("ms,ks->k", l2[li], mg ** 2))
        mag = np.where(mag > 0, mag, 1.0)
        if mat.shape[0]:
            _, sv, vt = np.linalg.svd(mat / mag, full_matrices=mat.shape[0] < mat.shape[1])
            r = int(np.sum(sv > rtol))
            if r:
                smallest = min(smallest, float(sv[r - 1]))
        else:
            r, vt = 0, np.eye(len(wr))
        coef = vt[r:] / mag  # null combinations, on the columns as they are
        if not len(coef):
            continue
        p = int(par[b])
        if p < 0:
            missing += len(coef)
            continue
        merged[b] = p
        new_w = np.einsum("nk,ksc->nsc", coef, wr)
        new_g = np.abs(coef) @ mg
        pending.setdefault(p, []).extend(zip(new_w, new_g))
        if p not in queued:
            queued.add(p)
            heapq.heappush(heap, -p)
    return missing, merged, smallest


def _largest_group(merged: dict[int, int], n: int) -> tuple[int, int]:
    """``(number of blocks, bodies in the largest)`` after the merges (each body joins its absorber)."""
    root = {}

    def find(b: int) -> int:
        while b in merged:
            b = merged[b]
        return b

    for b in merged:
        r = find(b)
        root[r] = root.get(r, 1) + 1
    return n - len(merged), max(root.values(), default=1)


def structured_check(robot: Robot, result: DRNGResult, samples: int | None = None, seed: int = 0,
                     rows: str = "all", rtol: float = 1e-9, residual_tol: float = 1e-8) -> StructuredCheck:
    """Certify DRNG's nullspace of a tree body by body (module doc): (a) columns, (b) ranks.

    Parameters
    ----------
    robot : Robot
        A tree (:func:`applicable`), ``n`` bodies.
    result : DRNGResult
        DRNG's columns for ``rows``.
    samples : int, optional
        Random states (default :data:`STRUCTURED_SAMPLES`).
    seed : int, default 0
        Seed of the states (the same states as the dense check's first set).
    rows : str, default "all"
        The measured generalized forces (any but ``base``, :func:`applicable`).
    rtol : float, default 1e-9
        Singular values of magnitude-normalised blocks at most this are null.
    residual_tol : float, default 1e-8
        Largest relative residual of a DRNG column (:func:`column_residuals`).

    Returns
    -------
    StructuredCheck
        ``certified`` with ``rank_b`` the nullity; ``failed`` when a column is not in the
        nullspace; ``undecided`` when a deficiency is left at a root or the echelon form does not
        reproduce DRNG's rank (the dense check then decides, and completes).

    Raises
    ------
    BaseparamsError
        The check does not apply (loops, or the base wrench alone measured).
    """
    t0 = time.perf_counter()
    if not applicable(robot, rows):
        raise BaseparamsError(f"robot {robot.name!r}: the structured certificate needs a tree whose joint rows are "
                              f"measured (rows other than 'base'), got rows {rows!r}"
                              f"{' and loops' if robot.has_loops else ''}")
    samples = STRUCTURED_SAMPLES if samples is None else samples
    n, d10 = robot.n, decision_scale(robot, "paper")[:10]
    cols = result.columns
    raw = replace(cols, h=cols.h / d10, hp=cols.hp / d10, he=cols.he / d10)
    x, lines = wrench_maps(robot, samples, seed, d10)
    dofs = _measured_dofs(robot, rows)
    res = column_residuals(raw, robot, x, lines, dofs, residual_tol) if len(cols) else np.zeros(0)
    worst = float(res.max()) if len(res) else 0.0
    q, lead, indep = leading_spans(raw, n)
    rank_b = int(lead.sum())
    if indep is not None:
        indep = replace(indep, h=indep.h * d10, hp=indep.hp * d10, he=indep.he * d10)
    par = np.asarray(robot.parent, dtype=int)
    bad, small = diagonal_blocks(q, lead, x, lines, dofs, rtol)
    missing, merged, small2 = merge_blocks(bad, par, q, lead, x, lines, dofs, rtol)
    nblocks, largest = _largest_group(merged, n)
    out = dict(rank_b=rank_b, rank_w=10 * n - rank_b - missing, missing=missing, blocks=nblocks, largest=largest,
               smallest_sv=min(small, small2), column_residuals=res, worst=worst, samples=samples, independent=indep)
    status, message = _structured_verdict(result, out, rtol, residual_tol)
    return StructuredCheck(status, message, seconds=time.perf_counter() - t0, **out)


def _structured_verdict(result: DRNGResult, out: dict, rtol: float, residual_tol: float) -> tuple[Status, str]:
    """``(status, message)`` of :func:`structured_check` from its figures ``out``."""
    ncols = 10 * result.robot.n
    res, worst = out["column_residuals"], out["worst"]
    how = (f"structured certificate: {out['blocks']} diagonal blocks (largest {out['largest']} bodies), smallest "
           f"normalised singular value {out['smallest_sv']:.3g} (rtol {rtol:g}), worst column residual {worst:.2e} "
           f"(tolerance {residual_tol:g}), {out['samples']} samples")
    if worst > residual_tol:
        bad = np.argsort(res)[::-1][: int(np.sum(res > residual_tol))]
        where = "; ".join(result.provenance(int(k)) for k in bad[:3])
        return Status.FAILED, (f"{len(bad)} DRNG column(s) are not in the nullspace (worst relative residual "
                               f"{worst:.2e}): {where}")
    if out["rank_b"] != result.rank:
        return Status.UNDECIDED, (f"the echelon form gives rank(B) {out['rank_b']}, DRNG's rank is {result.rank}; "
                                  f"{how}")
    if out["missing"]:
        return Status.UNDECIDED, (f"{out['missing']} direction(s) outside DRNG's span are not seen by the joint "
                                  f"rows of their subtree (DRNG may be incomplete); {how}")
    return Status.CERTIFIED, (f"DRNG is complete: rank(B) {out['rank_b']} + rank(W) {out['rank_w']} = {ncols} "
                              f"(rank(W) bounded below block by block); {how}")


def independent_columns(robot: Robot, result: DRNGResult) -> Columns | None:
    """A basis of DRNG's span in compact form (SI ``paper`` convention), without numerics.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    result : DRNGResult
        DRNG's columns.

    Returns
    -------
    Columns or None
        ``result.rank`` linearly independent columns spanning the same space, each independent
        on its highest body (:func:`.rank.leading_spans` on ``pi / d``): what
        :func:`baseparams.base.sparse.tree_base_parameters` regroups; ``None`` when the echelon
        form needed eliminations or does not reproduce DRNG's rank.
    """
    d10 = decision_scale(robot, "paper")[:10]
    cols = result.columns
    _, lead, indep = leading_spans(replace(cols, h=cols.h / d10, hp=cols.hp / d10, he=cols.he / d10), robot.n)
    if indep is None or int(lead.sum()) != result.rank:
        return None
    return replace(indep, h=indep.h * d10, hp=indep.hp * d10, he=indep.he * d10)


def dense_bytes(robot: Robot, samples: int, rows: str = "all") -> float:
    """Memory the dense check needs: the stacked regressor and the square factors [bytes].

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies, ``dof`` coordinates).
    samples : int
        Random states of the check.
    rows : str, default "all"
        The measured generalized forces.

    Returns
    -------
    float
        ``8 (2 S rows (10 n) + 6 (10 n)^2)``: the stacked regressor (twice for the saturation
        check) and the square factors of the SVD and the completion.
    """
    n10 = 10 * robot.n
    return 8.0 * (2 * samples * int(row_mask(robot, rows).sum()) * n10 + 6 * n10 ** 2)


def dense_fits(robot: Robot, samples: int, rows: str = "all") -> bool:
    """Whether the dense check fits in the memory available (:func:`dense_bytes` vs Linux's ``MemAvailable``).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies, ``dof`` coordinates).
    samples : int
        Random states of the check.
    rows : str, default "all"
        The measured generalized forces.

    Returns
    -------
    bool
        True when it fits, or when the memory available is unknown.
    """
    have = _available_bytes()
    return have is None or dense_bytes(robot, samples, rows) <= have
