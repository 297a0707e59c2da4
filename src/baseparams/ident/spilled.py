"""A large model's fitted rows held in a temporary file, not in memory (issue 51).

The row factors of :class:`~baseparams.ident.estimate.RowAccumulator` compress a measured row's
samples to ``min(S, p + 1)`` rows of ``p + 1`` numbers: nothing when a log has fewer samples than
the model has parameters. A 220-link chain (``m = 220`` rows, ``p = 2196``) on 500 samples held
``m S (p + 1)`` numbers, 1.9 GB, twice (the regressor formed at once and its factors), with the
filter's copies: 2.3-6 GB. Here the rows are made a few measured rows at a time
(:func:`group_rows`: the regressor of those rows only, parallel-filtered as
:func:`~baseparams.ident.chunks.prepared_rows` filters every row) and written to an unnamed
temporary file; :class:`SpilledRows` reads them back a block of samples at a time for what the
estimators ask (each weighting's stacked factor, once; residual sums of squares; column norms;
the HAC pass's blocks). Memory is a block of rows and the ``p x p`` factors, whatever ``m`` and
``S``; the estimate is the one of the rows in memory, to rounding (the same rows, stacked in
another order).

Only models whose row factors would exceed :data:`SPILL_MIN_MB` (and ``memory_mb``) take this
path: an arm's ``m (p + 1)^2`` numbers are a fraction of a megabyte.
"""

from __future__ import annotations

import numpy as np

from ..errors import BaseparamsError
from .estimate import RowAccumulator

#: row factors [MB] from which a model's fitted rows are spilled to a file (and above ``memory_mb``)
SPILL_MIN_MB = 256.0
#: bytes of rows read from the file at once
BLOCK_BYTES = 32e6


def factor_mb(model, samples: int) -> float:
    """The row factors' size [MB]: ``m min(S, p + 1) (p + 1)`` numbers.

    Parameters
    ----------
    model : IdentModel
        The model (``m`` measured rows, ``p`` columns).
    samples : int
        Fitted samples ``S``.

    Returns
    -------
    float
        Megabytes.
    """
    p1 = model.n_params + 1
    return len(model.coords) * min(int(samples), p1) * p1 * 8 / 1e6


def spills(model, samples: int, memory_mb: float) -> bool:
    """Whether the fitted rows are spilled: a tree's rows whose factors exceed ``max(memory_mb, SPILL_MIN_MB)``.

    Parameters
    ----------
    model : IdentModel
        The model (a robot with loops or a logged floating base keeps the in-memory rows).
    samples : int
        Fitted samples.
    memory_mb : float
        The run's ``memory_mb``.

    Returns
    -------
    bool
        True to spill.
    """
    robot = model.robot
    if robot.has_loops or (model.log_base and robot.floating):
        return False
    return factor_mb(model, samples) > max(float(memory_mb), SPILL_MIN_MB)


class RowsView:
    """The model restricted to some measured rows, for :func:`~baseparams.ident.chunks.parallel_rows`.

    Parameters
    ----------
    model : IdentModel
        A tree's model (no loops, no logged floating base).
    rows : ndarray of int, shape ``(g,)``
        Measured rows kept (indices into ``model.coords``).
    """

    def __init__(self, model, rows):
        self.model, self.rows = model, np.asarray(rows, dtype=int)
        self.n_params = model.n_params
        self.coords = model.coords[self.rows]
        nb = len(model.analysis.base_names)
        self._drive = [(col, int(i - nb)) for col, i in enumerate(model.regrouping.independent) if i >= nb]

    def __repr__(self) -> str:
        return f"<RowsView {len(self.rows)} of {len(self.model.coords)} rows, {self.n_params} columns>"

    def regressor(self, q, dq, ddq, backend: str = "auto") -> np.ndarray:
        """``model.regressor(q, dq, ddq)[:, rows]`` without the other rows.

        Parameters
        ----------
        q, dq, ddq : ndarray, shape ``(S, state_columns)``
            States.
        backend : str
            The kernel.

        Returns
        -------
        ndarray, shape ``(S, g, p)``
            The rows.
        """
        from ..analysis import checked_states
        from ..regressor.tp import projected_regressor

        model = self.model
        q, dq, ddq, _ = checked_states(model.robot, q, dq, ddq)
        out = projected_regressor(model.robot, q, dq, ddq, P=model._column_map(), rows=self.coords, backend=backend)
        sel = model.row_states
        where = {int(r): k for k, r in enumerate(self.rows)}
        for col, d in self._drive:
            rows, values = model.drives.param_column(d, dq[:, sel], ddq[:, sel])
            for j, r in enumerate(np.atleast_1d(rows)):
                if int(r) in where:
                    out[:, where[int(r)], col] = values[:, j] if np.ndim(values) == 2 else values
        return out

    def broadband_entries(self, q, dq, ddq):
        """The model's broadband entries on these rows (rows renumbered).

        Parameters
        ----------
        q, dq, ddq : ndarray, shape ``(S, state_columns)``
            States.

        Returns
        -------
        rows, cols : ndarray of int, shape ``(e,)``
            Entries (rows local to the view).
        values : ndarray, shape ``(S, e)``
            Their values.
        """
        rows, cols, values = self.model.broadband_entries(q, dq, ddq)
        local = np.full(len(self.model.coords), -1)
        local[self.rows] = np.arange(len(self.rows))
        keep = local[rows] >= 0
        return local[rows[keep]], cols[keep], values[:, keep]


