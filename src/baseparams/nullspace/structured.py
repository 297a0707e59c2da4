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
    ``span(B)`` (:func:`.rank.leading_spans` in decision coordinates, each body's parameters
    about its own origin: :func:`~.result.decision_columns`; the wrench maps taken to the same
    coordinates) has ``W U`` of full column rank. If
    ``W U x = 0``, joint ``j``'s rows involve only ``subtree(j)``, so from the leaves up every
    diagonal block (joint ``j``'s rows x ``W U_j``) of full column rank forces ``x_j = 0``.
    Where one is rank deficient, its null combinations are carried into the parent's block (a
    merged block), and so on; a deficiency left at a root is a null direction of ``W`` outside
    ``span(B)`` (DRNG incomplete, or the samples too few).

(a) gives ``rank(W) <= 10 n - rank(B)``, (b) the reverse, so the nullity is ``rank(B)``. Each
column entering a rank decision is divided by the norm it would have without cancellation
(its magnitude), so a singular value below ``rtol`` is what rounding can produce and one above
it is not: a full-rank block is full rank for the exact ``W`` of these samples, hence for the
regressor. Memory is linear in the number of bodies (``S x n x 60`` numbers for the bodies'
wrench maps); no ``(S rows, 10 n)`` matrix is formed. So is time, but for (a)'s columns whose
total wrench no row sees (a slide chain's first moments: a pure moment): each is checked on
every row to the root, its depth in rows, read as a few contiguous slices (``_climb``).

Coupled coordinates (URDF ``<mimic>``, linear couplings without loop joints): the states are
drawn in the actuated coordinates (:func:`baseparams.numerics.closed_samples`, as the dense
check) and an actuated coordinate moving several tree coordinates ``k`` (``dq_k = G[k, a]
dq_a``) has one row ``sum_k G[k, a] L_k . sum_{i in subtree(k)} X_i pi_i`` (a *coupled row*),
which sees the union of its coordinates' subtrees. (a) checks coupled rows directly; in (b) a
coupled row enters the block of its *anchor*, the lowest common ancestor of its coordinates'
bodies, where every column of that union is present, and each column carries the row's value
accumulated over the coupled coordinates it has passed (a column at body ``b`` lives in
``subtree(b)``, so ``b``'s coordinates see all of it). A coupled coordinate has no row of its
own: its body's directions are carried up to the anchor.
"""

from __future__ import annotations

import heapq
import time
from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..enums import Status
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..model.scale import decision_frames, decision_scale
from ..numerics import STRUCTURED_MIN_BODIES as STRUCTURED_MIN_BODIES  # re-exported: where the path is described
from ..numerics import available_bytes as _available_bytes
from ..numerics import closed_samples, row_mask, rows_spec, sample_states
from ..pga import adjoint, commutator, hat, se3_exp, swap
from ..regressor.tp import bar_lines
from .columns import Columns
from .rank import leading_spans
from .result import DRNGResult, decision_columns

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
    sampling : dict or None
        What the sampling did (``requested``, ``kept``; with couplings also ``cond_max``,
        ``not_converged``, ``branch_jumps``, ``ill_conditioned``, ``max_loop_residual``).
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
    sampling: dict | None = None

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
        True for a robot without loop joints and ``rows`` other than ``base`` (with the base
        wrench alone every body is in one block: the dense check is that); with couplings
        (``<mimic>``) ``rows`` ``all`` only, the actuated generalized forces. An unmeasured
        joint's block has no rows of its own: it is merged into its parent's, so the check holds
        for any set of measured joints.
    """
    if robot.loops or robot.n == 0:
        return False
    spec = rows_spec(rows)
    return spec == "all" if robot.couplings else spec != "base"


def sampled_states(robot: Robot, samples: int, seed: int):
    """The random states of the dense check's first set: tree states, or coupled ones.

    Parameters
    ----------
    robot : Robot
        A tree, possibly with couplings (no loop joints).
    samples : int
        Number of random states (actuated samples with couplings).
    seed : int
        Seed of :func:`numpy.random.default_rng`.

    Returns
    -------
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Tree coordinates, velocities and accelerations (``S`` kept samples).
    G : ndarray, shape ``(S, dof, na)``, or None
        ``dq / dq_a`` with couplings, else None.
    info : dict
        ``requested``, ``kept`` and with couplings the loop sampling counts.

    Raises
    ------
    BaseparamsError
        No sample satisfies the couplings.
    """
    rng = np.random.default_rng(seed)
    if not robot.couplings:
        q, dq, ddq = sample_states(robot, samples, rng)
        return q, dq, ddq, None, {"requested": samples, "kept": samples}
    cs = closed_samples(robot, samples, rng)
    if cs.kept == 0:
        raise BaseparamsError(f"robot {robot.name!r}: none of {samples} samples satisfied the couplings")
    info = dict(requested=cs.requested, kept=cs.kept, cond_max=cs.cond_max, not_converged=cs.not_converged,
                branch_jumps=cs.branch_jumps, ill_conditioned=cs.ill_conditioned, max_loop_residual=cs.max_residual)
    return cs.q, cs.dq, cs.ddq, cs.G, info


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
    n, qi, nd, sc = robot.n, robot.q_index, robot.ndofs, robot.screws
    floating = [i for i in range(n) if robot.jtype[i] == "F"]
    # the loops over bodies carry only what depends on the parent; the rest is batched over coordinates
    exps = se3_exp(sc[None] * q[..., None])  # (S, dof, 4, 4): each coordinate's displacement
    g, before = _poses(robot, q, exps, floating)
    lines = adjoint(before, np.broadcast_to(sc, before.shape[:2] + (6,)))
    for i in floating:
        lines[:, qi[i]:qi[i] + nd[i]] = np.eye(6)
    v, after = _accumulate(robot, lines * dq[..., None], dq, floating, running=True)
    push = commutator(lines, after) * dq[..., None] + lines * ddq[..., None]  # (S, dof, 6)
    a, _ = _accumulate(robot, push, ddq, floating, running=False)
    return g, v, a, lines


def _poses(robot: Robot, q: np.ndarray, exps: np.ndarray, floating: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Body poses ``(S, n, 4, 4)`` and each coordinate's pose before its own displacement ``(S, dof, 4, 4)``."""
    s, n = q.shape[0], robot.n
    qi, nd = robot.q_index, robot.ndofs
    g, before = np.empty((s, n, 4, 4)), np.empty((s, robot.dof, 4, 4))
    eye = np.broadcast_to(np.eye(4), (s, 4, 4))
    free = set(floating)
    for i in range(n):
        p = robot.parent[i]
        h = eye if p < 0 else g[:, p]
        if i in free:
            g[:, i] = se3_exp(q[:, qi[i]:qi[i] + nd[i]])
            continue
        for jj in range(qi[i], qi[i] + nd[i]):
            before[:, jj] = h
            h = h @ exps[:, jj]
        g[:, i] = h
    return g, before


def _accumulate(robot: Robot, terms: np.ndarray, free_terms: np.ndarray, floating: list[int],
                running: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """Per body, its parent's value plus its coordinates' ``terms (S, dof, 6)`` (a floating root: ``free_terms``).

    ``running``: also each coordinate's value once its own term is added ``(S, dof, 6)``.
    """
    s, n = terms.shape[0], robot.n
    qi, nd = robot.q_index, robot.ndofs
    out = np.empty((s, n, 6))
    after = np.empty_like(terms) if running else None
    zero = np.zeros((s, 6))
    free = set(floating)
    for i in range(n):
        p = robot.parent[i]
        h = zero if p < 0 else out[:, p]
        if i in free:
            out[:, i] = h + free_terms[:, qi[i]:qi[i] + nd[i]]
            continue
        for jj in range(qi[i], qi[i] + nd[i]):
            h = h + terms[:, jj]
            if running:
                after[:, jj] = h
        out[:, i] = h
    return out, after


def wrench_maps(robot: Robot, samples: int, seed: int, d10: np.ndarray,
                states: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
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
    states : tuple of ndarray, optional
        ``(q, dq, ddq)`` to use instead of drawing them (e.g. coupled states,
        :func:`sampled_states`); ``samples`` and ``seed`` are then unused.

    Returns
    -------
    X : ndarray, shape ``(n, S, 6, 10)``
        ``X[i, s] @ pi_i`` is body ``i``'s contribution (gravity included) that joint ``k``'s
        line meets: the regressor entry is ``Y[s, k, 10 i:10 i + 10] = lines[k, s] @ X[i, s]``
        for ``k`` on ``i``'s path (``paper`` convention, world frame).
    lines : ndarray, shape ``(dof, S, 6)``
        The joint lines (a floating root's: the basis ``e_k``).
    """
    q, dq, ddq = sample_states(robot, samples, np.random.default_rng(seed)) if states is None else states
    samples, n = q.shape[0], robot.n
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


@dataclass(frozen=True, eq=False)
class CoupledRow:
    """The row of an actuated coordinate that moves several tree coordinates (a coupling).

    Parameters
    ----------
    coords : ndarray of int, shape ``(m,)``
        The tree coordinates it moves.
    coef : ndarray, shape ``(S, m)``
        ``G[s, coords, a]``: ``dq_k = coef dq_a``.
    bodies : ndarray of int, shape ``(m,)``
        The body of each coordinate.
    anchor : int
        Lowest common ancestor of ``bodies`` (-1: none, the row is not used for ranks).
    """

    coords: np.ndarray
    coef: np.ndarray
    bodies: np.ndarray
    anchor: int

    __repr__ = summary_repr


def row_groups(robot: Robot, rows: str, big_g: np.ndarray | None) -> tuple[list[np.ndarray], list[CoupledRow]]:
    """Per body its plain rows (tree coordinates measured alone), and the coupled rows.

    Parameters
    ----------
    robot : Robot
        The tree (``dof`` coordinates, ``n`` bodies).
    rows : str
        The measured generalized forces.
    big_g : ndarray, shape ``(S, dof, na)``, or None
        ``dq / dq_a`` with couplings (:func:`sampled_states`), else None.

    Returns
    -------
    dofs : list of ndarray
        Per body, the coordinates whose row is an actuated coordinate's alone (``G`` column
        ``e_k``).
    coupled : list of CoupledRow
        The other actuated coordinates' rows.
    """
    if big_g is None:
        return _measured_dofs(robot, rows), []
    moves = np.any(big_g != 0, axis=0)  # (dof, na)
    plain = np.zeros(robot.dof, dtype=bool)
    coupled = []
    for a in range(big_g.shape[2]):
        ks = np.flatnonzero(moves[:, a])
        if len(ks) == 1 and np.all(big_g[:, ks[0], a] == 1.0):
            plain[ks[0]] = True
        elif len(ks):
            bodies = robot.dof_body[ks]
            coupled.append(CoupledRow(ks, big_g[:, ks, a], bodies, _common_ancestor(robot.parent, bodies)))
    qi, nd = robot.q_index, robot.ndofs
    return [np.arange(qi[i], qi[i] + nd[i])[plain[qi[i]:qi[i] + nd[i]]] for i in range(robot.n)], coupled


def _common_ancestor(parent, bodies: np.ndarray) -> int:
    """Lowest common ancestor (or self) of ``bodies`` (-1 when they are under different roots)."""
    chains = []
    for b in bodies:
        chain = []
        while b >= 0:
            chain.append(int(b))
            b = parent[b]
        chains.append(chain[::-1])
    k = 0
    while all(len(c) > k for c in chains) and len({c[k] for c in chains}) == 1:
        k += 1
    return chains[0][k - 1] if k else -1


def _subtree_intervals(parent) -> tuple[np.ndarray, np.ndarray]:
    """``tin, tout``: body ``i`` is in ``subtree(b)`` iff ``tin[b] <= tin[i] < tout[b]`` (preorder)."""
    n = len(parent)
    children: list[list[int]] = [[] for _ in range(n)]
    roots = []
    for i, p in enumerate(parent):
        (children[p] if p >= 0 else roots).append(i)
    tin, tout = np.zeros(n, dtype=int), np.zeros(n, dtype=int)
    clock, stack = 0, [(r, False) for r in reversed(roots)]
    while stack:
        b, done = stack.pop()
        if done:
            tout[b] = clock
            continue
        tin[b] = clock
        clock += 1
        stack.append((b, True))
        stack.extend((c, False) for c in reversed(children[b]))
    return tin, tout


def _ratio(num2: np.ndarray, den2: np.ndarray) -> np.ndarray:
    """``sqrt(num2 / den2)``, 0 where both vanish and inf where only the denominator does."""
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.sqrt(num2 / den2)
    return np.where(den2 > 0, r, np.where(num2 > 0, np.inf, 0.0))


def _walk(parts: dict[int, list], par: np.ndarray, lines: np.ndarray, l2: np.ndarray,
          dofs: list[np.ndarray], tol: float, climbs: list) -> float:
    """Worst row residual of one column given as ``body -> [wrench (S, 6), magnitude^2 (S,)]``.

    Bodies are taken highest first (a parent's index is lower than its children's); each one's
    rows see the sum of the wrenches of the column's bodies in its subtree. Once they have all
    merged, a total wrench that vanishes relative to its terms clears every row above; one that
    does not is left to be checked on every row up to the root: ``(wrench, magnitude^2, body,
    worst so far)`` appended to ``climbs`` (:func:`_climbs`), the worst so far returned.
    """
    worst = 0.0
    while parts:
        x = max(parts)
        w, d2 = parts.pop(x)
        if not parts:
            r = float(_ratio(np.sum(w * w), np.sum(d2)))
            if r <= tol:
                return max(worst, r)
            climbs.append((w, d2, x, worst))
            return worst
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


def _root_runs(par: np.ndarray, dofs: list[np.ndarray], lines: np.ndarray, l2: np.ndarray) -> tuple:
    """The tree's root paths as few runs of consecutive positions, with the rows in that order.

    Bodies are ordered depth first, each body's largest child right after it (a heavy path), so
    the path from any body to the root crosses ``O(log n)`` runs, each a slice of the reordered
    rows: the climb of :func:`_climb` reads them without gathering.

    Parameters
    ----------
    par : ndarray of int, shape ``(n,)``
        Parent of each body (-1: a root).
    dofs : list of ndarray
        Per body, its measured coordinates.
    lines : ndarray, shape ``(dof, S, 6)``
        Joint lines.
    l2 : ndarray, shape ``(dof, S)``
        Their squared norms.

    Returns
    -------
    tuple
        ``(par, head, pos, order, ptr, owner, lines_o, l2_o)``: body ``b`` at position ``pos[b]``
        of ``order``, its run starting at body ``head[b]``; position ``p``'s rows are
        ``lines_o[ptr[p]:ptr[p + 1]]``, row ``r``'s position ``owner[r]``.
    """
    n = len(par)
    children: list[list[int]] = [[] for _ in range(n)]
    for i, p in enumerate(par):
        if p >= 0:
            children[p].append(i)
    size = np.ones(n, dtype=int)
    for i in range(n - 1, -1, -1):  # a parent's index is lower than its children's
        if par[i] >= 0:
            size[par[i]] += size[i]
    head, order = np.arange(n), []
    stack = [int(r) for r in np.flatnonzero(par < 0)[::-1]]
    while stack:
        b = stack.pop()
        order.append(b)
        kids = sorted(children[b], key=lambda c: size[c])  # the largest last: popped next
        if kids:
            head[kids[-1]] = head[b]
        stack.extend(kids)
    order = np.asarray(order, dtype=int)
    pos = np.empty(n, dtype=int)
    pos[order] = np.arange(n)
    counts = np.array([len(dofs[b]) for b in order], dtype=int)
    ptr = np.r_[0, np.cumsum(counts)]
    flat = np.concatenate([dofs[b] for b in order]).astype(int) if n else np.zeros(0, dtype=int)
    owner = np.repeat(np.arange(n), counts)
    return par, head, pos, order, ptr, owner, lines[flat], l2[flat]


def _climbs(climbs: list, tol: float, runs: tuple) -> np.ndarray:
    """The climbs :func:`_walk` left, those from one body together (:func:`_climb`): each one's worst residual."""
    out = np.zeros(len(climbs))
    start = np.array([c[2] for c in climbs], dtype=int)
    for x in np.unique(start):
        k = np.flatnonzero(start == x)
        w = np.stack([climbs[i][0] for i in k])
        d2 = np.stack([climbs[i][1] for i in k])
        out[k] = _climb(w, d2, int(x), np.array([climbs[i][3] for i in k], dtype=float), tol, runs)
    return out


def _climb(w: np.ndarray, d2: np.ndarray, x: int, worst: np.ndarray, tol: float, runs: tuple) -> np.ndarray:
    """:func:`_walk` from body ``x`` to the root for ``J`` total wrenches: the same residuals, run by run.

    ``w (J, S, 6)``, ``d2 (J, S)``: wrenches and magnitudes^2; ``worst (J,)``: each walk's so
    far (at most ``tol``); ``runs`` from :func:`_root_runs`. Each run's rows are checked in
    slices of doubling length (a column that fails near ``x`` costs little), all rows of a slice
    and all columns at once; the result is the one of the row-by-row walk: the worst residual up
    to the first body whose rows exceed ``tol`` (all of them if none).
    """
    par, head, pos, order, ptr, owner, lines, l2 = runs
    worst, live = worst.copy(), np.arange(len(w))
    while x >= 0 and len(live):
        lo, hi, step = pos[head[x]], pos[x], 8
        while hi >= lo and len(live):
            a = max(lo, hi - step + 1)
            r0, r1 = ptr[a], ptr[hi + 1]
            if r1 > r0:
                num = np.sum(np.einsum("msc,jsc->jms", lines[r0:r1], w[live]) ** 2, axis=2)
                r = _ratio(num, np.sum(l2[r0:r1] * d2[live][:, None, :], axis=2))  # (live, rows)
                r[np.isnan(r)] = 0.0  # as max(worst, nan) in the row-by-row walk
                over = r > tol
                hit = over.any(axis=1)
                last = r1 - r0 - 1 - np.argmax(over[:, ::-1], axis=1)  # the first body met going up: highest
                upto = owner[r0:r1][None, :] >= np.where(hit, owner[r0 + last], -1)[:, None]
                worst[live] = np.maximum(worst[live], np.max(np.where(upto, r, 0.0), axis=1))
                live = live[~hit]
            hi, step = a - 1, step * 2
        x = int(par[order[lo]])
    return worst


def _wrenches(x: np.ndarray, bodies: np.ndarray, h: np.ndarray) -> np.ndarray:
    """``X[bodies[k]] @ h[k]`` for every ``k``: ``(k, S, 6)``."""
    return np.einsum("ksce,ke->ksc", x[bodies], h)


def column_residuals(cols: Columns, robot: Robot, x: np.ndarray, lines: np.ndarray,
                     dofs: list[np.ndarray], tol: float, coupled: list[CoupledRow] | tuple = ()) -> np.ndarray:
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
    coupled : list of CoupledRow, optional
        Coupled rows (:func:`row_groups`), each checked on every column.

    Returns
    -------
    ndarray, shape ``(k,)``
        For each column and each joint row group (all samples) it reaches: ``||rows @ b||``
        divided by ``sqrt(sum_s |L_k(s)|^2 sum_i |X_i(s)|_F^2 |b_i|^2)`` (the norm without
        cancellation); the worst, or the total wrench's when it clears every row above.
    """
    par = np.asarray(robot.parent, dtype=int)
    norm2 = (np.sum(cols.h ** 2, 1) + np.sum(cols.hp ** 2 * (cols.parent >= 0)[:, None], 1)
             + np.sum(cols.he ** 2 * (cols.extra >= 0)[:, None], 1))
    more = cols.has_more()
    for j in np.flatnonzero(more):
        norm2[j] += float(np.sum(np.asarray(cols.more[j][1], dtype=float) ** 2))
    flat_norm = np.where(norm2 > 0, np.sqrt(norm2), 1.0)
    norm = flat_norm[:, None]
    h, hp, he = cols.h / norm, cols.hp / norm, cols.he / norm
    x2 = np.sum(x * x, axis=(2, 3))  # (n, S)
    l2 = np.sum(lines * lines, axis=2)  # (dof, S)
    out = np.zeros(len(cols))
    common = (cols.extra < 0) & ~more & ((cols.parent < 0) | (cols.parent == par[cols.child]))
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
    climbs: list = []
    climbers = []
    for j in np.flatnonzero(walk):
        parts: dict[int, list] = {}
        extra_blocks = zip(cols.more[j][0], np.asarray(cols.more[j][1], dtype=float) / flat_norm[j]) if more[j] else ()
        for body, blk in ((cols.child[j], h[j]), (cols.parent[j], hp[j]), (cols.extra[j], he[j]), *extra_blocks):
            if body >= 0:
                w, d2 = x[body] @ blk, x2[body] * float(blk @ blk)
                parts[int(body)] = [parts[int(body)][0] + w, parts[int(body)][1] + d2] if body in parts else [w, d2]
        before = len(climbs)
        out[j] = _walk(parts, par, lines, l2, dofs, tol, climbs)
        climbers.extend([j] * (len(climbs) - before))
    if climbs:
        out[climbers] = _climbs(climbs, tol, _root_runs(par, dofs, lines, l2))
    if coupled:
        out = np.maximum(out, _coupled_residuals(cols, flat_norm, x, x2, lines, l2, coupled, par))
    return out


def _blocks(cols: Columns, norm: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every block of every column: ``(column, body, block / norm[column])``, ``more`` included."""
    idx, bodies, blocks = [np.arange(len(cols))], [cols.child], [cols.h]
    for body, hh in ((cols.parent, cols.hp), (cols.extra, cols.he)):
        ok = np.flatnonzero(body >= 0)
        idx.append(ok)
        bodies.append(body[ok])
        blocks.append(hh[ok])
    for j in np.flatnonzero(cols.has_more()):
        mb, mh = cols.more[j]
        idx.append(np.full(len(mb), j))
        bodies.append(np.asarray(mb, dtype=int))
        blocks.append(np.asarray(mh, dtype=float).reshape(-1, 10))
    idx = np.concatenate(idx)
    return idx, np.concatenate(bodies), np.concatenate(blocks) / norm[idx][:, None]


def _coupled_residuals(cols: Columns, norm: np.ndarray, x: np.ndarray, x2: np.ndarray, lines: np.ndarray,
                       l2: np.ndarray, coupled: list[CoupledRow], par: np.ndarray) -> np.ndarray:
    """Per column, the worst coupled row's ``||row @ b||`` relative to the size of its terms.

    Coupled coordinate ``k`` sees the column's blocks on bodies of its subtree.
    """
    tin, tout = _subtree_intervals(par)
    idx, bodies, blocks = _blocks(cols, norm)
    w = np.einsum("ksce,ke->ksc", x[bodies], blocks)  # (blocks, S, 6)
    d2 = x2[bodies] * np.sum(blocks ** 2, 1)[:, None]
    tb = tin[bodies]
    k, s = len(cols), x.shape[1]
    out = np.zeros(k)
    for row in coupled:
        val, den = np.zeros((k, s)), np.zeros(k)
        for m, (kk, bk) in enumerate(zip(row.coords, row.bodies)):
            g = row.coef[:, m]
            inside = np.flatnonzero((tb >= tin[bk]) & (tb < tout[bk]))
            if len(inside):
                np.add.at(val, idx[inside], g * np.einsum("sc,ksc->ks", lines[kk], w[inside]))
                np.add.at(den, idx[inside], np.sum(g ** 2 * l2[kk] * d2[inside], 1))
        out = np.maximum(out, _ratio(np.sum(val ** 2, 1), den))
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
    for mj in sorted(set(m.tolist())):  # not np.unique: it imports numpy.ma (start-up time)
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
            for lj in sorted(set(lead[bodies].tolist())):
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
                 lines: np.ndarray, dofs: list[np.ndarray], rtol: float,
                 coupled: list[CoupledRow] | tuple = ()) -> tuple[int, dict[int, int], float]:
    """Carry the rank-deficient blocks' null combinations into their parents' blocks, leaves first.

    Parameters
    ----------
    deficient : ndarray of int
        Bodies whose diagonal block lacks full column rank (:func:`diagonal_blocks`).
    par : ndarray of int, shape ``(n,)``
        Parent of each body (``-1``: a root).
    q, lead, x, lines, dofs, rtol
        As for :func:`diagonal_blocks`.
    coupled : list of CoupledRow, optional
        Coupled rows (:func:`row_groups`): each column carries their values accumulated over
        the coupled coordinates it has passed; a row enters its anchor's block.

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
    at_body: dict[int, list] = {}
    for r, row in enumerate(coupled):
        for m, (kk, bk) in enumerate(zip(row.coords, row.bodies)):
            at_body.setdefault(int(bk), []).append((r, int(kk), row.coef[:, m]))
    pending: dict[int, list[tuple]] = {}
    heap = [-int(b) for b in deficient]
    heapq.heapify(heap)
    queued = set(int(b) for b in deficient)
    missing, merged, smallest = 0, {}, np.inf
    while heap:
        b = -heapq.heappop(heap)
        wr, mg, acc, am = _block_columns(x[b] @ q[b][:, lead[b]:], np.sqrt(x2[b]), pending.pop(b, []), len(coupled))
        for r, kk, g in at_body.get(b, ()):  # every column here lives in subtree(b): b's coordinates see it whole
            acc[:, r] += g * np.einsum("sc,ksc->ks", lines[kk], wr)
            am[:, r] += np.abs(g) * np.sqrt(l2[kk]) * mg
        here = [r for r, row in enumerate(coupled) if row.anchor == b]
        li = dofs[b]
        mat = np.einsum("msc,ksc->msk", lines[li], wr).reshape(-1, len(wr))
        mag2 = np.einsum("ms,ks->k", l2[li], mg ** 2)
        if here:
            mat = np.concatenate([mat, acc[:, here].reshape(len(wr), -1).T])
            mag2 = mag2 + np.sum(am[:, here] ** 2, axis=(1, 2))
        mag = np.sqrt(mag2)
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
        pending.setdefault(p, []).extend(zip(np.einsum("nk,ksc->nsc", coef, wr), np.abs(coef) @ mg,
                                             np.einsum("nk,krs->nrs", coef, acc),
                                             np.einsum("nk,krs->nrs", np.abs(coef), am)))
        if p not in queued:
            queued.add(p)
            heapq.heappush(heap, -p)
    return missing, merged, smallest


def _block_columns(own: np.ndarray, mag: np.ndarray, pending: list[tuple], rows: int):
    """A block's columns: its own ``x_b U_b`` ``(S, 6, c)`` and the combinations carried into it.

    Returns ``wrenches (k, S, 6)``, ``magnitudes (k, S)``, and the coupled rows' accumulated
    values and magnitudes ``(k, rows, S)`` (zero for the own columns).
    """
    own = np.moveaxis(own, -1, 0)
    s = own.shape[1]
    wr = np.concatenate([own] + [w[None] for w, _, _, _ in pending])
    mg = np.concatenate([np.broadcast_to(mag, (len(own), s))] + [g[None] for _, g, _, _ in pending])
    acc = np.concatenate([np.zeros((len(own), rows, s))] + [a[None] for _, _, a, _ in pending])
    am = np.concatenate([np.zeros((len(own), rows, s))] + [a[None] for _, _, _, a in pending])
    return wr, mg, acc, am


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
        A tree, possibly with couplings (:func:`applicable`), ``n`` bodies.
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
        The check does not apply (loop joints, the base wrench alone measured, or couplings with
        rows other than ``all``), or no sample satisfies the couplings.
    """
    t0 = time.perf_counter()
    if not applicable(robot, rows):
        raise BaseparamsError(f"robot {robot.name!r}: the structured certificate needs a tree whose joint rows are "
                              f"measured (rows other than 'base'; with couplings 'all'), got rows {rows!r}"
                              f"{' and loop joints' if robot.loops else ''}")
    samples = STRUCTURED_SAMPLES if samples is None else samples
    n, d10 = robot.n, decision_scale(robot, "paper")[:10]
    cols = result.columns
    raw = cols.scaled(1.0 / d10)
    *states, big_g, sampling = sampled_states(robot, samples, seed)
    x, lines = wrench_maps(robot, samples, seed, d10, states=tuple(states))
    dofs, coupled = row_groups(robot, rows, big_g)
    res = column_residuals(raw, robot, x, lines, dofs, residual_tol, coupled) if len(cols) else np.zeros(0)
    worst = float(res.max()) if len(res) else 0.0
    local, local_rtol = decision_columns(cols, robot)
    q, lead, indep = leading_spans(local, n, local_rtol)  # q about each body's origin
    rank_b = int(lead.sum())
    inverse = decision_frames(robot)[1]
    if indep is not None:
        indep = indep.transformed(inverse)
    x = _in_decision_frames(x, inverse, d10)
    par = np.asarray(robot.parent, dtype=int)
    bad, small = diagonal_blocks(q, lead, x, lines, dofs, rtol)
    missing, merged, small2 = merge_blocks(bad, par, q, lead, x, lines, dofs, rtol, coupled)
    nblocks, largest = _largest_group(merged, n)
    out = dict(rank_b=rank_b, rank_w=10 * n - rank_b - missing, missing=missing, blocks=nblocks, largest=largest,
               smallest_sv=min(small, small2), column_residuals=res, worst=worst, samples=sampling["kept"],
               independent=indep, sampling=sampling)
    status, message = _structured_verdict(result, out, rtol, residual_tol)
    return StructuredCheck(status, message, seconds=time.perf_counter() - t0, **out)


def _in_decision_frames(x: np.ndarray, inverse: np.ndarray, d10: np.ndarray) -> np.ndarray:
    """Wrench maps on ``pi / d`` ``(n, S, 6, 10)`` made maps on decision coordinates, in place and by chunks.

    ``inverse``: :func:`baseparams.model.scale.decision_frames`'s, from decision coordinates to
    ``pi``; the map on ``pi / d`` then takes ``diag(1 / d) inverse``.
    """
    g = inverse / d10[None, :, None]
    step = max(1, CHUNK // (60 * x.shape[1]))
    for a in range(0, len(x), step):
        x[a:a + step] = np.einsum("nsce,nef->nscf", x[a:a + step], g[a:a + step])
    return x


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
        on its highest body (:func:`.rank.leading_spans` in decision coordinates,
        :func:`~baseparams.nullspace.result.decision_columns`): what
        :func:`baseparams.base.sparse.tree_base_parameters` regroups; ``None`` when the echelon
        form needed eliminations or does not reproduce DRNG's rank.
    """
    local, rtol = decision_columns(result.columns, robot)
    _, lead, indep = leading_spans(local, robot.n, rtol)
    if indep is None or int(lead.sum()) != result.rank:
        return None
    return indep.transformed(decision_frames(robot)[1])


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
