"""A small batched PGA kernel for G(3,0,1) in the paper's coordinates.

Layouts (any number of leading batch axes ``*``):

* point ``(*, 4)``: ``[x, y, z, w]`` = x e032 + y e013 + z e021 + w e123; ``w = 1`` is a
  Euclidean point, ``w = 0`` an infinite point (a direction).
* line / twist / wrench ``(*, 6)``: ``[e23, e31, e12, e01, e02, e03]``. A line through
  ``p`` with direction ``d`` is ``(d, p x d)``; a spatial twist is ``(omega, v)`` with ``v``
  the velocity of the point at the world origin; a wrench is ``(f, n)`` with ``n`` the moment
  about the world origin.
* motor ``(*, 8)``: ``[1, e23, e31, e12, e01, e02, e03, e0123]``.

Conventions (checked against :mod:`baseparams.pga.algebra` in the tests):

* a motor acts by the paper's sandwich ``X = ~M X0 M`` (eq. "position");
* ``M = exp(B)`` with ``B = theta/2 * S`` is the screw displacement ``exp(theta * S^)``
  for a unit twist ``S``: rotation angle and translation are **twice** the bivector;
* ``matrix(a * b) = matrix(b) @ matrix(a)``: ``a * b`` applies ``a`` first, then ``b``
  (both in the world frame).
"""

from __future__ import annotations

import numpy as np

from . import algebra as _alg
from .linalg import cross3, skew

# ----------------------------------------------------------------------------------------
# points and lines

def point(xyz: np.ndarray) -> np.ndarray:
    """Euclidean point ``(*, 4)`` from coordinates ``(*, 3)``.

    Parameters
    ----------
    xyz : array_like, shape ``(*, 3)``
        Coordinates.

    Returns
    -------
    ndarray, shape ``(*, 4)``
        ``[x, y, z, 1]``.
    """
    xyz = np.asarray(xyz, dtype=float)
    return np.concatenate([xyz, np.ones(xyz.shape[:-1] + (1,))], axis=-1)


def direction(xyz: np.ndarray) -> np.ndarray:
    """Infinite point ``(*, 4)`` (a direction) from ``(*, 3)``.

    Parameters
    ----------
    xyz : array_like, shape ``(*, 3)``
        Direction vectors.

    Returns
    -------
    ndarray, shape ``(*, 4)``
        ``[x, y, z, 0]``.
    """
    xyz = np.asarray(xyz, dtype=float)
    return np.concatenate([xyz, np.zeros(xyz.shape[:-1] + (1,))], axis=-1)


