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

from ..errors import BaseparamsError, ModelError
from ..model.robot import Robot
from ..pga import hat
from ..pga.linalg import cross3, perp_basis
from .tree import forward_kinematics, re_reference


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


def _body_data(state, body: int, s: int, dof: int):
    if body < 0:
        eye = np.broadcast_to(np.eye(4), (s, 4, 4))
        z6 = np.zeros((s, 6))
        return eye, z6, z6, np.zeros((s, dof, 6))
    lines = state.lines * state.support[None, :, body, None]
    return state.g[:, body], state.V[:, body], state.dV[:, body], lines


def _moving(state, body, x, s, dof, need_bias):
    """Current vector X, its per-dof velocities (S, dof, 4), its velocity and bias acceleration."""
    g, v, dv, lines = _body_data(state, body, s, dof)
    xw = np.einsum("sij,j->si", g, x)
    # velocity of X under each line: omega x X + w v  (commutator with the line)
    om, lv = lines[..., :3], lines[..., 3:]
    vel = cross3(om, xw[:, None, :3]) + x[3] * lv  # (S, dof, 3)
    vel = np.concatenate([vel, np.zeros(vel.shape[:-1] + (1,))], axis=-1)
    if not need_bias:
        return xw, vel, None, None
    vh = hat(v)
    xdot = np.einsum("sij,sj->si", vh, xw)
    acc = np.einsum("sij,sj->si", hat(dv) + vh @ vh, xw)
    return xw, vel, xdot, acc


