"""Tree kinematics batched over samples.

Body displacements, twists, accelerations and the Jacobian lines ``L_j^i`` of the paper
(eq. "jacobian line").

Spatial assignment (paper, Sec. "Spatial assignment of tetrahedral points"): every body's
tetrahedral points coincide with the world frame at q = 0, so a body's state is its
displacement ``g_i (4, 4)`` from its pose at q = 0 (world frame), its spatial twist
``V_i = (omega, v)`` and acceleration ``dV_i`` (world frame, no gravity).

Product of exponentials: ``g_i = g_parent exp(S_1 q_1) ... exp(S_k q_k)`` with ``S`` the
joint lines at q = 0 (:attr:`Robot.screws`). The current line of coordinate ``k`` is
``L_k = Ad(g_parent exp(S_1 q_1) .. exp(S_{k-1} q_{k-1})) S_k``; ``V_i = V_p + sum L_k dq_k``;
``dV_i = dV_p + sum ad(V_{k}) L_k dq_k + L_k ddq_k``. The floating (F) root uses
quasi-velocities: ``L_k = e_k`` and ``V = dq`` (the paper's Go2 section).

:func:`forward_kinematics` returns samples first (``TreeState``); :func:`poses` computes the same
with samples last (``Poses``: each component a contiguous row), for the bodies asked for only,
by closed-form screw products -- the loop-closure solver's hot path.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, replace

import numpy as np

from ..display import summary_repr
from ..errors import BaseparamsError, ModelError
from ..model.robot import Robot
from ..pga import adjoint, commutator, inverse_transform, se3_exp
from ..pga.core import screw_exp
from ..pga.linalg import cross3_first, skew


@dataclass(frozen=True, eq=False)
class TreeState:
    """Kinematic state of all bodies for ``S`` samples.

    Made by :func:`forward_kinematics`. Twists, accelerations and lines are ``(omega, v)`` in the
    world frame (``v`` the velocity of the point at the world origin).

    Parameters
    ----------
    g : ndarray, shape ``(S, n, 4, 4)``
        Displacements from q = 0 (world frame): a body's pose is ``g_i M0_i``.
    V : ndarray, shape ``(S, n, 6)``
        Spatial twists of the bodies (world frame).
    dV : ndarray, shape ``(S, n, 6)``
        Spatial accelerations (world frame, gravity not included).
    lines : ndarray, shape ``(S, dof, 6)``
        Current joint lines ``L_k`` (eq. "jacobian line"); the floating root's are the unit
        vectors ``e_k`` (quasi-velocities).
    robot : Robot
        The robot (:attr:`support`, formed when first read).
    """

    g: np.ndarray
    V: np.ndarray
    dV: np.ndarray
    lines: np.ndarray
    robot: Robot

    __repr__ = summary_repr

    @property
    def support(self) -> np.ndarray:
        """``(dof, n)`` bool: which coordinates move which bodies (:attr:`Robot.support`; dense, formed on demand)."""
        s = self.__dict__.get("_support")
        if s is None:
            s = self.robot.support
            object.__setattr__(self, "_support", s)
        return s

    def jacobian_lines(self) -> np.ndarray:
        """Dense Jacobian lines ``L[s, j, i] (S, dof, n, 6)`` (zero where j does not move i).

        Returns
        -------
        ndarray, shape ``(S, dof, n, 6)``
            ``lines[s, j]`` where coordinate ``j`` moves body ``i``, else zero (world frame).
        """
        return self.lines[:, :, None, :] * self.support[None, :, :, None]


def _as_samples(x, dof: int, label: str) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[None]
    if x.ndim != 2 or x.shape[1] != dof:
        raise BaseparamsError(f"{label} must have shape (S, {dof}) or ({dof},), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise BaseparamsError(f"{label} contains NaN or inf")
    return x


def as_states(dof: int, q, dq=None, ddq=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validated joint states: float arrays of one shape, finite.

    Parameters
    ----------
    dof : int
        Number of coordinates per sample.
    q : array_like, shape ``(S, dof)`` or ``(dof,)``
        Positions.
    dq, ddq : array_like, shape ``(S, dof)`` or ``(dof,)``, optional
        Velocities and accelerations; default zero.

    Returns
    -------
    q, dq, ddq : ndarray, shape ``(S, dof)``
        The states as float64 arrays (views of the inputs where no conversion was needed).

    Raises
    ------
    BaseparamsError
        Wrong shapes, different numbers of samples, NaN or inf (naming the array).
    """
    q = _as_samples(q, dof, "q")
    s = q.shape[0]
    dq = np.zeros_like(q) if dq is None else _as_samples(dq, dof, "dq")
    ddq = np.zeros_like(q) if ddq is None else _as_samples(ddq, dof, "ddq")
    if dq.shape[0] != s or ddq.shape[0] != s:
        raise BaseparamsError(f"q, dq, ddq must have the same number of samples, got {s}, "
                              f"{dq.shape[0]}, {ddq.shape[0]}")
    return q, dq, ddq


