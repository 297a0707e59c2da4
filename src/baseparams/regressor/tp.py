"""The tetrahedral-point (TP) regressor (the paper's Algorithm DR).

Coefficient (eq. "basic coeff"): ``R[j, i, m, n] = L_j^i ^ (E_m^i v ddE_n^i)`` with the
tetrahedral points ``E^i = g_i [x y z O]`` of body ``i`` (spatial assignment: the world
frame at q = 0) and their accelerations including gravity as an extra acceleration of
Euclidean points, ``ddE_n = (dV^ + V^ V^) E_n - w_n (gravity, 0)``.

Matrix form: ``Y[:, j, 10 i + k] = bar(R)[j, i, k]`` in the paper's hat/bar order, so that
``tau = Y @ pi`` with ``pi`` the spatial pseudo-inertia parameters at q = 0
(``Robot.parameters("paper")``).
"""

from __future__ import annotations

import numpy as np

from ..kinematics.tree import TreeState, forward_kinematics
from ..model.inertia import HAT_INDEX
from ..model.robot import Robot
from ..pga import hat, join, swap
from ..pga.linalg import cross3

_M = np.array([m for m, _ in HAT_INDEX])
_N = np.array([n for _, n in HAT_INDEX])
_OFF = (_M != _N)[:, None]


