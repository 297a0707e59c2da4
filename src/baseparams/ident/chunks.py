"""A long log identified chunk by chunk, with the same answer as all at once.

The preprocessing of :func:`~baseparams.ident.preprocess.prepare` is local but for its
zero-phase filter, whose response to a chunk's edge decays exponentially: each chunk is read with
:func:`overlap` samples on both sides (enough for the edge transient to fall below ~1e-12), filtered,
differentiated, turned into the model regressor, filtered again (parallel filtering), and only the
samples the chunk owns — those the whole-log path keeps (past the log's filter edges, on its
decimation grid, not slow) — are reduced to their row factors. Factors of chunks combine exactly
(:func:`combine`), in any order or tree (TSQR): the estimate equals the whole log's to rounding.

Memory per chunk is ``(chunk + 2 overlap) x m x p`` floats, whatever the log's length.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..display import summary_repr
from ..errors import DataError
from ..jointlog import JointLog
from .estimate import RowAccumulator
from .preprocess import LowPass, prepare, stride_design, zero_phase

#: edge transient of the zero-phase filter kept below ~1e-12: the least damped pole of a
#: Butterworth low-pass of order 4 decays as exp(-2 pi fc cos(67.5 deg) t), 27.6 / (2 pi 0.383) = 11.5
OVERLAP_PERIODS = 12.0


def overlap(design: LowPass) -> int:
    """Samples read on each side of a chunk so that its filtered values equal the whole log's.

    Parameters
    ----------
    design : LowPass
        The low-pass (its rate and cutoff).

    Returns
    -------
    int
        ``ceil(12 fs / cutoff)``: twelve cutoff periods, past which the edge transient of a
        Butterworth low-pass of order <= 4 has decayed below ~1e-12 of the signal.
    """
    return math.ceil(OVERLAP_PERIODS * design.fs / design.cutoff)


@dataclass(frozen=True)
class ChunkPlan:
    """One chunk: the samples it owns and the samples it reads.

    Parameters
    ----------
    start, stop : int
        Owned samples ``[start, stop)`` of the (uniform) log.
    lo, hi : int
        Samples read ``[lo, hi)``: the owned ones and the overlap on both sides.
    """

    start: int
    stop: int
    lo: int
    hi: int

    __repr__ = summary_repr


#: owned samples of a window, at least, in overlaps (:func:`overlap`): each sample is then read, filtered and
#: evaluated at most ``1 + 2 / MIN_OWNED_MARGINS`` times; a window is at least ``MIN_OWNED_MARGINS + 2`` overlaps
#: long. Was 4 (6 overlaps: a 100 kHz log's 1.2 million-sample windows, 1.35 GB); 1 bounds a window to 3 overlaps
#: (12 cutoff periods each: a time, whatever the rate) for three times the filtering of the fewest windows
MIN_OWNED_MARGINS = 1


def sample_bytes(model, stride: int = 1) -> float:
    """Bytes one window sample costs at its peak (the regressor at the stride, the full-rate signals and their copies).

    Parameters
    ----------
    model : IdentModel
        The model (``m`` measured rows, ``p`` columns).
    stride : int
        The regressor's stride (evaluated at one sample in ``stride``).

    Returns
    -------
    float
        ``8 m p 4 / stride + 8 x 16 m``: the regressor with ~4 copies in the filter, the window's
        signals, their filtered copies, rates and columns (:func:`window_states`; measured on a
        100 kHz Panda log's 600 000-sample windows: 0.75 kB per sample with the window itself for
        ``m = 7``, ``p = 64``, stride 200, where all joints filtered together took 1.2 kB).
    """
    return len(model.coords) * model.n_params * 8 * 4 / stride + 8 * 16 * len(model.coords)


def window_size(model, memory_mb: float, margin: int, stride: int = 1) -> int:
    """Owned samples per window so that one window's regressor and its filter's copies fit in ``memory_mb``.

    Parameters
    ----------
    model : IdentModel
        The model (``m`` measured rows, ``p`` columns).
    memory_mb : float
        The budget [MB].
    margin : int
        Overlap read on each side (:func:`overlap`).
    stride : int
        The regressor's stride (evaluated at one sample in ``stride``).

    Returns
    -------
    int
        At least ``MIN_OWNED_MARGINS x margin`` (the floor, :func:`floor_note` says when the budget
        is then exceeded), else as many as :func:`sample_bytes` allows within the budget.
    """
    per_sample_mb = sample_bytes(model, stride) / 1e6
    return max(MIN_OWNED_MARGINS * margin, 1, int(memory_mb / per_sample_mb) - 2 * margin)


def floor_note(model, memory_mb: float, margin: int, size: int, stride: int = 1, samples: int | None = None):
    """A WARNING note when the windows, at their floor, need more than ``memory_mb`` (None when they fit).

    Parameters
    ----------
    model : IdentModel
        The model.
    memory_mb : float
        The budget [MB] the windows were sized for.
    margin, size : int
        The windows' overlap and owned samples (:func:`window_size`).
    stride : int
        The regressor's stride.
    samples : int, optional
        Samples of the log (a shorter log's one window is its own length).

    Returns
    -------
    str or None
        One line: the floor, the memory a window needs, and what would lower it.
    """
    total = size + 2 * margin if samples is None else min(size + 2 * margin, samples)
    need = total * sample_bytes(model, stride) / 1e6
    if need <= memory_mb:
        return None
    return (f"memory: WARNING, memory_mb {memory_mb:g} MB cannot be met: a window is at least {total} samples (its "
            f"{margin}-sample filter overlaps, 12 cutoff periods, on both sides of {size} owned), about {need:.0f} MB "
            f"(memory_mb {math.ceil(need):d} or more to stay within it; a higher cutoff shortens the overlaps)")


def plan(n: int, chunk: int, margin: int) -> list[ChunkPlan]:
    """Cut ``n`` samples into chunks of ``chunk`` owned samples with ``margin`` read around them.

    Parameters
    ----------
    n : int
        Samples of the log.
    chunk : int
        Owned samples per chunk (the last may be shorter).
    margin : int
        Overlap read on each side (:func:`overlap`).

    Returns
    -------
    list of ChunkPlan
        Covering ``[0, n)`` exactly once.

    Raises
    ------
    DataError
        A non-positive chunk.
    """
    if chunk < 1:
        raise DataError(f"chunk must be at least 1 sample, got {chunk}")
    return [ChunkPlan(s, min(s + chunk, n), max(0, s - margin), min(n, s + chunk + margin))
            for s in range(0, n, chunk)]


@dataclass(frozen=True, eq=False)
class Grid:
    """Which samples of the whole log are kept, as :func:`prepare` decides on the whole log.

    Parameters
    ----------
    n : int
        Samples of the log.
    pad : int
        Samples left out at both ends of the whole log (0: none; :attr:`Prepared.trim
        <baseparams.ident.preprocess.Prepared.trim>`).
    factor : int
        Decimation factor.
    cutoff : float
        The low-pass cutoff [Hz].
    min_speed : float, optional
        Slow-sample threshold (or ``None``).
    notes : tuple of str
        The whole-log decisions (cutoff, decimation), for the report.
    stride : int
        The regressor's stride (:func:`~baseparams.ident.preprocess.regressor_stride`): it is
        evaluated at the samples ``pad + j stride`` and parallel-filtered at that rate.
    """

    n: int
    pad: int
    factor: int
    cutoff: float
    min_speed: float | None = None
    notes: tuple[str, ...] = field(default=())
    stride: int = 1

    __repr__ = summary_repr

    def owned(self, c: ChunkPlan) -> np.ndarray:
        """The samples a chunk owns that the whole-log path keeps (before slow-sample removal).

        Parameters
        ----------
        c : ChunkPlan
            The chunk.

        Returns
        -------
        ndarray of int, shape ``(k,)``
            Global indices: past ``pad`` samples at each end, on the decimation grid ``pad + j factor``.
        """
        first = max(c.start, self.pad)
        first += (-(first - self.pad)) % self.factor
        return np.arange(first, min(c.stop, self.n - self.pad), self.factor)


def chunk_factors(log: JointLog, c: ChunkPlan, grid: Grid, model, cols: np.ndarray,
                  keep: list | None = None, rows: np.ndarray | None = None):
    """The row factors of one chunk (the task a worker runs).

    Parameters
    ----------
    log : JointLog
        The whole (uniform) log, or any log holding samples ``[c.lo, c.hi)`` at those indices
        (a reader may pass the slice only: see :func:`chunk_factors_of_slice`).
    c : ChunkPlan
        The chunk.
    grid : Grid
        The whole log's kept-sample rule.
    model : IdentModel
        The model (:func:`parallel_rows`).
    cols : ndarray of int, shape ``(state_columns,)``
        Log column of each state column.
    keep : list, optional
        When given, the chunk's fitted rows ``(A, tau)`` are appended to it (for a second pass
        that would otherwise recompute them: :mod:`baseparams.ident.uncertainty`).
    rows : ndarray of int, shape ``(m,)``, optional
        The state column of each measured row (``IdentModel.row_states``; default every state
        column: a floating base's six are not measured).

    Returns
    -------
    acc : RowAccumulator
        The chunk's row factors.
    removed : dict of str to int
        Slow samples removed in the chunk.
    """
    sl = slice(c.lo, c.hi)
    rates = {k: None if getattr(log, k) is None else getattr(log, k)[sl] for k in ("dq", "ddq")}
    part = replace(log, t=log.t[sl], q=log.q[sl], tau=log.tau[sl], **rates)
    return chunk_factors_of_slice(part, c, grid, model, cols, keep, rows)


def chunk_factors_of_slice(part: JointLog, c: ChunkPlan, grid: Grid, model, cols: np.ndarray,
                           keep: list | None = None, rows: np.ndarray | None = None):
    """:func:`chunk_factors` on the slice ``[c.lo, c.hi)`` of the log alone.

    Parameters
    ----------
    part : JointLog
        Samples ``[c.lo, c.hi)`` of the whole log.
    c : ChunkPlan
        The chunk.
    grid : Grid
        The whole log's kept-sample rule.
    model : IdentModel
        The model.
    cols : ndarray of int
        Log column of each state column.
    keep, rows : optional
        As for :func:`chunk_factors`.

    Returns
    -------
    acc : RowAccumulator
        The chunk's row factors.
    removed : dict of str to int
        Slow samples removed in the chunk.
    """
    acc = RowAccumulator(len(cols) if rows is None else len(rows), model.n_params)
    a, tau, removed = chunk_rows(part, c, grid, model, cols, rows=rows)
    if a is not None:
        acc.add(a, tau)
        if keep is not None:
            keep.append((a, tau))
    return acc, removed


def chunk_rows(part: JointLog, c: ChunkPlan, grid: Grid, model, cols: np.ndarray, index_out: list | None = None,
               rows: np.ndarray | None = None, backend: str = "auto"):
    """The fitted rows one chunk owns, in time order (what :func:`chunk_factors_of_slice` reduces).

    Parameters
    ----------
    part : JointLog
        Samples ``[c.lo, c.hi)`` of the whole log.
    c : ChunkPlan
        The chunk.
    grid : Grid
        The whole log's kept-sample rule.
    model : IdentModel
        The model (its rows: :func:`parallel_rows`).
    cols : ndarray of int
        Log column of each state column.
    index_out : list, optional
        When given, the kept samples' global indices ``(k,)`` are appended to it (an empty
        array when the chunk keeps none).
    rows : ndarray of int, shape ``(m,)``, optional
        The state column of each measured row (default every state column).
    backend : str
        The regressor's kernel.

    Returns
    -------
    a : ndarray, shape ``(k, m, p)``, or None
        The parallel-filtered regressor of the kept samples (``None`` when the chunk keeps none).
    tau : ndarray, shape ``(k, m)``, or None
        Their filtered torques.
    removed : dict of str to int
        Slow samples removed in the chunk.
    """
    from .preprocess import remove_slow, slow_threshold

    idx = grid.owned(c) - c.lo
    if not len(idx):
        if index_out is not None:
            index_out.append(idx + c.lo)
        return None, None, {}
    design, q, dq, ddq, tau_full = window_states(part, grid.cutoff, cols)
    r = grid.stride
    removed = {}
    if grid.min_speed is not None:
        keep, removed = remove_slow(dq[idx], slow_threshold([part.joints[k] for k in cols], grid.min_speed))
        idx = idx[keep]
    if index_out is not None:
        index_out.append(idx + c.lo)
    a = parallel_rows(model, q, dq, ddq, design, idx, r, (grid.pad - c.lo) % r, backend)  # the whole log's phase
    return a, tau_full[idx][:, slice(None) if rows is None else rows], removed


def window_states(part: JointLog, cutoff: float, cols: np.ndarray):
    """A window's full-rate filtered states, :func:`prepare`'s, a few joints at a time when the window is long.

    :func:`~baseparams.ident.preprocess.prepare` filters and differentiates each column on its own,
    so preparing a few joints' columns at a time gives its arrays (the same arithmetic per column)
    with the filter's copies of those joints only: a 100 kHz log's 600 000-sample window filtered
    its 28 columns together (0.9 GB at the peak).

    Parameters
    ----------
    part : JointLog
        The window's samples (uniform).
    cutoff : float
        The low-pass cutoff [Hz].
    cols : ndarray of int, shape ``(state_columns,)``
        Log column of each state column.

    Returns
    -------
    design : LowPass
        The full-rate low-pass.
    q, dq, ddq : ndarray, shape ``(S, state_columns)``
        Filtered states of the state columns.
    tau : ndarray, shape ``(S, state_columns)``
        Filtered torques of the state columns.
    """
    cols = np.asarray(cols, dtype=int)
    group = max(1, FILTER_VALUES // max(part.n_samples, 1))  # joints prepared at once: all of them on a short window
    if group >= len(part.joints):
        f = (prep := prepare(part, cutoff=cutoff, decimate=1)).full
        return prep.design, f.q[:, cols], f.dq[:, cols], f.ddq[:, cols], f.tau[:, cols]
    out = [np.empty((part.n_samples, len(cols))) for _ in range(4)]
    design = None
    for k in range(0, len(cols), group):
        sub = cols[k:k + group]
        picked = {x: None if getattr(part, x) is None else getattr(part, x)[:, sub] for x in ("q", "tau", "dq", "ddq")}
        prep = prepare(replace(part, joints=tuple(part.joints[j] for j in sub), cur=None, **picked), cutoff=cutoff,
                       decimate=1)
        design = prep.design
        for o, x in zip(out, (prep.full.q, prep.full.dq, prep.full.ddq, prep.full.tau)):
            o[:, k:k + group] = x
        del prep
    return (design, *out)


def parallel_rows(model, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, design: LowPass, idx: np.ndarray,
                  stride: int = 1, phase: int = 0, backend: str = "auto") -> np.ndarray:
    """A model's parallel-filtered rows at the kept samples, from full-rate filtered states.

    With ``stride`` 1, ``zero_phase(model.regressor(q, dq, ddq), design)[idx]``. Else the
    regressor is evaluated at the samples ``phase + j stride`` only and filtered there with the
    low-pass of the same cutoff (:func:`~baseparams.ident.preprocess.stride_design`; ``idx - phase``
    must be multiples of ``stride``), and the entries that are not smooth in the states (Coulomb
    friction's sign: it would alias, :meth:`~baseparams.ident.model.IdentModel.broadband_entries`)
    are replaced by their full-rate filtered values (:mod:`baseparams.ident.preprocess`'s docstring).

    Parameters
    ----------
    model : IdentModel
        The model.
    q, dq, ddq : ndarray, shape ``(S, state_columns)``
        Filtered full-rate states.
    design : LowPass
        The full-rate low-pass.
    idx : ndarray of int, shape ``(k,)``
        The kept samples.
    stride, phase : int
        The rigid-body regressor's samples.
    backend : str
        The regressor's kernel (:meth:`~baseparams.ident.model.IdentModel.regressor`).

    Returns
    -------
    ndarray, shape ``(k, m, p)``
        The fitted rows.
    """
    def reg(*x):
        return model.regressor(*x) if backend == "auto" else model.regressor(*x, backend=backend)

    if stride == 1:
        return filtered_rows(reg(q, dq, ddq), design, idx)
    g = slice(phase, None, stride)
    a = filtered_rows(reg(q[g], dq[g], ddq[g]), stride_design(design, stride), (idx - phase) // stride)
    rows, cols, values = model.broadband_entries(q, dq, ddq)
    if len(rows):
        a[:, rows, cols] = filtered_rows(values, design, idx)
    return a


def prepared_rows(model, prep, cols: np.ndarray) -> np.ndarray:
    """:func:`parallel_rows` of a prepared log: ``prep.apply(model.regressor(...))`` at ``1 / prep.stride`` of the cost.

    Parameters
    ----------
    model : IdentModel
        The model.
    prep : Prepared
        The prepared log (its full-rate states, low-pass, kept samples and stride).
    cols : ndarray of int, shape ``(state_columns,)``
        Log column of each state column.

    Returns
    -------
    ndarray, shape ``(S', m, p)``
        The fitted rows (matching ``prep.tau``).
    """
    f = prep.full
    return parallel_rows(model, f.q[:, cols], f.dq[:, cols], f.ddq[:, cols], prep.design, prep.index, prep.stride,
                         prep.trim % prep.stride)


#: regressor columns filtered at once by :func:`filtered_rows` (at least; bounds the filter's copies) ...
FILTER_COLUMNS = 64
#: ... or as many as make this many values
FILTER_VALUES = 1 << 20
#: ... but fewer than FILTER_COLUMNS (down to one) when those would make more than this many times FILTER_VALUES
#: (a long window's full-rate columns: 64 columns of 1.2 million samples were 0.6 GB per copy)
FILTER_LONG = 8


def filtered_rows(x: np.ndarray, design: LowPass, idx: np.ndarray) -> np.ndarray:
    """``zero_phase(x, design)[idx]``, filtering a few columns at a time, the columns zero at every sample skipped.

    Each column is filtered on its own, so the result is the whole array's; the filter's padded
    and intermediate copies are those of :data:`FILTER_VALUES` values (at least
    :data:`FILTER_COLUMNS` columns, but for a long window's, :data:`FILTER_LONG`), not of the whole
    regressor. A column zero at every sample (a tree's regressor is zero where a joint does not
    carry a body) filters to zero: not filtered.

    Parameters
    ----------
    x : ndarray, shape ``(S, ...)``
        Full-rate signals (a regressor ``(S, m, p)``).
    design : LowPass
        The low-pass.
    idx : ndarray of int, shape ``(k,)``
        The samples kept.

    Returns
    -------
    ndarray, shape ``(k, ...)``
        The filtered signals at the kept samples.
    """
    flat = x.reshape(len(x), -1)
    out = np.zeros((len(idx), flat.shape[1]))
    live = np.flatnonzero(np.any(flat != 0, axis=0))  # a column zero at every sample filters to zero
    per_call = FILTER_VALUES // max(len(flat), 1)  # a long window: fewer columns, down to one at a time
    step = max(per_call, 1 if len(flat) * FILTER_COLUMNS > FILTER_LONG * FILTER_VALUES else FILTER_COLUMNS)
    for k in range(0, len(live), step):
        c = live[k:k + step]
        out[:, c] = zero_phase(flat[:, c], design)[idx]
    return out.reshape((len(idx),) + x.shape[1:])


def combine(parts) -> RowAccumulator:
    """Combine chunk factors (TSQR: the factor of the stacked factors is the whole's).

    Parameters
    ----------
    parts : iterable of RowAccumulator
        Accumulators of the same rows and parameters.

    Returns
    -------
    RowAccumulator
        Their combination: the same estimate as one accumulator fed every chunk's samples.
    """
    from .estimate import RowAccumulator

    return RowAccumulator.combine(parts)


def fold_edges(count: int, folds: int) -> np.ndarray:
    """The blocked cross-validation's fold boundaries over ``count`` samples, without an array of them.

    The boundaries of ``np.array_split(np.arange(count), folds)`` (the in-memory path's folds: the
    first ``count % folds`` folds one sample longer), computed from the two integers alone.

    Parameters
    ----------
    count : int
        Samples split.
    folds : int
        Number of consecutive folds.

    Returns
    -------
    ndarray of int, shape ``(folds + 1,)``
        ``0``, the end of each fold, ``count`` last.
    """
    size, extra = divmod(int(count), int(folds))
    return np.cumsum([0] + [size + 1] * extra + [size] * (folds - extra))


def scratch_file(mb: float, prefix: str):
    """An unnamed temporary file (deleted when closed or at exit), or None when the temporary folder lacks ``2 mb`` MB.

    Parameters
    ----------
    mb : float
        What will be written [MB].
    prefix : str
        The file's name prefix.

    Returns
    -------
    file object or None
        Open for binary reading and writing; None when there is no room or it cannot be created.
    """
    import shutil
    import tempfile

    try:
        if shutil.disk_usage(tempfile.gettempdir()).free < 2 * mb * 1e6:
            return None
        return tempfile.TemporaryFile(prefix=prefix)
    except OSError:
        return None
