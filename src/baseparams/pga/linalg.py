"""Small linear-algebra helpers shared by every layer: one copy each.

Skew matrices, perpendicular bases, symmetric products of homogeneous 4-vectors and the
SVD-based row, column and null spaces. Everything broadcasts over leading axes unless said
otherwise; nothing here knows about robots.
"""

from __future__ import annotations

import numpy as np


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis (broadcasting); cheaper than ``np.cross``.

    Parameters
    ----------
    a, b : ndarray, shape ``(*, 3)``
        Vectors (broadcast against each other).

    Returns
    -------
    ndarray, shape ``(*, 3)``
        ``a × b``.
    """
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def cross3_first(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the first axis (broadcasting): components first, samples last.

    For arrays laid out ``(3, *)`` (each component a contiguous row), where :func:`cross3`
    would work on strided columns.

    Parameters
    ----------
    a, b : ndarray, shape ``(3, *)``
        Vectors (the trailing axes broadcast against each other).

    Returns
    -------
    ndarray, shape ``(3, *)``
        ``a × b``.
    """
    a0, a1, a2 = a[0], a[1], a[2]
    b0, b1, b2 = b[0], b[1], b[2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def skew(w: np.ndarray) -> np.ndarray:
    """Skew matrix ``[w]_x`` with ``[w]_x v = w × v``.

    Parameters
    ----------
    w : array_like, shape ``(*, 3)``
        Vectors.

    Returns
    -------
    ndarray, shape ``(*, 3, 3)``
        ``[w]_x``.
    """
    w = np.asarray(w, dtype=float)
    out = np.zeros(w.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    return out


def perp_basis(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit directions completing unit directions ``d`` to right-handed orthonormal frames.

    ``x = unit(d × h)`` with ``h`` the first world axis unless ``|d_x| >= 0.9`` (then the
    second), and ``y = d × x``.

    Parameters
    ----------
    d : ndarray, shape ``(m, 3)``
        Unit directions.

    Returns
    -------
    x, y : ndarray, shape ``(m, 3)``
        Unit directions with ``(x, y, d)`` right-handed and orthonormal.
    """
    helper = np.where(np.abs(d[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    x = cross3(d, np.broadcast_to(helper, d.shape))
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = cross3(d, x)
    return x, y


def sym(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Symmetric product ``a b^T + b a^T`` of 4-vectors (broadcasting).

    Parameters
    ----------
    a, b : ndarray, shape ``(*, 4)``
        Homogeneous 4-vectors (broadcast against each other).

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        ``a b^T + b a^T``. For ``a == b`` this is ``2 a a^T``: use :func:`outer` for ``a a^T``.
    """
    ab = np.einsum("...i,...j->...ij", a, b)
    return ab + np.swapaxes(ab, -1, -2)


def outer(a: np.ndarray) -> np.ndarray:
    """``a a^T`` of 4-vectors: ``(*, 4) -> (*, 4, 4)``.

    Parameters
    ----------
    a : ndarray, shape ``(*, 4)``
        Homogeneous 4-vectors.

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        ``a a^T``.
    """
    return np.einsum("...i,...j->...ij", a, a)


def rowspace(a: np.ndarray, tol: float) -> np.ndarray:
    """Orthonormal basis of the row space of ``a``.

    Parameters
    ----------
    a : ndarray, shape ``(k, m)``
        The matrix.
    tol : float
        Absolute singular-value threshold.

    Returns
    -------
    ndarray, shape ``(r, m)``
        Orthonormal rows (``a`` itself when ``k == 0``).
    """
    if a.shape[0] == 0:
        return a
    _, s, vt = np.linalg.svd(a, full_matrices=False)
    return vt[: int(np.sum(s > tol))]


def nullspace(a: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Orthonormal basis of the right nullspace of ``a``.

    Parameters
    ----------
    a : ndarray, shape ``(k, m)``
        The matrix.
    tol : float, optional
        Absolute singular-value threshold.

    Returns
    -------
    ndarray, shape ``(m - r, m)``
        Orthonormal rows (the identity when ``k == 0``).
    """
    m = a.shape[1]
    if a.shape[0] == 0:
        return np.eye(m)
    _, s, vt = np.linalg.svd(a, full_matrices=True)
    return vt[int(np.sum(s > tol)):]


def column_basis(b: np.ndarray, rtol: float = 1e-10) -> np.ndarray:
    """Orthonormal basis of the span of the columns of ``b``, each column first normalised.

    Parameters
    ----------
    b : ndarray, shape ``(m, k)``
        Columns; exactly zero ones (a rule may emit one) span nothing and are skipped.
    rtol : float, optional
        Singular-value threshold relative to the largest.

    Returns
    -------
    ndarray, shape ``(m, r)``
        Orthonormal columns (``b`` itself when ``k == 0``).
    """
    norms = np.linalg.norm(b, axis=0)
    if b.shape[1] == 0 or not np.any(norms > 0):
        return b[:, :0]
    b = b[:, norms > 0] / norms[norms > 0]
    u, s, _ = np.linalg.svd(b, full_matrices=False)
    return u[:, : int(np.sum(s > rtol * s[0]))]


def null_rows(k: np.ndarray, tol: float) -> np.ndarray:
    """Right nullspaces of a batch of matrices with four columns, padded (one batched SVD).

    Parameters
    ----------
    k : ndarray, shape ``(..., r, 4)``
        The matrices.
    tol : float
        Absolute singular-value threshold (missing singular values, ``r < 4``, count as zero).

    Returns
    -------
    ndarray, shape ``(..., 4, 4)``
        Orthonormal nullspace rows, the other rows zero.
    """
    _, sv, vt = np.linalg.svd(k, full_matrices=True)
    full = np.zeros(k.shape[:-2] + (4,))
    full[..., : sv.shape[-1]] = sv
    return vt * (full <= tol)[..., None]


def span_rows(z: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Row spaces of a batch of matrices with four columns, padded (one batched SVD).

    Parameters
    ----------
    z : ndarray, shape ``(..., R, 4)``
        The matrices, ``R >= 4``.
    tol : float
        Absolute singular-value threshold.

    Returns
    -------
    rows : ndarray, shape ``(..., 4, 4)``
        Orthonormal rows of the row space, the other rows zero.
    rank : ndarray of int, shape ``(...)``
        The ranks.
    """
    _, sv, vt = np.linalg.svd(z, full_matrices=False)
    keep = sv > tol
    return vt * keep[..., None], keep.sum(-1)
