"""The default estimate: least squares pulled towards the model file, as much as the data ask.

A log that excites some directions poorly lets least squares fit noise along them: the fit is
good on the recording and poor on another one. The default (``method="auto"``) regularises the
weighted least-squares fit towards the model file's own parameters ``theta_0``::

    min  ||R11 theta - r12||^2 + lam * sum_k s_k^2 (theta_k - theta0_k)^2

with ``s_k`` the norm of column ``k`` of ``R11`` (so ``lam`` is relative to the information the
data hold on each parameter) for the base parameters and 0 for the drive terms (a model file has
no friction or offsets: pulling them to 0 would bias them) and ``lam`` chosen by **blocked
cross-validation on the training data**: the training rows are cut into ``K`` contiguous time
blocks (serially correlated samples stay together), each block is predicted from the others,
and the ``lam`` of the smallest pooled held-out RMS is kept (``lam = 0``, plain weighted least
squares, is a candidate). Only the training data are used; the factors are the streamed
``(p + 1, p + 1)`` triangles of each block, so memory does not grow with the log.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .estimate import RowAccumulator, stacked_factor

#: candidate weights (relative to each column's information); 0 = no pull
LAMBDAS = (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)
#: number of contiguous blocks of the cross-validation
FOLDS = 5


@dataclass(frozen=True)
class Selection:
    """The outcome of the cross-validation.

    Parameters
    ----------
    lam : float
        The chosen weight (0: none).
    lambdas : tuple of float
        The candidates.
    cv_rms : tuple of float
        Pooled held-out RMS of each candidate [N m or N, unweighted].
    folds : int
        Number of contiguous blocks.
    """

    lam: float
    lambdas: tuple[float, ...]
    cv_rms: tuple[float, ...]
    folds: int

    def __repr__(self) -> str:
        return f"<Selection: weight {self.lam:g} of {len(self.lambdas)} by {self.folds}-fold blocked cross-validation>"

    def note(self) -> str:
        """One line for the report: what was chosen and why.

        Returns
        -------
        str
            The chosen weight, the number of blocks and the held-out RMS with and without it.
        """
        best = self.cv_rms[self.lambdas.index(self.lam)]
        plain = self.cv_rms[0]
        if self.lam == 0:
            return (f"default estimate: weighted least squares; a pull towards the model file's parameters did not "
                    f"predict better in {self.folds}-fold blocked cross-validation on the training data "
                    f"(held-out RMS {plain:.4g})")
        return (f"default estimate: weighted least squares pulled towards the model file's parameters, weight "
                f"{self.lam:g} chosen by {self.folds}-fold blocked cross-validation on the training data (held-out "
                f"RMS {best:.4g}, without the pull {plain:.4g})")


def ridge(r11: np.ndarray, r12: np.ndarray, theta0: np.ndarray, scale: np.ndarray, lam: float) -> np.ndarray:
    """The regularised solution (module docstring).

    Parameters
    ----------
    r11 : ndarray, shape ``(p, p)``
        Triangular factor of the (weighted) regressor.
    r12 : ndarray, shape ``(p,)``
        Its right-hand side.
    theta0 : ndarray, shape ``(p,)``
        The prior (the model file's parameters in the model's parameterisation).
    scale : ndarray, shape ``(p,)``
        ``s_k``, the column norms of the whole training factor.
    lam : float
        The weight (0: least squares).

    Returns
    -------
    ndarray, shape ``(p,)``
        The estimate.
    """
    h = r11.T @ r11 + lam * np.diag(scale**2)
    g = r11.T @ r12 + lam * scale**2 * theta0
    try:
        return np.linalg.solve(h, g)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(h, g, rcond=None)[0]


def _system(blocks: list[RowAccumulator], weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p = blocks[0].nparams
    acc = RowAccumulator(blocks[0].nrows, p)
    for b in blocks:
        for f, g in zip(acc.factors, b.factors):
            f.add(g.r)
        acc.samples += b.samples
    r = stacked_factor(acc, weights)
    r = np.vstack([r, np.zeros((max(p + 1 - r.shape[0], 0), p + 1))])
    return r[:p, :p], r[:p, p]


def _sse(block: RowAccumulator, theta: np.ndarray) -> float:
    return float(sum(np.linalg.norm(f.r @ np.r_[theta, -1.0]) ** 2 for f in block.factors))


def select(blocks: list[RowAccumulator], weights: np.ndarray, theta0: np.ndarray,
           lambdas=LAMBDAS, pulled: np.ndarray | None = None) -> Selection | None:
    """Choose the pull's weight by blocked cross-validation.

    Parameters
    ----------
    blocks : list of RowAccumulator
        The training rows of each contiguous time block, in time order.
    weights : ndarray, shape ``(m,)``
        Row weights of the fit (WLS).
    theta0 : ndarray, shape ``(p,)``
        The prior.
    lambdas : sequence of float
        Candidates, 0 first.
    pulled : ndarray of bool, shape ``(p,)``, optional
        The parameters pulled (default all): the file's inertial parameters are a prior, its
        absent friction and offsets are not.

    Returns
    -------
    Selection or None
        None when there are fewer than 2 usable blocks (nothing to cross-validate).
    """
    blocks = [b for b in blocks if b.samples > 0]
    if len(blocks) < 2:
        return None
    r11, _ = _system(blocks, weights)
    scale = pull_scale(r11, pulled)
    sse = np.zeros(len(lambdas))
    count = 0
    for k, held in enumerate(blocks):
        a11, a12 = _system(blocks[:k] + blocks[k + 1:], weights)
        for i, lam in enumerate(lambdas):
            sse[i] += _sse(held, ridge(a11, a12, theta0, scale, lam))
        count += held.samples * held.nrows
    rms = np.sqrt(sse / max(count, 1))
    best = int(np.argmin(np.where(np.isfinite(rms), rms, np.inf)))
    return Selection(float(lambdas[best]), tuple(float(x) for x in lambdas), tuple(float(x) for x in rms), len(blocks))


def pull_scale(r11: np.ndarray, pulled: np.ndarray | None = None) -> np.ndarray:
    """``s_k``: column norms of ``R11`` for the pulled parameters, 0 for the others.

    Parameters
    ----------
    r11 : ndarray, shape ``(p, p)``
        Triangular factor of the (weighted) training regressor.
    pulled : ndarray of bool, shape ``(p,)``, optional
        The parameters pulled (default all).

    Returns
    -------
    ndarray, shape ``(p,)``
        The scale of each parameter's pull.
    """
    scale = np.linalg.norm(r11, axis=0)
    return scale if pulled is None else np.where(pulled, scale, 0.0)


def split_blocks(acc_parts: list[RowAccumulator], folds: int = FOLDS) -> list[RowAccumulator]:
    """Group consecutive accumulators (time-ordered chunks) into at most ``folds`` blocks.

    Parameters
    ----------
    acc_parts : list of RowAccumulator
        Time-ordered pieces of the training rows.
    folds : int
        Number of blocks wanted.

    Returns
    -------
    list of RowAccumulator
        ``min(folds, len(acc_parts))`` blocks.
    """
    k = min(folds, len(acc_parts))
    groups = np.array_split(np.arange(len(acc_parts)), k)
    out = []
    for g in groups:
        acc = RowAccumulator(acc_parts[0].nrows, acc_parts[0].nparams)
        for i in g:
            for f, h in zip(acc.factors, acc_parts[i].factors):
                f.add(h.r)
            acc.samples += acc_parts[i].samples
        out.append(acc)
    return out
