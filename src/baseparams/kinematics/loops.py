"""Closed-loop kinematics.

Loop-closure constraints, Newton from the actuated coordinates, passive velocities and
accelerations from the exact analytic ``Jdot qdot`` terms.

Each loop joint (cut joint) between a predecessor body ``p`` and a successor body ``c`` is a
list of elementary constraints on points/directions given in world coordinates at q = 0
(where the two frames coincide):

* ``point (x, x')``: ``g_c x' - g_p x = 0`` (3 rows; a direction when ``x[3] = 0``);
* ``dot (u, w)``: ``(g_p u) . (g_c w) = 0`` (1 row; ``u`` carried by p, ``w`` by c);
* ``proj (n, x, x')``: ``(g_p n) . (g_c x' - g_p x) = 0`` (1 row).

(``x' = x`` when the file is assembled at q = 0; otherwise ``x'`` is the successor's copy.)

S: point; R: point + axis direction; U: point + dot(axis, axis2); P: three directions + two
projections normal to the axis; fixed: point + three directions. Rows may be redundant
(e.g. a direction gives 3 rows for 2 constraints): every solve is rank-revealing (pseudo-inverse).

With ``r(q)`` the residuals, ``K = dr/dq`` (built from the Jacobian lines) and the bias
``b = d^2 r/dt^2`` at zero ``ddq`` (exact point accelerations), the passive coordinates obey
``K_p dq_p = -K_a dq_a`` and ``K_p ddq_p = -(K_a ddq_a + b)``. No finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..errors import BaseparamsError, ModelError, NoMotionError
from ..model.robot import Robot
from ..pga.linalg import cross3_first, perp_basis
from .tree import Poses, as_states, poses, re_reference


@dataclass(frozen=True, eq=False)
class Elementary:
    """One elementary constraint of a loop joint (see the module doc).

    Vectors are homogeneous ``(4,)`` in world coordinates at q = 0 (``x[3] = 0``: a direction).

    Parameters
    ----------
    kind : {'point', 'dot', 'proj'}
        ``point``: ``g_c b - g_p a = 0`` (3 rows); ``dot``: ``(g_p a) . (g_c b) = 0`` (1 row);
        ``proj``: ``(g_p a) . (g_c c - g_p b) = 0`` (1 row).
    pred : int
        The predecessor body ``p`` (-1: the world).
    succ : int
        The successor body ``c``.
    a : ndarray, shape ``(4,)``
        The predecessor's point/direction (``proj``: the normal ``n``).
    b : ndarray, shape ``(4,)``, optional
        ``point``, ``dot``: the successor's vector; ``proj``: the predecessor's point.
    c : ndarray, shape ``(4,)``, optional
        ``proj``: the successor's point.
    loop : int, optional
        Index of the loop joint in ``robot.loops``.
    """

    kind: str  # point | dot | proj
    pred: int
    succ: int
    a: np.ndarray  # the predecessor's point/direction (4,)
    b: np.ndarray | None = None  # point, dot: the successor's vector; proj: the predecessor's point
    c: np.ndarray | None = None  # proj: the successor's point
    loop: int = 0

    __repr__ = summary_repr


def elementary_constraints(robot: Robot) -> list[Elementary]:
    """The elementary constraints of every loop joint (see module doc).

    Parameters
    ----------
    robot : Robot
        The robot; its loop joints ``robot.loops`` (frames ``M``, and ``M_child`` for the
        successor's copy when the file is not assembled at q = 0).

    Returns
    -------
    list of Elementary
        S: point; R: point + axis direction; U: point + dot(axis, axis2); P: three directions +
        two projections normal to the axis; fixed: point + three directions. Loop by loop.
    """
    out: list[Elementary] = []
    for k, lj in enumerate(robot.loops):
        mc = lj.M if lj.M_child is None else lj.M_child  # the successor's copy of the frame
        o, oc = np.r_[lj.M[:3, 3], 1.0], np.r_[mc[:3, 3], 1.0]
        r, rc = lj.M[:3, :3], mc[:3, :3]
        p, c = lj.parent, lj.child
        if lj.type in ("S", "R", "U", "fixed"):
            out.append(Elementary("point", p, c, o, oc, loop=k))
        if lj.type == "R":
            out.append(Elementary("point", p, c, np.r_[r @ lj.axes[0], 0.0], np.r_[rc @ lj.axes[0], 0.0], loop=k))
        elif lj.type == "U":
            out.append(Elementary("dot", p, c, np.r_[r @ lj.axes[0], 0.0], np.r_[rc @ lj.axes[1], 0.0], loop=k))
        elif lj.type in ("P", "fixed"):
            out += [Elementary("point", p, c, np.r_[r[:, m], 0.0], np.r_[rc[:, m], 0.0], loop=k) for m in range(3)]
            if lj.type == "P":
                a = r @ lj.axes[0]
                for n in (v[0] for v in perp_basis(np.asarray(a, dtype=float)[None])):
                    out.append(Elementary("proj", p, c, np.r_[n, 0.0], o, oc, loop=k))
    return out


@dataclass(frozen=True, eq=False)
class ConstraintEval:
    """The loop constraints evaluated at ``S`` states (:func:`evaluate`).

    Parameters
    ----------
    r : ndarray, shape ``(S, m)``
        Residuals.
    K : ndarray, shape ``(S, m, dof)``
        Jacobian ``dr/dq``.
    b : ndarray, shape ``(S, m)``, or None
        Bias ``d^2 r/dt^2`` at zero ``ddq`` (needs dq; None without it).
    """

    r: np.ndarray
    K: np.ndarray
    b: np.ndarray | None

    __repr__ = summary_repr


def evaluate(robot: Robot, q: np.ndarray, dq: np.ndarray | None = None,
             constraints: list[Elementary] | None = None) -> ConstraintEval:
    """Residuals, Jacobian and (when ``dq`` is given) the bias of the loop constraints.

    The rows are the couplings' (``q[succ] - sum ratio q[pred] - offset``, less the polynomial
    terms of a nonlinear one) first, then the elementary constraints' in order.

    Parameters
    ----------
    robot : Robot
        The robot (``dof`` tree coordinates).
    q : ndarray, shape ``(S, dof)``
        Tree coordinates (two-dimensional).
    dq : ndarray, shape ``(S, dof)``, optional
        Velocities; when given, the bias is computed (exact point accelerations, no finite
        differences).
    constraints : list of Elementary, optional
        The elementary constraints; default :func:`elementary_constraints` of ``robot``.

    Returns
    -------
    ConstraintEval
        ``r (S, m)``, ``K (S, m, dof)`` and ``b (S, m)`` (None without ``dq``).
    """
    plan = _plan(robot, elementary_constraints(robot) if constraints is None else constraints)
    r, k, b = _eval(plan, np.asarray(q, dtype=float), np.arange(robot.dof), dq)
    return ConstraintEval(r.T.copy(), np.ascontiguousarray(k.transpose(2, 0, 1)), None if b is None else b.T.copy())


@dataclass(frozen=True, eq=False)
class _Plan:
    """What :func:`_eval` needs of a robot and its constraints, computed once per solve.

    ``groups``: per body carrying constraint vectors, ``(body, slots, X (nv, 3), x3 (nv,))``;
    ``slots``: per constraint, the slots of its vectors ``a, b[, c]``; ``rows``: its first row;
    ``sup``: ``(dof, n + 1)`` support with a zero last column (the world, body -1).
    """

    robot: Robot
    cons: list
    kc: np.ndarray
    offsets: np.ndarray
    poly: list  # (row, pred, coefficients of q_pred^2, q_pred^3, ...) of the nonlinear couplings
    groups: list
    nvec: int
    slots: list
    rows: list
    m: int
    sup: np.ndarray
    bodies: np.ndarray
    columns_cache: dict


def _plan(robot: Robot, cons: list[Elementary]) -> _Plan:
    """The constraint vectors grouped by body, the couplings as a matrix, the row layout."""
    dof = robot.dof
    kc = np.zeros((len(robot.couplings), dof))
    for i, c in enumerate(robot.couplings):
        kc[i, c.succ] = 1.0
        for j, ratio in c.terms():
            kc[i, j] -= ratio
    offsets = np.array([c.offset for c in robot.couplings], dtype=float)
    poly = [(i, c.pred, np.asarray(c.poly, dtype=float)) for i, c in enumerate(robot.couplings) if c.poly]
    slot_of: dict = {}
    slots, rows, row = [], [], len(robot.couplings)
    for e in cons:
        owners = {"point": (e.pred, e.succ), "dot": (e.pred, e.succ), "proj": (e.pred, e.pred, e.succ)}[e.kind]
        vecs = (e.a, e.b, e.c)[:len(owners)]
        slots.append(tuple(slot_of.setdefault((body, tuple(np.asarray(x, dtype=float))), len(slot_of))
                           for body, x in zip(owners, vecs)))
        rows.append(row)
        row += 3 if e.kind == "point" else 1
    groups = []
    for body in sorted({b for b, _ in slot_of}):
        items = [(sl, x) for (b, x), sl in slot_of.items() if b == body]
        xs = np.array([x for _, x in items], dtype=float)
        groups.append((body, np.array([sl for sl, _ in items]), xs[:, :3].copy(), xs[:, 3].copy()))
    sup = np.zeros((dof, robot.n + 1))
    sup[:, :-1] = robot.support
    bodies = np.array([g[0] for g in groups if g[0] >= 0], dtype=int)
    return _Plan(robot, list(cons), kc, offsets, poly, groups, len(slot_of), slots, rows, row, sup, bodies, {})


def _columns(plan: _Plan, cols: np.ndarray) -> list:
    """Per constraint ``(J, dofs, s_c, s_p, coef)``: the columns ``J`` of ``cols`` moving its bodies.

    ``s_c``, ``s_p``: whether each moves the successor, the predecessor; ``coef``: the factor of
    the line's moment (the vectors' homogeneous weights).
    """
    key = cols.tobytes()
    out = plan.columns_cache.get(key)
    if out is None:
        out = []
        for e in plan.cons:
            sp, sc = plan.sup[cols, e.pred], plan.sup[cols, e.succ]
            j = np.flatnonzero((sp != 0) | (sc != 0))
            sp, sc = sp[j], sc[j]
            if e.kind == "point":
                coef = sc * e.b[3] - sp * e.a[3]
            elif e.kind == "proj":
                coef = sc * e.c[3] - sp * e.b[3]
            else:
                coef = None
            out.append((j, cols[j], sc, sp, coef))
        plan.columns_cache[key] = out
    return out


def _eval(plan: _Plan, q: np.ndarray, cols: np.ndarray, dq: np.ndarray | None = None):
    """``r (m, S)``, ``K (m, len(cols), S)`` (the columns ``cols`` of ``dr/dq``) and the bias ``(m, S)``.

    Samples last (see :func:`evaluate` for the rows); the bias is None without ``dq``.
    """
    s = q.shape[0]
    r = np.empty((plan.m, s))
    k = np.zeros((plan.m, len(cols), s))
    b = None if dq is None else np.zeros((plan.m, s))
    nc = len(plan.offsets)
    if nc:  # couplings: the linear part, then the nonlinear terms of polynomial ones
        r[:nc] = plan.kc @ q.T - plan.offsets[:, None]
        k[:nc] = plan.kc[:, cols][:, :, None]
        for row, pred, c in plan.poly:
            x = q[:, pred]
            powers = np.arange(2, 2 + len(c))
            r[row] -= np.power.outer(x, powers) @ c
            where = np.flatnonzero(cols == pred)
            if len(where):
                k[row, where[0]] -= np.power.outer(x, powers - 1) @ (powers * c)
            if b is not None:
                b[row] -= (np.power.outer(x, powers - 2) @ (powers * (powers - 1) * c)) * dq[:, pred] ** 2
    if not plan.cons:
        as_states(plan.robot.dof, q)  # validated as the kinematics would
        return r, k, b
    ps = poses(plan.robot, q, dq, None, bodies=plan.bodies)
    w, wd, wa = _world_vectors(plan, ps, s)
    for e, sl, row, cd in zip(plan.cons, plan.slots, plan.rows, _columns(plan, cols)):
        _ROWS[e.kind](e, ps.lines, w, wd, wa, sl, row, cd, r, k, b)
    return r, k, b


def _world_vectors(plan: _Plan, ps: Poses, s: int):
    """Constraint vectors ``(3, nvec, S)`` in the world, and (with twists) their velocities and bias accelerations.

    ``x_w = R x + x3 p``; ``dx = omega x x_w + x3 v``; ``ddx = domega x x_w + x3 dv + omega x dx``
    (the point's acceleration at zero ``ddq``).
    """
    w = np.empty((3, plan.nvec, s))
    need = ps.V is not None
    wd = np.zeros((3, plan.nvec, s)) if need else None
    wa = np.zeros((3, plan.nvec, s)) if need else None
    for body, sl, xs, x3 in plan.groups:
        if body < 0:
            w[:, sl] = xs.T[:, :, None]
            continue
        xw = (xs @ ps.rot[body].reshape(3, -1)).reshape(len(sl), 3, s).transpose(1, 0, 2)
        if np.any(x3):
            xw = xw + x3[:, None] * ps.pos[body][:, None]
        w[:, sl] = xw
        if need:
            om, v = ps.V[body, :3, None], ps.V[body, 3:, None]
            dom, dv = ps.dV[body, :3, None], ps.dV[body, 3:, None]
            xd = cross3_first(om, xw) + x3[:, None] * v
            wd[:, sl] = xd
            wa[:, sl] = cross3_first(dom, xw) + x3[:, None] * dv + cross3_first(om, xd)
    return w, wd, wa


def _point_rows(e, lines, w, wd, wa, sl, row, cd, r, k, b) -> None:
    """``g_c b - g_p a``: 3 rows; ``K_j = d_j x (s_c x_c - s_p x_p) + coef_j m_j``."""
    xp, xc = w[:, sl[0]], w[:, sl[1]]
    r[row:row + 3] = xc - xp
    j, dofs, sc, sp, coef = cd
    if len(j):
        y = xc[:, None] * sc[:, None] - xp[:, None] * sp[:, None]
        vel = cross3_first(lines[:3, dofs], y)
        if np.any(coef):
            vel += coef[:, None] * lines[3:, dofs]
        k[row:row + 3, j] = vel
    if b is not None:
        b[row:row + 3] = wa[:, sl[1]] - wa[:, sl[0]]


def _dot_rows(e, lines, w, wd, wa, sl, row, cd, r, k, b) -> None:
    """``(g_p a) . (g_c b)``: 1 row; ``K_j = (s_p - s_c) d_j . (u x w)`` (plus moment terms)."""
    u, v = w[:, sl[0]], w[:, sl[1]]
    u3, v3 = e.a[3], e.b[3]
    r[row] = np.sum(u * v, 0) + u3 * v3
    j, dofs, sc, sp, _ = cd
    if len(j):
        kj = (sp - sc)[:, None] * np.sum(lines[:3, dofs] * cross3_first(u, v)[:, None], 0)
        if u3 or v3:
            kj += np.sum(lines[3:, dofs] * ((sp * u3)[:, None] * v[:, None] + (sc * v3)[:, None] * u[:, None]), 0)
        k[row, j] = kj
    if b is not None:
        b[row] = (np.sum(wa[:, sl[0]] * v, 0) + 2 * np.sum(wd[:, sl[0]] * wd[:, sl[1]], 0)
                  + np.sum(u * wa[:, sl[1]], 0))


def _proj_rows(e, lines, w, wd, wa, sl, row, cd, r, k, b) -> None:
    """``(g_p n) . (g_c c - g_p b)``: 1 row; ``K_j = (s_c - s_p) d_j . (x_c x n)`` (plus moment terms)."""
    n, xp, xc = w[:, sl[0]], w[:, sl[1]], w[:, sl[2]]
    n3 = e.a[3]
    dlt = xc - xp
    r[row] = np.sum(n * dlt, 0) + n3 * (e.c[3] - e.b[3])
    j, dofs, sc, sp, coef = cd
    if len(j):
        kj = (sc - sp)[:, None] * np.sum(lines[:3, dofs] * cross3_first(xc, n)[:, None], 0)
        if n3 or np.any(coef):
            kj += np.sum(lines[3:, dofs] * ((sp * n3)[:, None] * dlt[:, None] + coef[:, None] * n[:, None]), 0)
        k[row, j] = kj
    if b is not None:
        b[row] = (np.sum(wa[:, sl[0]] * dlt, 0) + 2 * np.sum(wd[:, sl[0]] * (wd[:, sl[2]] - wd[:, sl[1]]), 0)
                  + np.sum(n * (wa[:, sl[2]] - wa[:, sl[1]]), 0))


_ROWS = {"point": _point_rows, "dot": _dot_rows, "proj": _proj_rows}


def _pinv(k: np.ndarray, rcond: float = 1e-10) -> tuple[np.ndarray, np.ndarray]:
    """Batched pseudo-inverse and singular values of ``k (S, m, n)``."""
    u, s, vt = np.linalg.svd(k, full_matrices=False)
    cut = rcond * s[..., :1]
    sinv = np.where(s > cut, 1.0 / np.where(s > cut, s, 1.0), 0.0)
    return np.einsum("sji,sj,skj->sik", vt, sinv, u), s


def _lstsq(k: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Batched least-squares step ``k x ~ r`` by regularised normal equations, samples last.

    ``k (m, n, S)`` (or ``(m, n, 1)``: one matrix for all), ``r (m, S)`` -> ``x (n, S)``. Newton
    only; redundant rows are fine, a rank-deficient ``k`` gets a tiny Tikhonov term. Gaussian
    elimination without pivoting (the matrix is symmetric positive definite), vectorised over the
    samples.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # singular: non-finite, filtered
        return _solve_normal(k, r)


def _solve_normal(k: np.ndarray, r: np.ndarray) -> np.ndarray:
    """:func:`_lstsq`'s normal equations ``(k^T k + eps I) x = k^T r``, eliminated in place."""
    n = k.shape[1]
    a = np.einsum("mis,mjs->ijs", k, k)
    diag = np.arange(n)
    a[diag, diag] += 1e-12 * a[diag, diag].sum(0) + 1e-300
    x = k[:, :, 0].T @ r if k.shape[2] == 1 else np.einsum("mis,ms->is", k, r)
    for p in range(n - 1):
        f = a[p + 1:, p] / a[p, p]
        a[p + 1:, p + 1:] -= f[:, None] * a[p, p + 1:]
        x[p + 1:] -= f * x[p]
    for p in range(n - 1, -1, -1):
        if p < n - 1:
            x[p] -= np.sum(a[p, p + 1:] * x[p + 1:], 0)
        x[p] /= a[p, p]
    return x


def _passive(dof: int, act) -> np.ndarray:
    """The coordinates not in ``act``, sorted (not np.setdiff1d: it imports numpy.ma, start-up time)."""
    keep = np.ones(dof, dtype=bool)
    keep[np.asarray(act, dtype=int)] = False
    return np.flatnonzero(keep)


@dataclass(frozen=True, eq=False)
class ClosedStates:
    """Loop-closed samples, as returned by :func:`close_loops`.

    The kept samples' states and rates, and the counts of discarded samples.

    Parameters
    ----------
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Full tree coordinates, velocities and accelerations of the ``S`` kept samples.
    G : ndarray, shape ``(S, dof, na)``
        ``dq/dq_a``: ``dq = G dq_a``.
    cond : ndarray, shape ``(S,)``
        Condition number of ``K_p`` (the constraint Jacobian's passive columns).
    requested : int
        Number of samples asked for.
    not_converged : int
        Discarded as outside the workspace (Newton did not converge).
    branch_jumps : int
        Discarded as branch jumps: left the reference assembly mode, or crossed a singular
        configuration on the way (where branches may meet, so the branch is not known).
    ill_conditioned : int
        Discarded with ``cond(K_p) >= cond_max``.
    max_residual : float
        Largest loop residual of the kept samples (nan when none is kept).
    cond_max : float, optional
        The conditioning threshold used.
    motion : tuple of str, optional
        One line per group of coordinates sampled over its whole motion
        (:mod:`baseparams.kinematics.manifold`); empty when every sample was closed from the box.
    """

    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    G: np.ndarray
    cond: np.ndarray
    requested: int
    not_converged: int
    branch_jumps: int
    ill_conditioned: int
    max_residual: float
    cond_max: float = 30.0
    motion: tuple[str, ...] = ()

    __repr__ = summary_repr

    @property
    def kept(self) -> int:
        """Number of samples kept, ``S``."""
        return self.q.shape[0]


def close_loops(robot: Robot, qa: np.ndarray, dqa: np.ndarray | None = None, ddqa: np.ndarray | None = None,
                steps: int = 4, tol: float = 1e-11, max_iter: int = 15, cond_max: float = 30.0,
                max_step: float = 0.5, q_start: np.ndarray | None = None) -> ClosedStates:
    """Solve the loops for actuated samples ``qa (S, na)`` (coordinates ``robot.actuated``).

    Continuation from q = 0 (the reference assembly) in ``steps`` steps -- a tangent
    predictor, then damped Newton on the passive coordinates -- keeps every sample on the
    reference assembly mode; a sample whose corrected passive coordinates land more than
    ``max_step`` away from the prediction, or whose path crosses a singular configuration
    (``det(K_p^T K_p')`` between the ends of a step changes sign, :func:`_crossed`), is
    discarded as a branch jump, one that does not converge to ``tol`` is discarded as outside
    the workspace, and one with ``cond(K_p) > cond_max`` as ill-conditioned. The kept samples
    are refined by Newton to the rounding floor of their residual (:func:`_polish`): near a
    singularity the rates amplify the closure error. Velocities and accelerations are exact.

    Parameters
    ----------
    robot : Robot
        A robot with loops (``na = len(robot.actuated)`` actuated coordinates).
    qa : ndarray, shape ``(S, na)`` or ``(na,)``
        Actuated coordinates.
    dqa, ddqa : ndarray, shape ``(S, na)`` or ``(na,)``, optional
        Actuated velocities and accelerations; default zero.
    steps : int, optional
        Continuation steps from q = 0 (passive coordinates: from ``q_start`` when given).
    tol : float, optional
        Newton's tolerance on the largest residual (a sample is kept below ``max(100 tol, 1e-9)``).
    max_iter : int, optional
        Newton iterations per continuation step.
    cond_max : float, optional
        Conditioning threshold: samples above it are discarded as ill-conditioned (the paper's 30).
    max_step : float, optional
        Largest move of a passive coordinate from the predictor in one step (rad or m) before
        the sample counts as a branch jump.
    q_start : ndarray, shape ``(dof,)``, optional
        Initial guess of the passive coordinates (assembly search); default zero.

    Returns
    -------
    ClosedStates
        The kept samples in full tree coordinates, ``G = dq/dq_a``, ``cond(K_p)`` and the
        counts of discarded samples.

    Raises
    ------
    BaseparamsError
        ``qa`` with a number of columns other than ``na``.
    """
    act = np.asarray(robot.actuated, dtype=int)
    pas = _passive(robot.dof, act)
    qa = np.atleast_2d(np.asarray(qa, dtype=float))
    s = qa.shape[0]
    if qa.shape[1] != len(act):
        raise BaseparamsError(f"robot {robot.name!r}: expected {len(act)} actuated coordinates, got {qa.shape[1]}")
    dqa = np.zeros_like(qa) if dqa is None else np.broadcast_to(np.asarray(dqa, dtype=float), qa.shape)
    ddqa = np.zeros_like(qa) if ddqa is None else np.broadcast_to(np.asarray(ddqa, dtype=float), qa.shape)
    plan = _plan(robot, elementary_constraints(robot))
    q = np.zeros((s, robot.dof))
    if q_start is not None:  # initial guess of the passive coordinates (assembly search)
        q[:, pas] = np.asarray(q_start, dtype=float)[pas]
    elif len(pas):  # the reference's passive coordinates: 0, unless a coupling's offset moves them
        ref = np.zeros((1, robot.dof))
        f0, _, e0, _ = _continuation(plan, ref, np.zeros((1, len(act))), act, pas, 1, tol, max_iter, np.inf,
                                     crossing=False)
        if not f0[0] and e0[0] < max(tol * 100, 1e-9):
            q[:, pas] = ref[0, pas]
    # an assembly search (q_start) starts off the loops: no branch to keep, no crossing checked
    failed, jumped, err, k = _continuation(plan, q, qa, act, pas, steps, tol, max_iter, max_step,
                                           crossing=q_start is None)
    converged = (err < max(tol * 100, 1e-9)) & ~failed
    ok = np.flatnonzero(converged & ~jumped)  # conditioning of these
    k = np.ascontiguousarray(k[:, :, ok].transpose(2, 0, 1))  # (S', m, dof)
    cond = np.full(s, np.inf)
    cond[ok] = _conditioning(k[:, :, pas], len(pas))
    good_cond = cond < cond_max
    keep = converged & ~jumped & good_cond
    k = k[good_cond[ok]]
    kp_inv = _passive_pinv(k[:, :, pas], cond[keep])
    g, dq, ddq = _closed_rates(plan, q[keep], k, kp_inv, act, pas, dqa[keep], ddqa[keep])
    return ClosedStates(q[keep], dq, ddq, g, cond[keep], s,
                        int((~converged).sum()), int((converged & jumped).sum()),
                        int((converged & ~jumped & ~good_cond).sum()),
                        float(err[keep].max()) if keep.any() else float("nan"), float(cond_max))


def restrict(cs: ClosedStates, cond_max: float) -> ClosedStates:
    """The samples of ``cs`` with ``cond(K_p) < cond_max`` (the others counted as ill-conditioned).

    Parameters
    ----------
    cs : ClosedStates
        Closed samples (:func:`close_loops`), usually with a looser ``cond_max``.
    cond_max : float
        The new threshold (no looser than ``cs.cond_max``: the smaller is kept).

    Returns
    -------
    ClosedStates
        Same fields, kept samples only; ``max_residual`` of those.
    """
    cond_max = min(float(cond_max), cs.cond_max)
    keep = cs.cond < cond_max
    if keep.all():
        return ClosedStates(**{**cs.__dict__, "cond_max": cond_max})
    err = float(cs.max_residual) if keep.any() else float("nan")  # an upper bound for the subset
    return ClosedStates(cs.q[keep], cs.dq[keep], cs.ddq[keep], cs.G[keep], cs.cond[keep], cs.requested,
                        cs.not_converged, cs.branch_jumps, cs.ill_conditioned + int((~keep).sum()), err, cond_max,
                        cs.motion)


def closed_states(robot: Robot, q: np.ndarray, dqa: np.ndarray | None = None, ddqa: np.ndarray | None = None,
                  cond_max: float = 30.0, tol: float = 1e-9, rechart: bool = False) -> ClosedStates:
    """States at configurations already on the loops: exact rates from independent ``dq_a, ddq_a``.

    Samples whose largest loop residual is ``tol`` or more are discarded (counted as not
    converged), and those with ``cond(K_p) >= cond_max`` (ill-conditioned).

    Parameters
    ----------
    robot : Robot
        A robot with loops (``na = len(robot.actuated)``).
    q : ndarray, shape ``(S, dof)``
        Tree coordinates on the loops (e.g. :mod:`baseparams.kinematics.manifold`'s traces).
    dqa, ddqa : ndarray, shape ``(S, na)``, optional
        Independent velocities and accelerations; default zero.
    cond_max : float, optional
        Conditioning threshold.
    tol : float, optional
        Largest loop residual of a kept sample.
    rechart : bool, optional
        Each sample's independent coordinates chosen there (:func:`local_charts`: the actuated
        ones unless the passive Jacobian is better conditioned with others), so that a loop's
        whole motion is covered through the turning points of the actuated coordinates. The
        rows of a closed regressor are then each sample's own independent generalized forces:
        the same span per sample, so the same rank.

    Returns
    -------
    ClosedStates
        The kept samples, ``G = dq/dq_a`` (``rechart``: per sample, ``dq`` over that sample's
        independent coordinates) and the counts (no branch jumps: none is continued).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    s, na = q.shape[0], len(robot.actuated)
    dqa = np.zeros((s, na)) if dqa is None else np.asarray(dqa, dtype=float)
    ddqa = np.zeros((s, na)) if ddqa is None else np.asarray(ddqa, dtype=float)
    plan = _plan(robot, elementary_constraints(robot))
    r, k, _ = _eval(plan, q, np.arange(robot.dof))
    err = np.abs(r).max(axis=0) if len(r) else np.zeros(s)
    k = np.ascontiguousarray(k.transpose(2, 0, 1))
    charts = np.broadcast_to(np.asarray(robot.actuated, dtype=int), (s, na))
    if rechart:
        charts = local_charts(robot, k, cond_max)
    cond = np.empty(s)
    g, dq, ddq = np.zeros((s, robot.dof, na)), np.zeros((s, robot.dof)), np.zeros((s, robot.dof))
    for chart in np.unique(charts, axis=0):
        at = np.flatnonzero((charts == chart).all(axis=1))
        pas = _passive(robot.dof, chart)
        cond[at] = _conditioning(k[at][:, :, pas], len(pas))
        kp_inv = _passive_pinv(k[at][:, :, pas], cond[at])
        g[at], dq[at], ddq[at] = _closed_rates(plan, q[at], k[at], kp_inv, chart, pas, dqa[at], ddqa[at])
    on = err < tol
    keep = on & (cond < cond_max)
    return ClosedStates(q[keep], dq[keep], ddq[keep], g[keep], cond[keep], s, int((~on).sum()), 0,
                        int((on & ~keep).sum()), float(err[keep].max()) if keep.any() else float("nan"),
                        float(cond_max))


def local_charts(robot: Robot, k: np.ndarray, cond_max: float = 30.0) -> np.ndarray:
    """Each sample's independent coordinates ``(S, na)``: the actuated ones where they serve, else the best.

    The robot's actuated coordinates where the passive Jacobian ``K_p`` is conditioned below
    ``cond_max``; elsewhere (near a turning point of an actuated coordinate) the coordinates left
    by a column-pivoted QR of the sample's constraint Jacobian (the best-conditioned passive set,
    as :func:`choose_independent`); always ``na = len(robot.actuated)`` of them, sorted.

    Parameters
    ----------
    robot : Robot
        A robot with loops.
    k : ndarray, shape ``(S, m, dof)``
        The constraint Jacobian at each sample.
    cond_max : float, optional
        Conditioning up to which the actuated coordinates are kept.

    Returns
    -------
    ndarray of int, shape ``(S, na)``
        The independent coordinates of each sample.
    """
    from scipy.linalg import qr

    act = np.asarray(robot.actuated, dtype=int)
    na = len(act)
    out = np.tile(act, (k.shape[0], 1))
    pas = _passive(robot.dof, act)
    for i in np.flatnonzero(~(_conditioning(k[:, :, pas], len(pas)) < cond_max)):
        piv = qr(k[i], pivoting=True, mode="r")[1]
        out[i] = np.sort(piv[robot.dof - na:])
    return out


def _conditioning(kp: np.ndarray, npas: int) -> np.ndarray:
    """Condition number ``(S,)`` of ``K_p (S, m, npas)`` (singular values only)."""
    s = kp.shape[0]
    if not npas:
        return np.ones(s)
    sv = np.linalg.svd(kp, compute_uv=False)
    smin = sv[:, npas - 1] if sv.shape[1] >= npas else np.ones(s)
    return np.where(smin > 0, sv[:, 0] / np.where(smin > 0, smin, 1.0), np.inf)


#: below this cond(K_p), its pseudo-inverse is taken from the normal equations (error ~ cond^2 eps)
_NORMAL_COND = 100.0


def _passive_pinv(kp: np.ndarray, cond: np.ndarray) -> np.ndarray:
    """Pseudo-inverse ``(S, npas, m)`` of ``K_p (S, m, npas)`` with condition numbers ``cond (S,)``.

    ``(K_p^T K_p)^-1 K_p^T`` where ``K_p`` has full column rank and ``cond < 100``, the SVD
    elsewhere.
    """
    out = np.empty((kp.shape[0], kp.shape[2], kp.shape[1]))
    regular = (cond < _NORMAL_COND) & (kp.shape[1] >= kp.shape[2])
    if regular.any():
        kt = np.swapaxes(kp[regular], 1, 2)
        out[regular] = np.linalg.solve(kt @ kp[regular], kt)
    if not regular.all():
        out[~regular] = _pinv(kp[~regular])[0]
    return out


def _continuation(plan: _Plan, q: np.ndarray, qa: np.ndarray, act: np.ndarray, pas: np.ndarray,
                  steps: int, tol: float, max_iter: int, max_step: float, crossing: bool = True):
    """Move ``q (S, dof)`` in place from its start to the actuated targets ``qa``.

    In ``steps`` predictor-corrector steps. Returns ``(failed, jumped, err, K)``: flags ``(S,)``
    (no convergence, branch jump; with ``crossing``, a step across a singular configuration
    counts as one, :func:`_crossed`), and the largest residual ``(S,)`` and Jacobian
    ``(m, dof, S)`` at the final ``q`` of the samples that converged (inf and zero elsewhere).
    """
    s, dof = q.shape
    failed = np.zeros(s, dtype=bool)
    jumped = np.zeros(s, dtype=bool)
    err, k_all = np.full(s, np.inf), np.zeros((plan.m, dof, s))
    for step, t in enumerate(np.linspace(0, 1, steps + 1)[1:]):
        live = np.flatnonzero(~failed & ~jumped)
        if not len(live):
            break
        # predictor: follow the tangent of the solution curve, dq_p = -K_p^+ K_a dq_a; K at the
        # start (one configuration for all samples) or where the previous step converged
        ql = q[live]
        k = _eval(plan, ql[:1], np.arange(dof))[1] if step == 0 else k_all[:, :, live]
        dqa_step = t * qa[live] - ql[:, act]
        if k.shape[2] == 1:
            rhs = k[:, act, 0] @ dqa_step.T
        else:
            rhs = np.einsum("mjs,js->ms", k[:, act], dqa_step.T)
        pred = ql[:, pas] - _lstsq(k[:, pas], rhs).T if len(pas) else ql[:, pas]
        q[live[:, None], act] = t * qa[live]
        q[live[:, None], pas] = np.where(np.isfinite(pred), pred, ql[:, pas])
        start = q[live][:, pas]
        failed[_damped_newton(plan, q, live, pas, tol, max_iter, err, k_all)] = True
        moved = np.abs(q[live][:, pas] - start).max(axis=1, initial=0.0)
        jumped[live[(moved > max_step) & ~failed[live]]] = True
        # k: the Jacobian where the step started (a copy), k_all: where it converged
        if crossing:
            jumped[live[_crossed(k[:, pas], k_all[:, pas[:, None], live]) & ~failed[live]]] = True
    _polish(plan, q, np.flatnonzero(~failed & ~jumped), pas, err, k_all)
    return failed, jumped, err, k_all


def _crossed(kp_before: np.ndarray, kp_after: np.ndarray) -> np.ndarray:
    """Whether each continuation step crossed a singular configuration ``(S,)``.

    ``kp_before``, ``kp_after``: the passive Jacobians ``K_p (m, npas, S)`` at the ends of a step
    (``kp_before`` may be ``(m, npas, 1)``: one start for all). ``det(K_p,before^T K_p,after)``
    is positive for a step that stays on one side of every singularity (it is ``det(K_p^T K_p) > 0`` for a zero step);
    where a singular value of ``K_p`` passes through zero on the way it changes sign. Past such a
    point two assembly branches may meet (a parallelogram and its anti-parallelogram at the flat
    configuration), so the branch of the sample is not known: the caller discards it.
    """
    npas, s = kp_after.shape[1], kp_after.shape[2]
    if not npas:
        return np.zeros(s, dtype=bool)
    if kp_before.shape[2] not in (1, s):
        raise ValueError("kp_before must have one sample or as many as kp_after")
    m = np.einsum("mis,mjs->sij", np.broadcast_to(kp_before, kp_after.shape), kp_after)
    return ~(np.linalg.det(m) > 0)


def _polish(plan: _Plan, q: np.ndarray, idx: np.ndarray, pas: np.ndarray, err: np.ndarray, k_out: np.ndarray,
            iters: int = 3) -> None:
    """Newton steps past the tolerance on the converged samples ``idx`` of ``q (S, dof)``, in place.

    Near a singular configuration the rates amplify the closure error (``dq`` by ``cond(K_p)``,
    ``ddq`` by about its square): each sample is refined to the rounding floor of its residual.
    A step is kept only where it lowers the sample's largest residual; ``err (S,)`` and the
    Jacobian ``k_out (m, dof, S)`` follow.
    """
    cols = np.arange(q.shape[1])
    for _ in range(iters):
        if not len(idx) or not len(pas):
            return
        r, k, _ = _eval(plan, q[idx], cols)
        trial = q[idx].copy()
        st = -_lstsq(k[:, pas[:, None], np.arange(len(idx))], r).T
        trial[:, pas] += np.where(np.isfinite(st), st, 0.0)
        r2, k2, _ = _eval(plan, trial, cols)
        e2 = np.abs(r2).max(axis=0) if len(r2) else np.zeros(len(idx))
        better = e2 < err[idx]
        q[idx[better]] = trial[better]
        err[idx[better]] = e2[better]
        k_out[:, :, idx[better]] = k2[:, :, better]
        idx = idx[better & (e2 > 0)]


def _damped_newton(plan: _Plan, q: np.ndarray, live: np.ndarray, pas: np.ndarray, tol: float,
                   max_iter: int, err_out: np.ndarray, k_out: np.ndarray) -> np.ndarray:
    """Correct the passive coordinates of samples ``live`` of ``q`` in place.

    The samples that did not converge within ``max_iter`` (outside the workspace) are returned;
    for those that did, the largest residual and the Jacobian ``(m, dof)`` at the solution are
    written to ``err_out`` and ``k_out``.

    Damped Newton on the samples still iterating (``idx`` shrinks): a step that does not reduce
    the residual is halved and retried from the previous iterate (its Newton step is not needed).
    """
    cols = np.arange(q.shape[1])
    idx, sub = live, q[live]
    prev_sub, prev_err, prev_step = sub.copy(), np.full(len(idx), np.inf), np.zeros((len(idx), len(pas)))
    lam = np.ones(len(idx))
    for _ in range(max_iter):
        r, k, _ = _eval(plan, sub, cols)
        err = np.abs(r).max(axis=0) if len(r) else np.zeros(len(idx))
        done = err < tol
        q[idx[done]] = sub[done]
        err_out[idx[done]] = err[done]
        k_out[:, :, idx[done]] = k[:, :, done]
        worse = ~done & (err > prev_err)
        keep = ~done
        idx, sub, err, worse = idx[keep], sub[keep], err[keep], worse[keep]
        prev_sub, prev_err, prev_step, lam = prev_sub[keep], prev_err[keep], prev_step[keep], lam[keep]
        if not len(idx):
            break
        step = np.zeros((len(idx), len(pas)))
        go = np.flatnonzero(keep)[~worse]
        if len(go):
            st = -_lstsq(k[:, pas[:, None], go], r[:, go]).T
            step[~worse] = np.where(np.isfinite(st), np.clip(st, -1.0, 1.0), 0.0)
        # rejected samples: back to the previous iterate with half the previous step
        lam = np.where(worse, lam * 0.5, np.minimum(1.0, lam * 2.0))
        base = np.where(worse[:, None], prev_sub[:, pas], sub[:, pas])
        use = np.where(worse[:, None], prev_step, step)
        prev_sub = np.where(worse[:, None], prev_sub, sub)
        prev_err = np.where(worse, prev_err, err)
        prev_step = use
        sub = sub.copy()
        sub[:, pas] = base + lam[:, None] * use
    q[idx] = sub
    return idx


def _closed_rates(plan: _Plan, q: np.ndarray, k: np.ndarray, kp_inv: np.ndarray, act: np.ndarray, pas: np.ndarray,
                  dqa: np.ndarray, ddqa: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact closed-loop rates at ``q``: ``G (S, dof, na)`` with ``dq = G dqa``, ``dq`` and ``ddq``.

    ``K (S, m, dof)`` is the constraint Jacobian, ``kp_inv`` the pseudo-inverse of its passive part.
    """
    g = np.zeros((q.shape[0], q.shape[1], len(act)))
    g[:, act, np.arange(len(act))] = 1.0
    g[:, pas] = -kp_inv @ k[:, :, act]
    dq = np.einsum("sij,sj->si", g, dqa)
    _, _, bias = _eval(plan, q, act[:0], dq)
    ddq = np.zeros_like(q)
    ddq[:, act] = ddqa
    ddq[:, pas] = -np.einsum("sij,sj->si", kp_inv, np.einsum("sij,sj->si", k[:, :, act], ddqa) + bias.T)
    return g, dq, ddq


