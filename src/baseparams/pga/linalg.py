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
    a, b : (*, 3) arrays

    Returns
    -------
    (*, 3) array ``a × b``.
    """
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def skew(w: np.ndarray) -> np.ndarray:
    """Skew matrix ``[w]_x`` with ``[w]_x v = w × v``.

    Parameters
    ----------
    w : (*, 3) array

    Returns
    -------
    (*, 3, 3) array.
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
    d : (m, 3) array of unit directions

    Returns
    -------
    x, y : (m, 3) arrays.
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
    a, b : (*, 4) arrays

    Returns
    -------
    (*, 4, 4) array. For ``a == b`` this is ``2 a a^T``: use :func:`outer` for ``a a^T``.
    """
    ab = np.einsum("...i,...j->...ij", a, b)
    return ab + np.swapaxes(ab, -1, -2)


def outer(a: np.ndarray) -> np.ndarray:
    """``a a^T`` of 4-vectors: ``(*, 4) -> (*, 4, 4)``."""
    return np.einsum("...i,...j->...ij", a, a)


def rowspace(a: np.ndarray, tol: float) -> np.ndarray:
    """Orthonormal basis of the row space of ``a``.

    Parameters
    ----------
    a : (k, m) array
    tol : absolute singular-value threshold

    Returns
    -------
    (r, m) array of orthonormal rows (``a`` itself when ``k == 0``).
    """
    if a.shape[0] == 0:
        return a
    _, s, vt = np.linalg.svd(a, full_matrices=False)
    return vt[: int(np.sum(s > tol))]


def nullspace(a: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Orthonormal basis of the right nullspace of ``a``.

    Parameters
    ----------
    a : (k, m) array
    tol : absolute singular-value threshold

    Returns
    -------
    (m - r, m) array of orthonormal rows (the identity when ``k == 0``).
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
    b : (m, k) array with nonzero columns
    rtol : singular-value threshold relative to the largest

    Returns
    -------
    (m, r) array of orthonormal columns (``b`` itself when ``k == 0``).
    """
    if b.shape[1] == 0:
        return b
    b = b / np.linalg.norm(b, axis=0)
    u, s, _ = np.linalg.svd(b, full_matrices=False)
    return u[:, : int(np.sum(s > rtol * s[0]))]


def null_rows(k: np.ndarray, tol: float) -> np.ndarray:
    """Right nullspaces of a batch of matrices with four columns, padded (one batched SVD).

    Parameters
    ----------
    k : (..., r, 4) array
    tol : absolute singular-value threshold

    Returns
    -------
    (..., 4, 4) array: orthonormal nullspace rows, the other rows zero.
    """
    _, sv, vt = np.linalg.svd(k, full_matrices=True)
    full = np.zeros(k.shape[:-2] + (4,))
    full[..., : sv.shape[-1]] = sv
    return vt * (full <= tol)[..., None]


def span_rows(z: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Row spaces of a batch of matrices with four columns, padded (one batched SVD).

    Parameters
    ----------
    z : (..., R, 4) array, ``R >= 4``
    tol : absolute singular-value threshold

    Returns
    -------
    rows : (..., 4, 4) array, orthonormal rows of the row space, the other rows zero
    rank : (...) int array
    """
    _, sv, vt = np.linalg.svd(z, full_matrices=False)
    keep = sv > tol
    return vt * keep[..., None], keep.sum(-1)