def group_rows(model, prep, cols: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The fitted (parallel-filtered) rows ``rows`` of a prepared log: :func:`~baseparams.ident.chunks.prepared_rows`'s.

    Parameters
    ----------
    model : IdentModel
        The model.
    prep : Prepared
        The prepared log.
    cols : ndarray of int
        Log column of each state column.
    rows : ndarray of int, shape ``(g,)``
        Measured rows.

    Returns
    -------
    ndarray, shape ``(S', g, p)``
        Their fitted rows.
    """
    from .chunks import prepared_rows

    return prepared_rows(RowsView(model, rows), prep, cols)


def staircase_order(support: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Columns ordered so that each measured row's columns start as late as they can (a tree's staircase).

    Columns are sorted by the last measured row they appear in (stable): on a tree whose rows are
    parents before children, a body's columns appear in its ancestors' rows and its own, so a row's
    columns (its subtree's bodies, its own drive terms) all come at or after its first.

    Parameters
    ----------
    support : ndarray of bool, shape ``(m, c)``
        Whether row ``r`` has column ``k`` (any nonzero sample).

    Returns
    -------
    perm : ndarray of int, shape ``(c,)``
        The new order (``perm[j]`` the column placed ``j``-th).
    starts : ndarray of int, shape ``(m,)``
        Each row's first column in that order (``c`` for a row without columns); every column of
        the row is at or after it.
    """
    m, c = support.shape
    last = np.where(support.any(axis=0), m - 1 - np.argmax(support[::-1], axis=0), -1)
    perm = np.argsort(last, kind="stable")
    placed = support[:, perm]
    starts = np.where(placed.any(axis=1), np.argmax(placed, axis=1), c)
    return perm, starts


class SpilledRows(RowAccumulator):
    """The fitted samples ``[lo, hi)`` of rows written to a file: what a :class:`RowAccumulator` gives, read back.

    Holds no row factors: :meth:`stacked` (cached per weighting), :meth:`row_sse`,
    :meth:`column_norms2` (cached) and :meth:`row_gram` read the file a block of samples at a time;
    an object with ``children`` (the cross-validation's folds) composes those from theirs, as a
    combination does (each fold's stacked factor made once, in the staircase order of the rows' columns,
    :meth:`staircase_factor`; the whole's their TSQR, returned to the columns' order once).

    Parameters
    ----------
    fh : file object
        The rows, sample-major: per sample ``m`` rows of ``[A_r | tau_r]`` (``p + 1`` float64).
    nrows, nparams : int
        ``m`` and ``p``.
    lo, hi : int
        The samples read.
    children : list of SpilledRows, optional
        Consecutive pieces of ``[lo, hi)``.
    """

    def __init__(self, fh, nrows: int, nparams: int, lo: int, hi: int, children=None):
        super().__init__(nrows, nparams)
        self.fh, self.lo, self.hi = fh, int(lo), int(hi)
        self.children = list(children or [])
        self.samples = self.hi - self.lo
        self._norms = None
        self._staircased: dict[bytes, np.ndarray] = {}  # staircase_factor's, per weighting
        self._order = None  # the staircase (held by the root)
        self.root = self  # whose staircase order the rows are stacked in (the whole log's, set by spill)
        for c in self.children:
            c.root = self

    def __repr__(self) -> str:
        return f"<SpilledRows samples {self.lo}-{self.hi} of {self.nrows} rows x {self.nparams} parameters (a file)>"

    @property
    def factors(self):
        """Not held (the rows are in a file): :meth:`stacked` and the other readers instead."""
        raise BaseparamsError("SpilledRows: the rows are held in a file, not as row factors")

    def add(self, a, tau):
        """Not supported: the rows are written once (:func:`spill`).

        Parameters
        ----------
        a : ndarray, shape ``(S, m, p)``
            Rows (refused).
        tau : ndarray, shape ``(S, m)``
            Torques (refused).

        Raises
        ------
        BaseparamsError
            Always.
        """
        raise BaseparamsError("SpilledRows: the rows are written once, by spill()")

    def blocks(self):
        """The samples' rows ``[A | tau]``, a block at a time.

        Yields
        ------
        ndarray, shape ``(k, m, p + 1)``
            Consecutive samples.
        """
        m, p1 = self.nrows, self.nparams + 1
        step = max(1, int(BLOCK_BYTES // (8 * m * p1)))
        for s in range(self.lo, self.hi, step):
            k = min(step, self.hi - s)
            self.fh.seek(s * m * p1 * 8)
            buf = self.fh.read(k * m * p1 * 8)
            if len(buf) != k * m * p1 * 8:
                raise BaseparamsError("SpilledRows: the temporary file of fitted rows was cut short")
            yield np.frombuffer(buf, dtype=np.float64).reshape(k, m, p1)

    def fitted_blocks(self):
        """``(A (k, m, p), tau (k, m))`` blocks in time order (the HAC pass's rows).

        Yields
        ------
        tuple of ndarray
            Consecutive samples' rows and torques.
        """
        for b in self.blocks():
            yield b[:, :, :-1], b[:, :, -1]

    def stacked(self, weights):
        """The triangular factor of every row, row ``r`` scaled by ``weights[r]`` (cached per weighting).

        Parameters
        ----------
        weights : ndarray, shape ``(m,)``
            Row weights.

        Returns
        -------
        ndarray, shape ``(<= p + 1, p + 1)``
            Read-only.
        """
        from ..numerics import blas_threads

        w = np.ascontiguousarray(weights, dtype=float).reshape(-1)
        hit = self._stacked.get(w.tobytes())
        if hit is not None:
            return hit
        perm, _ = self.staircase()
        with blas_threads():  # back to the columns' own order: one QR of the (p + 1)^2 factor
            r = np.linalg.qr(self.staircase_factor(w)[:, np.argsort(perm)], mode="r")
        return self.remember(self._stacked, w.tobytes(), r)

    def release(self) -> None:
        """Drop the cached factors (stacked and staircase), this object's and its pieces'."""
        self._stacked.clear()
        self._staircased.clear()
        for c in self.children:
            c.release()

    def staircase(self) -> tuple[np.ndarray, np.ndarray]:
        """The columns' staircase order and each row's start (:func:`staircase_order`), the whole log's.

        Returns
        -------
        perm : ndarray of int, shape ``(p + 1,)``
            The order (the torque column last whenever every row has it).
        starts : ndarray of int, shape ``(m,)``
            Each row's first column in it.
        """
        root = self.root
        if root._order is None:
            root._order = staircase_order(root.column_norms2() > 0)
        return root._order

    def staircase_factor(self, weights) -> np.ndarray:
        """The weighted rows' triangular factor in the staircase order, each measured row folded in where it starts.

        A tree's measured row (a joint's torque) has columns only of the bodies it carries: in the
        order of :meth:`staircase`, a row's columns lie at or after its start, and folding its samples
        into ``R`` touches only ``R``'s trailing block from there
        (:func:`~baseparams.numerics.triangular_update`; a Householder reflection of a column the new
        rows do not have is the identity). A chain's rows then cost ``2 S sum_r (p - start_r)^2``, a
        third of a dense stacking's ``2 S m p^2`` (a 220-link chain: ~3.5e11 flops a weighting, not
        1.1e12). The pieces (``children``) are stacked in that order too: one return to the columns'
        order for the whole (:meth:`stacked`), not one per piece. A piece's is cached per weighting.

        Parameters
        ----------
        weights : ndarray, shape ``(m,)``
            Row weights.

        Returns
        -------
        ndarray, shape ``(p + 1, p + 1)``
            Upper triangular in the staircase order (read-only).
        """
        from ..numerics import triangular_update

        w = np.ascontiguousarray(weights, dtype=float).reshape(-1)
        hit = self._staircased.get(w.tobytes())
        if hit is not None:
            return hit
        p1 = self.nparams + 1
        perm, starts = self.staircase()
        if self.children:  # a TSQR of the pieces' triangles
            r = np.zeros((p1, p1))
            for c in self.children:
                r = triangular_update(r, np.array(c.staircase_factor(w), order="F"), triangular=True)
        else:
            r = np.zeros((p1, p1))
            group = max(1, int(BLOCK_BYTES // (8 * max(self.samples, 1) * p1)))
            for r0 in range(0, self.nrows, group):
                r1 = min(r0 + group, self.nrows)
                s = int(starts[r0:r1].min())
                if s >= p1 or self.samples == 0:  # rows without a column (a measured row nothing moves)
                    continue
                rows = (self._rows(r0, r1) * w[None, r0:r1, None]).reshape(-1, p1)[:, perm[s:]]
                r[s:, s:] = triangular_update(r[s:, s:], rows)
        if self.root is not self:  # a piece's, for the folds' systems (the whole's own is kept by stacked)
            return self.remember(self._staircased, w.tobytes(), r)
        r.flags.writeable = False
        return r

    def _rows(self, r0: int, r1: int, s0: int = 0, s1: int | None = None) -> np.ndarray:
        """Measured rows ``[r0, r1)`` of samples ``[s0, s1)`` (relative to ``lo``), ``(s1 - s0, r1 - r0, p + 1)``."""
        m, p1 = self.nrows, self.nparams + 1
        s1 = self.samples if s1 is None else s1
        out = np.empty((s1 - s0, r1 - r0, p1))
        size = (r1 - r0) * p1 * 8
        for j, s in enumerate(range(self.lo + s0, self.lo + s1)):
            self.fh.seek((s * m + r0) * p1 * 8)
            buf = self.fh.read(size)
            if len(buf) != size:
                raise BaseparamsError("SpilledRows: the temporary file of fitted rows was cut short")
            out[j] = np.frombuffer(buf, dtype=np.float64).reshape(r1 - r0, p1)
        return out

    def row_sse(self, theta):
        """Each row's residual sum of squares at ``theta``.

        Parameters
        ----------
        theta : ndarray, shape ``(p,)``
            The values.

        Returns
        -------
        ndarray, shape ``(m,)``
            ``||A_r theta - tau_r||^2``.
        """
        x = np.r_[np.asarray(theta, dtype=float), -1.0]
        if self.children:
            return np.sum([c.row_sse(theta) for c in self.children], axis=0)
        out = np.zeros(self.nrows)
        for b in self.blocks():
            out += np.sum((b @ x) ** 2, axis=0)
        return out

    def column_norms2(self):
        """Each row's squared column norms, the torque's last (cached).

        Returns
        -------
        ndarray, shape ``(m, p + 1)``
            ``||A_r[:, k]||^2`` and ``||tau_r||^2``.
        """
        if self._norms is None:
            parts = [c.column_norms2() for c in self.children] or [np.sum(b**2, axis=0) for b in self.blocks()]
            self._norms = np.zeros((self.nrows, self.nparams + 1)) + np.sum(parts, axis=0)
        return self._norms

    def row_gram(self, row: int, cols):
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
            ``A_row[:, cols]^T A_row[:, cols]``.
        """
        cols = np.asarray(cols, dtype=int)
        if self.children:
            return np.sum([c.row_gram(row, cols) for c in self.children], axis=0)
        x = self._rows(row, row + 1)[:, 0][:, cols]  # that row's samples only, not every row's
        return x.T @ x

    def nbytes(self) -> int:
        """Bytes held in memory: the cached stacked factors and norms (the rows are in the file).

        Returns
        -------
        int
            Their size.
        """
        own = sum(r.nbytes for r in [*self._stacked.values(), *self._staircased.values()])
        own += 0 if self._norms is None else self._norms.nbytes
        return own + sum(c.nbytes() for c in self.children)


def spill(model, prep, cols: np.ndarray, memory_mb: float, folds: int):
    """The fitted rows of a prepared log written to a temporary file a few measured rows at a time.

    Parameters
    ----------
    model : IdentModel
        The model (:func:`spills`).
    prep : Prepared
        The prepared log.
    cols : ndarray of int
        Log column of each state column.
    memory_mb : float
        A group's regressor, at the full rate, with its filter's copies, within this (at least one row).
    folds : int
        Cross-validation folds (the whole's children, split by count as in memory).

    Returns
    -------
    SpilledRows or None
        The rows (children the folds), or None when the temporary folder has no room for them.
    """
    from .chunks import fold_edges, scratch_file

    m, p1, count = len(model.coords), model.n_params + 1, prep.n_samples
    fh = scratch_file(count * m * p1 * 8 / 1e6, "baseparams-rows-")
    if fh is None:
        return None
    full_rate = prep.full.n_samples / max(prep.stride, 1)
    group = max(1, int(memory_mb * 1e6 // (4 * 8 * full_rate * p1)))
    tau = prep.tau[:, cols[model.row_states]]
    for g in range(0, m, group):
        rows = np.arange(g, min(g + group, m))
        block = np.concatenate([group_rows(model, prep, cols, rows), tau[:, rows, None]], axis=2)
        for s in range(count):  # sample-major: each sample's rows g .. g + group
            fh.seek((s * m + g) * p1 * 8)
            fh.write(np.ascontiguousarray(block[s]).tobytes())
    fh.flush()
    edges = fold_edges(count, folds)
    children = [SpilledRows(fh, m, p1 - 1, a, b) for a, b in zip(edges[:-1], edges[1:])]
    out = SpilledRows(fh, m, p1 - 1, 0, count, children)
    for x in [out, *children]:
        x.oversampling = prep.oversampling
    return out