def assemble(robot: Robot, cond_max: float = 1e6, tol: float = 1e-10) -> tuple[Robot, np.ndarray, str]:
    """A regular, assembled reference configuration for a loop robot.

    If the loop frames coincide at q = 0 and ``K_p`` is regular there, the robot is returned
    unchanged. Otherwise the loops are closed by Newton from q = 0 with the actuated
    coordinates at 0 (or, when q = 0 is a singular configuration, at small offsets), and the
    robot is re-referenced there (its new q = 0; ``q_box`` shifted). Returns the robot, the
    reference in the old coordinates, and a note for the user ('' when nothing was done).

    Parameters
    ----------
    robot : Robot
        The robot (returned unchanged without loops).
    cond_max : float, optional
        ``cond(K_p)`` at or above which a configuration counts as singular.
    tol : float, optional
        Largest loop residual at q = 0 for the frames to coincide.

    Returns
    -------
    robot : Robot
        The assembled robot (re-referenced, ``q_box`` shifted; when q = 0 was singular, the box
        is also cut to ``+-|offset| / 2`` so that samples stay on this side of the singular
        configuration).
    qref : ndarray, shape ``(dof,)``
        The new reference in the old coordinates (zero when nothing was done).
    note : str
        Why and where the robot was re-referenced ('' when nothing was done).

    Raises
    ------
    ModelError
        No regular assembled configuration found near q = 0 (actuated offsets up to +-0.3, from
        q = 0 and 20 random starts), or one that needs re-referencing a robot with S joints;
        :class:`~baseparams.errors.NoMotionError` when the constraints leave no motion.
    """
    from dataclasses import replace

    if not robot.has_loops:
        return robot, np.zeros(robot.dof), ""
    act = robot.actuated
    pas = _passive(robot.dof, act)
    ev = evaluate(robot, np.zeros((1, robot.dof)))
    res0 = float(np.abs(ev.r).max()) if ev.r.size else 0.0
    if res0 < tol and _jacobian_rank(ev.K[0])[0] >= robot.dof:  # assembled and locked: no rank nearby is higher
        raise no_motion(robot, robot.dof)
    sv = np.linalg.svd(ev.K[0][:, pas], compute_uv=False) if len(pas) else np.ones(1)
    if not len(pas):
        cond0 = 1.0
    elif len(sv) < len(pas) or sv[len(pas) - 1] <= 0:
        cond0 = np.inf  # fewer independent constraints than passive coordinates
    else:
        cond0 = sv[0] / sv[len(pas) - 1]
    if res0 < tol and any(lj.anchor_free for lj in robot.loops) and "S" not in robot.jtype:
        moved = _free_anchor_reference(robot, ev.K[0], cond0, cond_max, tol)
        if moved is not None:
            return moved
    if res0 < tol and cond0 < cond_max:
        found = _regular_nearby(robot, ev.K[0], tol) if "S" not in robot.jtype and robot.loops else None
        if found is None:
            return robot, np.zeros(robot.dof), ""
        return _re_referenced_regular(robot, *found, cond_max)
    if not robot.loops:  # couplings alone: an offset moves a driven joint away from 0
        moved = [robot.joint_names[robot.dof_body[c.succ]] for c in robot.couplings if c.offset]
        why = f"the couplings' offsets move joints {moved} at q = 0"
    else:
        why = (f"the loop frames do not coincide at q = 0 (residual {res0:.3g})" if res0 >= tol
               else f"q = 0 is a singular configuration of the loops (cond(J_p) = {cond0:.3g})")
    rng = np.random.default_rng(0)
    starts = [np.zeros(robot.dof)] + [rng.uniform(-1.0, 1.0, robot.dof) for _ in range(20)]
    singular = res0 < tol  # assembled but singular: move away from the singular point
    offsets = (0.3, -0.3, 0.2, -0.2, 0.1, -0.1) if singular else (0.0, 0.1, -0.1, 0.2, -0.2)
    tries = [(off, st) for off in offsets for st in starts]
    for offset, start in tries:
        qa = np.full((1, len(act)), offset)
        cs = close_loops(robot, qa, steps=10, cond_max=cond_max, max_step=np.inf, max_iter=50, q_start=start)
        if cs.kept:
            qref = cs.q[0]
            new = re_reference(robot, qref) if "S" not in robot.jtype else None
            if new is None:
                raise ModelError(f"robot {robot.name!r}: {why}; re-referencing with S joints is not supported")
            box = None if robot.q_box is None else robot.q_box - qref[act][:, None]
            if singular:  # sample on this side of the singular configuration only
                half = np.full((len(act), 2), [-abs(offset) / 2, abs(offset) / 2])
                box = half if box is None else np.column_stack([np.maximum(box[:, 0], half[:, 0]),
                                                               np.minimum(box[:, 1], half[:, 1])])
            new = replace(new, q_box=box)
            note = (f"{why}; assembled and re-referenced at actuated coordinates {np.round(qref[act], 4).tolist()} "
                    f"(passive {np.round(qref[pas], 4).tolist()}): q = 0 now means this configuration")
            return new, qref, note
    raise ModelError(f"robot {robot.name!r}: {why}, and no regular assembled configuration was found near it; "
                      f"check the loop frames and the independent joints")