def point_accelerations(robot: Robot, state: TreeState) -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedral points ``E (S, n, 4, 4)`` (columns x, y, z, O) and their accelerations
    ``ddE (S, n, 4, 4)`` including the gravity term (columns; last row zero).
    """
    e = state.g
    vh = hat(state.V)
    acc = (hat(state.dV) + vh @ vh) @ e
    acc[..., :3, 3] -= robot.gravity
    return e, acc


def bar_lines(e: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """The ten lines ``bar(E_m v ddE_n)`` per body ``(S, n, 10, 6)`` (paper's bar order)."""
    return swap(_bar_lines_swapped(e, acc))


def _bar_lines_swapped(e: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """``swap(bar(E_m v ddE_n))`` ``(S, n, 10, 6)``, built from the 16 products ``e_m x a_n``.

    With ``E_m = (e_m, w_m)`` (w = 0, 0, 0, 1) and ``ddE_n = (a_n, 0)``:
    ``E_m v ddE_n = (w_m a_n, e_m x a_n)``; only pairs with O carry a direction part.
    """
    pts = np.swapaxes(e[..., :3, :], -1, -2)  # (S, n, 4, 3)
    accs = np.swapaxes(acc[..., :3, :], -1, -2)
    c = cross3(pts[..., :, None, :], accs[..., None, :, :])  # (S, n, 4, 4, 3): e_m x a_n
    out = np.zeros(e.shape[:-2] + (10, 6))
    out[..., :3] = c[..., _M, _N, :]
    out[..., _OFF[:, 0], :3] += c[..., _N[_OFF[:, 0]], _M[_OFF[:, 0]], :]
    out[..., 6:9, 3:] = accs[..., :3, :]  # (m, O) pairs: direction a_m
    out[..., 9, 3:] = accs[..., 3, :]  # (O, O): direction a_O
    return out


def _subtree_slices(robot: Robot) -> list[tuple[int, int]] | None:
    """Per coordinate, the contiguous range of bodies it moves, or None if not contiguous."""
    out = []
    for row in robot.support:
        idx = np.flatnonzero(row)
        if idx[-1] - idx[0] + 1 != len(idx):
            return None
        out.append((int(idx[0]), int(idx[-1]) + 1))
    return out


def regressor(robot: Robot, q, dq=None, ddq=None, *, state: TreeState | None = None,
              chunk: int = 1024) -> np.ndarray:
    """TP regressor in matrix form ``Y (S, dof, 10 n)``, columns in the paper's order
    (spatial pseudo-inertia at q = 0), gravity included.

    ``q, dq, ddq``: ``(S, dof)``. Computed in chunks of ``chunk`` samples (memory, cache).
    Each coordinate's row is built only over the bodies it moves; the floating root's lines
    are the constant basis lines, so its rows are the bar lines themselves.
    """
    if state is None:
        q = np.atleast_2d(np.asarray(q, dtype=float))
        s = q.shape[0]
        dq = np.zeros_like(q) if dq is None else np.atleast_2d(np.asarray(dq, dtype=float))
        ddq = np.zeros_like(q) if ddq is None else np.atleast_2d(np.asarray(ddq, dtype=float))
        if s > chunk:
            out = np.empty((s, robot.dof, 10 * robot.n))
            for k in range(0, s, chunk):
                out[k:k + chunk] = regressor(robot, q[k:k + chunk], dq[k:k + chunk], ddq[k:k + chunk],
                                             chunk=chunk)
            return out
        state = forward_kinematics(robot, q, dq, ddq)
    e, acc = point_accelerations(robot, state)
    xs = _bar_lines_swapped(e, acc)  # (S, n, 10, 6): wedge(L, X) = L . swap(X)
    s, n = xs.shape[:2]
    slices = _subtree_slices(robot)
    if slices is None:  # general topological order: dense product, masked
        y = np.matmul(state.lines, xs.reshape(s, n * 10, 6).transpose(0, 2, 1)).reshape(s, -1, n, 10)
        y *= state.support[None, :, :, None]
        return y.reshape(s, -1, n * 10)
    xc = np.ascontiguousarray(np.moveaxis(xs, -1, 1))  # (S, 6, n, 10)
    y = np.zeros((s, robot.dof, n, 10))
    is_f = [robot.jtype[b] == "F" for b in robot.dof_body]
    for j, (a, b) in enumerate(slices):
        if is_f[j]:  # constant basis line e_j: the row is one coordinate of the bar lines
            y[:, j, a:b] = xc[:, j % 6, a:b]
            continue
        line = state.lines[:, j, :, None, None]
        row = y[:, j, a:b]
        np.multiply(line[:, 0], xc[:, 0, a:b], out=row)
        for c in range(1, 6):
            row += line[:, c] * xc[:, c, a:b]
    return y.reshape(s, -1, n * 10)


def regressor_tensor(robot: Robot, q, dq=None, ddq=None) -> np.ndarray:
    """TP regressor in tensor form ``R (S, dof, n, 4, 4)`` (eq. "basic coeff"), computed
    coefficient by coefficient as ``L_j^i ^ (E_m^i v ddE_n^i)``.
    """
    from ..pga import wedge

    state = forward_kinematics(robot, q, dq, ddq)
    e, acc = point_accelerations(robot, state)
    pts = np.swapaxes(e, -1, -2)
    accs = np.swapaxes(acc, -1, -2)
    lines4 = join(pts[:, :, :, None, :], accs[:, :, None, :, :])  # (S, n, 4, 4, 6)
    jl = state.jacobian_lines()  # (S, dof, n, 6)
    return wedge(jl[:, :, :, None, None, :], lines4[:, None])


def bar(r: np.ndarray) -> np.ndarray:
    """The paper's bar operator: ``(*, 4, 4)`` -> ``(*, 10)`` (off-diagonal pairs summed)."""
    out = r[..., _M, _N]
    return out + np.where(_OFF[:, 0], r[..., _N, _M], 0.0)


def generalized_forces(robot: Robot, q, dq, ddq, params=None) -> np.ndarray:
    """``tau = Y pi`` ``(S, dof)``; ``params`` default to the robot's own (paper convention)."""
    pi = robot.parameters("paper") if params is None else np.asarray(params, dtype=float)
    return regressor(robot, q, dq, ddq) @ pi


def closed_regressor(robot: Robot, closed) -> np.ndarray:
    """TP regressor of a closed-loop robot w.r.t. its actuated coordinates ``(S, na, 10 n)``.

    ``closed``: :class:`baseparams.kinematics.loops.ClosedStates`. The Jacobian lines include
    ``dq_k/dq_a`` (paper eq. "jacobian line"): ``L~_a^i = sum_k L_k^i G[k, a]``.
    """
    state = forward_kinematics(robot, closed.q, closed.dq, closed.ddq)
    e, acc = point_accelerations(robot, state)
    xbar = swap(bar_lines(e, acc))  # (S, n, 10, 6)
    lines = np.einsum("skc,ki,ska->saic", state.lines, state.support.astype(float), closed.G)
    s, n = xbar.shape[:2]
    return np.einsum("saic,sikc->saik", lines, xbar).reshape(s, -1, n * 10)