def forward_kinematics(robot: Robot, q, dq=None, ddq=None) -> TreeState:
    """Batched tree kinematics (product of exponentials, see the module doc).

    Loops over bodies, vectorised over samples. Loop joints are ignored: this is the spanning
    tree's kinematics.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies, ``dof`` coordinates).
    q : array_like, shape ``(S, dof)`` or ``(dof,)``
        Tree coordinates (a floating root's six first: twist coordinates, ``g = exp(q^)``).
    dq, ddq : array_like, shape ``(S, dof)`` or ``(dof,)``, optional
        Velocities and accelerations (the floating root's: quasi-velocities, its spatial twist
        and its derivative); default zero.

    Returns
    -------
    TreeState
        Displacements, twists, accelerations and joint lines of the ``S`` samples.

    Raises
    ------
    BaseparamsError
        Wrong shapes, different numbers of samples, NaN or inf.
    """
    dof = robot.dof
    q, dq, ddq = as_states(dof, q, dq, ddq)
    s = q.shape[0]
    n = robot.n
    screws = robot.screws
    qi = robot.q_index
    nd = robot.ndofs
    g = np.empty((s, n, 4, 4))
    v = np.empty((s, n, 6))
    a = np.empty((s, n, 6))
    lines = np.empty((s, dof, 6))
    eye = np.broadcast_to(np.eye(4), (s, 4, 4))
    zero6 = np.zeros((s, 6))
    for i in range(n):
        p = robot.parent[i]
        gp, vp, ap = (eye, zero6, zero6) if p < 0 else (g[:, p], v[:, p], a[:, p])
        j0, k = qi[i], nd[i]
        sl = slice(j0, j0 + k)
        if robot.jtype[i] == "F":
            lines[:, sl] = np.broadcast_to(np.eye(6), (s, 6, 6))
            u, du = dq[:, sl], ddq[:, sl]
            g[:, i] = se3_exp(q[:, sl])
            v[:, i] = vp + u
            a[:, i] = ap + du
            continue
        h, vh, ah = gp, vp, ap
        for jj in range(j0, j0 + k):
            line = adjoint(h, np.broadcast_to(screws[jj], (s, 6)))
            lines[:, jj] = line
            vh = vh + line * dq[:, jj:jj + 1]
            ah = ah + commutator(line, vh) * dq[:, jj:jj + 1] + line * ddq[:, jj:jj + 1]
            h = h @ screw_exp(screws[jj], q[:, jj])
        g[:, i], v[:, i], a[:, i] = h, vh, ah
    return TreeState(g, v, a, lines, robot)