#: perturbation sizes (rad or m) tried, smallest first, when looking for a regular configuration near q = 0
NEARBY_SCALES = (0.02, 0.05, 0.1, 0.2, 0.4)
#: perturbations tried per size
NEARBY_TRIES = 6
#: sizes and tries when looking for a higher rank of the loops' Jacobian near an assembled q = 0 (every loop file)
RANK_SCALES = (0.05, 0.2)
RANK_TRIES = 3
#: a re-anchored reference whose cond(J_p) is below this (the paper's 30, ``numerics.COND_MAX``) ends the search
REGULAR_COND = 30.0


def _jacobian_rank(k: np.ndarray, rtol: float = 1e-8) -> tuple[int, float]:
    """``(rank, smallest kept singular value / largest)`` of a constraint Jacobian ``(m, dof)``."""
    sv = np.linalg.svd(k, compute_uv=False)
    if not len(sv) or sv[0] <= 0:
        return 0, 1.0
    rank = int(np.sum(sv > rtol * sv[0]))
    return rank, float(sv[rank - 1] / sv[0]) if rank else 1.0


def _project(robot: Robot, q: np.ndarray, tol: float, iters: int = 60) -> np.ndarray | None:
    """``q (dof,)`` moved onto the loops and couplings by Gauss-Newton on every coordinate (minimum-norm steps)."""
    for _ in range(iters):
        ev = evaluate(robot, q[None])
        if not ev.r.size or np.abs(ev.r).max() < tol:
            return q
        q = q - np.linalg.lstsq(ev.K[0], ev.r[0], rcond=None)[0]
    return None