def join(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The line ``P v Q`` through two points ``(*, 4)`` -> ``(*, 6)``.

    ``[w1 p2 - w2 p1, p1 x p2]`` (the paper's vee product of two points).

    Parameters
    ----------
    p, q : array_like, shape ``(*, 4)``
        Points ``[p1, w1]`` and ``[p2, w2]`` (Euclidean or infinite).

    Returns
    -------
    ndarray, shape ``(*, 6)``
        The line ``(d, m)``.
    """
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    d = p[..., 3:4] * q[..., :3] - q[..., 3:4] * p[..., :3]
    m = cross3(p[..., :3], q[..., :3])
    return np.concatenate([d, m], axis=-1)


def line_through(p: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Line ``(*, 6)`` through Euclidean point ``p (*, 3)`` with direction ``d (*, 3)``.

    Parameters
    ----------
    p : array_like, shape ``(*, 3)``
        A point on the line.
    d : array_like, shape ``(*, 3)``
        Its direction (not normalised here).

    Returns
    -------
    ndarray, shape ``(*, 6)``
        ``(d, p x d)``.
    """
    return join(point(p), direction(d))


def wedge(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Outer product of two bivectors ``(*, 6)`` -> pseudoscalar coefficient ``(*)``.

    For a wrench ``w`` and a twist ``V``, ``w ^ V`` is the power (eq. "duality").

    Parameters
    ----------
    a, b : ndarray, shape ``(*, 6)``
        Bivectors (lines, twists, wrenches).

    Returns
    -------
    ndarray, shape ``(*)``
        ``a_d . b_m + a_m . b_d``.
    """
    return np.sum(a[..., :3] * b[..., 3:] + a[..., 3:] * b[..., :3], axis=-1)


def swap(l: np.ndarray) -> np.ndarray:
    """``[m, d]`` from ``[d, m]``: ``wedge(a, b) == a . swap(b)``.

    Parameters
    ----------
    l : ndarray, shape ``(*, 6)``
        Bivectors ``[d, m]``.

    Returns
    -------
    ndarray, shape ``(*, 6)``
        ``[m, d]``.
    """
    return np.concatenate([l[..., 3:], l[..., :3]], axis=-1)


def commutator(x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The paper's cross product ``X x V = (XV - VX)/2`` for ``V`` a bivector ``(*, 6)``.

    * ``x`` a line ``(*, 6)``: returns the line's velocity ``ad_V X``;
    * ``x`` a point ``(*, 4)``: returns the point's velocity ``omega x p + w v`` as an
      infinite point ``(*, 4)`` (eq. "vel").

    Parameters
    ----------
    x : array_like, shape ``(*, 6)`` or ``(*, 4)``
        A line or a point.
    v : array_like, shape ``(*, 6)``
        The bivector (a twist ``(omega, v)``).

    Returns
    -------
    ndarray, shape of ``x``
        The line's velocity (``(*, 6)``) or the point's (an infinite point ``(*, 4)``).

    Raises
    ------
    ValueError
        ``x`` neither a line nor a point.
    """
    x = np.asarray(x, dtype=float)
    v = np.asarray(v, dtype=float)
    w, u = v[..., :3], v[..., 3:]
    if x.shape[-1] == 6:
        d, m = x[..., :3], x[..., 3:]
        return np.concatenate([cross3(w, d), cross3(w, m) + cross3(u, d)], axis=-1)
    if x.shape[-1] == 4:
        vel = cross3(w, x[..., :3]) + x[..., 3:4] * u
        return np.concatenate([vel, np.zeros(vel.shape[:-1] + (1,))], axis=-1)
    raise ValueError(f"commutator: expected a line (*, 6) or a point (*, 4), got {x.shape}")


# ----------------------------------------------------------------------------------------
# motors

def _even_table() -> np.ndarray:
    idx = [(_alg.blade(n)) for n in _alg.MOTOR_BLADES]
    t = np.zeros((8, 8, 8))
    for a, (sa, ia) in enumerate(idx):
        for b, (sb, ib) in enumerate(idx):
            s, ic = _alg.blade_product(ia, ib)
            for c, (sc, icc) in enumerate(idx):
                if icc == ic:
                    t[a, b, c] = sa * sb * s * sc
    return t


_EVEN = _even_table()
_EVEN_NZ = np.nonzero(_EVEN)
_REV = np.array([1, -1, -1, -1, -1, -1, -1, 1.0])


def motor_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Geometric product of two even elements ``(*, 8)``: ``a`` first, then ``b``.

    Parameters
    ----------
    a, b : array_like, shape ``(*, 8)``
        Motors (broadcast against each other).

    Returns
    -------
    ndarray, shape ``(*, 8)``
        ``a b``: ``matrix(a * b) = matrix(b) @ matrix(a)`` (both in the world frame).
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    i, j, k = _EVEN_NZ
    terms = a[..., i] * b[..., j] * _EVEN[i, j, k]
    out = np.zeros(np.broadcast_shapes(a.shape, b.shape))
    for kk in range(8):
        out[..., kk] = terms[..., k == kk].sum(axis=-1)
    return out


def reverse(m: np.ndarray) -> np.ndarray:
    """Reverse ``~M`` of an even element ``(*, 8)``.

    Parameters
    ----------
    m : array_like, shape ``(*, 8)``
        Motors.

    Returns
    -------
    ndarray, shape ``(*, 8)``
        ``~m`` (the bivector part negated); for a unit motor, its inverse.
    """
    return np.asarray(m, dtype=float) * _REV


def identity_motor(shape: tuple[int, ...] = ()) -> np.ndarray:
    """Identity motors ``1``: no displacement.

    Parameters
    ----------
    shape : tuple of int, optional
        Batch shape ``*``.

    Returns
    -------
    ndarray, shape ``(*shape, 8)``
        ``[1, 0, 0, 0, 0, 0, 0, 0]`` each.
    """
    m = np.zeros(shape + (8,))
    m[..., 0] = 1.0
    return m


def quat_to_rot(q: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(*, 3, 3)`` from unit quaternions ``(*, 4)`` [w, x, y, z].

    Parameters
    ----------
    q : ndarray, shape ``(*, 4)``
        Unit quaternions, scalar first (not normalised here).

    Returns
    -------
    ndarray, shape ``(*, 3, 3)``
        Rotation matrices.
    """
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r = np.empty(q.shape[:-1] + (3, 3))
    r[..., 0, 0] = 1 - 2 * (y * y + z * z)
    r[..., 0, 1] = 2 * (x * y - z * w)
    r[..., 0, 2] = 2 * (x * z + y * w)
    r[..., 1, 0] = 2 * (x * y + z * w)
    r[..., 1, 1] = 1 - 2 * (x * x + z * z)
    r[..., 1, 2] = 2 * (y * z - x * w)
    r[..., 2, 0] = 2 * (x * z - y * w)
    r[..., 2, 1] = 2 * (y * z + x * w)
    r[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def rot_to_quat(r: np.ndarray) -> np.ndarray:
    """Unit quaternion ``(*, 4)`` [w, x, y, z] from rotation matrices ``(*, 3, 3)``.

    Parameters
    ----------
    r : array_like, shape ``(*, 3, 3)``
        Rotation matrices.

    Returns
    -------
    ndarray, shape ``(*, 4)``
        Unit quaternions, scalar first, with ``w >= 0`` (from the best-conditioned diagonal
        pivot of each matrix).
    """
    r = np.asarray(r, dtype=float)
    tr = np.trace(r, axis1=-2, axis2=-1)
    # candidates from each diagonal pivot; pick the best-conditioned per element
    q = np.empty(r.shape[:-2] + (4, 4))
    q[..., 0, :] = np.stack([1 + tr, r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0],
                             r[..., 1, 0] - r[..., 0, 1]], -1)
    q[..., 1, :] = np.stack([r[..., 2, 1] - r[..., 1, 2], 1 + 2 * r[..., 0, 0] - tr,
                             r[..., 0, 1] + r[..., 1, 0], r[..., 0, 2] + r[..., 2, 0]], -1)
    q[..., 2, :] = np.stack([r[..., 0, 2] - r[..., 2, 0], r[..., 0, 1] + r[..., 1, 0],
                             1 + 2 * r[..., 1, 1] - tr, r[..., 1, 2] + r[..., 2, 1]], -1)
    q[..., 3, :] = np.stack([r[..., 1, 0] - r[..., 0, 1], r[..., 0, 2] + r[..., 2, 0],
                             r[..., 1, 2] + r[..., 2, 1], 1 + 2 * r[..., 2, 2] - tr], -1)
    piv = np.stack([1 + tr, 1 + 2 * r[..., 0, 0] - tr, 1 + 2 * r[..., 1, 1] - tr,
                    1 + 2 * r[..., 2, 2] - tr], -1)
    best = np.argmax(piv, axis=-1)
    out = np.take_along_axis(q, best[..., None, None], axis=-2)[..., 0, :]
    out = out / np.linalg.norm(out, axis=-1, keepdims=True)
    return out * np.where(out[..., :1] < 0, -1.0, 1.0)


def matrix_to_motor(t: np.ndarray) -> np.ndarray:
    """Motor ``(*, 8)`` from homogeneous matrices ``(*, 4, 4)`` (rigid, det +1).

    Parameters
    ----------
    t : array_like, shape ``(*, 4, 4)``
        Rigid displacements ``X = T @ X0``.

    Returns
    -------
    ndarray, shape ``(*, 8)``
        Unit motors ``M`` with ``motor_to_matrix(M) == t``: the rotation, then the translation.
    """
    t = np.asarray(t, dtype=float)
    q = rot_to_quat(t[..., :3, :3])
    rot = np.zeros(t.shape[:-2] + (8,))
    rot[..., :4] = q
    tr = identity_motor(t.shape[:-2])
    tr[..., 4:7] = 0.5 * t[..., :3, 3]
    return motor_product(rot, tr)


def motor_to_matrix(m: np.ndarray) -> np.ndarray:
    """Homogeneous matrix ``(*, 4, 4)`` of a unit motor ``(*, 8)`` (``X = T @ X0``).

    Parameters
    ----------
    m : array_like, shape ``(*, 8)``
        Unit motors, acting by ``X = ~M X0 M``.

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        The same displacements as matrices ``T``: ``X = T @ X0``.
    """
    m = np.asarray(m, dtype=float)
    rot = np.zeros_like(m)
    rot[..., :4] = m[..., :4]
    tr = motor_product(reverse(rot), m)
    t = np.zeros(m.shape[:-1] + (4, 4))
    t[..., :3, :3] = quat_to_rot(m[..., :4])
    t[..., :3, 3] = 2.0 * tr[..., 4:7]
    t[..., 3, 3] = 1.0
    return t


def motor_exp(b: np.ndarray) -> np.ndarray:
    """``exp(B)`` of a bivector ``(*, 6)`` -> motor ``(*, 8)`` (displacement ``exp(2B^)``).

    Parameters
    ----------
    b : array_like, shape ``(*, 6)``
        Bivectors ``B = theta/2 * S``.

    Returns
    -------
    ndarray, shape ``(*, 8)``
        Unit motors; rotation angle and translation are **twice** the bivector's.
    """
    return matrix_to_motor(se3_exp(2.0 * np.asarray(b, dtype=float)))


def motor_log(m: np.ndarray) -> np.ndarray:
    """Bivector ``B (*, 6)`` with ``exp(B) == M`` (rotation angle of ``M`` in ``[0, pi]``).

    Parameters
    ----------
    m : array_like, shape ``(*, 8)``
        Unit motors.

    Returns
    -------
    ndarray, shape ``(*, 6)``
        ``B``: half the twist of the displacement (:func:`se3_log`).
    """
    return 0.5 * se3_log(motor_to_matrix(m))


def sandwich(m: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``~M X M``: move a point ``(*, 4)`` or a line ``(*, 6)`` by the motor ``(*, 8)``.

    Parameters
    ----------
    m : array_like, shape ``(*, 8)``
        Unit motors.
    x : array_like, shape ``(*, 4)`` or ``(*, 6)``
        Points or lines.

    Returns
    -------
    ndarray, shape of ``x``
        The moved points or lines (the paper's sandwich, eq. "position").

    Raises
    ------
    ValueError
        ``x`` neither a point nor a line.
    """
    t = motor_to_matrix(m)
    x = np.asarray(x, dtype=float)
    if x.shape[-1] == 4:
        return np.einsum("...ij,...j->...i", t, x)
    if x.shape[-1] == 6:
        return adjoint(t, x)
    raise ValueError(f"sandwich: expected a point (*, 4) or a line (*, 6), got {x.shape}")


# ----------------------------------------------------------------------------------------
# the same rigid motions as 4x4 matrices (what the kinematics hot path uses)

def hat(xi: np.ndarray) -> np.ndarray:
    """se(3) matrix ``(*, 4, 4)`` of a twist ``(*, 6)`` = (omega, v).

    Parameters
    ----------
    xi : array_like, shape ``(*, 6)``
        Twists ``(omega, v)``.

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        ``[[omega]_x, v; 0, 0]``.
    """
    xi = np.asarray(xi, dtype=float)
    out = np.zeros(xi.shape[:-1] + (4, 4))
    w = xi[..., :3]
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    out[..., :3, 3] = xi[..., 3:]
    return out


def se3_exp(xi: np.ndarray) -> np.ndarray:
    """Matrix exponential ``exp(xi^) (*, 4, 4)`` of twists ``(*, 6)`` (closed form).

    Parameters
    ----------
    xi : array_like, shape ``(*, 6)``
        Twists ``(omega, v)`` (any magnitude; Taylor series below ``|omega| = 1e-6``).

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        Rigid displacements.
    """
    xi = np.asarray(xi, dtype=float)
    w, v = xi[..., :3], xi[..., 3:]
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    small = th < 1e-6
    ths = np.where(small, 1.0, th)
    th2 = th * th
    a = np.where(small, 1 - th2 / 6 + th2 * th2 / 120, np.sin(ths) / ths)
    b = np.where(small, 0.5 - th2 / 24 + th2 * th2 / 720, (1 - np.cos(ths)) / ths**2)
    c = np.where(small, 1.0 / 6 - th2 / 120 + th2 * th2 / 5040, (ths - np.sin(ths)) / ths**3)
    k = skew(w)
    k2 = k @ k
    eye = np.eye(3)
    out = np.zeros(xi.shape[:-1] + (4, 4))
    out[..., :3, :3] = eye + a * k + b * k2
    out[..., :3, 3] = np.einsum("...ij,...j->...i", eye + b * k + c * k2, v)
    out[..., 3, 3] = 1.0
    return out


def screw_exp(screw: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``exp(screw^ theta) (S, 4, 4)`` for one unit screw ``(6,)`` and angles/displacements ``theta (S,)``.

    Closed form.

    Parameters
    ----------
    screw : ndarray, shape ``(6,)``
        A unit screw ``(omega, v)`` (rotation: ``|omega| = 1``; translation: ``omega = 0``, ``|v| = 1``).
    theta : array_like, shape ``(S,)``
        Angles (rad) or displacements (m); any shape ``(*)``.

    Returns
    -------
    ndarray, shape ``(S, 4, 4)``
        Rigid displacements (``(*, 4, 4)`` for ``theta (*)``).
    """
    w, v = screw[:3], screw[3:]
    theta = np.asarray(theta, dtype=float)
    out = np.zeros(theta.shape + (4, 4))
    out[..., 3, 3] = 1.0
    if not np.any(w):
        out[..., 0, 0] = out[..., 1, 1] = out[..., 2, 2] = 1.0
        out[..., :3, 3] = theta[..., None] * v
        return out
    k = skew(w)
    k2 = k @ k
    s, c = np.sin(theta)[..., None, None], (1 - np.cos(theta))[..., None, None]
    out[..., :3, :3] = np.eye(3) + s * k + c * k2
    t = theta[..., None, None]
    out[..., :3, 3] = (t * np.eye(3) + c * k + (t - s) * k2) @ v
    return out


def se3_log(t: np.ndarray) -> np.ndarray:
    """Twist ``(*, 6)`` with ``se3_exp(twist) == t`` for rotation angles in ``[0, pi)``.

    Parameters
    ----------
    t : array_like, shape ``(*, 4, 4)``
        Rigid displacements.

    Returns
    -------
    ndarray, shape ``(*, 6)``
        Twists ``(omega, v)`` with ``|omega|`` the rotation angle.

    Notes
    -----
    Angles within 1e-4 of pi take the axis from the symmetric part,
    ``(R + R^T)/2 - cos(theta) I = (1 - cos(theta)) a a^T``, signed like the skew part.
    """
    t = np.asarray(t, dtype=float)
    r = t[..., :3, :3]
    cos = np.clip((np.trace(r, axis1=-2, axis2=-1) - 1) / 2, -1.0, 1.0)
    th = np.arccos(cos)
    vee = np.stack([r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0],
                    r[..., 1, 0] - r[..., 0, 1]], -1)
    small = th < 1e-6
    s = np.where(small, 1.0, np.sin(np.where(small, 1.0, th)))
    fac = np.where(small, 0.5 + th**2 / 12, th / (2 * s))
    w = vee * fac[..., None]
    near_pi = th > np.pi - 1e-4
    if np.any(near_pi):
        # axis from the symmetric part: (R + R^T)/2 - cos(th) I = (1 - cos(th)) a a^T
        rs = r[near_pi]
        b = (rs + np.swapaxes(rs, -1, -2)) / 2 - np.eye(3) * np.cos(th[near_pi])[..., None, None]
        col = np.argmax(np.linalg.norm(b, axis=-2), axis=-1)
        ax = np.take_along_axis(b, col[:, None, None], axis=-1)[..., 0]
        ax = ax / np.linalg.norm(ax, axis=-1, keepdims=True)
        ax = ax * np.where(np.sum(ax * vee[near_pi], -1, keepdims=True) < 0, -1.0, 1.0)
        w[near_pi] = ax * th[near_pi][:, None]
    k = skew(w)
    th_ = th[..., None, None]
    small_ = th_ < 1e-6
    ths = np.where(small_, 1.0, th_)
    coef = np.where(small_, 1.0 / 12, (1 - ths * np.sin(ths) / (2 * (1 - np.cos(ths)))) / ths**2)
    vinv = np.eye(3) - 0.5 * k + coef * (k @ k)
    v = np.einsum("...ij,...j->...i", vinv, t[..., :3, 3])
    return np.concatenate([w, v], axis=-1)


def adjoint(t: np.ndarray, l: np.ndarray) -> np.ndarray:
    """Move a line / twist ``(*, 6)`` by the rigid displacement ``t (*, 4, 4)``: ``Ad_T L``.

    Parameters
    ----------
    t : ndarray, shape ``(*, 4, 4)``
        Rigid displacements ``(R, p)``.
    l : ndarray, shape ``(*, 6)``
        Lines or twists ``(d, m)``.

    Returns
    -------
    ndarray, shape ``(*, 6)``
        ``(R d, R m + p x R d)``.
    """
    r = t[..., :3, :3]
    p = t[..., :3, 3]
    d = np.einsum("...ij,...j->...i", r, l[..., :3])
    m = np.einsum("...ij,...j->...i", r, l[..., 3:]) + cross3(p, d)
    return np.concatenate([d, m], axis=-1)


def inverse_transform(t: np.ndarray) -> np.ndarray:
    """Inverse of rigid homogeneous matrices ``(*, 4, 4)``.

    Parameters
    ----------
    t : ndarray, shape ``(*, 4, 4)``
        Rigid displacements ``(R, p)``.

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        ``(R^T, -R^T p)``.
    """
    out = np.zeros_like(t)
    rt = np.swapaxes(t[..., :3, :3], -1, -2)
    out[..., :3, :3] = rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", rt, t[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out
