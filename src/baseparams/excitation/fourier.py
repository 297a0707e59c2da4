"""The trajectory's parametrisation: a finite Fourier series per designed coordinate, at rest at both ends.

``q_j(t) = q0_j + sum_l a_lj / (l w) sin(l w t) - b_lj / (l w) cos(l w t)``, ``w = 2 pi f``, with
the first harmonic's coefficients eliminated (``a_1 = -sum_{l>=2} a_l``, ``b_1 = -sum_{l>=2} l b_l``)
so that ``dq(0) = ddq(0) = 0`` (:mod:`baseparams.excitation` describes the method).
"""

from __future__ import annotations

import numpy as np


def rest_map(harmonics: int) -> np.ndarray:
    """The map from free coefficients to all of them, at rest at ``t = 0``.

    Parameters
    ----------
    harmonics : int
        ``L >= 2``.

    Returns
    -------
    ndarray, shape ``(2 L, 2 L - 2)``
        ``[a_1..a_L, b_1..b_L] = N [a_2..a_L, b_2..b_L]`` with ``a_1 = -sum a_l`` and
        ``b_1 = -sum l b_l`` (``dq(0) = ddq(0) = 0``).
    """
    n = np.zeros((2 * harmonics, 2 * harmonics - 2))
    rest = np.arange(2, harmonics + 1)
    n[0, : harmonics - 1] = -1.0
    n[1:harmonics, : harmonics - 1] = np.eye(harmonics - 1)
    n[harmonics, harmonics - 1:] = -rest
    n[harmonics + 1:, harmonics - 1:] = np.eye(harmonics - 1)
    return n


def free_coefficients(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The free coefficients of a series at rest at ``t = 0`` (inverse of :func:`rest_map`).

    Parameters
    ----------
    a, b : ndarray, shape ``(L, m)``
        Sine and cosine coefficients.

    Returns
    -------
    ndarray, shape ``(m, 2 L - 2)``
        ``[a_2..a_L, b_2..b_L]`` per coordinate.
    """
    return np.column_stack([np.asarray(a)[1:].T, np.asarray(b)[1:].T])


def fourier_basis(t: np.ndarray, harmonics: int, omega: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The series' basis at rest at both ends: ``q = Bq x``, ``dq = Bv x``, ``ddq = Ba x``.

    Parameters
    ----------
    t : ndarray, shape ``(S,)``
        Times [s].
    harmonics : int
        ``L >= 2``.
    omega : float
        ``w = 2 pi f`` [rad/s].

    Returns
    -------
    Bq, Bv, Ba : ndarray, shape ``(S, 2 L - 1)``
        Columns: the offset ``q0``, then ``a_2..a_L, b_2..b_L`` (:func:`rest_map`); a coordinate's
        variables are ``x = [q0, a_2..a_L, b_2..b_L]``.
    """
    lw = omega * np.arange(1, harmonics + 1)
    wt = np.outer(t, lw)
    s, c = np.sin(wt), np.cos(wt)
    n = rest_map(harmonics)
    pos = np.hstack([s / lw, -c / lw]) @ n
    vel = np.hstack([c, s]) @ n
    acc = np.hstack([-s * lw, c * lw]) @ n
    one, zero = np.ones((len(t), 1)), np.zeros((len(t), 1))
    return np.hstack([one, pos]), np.hstack([zero, vel]), np.hstack([zero, acc])


def coefficients(x: np.ndarray, harmonics: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Offsets and all coefficients of the variables.

    Parameters
    ----------
    x : ndarray, shape ``(m, 2 L - 1)``
        Per coordinate ``[q0, a_2..a_L, b_2..b_L]``.
    harmonics : int
        ``L``.

    Returns
    -------
    offsets : ndarray, shape ``(m,)``
        ``q0``.
    a, b : ndarray, shape ``(L, m)``
        Every coefficient, ``a_1`` and ``b_1`` included.
    """
    full = x[:, 1:] @ rest_map(harmonics).T  # (m, 2 L)
    return x[:, 0].copy(), full[:, :harmonics].T.copy(), full[:, harmonics:].T.copy()