def _regular_nearby(robot: Robot, k0: np.ndarray, tol: float) -> tuple[np.ndarray, int, int] | None:
    """An assembled configuration near q = 0 where the constraint Jacobian has a higher rank, or None.

    At a configuration where branches of the mechanism meet (coaxial joint axes of a welded arm,
    a straight arm), ``K`` loses rank: the coordinates chosen there as independent are too many,
    and samples continued from it stay on the singular set. From perturbed configurations (sizes
    :data:`RANK_SCALES`, smallest first, :data:`RANK_TRIES` each, seeded), Gauss-Newton on
    every coordinate returns to the loops; the first size where some point has a higher rank
    gives the best-conditioned of them. Returns ``(q (dof,), rank there, rank at q = 0)``.
    """
    r0, _ = _jacobian_rank(k0)
    if r0 == 0 or r0 >= robot.dof:
        return None
    rng = np.random.default_rng(0)
    for scale in RANK_SCALES:  # the rank nearby is generic: a few points tell
        best = None
        for _ in range(RANK_TRIES):
            q = _project(robot, rng.normal(scale=scale, size=robot.dof), tol)
            if q is None:
                continue
            rank, quality = _jacobian_rank(evaluate(robot, q[None]).K[0])
            if rank > r0 and (best is None or (rank, quality) > (best[1], best[2])):
                best = (q, rank, quality)
        if best is not None:
            return best[0], best[1], r0
    return None


