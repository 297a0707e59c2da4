"""Standard deviations that hold when the residuals are correlated (HAC, Newey-West).

Real torque residuals are far from white noise: on the Panda and the TX40 their lag-1
correlation is 0.82-0.96 (model error, filtered noise), and the least-squares formula
``sigma^2 (A^T W A)^-1`` then understates the spread of the estimate 1.6-7 times. The
heteroskedasticity- and autocorrelation-consistent (HAC) covariance of the (weighted) least-squares
estimate is the sandwich

``cov(theta) = c H^-1 S H^-1``, ``H = A^T W A = R11^T R11``,
``S = sum_{|l| < b} (1 - |l| / b) Gamma_l``, ``Gamma_l = sum_t s_t s_{t-l}^T``,

with the score of sample ``t`` the sum over its measured rows ``s_t = sum_r w_r^2 A_tr^T e_tr``
(``e`` the residual at the estimate, ``w_r`` the row weights of WLS, ones for OLS), the Bartlett
kernel of Newey & West (1987) with bandwidth ``b`` samples, and ``c = N / (N - p)`` the same
degrees-of-freedom correction as the white formula (``N`` observations).

Why this and not a block bootstrap: it needs one more pass over the fitted rows and no refit, it
is exact for any bandwidth, and memory stays independent of the log's length. The Bartlett sum is
computed as overlapping block sums: with ``B_t`` the sum of the scores in the window of ``b``
samples ending at ``t`` (zero outside the log), ``sum_t B_t B_t^T = b S`` exactly, so the pass
keeps only the last ``b - 1`` scores (:class:`HacMeat`).

The bandwidth is Andrews' (1991) AR(1) plug-in for the Bartlett kernel,
``b = 1.1447 (alpha(1) N)^(1/3)`` with ``alpha(1)`` from an AR(1) fitted to each score
component; it is estimated on the first :data:`PILOT` fitted samples (all of them in a shorter
log; a large model's first :data:`PILOT_BYTES` of rows), whatever the chunks.

A large model's pass stays bounded: its rows are scored a few at a time (:data:`FEED_BYTES`), and
the projection bias ``Q`` (a ``p x p`` product per window) is summed over every k-th window, scaled
by k, so that it takes at most :data:`BIAS_FLOPS` (every window of an ordinary model; k = 8 on a
220-link chain's 100 samples).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import BaseparamsError

#: the choices of ``covariance``
COVARIANCES = ("hac", "white")
#: fitted samples the bandwidth is estimated on (the first ones; all of a shorter log)
PILOT = 4096
#: AR(1) coefficients of the score components are clipped to this before the plug-in
MAX_RHO = 0.97
#: the pilot's rows are held until the bandwidth is known: at most this many bytes of them (a large model's
#: pilot is shorter than :data:`PILOT` samples)
PILOT_BYTES = 256e6
#: bytes of weighted rows formed at once while feeding the meat
FEED_BYTES = 32e6
#: the most floating-point operations the projection bias ``Q`` takes (:class:`HacMeat`'s window stride)
BIAS_FLOPS = 2e11


def andrews_bandwidth(scores: np.ndarray, total: int) -> int:
    """Andrews' (1991) AR(1) plug-in bandwidth of the Bartlett kernel.

    Parameters
    ----------
    scores : ndarray, shape ``(n, p)``
        Consecutive score vectors (a pilot sample).
    total : int
        Samples of the whole series ``N`` (the bandwidth grows as ``N^(1/3)``).

    Returns
    -------
    int
        ``ceil(1.1447 (alpha(1) N)^(1/3))``, between 1 and ``N``.
    """
    s = np.asarray(scores, dtype=float)
    if len(s) < 3:
        return 1
    x, y = s[:-1], s[1:]
    den = np.einsum("ij,ij->j", x, x)
    ok = den > 0
    if not ok.any():
        return 1
    rho = np.clip(np.einsum("ij,ij->j", x[:, ok], y[:, ok]) / den[ok], -MAX_RHO, MAX_RHO)
    innov = np.mean((y[:, ok] - rho * x[:, ok]) ** 2, axis=0)
    scale = np.max(innov)
    innov = innov / scale if scale > 0 else innov
    num = np.sum(4 * rho**2 * innov**2 / ((1 - rho) ** 6 * (1 + rho) ** 2))
    den_a = np.sum(innov**2 / (1 - rho) ** 4)
    if not den_a > 0:
        return 1
    b = 1.1447 * (num / den_a * total) ** (1 / 3)
    return int(min(max(np.ceil(b), 1), max(total, 1)))


class HacMeat:
    """The Bartlett-weighted sum of lagged score products, fed in time order, and its projection bias.

    ``S = sum_{|l| < b} (1 - |l| / b) sum_t s_t s_{t-l}^T``, accumulated as ``(1 / b) sum_t B_t B_t^T``
    over the windows ``B_t`` of ``b`` consecutive scores (zero beyond both ends); and
    ``Q = (1 / b) sum_t C_t H^-1 C_t`` with ``C_t`` the windows' ``A^T W A`` (every
    ``stride``-th window, scaled): the residuals' scores are ``B_t - C_t H^-1 B_all`` exactly, so
    when the noise's long-run covariance is locally ``kappa A^T W A`` the expected meat is
    ``kappa (H - Q)`` short of ``kappa H`` by ``kappa Q`` (:func:`hac_covariance` adds it back).
    Each window's ``C_t`` is summed as its rows arrive, so no rows are held: memory ``b p`` floats
    for the scores and ``ceil(b / stride) p^2`` for the windows still open, whatever the number of
    samples and rows (a 220-link chain's 52 samples of rows were 200 MB).

    Parameters
    ----------
    nparams : int
        Length ``p`` of a score.
    bandwidth : int
        ``b`` (>= 1); ``b = 1`` is the heteroskedasticity-consistent (White) sum.
    h_inv : ndarray, shape ``(p, p)``, optional
        ``H^-1`` (needed for ``Q``).
    stride : int, optional
        ``Q`` summed over every ``stride``-th window, scaled by it (at least ``b // 8``).
    """

    def __init__(self, nparams: int, bandwidth: int, h_inv: np.ndarray | None = None, stride: int | None = None):
        self.p, self.b = int(nparams), max(int(bandwidth), 1)
        self.stride = max(1, self.b // 8, int(stride or 1))
        self.h_inv = h_inv
        self.tail = np.zeros((0, self.p))
        self.open: dict[int, np.ndarray] = {}  # the last sample of each window Q still sums -> its C so far
        self.sum = np.zeros((self.p, self.p))
        self.q = np.zeros((self.p, self.p))
        self.samples = 0

    def add(self, scores: np.ndarray, rows: np.ndarray | None = None) -> HacMeat:
        """Feed the next scores (and their weighted regressor rows, for ``Q``).

        Parameters
        ----------
        scores : ndarray, shape ``(n, p)``
            Score vectors of consecutive samples, following those fed before.
        rows : ndarray, shape ``(n, m, p)``, optional
            ``w_r A_tr`` of the same samples.

        Returns
        -------
        HacMeat
            This object.
        """
        s = np.asarray(scores, dtype=float).reshape(-1, self.p)
        if not len(s):
            return self
        keep = self.b - 1
        x = np.concatenate([self.tail, s])
        c = np.concatenate([np.zeros((1, self.p)), np.cumsum(x, axis=0)])
        ends = np.arange(len(self.tail), len(x)) + 1  # windows ending at each new sample (exclusive end)
        blocks = c[ends] - c[np.maximum(ends - self.b, 0)]
        self.sum += blocks.T @ blocks
        if rows is not None and self.h_inv is not None:
            self._windows(rows)
        self.tail = x[max(len(x) - keep, 0):] if keep else x[:0]
        self.samples += len(s)
        return self

    def _windows(self, rows: np.ndarray) -> None:
        """Add the rows of samples ``samples ..`` to the windows they fall in; close the windows they complete."""
        start, b, st = self.samples, self.b, self.stride
        end = start + len(rows)
        for t in range(-(-start // st) * st, end + b - 1, st):  # windows [t - b + 1, t] meeting [start, end)
            lo, hi = max(t - b + 1, start), min(t + 1, end)
            if lo >= hi:
                continue
            g = rows[lo - start:hi - start].reshape(-1, self.p)
            part = g.T @ g
            if t in self.open:
                self.open[t] += part
            else:
                self.open[t] = part
            if t < end:  # its last sample arrived
                c = self.open.pop(t)
                self.q += st * (c @ self.h_inv @ c)

    def meat(self) -> np.ndarray:
        """``S``: the windows running past the last sample closed (the fed scores unchanged).

        Returns
        -------
        ndarray, shape ``(p, p)``
            The Bartlett-weighted sum of lagged score products.
        """
        total = self.sum.copy()
        t = self.tail
        if len(t):
            suffix = np.cumsum(t[::-1], axis=0)  # windows ending past the log: sums of the last k scores
            total += suffix.T @ suffix
            total += (self.b - 1 - len(t)) * np.outer(suffix[-1], suffix[-1])  # a log shorter than b: whole
        return total / self.b

    def bias(self) -> np.ndarray:
        """``Q``: the windows running past the last sample closed.

        Returns
        -------
        ndarray, shape ``(p, p)``
            ``(1 / b) sum_t C_t H^-1 C_t`` (zero when no rows were fed).
        """
        q = self.q.copy()
        for c in self.open.values():  # windows ending past the last sample: their rows are all in
            q += self.stride * (c @ self.h_inv @ c)
        return q / self.b


def scores(a: np.ndarray, tau: np.ndarray, theta: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Per-sample scores ``s_t = sum_r w_r^2 A_tr^T (tau_tr - A_tr theta)``.

    Parameters
    ----------
    a : ndarray, shape ``(n, m, p)``
        Regressor rows of the fitted samples.
    tau : ndarray, shape ``(n, m)``
        Their torques.
    theta : ndarray, shape ``(p,)``
        The estimate.
    weights : ndarray, shape ``(m,)``
        Row weights of the fit.

    Returns
    -------
    ndarray, shape ``(n, p)``
        The scores.
    """
    e = (tau - a @ theta) * np.asarray(weights, dtype=float) ** 2
    return np.einsum("nmp,nm->np", a, e)


def hac_covariance(blocks, r11: np.ndarray, theta: np.ndarray, weights: np.ndarray, n_obs: int,
                   samples: int, bandwidth: int | None = None, corrected: bool = True) -> tuple[np.ndarray, int]:
    """The HAC (Newey-West, Bartlett) covariance of a least-squares estimate, in one pass.

    Parameters
    ----------
    blocks : iterable of (ndarray, ndarray), or callable returning one
        ``(A (n, m, p), tau (n, m))`` of the fitted samples, in time order. A callable or a list is
        read twice (the plug-in bandwidth's pilot scores first): no rows are held while the pilot
        is gathered, as a one-pass iterator's must be (up to :data:`PILOT_BYTES`).
    r11 : ndarray, shape ``(p, p)``
        The (weighted) triangular factor of the fit: ``R11^T R11 = A^T W A``.
    theta : ndarray, shape ``(p,)``
        The estimate the residuals are taken at.
    weights : ndarray, shape ``(m,)``
        Row weights of the fit.
    n_obs : int
        Observations ``N`` (samples x rows), for the ``N / (N - p)`` correction.
    samples : int
        Samples fitted (the plug-in bandwidth grows with it).
    bandwidth : int, optional
        Bartlett bandwidth [samples] (default: Andrews' AR(1) plug-in on the first
        :data:`PILOT` samples).
    corrected : bool
        Add back the meat the fit's projection removes (``kappa Q``, :class:`HacMeat`;
        ``kappa = tr(H^-1 S) / (p - tr(H^-1 Q))``); else scale by ``N / (N - p)``.

    Returns
    -------
    cov : ndarray, shape ``(p, p)``
        ``H^-1 (S + kappa Q) H^-1``, or ``N / (N - p) H^-1 S H^-1`` uncorrected.
    bandwidth : int
        The bandwidth used.
    """
    inv = np.linalg.inv(r11)
    h_inv = inv @ inv.T
    meat = hac_meat(blocks, h_inv, theta, weights, samples, bandwidth, corrected)
    return sandwich([meat], h_inv, n_obs, corrected), meat.b


def hac_meat(blocks, h_inv: np.ndarray, theta: np.ndarray, weights: np.ndarray, samples: int,
             bandwidth: int | None = None, corrected: bool = True) -> HacMeat:
    """The HAC meat of one stream of fitted rows (one log), in one pass.

    Parameters
    ----------
    blocks : iterable of (ndarray, ndarray), or callable returning one
        ``(A (n, m, p), tau (n, m))`` of the fitted samples, in time order. A callable or a list is
        read twice (the plug-in bandwidth's pilot scores first): no rows are held while the pilot
        is gathered, as a one-pass iterator's must be (up to :data:`PILOT_BYTES`).
    h_inv : ndarray, shape ``(p, p)``
        ``H^-1 = (A^T W A)^-1`` of the fit.
    theta : ndarray, shape ``(p,)``
        The estimate the residuals are taken at.
    weights : ndarray, shape ``(m,)``
        Row weights of the fit.
    samples : int
        Samples of this stream (the plug-in bandwidth grows with it).
    bandwidth : int, optional
        Bartlett bandwidth [samples] (default: Andrews' AR(1) plug-in on the first
        :data:`PILOT` samples).
    corrected : bool
        Also accumulate the projection bias ``Q`` (:class:`HacMeat`).

    Returns
    -------
    HacMeat
        The fed meat (``meat()``, ``bias()``, bandwidth ``b``).

    Raises
    ------
    BaseparamsError
        No fitted sample.
    """
    p = len(theta)
    w = np.asarray(weights, dtype=float)
    per_sample = 8.0 * len(w) * p  # bytes of one sample's rows
    step = max(1, min(512, int(FEED_BYTES // per_sample)))
    pilot_len = max(1, min(PILOT, int(PILOT_BYTES // per_sample)))

    def feed(meat, s, a):
        for k in range(0, len(s), step):  # bounded temporaries whatever the block
            meat.add(s[k:k + step], a[k:k + step] * w[None, :, None] if corrected else None)
        return meat

    def start(pilot_scores):
        b = bandwidth if bandwidth is not None else andrews_bandwidth(pilot_scores, samples)
        window = 2.0 * p * p * b * len(w) + 4.0 * float(p) ** 3  # one window's C H^-1 C
        return HacMeat(p, b, h_inv if corrected else None, stride=int(np.ceil(samples * window / BIAS_FLOPS)))

    if callable(blocks) or isinstance(blocks, (list, tuple)):  # read twice: the pilot's scores only, then the rows
        again = blocks if callable(blocks) else (lambda: blocks)
        pilot, got = [], 0
        if bandwidth is None:
            for a, tau in again():
                pilot.append(scores(a, tau, theta, w))
                got += len(pilot[-1])
                if got >= pilot_len:
                    break
        meat = start(np.concatenate(pilot) if pilot else np.zeros((0, p)))
        for a, tau in again():
            feed(meat, scores(a, tau, theta, w), a)
        if not meat.samples:
            raise BaseparamsError("no fitted sample to estimate the covariance from")
        return meat
    meat, pilot = None, []
    for a, tau in blocks:  # one pass: the pilot's rows held until the bandwidth is known
        s = scores(a, tau, theta, w)
        if meat is not None:
            feed(meat, s, a)
            continue
        pilot.append((s, a))
        if sum(len(x) for x, _ in pilot) >= pilot_len:  # the same pilot whatever the chunks
            meat = start(np.concatenate([x for x, _ in pilot]))
            for x, y in pilot:
                feed(meat, x, y)
    if meat is None and pilot:
        meat = start(np.concatenate([x for x, _ in pilot]))
        for x, y in pilot:
            feed(meat, x, y)
    if meat is None:
        raise BaseparamsError("no fitted sample to estimate the covariance from")
    return meat


def sandwich(meats, h_inv: np.ndarray, n_obs: int, corrected: bool = True) -> np.ndarray:
    """The HAC covariance from the meats of independent streams (one per log: their sums add).

    Parameters
    ----------
    meats : sequence of HacMeat or of (ndarray, ndarray)
        Per stream, the meat (or its ``(meat(), bias())``, ``(p, p)`` each), all at the same estimate.
    h_inv : ndarray, shape ``(p, p)``
        ``H^-1`` of the fit.
    n_obs : int
        Observations ``N`` (samples x rows) of all streams, for the uncorrected ``N / (N - p)``.
    corrected : bool
        Add back the meat the fit's projection removes (``kappa Q``,
        ``kappa = tr(H^-1 S) / (p - tr(H^-1 Q))``); else scale by ``N / (N - p)``.

    Returns
    -------
    ndarray, shape ``(p, p)``
        ``H^-1 (S + kappa Q) H^-1`` (symmetrised).
    """
    p = len(h_inv)
    pairs = [(m.meat(), m.bias()) if isinstance(m, HacMeat) else m for m in meats]
    raw = sum(s for s, _ in pairs)
    if corrected:
        q = sum(b for _, b in pairs)
        free = p - float(np.trace(h_inv @ q))
        kappa = float(np.trace(h_inv @ raw)) / max(free, 0.25 * p)
        raw = raw + kappa * q
    else:
        raw = raw * (n_obs / max(n_obs - p, 1))
    cov = h_inv @ raw @ h_inv
    return (cov + cov.T) / 2


def describe(covariance: str, bandwidth: int | None = None, rate: float | None = None) -> str:
    """How the standard deviations were computed, one line (the report and the JSON).

    Parameters
    ----------
    covariance : {"hac", "white"}
        The covariance.
    bandwidth : int, optional
        The HAC bandwidth [samples].
    rate : float, optional
        The fitted samples' rate [Hz], to say the bandwidth in seconds.

    Returns
    -------
    str
        E.g. ``HAC Newey-West (Bartlett), bandwidth 57 samples``.
    """
    if covariance == "white":
        return "white (OLS formula: residuals taken as uncorrelated noise)"
    secs = f" ({bandwidth / rate:.3g} s)" if rate else ""
    return f"HAC Newey-West (Bartlett), bandwidth {bandwidth} samples{secs}"


def with_covariance(estimate, theta: np.ndarray, cov: np.ndarray, label: str):
    """The estimate with standard deviations from ``cov`` (relative to the values ``theta`` reported).

    Parameters
    ----------
    estimate : Estimate
        The least-squares estimate.
    theta : ndarray, shape ``(p,)``
        The values reported (the estimate's, or the physical fit's).
    cov : ndarray, shape ``(p, p)``
        Their covariance.
    label : str
        :func:`describe`'s line.

    Returns
    -------
    Estimate
        A copy with ``std``, ``pct_sigma``, ``cov`` and ``covariance`` replaced.
    """
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        pct = np.where(theta != 0, 100 * std / np.abs(theta), np.inf)
    return replace(estimate, std=std, pct_sigma=pct, cov=cov, covariance=label)


def fitted_rows(model, prep, cols: np.ndarray, memory_mb: float, log, min_speed=None):
    """The fitted samples' rows again, chunk by chunk in time order (the covariance's second pass).

    The same samples :func:`baseparams.ident.accumulate_prepared` fitted on its chunked
    path (the kept samples are decided on the whole log's grid, so any chunk size gives them).

    Parameters
    ----------
    model : IdentModel
        The model.
    prep : Prepared
        The prepared training log.
    cols : ndarray of int
        Log column of each state column.
    memory_mb : float
        Largest regressor formed at once.
    log : JointLog
        The unfiltered training log ``prep`` came from.
    min_speed : float, optional
        The slow-sample threshold ``prep`` used.

    Yields
    ------
    tuple of ndarray
        ``(A (k, m, p), tau (k, m))`` per chunk.
    """
    from . import chunks
    from .preprocess import resample

    full = prep.full
    grid = chunks.Grid(full.n_samples, prep.trim, prep.factor, prep.design.cutoff, min_speed,
                       stride=prep.stride)
    margin = chunks.overlap(prep.design)
    size = chunks.window_size(model, memory_mb, margin, prep.stride)
    uniform = resample(log)
    for c in chunks.plan(full.n_samples, size, margin):
        sl = slice(c.lo, c.hi)
        rates = {k: None if getattr(uniform, k) is None else getattr(uniform, k)[sl] for k in ("dq", "ddq")}
        part = replace(uniform, t=uniform.t[sl], q=uniform.q[sl], tau=uniform.tau[sl], **rates)
        a, tau, _ = chunks.chunk_rows(part, c, grid, model, cols, rows=model.row_states)
        if a is not None and len(a):
            yield a, tau


def apply_covariance(f, acc, blocks, covariance: str = "hac", rate: float | None = None):
    """A fit with the standard deviations of the chosen covariance.

    Parameters
    ----------
    f : Fit
        The fit (its estimate's ``R11`` and weights; for ``physical`` the sandwich is taken at
        the physical values, with the weighted least-squares bread).
    acc : RowAccumulator
        The accumulated rows (observation count).
    blocks : iterable of (ndarray, ndarray), or callable returning one
        The fitted rows in time order (:func:`fitted_rows`); not read for ``white``.
    covariance : {"hac", "white"}
        ``hac``: Newey-West (:func:`hac_covariance`); ``white``: the least-squares formula.
    rate : float, optional
        Rate of the fitted samples [Hz] (to state the bandwidth in seconds).

    Returns
    -------
    fit : Fit
        ``f`` with its estimate's ``std``, ``pct_sigma``, ``cov`` and ``covariance`` set.
    note : str
        One line for the report.

    Raises
    ------
    BaseparamsError
        An unknown covariance.
    """
    if covariance not in COVARIANCES:
        raise BaseparamsError(f"unknown covariance {covariance!r}; choose {' or '.join(COVARIANCES)}")
    est = f.estimate
    if covariance == "white":
        inv = np.linalg.inv(est.R11)
        sigma2 = (est.std[0] / np.linalg.norm(inv[0])) ** 2 if np.linalg.norm(inv[0]) > 0 else 0.0
        label = describe("white")
        new = with_covariance(est, f.theta, sigma2 * inv @ inv.T, label)
        return replace(f, estimate=new), f"standard deviations: {label}"
    n_obs = acc.samples * acc.nrows
    cov, b = hac_covariance(blocks, est.R11, f.theta, est.weights, n_obs, acc.samples)
    label = describe("hac", b, rate)
    w = np.linalg.eigvalsh(0.5 * (cov + cov.T)) if np.all(np.isfinite(cov)) else np.array([-1.0, 1.0])
    if w.min() < -1e-6 * max(float(w.max()), 0.0):  # rounding on an ill-conditioned fit: say so
        label += (f" - INACCURATE: rounding made it indefinite (condition number "
                  f"{est.condition_number:.3g}), negative part dropped; --covariance white, or a richer log")
        cov = psd(cov)
    where = (" at the physical values with the weighted least-squares bread (a first-order sandwich: active "
             "constraints and the prior's pull are not credited, so constrained terms are not understated)"
             if f.physical is not None else "")
    note = (f"standard deviations: {label}: sandwich H^-1 S H^-1 over the {acc.samples} fitted samples' scores "
            f"(per sample, the sum over its joints' rows), the meat the fit's projection removes added back"
            f"{where}; the white-noise formula: --covariance white")
    return replace(f, estimate=with_covariance(est, f.theta, cov, label)), note


def psd(a: np.ndarray) -> np.ndarray:
    """The nearest symmetric positive semidefinite matrix (negative eigenvalues set to 0).

    Parameters
    ----------
    a : ndarray, shape ``(p, p)``
        A covariance that rounding on an ill-conditioned fit may have made indefinite.

    Returns
    -------
    ndarray, shape ``(p, p)``
        ``V max(w, 0) V^T`` of ``(a + a^T) / 2``.
    """
    a = 0.5 * (a + a.T)
    if not np.all(np.isfinite(a)):
        return a
    try:  # positive definite: a Cholesky factor exists (p^3 / 3 flops; an eigendecomposition ~9 p^3)
        np.linalg.cholesky(a)
        return a
    except np.linalg.LinAlgError:
        pass
    w, v = np.linalg.eigh(a)
    if w.min() >= 0:
        return a
    return (v * np.maximum(w, 0.0)) @ v.T