def evaluate(robot: Robot, q: np.ndarray, dq: np.ndarray | None = None,
             constraints: list[Elementary] | None = None) -> ConstraintEval:
    """Residuals, Jacobian and (when ``dq`` is given) the bias of the loop constraints.

    The rows are the couplings' (linear: ``q[succ] - sum ratio q[pred] - offset``) first, then
    the elementary constraints' in order.

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
    cons = elementary_constraints(robot) if constraints is None else constraints
    s, dof = q.shape
    need = dq is not None
    state = forward_kinematics(robot, q, dq if need else None, None)
    rs, ks, bs = [], [], []
    for c in robot.couplings:  # linear: q[succ] - sum ratio q[pred] - offset = 0
        k = np.zeros((s, 1, dof))
        k[:, 0, c.succ] = 1.0
        for j, r in c.terms():
            k[:, 0, j] -= r
        rs.append(q @ k[0, 0][:, None] - c.offset)
        ks.append(k)
        if need:
            bs.append(np.zeros((s, 1)))
    for e in cons:
        if e.kind == "point":
            xc, vc, dc, ac = _moving(state, e.succ, e.b, s, dof, need)
            xp, vp, dp, ap = _moving(state, e.pred, e.a, s, dof, need)
            rs.append((xc - xp)[:, :3])
            ks.append(np.swapaxes(vc - vp, 1, 2)[:, :3])
            if need:
                bs.append((ac - ap)[:, :3])
        elif e.kind == "dot":
            u, vu, du, au = _moving(state, e.pred, e.a, s, dof, need)
            w, vw, dw, aw = _moving(state, e.succ, e.b, s, dof, need)
            rs.append(np.sum(u * w, -1)[:, None])
            ks.append((np.einsum("sjc,sc->sj", vu, w) + np.einsum("sc,sjc->sj", u, vw))[:, None])
            if need:
                bs.append((np.sum(au * w, -1) + 2 * np.sum(du * dw, -1) + np.sum(u * aw, -1))[:, None])
        elif e.kind == "proj":
            n_, vn, dn, an = _moving(state, e.pred, e.a, s, dof, need)
            xc, vc, dc, ac = _moving(state, e.succ, e.c, s, dof, need)
            xp, vp, dp, ap = _moving(state, e.pred, e.b, s, dof, need)
            d = xc - xp
            rs.append(np.sum(n_ * d, -1)[:, None])
            ks.append((np.einsum("sjc,sc->sj", vn, d) + np.einsum("sc,sjc->sj", n_, vc - vp))[:, None])
            if need:
                bs.append((np.sum(an * d, -1) + 2 * np.sum(dn * (dc - dp), -1)
                           + np.sum(n_ * (ac - ap), -1))[:, None])
    if not rs:
        return ConstraintEval(np.zeros((s, 0)), np.zeros((s, 0, dof)), np.zeros((s, 0)) if need else None)
    return ConstraintEval(np.concatenate(rs, 1), np.concatenate(ks, 1), np.concatenate(bs, 1) if need else None)


def _pinv(k: np.ndarray, rcond: float = 1e-10) -> tuple[np.ndarray, np.ndarray]:
    """Batched pseudo-inverse and singular values of ``k (S, m, n)``."""
    u, s, vt = np.linalg.svd(k, full_matrices=False)
    cut = rcond * s[..., :1]
    sinv = np.where(s > cut, 1.0 / np.where(s > cut, s, 1.0), 0.0)
    return np.einsum("sji,sj,skj->sik", vt, sinv, u), s


def _lstsq(k: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Batched least-squares step ``k x ~ r`` by regularised normal equations.

    Newton only; redundant rows are fine, a rank-deficient ``k`` gets a tiny Tikhonov term.
    """
    ktk = np.einsum("smi,smj->sij", k, k)
    eps = 1e-12 * np.trace(ktk, axis1=1, axis2=2)[:, None, None] + 1e-300
    return np.linalg.solve(ktk + eps * np.eye(k.shape[2]), np.einsum("smi,sm->si", k, r)[..., None])[..., 0]


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
        Discarded as branch jumps (left the reference assembly mode).
    ill_conditioned : int
        Discarded with ``cond(K_p) >= cond_max``.
    max_residual : float
        Largest loop residual of the kept samples (nan when none is kept).
    cond_max : float, optional
        The conditioning threshold used.
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
    ``max_step`` away from the prediction is discarded as a branch jump, one that does not
    converge to ``tol`` is discarded as outside the workspace, and one with
    ``cond(K_p) > cond_max`` as ill-conditioned. Velocities and accelerations are exact.

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
    pas = np.setdiff1d(np.arange(robot.dof), act)
    qa = np.atleast_2d(np.asarray(qa, dtype=float))
    s = qa.shape[0]
    if qa.shape[1] != len(act):
        raise BaseparamsError(f"robot {robot.name!r}: expected {len(act)} actuated coordinates, got {qa.shape[1]}")
    dqa = np.zeros_like(qa) if dqa is None else np.atleast_2d(np.asarray(dqa, dtype=float))
    ddqa = np.zeros_like(qa) if ddqa is None else np.atleast_2d(np.asarray(ddqa, dtype=float))
    cons = elementary_constraints(robot)
    q = np.zeros((s, robot.dof))
    if q_start is not None:  # initial guess of the passive coordinates (assembly search)
        q[:, pas] = np.asarray(q_start, dtype=float)[pas]
    failed, jumped = _continuation(robot, q, qa, act, pas, cons, steps, tol, max_iter, max_step)
    ev = evaluate(robot, q, constraints=cons)
    err = np.abs(ev.r).max(axis=1) if ev.r.shape[1] else np.zeros(s)
    converged = (err < max(tol * 100, 1e-9)) & ~failed
    kp_inv, sv = _pinv(ev.K[:, :, pas])
    npas = len(pas)
    smin = sv[:, npas - 1] if sv.shape[1] >= npas and npas else np.ones(s)
    cond = np.where(smin > 0, sv[:, 0] / np.where(smin > 0, smin, 1.0), np.inf) if npas else np.ones(s)
    good_cond = cond < cond_max
    keep = converged & ~jumped & good_cond
    g, dq, ddq = _closed_rates(robot, q, ev.K, kp_inv, act, pas, dqa, ddqa, cons)
    return ClosedStates(q[keep], dq[keep], ddq[keep], g[keep], cond[keep], s,
                        int((~converged).sum()), int((converged & jumped).sum()),
                        int((converged & ~jumped & ~good_cond).sum()),
                        float(err[keep].max()) if keep.any() else float("nan"), float(cond_max))