def _free_anchor_reference(robot: Robot, k0: np.ndarray, cond0: float, cond_max: float,
                           tol: float) -> tuple[Robot, np.ndarray, str] | None:
    """Loops to a control device (a mocap weld) off a singular reference: the device placed where the hand is.

    A mocap body is moved by the simulation; where the file puts it only fixes the reference. When
    q = 0 is singular (``cond(J_p)`` at least ``cond_max``, or the constraint Jacobian gains rank at
    perturbed configurations: a straight arm welded where it is), configurations perturbed from
    q = 0 (sizes :data:`NEARBY_SCALES`, inside the joint ranges where known, the other loops and
    couplings closed again by Gauss-Newton) are tried with each free anchor placed at its
    successor's frame there; the first size with a configuration whose passive conditioning is
    below :data:`REGULAR_COND` gives the best one (else the best of all).
    Returns None when q = 0 is not singular.
    """
    from dataclasses import replace

    r0, _ = _jacobian_rank(k0)
    others = replace(robot, loops=tuple(lj for lj in robot.loops if not lj.anchor_free))
    lim = None if robot.limits is None else robot.limits[:, :2]
    rng = np.random.default_rng(0)
    best = None
    for scale in NEARBY_SCALES[1:]:
        for _ in range(NEARBY_TRIES):
            q = rng.normal(scale=scale, size=robot.dof)
            if lim is not None:
                ok = np.all(np.isfinite(lim), axis=1)
                pad = 0.05 * (lim[ok, 1] - lim[ok, 0])
                q[ok] = np.clip(q[ok], lim[ok, 0] + pad, lim[ok, 1] - pad)
            q = _project(others, q, tol)
            if q is None:
                continue
            moved = re_reference(robot, q)
            moved = replace(moved, q_box=None, loops=tuple(
                replace(lj, M=lj.M if lj.M_child is None else lj.M_child, M_child=None) if lj.anchor_free else lj
                for lj in moved.loops))
            rank, _ = _jacobian_rank(evaluate(moved, np.zeros((1, robot.dof))).K[0])
            moved = choose_independent(moved, set(robot.independent or ()))
            pas = _passive(robot.dof, moved.actuated)
            cond = _conditioning(evaluate(moved, np.zeros((1, robot.dof))).K[:, :, pas], len(pas))[0] if len(pas) \
                else 1.0
            if best is None or (rank, -cond) > (best[2], -best[3]):
                best = (moved, q, rank, cond)
        if best is not None and best[3] < REGULAR_COND:
            break
    if best is None or not (best[2] > r0 or cond0 >= cond_max) or not best[3] < cond_max:
        return None
    moved, q, rank, cond = best
    names = [robot.joint_names[robot.dof_body[j]] for j in moved.actuated]
    anchors = [lj.name for lj in robot.loops if lj.anchor_free]
    note = (f"q = 0 is a singular configuration of the loops (constraint Jacobian of rank {r0}, cond(J_p) "
            f"{cond0:.3g}); the loops to a control device ({', '.join(anchors)}: a mocap body, placed by the "
            f"simulation) re-anchored where the hand is at a regular configuration nearby ({np.abs(q).max():.3g} rad "
            f"or m away, inside the joint ranges; rank {rank}, cond(J_p) {cond:.3g}), independent coordinates "
            f"{names}: q = 0 now means this configuration ({np.round(q, 4).tolist()} in the file's coordinates)")
    return moved, q, note