@dataclass(frozen=True, eq=False)
class Poses:
    """Body displacements, joint lines and (optionally) twists, samples last (:func:`poses`).

    Every component is a contiguous row of ``S`` samples, so that products with constant vectors
    are single matrix products and elementwise work runs on contiguous rows.

    Parameters
    ----------
    rot : ndarray, shape ``(n, 3, 3, S)``
        Rotations of the displacements ``g_i`` by columns: ``rot[i, k]`` is ``R_i e_k``
        (components, samples).
    pos : ndarray, shape ``(n, 3, S)``
        Translations of the displacements ``g_i``.
    lines : ndarray, shape ``(6, dof, S)``
        Current joint lines ``L_k`` (components first; the floating root's: ``e_k``).
    V, dV : ndarray, shape ``(n, 6, S)``, or None
        Spatial twists and accelerations (world frame, no gravity); None without ``dq``.
    bodies : ndarray of bool, shape ``(n,)``
        The bodies computed (and their coordinates' lines); the others' entries are undefined.
    """

    rot: np.ndarray
    pos: np.ndarray
    lines: np.ndarray
    V: np.ndarray | None
    dV: np.ndarray | None
    bodies: np.ndarray

    __repr__ = summary_repr


#: per robot: the constant vectors of each coordinate's screw (see :func:`_screw_constants`)
_SCREW_CONSTANTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _screw_constants(robot: Robot) -> list[tuple[bool, np.ndarray]]:
    """Per coordinate ``(revolute, C)``: the vectors multiplied by the rotation before the joint.

    Revolute (``omega != 0``, ``K = [omega]_x``): ``C (10, 3)`` = the columns of ``K`` and ``K^2``,
    then ``v``, ``K v``, ``K^2 v`` and ``omega``. Prismatic: ``C (1, 3)`` = ``v``.
    """
    out = _SCREW_CONSTANTS.get(robot)
    if out is None:
        out = []
        for sc in np.asarray(robot.screws, dtype=float):
            w, v = sc[:3], sc[3:]
            if np.any(w):
                k = skew(w)
                k2 = k @ k
                out.append((True, np.vstack([k.T, k2.T, v, k @ v, k2 @ v, w])))
            else:
                out.append((False, v[None].copy()))
        _SCREW_CONSTANTS[robot] = out
    return out


def _advance(rev: bool, cm: np.ndarray, th: np.ndarray, rot, pos, line: np.ndarray):
    """``h exp(S th)`` for ``h = (rot, pos)`` (None: identity / zero); writes ``L = Ad(h) S`` to ``line``.

    Rotation ``R_h (I + sin K + (1 - cos) K^2)``, translation ``p_h + R_h (th v + (1 - cos) K v
    + (th - sin) K^2 v)``, both from the products of ``R_h`` with the constant vectors ``cm``;
    sine and cosine from the tangent of the half angle (one vectorised call instead of two).
    """
    if rot is None and pos is None:
        return _advance_root(rev, cm, th, line)
    out = np.repeat(cm[:, :, None], len(th), 2) if rot is None else (cm @ rot.reshape(3, -1)).reshape(len(cm), 3, -1)
    if not rev:  # translation along R v
        line[:3] = 0.0
        line[3:] = out[0]
        out[0] *= th
        return rot, out[0] if pos is None else np.add(pos, out[0], out=out[0])
    s, c = _sin_versine(th)
    line[:3] = out[9]
    if pos is None:
        line[3:] = out[6]
    else:
        _cross_into(pos, out[9], line[3:])
        line[3:] += out[6]
    new_rot = out[0:3]
    new_rot *= s
    out[3:6] *= c
    new_rot += out[3:6]
    new_rot += _EYE3 if rot is None else rot
    t = out[6]
    t *= th
    out[7] *= c
    t += out[7]
    out[8] *= th - s
    t += out[8]
    if pos is not None:
        t += pos
    return new_rot, t


def _advance_root(rev: bool, cm: np.ndarray, th: np.ndarray, line: np.ndarray):
    """:func:`_advance` from the identity: ``exp(S th)`` itself (``L = S``)."""
    if not rev:
        line[:3] = 0.0
        line[3:] = cm[0][:, None]
        return None, cm[0][:, None] * th
    s, c = _sin_versine(th)
    line[:3] = cm[9][:, None]
    line[3:] = cm[6][:, None]
    new_rot = cm[0:3, :, None] * s
    new_rot += cm[3:6, :, None] * c
    new_rot += _EYE3
    t = cm[6][:, None] * th
    t += cm[7][:, None] * c
    t += cm[8][:, None] * (th - s)
    return new_rot, t


