"""Least-squares estimators on a streaming QR: OLS, WLS, standard deviations, excitation.

The model ``tau = A theta + e`` is accumulated row by row of the generalized forces: for each
measured row ``r`` (a joint's torque), the triangular factor of ``[A_r | tau_r]`` over every
sample (:class:`~baseparams.numerics.StreamingQR`), so memory and the estimators' cost do not
grow with the log length, and per-joint residuals and weights come without a second pass.

Ordinary least squares stacks the row factors; weighted least squares (Gautier's per-joint
weighting) divides row ``r``'s factor by its OLS noise ``sigma_r`` first. Standard deviations:
``cov(theta) = sigma^2 (A^T W A)^-1`` with ``sigma^2 = ||W^(1/2) e||^2 / (N - p)``, from the
stacked factor ``R11`` as ``sigma * ||row_i(R11^-1)||``; ``%sigma = 100 std / |theta|``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..display import counted, name_list, summary_repr
from ..errors import BaseparamsError
from ..numerics import StreamingQR


class RowAccumulator:
    """Per measured row, the triangular factor of ``[A_r | tau_r]`` over all samples fed.

    An accumulator is either fed samples (:meth:`add`: its own row factors) or the combination
    of others (:meth:`combine`: e.g. the cross-validation's blocks, the chunks of a long log),
    which holds no row factors of its own: what the estimators read of it, :meth:`stacked`,
    :meth:`row_sse` and :meth:`column_norms2`, is composed from its parts' (TSQR: the factor of
    the parts' stacked factors is the whole's; sums of squares add). A large model's row factors
    are ``m`` times ``min(S, p + 1) x (p + 1)``: the combinations add nothing to that, and each
    weighting's stacked factor is computed once per part (cached, :data:`STACK_CACHE` weightings).

    Parameters
    ----------
    nrows : int
        Number of measured rows ``m`` (generalized forces per sample).
    nparams : int
        Number of model parameters ``p`` (columns of ``A``).

    Attributes
    ----------
    oversampling : float
        Samples fed per independent sample of the low-passed signals (>= 1; the kept rate over
        :data:`~baseparams.ident.preprocess.DECIMATE_MARGIN` x the cutoff,
        :attr:`~baseparams.ident.preprocess.Prepared.oversampling`): the priors' weights are set against
        the information the rows hold, which keeping every filtered sample does not multiply.
    """

    #: stacked factors kept per accumulator (the weightings in use: ones, WLS, ...)
    STACK_CACHE = 3

    def __init__(self, nrows: int, nparams: int):
        self.nrows, self.nparams = int(nrows), int(nparams)
        self._factors: list[StreamingQR] | None = None
        self._parts: list[RowAccumulator] = []
        self._stacked: dict[bytes, np.ndarray] = {}
        self.samples = 0
        self.oversampling = 1.0

    @classmethod
    def combine(cls, parts) -> RowAccumulator:
        """The accumulator of every part's rows, without copying their factors.

        Parameters
        ----------
        parts : iterable of RowAccumulator
            Accumulators of the same rows and parameters (at least one).

        Returns
        -------
        RowAccumulator
            Their combination: the same estimates as one accumulator fed every part's samples.
        """
        parts = [p for p in parts]
        out = cls(parts[0].nrows, parts[0].nparams)
        for p in parts:
            if (p.nrows, p.nparams) != (out.nrows, out.nparams):
                raise BaseparamsError(f"RowAccumulator.combine: parts of {p.nrows} rows x {p.nparams} parameters "
                                      f"and {out.nrows} x {out.nparams}")
            out._parts.extend(p._parts if p._parts else [p])  # flat: parts of parts are parts
            out.samples += p.samples
        out.oversampling = max([1.0, *(p.oversampling for p in parts)])  # the rows' information per sample
        return out

    @property
    def factors(self) -> list[StreamingQR]:
        """The row factors (a combination's are formed from its parts' when first read)."""
        if self._factors is None:
            self._factors = [StreamingQR(self.nparams + 1) for _ in range(self.nrows)]
            for part in self._parts:
                for mine, theirs in zip(self._factors, part.factors):
                    if theirs.rows:
                        mine.add(theirs.r)
                        mine.rows += theirs.rows - theirs.r.shape[0]  # count samples, not factor rows
            self._parts = []
        return self._factors

    def add(self, a: np.ndarray, tau: np.ndarray) -> RowAccumulator:
        """Feed samples.

        Parameters
        ----------
        a : ndarray, shape ``(S, m, p)``
            Model regressor of the samples.
        tau : ndarray, shape ``(S, m)``
            Measured generalized forces.

        Returns
        -------
        RowAccumulator
            This object.

        Raises
        ------
        BaseparamsError
            Shapes that do not match, NaN or inf.
        """
        if a.shape[1:] != (self.nrows, self.nparams) or tau.shape != a.shape[:2]:
            raise BaseparamsError(f"regressor {a.shape} and torques {tau.shape} do not match "
                                  f"({self.nrows} rows, {self.nparams} parameters)")
        for r, f in enumerate(self.factors):
            f.add(a[:, r], tau[:, r])
        self.samples += a.shape[0]
        self._stacked.clear()
        return self

    def stacked(self, weights: np.ndarray) -> np.ndarray:
        """The triangular factor ``(<= p + 1, p + 1)`` of all rows, row ``r`` scaled by ``weights[r]``.

        Parameters
        ----------
        weights : ndarray, shape ``(m,)``
            Row weights.

        Returns
        -------
        ndarray, shape ``(<= p + 1, p + 1)``
            ``R`` of ``[W^(1/2) A | W^(1/2) tau]`` (read-only: cached per weighting).
        """
        w = np.ascontiguousarray(weights, dtype=float).reshape(-1)
        key = w.tobytes()
        hit = self._stacked.get(key)
        if hit is not None:
            return hit
        qr = StreamingQR(self.nparams + 1)
        if self._parts:  # TSQR over the parts (each part's own stacked factor computed once)
            for part in self._parts:
                qr.add(part.stacked(w))
        else:
            for wr, f in zip(w, self.factors):
                qr.add(wr * f.r)
        return self.remember(self._stacked, key, qr.r)

    def remember(self, cache: dict, key: bytes, factor: np.ndarray) -> np.ndarray:
        """Keep a factor read-only in a per-weighting cache of at most :data:`STACK_CACHE` entries (oldest dropped).

        Parameters
        ----------
        cache : dict of bytes to ndarray
            The cache (e.g. the stacked factors).
        key : bytes
            The weighting's bytes.
        factor : ndarray
            The factor.

        Returns
        -------
        ndarray
            ``factor``, made read-only.
        """
        factor.flags.writeable = False
        if len(cache) >= self.STACK_CACHE:
            cache.pop(next(iter(cache)))
        cache[key] = factor
        return factor

    def release(self) -> None:
        """Drop the cached stacked factors, this accumulator's and its parts': the fitting is done.

        A large model's are ``(p + 1)^2`` each, per weighting and per cross-validation block (a 220-link
        chain: 38 MB each, ~460 MB in all) and the covariance's pass comes after them; a later read
        computes them again.
        """
        self._stacked.clear()
        for part in self._parts:
            part.release()

    def row_sse(self, theta: np.ndarray) -> np.ndarray:
        """Each row's residual sum of squares at ``theta``.

        Parameters
        ----------
        theta : ndarray, shape ``(p,)``
            The values.

        Returns
        -------
        ndarray, shape ``(m,)``
            ``||A_r theta - tau_r||^2`` over the samples fed.
        """
        x = np.r_[np.asarray(theta, dtype=float), -1.0]
        if self._parts:
            return np.sum([part.row_sse(theta) for part in self._parts], axis=0)
        return np.array([float(np.sum((f.r @ x) ** 2)) for f in self.factors])

    def column_norms2(self) -> np.ndarray:
        """Each row's squared column norms, the torque's last.

        Returns
        -------
        ndarray, shape ``(m, p + 1)``
            ``||A_r[:, k]||^2`` and ``||tau_r||^2`` over the samples fed.
        """
        if self._parts:
            return np.sum([part.column_norms2() for part in self._parts], axis=0)
        return np.array([np.sum(f.r**2, axis=0) for f in self.factors]).reshape(self.nrows, self.nparams + 1)

    def row_gram(self, row: int, cols) -> np.ndarray:
        """One row's Gram matrix on some columns.

        Parameters
        ----------
        row : int
            The measured row.
        cols : array_like of int, shape ``(k,)``
            Columns of ``[A | tau]``.

        Returns
        -------
        ndarray, shape ``(k, k)``
            ``A_row[:, cols]^T A_row[:, cols]`` over the samples fed.
        """
        cols = np.asarray(cols, dtype=int)
        if self._parts:
            return np.sum([part.row_gram(row, cols) for part in self._parts], axis=0)
        x = self.factors[row].r[:, cols]
        return x.T @ x

    def nbytes(self) -> int:
        """Bytes held by the row factors (a combination's parts' included).

        Returns
        -------
        int
            The memory of the factors and pending rows.
        """
        if self._parts:
            return sum(part.nbytes() for part in self._parts)
        return sum(f.nbytes() for f in (self._factors or []))


@dataclass(frozen=True, eq=False)
class Estimate:
    """A least-squares estimate of the model parameters.

    Parameters
    ----------
    method : str
        ``ols`` or ``wls``.
    theta : ndarray, shape ``(p,)``
        The estimate.
    std : ndarray, shape ``(p,)``
        Standard deviations.
    pct_sigma : ndarray, shape ``(p,)``
        ``100 std / |theta|`` (inf where ``theta`` is 0).
    weights : ndarray, shape ``(m,)``
        Row weights used (``1 / sigma_r`` for WLS, ones for OLS).
    rms : ndarray, shape ``(m,)``
        Per-row residual RMS on the data fitted [N m or N].
    rms_total : float
        RMS over all rows and samples.
    condition_number : float
        Of the regressor with unit-norm columns (weighted as fitted).
    samples : int
        Samples fitted.
    R11 : ndarray, shape ``(p, p)``
        The stacked (weighted) triangular factor: the fit is ``||R11 theta - r12||^2 + rho^2``.
    r12 : ndarray, shape ``(p,)``
        Its right-hand side.
    cov : ndarray, shape ``(p, p)``, optional
        The covariance ``std`` comes from, when not the white formula's
        (:mod:`baseparams.ident.uncertainty`).
    covariance : str
        How ``std`` was computed (one line for the report).
    """

    method: str
    theta: np.ndarray
    std: np.ndarray
    pct_sigma: np.ndarray
    weights: np.ndarray
    rms: np.ndarray
    rms_total: float
    condition_number: float
    samples: int
    R11: np.ndarray
    r12: np.ndarray
    cov: np.ndarray | None = None
    covariance: str = "white (OLS formula: residuals taken as uncorrelated noise)"

    __repr__ = summary_repr


def stacked_factor(acc: RowAccumulator, weights: np.ndarray) -> np.ndarray:
    """The triangular factor ``(p + 1, p + 1)`` of all rows, row ``r`` scaled by ``weights[r]``.

    Parameters
    ----------
    acc : RowAccumulator
        The accumulated rows.
    weights : ndarray, shape ``(m,)``
        Row weights.

    Returns
    -------
    ndarray, shape ``(<= p + 1, p + 1)``
        ``R`` of ``[W^(1/2) A | W^(1/2) tau]`` (:meth:`RowAccumulator.stacked`, read-only).
    """
    return acc.stacked(weights)


def least_squares(acc: RowAccumulator, names: list[str], weights: np.ndarray | None = None,
                  method: str = "ols") -> Estimate:
    """Weighted least squares on the accumulated rows.

    Parameters
    ----------
    acc : RowAccumulator
        The accumulated rows (``m`` rows, ``p`` parameters).
    names : list of str, shape ``(p,)``
        Parameter names, for the error naming the parameters the data do not excite.
    weights : ndarray, shape ``(m,)``, optional
        Row weights (default ones: OLS).
    method : str
        Label of the estimate.

    Returns
    -------
    Estimate
        The estimate with its statistics.

    Raises
    ------
    BaseparamsError
        Fewer observations than parameters, or a regressor whose columns the data do not
        separate (naming the parameters of its weakest direction).
    """
    p, m = acc.nparams, acc.nrows
    w = np.ones(m) if weights is None else np.asarray(weights, dtype=float)
    n_obs = acc.samples * m
    if n_obs <= p:
        raise BaseparamsError(f"{counted(acc.samples, 'sample')} x {counted(m, 'row')} = "
                              f"{counted(n_obs, 'observation')} for {counted(p, 'parameter')}: record a longer log")
    r = stacked_factor(acc, w)
    r11, r12, rho = r[:p, :p], r[:p, p], abs(r[p, p]) if r.shape[0] > p else 0.0
    cond = condition_number(r11)
    if not np.isfinite(cond) or cond > 1e12:
        weak = excitation(r11, names)[1]
        raise BaseparamsError(f"the data do not excite every model parameter (condition number {cond:.3g}); "
                              f"weakest: {name_list(weak)}. Use a richer trajectory, or fewer drive terms")
    theta = np.linalg.solve(r11, r12)
    inv = np.linalg.inv(r11)
    # the white formula per independent sample: rows kept beyond the low-pass's information (every filtered
    # sample of a short log, issue 48) are correlated, and counting them as independent shrinks the std
    sigma = rho / np.sqrt(n_obs - p) * np.sqrt(acc.oversampling)
    std = sigma * np.linalg.norm(inv, axis=1)
    with np.errstate(divide="ignore"):
        pct = np.where(theta != 0, 100 * std / np.abs(theta), np.inf)
    res = np.sqrt(acc.row_sse(theta))
    rms = res / np.sqrt(max(acc.samples, 1))
    return Estimate(method, theta, std, pct, w, rms, float(np.sqrt((res**2).sum() / n_obs)), cond, acc.samples,
                    r11, r12)


def ols(acc: RowAccumulator, names: list[str]) -> Estimate:
    """Ordinary least squares (see :func:`least_squares`).

    Parameters
    ----------
    acc : RowAccumulator
        The accumulated rows.
    names : list of str
        Parameter names.

    Returns
    -------
    Estimate
        ``method = "ols"``.
    """
    return least_squares(acc, names)


def wls(acc: RowAccumulator, names: list[str], first: Estimate | None = None) -> Estimate:
    """Weighted least squares with per-row noise from the OLS residuals (Gautier 1997).

    ``sigma_r^2 = ||e_r||^2 / (S - p / m)``; rows weighted by ``1 / sigma_r``.

    Parameters
    ----------
    acc : RowAccumulator
        The accumulated rows.
    names : list of str
        Parameter names.
    first : Estimate, optional
        The OLS estimate of ``acc`` when already computed.

    Returns
    -------
    Estimate
        ``method = "wls"``; its ``rms`` are the unweighted per-row residuals.
    """
    first = ols(acc, names) if first is None else first
    dof = max(acc.samples - acc.nparams / acc.nrows, 1.0)
    sig = first.rms * np.sqrt(acc.samples / dof)
    floor = max(float(sig.max()) * 1e-6, np.finfo(float).tiny)
    return least_squares(acc, names, 1.0 / np.maximum(sig, floor), "wls")


def motion_factor(model, q, dq, ddq, chunk: int = 4000) -> np.ndarray:
    """The triangular factor of a motion's model regressor, unweighted, at every sample.

    What a motion's condition number is of: ``excite`` reports it for a design, ``identify`` for
    the log's states (column-scaled by :func:`excitation`).

    Parameters
    ----------
    model : IdentModel
        The identification model (its regressor's columns: base and drive parameters).
    q, dq, ddq : array_like, shape ``(S, state_columns)``
        The states (a loop robot's actuated coordinates).
    chunk : int
        Samples per regressor block (memory ``chunk * m * p`` floats, at most 32 MB).

    Returns
    -------
    ndarray, shape ``(p, p)``
        ``R`` with ``R^T R = sum_s A_s^T A_s``; :func:`excitation` gives its column-scaled condition number.
    """
    from ..numerics import StreamingQR

    q, dq, ddq = (np.asarray(x, dtype=float) for x in (q, dq, ddq))
    qr = StreamingQR(model.n_params)
    for _, a in model.regressor_blocks(q, dq, ddq, max_samples=chunk):  # at most REGRESSOR_BYTES at once
        qr.add(a)
    return qr.r


#: floating-point operations a motion's condition number may take (:func:`motion_stride`): ~15 s of QR
MOTION_FLOPS = 1e11


def motion_stride(model, samples: int) -> int:
    """Every how many samples a long log's motion factor is formed, to stay within :data:`MOTION_FLOPS`.

    A motion's condition number is of the regressor at every sample (:func:`motion_factor`), ``2 S m p^2``
    flops: a 220-link chain's 20 s log at 500 Hz would take 2e13. Where that exceeds the budget, every
    k-th sample (the states are smooth: their low-passed motion changes little between neighbours).

    Parameters
    ----------
    model : IdentModel
        The identification model (``m`` measured rows, ``p`` parameters).
    samples : int
        Samples of the motion.

    Returns
    -------
    int
        The stride ``k >= 1`` (1 for every model and log of ordinary size).
    """
    per = 2.0 * len(model.coords) * float(model.n_params) ** 2
    return max(1, math.ceil(samples * per / MOTION_FLOPS))


def condition_number(r11: np.ndarray) -> float:
    """Condition number of the column-scaled regressor (:func:`excitation`'s, without its weak directions).

    Parameters
    ----------
    r11 : ndarray, shape ``(p, p)``
        Triangular factor of the regressor (``||A x|| = ||R11 x||``).

    Returns
    -------
    float
        ``s_max / s_min`` of ``R11`` with unit-norm columns (inf when singular): singular values only,
        a third of a full SVD's work (a 2 196-parameter model: ~2 s instead of ~6).
    """
    norms = np.linalg.norm(r11, axis=0)
    s = np.linalg.svd(r11 / np.where(norms > 0, norms, 1.0), compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else np.inf


def excitation(r11: np.ndarray, names: list[str], weak_ratio: float = 1e-3) -> tuple[float, list[str]]:
    """Condition number of the column-scaled regressor, and its poorly excited parameters.

    Parameters
    ----------
    r11 : ndarray, shape ``(p, p)``
        Triangular factor of the regressor (``||A x|| = ||R11 x||``).
    names : list of str, shape ``(p,)``
        Parameter names.
    weak_ratio : float
        A direction is weak when its singular value is below ``weak_ratio`` times the largest.

    Returns
    -------
    condition_number : float
        ``s_max / s_min`` of ``R11`` with unit-norm columns (inf when singular).
    weak : list of str
        The parameters carrying the weak directions (the largest entry of each weak right
        singular vector), weakest first; empty when none.
    """
    norms = np.linalg.norm(r11, axis=0)
    scaled = r11 / np.where(norms > 0, norms, 1.0)
    s = np.linalg.svd(scaled, compute_uv=False)  # the singular vectors only where some direction is weak
    cond = float(s[0] / s[-1]) if s[-1] > 0 else np.inf
    weak_dirs = [k for k in range(len(s) - 1, -1, -1) if s[k] < weak_ratio * s[0]]
    if weak_dirs:
        _, s, vt = np.linalg.svd(scaled)
        weak_dirs = [k for k in range(len(s) - 1, -1, -1) if s[k] < weak_ratio * s[0]]
    weak = []
    for k in weak_dirs:
        name = names[int(np.argmax(np.abs(vt[k])))]
        if name not in weak:
            weak.append(name)
    zero_cols = [names[k] for k in np.flatnonzero(norms == 0)]
    return cond, zero_cols + [w for w in weak if w not in zero_cols]
