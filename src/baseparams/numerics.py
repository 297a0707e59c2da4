"""The numerical method (the paper's baseline and our judge).

Random states, the stacked TP regressor and a rank decision by SVD with a stated tolerance and
singular-value gap.
"""

from __future__ import annotations

import os
import time
from contextlib import contextmanager
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from .display import summary_repr
from .enums import Rows, values
from .errors import BaseparamsError
from .model.robot import Robot
from .regressor import regressor

#: which generalized forces are measured (:class:`~baseparams.enums.Rows`)
ROWS = values(Rows)


def sample_states(robot: Robot, samples: int, rng: np.random.Generator, low: float = 0.0,
                  high: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random tree states ``q, dq, ddq (S, dof)``, uniform in ``(low, high)`` as in the paper's validation.

    Parameters
    ----------
    robot : Robot
        The robot (``dof`` coordinates).
    samples : int
        Number of states ``S``.
    rng : numpy.random.Generator
        Source of the draws (``q``, then ``dq``, then ``ddq``).
    low, high : float, optional
        Bounds of the uniform distribution, default ``(0, 1)``.

    Returns
    -------
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Coordinates, velocities and accelerations.
    """
    shape = (samples, robot.dof)
    return rng.uniform(low, high, shape), rng.uniform(low, high, shape), rng.uniform(low, high, shape)


#: the forms naming measured joints (:func:`row_mask`): only these joints' torques; the base wrench
#: and these joints' torques; every row but these (passive) joints'
ROW_FORMS = ("joints:", "base+joints:", "passive:")


def rows_spec(rows) -> str:
    """The measured rows as one string: a :class:`~baseparams.enums.Rows` or a joint-set form.

    Parameters
    ----------
    rows : str or sequence of str
        ``all``, ``joints``, ``base``, a form of :data:`ROW_FORMS` (``joints:NAME,NAME``,
        ``base+joints:NAME,...``, ``passive:NAME,...``), or a list of joint names (the measured
        joints: ``joints:`` with those names).

    Returns
    -------
    str
        The string form (a list becomes ``"joints:" + ",".join(names)``); not checked against a
        robot (:func:`row_mask` does).

    Raises
    ------
    BaseparamsError
        Neither a string nor a sequence of strings.
    """
    if isinstance(rows, str):
        return str(rows)
    try:
        names = [str(x) if isinstance(x, str) else None for x in rows]
    except TypeError:
        names = [None]
    if None in names:
        raise BaseparamsError(f"measured rows {rows!r}: expected one of {ROWS}, a form "
                              f"{', '.join(f + 'NAME,...' for f in ROW_FORMS)}, or a list of joint names")
    return "joints:" + ",".join(names)


def measured_joints(robot: Robot, rows) -> tuple[bool, np.ndarray]:
    """The base wrench and the joints whose generalized forces are measured.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies, one joint each).
    rows : str or sequence of str
        As for :func:`row_mask`.

    Returns
    -------
    base : bool
        Whether a floating root's wrench is measured (False without a floating base).
    joints : ndarray of bool, shape ``(n,)``
        Per body, whether its joint's coordinates are measured (a floating root's: its wrench).

    Raises
    ------
    BaseparamsError
        As for :func:`row_mask`.
    """
    mask = row_mask(robot, rows)
    per = np.zeros(robot.n, dtype=bool)
    np.logical_or.at(per, np.asarray(robot.dof_body, dtype=int), mask)
    base = bool(any(per[i] for i in range(robot.n) if robot.jtype[i] == "F"))
    return base, per


def row_mask(robot: Robot, rows) -> np.ndarray:
    """Which generalized forces are measured, as a boolean mask ``(dof,)``.

    Parameters
    ----------
    robot : Robot
        The robot (``dof`` coordinates).
    rows : str or sequence of str
        A :class:`~baseparams.enums.Rows`: ``all``; ``joints`` (every coordinate but the
        floating base's 6); ``base`` (only the floating base's wrench). Or a set of joints
        (every coordinate of each; a floating root's joint is its base wrench):
        ``joints:NAME,NAME`` (only these), ``base+joints:NAME,...`` (the floating base's wrench
        and these), ``passive:NAME,...`` (every row but these: under-actuated robots), or a
        list of joint names (as ``joints:``).

    Returns
    -------
    ndarray of bool, shape ``(dof,)``
        True for the measured rows. Without a floating base, ``joints`` is every row.

    Raises
    ------
    BaseparamsError
        Unknown ``rows`` or joint name (the message lists the robot's joints), no name after a
        form's colon, ``base`` (``base+joints:``) for a robot without a floating base, or a
        joint-set form for a robot with loops or couplings.
    """
    rows = rows_spec(rows)
    is_base = np.array([robot.jtype[b] == "F" for b in robot.dof_body], dtype=bool)
    if rows in ROWS:
        if rows == "all":
            return np.ones(robot.dof, dtype=bool)
        if not is_base.any():
            if rows == "base":
                raise BaseparamsError(f"robot {robot.name!r} has no floating base: no base-wrench rows")
            return np.ones(robot.dof, dtype=bool)
        return ~is_base if rows == "joints" else is_base
    form = next((f for f in ROW_FORMS if rows.startswith(f)), None)
    if form is None:
        raise BaseparamsError(f"unknown measured rows {rows!r}; expected one of {ROWS} or "
                              f"{', '.join(f + 'NAME,...' for f in ROW_FORMS)}")
    if robot.has_loops:
        raise BaseparamsError(f"robot {robot.name!r}: measured rows {rows!r} are not defined with loops or "
                              f"couplings; the generalized forces are the actuated ones (rows 'all')")
    names = [x.strip() for x in rows[len(form):].split(",") if x.strip()]
    if not names:
        raise BaseparamsError(f"measured rows {rows!r}: no joint named after {form!r}; "
                              f"the robot's joints: {', '.join(robot.joint_names)}")
    index = {nm: i for i, nm in enumerate(robot.joint_names)}
    for nm in names:
        if nm not in index:
            raise BaseparamsError(f"measured rows {rows!r}: robot {robot.name!r} has no joint {nm!r}; "
                                  f"its joints: {', '.join(robot.joint_names)}")
    named = np.isin(np.asarray(robot.dof_body, dtype=int), [index[nm] for nm in names])
    if form == "passive:":
        return ~named
    if form == "base+joints:":
        if not is_base.any():
            raise BaseparamsError(f"measured rows {rows!r}: robot {robot.name!r} has no floating base: "
                                  f"no base-wrench rows")
        return named | is_base
    return named


#: a gap in a spectrum: neighbouring singular values at least this ratio apart ...
GAP_RATIO = 100.0
#: ... and at least this many times the largest neighbour ratio inside the clusters on either side
GAP_OVER_SPREAD = 10.0
#: singular values at most this fraction of the largest are rounding of zero: one cluster, whatever their ratios
ZERO_FLOOR = 1e-13


@dataclass(frozen=True)
class Cluster:
    """Consecutive singular values with no gap between them (:func:`spectrum`).

    Parameters
    ----------
    first : int
        Index of its largest value in the descending spectrum (0-based).
    count : int
        Number of directions.
    top, bottom : float
        Its largest and smallest value, relative to the spectrum's largest.
    spread : float
        The largest ratio of neighbouring values inside it (1 for one direction; the values at
        or below :data:`ZERO_FLOOR` do not count).
    widest : (int, float)
        Where that ratio is: the rank a cut there would state, and the ratio.
    """

    first: int
    count: int
    top: float
    bottom: float
    spread: float

    @property
    def stop(self) -> int:
        """Index after its last value: the rank of a cut just below it."""
        return self.first + self.count

    @property
    def zero(self) -> bool:
        """Every value is rounding of zero (at most :data:`ZERO_FLOOR` of the largest)."""
        return self.top <= ZERO_FLOOR

    widest: tuple[int, float] = (0, 1.0)

    __repr__ = summary_repr

    def describe(self) -> str:
        """E.g. ``10 directions 9.4e-07 - 9.5e-06 (neighbour ratios <= 1.9)``.

        Returns
        -------
        str
            The count, the range relative to the largest value and the spread.
        """
        many = "s" if self.count != 1 else ""
        if self.zero:
            return f"{self.count} direction{many} <= {ZERO_FLOOR:g} (rounding of zero)"
        rng = f"{self.top:.2g}" if self.count == 1 else f"{self.bottom:.2g} - {self.top:.2g}"
        where = f", the largest at rank {self.widest[0]}" if self.spread >= GAP_OVER_SPREAD else ""
        why = ": not a gap, the steps around it are as large" if self.spread >= GAP_RATIO else ""
        inside = f" (neighbour ratios <= {self.spread:.2g}{where}{why})" if self.count > 1 else ""
        return f"{self.count} direction{many} {rng}{inside}"


@dataclass(frozen=True, eq=False)
class Spectrum:
    """A spectrum's structure: clusters of singular values and the gaps between them.

    Made by :func:`spectrum`. A *gap* is a ratio of neighbouring values of at least
    :data:`GAP_RATIO` and at least :data:`GAP_OVER_SPREAD` times the largest neighbour ratio
    inside the clusters on either side; a rank is stated only at a gap (:meth:`at_gap`), never
    inside a cluster.

    Parameters
    ----------
    values : ndarray, shape ``(m,)``
        The singular values, descending, relative to the largest (zeros when all vanish).
    clusters : tuple of Cluster
        In descending order; consecutive clusters are separated by a gap.
    """

    values: np.ndarray
    clusters: tuple[Cluster, ...]

    __repr__ = summary_repr

    @property
    def cuts(self) -> tuple[int, ...]:
        """The ranks stated at a gap: ``0``, each cluster's :attr:`~Cluster.stop`."""
        return (0,) + tuple(c.stop for c in self.clusters)

    def gap(self, rank: int) -> float:
        """``values[rank-1] / values[rank]`` (inf at ``0``, at full rank and above a zero value).

        Parameters
        ----------
        rank : int
            A cut, ``0 <= rank <= m``.

        Returns
        -------
        float
            The ratio across the cut.
        """
        s = self.values
        if rank <= 0 or rank >= len(s):
            return np.inf
        with np.errstate(over="ignore", divide="ignore"):
            return float(s[rank - 1] / s[rank]) if s[rank] > 0 else np.inf

    def at_gap(self, rank: int) -> bool:
        """Whether a cut at ``rank`` lies at a gap (between clusters), not inside a cluster.

        Parameters
        ----------
        rank : int
            The number of directions counted in.

        Returns
        -------
        bool
            True at ``0``, at full rank and at every cluster boundary.
        """
        return rank in self.cuts

    def straddling(self, bound: float) -> Cluster | None:
        """The cluster the threshold ``bound`` (relative) falls inside, or None when it lies in a gap.

        Parameters
        ----------
        bound : float
            A threshold relative to the largest value.

        Returns
        -------
        Cluster or None
            The cluster with a value above ``bound`` and one at or below it.
        """
        return next((c for c in self.clusters if c.top > bound >= c.bottom), None)

    def lines(self) -> list[str]:
        """One line per cluster, largest first, with the gap below it and the rank a cut there states.

        Returns
        -------
        list of str
            E.g. ``34 directions 6.5e-03 - 1 (...); gap 680 below: rank 34``.
        """
        out = []
        for c in self.clusters:
            g = self.gap(c.stop)
            below = "" if c.stop >= len(self.values) else f"; gap {g:.3g} below: rank {c.stop}"
            out.append(c.describe() + below)
        return out


def _clusters(s: np.ndarray, cuts: list[int], nz: int) -> list[Cluster]:
    """Clusters of the descending relative values ``s`` between the cut positions (``nz`` non-zero values)."""
    bounds = [0, *cuts, len(s)]
    out = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        live = s[a:min(b, nz)]
        steps = live[:-1] / live[1:] if len(live) > 1 else np.ones(1)
        k = int(np.argmax(steps))
        out.append(Cluster(a, b - a, float(s[a]), float(s[b - 1]), float(steps[k]), (a + k + 1, float(steps[k]))))
    return out


def spectrum(sv: np.ndarray, floor: float = ZERO_FLOOR) -> Spectrum:
    """The clusters and gaps of a spectrum (:class:`Spectrum`).

    A *gap* is a ratio of neighbouring values of at least :data:`GAP_RATIO` (or the step down to
    the values at or below ``floor``, rounding of zero) that is also at least
    :data:`GAP_OVER_SPREAD` times every other neighbour ratio between it and the next such ratio
    on either side (the spread of the runs it separates): a ratio that does not stand out from
    the steps around it is part of a continuum, not a divide. The clusters are the runs between
    gaps; a cluster may hold a ratio of 100 or more that is not a gap (:attr:`Cluster.spread`).

    Parameters
    ----------
    sv : ndarray, shape ``(m,)``
        Singular values (any order, non-negative).
    floor : float, default :data:`ZERO_FLOOR`
        Values at most this fraction of the largest are one cluster of zeros.

    Returns
    -------
    Spectrum
        The values relative to the largest, descending, and their clusters.
    """
    s = np.sort(np.abs(np.asarray(sv, dtype=float)))[::-1]
    if len(s) == 0 or s[0] <= 0:
        s = np.zeros(len(s))
        return Spectrum(s, (Cluster(0, len(s), 0.0, 0.0, 1.0),) if len(s) else ())
    s = s / s[0]
    nz = int(np.sum(s > floor))
    with np.errstate(divide="ignore", over="ignore"):
        ratio = np.r_[np.inf, s[:-1] / np.maximum(s[1:], np.finfo(float).tiny)]
    cuts = [k for k in range(1, nz) if ratio[k] >= GAP_RATIO]
    if 0 < nz < len(s) and ratio[nz] >= GAP_RATIO:
        cuts.append(nz)
    runs = _clusters(s, cuts, nz)  # the runs between candidate gaps: their spreads are below GAP_RATIO
    keep = [k for i, k in enumerate(cuts)
            if ratio[k] >= GAP_OVER_SPREAD * max(runs[i].spread, 1.0 if runs[i + 1].zero else runs[i + 1].spread)]
    return Spectrum(s, tuple(_clusters(s, keep, nz)))


@dataclass(frozen=True, eq=False)
class NumericalResult:
    """Rank decision on the stacked regressor ``W (S * rows, 10 n)``.

    Made by :func:`rank_decision`; columns of ``W`` and the bases are in the ``paper``
    convention.

    Parameters
    ----------
    rank : int
        Number of singular values above ``tol``.
    nullity : int
        ``10 n - rank``.
    singular_values : ndarray, shape ``(10 n,)``
        Descending (zero-padded when ``W`` has fewer rows than columns).
    rtol : float
        Relative tolerance.
    tol : float
        The absolute threshold used (``rtol * s_max``; ``rtol`` when ``s_max = 0``).
    gap : float
        ``gap = s[rank-1] / s[rank]`` (inf when full rank or rank 0).
    null_basis : ndarray, shape ``(10 n, k)``
        Orthonormal basis of the nullspace (``k = nullity``), paper convention.
    range_basis : ndarray, shape ``(10 n, rank)``
        Orthonormal basis of the row space of ``W``, paper convention.
    samples : int
        Number of random states stacked in ``W`` (0 when not recorded).
    seconds : float
        Wall time (of the whole numerical method in :func:`numerical_nullspace`).
    min_gap : float
        Smallest ``gap`` for a decided rank (:attr:`decided`).
    """

    rank: int
    nullity: int
    singular_values: np.ndarray
    rtol: float
    tol: float
    gap: float
    null_basis: np.ndarray
    range_basis: np.ndarray
    samples: int
    seconds: float
    min_gap: float

    __repr__ = summary_repr

    @property
    def spectrum(self) -> Spectrum | None:
        """The clusters and gaps of :attr:`singular_values` (:func:`spectrum`); None without them."""
        if len(self.singular_values) == 0:
            return None
        if "_spectrum" not in self.__dict__:
            object.__setattr__(self, "_spectrum", spectrum(self.singular_values))
        return self.__dict__["_spectrum"]

    @property
    def decided(self) -> bool:
        """True when the rank lies at a gap of at least ``min_gap`` (:meth:`Spectrum.at_gap`: never in a cluster)."""
        spec = self.spectrum
        return self.gap >= self.min_gap and (spec is None or spec.at_gap(self.rank))


@lru_cache(maxsize=1)
def _blas_controller():
    """Threadpoolctl's controller of the loaded BLAS libraries (created once), or None."""
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:  # pragma: no cover - a core dependency
        return None
    return ThreadpoolController()


@contextmanager
def blas_threads(limit: int | None = None):
    """Run the enclosed dense linear algebra on ``limit`` BLAS threads.

    The factorizations here are small to medium (``10 n`` columns): measured on a 2-core
    machine, OpenBLAS's default threads made a 655 x 131 QR 10-20x slower (16-30 ms against
    1.2 ms) and the certification's SVDs 10-140x slower in some runs, and one thread was never
    slower. The default is the environment variable ``BASEPARAMS_BLAS_THREADS``, else 1.

    Parameters
    ----------
    limit : int, optional
        Number of threads; default ``BASEPARAMS_BLAS_THREADS`` or 1. ``0``: leave BLAS alone.

    Yields
    ------
    None
        Inside the block, BLAS (through threadpoolctl) uses at most ``limit`` threads.
    """
    if limit is None:
        limit = int(os.environ.get("BASEPARAMS_BLAS_THREADS", "1"))
    ctl = _blas_controller() if limit > 0 else None
    if ctl is None:
        yield
        return
    with ctl.limit(limits=limit, user_api="blas"):
        yield


class StreamingQR:
    """The triangular factor of a tall matrix fed in blocks of rows: ``W^T W = R^T R``.

    ``R`` has the singular values and right singular vectors of ``W``, ``||W x|| = ||R x||``
    for every ``x`` and ``||W||_F = ||R||_F``: rank decisions, nullspaces and least squares
    need only ``R``. Memory is ``O(ncols^2)`` whatever the number of rows; each block costs a
    Householder QR of ``[R; block]`` (LAPACK ``geqrf``, no ``Q`` formed). Backward stable: no
    normal equations, so no squared condition number.

    Parameters
    ----------
    ncols : int
        Number of columns of ``W``.

    Attributes
    ----------
    r : ndarray, shape ``(min(rows, ncols), ncols)``
        The upper-triangular (trapezoidal while ``rows < ncols``) factor so far.
    rows : int
        Rows fed so far.

    Examples
    --------
    >>> import numpy as np
    >>> w = np.random.default_rng(0).normal(size=(1000, 4))
    >>> qr = StreamingQR(4).add(w[:300]).add(w[300:])
    >>> qr.rows, qr.r.shape, bool(np.allclose(qr.r.T @ qr.r, w.T @ w))
    (1000, (4, 4), True)
    """

    #: rows per Householder step, at least: [R; 512 rows] stays in cache (1.5x faster than
    #: 8000-row steps for 37 columns); wide factors take more (:meth:`step`)
    STEP = 512
    #: columns from which a full factor takes each step by :func:`triangular_update` (LAPACK through SciPy, which a
    #: narrower one does not import: ``analyze`` stays numpy-only), not by a dense QR of ``[R; rows]``
    WIDE = 256
    #: a wide factor's rows gathered per step [bytes], within ``ncols`` and ``4 ncols`` rows: each step's
    #: blocked Householder update (:func:`triangular_update`) works best on at least ``ncols`` rows
    STEP_BYTES = 64e6

    def __init__(self, ncols: int):
        self.ncols = int(ncols)
        self._r = np.zeros((0, self.ncols))
        self._pending: list[np.ndarray] = []  # rows fed, not yet folded into R (fewer than one step)
        self._npending = 0
        self.rows = 0

    @property
    def r(self) -> np.ndarray:
        """The triangular factor of every row fed so far (pending rows folded in first)."""
        if self._pending:
            self._flush()
        return self._r

    @property
    def step(self) -> int:
        """Rows gathered before a Householder step: :data:`STEP`, or for a wide factor ``ncols`` to ``4 ncols``.

        Small blocks fed one by one (a regressor evaluated a few states at a time, the factors of
        many rows stacked) are gathered first: a step per block re-triangularised ``R`` each time
        (220 row factors of a 220-link chain: 3e12 flops instead of 2e11).
        """
        n = self.ncols
        return max(self.STEP, min(4 * n, max(n, int(self.STEP_BYTES // (8 * max(n, 1))))))

    def add(self, block: np.ndarray, rhs: np.ndarray | None = None) -> StreamingQR:
        """Feed rows.

        Parameters
        ----------
        block : array_like, shape ``(k, ncols)`` or ``(..., c)``
            The next rows of ``W`` (any ``k``, ``0`` included); an array of more dimensions is
            read as rows of its last axis (e.g. a regressor ``(S, rows, c)``).
        rhs : array_like, shape ``(k,)`` or ``(k, ncols - c)``, optional
            Further columns of the same rows, e.g. the measured torques of a least-squares
            problem ``[Y | tau]`` (``R``'s last column then holds ``Q^T tau`` and its corner the
            residual norm); joined without an extra copy.

        Returns
        -------
        StreamingQR
            This object (calls chain).

        Raises
        ------
        BaseparamsError
            Blocks of the wrong width or number of rows, or NaN / inf in them.
        """
        block = np.asarray(block, dtype=float)
        block = block.reshape(-1, block.shape[-1]) if block.ndim != 2 else block
        if block.shape[0] == 0:  # e.g. a chunk whose samples were all removed (too slow): nothing to add
            return self
        parts = [block] if rhs is None else [block, np.asarray(rhs, dtype=float).reshape(block.shape[0], -1)]
        width = sum(p.shape[1] for p in parts)
        if width != self.ncols:
            raise BaseparamsError(f"StreamingQR: a block must have shape (k, {self.ncols}), got "
                                  f"{' + '.join(str(p.shape) for p in parts)}")
        if not all(np.all(np.isfinite(p)) for p in parts):
            raise BaseparamsError("StreamingQR: the block contains NaN or inf")
        step, nrows, start = self.step, block.shape[0], 0
        while start < nrows:  # gather up to a step of rows (copies: the caller may reuse its buffers)
            stop = min(start + step - self._npending, nrows)
            rows = np.empty((stop - start, self.ncols))
            col = 0
            for p in parts:
                rows[:, col:col + p.shape[1]] = p[start:stop]
                col += p.shape[1]
            self._pending.append(rows)
            self._npending += stop - start
            start = stop
            if self._npending >= step:
                self._flush()
        self.rows += nrows
        return self

    def nbytes(self) -> int:
        """Bytes held: the factor and the rows not yet folded in.

        Returns
        -------
        int
            ``R``'s bytes plus the pending rows'.
        """
        return int(self._r.nbytes + sum(p.nbytes for p in self._pending))

    def _flush(self) -> None:
        """Fold the pending rows into ``R`` (one Householder QR of ``[R; pending]``)."""
        if self._r.shape[0] == self.ncols >= self.WIDE:  # a wide full triangle: keep its zeros (triangular_update)
            rows = self._pending[0] if len(self._pending) == 1 else np.concatenate(self._pending)
            self._pending, self._npending = [], 0
            self._r = triangular_update(self._r, rows)
            return
        stacked = np.concatenate([self._r, *self._pending]) if self._r.shape[0] else (
            self._pending[0] if len(self._pending) == 1 else np.concatenate(self._pending))
        self._pending, self._npending = [], 0
        self._r = stacked  # the old R freed before the QR allocates its own
        with blas_threads():
            self._r = np.linalg.qr(stacked, mode="r")


def triangular_update(r: np.ndarray, rows: np.ndarray, triangular: bool = False) -> np.ndarray:
    """The triangular factor of ``[R; rows]`` for a square upper-triangular ``R`` (LAPACK ``dtpqrt``).

    A Householder QR of the stacked matrix that skips ``R``'s zeros: ``2 k n^2`` flops for ``k`` rows
    of ``n`` columns, where a QR of ``[R; rows]`` as a dense matrix re-triangularises ``R`` for
    another ``4/3 n^3`` (a wide factor fed a block at a time: 2.5x faster, 2 197 columns).

    Parameters
    ----------
    r : ndarray, shape ``(n, n)``
        Upper triangular, zeros below the diagonal (zero diagonal entries allowed: columns no row has
        touched yet). Not modified.
    rows : ndarray, shape ``(k, n)``
        The rows added (overwritten when Fortran-ordered: pass rows of your own).
    triangular : bool
        ``rows`` is itself upper triangular (``k = n``, another factor: a TSQR's merge), which the
        update skips too (``2/3 n^3`` flops instead of ``2 n^3``).

    Returns
    -------
    ndarray, shape ``(n, n)``
        ``R'`` with ``R'^T R' = R^T R + rows^T rows`` (upper triangular, signs as LAPACK leaves them).
    """
    from scipy.linalg import lapack

    n = r.shape[1]
    if rows.shape[0] == 0 or n == 0:
        return r
    if triangular and rows.shape != (n, n):
        raise BaseparamsError(f"triangular_update: a triangular block must be {n} x {n}, got {rows.shape}")
    a = np.array(r, order="F")  # a copy: a caller may hold R (StreamingQR.r) while more rows come
    b = np.asfortranarray(rows)
    with blas_threads():
        a, _, _, info = lapack.dtpqrt(n if triangular else 0, max(1, min(64, n)), a, b, overwrite_a=1, overwrite_b=1)
    if info != 0:
        raise BaseparamsError(f"triangular_update: LAPACK dtpqrt failed (info {info})")
    return a  # LAPACK neither reads nor writes below the diagonal: R's zeros stay


def rank_decision(w: np.ndarray, rtol: float = 1e-9, min_gap: float = 1e4, samples: int = 0,
                  seconds: float = 0.0) -> NumericalResult:
    """SVD rank of ``w`` with relative tolerance ``rtol``; reports the gap.

    Parameters
    ----------
    w : ndarray, shape ``(R, 10 n)``
        The stacked regressor (any matrix).
    rtol : float, optional
        Singular values above ``rtol * s_max`` count.
    min_gap : float, optional
        Gap ``s[rank-1] / s[rank]`` needed for :attr:`NumericalResult.decided`.
    samples : int, optional
        Number of states stacked in ``w``, recorded in the result.
    seconds : float, optional
        Wall time, recorded in the result.

    Returns
    -------
    NumericalResult
        Rank, nullity, singular values, gap and orthonormal null and range bases.
    """
    if w.shape[0] > w.shape[1]:  # same singular values and V, without U (a 15000-row U is 1.8 GB)
        w = StreamingQR(w.shape[1]).add(w).r
    with blas_threads():
        try:
            _, s, vt = np.linalg.svd(w, full_matrices=w.shape[0] < w.shape[1])
        except np.linalg.LinAlgError:  # LAPACK's divide-and-conquer (gesdd) fails on rare inputs
            from scipy.linalg import svd

            _, s, vt = svd(w, full_matrices=w.shape[0] < w.shape[1], lapack_driver="gesvd")
    ncol = w.shape[1]
    sv = np.zeros(ncol)
    sv[: len(s)] = s
    tol = rtol * (sv[0] if sv[0] > 0 else 1.0)
    rank = int(np.sum(sv > tol))
    if 0 < rank < ncol:
        with np.errstate(over="ignore"):  # a gap beyond the float range is an infinite gap
            gap = sv[rank - 1] / max(sv[rank], np.finfo(float).tiny)
    else:
        gap = np.inf
    return NumericalResult(rank, ncol - rank, sv, rtol, tol, float(gap), vt[rank:].T, vt[:rank].T,
                           samples, seconds, min_gap)


#: trees (couplings allowed) of at least this many bodies are certified body by body
#: (:mod:`baseparams.nullspace.structured`, ``certify(method="auto")``)
STRUCTURED_MIN_BODIES = 40
#: default number of random samples: the paper's 100 for trees, 5000 actuated samples for loops
DEFAULT_SAMPLES_TREE = 100
DEFAULT_SAMPLES_LOOPS = 5000
#: default sampling half-width of actuated coordinates around q = 0 when a loop robot has no box
DEFAULT_HALF_WIDTH = 0.3


def default_samples(robot: Robot) -> int:
    """Default number of random samples of the numerical method.

    100 random states for trees (the paper); for loops the paper's 5 000 actuated samples on
    small mechanisms (``n <= 12``), and enough for a stacked regressor with ~4x more rows than
    parameters on large ones (e.g. humanoids whose only loops are mimic couplings): at least
    200 and ``ceil(40 n / len(robot.actuated))``.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).

    Returns
    -------
    int
        Number of samples (tree states or actuated samples).
    """
    if not robot.has_loops:
        return DEFAULT_SAMPLES_TREE
    if robot.n <= 12:
        return DEFAULT_SAMPLES_LOOPS
    return max(200, int(np.ceil(40 * robot.n / len(robot.actuated))))


#: samples with cond(J_p) above this are discarded (the paper's 30) ...
COND_MAX = 30.0
#: ... or, when the reference configuration itself is above it, this multiple of its cond
COND_FACTOR = 3.0


#: a reference configuration with cond(J_p) above this is singular: its assembly branch is not defined
SINGULAR_COND = 1e12


def reference_cond(robot: Robot) -> float:
    """cond(J_p) at the reference configuration q = 0.

    Parameters
    ----------
    robot : Robot
        A robot with loops.

    Returns
    -------
    float
        Condition number of the passive constraint Jacobian ``K_p`` at actuated coordinates 0
        (:func:`baseparams.kinematics.loops.close_loops`); inf when no closed configuration is found there.
    """
    from .kinematics.loops import close_loops

    cs = close_loops(robot, np.zeros((1, len(robot.actuated))), cond_max=np.inf)
    return float(cs.cond[0]) if cs.kept else np.inf


def closed_samples(robot: Robot, samples: int, rng: np.random.Generator, cond_max: float | None = None,
                   whole_motion: bool = False):
    """Loop-closed random states: actuated q in the robot's box, dq_a, ddq_a in (0, 1).

    Parameters
    ----------
    robot : Robot
        A robot with loops; its box is ``robot.q_box`` (``(na, 2)``), or ``+-0.3`` around q = 0
        (:data:`DEFAULT_HALF_WIDTH`) when it has none.
    samples : int
        Number of actuated samples drawn.
    rng : numpy.random.Generator
        Source of the draws (``q_a``, then ``dq_a``, then ``ddq_a``).
    cond_max : float, optional
        Samples with ``cond(J_p) > cond_max`` are discarded. Default: 30 (the paper); when
        cond(J_p) at the reference is already above 30 (coordinates mixing metres and radians
        with millimetre lever arms, e.g. Cassie's rods; or a reference near a singular
        configuration), 3x the median of the samples' (at least 30, at most 3x the reference's):
        near a singularity the rates lose about ``cond^2`` of their precision.
    whole_motion : bool, optional
        Loops with a one- or two-dimensional motion sampled over all of it
        (:func:`baseparams.kinematics.manifold.motion_samples`: the rank decision's samples)
        instead of from actuated values in the box; such samples' actuated coordinates may lie
        beyond what continuation from the reference reaches.

    Returns
    -------
    ClosedStates
        The kept samples in full tree coordinates and the counts of discarded ones
        (:func:`baseparams.kinematics.loops.close_loops`): every kept sample is reached from the
        reference by continuation without crossing a singular configuration (its assembly branch).

    Raises
    ------
    BaseparamsError
        The reference configuration is singular (cond(J_p) >= :data:`SINGULAR_COND`).
    """
    from .kinematics.loops import close_loops, restrict
    from .kinematics.manifold import motion_samples

    na = len(robot.actuated)
    box = robot.q_box if robot.q_box is not None else np.tile([-DEFAULT_HALF_WIDTH, DEFAULT_HALF_WIDTH], (na, 1))
    auto = cond_max is None
    if auto:
        ref = reference_cond(robot)
        if not ref < SINGULAR_COND:
            raise BaseparamsError(
                f"robot {robot.name!r}: the reference configuration (actuated q = 0) is singular (cond(J_p) = "
                f"{ref:.3g}): assembly branches may meet there (a parallelogram and its anti-parallelogram at the "
                f"flat configuration), so the branch to sample is not defined; give the model at a regular "
                f"configuration of the branch meant (e.g. move the reference off the singular one)")
        cond_max = COND_MAX if ref < COND_MAX else COND_FACTOR * ref
    cs = motion_samples(robot, samples, rng, box, cond_max) if whole_motion else None  # 1- and 2-D loops
    if cs is None:
        qa = rng.uniform(box[:, 0], box[:, 1], (samples, na))
        cs = close_loops(robot, qa, rng.uniform(0, 1, (samples, na)), rng.uniform(0, 1, (samples, na)),
                         cond_max=cond_max)
    if cs.motion and cs.kept:  # a trace: its conditioning is the mechanism's (a weld mixes metres and radians)
        cs = restrict(cs, max(COND_MAX, COND_FACTOR * float(np.median(cs.cond))))
    elif auto and cond_max > COND_MAX and cs.kept:
        # an ill-conditioned reference (near a singular configuration): the samples' rates lose
        # about cond^2 of their precision, so keep the better-conditioned part of the box
        cs = restrict(cs, max(COND_MAX, COND_FACTOR * float(np.median(cs.cond))))
    return cs


def stacked_regressor(robot: Robot, samples: int | None = None, seed: int = 0, rows: str = "all",
                      info: dict | None = None, time_scale: float = 1.0) -> np.ndarray:
    """``W (kept samples * measured rows, 10 n)``: the TP regressor on random states, stacked.

    Trees: states uniform in (0, 1) (the paper). Closed loops: over the whole motion of loops
    with one or two degrees of freedom (:mod:`baseparams.kinematics.manifold`), else actuated
    samples in the robot's box, solved exactly (:func:`baseparams.kinematics.loops.close_loops`);
    discarded samples are counted in ``info`` (a dict filled in place) when given.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    samples : int, optional
        Number of random states (or actuated samples); default :func:`default_samples`.
    seed : int, optional
        Seed of :func:`numpy.random.default_rng`.
    rows : str, optional
        Measured generalized forces (:func:`row_mask`: ``all``, ``joints``, ``base`` or a set of
        joints); only ``all`` with loops (the rows are then the actuated generalized forces).
    info : dict, optional
        Filled in place with ``requested`` and ``kept``, and for loops ``cond_max``,
        ``not_converged``, ``branch_jumps``, ``ill_conditioned``, ``max_loop_residual`` and
        ``motion`` (one line per group of coordinates sampled over its whole motion).
    time_scale : float, default 1
        Rates ``w``: the same states with velocities times ``w`` and accelerations times ``w^2``
        (a motion ``w`` times faster; loop closures keep holding). 1: the paper's sampling.

    Returns
    -------
    ndarray, shape ``(kept samples * measured rows, 10 n)``
        The stacked regressor, gravity included, columns in the ``paper`` convention.

    Raises
    ------
    BaseparamsError
        ``rows`` other than ``all`` for a robot with loops, or no sample closing the loops.
    """
    from .regressor import closed_regressor

    samples = default_samples(robot) if samples is None else samples
    rng = np.random.default_rng(seed)
    if robot.has_loops:
        if rows_spec(rows) != "all":
            raise BaseparamsError(f"robot {robot.name!r}: measured rows {rows!r} are not defined with loops; "
                                  f"the generalized forces are the actuated ones")
        cs = closed_samples(robot, samples, rng, whole_motion=True)
        if info is not None:
            info.update(requested=cs.requested, kept=cs.kept, cond_max=cs.cond_max, not_converged=cs.not_converged,
                        branch_jumps=cs.branch_jumps, ill_conditioned=cs.ill_conditioned,
                        max_loop_residual=cs.max_residual, motion=list(cs.motion))
        if cs.kept == 0:
            raise BaseparamsError(f"robot {robot.name!r}: none of {samples} samples closed the loops "
                                  f"({cs.not_converged} outside the workspace, {cs.branch_jumps} branch jumps, "
                                  f"{cs.ill_conditioned} ill-conditioned); check q_box")
        if time_scale != 1.0:
            cs = replace(cs, dq=cs.dq * time_scale, ddq=cs.ddq * time_scale**2)
        y = closed_regressor(robot, cs)
        return y.reshape(-1, y.shape[-1])
    q, dq, ddq = sample_states(robot, samples, rng)
    y = regressor(robot, q, dq * time_scale, ddq * time_scale**2)[:, row_mask(robot, rows)]
    if info is not None:
        info.update(requested=samples, kept=samples)
    return y.reshape(-1, y.shape[-1])


def numerical_nullspace(robot: Robot, samples: int | None = None, seed: int = 0, rows: str = "all",
                        rtol: float = 1e-9, min_gap: float = 1e4, w: np.ndarray | None = None,
                        info: dict | None = None) -> NumericalResult:
    """The numerical method: random states (see :func:`stacked_regressor`), stacked regressor, SVD.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    samples : int, optional
        Number of random states (or actuated samples); default :func:`default_samples`.
    seed : int, optional
        Seed of the random states.
    rows : str, optional
        Measured generalized forces (:func:`row_mask`).
    rtol : float, optional
        Relative singular-value tolerance (:func:`rank_decision`).
    min_gap : float, optional
        Singular-value gap for a decided rank.
    w : ndarray, shape ``(R, 10 n)``, optional
        A stacked regressor to use instead of sampling one (``samples`` is then only recorded;
        ``seed``, ``rows`` and ``info`` are unused).
    info : dict, optional
        Sampling counts, filled in place (:func:`stacked_regressor`).

    Returns
    -------
    NumericalResult
        The rank decision; ``seconds`` is the wall time of sampling, stacking and SVD.
    """
    t0 = time.perf_counter()
    samples = default_samples(robot) if samples is None else samples
    if w is None:
        w = stacked_regressor(robot, samples, seed, rows, info)
    res = rank_decision(w, rtol, min_gap, samples)
    return NumericalResult(**{**res.__dict__, "seconds": time.perf_counter() - t0})


def available_bytes() -> float | None:
    """Memory available to this process [bytes], or None when unknown.

    The least of: Linux ``MemAvailable``, what the process's cgroup (v2 ``memory.max``, v1
    ``memory.limit_in_bytes``) still allows, and what its address-space limit (``RLIMIT_AS``)
    leaves beyond its current size: a container or ``ulimit -v`` kills a process long before
    the machine runs out.

    Returns
    -------
    float or None
        Bytes; None where none of them can be read.
    """
    found = [x for x in (_meminfo_available(), _cgroup_room(), _rlimit_room()) if x is not None]
    return min(found) if found else None


def _meminfo_available() -> float | None:
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def _read_number(path: str) -> float | None:
    try:
        with open(path) as fh:
            text = fh.read().strip()
        return None if text in ("", "max") else float(text)
    except (OSError, ValueError):
        return None


def _cgroup_room() -> float | None:
    """The cgroup's limit minus its usage (v2, then v1); None without a limit."""
    for limit, used in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                        ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        cap, now = _read_number(limit), _read_number(used)
        if cap is not None and cap < 2**60 and now is not None:  # v1 writes "no limit" as a huge number
            return max(cap - now, 0.0)
    return None


def _rlimit_room() -> float | None:
    """``RLIMIT_AS`` minus the process's virtual size; None without a limit."""
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft == resource.RLIM_INFINITY:
            return None
        with open("/proc/self/status") as fh:
            size = next((float(line.split()[1]) * 1024 for line in fh if line.startswith("VmSize:")), 0.0)
        return max(float(soft) - size, 0.0)
    except (ImportError, OSError, ValueError):
        return None


def decision_lines(d: dict | None) -> list[str]:
    """The report's line on the gap the count was stated at (or the clusters, when no gap decided).

    Parameters
    ----------
    d : dict or None
        :meth:`baseparams.analysis.Analysis.rank_decision`.

    Returns
    -------
    list of str
        One line (none when unverified).
    """
    if d is None:
        return []
    by = {"literal": "singular values of the sampled regressor", "practical": "effects on the torques",
          "structured": "body-by-body blocks"}[d["by"]]
    gap = "inf" if d["gap"] is None else f"{d['gap']:.3g}"
    if not d["decided"]:
        lines = " | ".join(_cluster_text(k) for k in d["clusters"])
        return [f"rank not decided ({by}): the bound {d['bound']:g} falls inside a cluster; clusters: {lines}"]
    if d["by"] == "structured":
        return [f"rank decided at a gap ({by}): smallest kept block value over the worst column residual {gap}"]
    kept = "-" if d["smallest_kept"] is None else f"{d['smallest_kept']:.2g}"
    out = "0" if d["largest_out"] is None else f"{d['largest_out']:.2g}"
    return [f"rank {d['rank']} decided at a gap of {gap} ({by}, relative to the largest: smallest kept {kept}, "
            f"largest counted out {out}; bound {d['bound']:g}){' on the snapped geometry' if d['snapped'] else ''}"]


def _cluster_text(k: dict) -> str:
    gap = "" if k["gap_below"] is None else f", gap {k['gap_below']:.3g} below"
    return f"{k['count']} at {k['bottom']:.2g} - {k['top']:.2g}{gap}"
