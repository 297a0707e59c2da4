"""Closed loops sampled over their whole motion.

A robot's loop joints and couplings split its coordinates into independent *groups*: coordinates
tied by a common constraint row (transitively). A coordinate that moves both sides of every
constraint alike (a floating base above a leg's linkage), or none, is in no group: the
constraints do not restrict it. Each group's configurations form a manifold of dimension
``d = len(coordinates) - rank(K)`` (``K`` the group's block of the constraint Jacobian at the
reference); the whole configuration set is the product of the groups' manifolds and the free
coordinates.

A group holding a loop joint whose manifold is one- or two-dimensional (a four-bar, a six-bar, a
redundant arm's self-motion under a weld) is *traced* over its whole motion
(:func:`trace_group`): a rapidly-exploring tree on the manifold, grown from the reference by
tangent steps corrected back onto the constraints (Newton orthogonal to the tangent plane),
until new steps no longer reach unexplored configurations. A step is kept only where the
constraint Jacobian keeps its rank, stays well conditioned and does not cross a singular
configuration (the sign of ``det(A_a^T A_b)`` with ``A = [K; T_a^T]`` at both ends, ``T_a`` the
tangent basis where the step starts: the test of :func:`~baseparams.kinematics.loops.close_loops`
in tangent coordinates). Past a singular configuration two assembly branches may meet (a
parallelogram and its anti-parallelogram at the flat configuration): every traced configuration
is on the reference's assembly mode, reached from it without crossing one (PAPER_NOTES, "Sampling
closed loops"). Turning points of the independent coordinates are not singular here (they are
for continuation in those coordinates, which is why a box of actuated values around the
reference reaches only an arc of a loop).

Why: the regressor's dependencies hold on the whole manifold if they hold on any open part of it
(its entries are analytic), but on a short arc the directions that only a large motion excites
are tiny: the stacked regressor's spectrum becomes a continuum with no gap to decide a rank at.
Over the whole motion the gap is clear (a welded 7-joint arm: 1e7 and more).

Groups of couplings alone, and groups of three or more dimensions, are sampled as before: actuated
coordinates in the robot's box, closed by continuation (:func:`~baseparams.kinematics.loops.close_loops`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..display import summary_repr
from ..model.robot import Robot
from .loops import ClosedStates, close_loops, closed_states, elementary_constraints, evaluate

#: tangent step of the exploration, in radians (metres scaled by the robot's length, :func:`coordinate_scale`)
STEP = 0.15
#: exploration steps tried at once
BATCH = 64
#: at most this many explored configurations per group (per dimension: 1-D, 2-D)
MAX_NODES = {1: 800, 2: 2500}
#: at most this many batches per group
MAX_BATCHES = 300
#: the exploration ends after this many batches in a row that reach nothing new
IDLE_BATCHES = 4
#: a configuration is new when no explored one is nearer than this fraction of a step
NOVEL = 0.5
#: Newton's tolerance on the largest constraint residual, and its iterations per step
TOL, ITERATIONS = 1e-11, 12
#: a step's corrected end may lie at most this fraction of a step from its prediction
MAX_CORRECTION = 0.5
#: the constraint Jacobian's condition number (over its rank) may grow to this multiple of the reference's
#: (at least 1e3)
COND_GROWTH = 100.0


@dataclass(frozen=True, eq=False)
class LoopGroup:
    """Coordinates tied together by loop constraints or couplings (see the module doc).

    Parameters
    ----------
    coords : ndarray of int, shape ``(c,)``
        The group's tree coordinates.
    rows : ndarray of int
        Its rows of the constraints (:func:`~baseparams.kinematics.loops.evaluate`'s layout).
    names : tuple of str
        The loop joints and couplings that tie it.
    rank : int
        Rank of its block of the constraint Jacobian at the reference q = 0.
    elementary : bool
        It holds a loop joint (not couplings alone).
    """

    coords: np.ndarray
    rows: np.ndarray
    names: tuple[str, ...]
    rank: int
    elementary: bool

    __repr__ = summary_repr

    @property
    def dim(self) -> int:
        """Dimension of the group's configuration manifold, ``c - rank``."""
        return len(self.coords) - self.rank


def loop_groups(robot: Robot, rtol: float = 1e-9) -> list[LoopGroup]:
    """The robot's coordinates grouped by the constraints that tie them (see the module doc).

    Parameters
    ----------
    robot : Robot
        A robot with loops or couplings, assembled at q = 0.
    rtol : float, optional
        Rank threshold of each group's Jacobian block, relative to its largest singular value.

    Returns
    -------
    list of LoopGroup
        One per group, in the order of their first coordinate; coordinates in no group are free.
    """
    sets = []  # (rows, coordinates, name) per coupling and elementary constraint
    row = 0
    for c in robot.couplings:
        sets.append(([row], {c.succ} | {j for j, _ in c.terms()}, c.name))
        row += 1
    for e in elementary_constraints(robot):
        on = [set() if b < 0 else set(robot.path_dofs(b).tolist()) for b in (e.pred, e.succ)]
        nrows = 3 if e.kind == "point" else 1
        sets.append((list(range(row, row + nrows)), on[0] ^ on[1], robot.loops[e.loop].name))
        row += nrows
    root = list(range(robot.dof))

    def find(j: int) -> int:
        while root[j] != j:
            root[j] = root[root[j]]
            j = root[j]
        return j

    for _, coords, _ in sets:
        first = sorted(coords)[:1]
        for j in coords:
            root[find(j)] = find(first[0])
    k = evaluate(robot, np.zeros((1, robot.dof))).K[0] if sets else None
    by_root: dict = {}
    elementary = [False] * len(robot.couplings) + [True] * (len(sets) - len(robot.couplings))
    for (rows, coords, name), elem in zip(sets, elementary):
        if not coords:
            continue
        g = by_root.setdefault(find(min(coords)), [[], set(), [], False])
        g[0] += rows
        g[1] |= coords
        if name not in g[2]:
            g[2].append(name)
        g[3] |= elem
    out = []
    for rows, coords, names, elem in by_root.values():
        cols = np.array(sorted(coords), dtype=int)
        sv = np.linalg.svd(k[np.ix_(rows, cols)], compute_uv=False)
        rank = int(np.sum(sv > rtol * sv[0])) if len(sv) and sv[0] > 0 else 0
        out.append(LoopGroup(cols, np.array(rows, dtype=int), tuple(names), rank, elem))
    return sorted(out, key=lambda g: int(g.coords[0]))


def coordinate_scale(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """Per coordinate, the scale to a common unit and whether it is an angle that wraps.

    Parameters
    ----------
    robot : Robot
        The robot.

    Returns
    -------
    scale : ndarray, shape ``(dof,)``
        1 for angles; ``1 / L`` for lengths (translations), ``L`` the robot's size (the largest
        distance of a body or loop frame from the origin at q = 0, at least 0.1 m).
    wraps : ndarray of bool, shape ``(dof,)``
        Angles of R, U, S and C joints (the same configuration every ``2 pi``).
    """
    pts = [robot.M0[:, :3, 3]] + [lj.M[None, :3, 3] for lj in robot.loops]
    size = max(0.1, float(np.abs(np.concatenate(pts)).max(initial=0.0)) * np.sqrt(3.0))
    linear = np.linalg.norm(robot.screws[:, :3], axis=1) < 0.5
    floating = np.isin(robot.dof_body, np.flatnonzero(np.asarray(robot.jtype) == "F"))
    return np.where(linear, 1.0 / size, 1.0), ~linear & ~floating


@dataclass(frozen=True, eq=False)
class _Tracer:
    """What a group's tracing needs: the robot, its constraints, the group and the scaled metric."""

    robot: Robot
    cons: list
    group: LoopGroup
    w: np.ndarray  # (c,) scale of the group's coordinates
    wraps: np.ndarray  # (c,)
    cond_max: float

    def diff(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """``a - b`` in scaled coordinates, angles wrapped to ``[-pi, pi)``."""
        d = a - b
        return np.where(self.wraps, (d + np.pi) % (2 * np.pi) - np.pi, d)

    def jacobian(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residuals ``(S, m)`` and the scaled Jacobian ``(S, m, c)`` at scaled group coordinates ``x (S, c)``."""
        q = np.zeros((x.shape[0], self.robot.dof))
        q[:, self.group.coords] = x / self.w
        ev = evaluate(self.robot, q, constraints=self.cons)
        k = ev.K[:, self.group.rows][:, :, self.group.coords] / self.w
        return ev.r[:, self.group.rows], k

    def tangents(self, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tangent bases ``(S, c, d)`` and whether each point is regular ``(S,)`` (rank kept, conditioned)."""
        r = self.group.rank
        _, s, vt = np.linalg.svd(k, full_matrices=True)
        top = np.maximum(s[:, 0], 1e-300)
        full = s[:, r - 1] / top if r else np.ones(len(s))
        extra = s[:, r] / top if s.shape[1] > r else np.zeros(len(s))
        regular = (full > 1.0 / self.cond_max) & (extra < 1e-8)
        return np.swapaxes(vt[:, r:], 1, 2), regular

    def correct(self, x: np.ndarray, t: np.ndarray, polish: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Newton onto the constraints orthogonal to the tangents ``t (S, c, d)``; ``(x, converged, K)``.

        With ``polish``, a converged point is then refined to the rounding floor of its residual
        (:meth:`polish`): near a singularity the rates amplify the closure error.
        """
        x = x.copy()
        ok = np.zeros(len(x), dtype=bool)
        err_out = np.full(len(x), np.inf)
        k_out = np.zeros((len(x), len(self.group.rows), len(self.group.coords)))
        live = np.arange(len(x))
        for _ in range(ITERATIONS):
            if not len(live):
                break
            r, k = self.jacobian(x[live])
            err = np.abs(r).max(axis=1) if r.shape[1] else np.zeros(len(live))
            done = err < TOL
            ok[live[done]] = True
            k_out[live[done]], err_out[live[done]] = k[done], err[done]
            live, r, k = live[~done], r[~done], k[~done]
            if len(live):
                x[live] += self.newton_step(k, r, t[live])
        if polish:
            self.polish(x, t, np.flatnonzero(ok), err_out, k_out)
        return x, ok, k_out

    def newton_step(self, k: np.ndarray, r: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The step ``(S, c)`` solving ``[K; T^T] dx = [-r; 0]`` (least squares), clipped to 1."""
        a = np.concatenate([k, np.swapaxes(t, 1, 2)], axis=1)
        rhs = np.concatenate([-r, np.zeros((len(r), t.shape[2]))], axis=1)
        at = np.swapaxes(a, 1, 2)
        with np.errstate(all="ignore"):
            step = np.linalg.solve(at @ a, at @ rhs[:, :, None])[:, :, 0]
        return np.where(np.isfinite(step), np.clip(step, -1.0, 1.0), 0.0)

    def polish(self, x: np.ndarray, t: np.ndarray, idx: np.ndarray, err: np.ndarray, k_out: np.ndarray,
               iterations: int = 3) -> None:
        """Newton steps past the tolerance on the converged points ``idx``, kept where they lower the residual."""
        for _ in range(iterations):
            if not len(idx):
                return
            r, k = self.jacobian(x[idx])
            trial = x[idx] + self.newton_step(k, r, t[idx])
            r2, k2 = self.jacobian(trial)
            e2 = np.abs(r2).max(axis=1) if r2.shape[1] else np.zeros(len(idx))
            better = e2 < err[idx]
            x[idx[better]], err[idx[better]], k_out[idx[better]] = trial[better], e2[better], k2[better]
            idx = idx[better & (e2 > 0)]

    def step(self, x0: np.ndarray, t0: np.ndarray, k0: np.ndarray, move: np.ndarray, polish: bool = False):
        """Tangent steps ``move (S, c)`` from ``x0`` (tangents ``t0``, Jacobians ``k0``), corrected (and polished).

        Returns ``(x, t, k, kept)``: the ends, their tangents and Jacobians, and which steps are
        kept (converged near the prediction, regular, no singular configuration crossed).
        """
        pred = x0 + move
        x, ok, k = self.correct(pred, t0, polish)
        size = np.linalg.norm(move, axis=1)
        ok &= np.linalg.norm(x - pred, axis=1) <= MAX_CORRECTION * np.maximum(size, 1e-12)
        t, regular = self.tangents(k)
        ok &= regular
        a0 = np.concatenate([k0, np.swapaxes(t0, 1, 2)], axis=1)
        a1 = np.concatenate([k, np.swapaxes(t0, 1, 2)], axis=1)
        with np.errstate(all="ignore"):
            ok &= np.linalg.det(np.swapaxes(a0, 1, 2) @ a1) > 0
        return x, t, k, ok


def _tracer(robot: Robot, cons: list, group: LoopGroup) -> _Tracer:
    """The tracer of ``group`` (its conditioning bound from the reference's).

    A group of loop joints alone is evaluated on its own constraints (the robot without couplings,
    the group's rows renumbered): the other groups' do not depend on its coordinates.
    """
    scale, wraps = coordinate_scale(robot)
    names = {lj.name for lj in robot.loops}
    if all(n in names for n in group.names):
        own = [e for e in cons if robot.loops[e.loop].name in group.names]
        rows = np.arange(sum(3 if e.kind == "point" else 1 for e in own))
        robot, cons, group = replace(robot, couplings=()), own, replace(group, rows=rows)
    w = scale[group.coords]
    tr = _Tracer(robot, cons, group, w, wraps[group.coords], np.inf)
    _, k = tr.jacobian(np.zeros((1, len(group.coords))))
    sv = np.linalg.svd(k[0], compute_uv=False)
    cond0 = sv[0] / sv[group.rank - 1] if group.rank and sv[group.rank - 1] > 0 else np.inf
    return replace(tr, cond_max=max(1e3, COND_GROWTH * cond0))


@dataclass(frozen=True, eq=False)
class Trace:
    """A group's explored configurations (:func:`trace_group`).

    Parameters
    ----------
    group : LoopGroup
        The group traced.
    x : ndarray, shape ``(N, c)``
        Explored configurations of its coordinates, scaled (:func:`coordinate_scale`).
    t : ndarray, shape ``(N, c, d)``
        Orthonormal tangent bases there (scaled coordinates).
    k : ndarray, shape ``(N, m, c)``
        The group's constraint Jacobian there (scaled columns).
    extent : ndarray, shape ``(c,)``
        Range of each coordinate over the explored configurations (rad or m, angles unwrapped
        along the tree: a crank turning fully shows ``2 pi`` or more).
    batches : int
        Exploration batches run.
    """

    group: LoopGroup
    x: np.ndarray
    t: np.ndarray
    k: np.ndarray
    extent: np.ndarray
    batches: int

    __repr__ = summary_repr


def trace_group(robot: Robot, group: LoopGroup, rng: np.random.Generator, cons: list | None = None) -> Trace:
    """Explore a group's configuration manifold from the reference (see the module doc).

    Parameters
    ----------
    robot : Robot
        The robot, assembled at a regular reference q = 0.
    group : LoopGroup
        A group of :func:`loop_groups` (any dimension; meant for 1 and 2).
    rng : numpy.random.Generator
        Source of the exploration's targets.
    cons : list of Elementary, optional
        The robot's elementary constraints (default: computed).

    Returns
    -------
    Trace
        The explored configurations, their tangents and Jacobians.
    """
    tr = _tracer(robot, elementary_constraints(robot) if cons is None else cons, group)
    c, d = len(group.coords), group.dim
    x = np.zeros((1, c))
    _, k = tr.jacobian(x)
    t, _ = tr.tangents(k)
    lo, hi = np.zeros(c), np.zeros(c)  # unwrapped extent: each node keeps its parent's unwrapped coordinates
    xu = x.copy()
    span = np.where(tr.wraps, np.pi, 2.0)
    idle = batches = 0
    cap = MAX_NODES.get(d, MAX_NODES[2])
    while idle < IDLE_BATCHES and len(x) < cap and batches < MAX_BATCHES:
        batches += 1
        target = rng.uniform(-span, span, (BATCH, c))
        dist = np.linalg.norm(tr.diff(target[:, None], x[None]), axis=2)
        near = np.argmin(dist, axis=1)
        toward = tr.diff(target, x[near])
        u = np.einsum("sij,si->sj", t[near], toward)
        move = np.einsum("sij,sj->si", t[near], u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-300))
        xn, tn, kn, ok = tr.step(x[near], t[near], k[near], STEP * move)
        added = []
        for i in np.flatnonzero(ok):
            seen = np.concatenate([x, xn[added]]) if added else x
            if np.linalg.norm(tr.diff(xn[i][None], seen), axis=1).min() >= NOVEL * STEP:
                added.append(i)
        if added:
            unwrapped = xu[near[added]] + tr.diff(xn[added], x[near[added]])
            x, t, k, xu = (np.concatenate([x, xn[added]]), np.concatenate([t, tn[added]]),
                           np.concatenate([k, kn[added]]), np.concatenate([xu, unwrapped]))
        lo, hi = np.minimum(lo, xu.min(axis=0)), np.maximum(hi, xu.max(axis=0))
        idle = 0 if added else idle + 1
    return Trace(group, x, t, k, (hi - lo) / tr.w, batches)


def sample_trace(robot: Robot, trace: Trace, samples: int, rng: np.random.Generator,
                 cons: list | None = None) -> np.ndarray:
    """``samples`` configurations of a traced group's coordinates, spread over the explored manifold.

    Each is a random explored configuration moved by a random tangent step of up to half a step
    and corrected onto the constraints (kept only where :meth:`_Tracer.step` keeps it; else the
    explored configuration itself).

    Parameters
    ----------
    robot : Robot
        The robot traced.
    trace : Trace
        The group's exploration (:func:`trace_group`).
    samples : int
        Number of configurations.
    rng : numpy.random.Generator
        Source of the draws.
    cons : list of Elementary, optional
        The robot's elementary constraints (default: computed).

    Returns
    -------
    ndarray, shape ``(samples, c)``
        The group's coordinates (rad or m), on the reference's assembly mode.
    """
    tr = _tracer(robot, elementary_constraints(robot) if cons is None else cons, trace.group)
    idx = rng.integers(0, len(trace.x), samples)
    u = rng.normal(size=(samples, trace.group.dim))
    u *= (rng.uniform(0.0, 0.5 * STEP, samples) / np.maximum(np.linalg.norm(u, axis=1), 1e-300))[:, None]
    move = np.einsum("sij,sj->si", trace.t[idx], u)
    x, _, _, ok = tr.step(trace.x[idx], trace.t[idx], trace.k[idx], move, polish=True)
    if not ok.all():  # the explored configuration itself, polished
        x[~ok] = tr.correct(trace.x[idx[~ok]], trace.t[idx[~ok]], polish=True)[0]
    return x / tr.w


#: groups of at most this many dimensions are traced
TRACED_DIMENSIONS = (1, 2)


def traced_groups(robot: Robot) -> list[LoopGroup]:
    """The robot's groups sampled over their whole motion: a loop joint, a 1- or 2-dimensional manifold.

    Parameters
    ----------
    robot : Robot
        The robot, assembled at q = 0.

    Returns
    -------
    list of LoopGroup
        Empty for a robot without loop joints (couplings alone are sampled in the box).
    """
    if not robot.loops:
        return []
    return [g for g in loop_groups(robot) if g.elementary and g.dim in TRACED_DIMENSIONS]


def motion_samples(robot: Robot, samples: int, rng: np.random.Generator, box: np.ndarray,
                   cond_max: float) -> ClosedStates | None:
    """Loop-closed random states, the traced groups over their whole motion (None when none is traced).

    The other coordinates as :func:`~baseparams.kinematics.loops.close_loops` from actuated
    values in ``box`` (the traced groups' actuated coordinates held at the reference there);
    then each traced group's coordinates from :func:`sample_trace`, and the rates from actuated
    ``dq_a, ddq_a`` uniform in ``(0, 1)`` (:func:`~baseparams.kinematics.loops.closed_states`).

    Parameters
    ----------
    robot : Robot
        A robot with loops, assembled at a regular reference q = 0.
    samples : int
        Number of samples drawn.
    rng : numpy.random.Generator
        Source of the draws (actuated ``q_a``, ``dq_a``, ``ddq_a``, then the traces).
    box : ndarray, shape ``(na, 2)``
        Sampling box of the actuated coordinates (the untraced ones).
    cond_max : float
        Box samples (the untraced coordinates) with ``cond(K_p)`` at or above it are discarded
        (counted ill-conditioned); the traced coordinates are held to their trace's bound instead
        (a welded arm's constraint Jacobian mixes metres and radians: its conditioning is in the
        thousands along the whole loop: the caller cuts relative to the samples' own median).

    Returns
    -------
    ClosedStates or None
        The kept samples (``motion`` describes each traced group); None when no group is traced.
    """
    groups = traced_groups(robot)
    if not groups:
        return None
    act = np.asarray(robot.actuated, dtype=int)
    qa = rng.uniform(box[:, 0], box[:, 1], (samples, len(act)))
    dqa, ddqa = rng.uniform(0, 1, (samples, len(act))), rng.uniform(0, 1, (samples, len(act)))
    traced = np.concatenate([g.coords for g in groups])
    qa[:, np.isin(act, traced)] = 0.0
    cs = close_loops(robot, qa, dqa, ddqa, cond_max=cond_max)
    cons = elementary_constraints(robot)
    q = cs.q.copy()
    motion = []
    for g in groups:
        tr = trace_group(robot, g, rng, cons)
        q[:, g.coords] = sample_trace(robot, tr, len(q), rng, cons)
        motion.append(describe(robot, tr))
    # the traces keep their constraint Jacobian's rank and conditioning (:meth:`_Tracer.tangents`): no further cut
    out = closed_states(robot, q, cs.dq[:, act], cs.ddq[:, act], np.inf, rechart=True)
    return replace(out, requested=samples, not_converged=cs.not_converged + out.not_converged,
                   branch_jumps=cs.branch_jumps, ill_conditioned=cs.ill_conditioned, motion=tuple(motion))


def describe(robot: Robot, trace: Trace) -> str:
    """One line on a traced group: its constraints, dimension, extent and configurations explored.

    Parameters
    ----------
    robot : Robot
        The robot.
    trace : Trace
        The group's exploration.

    Returns
    -------
    str
        E.g. ``"weld0: 1-dimensional motion of 7 joints traced (1412 configurations; right_j0 over
        6.28 rad, ...)"``.
    """
    g = trace.group
    names = [robot.joint_names[robot.dof_body[j]] for j in g.coords]
    widest = np.argsort(-trace.extent)[:3]
    spans = ", ".join(f"{names[i]} over {trace.extent[i]:.3g}" for i in widest)
    return (f"{', '.join(g.names)}: the {g.dim}-dimensional motion of {len(g.coords)} coordinates traced from the "
            f"reference ({len(trace.x)} configurations; {spans})")