def _continuation(robot: Robot, q: np.ndarray, qa: np.ndarray, act: np.ndarray, pas: np.ndarray, cons: list,
                  steps: int, tol: float, max_iter: int, max_step: float) -> tuple[np.ndarray, np.ndarray]:
    """Move ``q (S, dof)`` in place from its start to the actuated targets ``qa``.

    In ``steps`` predictor-corrector steps; ``(failed, jumped)`` flags ``(S,)``: no convergence,
    branch jump.
    """
    s = q.shape[0]
    failed = np.zeros(s, dtype=bool)
    jumped = np.zeros(s, dtype=bool)
    for t in np.linspace(0, 1, steps + 1)[1:]:
        live = np.flatnonzero(~failed & ~jumped)
        if not len(live):
            break
        # predictor: follow the tangent of the solution curve, dq_p = -K_p^+ K_a dq_a
        ev = evaluate(robot, q[live], constraints=cons)
        dqa_step = t * qa[live] - q[live][:, act]
        rhs = np.einsum("smj,sj->sm", ev.K[:, :, act], dqa_step)
        pred = q[live][:, pas] - _lstsq(ev.K[:, :, pas], rhs) if len(pas) else q[live][:, pas]
        q[live[:, None], act] = t * qa[live]
        q[live[:, None], pas] = np.where(np.isfinite(pred), pred, q[live][:, pas])
        start = q[live][:, pas]
        failed[_damped_newton(robot, q, live, pas, cons, tol, max_iter)] = True
        moved = np.abs(q[live][:, pas] - start).max(axis=1, initial=0.0)
        jumped[live[(moved > max_step) & ~failed[live]]] = True
    return failed, jumped


def _damped_newton(robot: Robot, q: np.ndarray, live: np.ndarray, pas: np.ndarray, cons: list, tol: float,
                   max_iter: int) -> np.ndarray:
    """Correct the passive coordinates of samples ``live`` of ``q`` in place.

    The samples that did not converge within ``max_iter`` (outside the workspace) are returned.

    Damped Newton on the samples still iterating (``idx`` shrinks): a step that does not reduce
    the residual is halved and retried from the previous iterate.
    """
    idx, sub = live, q[live]
    prev_sub, prev_err, prev_step = sub.copy(), np.full(len(idx), np.inf), np.zeros((len(idx), len(pas)))
    lam = np.ones(len(idx))
    for _ in range(max_iter):
        ev = evaluate(robot, sub, constraints=cons)
        err = np.abs(ev.r).max(axis=1) if ev.r.shape[1] else np.zeros(len(idx))
        done = err < tol
        q[idx[done]] = sub[done]
        worse = ~done & (err > prev_err)
        keep = ~done
        idx, sub, err, worse = idx[keep], sub[keep], err[keep], worse[keep]
        prev_sub, prev_err, prev_step, lam = prev_sub[keep], prev_err[keep], prev_step[keep], lam[keep]
        if not len(idx):
            break
        k_keep = ev.K[keep][:, :, pas]
        r_keep = ev.r[keep]
        step = -_lstsq(k_keep, r_keep)
        step = np.where(np.isfinite(step), np.clip(step, -1.0, 1.0), 0.0)
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


def _closed_rates(robot: Robot, q: np.ndarray, k: np.ndarray, kp_inv: np.ndarray, act: np.ndarray, pas: np.ndarray,
                  dqa: np.ndarray, ddqa: np.ndarray, cons: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact closed-loop rates at ``q``: ``G (S, dof, na)`` with ``dq = G dqa``, ``dq`` and ``ddq``.

    ``K (S, m, dof)`` is the constraint Jacobian, ``kp_inv`` the pseudo-inverse of its passive part.
    """
    g = np.zeros((q.shape[0], robot.dof, len(act)))
    g[:, act, np.arange(len(act))] = 1.0
    g[:, pas] = -kp_inv @ k[:, :, act]
    dq = np.einsum("sij,sj->si", g, dqa)
    ev2 = evaluate(robot, q, dq, constraints=cons)
    ddq = np.zeros_like(q)
    ddq[:, act] = ddqa
    ddq[:, pas] = -np.einsum("sij,sj->si", kp_inv, np.einsum("sij,sj->si", ev2.K[:, :, act], ddqa) + ev2.b)
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
        q = 0 and 20 random starts), or one that needs re-referencing a robot with S joints.
    """
    from dataclasses import replace

    if not robot.has_loops:
        return robot, np.zeros(robot.dof), ""
    act = robot.actuated
    pas = np.setdiff1d(np.arange(robot.dof), act)
    ev = evaluate(robot, np.zeros((1, robot.dof)))
    res0 = float(np.abs(ev.r).max()) if ev.r.size else 0.0
    sv = np.linalg.svd(ev.K[0][:, pas], compute_uv=False) if len(pas) else np.ones(1)
    if not len(pas):
        cond0 = 1.0
    elif len(sv) < len(pas) or sv[len(pas) - 1] <= 0:
        cond0 = np.inf  # fewer independent constraints than passive coordinates
    else:
        cond0 = sv[0] / sv[len(pas) - 1]
    if res0 < tol and cond0 < cond_max:
        return robot, np.zeros(robot.dof), ""
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
    return replace(robot, independent=independent, q_box=None)
