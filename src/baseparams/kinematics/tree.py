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
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import BaseparamsError, ModelError
from ..model.robot import Robot
from ..pga import adjoint, commutator, inverse_transform, se3_exp
from ..pga.core import screw_exp
from ..pga.linalg import skew


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
    support : ndarray of bool, shape ``(dof, n)``
        Which coordinates move which bodies (:attr:`Robot.support`).
    """

    g: np.ndarray
    V: np.ndarray
    dV: np.ndarray
    lines: np.ndarray
    support: np.ndarray

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
    return TreeState(g, v, a, lines, robot.support)


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
        (both copies, each carried by its own body) and the couplings' offsets moved to ``q0``.

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
    couplings = tuple(replace(c, offset=c.offset + sum(r * q0[k] for k, r in c.terms()) - q0[c.succ])
                      for c in robot.couplings)
    return replace(robot, M0=g @ robot.M0, axes=tuple(axes), loops=tuple(loops), couplings=couplings)


def _re_reference_compound(xs: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Screws ``xs (k, 6)`` of a compound joint seen from its configuration ``q0 (k,)``."""
    new = xs.copy()
    later = np.eye(4)  # exp(xi_{k+1} q_{k+1}) ... exp(xi_m q_m), joint frame
    for kk in range(len(xs) - 1, -1, -1):
        new[kk] = adjoint(inverse_transform(later), xs[kk])
        later = screw_exp(xs[kk], np.array(q0[kk])) @ later
    return new