def _re_referenced_regular(robot: Robot, qref: np.ndarray, rank: int, rank0: int,
                           cond_max: float) -> tuple[Robot, np.ndarray, str]:
    """``robot`` re-referenced at the regular configuration ``qref``, its independent coordinates chosen again."""
    from dataclasses import replace

    moved = replace(re_reference(robot, qref), q_box=None)
    if rank != rank0 or robot.independent is None:
        moved = choose_independent(moved, set(robot.independent or ()))
    names = [robot.joint_names[robot.dof_body[j]] for j in moved.actuated]
    cond = _conditioning(evaluate(moved, np.zeros((1, robot.dof))).K[:, :, _passive(robot.dof, moved.actuated)],
                         robot.dof - len(moved.actuated))[0]
    if not cond < cond_max:
        raise ModelError(f"robot {robot.name!r}: the loops are singular at q = 0 (constraint Jacobian of rank {rank0}, "
                         f"{rank} nearby) and no regular reference was found near it; move the file's reference "
                         f"(qpos0) off the singular configuration")
    note = (f"the loops are singular at q = 0 (constraint Jacobian of rank {rank0}, {rank} at assembled configurations "
            f"nearby: branches of the mechanism meet there); re-referenced at a regular assembled configuration found "
            f"nearby (Newton from perturbed configurations, {np.abs(qref).max():.3g} rad or m away; cond(J_p) "
            f"{cond:.3g}), independent coordinates {names}: q = 0 now means this configuration "
            f"({np.round(qref, 4).tolist()} in the file's coordinates)")
    return moved, qref, note