def _sin_versine(th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``sin th`` and ``1 - cos th`` from ``u = tan(th / 2)``: ``2u / (1 + u^2)``, ``2u^2 / (1 + u^2)``."""
    u = np.tan(0.5 * th)
    u2 = u * u
    f = 2.0 / (1.0 + u2)
    u *= f
    u2 *= f
    return u, u2


def _cross_into(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``out[:] = a x b`` for ``(3, *)`` arrays (components first), without temporaries of ``(3, *)``."""
    np.multiply(a[1], b[2], out=out[0])
    out[0] -= a[2] * b[1]
    np.multiply(a[2], b[0], out=out[1])
    out[1] -= a[0] * b[2]
    np.multiply(a[0], b[1], out=out[2])
    out[2] -= a[1] * b[0]
    return out


_EYE3 = np.eye(3)[:, :, None]


def _twist_step(line: np.ndarray, u: np.ndarray, du, vh, ah):
    """``V += L u``, ``dV += [L, V] u + L du`` (components first; ``du`` None: zero)."""
    vh = line * u if vh is None else vh + line * u
    w, v = vh[:3], vh[3:]
    d, m = line[:3], line[3:]
    com = np.concatenate([cross3_first(w, d), cross3_first(w, m) + cross3_first(v, d)]) * u
    ah = com if ah is None else ah + com
    return vh, ah if du is None else ah + line * du


def poses(robot: Robot, q, dq=None, ddq=None, bodies=None) -> Poses:
    """Tree kinematics with samples last: what :func:`forward_kinematics` computes, faster.

    The same product of exponentials (see the module doc), by closed-form screw products with
    one matrix product per coordinate; only the bodies asked for and their ancestors are
    computed, and twists only with ``dq``.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies, ``dof`` coordinates).
    q : array_like, shape ``(S, dof)`` or ``(dof,)``
        Tree coordinates (a floating root's six first: twist coordinates).
    dq, ddq : array_like, shape ``(S, dof)`` or ``(dof,)``, optional
        Velocities and accelerations; without ``dq`` no twists are computed, ``ddq`` defaults to
        zero.
    bodies : array_like of int, optional
        The bodies needed (default all); their ancestors are computed too.

    Returns
    -------
    Poses
        Displacements and lines (and twists with ``dq``) of the ``S`` samples, samples last.

    Raises
    ------
    BaseparamsError
        Wrong shapes or NaN or inf.
    """
    dof, n = robot.dof, robot.n
    qt = _as_samples(q, dof, "q").T.copy()
    s = qt.shape[1]
    dqt = None if dq is None else _as_samples(dq, dof, "dq").T.copy()
    ddqt = None if dq is None or ddq is None else _as_samples(ddq, dof, "ddq").T.copy()
    need = _with_ancestors(robot, bodies)
    rot, pos = np.empty((n, 3, 3, s)), np.empty((n, 3, s))
    lines = np.empty((6, dof, s))
    vel = np.zeros((n, 6, s)) if dqt is not None else None
    acc = np.zeros((n, 6, s)) if dqt is not None else None
    consts = _screw_constants(robot)
    qi, nd, parent = robot.q_index, robot.ndofs, robot.parent
    for i in np.flatnonzero(need):
        p, j0 = parent[i], qi[i]
        h, t = (None, None) if p < 0 else (rot[p], pos[p])
        vh, ah = (None, None) if p < 0 or vel is None else (vel[p], acc[p])
        if robot.jtype[i] == "F":
            h, t, vh, ah = _floating(qt, dqt, ddqt, j0, lines, vh, ah)
        else:
            for jj in range(j0, j0 + nd[i]):
                h, t = _advance(*consts[jj], qt[jj], h, t, lines[:, jj])
                if vel is not None:
                    vh, ah = _twist_step(lines[:, jj], dqt[jj], None if ddqt is None else ddqt[jj], vh, ah)
        rot[i] = _EYE3 if h is None else h
        pos[i] = 0.0 if t is None else t
        if vel is not None:
            vel[i] = 0.0 if vh is None else vh
            acc[i] = 0.0 if ah is None else ah
    return Poses(rot, pos, lines, vel, acc, need)


def _with_ancestors(robot: Robot, bodies) -> np.ndarray:
    """Bool mask ``(n,)`` of ``bodies`` (default all) and their ancestors."""
    need = np.zeros(robot.n, dtype=bool)
    if bodies is None:
        need[:] = True
        return need
    for b in np.asarray(bodies, dtype=int).ravel():
        while b >= 0 and not need[b]:
            need[b] = True
            b = robot.parent[b]
    return need


def _floating(qt, dqt, ddqt, j0: int, lines: np.ndarray, vh, ah):
    """The floating root's displacement ``exp(q^)``, unit lines and quasi-velocity twists."""
    g = se3_exp(qt[j0:j0 + 6].T)
    lines[:, j0:j0 + 6] = np.eye(6)[:, :, None]
    if dqt is not None:
        vh = dqt[j0:j0 + 6] if vh is None else vh + dqt[j0:j0 + 6]
        du = 0.0 if ddqt is None else ddqt[j0:j0 + 6]
        ah = du + (0.0 if ah is None else ah)
    return np.ascontiguousarray(g[:, :3, :3].transpose(2, 1, 0)), g[:, :3, 3].T.copy(), vh, ah


def re_reference(robot: Robot, q0: np.ndarray) -> Robot:
    """The same robot re-referenced at configuration ``q0 (dof,)``: its new q = 0 is the old ``q0``.

    Exactly ``q_new = q - q0`` for R, P, U and C joints. Not for S joints, whose Euler axes are
    tied to the joint frame.

    Parameters
    ----------
    robot : Robot
        A robot without S joints.
    q0 : ndarray, shape ``(dof,)``
        The new reference configuration, in the old coordinates.

    Returns
    -------
    Robot
        The robot with ``M0`` (world frame), the U and C joints' axes, the loop joints' frames
        (both copies, each carried by its own body), the couplings' offsets and the position
        limits (``lower - q0``, ``upper - q0``) moved to ``q0``.

    Raises
    ------
    ModelError
        The robot has S joints.
    """
    if "S" in robot.jtype:
        raise ModelError(f"robot {robot.name!r}: re-referencing at q0 is not supported with S joints")
    q0 = np.asarray(q0, dtype=float)
    g = forward_kinematics(robot, q0).g[0]
    axes = list(robot.axes)
    qi = robot.q_index
    for i, t in enumerate(robot.jtype):
        if t == "U":  # the first axis is carried by the parent: express it in the new frame
            a1, a2 = robot.axes[i]
            c, s = np.cos(q0[qi[i] + 1]), np.sin(q0[qi[i] + 1])
            k = skew(a2)
            rot = np.eye(3) + s * k + (1 - c) * (k @ k)  # Rot(a2, q2)
            axes[i] = np.stack([rot.T @ a1, a2])
        elif t == "C":  # screw k is carried by screws 1..k-1: undo the later ones
            axes[i] = _re_reference_compound(robot.axes[i], q0[qi[i]: qi[i] + len(robot.axes[i])])
    loops = []
    for lj in robot.loops:  # both copies of the frame move with their own body
        m = (np.eye(4) if lj.parent < 0 else g[lj.parent]) @ lj.M
        mc = g[lj.child] @ (lj.M if lj.M_child is None else lj.M_child)
        loops.append(replace(lj, M=m, M_child=None if np.abs(mc - m).max() <= 1e-12 else mc))
    couplings = tuple(_re_reference_coupling(c, q0) for c in robot.couplings)
    limits = None if robot.limits is None else robot.limits - np.c_[q0, q0, np.zeros((len(q0), 2))]
    return replace(robot, M0=g @ robot.M0, axes=tuple(axes), loops=tuple(loops), couplings=couplings,
                   limits=limits)


def _re_reference_coupling(c, q0: np.ndarray):
    """A coupling in the coordinates ``q - q0``: its polynomial in ``q[pred]`` shifted by ``q0[pred]``."""
    if not c.poly:
        return replace(c, offset=c.offset + sum(r * q0[k] for k, r in c.terms()) - q0[c.succ])
    from numpy.polynomial import Polynomial

    shifted = Polynomial(c.coefficients())(Polynomial([q0[c.pred], 1.0])).coef
    shifted = np.r_[shifted, np.zeros(max(0, 2 + len(c.poly) - len(shifted)))]
    return replace(c, offset=float(shifted[0] - q0[c.succ]), ratio=float(shifted[1]),
                   poly=tuple(float(x) for x in shifted[2:2 + len(c.poly)]))


def _re_reference_compound(xs: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Screws ``xs (k, 6)`` of a compound joint seen from its configuration ``q0 (k,)``."""
    new = xs.copy()
    later = np.eye(4)  # exp(xi_{k+1} q_{k+1}) ... exp(xi_m q_m), joint frame
    for kk in range(len(xs) - 1, -1, -1):
        new[kk] = adjoint(inverse_transform(later), xs[kk])
        later = screw_exp(xs[kk], np.array(q0[kk])) @ later
    return new


def wrench_forces(robot: Robot, q, body: int, wrench, frame: str = "world") -> np.ndarray:
    """Generalized forces of an external wrench on one body: ``J_body^T W`` (virtual power).

    A measured contact force or force/torque sensor reading on a link enters the identification
    as ``tau + J^T W = Y pi`` (the wrench moved to the measured side).

    Parameters
    ----------
    robot : Robot
        The robot (``dof`` coordinates).
    q : array_like, shape ``(S, dof)``
        Positions.
    body : int
        The body the wrench acts on.
    wrench : array_like, shape ``(S, 6)`` or ``(6,)``
        ``(force, moment)`` [N, N m] applied to the body: in the world frame with the moment about
        the world origin (``frame="world"``), or in the body's own frame with the moment about
        its origin (``frame="body"``; e.g. a force/torque sensor's reading).
    frame : {"world", "body"}
        The frame of ``wrench``.

    Returns
    -------
    ndarray, shape ``(S, dof)``
        ``Q_j = L_j . (m, f)`` for every coordinate ``j`` moving the body (its line
        ``L_j = (omega, v)``, eq. "jacobian line"), zero for the others: ``Q . dq`` is the
        wrench's power on the body's twist.

    Raises
    ------
    BaseparamsError
        A wrong shape, an unknown frame, or a body index out of range.
    """
    q = as_states(robot.dof, q)[0]
    w = np.broadcast_to(np.asarray(wrench, dtype=float), (q.shape[0], 6)) if np.ndim(wrench) == 1 else \
        np.asarray(wrench, dtype=float)
    if w.shape != (q.shape[0], 6) or not 0 <= body < robot.n or frame not in ("world", "body"):
        raise BaseparamsError(f"wrench_forces: need a wrench (S, 6) = ({q.shape[0]}, 6) on a body 0..{robot.n - 1} "
                              f"in the 'world' or 'body' frame; got {w.shape}, body {body}, frame {frame!r}")
    state = forward_kinematics(robot, q)
    f, m = w[:, :3], w[:, 3:]
    if frame == "body":  # to world: rotate, and move the moment to the world origin
        pose = state.g[:, body] @ robot.M0[body]
        f = np.einsum("sij,sj->si", pose[:, :3, :3], f)
        m = np.einsum("sij,sj->si", pose[:, :3, :3], m) + np.cross(pose[:, :3, 3], f)
    out = np.einsum("sjc,sc->sj", state.lines[..., :3], m) + np.einsum("sjc,sc->sj", state.lines[..., 3:], f)
    moved = np.zeros(robot.dof, dtype=bool)
    moved[robot.path_dofs(body)] = True
    out[:, ~moved] = 0.0
    return out
