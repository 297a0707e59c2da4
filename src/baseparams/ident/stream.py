"""Identification from a log streamed from its file: memory independent of the log's length.

:func:`identify_stream` gives what :func:`baseparams.ident.identify` gives on the whole
log (the same estimate to rounding, the same standard deviations, the same validation RMS) while
holding at most a few blocks of samples, one chunk's regressor and a bounded subsample. It reads
the file several times, each pass block by block (a *block source*: any object with ``source``,
``joints``, ``has_dq``, ``has_ddq`` and ``blocks()`` yielding consecutive
:class:`~baseparams.jointlog.JointLog` blocks, e.g. :class:`baseparams.io.logs.LogStream`):

1. **scan**: samples, first and last time, the time steps' range (uniform or not), the first
   :data:`HEAD_ROWS` samples (the unit checks of :mod:`baseparams.ident.plausibility` run on them);
2. **training statistics**: the hold-out split (``t >= t_end - holdout``, known after the scan), the
   training rate, and the positions subsampled for the cutoff choice and the excitation spectrum:
   every sample while the training part has at most :data:`SUBSAMPLE_MAX` samples (the in-memory
   choice exactly), else means of ``P = ceil(S / SUBSAMPLE_MAX)`` consecutive samples (the
   bandwidth is then resolved up to ``fs / 2P``);
3. **accumulation**: windows of the training part with overlaps of
   :func:`~baseparams.ident.chunks.overlap` samples on both sides (12 cutoff periods: the
   zero-phase filter's edge transient below ~1e-12), each filtered, differentiated, turned into the
   regressor, filtered again and reduced to the row factors of the samples it owns
   (:func:`~baseparams.ident.chunks.chunk_rows`), split into the blocked cross-validation's folds
   by the whole log's sample count;
4. **covariance**: the HAC second pass reads the fitted rows window by window (kept from pass 3
   when they fit in ``memory_mb``, else written by pass 3 to a temporary file, :class:`Spilled`, or
   recomputed from the log when the disk has no room), and collects the report's series (at most :data:`SERIES_MAX`
   fitted samples, evenly thinned);
5. **validation**: the held-out samples predicted from states filtered over the whole log (windows
   again), scored against the raw measured torques, optionally written out block by block.

A text or Parquet log (:class:`~baseparams.io.logs.LogStream` of kind ``text`` or ``parquet``)
is parsed once: pass 1 writes its blocks to a temporary binary file that the later passes read
(:class:`Replay`). In pass 3 the rigid-body regressor is evaluated at the plan's stride
(:func:`~baseparams.ident.chunks.parallel_rows`, as :func:`~baseparams.ident.preprocess.prepare`
decides it on the whole log).

Non-uniform time stamps are resampled block by block (:class:`Resampled`: the grid of
:func:`~baseparams.ident.preprocess.resample`, its median step from the first :data:`SUBSAMPLE_MAX`
steps) when every sample trains; with a hold-out or a validation log they are not streamed
(:class:`NotStreamable`): the validation's states are filtered on the whole log's grid and
interpolated back to its time stamps.

An interrupt (SIGINT, Ctrl-C; or SIGTERM) stops every pass cleanly (:class:`Interrupts`): a library
that swallows the ``KeyboardInterrupt`` raised in its code (pyarrow importing pandas lazily in the
first block of pass 1 did) cannot make the run go on, as the signal is also remembered and raised
again at the next block or step; outputs being written are removed, temporary files too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import BaseparamsError, DataError
from ..interrupts import Interrupts
from ..jointlog import JointLog
from . import chunks
from . import preprocess as pp
from .chunks import fold_edges, scratch_file
from .plausibility import check_rate


class Guarded:
    """A block source whose every block is preceded and followed by :meth:`Interrupts.check`.

    Parameters
    ----------
    stream : block source
        The log (module docstring); its other attributes are passed through.
    guard : Interrupts
        The run's interrupt guard.
    """

    def __init__(self, stream, guard: Interrupts):
        self._stream, self._guard = stream, guard

    def __getattr__(self, name):
        return getattr(self._stream, name)

    def __repr__(self) -> str:
        return f"<Guarded {self._stream!r}>"

    def blocks(self):
        """The wrapped source's blocks, an interrupt checked around each.

        Yields
        ------
        JointLog
            As the wrapped source yields them.
        """
        self._guard.check()
        for blk in self._stream.blocks():
            self._guard.check()
            yield blk
        self._guard.check()

#: training samples up to which the cutoff is chosen from every sample (as in memory)
SUBSAMPLE_MAX = 1 << 18
#: first samples kept for the unit checks and the rate notes
HEAD_ROWS = 1 << 16
#: most fitted samples in the report's series
SERIES_MAX = 1 << 15
#: held-out samples up to which the validation series (plots) is computed
HELD_SERIES_MAX = 1 << 18
#: samples owned by one validation window
VALIDATION_ROWS = 1 << 15


class NotStreamable(BaseparamsError):
    """A log the streamed path does not take (non-uniform time stamps with a validation): read it whole."""


@dataclass(frozen=True)
class Scan:
    """What one pass over a log found.

    Parameters
    ----------
    n : int
        Samples.
    t0, t_end : float
        First and last time stamp [s].
    head : JointLog
        The first :data:`HEAD_ROWS` samples (all of a shorter log).
    notes : tuple of str
        How the file was read (the first block's notes).
    dt : tuple of float
        Smallest and largest time step of the whole log [s].
    """

    n: int
    t0: float
    t_end: float
    head: JointLog
    notes: tuple[str, ...]
    dt: tuple[float, float] = (np.inf, -np.inf)

    def __repr__(self) -> str:
        return f"<Scan {self.n} samples, t {self.t0:.6g} to {self.t_end:.6g} s>"


def concat(parts: list[JointLog]) -> JointLog:
    """Consecutive blocks of one log as one log.

    Parameters
    ----------
    parts : list of JointLog
        Blocks in time order (at least one).

    Returns
    -------
    JointLog
        Their samples, the first block's source and notes.
    """
    if len(parts) == 1:
        return parts[0]
    cat = {k: None if getattr(parts[0], k) is None else np.concatenate([getattr(p, k) for p in parts])
           for k in ("t", "q", "tau", "dq", "ddq")}
    return replace(parts[0], **cat)


def rows(log: JointLog, lo: int, hi: int) -> JointLog:
    """Samples ``[lo, hi)`` of a log.

    Parameters
    ----------
    log : JointLog
        The log.
    lo, hi : int
        The sample range.

    Returns
    -------
    JointLog
        The slice (views).
    """
    sl = slice(lo, hi)
    return replace(log, **{k: None if getattr(log, k) is None else getattr(log, k)[sl]
                           for k in ("t", "q", "tau", "dq", "ddq")})


def copy(log: JointLog) -> JointLog:
    """A log whose arrays are its own (not views holding a larger block alive).

    Parameters
    ----------
    log : JointLog
        The log.

    Returns
    -------
    JointLog
        The same samples in fresh arrays.
    """
    return replace(log, **{k: None if getattr(log, k) is None else np.array(getattr(log, k))
                           for k in ("t", "q", "tau", "dq", "ddq")})


def windows(blocks, plans):
    """The samples each chunk reads, from consecutive blocks (only a few held at a time).

    Parameters
    ----------
    blocks : iterable of JointLog
        The log, block by block (``stream.blocks()``).
    plans : iterable of ChunkPlan
        Chunks with non-decreasing ``lo`` and ``hi``.

    Yields
    ------
    tuple of (ChunkPlan, JointLog)
        Each chunk and its samples ``[c.lo, c.hi)``.

    Raises
    ------
    DataError
        The blocks end before a chunk's samples.
    """
    it = iter(blocks)
    buf: list[JointLog] = []
    b0 = b1 = 0
    try:
        for c in plans:
            while b1 < c.hi:
                blk = next(it, None)
                if blk is None:
                    raise DataError(f"log ended after {b1} samples; sample {c.hi - 1} was expected "
                                    f"(changed while read?)")
                buf.append(blk)
                b1 += blk.n_samples
            while buf and b0 + buf[0].n_samples <= c.lo:
                b0 += buf.pop(0).n_samples
            whole = concat(buf)
            whole = rows(whole, c.lo - b0, whole.n_samples)  # later chunks start at or after c.lo
            buf, b0 = [whole], c.lo
            yield c, rows(whole, 0, c.hi - c.lo)
    finally:
        close = getattr(it, "close", None)
        if close is not None:
            close()


def scan(stream) -> Scan:
    """The first pass: samples, time span, the first samples; every block checked by the reader.

    Parameters
    ----------
    stream : block source
        The log (module docstring).

    Returns
    -------
    Scan
        Counts, span, head and reading notes.

    Raises
    ------
    DataError
        Bad values (the reader's message: file, column, row).
    """
    n, head, notes, t0, t_end, lo, hi = 0, [], [], None, None, np.inf, -np.inf
    for blk in stream.blocks():
        if t0 is None:
            t0, notes = float(blk.t[0]), list(blk.notes)
        elif blk.notes and sum("WARNING" in x for x in notes) < MAX_BLOCK_WARNINGS:
            notes += [x for x in blk.notes if x not in notes]  # a later block's warnings (the first few)
        if n < HEAD_ROWS:
            head.append(copy(rows(blk, 0, HEAD_ROWS - n)))
        d = np.diff(blk.t if t_end is None else np.r_[t_end, blk.t])
        if len(d):
            lo, hi = min(lo, float(d.min())), max(hi, float(d.max()))
        n += blk.n_samples
        t_end = float(blk.t[-1])
    return Scan(n, t0, t_end, concat(head), tuple(notes), (lo, hi))


#: warning notes of the log's blocks kept in a streamed run's notes (each block says its own rows)
MAX_BLOCK_WARNINGS = 5


@dataclass(frozen=True, eq=False)
class Training:
    """The training part's statistics (the second pass).

    Parameters
    ----------
    n : int
        Training samples (those before the hold-out).
    rate : float
        Their mean rate [Hz] (``(n - 1) / (t_last - t0)``, the in-memory path's).
    sub : JointLog
        Positions subsampled (every sample, or means of ``step`` samples) for the cutoff choice
        and the excitation spectrum (``q (k, m)``; ``tau`` zeros).
    step : int
        Samples per subsample point.
    dt : tuple of float
        Smallest, largest and median step [s] (median of the first :data:`SUBSAMPLE_MAX` steps).
    t_last : float
        The last training time stamp [s].
    uniform : bool
        Whether the training samples are uniform (within ``UNIFORM_RTOL`` of the median step).
    """

    n: int
    rate: float
    sub: JointLog
    step: int
    dt: tuple[float, float, float]
    t_last: float = float("nan")
    uniform: bool = True

    def __repr__(self) -> str:
        grid = "uniform" if self.uniform else "non-uniform"
        return f"<Training {self.n} samples at {self.rate:.6g} Hz ({grid}), subsample step {self.step}>"


def training(stream, sc: Scan, end_time: float | None, resample_ok: bool = False) -> Training:
    """The second pass: the training samples (``t < end_time``), their rate, steps and a subsample.

    Parameters
    ----------
    stream : block source
        The log.
    sc : Scan
        The first pass.
    end_time : float or None
        First held-out time (``t_end - holdout``), or None (every sample trains).
    resample_ok : bool
        Non-uniform training samples are resampled block by block (:class:`Resampled`): no
        validation on the same log, whose states would be filtered on the whole log's grid.

    Returns
    -------
    Training
        The statistics.

    Raises
    ------
    NotStreamable
        Non-uniform time stamps where they cannot be resampled block by block.
    """
    step = max(1, math.ceil(sc.n / SUBSAMPLE_MAX))
    n, last, dts, lo, hi, means, times = 0, None, [], np.inf, -np.inf, [], []
    carry_t, carry_q = np.empty(0), np.empty((0, len(stream.joints)))
    for blk in stream.blocks():
        k = blk.n_samples if end_time is None else int(np.searchsorted(blk.t, end_time))
        t = blk.t[:k]
        if k:
            d = np.diff(t if last is None else np.r_[last, t])
            if len(d):
                lo, hi = min(lo, float(d.min())), max(hi, float(d.max()))
                if sum(map(len, dts)) < SUBSAMPLE_MAX:
                    dts.append(d)
            tt, q = np.r_[carry_t, t], np.concatenate([carry_q, blk.q[:k]])
            g = len(q) // step
            means.append(q[:g * step].reshape(g, step, -1).mean(axis=1))
            times.append(tt[:g * step:step].copy())  # not a view holding the block
            carry_t, carry_q = tt[g * step:], q[g * step:]
            n, last = n + k, float(t[-1])
        if k < blk.n_samples:
            break
    med = float(np.median(np.concatenate(dts)[:SUBSAMPLE_MAX])) if dts else 1.0
    every = (min(lo, sc.dt[0]), max(hi, sc.dt[1]))  # the held-out part too: its states are filtered on one grid
    uniform = lo >= med * (1 - pp.UNIFORM_RTOL) and hi <= med * (1 + pp.UNIFORM_RTOL)
    if not (uniform or resample_ok) or not (every[0] >= med * (1 - pp.UNIFORM_RTOL)
                                            and every[1] <= med * (1 + pp.UNIFORM_RTOL)) and not resample_ok:
        raise NotStreamable(f"{stream.source}: non-uniform time stamps (steps {every[0]:.6g}-{every[1]:.6g} s) with a "
                            f"validation: the log is resampled in memory, not streamed")
    q = np.concatenate(means)
    sub = JointLog(np.concatenate(times), tuple(stream.joints), q, np.zeros_like(q), source=stream.source)
    return Training(n, (n - 1) / (last - sc.t0) if n > 1 else 1.0, sub, step, (lo, hi, med), last, bool(uniform))


class Resampled:
    """A block source on the uniform grid :func:`~baseparams.ident.preprocess.resample` makes, block by block.

    The grid starts at the first time stamp with the median step (of the first
    :data:`SUBSAMPLE_MAX` steps: the whole log's median up to that length) and ends at or before
    the last training stamp; every signal is interpolated linearly between the raw samples around
    each grid point (the previous block's last sample carried over), with the arithmetic of
    ``resample``: the same values as resampling the whole log.

    Parameters
    ----------
    stream : block source
        The raw log.
    t0 : float
        Its first time stamp [s].
    tr : Training
        Its training statistics (median step, last training stamp, raw sample count).
    end_time : float or None
        First time not read (None: every sample).
    """

    def __init__(self, stream, t0: float, tr: Training, end_time: float | None = None):
        self.raw, self.t0, self.step, self.end_time = stream, float(t0), tr.dt[2], end_time
        self.source, self.joints = stream.source, tuple(stream.joints)
        self.has_dq, self.has_ddq = stream.has_dq, stream.has_ddq
        self.n = int(np.floor((tr.t_last - self.t0) / self.step * (1 + 1e-12))) + 1
        lo, hi, med = tr.dt
        self.note = (f"time: resampled {tr.n} non-uniform samples (dt {lo * 1e3:.4g}-{hi * 1e3:.4g} ms, median "
                     f"{med * 1e3:.4g} ms) to {self.n} at {1 / self.step:.6g} Hz (the median rate), linear "
                     f"interpolation, block by block")
        self.removed, self.raw_n = max(tr.n - self.n, 0), tr.n

    def blocks(self):
        """The resampled samples, block after block.

        Yields
        ------
        JointLog
            Grid samples (``t (k,)``, signals ``(k, m)``) in time order.
        """
        k, prev = 0, None
        for blk in self.raw.blocks():
            cut = blk.n_samples if self.end_time is None else int(np.searchsorted(blk.t, self.end_time))
            done = cut < blk.n_samples
            cat = rows(blk, 0, cut) if prev is None else concat([prev, rows(blk, 0, cut)])
            if cat.n_samples >= 2:
                tn = self.t0 + self.step * np.arange(k, self.n)
                stop = k + (self.n - k if done else int(np.searchsorted(tn, cat.t[-1], side="right")))
                if stop > k:
                    yield self._interp(cat, tn[:stop - k])
                k, prev = stop, copy(rows(cat, cat.n_samples - 2, cat.n_samples))
            else:
                prev = cat
            if done:
                return
        if k < self.n and prev is not None and prev.n_samples >= 2:  # past the last stamp (rounding): its value
            yield self._interp(prev, self.t0 + self.step * np.arange(k, self.n))

    def _interp(self, cat: JointLog, tn: np.ndarray) -> JointLog:
        """``cat`` at the grid times ``tn`` (:func:`~baseparams.ident.preprocess.interpolate`, as ``resample``)."""
        return replace(pp.interpolate(cat, tn), source=self.source, notes=(), removed={})


@dataclass(frozen=True, eq=False)
class Plan:
    """How the training part is filtered, cut into windows and decimated.

    Parameters
    ----------
    design : LowPass
        The zero-phase low-pass at the training rate.
    factor : int
        Decimation factor.
    grid : Grid
        The kept samples (:class:`~baseparams.ident.chunks.Grid`).
    margin, size : int
        Overlap on each side and owned samples per window.
    notes : tuple of str
        The preprocessing's notes (as :func:`~baseparams.ident.preprocess.prepare` words them).
    """

    design: pp.LowPass
    factor: int
    grid: chunks.Grid
    margin: int
    size: int
    notes: tuple[str, ...]

    def __repr__(self) -> str:
        return (f"<Plan cutoff {self.design.cutoff:.4g} Hz, 1 in {self.factor} kept, windows of {self.size} + 2 x "
                f"{self.margin} samples>")

    def windows(self):
        """The training windows (:func:`~baseparams.ident.chunks.plan`).

        Returns
        -------
        list of ChunkPlan
            Owned samples ``size`` each, ``margin`` read on both sides.
        """
        return chunks.plan(self.grid.n, self.size, self.margin)

    def fitted_count(self) -> int:
        """Samples kept before slow-sample removal (on the decimation grid; every one when not decimated).

        Returns
        -------
        int
            Their number.
        """
        return len(range(self.grid.pad, self.grid.n - self.grid.pad, self.factor))


def plan_training(model, stream, sc: Scan, tr: Training, cutoff, decimate, min_speed, memory_mb: float,
                  band: float) -> Plan:
    """The filter, decimation, kept-sample grid and windows of the training part (and their notes).

    Parameters
    ----------
    model : IdentModel
        The model (its regressor's size sets the window).
    stream : block source
        The log.
    sc : Scan
        The first pass.
    tr : Training
        The second pass.
    cutoff : float or None
        Given cutoff [Hz], or None: from the excitation (the subsample).
    decimate : int or None
        Given decimation factor.
    min_speed : float or None
        Slow-sample threshold.
    memory_mb : float
        Largest regressor formed at once (the window's size).
    band : float
        The motion's bandwidth [Hz] (of the measured coordinates: the rate is checked against it too),
        which chooses the cutoff when none is given.

    Returns
    -------
    Plan
        The plan.

    Raises
    ------
    DataError
        Too few samples for the filter edges, a bad cutoff or factor.
    """
    lo, hi, med = tr.dt
    notes = [*sc.notes]
    if not any(x.startswith("time: resampled") for x in notes):
        notes.append(f"time: uniform (dt {lo * 1e3:.4g}-{hi * 1e3:.4g} ms, median {med * 1e3:.4g} ms), not resampled")
    given_cutoff = cutoff is not None
    if cutoff is None:
        sub = "" if tr.step == 1 else f"; from means of {tr.step} samples (more than {SUBSAMPLE_MAX} samples)"
        cutoff, note = pp.default_cutoff(band, tr.rate, sub)
        notes.append(note)
    design = pp.lowpass_design(tr.rate, cutoff, why="given" if given_cutoff else "from the excitation bandwidth")
    pp.check_length(stream.source, tr.n, design)
    k, k_note = pp.decimation_factor(decimate, tr.rate, design, tr.n)
    head = rows(sc.head, 0, min(sc.head.n_samples, tr.n))
    rate_notes = (pp.filtered_rates(head, pp.zero_phase(head.q, design), tr.rate, design)[2]
                  if head.n_samples > 2 * design.pad else [])
    if head.n_samples < tr.n and stream.has_dq:
        rate_notes = [f"{x} (over the first {head.n_samples} samples)" if x.startswith("dq: measured") else x
                      for x in rate_notes]
    r, r_note = pp.regressor_stride(k, tr.rate, design)
    margin = chunks.overlap(design)
    size = chunks.window_size(model, memory_mb, margin, r)
    floor = chunks.floor_note(model, memory_mb, margin, size, r, tr.n)
    notes += [design.note, *rate_notes, k_note, r_note, pp.EDGE_NOTE, *([floor] if floor else [])]
    return Plan(design, k, chunks.Grid(tr.n, 0, k, design.cutoff, min_speed, stride=r), margin, size,
                tuple(notes))


def regressor_backend(model, n: int) -> str:
    """The regressor kernel for the windows of an ``n``-sample log.

    ``compiled`` when numba is installed and the whole log's regressor is as large as
    :func:`~baseparams.regressor.tp.use_compiled` compiles for (each window alone is smaller:
    ``auto`` would evaluate every window with numpy), else ``auto``.

    Parameters
    ----------
    model : IdentModel
        The model.
    n : int
        Samples whose regressor is evaluated.

    Returns
    -------
    {"compiled", "auto"}
        The backend.
    """
    from ..regressor import compiled

    work = n * len(model.coords) * model.robot.n
    return "compiled" if compiled.available() and work >= compiled.MIN_WORK else "auto"


def fitted(stream, plan: Plan, model, cols: np.ndarray):
    """The fitted samples' rows, window by window in time order (one pass over the file).

    Parameters
    ----------
    stream : block source
        The log.
    plan : Plan
        The training plan.
    model : IdentModel
        The model.
    cols : ndarray of int
        Log column of each state column.

    Yields
    ------
    tuple
        ``(t (k,), A (k, m, p), tau (k, m), removed dict, index (k,))`` per window: the kept
        samples' times, parallel-filtered regressor, filtered torques, slow samples removed, global
        sample indices.
    """
    backend = regressor_backend(model, plan.grid.n // plan.grid.stride)
    for c, part in windows(stream.blocks(), plan.windows()):
        idx: list = []
        a, tau, removed = chunks.chunk_rows(part, c, plan.grid, model, cols, idx, backend=backend)
        if a is not None and len(a):
            yield part.t[idx[0] - c.lo], a, tau, removed, idx[0]
        elif removed:
            yield np.empty(0), None, None, removed, idx[0]


def accumulate(stream, plan: Plan, model, cols: np.ndarray, memory_mb: float, spill: bool = True):
    """Pass 3: the row factors, in the blocked cross-validation's folds, and the fitted rows if they fit.

    Parameters
    ----------
    stream : block source
        The log.
    plan : Plan
        The training plan.
    model : IdentModel
        The model.
    cols : ndarray of int
        Log column of each state column.
    memory_mb : float
        The fitted rows are kept (for the covariance's pass) when they fit in this.
    spill : bool
        Larger fitted rows are written to a temporary file (:class:`Spilled`) when the disk has room.

    Returns
    -------
    parts : list of RowAccumulator
        :data:`~baseparams.ident.select.FOLDS` consecutive pieces of the fitted samples, split by
        count as the in-memory path splits them (by the count before slow-sample removal).
    kept : list of tuple, Spilled or None
        ``(t, A, tau)`` per window, their temporary file, or None (recomputed by pass 4).
    slow : int
        Slow samples removed.
    """
    from .estimate import RowAccumulator
    from .select import FOLDS

    count = plan.fitted_count()
    edges = fold_edges(count, FOLDS)  # not np.array_split(np.arange(count)): no array of every fitted sample
    parts = [RowAccumulator(len(model.coords), model.n_params) for _ in range(FOLDS)]
    fitted_mb = count * len(model.coords) * (model.n_params + 1) * 8 / 1e6
    kept = [] if fitted_mb <= memory_mb else Spilled.open(fitted_mb) if spill else None
    slow = 0
    try:
        for t, a, tau, removed, idx in fitted(stream, plan, model, cols):
            slow += sum(removed.values())
            if a is None:
                continue
            fold = np.searchsorted(edges, (idx - plan.grid.pad) // plan.factor, side="right") - 1
            for j in np.unique(fold):
                sel = fold == j
                parts[j].add(a[sel], tau[sel])
            if isinstance(kept, Spilled):
                kept = kept.write(t, a, tau)
            elif kept is not None:
                kept.append((t, a, tau))
    except BaseException:
        if isinstance(kept, Spilled):
            kept.close()
        raise
    return parts, kept, slow


def read_floats(fh, shape: tuple, what: str) -> np.ndarray:
    """The next ``prod(shape)`` float64 values of a scratch file, as an array of that shape.

    Parameters
    ----------
    fh : file object
        The scratch file (:func:`scratch_file`), positioned at the values.
    shape : tuple of int
        The array's shape.
    what : str
        The file, named in the error.

    Returns
    -------
    ndarray, shape ``shape``
        The values (a read-only view of the bytes read).

    Raises
    ------
    BaseparamsError
        Fewer bytes left than asked (``what`` names the file).
    """
    n = math.prod(shape)
    raw = fh.read(8 * n)
    if len(raw) != 8 * n:
        raise BaseparamsError(f"{what} was truncated while read")
    return np.frombuffer(raw, dtype=np.float64).reshape(shape)


class Replay:
    """A block source parsed once and read again from a temporary binary copy (a text or Parquet log).

    Each pass over a CSV re-parses its text (about 2 s per million rows here); the first complete
    pass through :meth:`blocks` writes every block's arrays to an anonymous temporary file
    (``tempfile.TemporaryFile``: unnamed, deleted when closed or at exit; ``8 (1 + k m)`` bytes per
    sample, ``k`` the signals) and later passes read them back (the same blocks, bit for bit; the
    first block, with the reader's notes, kept in memory). When the temporary folder lacks twice
    the file's size, or a write fails, every pass reads the file again.

    Parameters
    ----------
    stream : block source
        The log (e.g. :class:`baseparams.io.logs.LogStream`).
    size_mb : float
        The log's decoded size [MB] (the free space asked for is twice that).
    """

    def __init__(self, stream, size_mb: float):
        self.raw, self.size_mb = stream, float(size_mb)
        self.source, self.joints = stream.source, tuple(stream.joints)
        self.has_dq, self.has_ddq = stream.has_dq, stream.has_ddq
        self.fh, self.first, self.shapes, self.ready = None, None, [], False

    def __repr__(self) -> str:
        state = f"{len(self.shapes)} blocks kept" if self.ready else "not read yet"
        return f"<Replay {self.source}: {state}>"

    def blocks(self):
        """The log's blocks: read from the file (and kept) the first time, from the copy after.

        Yields
        ------
        JointLog
            Consecutive blocks, as the wrapped source yields them.
        """
        if self.ready:
            yield from self._replay()
            return
        fh, shapes, first = scratch_file(self.size_mb, "baseparams-log-"), [], None
        complete = False
        try:
            for blk in self.raw.blocks():
                if first is None:
                    first = blk
                elif fh is not None:
                    try:
                        for x in (blk.t, blk.q, blk.tau, blk.dq, blk.ddq):
                            if x is not None:
                                fh.write(np.ascontiguousarray(x, dtype=np.float64).data)
                        shapes.append(blk.n_samples)
                    except OSError:
                        fh.close()
                        fh = None
                yield blk
            complete = True
        finally:
            if complete and fh is not None:
                self.fh, self.first, self.shapes, self.ready = fh, first, shapes, True
            elif fh is not None:
                fh.close()

    def _replay(self):
        self.fh.seek(0)
        yield self.first
        m = len(self.joints)
        for n in self.shapes:
            arrays = {}
            for k in ("t", "q", "tau", "dq", "ddq"):
                if getattr(self.first, k) is None:
                    arrays[k] = None
                    continue
                arrays[k] = read_floats(self.fh, (n,) if k == "t" else (n, m),
                                        f"{self.source}: the log's temporary copy")
            yield JointLog(arrays["t"], self.joints, arrays["q"], arrays["tau"], arrays["dq"], arrays["ddq"],
                           self.first.source)

    def close(self) -> None:
        """Delete the copy."""
        if self.fh is not None:
            self.fh.close()
            self.fh, self.ready = None, False


class Spilled:
    """The fitted rows of pass 3 written to an anonymous temporary file, read back window by window by pass 4.

    The HAC covariance needs every fitted row again; recomputing them (the regressor and its
    filter over the whole log) costs as much as pass 3, reading them back costs a file read. The
    file (``tempfile.TemporaryFile``: unnamed, deleted when closed or at exit) holds
    ``8 (p + 1) m + 8`` bytes per fitted sample; memory stays one window's. Used only when the
    temporary folder has twice that free (:meth:`open`), else the rows are recomputed.

    Parameters
    ----------
    fh : file object
        The open temporary file (binary, read and write).
    """

    def __init__(self, fh):
        self.fh, self.shapes = fh, []

    @classmethod
    def open(cls, mb: float):
        """A new spill file, or None when the temporary folder lacks ``2 mb`` MB free (or cannot be written).

        Parameters
        ----------
        mb : float
            The fitted rows' size [MB].

        Returns
        -------
        Spilled or None
            The empty spill.
        """
        fh = scratch_file(mb, "baseparams-rows-")
        return None if fh is None else cls(fh)

    def write(self, t: np.ndarray, a: np.ndarray, tau: np.ndarray):
        """Append one window's rows; the spill, or None when the file cannot take them (then recomputed).

        Parameters
        ----------
        t : ndarray, shape ``(k,)``
            Times [s].
        a : ndarray, shape ``(k, m, p)``
            Fitted regressor rows.
        tau : ndarray, shape ``(k, m)``
            Fitted torques.

        Returns
        -------
        Spilled or None
            ``self``, or None after a write error (disk full: the file is closed).
        """
        try:
            for x in (t, a, tau):
                self.fh.write(np.ascontiguousarray(x, dtype=np.float64).data)
        except OSError:
            self.close()
            return None
        self.shapes.append((t.shape, a.shape, tau.shape))
        return self

    def read(self):
        """The rows back, window by window, as :func:`fitted` yields them.

        Yields
        ------
        tuple
            ``(t, A, tau, None, None)`` per window.
        """
        self.fh.seek(0)
        for shapes in self.shapes:
            out = [read_floats(self.fh, shape, "the fitted rows' temporary file") for shape in shapes]
            yield out[0], out[1], out[2], None, None

    def close(self) -> None:
        """Delete the file."""
        self.fh.close()


class _Scores:
    """Sums of squared validation errors, accumulated window by window."""

    def __init__(self, m: int):
        self.sq, self.sq_lp, self.count, self.t = np.zeros(m), np.zeros(m), 0, [None, None]

    def add(self, t, err, err_lp=None):
        self.sq += np.sum(err**2, axis=0)
        if err_lp is not None:
            self.sq_lp += np.sum(err_lp**2, axis=0)
        self.count += len(err)
        self.t = [self.t[0] if self.t[0] is not None else float(t[0]), float(t[-1])]

    def result(self, names, source, score_cutoff) -> dict:
        rms = np.sqrt(self.sq / self.count)
        out = {"rms": dict(zip(names, rms.tolist())), "rms_total": float(np.sqrt(np.mean(self.sq / self.count))),
               "samples": int(self.count), "t_start": self.t[0], "t_end": self.t[1], "source": source,
               "measure": "RMS of predicted minus raw measured torques at every held-out sample"}
        if score_cutoff is not None:
            out.update({"score_cutoff": float(score_cutoff),
                        "rms_lowpassed": dict(zip(names, np.sqrt(self.sq_lp / self.count).tolist())),
                        "rms_lowpassed_total": float(np.sqrt(np.mean(self.sq_lp / self.count)))})
        return out


def validate(f, stream, span: tuple[int, int, float], cutoff: float, names, score_cutoff=None, sink=None,
             held_out: list | None = None, source: str | None = None) -> dict:
    """Pass 5: every sample ``[first, n)`` predicted and scored against the raw measured torques.

    The states are those of :func:`~baseparams.ident.predict_log` on the whole log
    (:func:`~baseparams.ident.preprocess.log_states`, filtered over samples ``[0, n)``): each window
    reads :func:`~baseparams.ident.chunks.overlap` samples more on both sides. With
    ``score_cutoff``, the measured torques are low-passed over ``[first, n)`` alone, as
    :func:`~baseparams.ident.validation_scores` does.

    Parameters
    ----------
    f : Fit
        The identified values.
    stream : block source
        The log (uniform time stamps).
    span : tuple of (int, int, float)
        ``(first, n, rate)``: the scored samples ``[first, n)``, ``n`` the log's length, and its
        rate [Hz] (sets the overlap).
    cutoff : float
        The identification's cutoff [Hz].
    names : list of str, shape ``(m,)``
        The measured joints, in the model's order.
    score_cutoff : float, optional
        Also score against the measured torques low-passed at this cutoff [Hz].
    sink : callable, optional
        ``sink(t (k,), tau (k, m))``: the predictions, window by window in time order.
    held_out : list, optional
        When given, the scored samples' blocks are appended to it (the validation series).
    source : str, optional
        The validation's source for the report (default the stream's).

    Returns
    -------
    dict
        :func:`~baseparams.ident.validation_scores`'s result.
    """
    from .rows import log_columns

    first, n, rate = span
    margin = math.ceil(chunks.OVERLAP_PERIODS * rate / min(cutoff, score_cutoff or cutoff))
    plans = [chunks.ChunkPlan(s, min(s + VALIDATION_ROWS, n), max(0, s - margin), min(n, s + VALIDATION_ROWS + margin))
             for s in range(first, n, VALIDATION_ROWS)]
    where = {j: k for k, j in enumerate(stream.joints)}
    meas_cols = [where[j] for j in names]
    scores = _Scores(len(names))
    for c, part in windows(stream.blocks(), plans):
        cols = log_columns(f.model, part)
        q, dq, ddq, _ = pp.log_states(part, cutoff, True)
        own = slice(c.start - c.lo, c.stop - c.lo)
        pred = f.predict(q[own][:, cols], dq[own][:, cols], ddq[own][:, cols])  # in blocks of PREDICT_BYTES
        meas = part.tau[own][:, meas_cols]
        err_lp = None
        if score_cutoff is not None:
            lo = max(first, c.lo) - c.lo
            try:
                lp = pp.lowpass_at(part.t[lo:], part.tau[lo:][:, meas_cols], float(score_cutoff))
            except BaseparamsError as exc:
                raise BaseparamsError(f"--score-cutoff {score_cutoff:g} Hz on {source or stream.source}'s held-out "
                                      f"samples: {exc}") from None
            err_lp = pred - lp[c.start - c.lo - lo:c.stop - c.lo - lo]
        scores.add(part.t[own], pred - meas, err_lp)
        if sink is not None:
            sink(part.t[own], pred)
        if held_out is not None:
            held_out.append(copy(rows(part, own.start, own.stop)))
    return scores.result(names, source or stream.source, score_cutoff)


def _series_of(kept, theta, names, limit: int = SERIES_MAX) -> dict:
    """The report's training series from fitted rows ``(t, A or A @ theta, tau)`` (evenly thinned to ``limit``)."""
    t = np.concatenate([k[0] for k in kept]) if kept else np.empty(0)
    step = max(1, math.ceil(len(t) / limit))
    tau = np.concatenate([k[2] for k in kept])[::step] if kept else np.empty((0, len(names)))
    hat = (np.concatenate([k[1] if k[1].ndim == 2 else k[1] @ theta for k in kept])[::step] if kept
           else np.empty((0, len(names))))
    return {"t": t[::step], "tau": tau, "tau_hat": hat, "joints": names}


def _thinned(gen, every: int, theta: np.ndarray, out: list):
    """``(A, tau)`` of :func:`fitted`'s windows; every ``every``-th row's ``(t, A @ theta, tau)`` into ``out``."""
    seen = 0
    for t, a, tau, _, _ in gen:
        if a is None:
            continue
        sel = (seen + np.arange(len(t))) % every == 0
        out.append((t[sel], a[sel] @ theta, tau[sel]))
        seen += len(t)
        yield a, tau


def covariance_pass(f, acc, covariance, kept, stream, plan, model, cols, say):
    """Pass 4: the fit's standard deviations (HAC: the fitted rows again) and the report's series.

    Parameters
    ----------
    f : Fit
        The fit.
    acc : RowAccumulator
        The accumulated rows.
    covariance : {"hac", "white"}
        The covariance.
    kept : list, Spilled or None
        The fitted rows ``(t, A, tau)`` from pass 3, their temporary file (read back and closed),
        or None (recomputed from the log).
    stream, plan, model, cols
        As for :func:`fitted`.
    say : callable
        Progress.

    Returns
    -------
    fit : Fit
        With its standard deviations.
    note : str
        The covariance's note.
    series : dict or None
        ``{"t", "tau", "tau_hat", "joints"}`` of (at most :data:`SERIES_MAX`) fitted samples.
    """
    from .uncertainty import apply_covariance

    names = model.joints
    rate = plan.design.fs / plan.factor
    if isinstance(kept, Spilled) and covariance != "hac":
        kept.close()
        kept = None
    if isinstance(kept, list) or covariance != "hac":
        f, note = apply_covariance(f, acc, [(a, tau) for _, a, tau in kept or ()], covariance, rate)
        return f, note, (_series_of(kept, f.theta, names) if kept is not None else None)
    thin: list = []
    every = max(1, math.ceil(plan.fitted_count() / SERIES_MAX))
    if isinstance(kept, Spilled):
        say("covariance (HAC: the fitted rows read back from a temporary file, window by window)")
        try:
            f, note = apply_covariance(f, acc, _thinned(kept.read(), every, f.theta, thin), covariance, rate)
        finally:
            kept.close()
        return f, note, _series_of(thin, f.theta, names)
    say("covariance (HAC: a second pass over the file, window by window)")
    f, note = apply_covariance(f, acc, _thinned(fitted(stream, plan, model, cols), every, f.theta, thin), covariance,
                               rate)
    return f, note, _series_of(thin, f.theta, names)


def check_effort(stream, effort: str, gain_anchor: str | None) -> None:
    """A log identified from its motor currents is read whole (:class:`NotStreamable`); the rest as the whole log's.

    Currents asked for and none logged, or a gain anchor for a log identified from its torques,
    are refused as :func:`~baseparams.ident.identify` refuses them.

    Parameters
    ----------
    stream : LogStream
        The log's stream (its ``has_currents`` and ``has_tau``).
    effort : {"auto", "torque", "current"}
        The identification's input kind (``IdentOptions.effort``).
    gain_anchor : str or None
        ``IdentOptions.gain_anchor``.

    Raises
    ------
    NotStreamable
        The log is identified from its currents: read it whole.
    BaseparamsError
        Currents asked for and none logged; a gain anchor for a log identified from its torques.
    """
    currents, torques = getattr(stream, "has_currents", False), getattr(stream, "has_tau", True)
    if effort == "current" and not currents:
        raise DataError(f"{stream.source}: no motor currents (columns cur_<joint> [A], or cur = ... in a columns= "
                        f"map)")
    if effort == "current" or (effort == "auto" and currents and not torques):
        raise NotStreamable(f"{stream.source}: motor currents (cur_ columns): the log is read whole, not streamed "
                            f"(identification from currents fits the gains over all its rows)")
    if gain_anchor is not None:
        raise BaseparamsError("identify: gain_anchor= applies to motor currents; this log is identified from its "
                              "joint torques (effort=current to use its currents)")


def identify_stream(robot, stream, options=None, /, *, validation=None, predictions=None, progress=None,
                    **keywords):
    """:func:`~baseparams.ident.identify` on a log streamed from its file (module docstring).

    Parameters
    ----------
    robot : Robot
        The model (fixed base).
    stream : block source
        The log, e.g. :class:`baseparams.io.logs.LogStream`.
    options : IdentOptions, optional
        How, as for :func:`~baseparams.ident.identify` (``memory_mb``: the window's regressor;
        model terms are not tried on a streamed log).
    validation : block source, optional
        Another log to validate on (exclusive with ``holdout``).
    predictions : callable, optional
        ``predictions(t (k,), tau (k, m))`` receives the predicted torques of every validation sample,
        window by window in time order (``identify --predictions``).
    progress : callable, optional
        Called with one line of text at each step.
    **keywords
        Options as keywords, instead of or over ``options`` (:class:`~baseparams.ident.options.IdentOptions`).

    Returns
    -------
    Identification
        As :func:`~baseparams.ident.identify` returns (the series thinned to
        :data:`SERIES_MAX` samples; no validation series beyond :data:`HELD_SERIES_MAX` held-out
        samples).

    Raises
    ------
    NotStreamable
        Non-uniform time stamps, a floating base, motor currents (read the log whole).
    BaseparamsError
        As :func:`~baseparams.ident.identify`.
    """
    from ..numerics import blas_threads
    from .options import options_of

    opts = options_of(options, keywords)
    if robot.floating:
        raise NotStreamable(f"robot {robot.name!r}: a floating base's log is read whole (its pose is unwrapped "
                            "over the whole log), not streamed")
    if opts.holdout is not None and validation is not None:
        raise BaseparamsError("give either holdout seconds or a validation log, not both")
    check_effort(stream, opts.effort, opts.gain_anchor)
    kept = None
    if getattr(stream, "kind", None) in ("text", "parquet"):  # parsed once, replayed from a binary copy
        stream = kept = Replay(stream, stream.decoded_mb)
    tell = progress or (lambda msg: None)
    try:
        with Interrupts() as guard, blas_threads():
            def say(msg: str) -> None:
                guard.check()
                tell(msg)

            return _identify_stream(robot, Guarded(stream, guard),
                                    None if validation is None else Guarded(validation, guard), predictions, say, opts)
    finally:
        if kept is not None:
            kept.close()


def _passes(robot, stream, o, validating: bool, say):
    """Passes 1-3: the model, the scan, the training statistics, the plan and the accumulated rows."""
    from .model import model_for
    from .notes import check_log_units
    from .rows import log_columns

    say(f"scanning {stream.source} (pass 1: samples, time span, checks)")
    sc = scan(stream)
    end_time = None
    if o.holdout is not None:
        if not 0 < o.holdout < sc.t_end - sc.t0:
            raise BaseparamsError(f"{stream.source}: holdout {o.holdout} s must be inside the log's "
                                  f"{sc.t_end - sc.t0:.6g} s")
        end_time = sc.t_end - o.holdout
    say(f"analysing {robot.name} (base parameters, drive model)")
    model = model_for(robot, o)
    cols = log_columns(model, sc.head)
    say(f"training statistics of {sc.n} samples (pass 2: hold-out split, rate, cutoff subsample)")
    tr = training(stream, sc, end_time, resample_ok=end_time is None and not validating)
    unit_notes = check_log_units(model, rows(sc.head, 0, min(sc.head.n_samples, tr.n)), cols, o.allow_units)
    if sc.head.n_samples < tr.n:
        unit_notes = [f"{x} (on the first {sc.head.n_samples} samples)" for x in unit_notes]
    if not tr.uniform:  # resampled block by block; the passes read the grid
        stream = Resampled(stream, sc.t0, tr, end_time)
        say(f"resampling {tr.n} non-uniform samples to {stream.n} block by block (pass 2b: the grid's statistics)")
        sc = Scan(stream.n, sc.t0, sc.t0 + stream.step * (stream.n - 1), sc.head, (*sc.notes, stream.note))
        tr = training(stream, sc, None)
    band = pp.excitation_bandwidth(tr.sub.q[:, cols], tr.rate / tr.step)  # once: the cutoff's and the rate's
    plan = plan_training(model, stream, sc, tr, o.cutoff, o.decimate, o.min_speed, o.memory_mb, band)
    unit_notes = [*unit_notes, *check_rate(stream.source, band, (tr.n - 1) / tr.rate, tr.rate, plan.design.cutoff,
                                           o.cutoff is not None, o.allow_units)]
    for note in plan.notes:
        if note.startswith("memory: WARNING"):
            say(note)  # on stderr before the pass that needs it, not only in the report
    say(f"accumulating the regressor of {plan.fitted_count()} samples ({model.n_params} parameters; pass 3, "
        f"windows of {plan.size} + 2 x {plan.margin} samples)")
    parts, kept, slow = accumulate(stream, plan, model, cols, o.memory_mb, spill=o.covariance == "hac")
    for part in parts:  # as Prepared.oversampling: the priors weighed against the rows' information
        part.oversampling = max(1.0, tr.rate / plan.factor / (pp.DECIMATE_MARGIN * plan.design.cutoff))
    return stream, sc, tr, model, cols, unit_notes, plan, parts, kept, slow


def _rule(tr) -> str:
    """What chooses the default estimate (:func:`~baseparams.ident.fitting.fit`'s ``rule``), as in memory.

    ``structure`` when each cross-validation block spans less than
    :data:`~baseparams.ident.pipeline.MIN_BLOCK_PERIODS` periods of the motion's bandwidth (from the
    scan's subsample), else ``blocks``.
    """
    from .pipeline import MIN_BLOCK_PERIODS
    from .select import FOLDS

    band = pp.excitation_bandwidth(tr.sub.q, tr.rate / tr.step)
    return "structure" if (tr.n - 1) / tr.rate / FOLDS * band < MIN_BLOCK_PERIODS else "blocks"


def _identify_stream(robot, stream, validation, predictions, say, o):
    """:func:`identify_stream`'s steps."""
    from .fitting import fit, pulled_covariance, residual_rms
    from .pipeline import assemble
    from .validation import position_spectrum

    train, sc, tr, model, cols, unit_notes, plan, parts, kept, slow = _passes(robot, stream, o, validation is not None,
                                                                              say)
    acc = chunks.combine(parts)
    say(f"fitting ({o.method})")
    f = fit(model, acc, o.method, o.prior_weight, blocks=parts, rule=_rule(tr))
    f, cov_note, train_series = covariance_pass(f, acc, o.covariance, kept, train, plan, model, cols, say)
    f = pulled_covariance(f)
    names = model.joints
    res = residual_rms(acc, f.theta)
    train_rms = {"rms": dict(zip(names, res.tolist())), "rms_total": float(np.sqrt(np.mean(res**2))),
                 "measure": "RMS on the fit's own rows (filtered and decimated as fitted; a streamed log is not "
                            "predicted again at every training sample)"}
    if train_series is not None:
        train_series["spectrum"] = position_spectrum(tr.sub, cols, tr.rate / tr.step, plan.design.cutoff)
    series = {"train": train_series, "validation": None}
    val = _validation(f, (stream, validation), (sc, tr, plan), names, o, predictions, series, say)
    return assemble(f, acc, o, _account(train, tr, plan, slow, o, (cov_note, unit_notes)), train_rms, val, series)


def _account(train, tr: Training, plan: Plan, slow: int, o, notes) -> object:
    """What the streamed passes did to the data (:class:`~baseparams.ident.pipeline.Account`)."""
    from .pipeline import Account
    from .terms.fit import parse_terms

    cov_note, unit_notes = notes
    removed = {"resampling to fewer samples": train.removed} if getattr(train, "removed", 0) else {}
    inner = tr.n - 2 * plan.grid.pad
    if plan.factor > 1:
        removed[f"decimation by {plan.factor}"] = inner - plan.fitted_count()
    slow_note = ["slow samples: kept (min_speed not given)"]
    if o.min_speed is not None:
        shown = np.asarray(o.min_speed) if np.ndim(o.min_speed) else o.min_speed
        slow_note = [f"slow samples: {slow} with |dq| below {shown} on a joint removed"]
        if slow:
            removed["slow (|dq| < min_speed on a joint)"] = slow
    acc_note = (f"parallel filtering in {len(plan.windows())} windows of {plan.size} samples with {plan.margin}-sample "
                f"overlaps, the log streamed from its file (equal to the whole log's to rounding)")
    no_terms = (["model terms: not considered for a log streamed from its file (the linear model alone; read the log "
                 "whole with --stream off for pre-sliding friction, tilt, delays and scales)"]
                if parse_terms(o.terms)[0] else [])
    return Account(int(getattr(train, "raw_n", tr.n)), removed, float(plan.design.cutoff), int(plan.factor),
                   (*plan.notes, *slow_note), acc_note, tuple(no_terms), cov_note, tuple(unit_notes), run="stream")


def _validation(f, sources, passes, names, o, predictions, series, say):
    """Pass 5 on the held-out tail or on another log (None without either); the validation series when small.

    ``sources`` is ``(stream, other log or None)``, ``passes`` the training log's ``(Scan, Training, Plan)``.
    """
    from .rows import log_columns
    from .validation import report_series

    (stream, other), (sc, tr, plan) = sources, passes
    if o.holdout is None and other is None:
        return None
    if other is None:
        src, first, n, rate = stream, tr.n, sc.n, tr.rate
        source = f"{stream.source} (last {o.holdout:g} s)"
        say(f"validating on {n - first} held-out samples (pass 5: every one, against the raw measured torques)")
    else:
        osc = scan(other)
        otr = training(other, osc, None)  # the rate, and refuses non-uniform time
        src, first, n, rate, source = other, 0, osc.n, otr.rate, other.source
        say(f"validating on {n} samples of {other.source} (every one, against the raw measured torques)")
    held: list | None = [] if n - first <= HELD_SERIES_MAX else None
    val = validate(f, src, (first, n, rate), plan.design.cutoff, names, o.score_cutoff, predictions, held, source)
    if held:
        h = replace(concat(held), source=source)
        vprep = pp.prepare(h, cutoff=plan.design.cutoff, decimate=plan.factor)
        series["validation"] = report_series(f.model, vprep, log_columns(f.model, h), f.theta, names, o.memory_mb)
    return val