def choose_independent(robot: Robot, prefer_independent: set[int] | None = None, rtol: float = 1e-9) -> Robot:
    """The same robot with independent coordinates chosen from the loop constraints at q = 0.

    For files that do not say which coordinates are independent (MJCF): the passive set is a
    maximal set of coordinates whose constraint-Jacobian columns are independent, picked
    greedily, coordinates in ``prefer_independent`` (e.g. actuated joints) last.

    Parameters
    ----------
    robot : Robot
        A robot with loops.
    prefer_independent : set of int, optional
        Coordinates to keep independent where possible (down-weighted 1000x in the column-pivoted
        QR of the constraint Jacobian at q = 0).
    rtol : float, optional
        Rank threshold relative to the largest ``|R_ii|`` of the QR.

    Returns
    -------
    Robot
        The robot with ``independent`` set (the coordinates outside the passive set) and
        ``q_box`` reset to None.

    Raises
    ------
    NoMotionError
        The constraints leave no coordinate independent (:func:`no_motion`).
    """
    from dataclasses import replace

    from scipy.linalg import qr

    ev = evaluate(replace(robot, independent=tuple(range(robot.dof))), np.zeros((1, robot.dof)))
    k = ev.K[0]
    prefer = prefer_independent or set()
    # column-pivoted QR picks well-conditioned passive columns; preferred-independent
    # coordinates are down-weighted so that they are picked only when needed
    weight = np.array([1e-3 if j in prefer else 1.0 for j in range(robot.dof)])
    _, r, piv = qr(k * weight, pivoting=True, mode="economic")
    diag = np.abs(np.diag(r))
    rank = int(np.sum(diag > rtol * max(diag.max(initial=0.0), 1e-300)))
    passive = set(int(j) for j in piv[:rank])
    independent = tuple(j for j in range(robot.dof) if j not in passive)
    if not independent:
        raise no_motion(robot, rank)
    return replace(robot, independent=independent, q_box=None)


def no_motion(robot: Robot, rank: int) -> NoMotionError:
    """The error for a mechanism its constraints lock: one line naming them and what would help.

    Parameters
    ----------
    robot : Robot
        The robot (``dof`` coordinates).
    rank : int
        Rank of its constraint Jacobian (``dof``: no motion left).

    Returns
    -------
    NoMotionError
        ``robot NAME: the constraints (...) leave this mechanism no motion ...``.
    """
    names = [lj.name for lj in robot.loops] + [c.name for c in robot.couplings]
    free = [lj.name for lj in robot.loops if lj.anchor_free]
    hint = (f"{', '.join(free)} {'ties' if len(free) == 1 else 'tie'} a body to a control device (a mocap body): "
            f"leave {'it' if len(free) == 1 else 'them'} out (mocap_welds='drop', --mocap-welds drop)" if free
            else "remove a constraint, or check the loop frames and the joints' axes")
    return NoMotionError(f"robot {robot.name!r}: the constraints ({', '.join(names)}) leave this mechanism no motion "
                         f"(their Jacobian has rank {rank} on its {robot.dof} coordinates): every body is held still, "
                         f"so "
                         f"no measurement sees any inertial parameter; {hint}")
