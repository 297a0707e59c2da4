"""Synthetic excitation trajectories and torques with a known parameter vector (tests, demos).

A user checking a pipeline simulates a log from the model with known parameters and noise, runs
the identification on it and compares: what comes back must be what went in, to the noise.
"""

from __future__ import annotations

import numpy as np

from ..errors import BaseparamsError


def fourier_trajectory(m: int, duration: float, rate: float, rng: np.random.Generator, harmonics: int = 5,
                       base_frequency: float = 0.1, amplitude: float = 0.6,
                       center: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """A finite Fourier series per joint (Swevers et al. 1997), with exact derivatives.

    ``q_j(t) = c_j + sum_l a_lj / (l w) sin(l w t) - b_lj / (l w) cos(l w t)``, ``w = 2 pi f``,
    coefficients drawn normal and scaled so that each joint's peak excursion is about
    ``amplitude``.

    Parameters
    ----------
    m : int
        Number of joints.
    duration : float
        Length [s].
    rate : float
        Sampling rate [Hz].
    rng : numpy.random.Generator
        Source of the coefficients.
    harmonics : int
        Number of harmonics.
    base_frequency : float
        Fundamental frequency ``f`` [Hz].
    amplitude : float
        Approximate peak excursion of each joint [rad or m].
    center : ndarray, shape ``(m,)``, optional
        Offsets ``c`` (default zero).

    Returns
    -------
    t : ndarray, shape ``(S,)``
        Time [s], uniform.
    q, dq, ddq : ndarray, shape ``(S, m)``
        Positions, velocities and accelerations (exact).

    Raises
    ------
    BaseparamsError
        A non-positive duration or rate.
    """
    if not (duration > 0 and rate > 0):
        raise BaseparamsError(f"duration and rate must be > 0, got {duration} s and {rate} Hz")
    t = np.arange(int(round(duration * rate))) / rate
    w = 2 * np.pi * base_frequency * np.arange(1, harmonics + 1)  # (L,)
    a, b = rng.normal(size=(2, harmonics, m))
    wt = np.outer(t, w)  # (S, L)
    s, c = np.sin(wt), np.cos(wt)
    q = s @ (a / w[:, None]) - c @ (b / w[:, None])
    dq = c @ a + s @ b
    ddq = -s @ (a * w[:, None]) + c @ (b * w[:, None])
    peak = np.abs(q - q.mean(axis=0)).max(axis=0)
    k = amplitude / np.where(peak > 0, peak, 1.0)
    off = (np.zeros(m) if center is None else np.asarray(center, dtype=float)) - (q * k).mean(axis=0)
    return t, q * k + off, dq * k, ddq * k


def add_noise(tau: np.ndarray, std, rng: np.random.Generator) -> np.ndarray:
    """Gaussian noise on the generalized forces.

    Parameters
    ----------
    tau : ndarray, shape ``(S, m)``
        Noise-free generalized forces.
    std : float or array_like, shape ``(m,)``
        Standard deviation per joint [N m or N].
    rng : numpy.random.Generator
        Source of the noise.

    Returns
    -------
    ndarray, shape ``(S, m)``
        ``tau`` plus noise.
    """
    return tau + rng.normal(size=tau.shape) * np.broadcast_to(np.asarray(std, dtype=float), tau.shape[1:])
