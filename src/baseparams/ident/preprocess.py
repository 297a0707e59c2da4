"""Preprocessing of a joint log for identification: uniform time, zero-phase low-pass, rates, decimation.

The chain (:func:`prepare`): resample non-uniform time stamps to a uniform grid
(:func:`resample`), low-pass ``q`` and ``tau`` with one zero-phase Butterworth filter
(:func:`lowpass_design`, :func:`zero_phase`), derive ``dq`` and ``ddq`` from the filtered ``q``
where the log has none (:func:`derivatives`), drop the filter's edge transients, keep every
k-th sample (:func:`decimate`) and optionally the samples where every joint moves
(:func:`remove_slow`).

Parallel filtering: the inverse-dynamics model ``tau = W(q, dq, ddq) beta`` is linear in the
parameters, so a linear filter applied to ``tau`` and to every column of ``W`` keeps it exact.
Compute the regressor on :attr:`Prepared.full` (filtered ``q``, ``dq``, ``ddq``), then
:meth:`Prepared.apply` filters it with the same zero-phase filter, trims the same edges and keeps
the same samples as :attr:`Prepared.tau`. The rigid-body part, the costly one, is smooth in the
filtered states: :func:`baseparams.ident.chunks.prepared_rows` evaluates it at every
:attr:`Prepared.stride`-th sample only (a divisor of the decimation factor at which the rate stays
at least :data:`STRIDE_MARGIN` times the cutoff, :func:`regressor_stride`) and filters it with the
low-pass of the same cutoff at that rate; the states were low-passed at the full rate, so it has
nothing there to alias (its columns differ from the full-rate ones by ~1e-6 of their size on a
simulated arm), and the two filters differ by less than 1e-8 below a tenth of the cutoff, where the
motion is. Columns that are not smooth (Coulomb friction's sign, the model terms' states) are
filtered at the full rate. (Building the regressor from the kept samples' ``q, dq, ddq`` directly
is the other consistent choice: those and ``tau`` each went through the filter once.)

Everything here is numpy/scipy on arrays whose first axis is the sample; nothing loops over
samples in Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import signal

from ..display import counted, summary_repr
from ..errors import DataError
from ..jointlog import JointLog

#: default low-pass cutoff: fs / CUTOFF_DIVISOR, at most CUTOFF_CAP Hz
CUTOFF_DIVISOR = 20.0
CUTOFF_CAP = 20.0
#: the filter's edge extension at each end: EDGE_PERIODS periods of the cutoff (no sample is dropped: the
#: extension keeps a smooth signal's derivatives, :func:`zero_phase`, and the torques and every regressor column go
#: through the same linear filter, so the fit holds at the ends too)
EDGE_PERIODS = 2.0
#: default cutoff of a log: this multiple of the excitation bandwidth (:func:`excitation_bandwidth`)
BANDWIDTH_FACTOR = 10.0
#: ... and never below this [Hz]
CUTOFF_FLOOR = 1.0
#: default decimation: the rate after it stays at least DECIMATE_MARGIN x the cutoff
DECIMATE_MARGIN = 5.0
#: ... and it keeps at least MIN_FITTED samples (a short log is fitted at every sample: decimating it saves little
#: time and leaves a few hundred samples, a 25 s motion at 200 Hz 132 of its 5 027)
MIN_FITTED = 5000
#: :func:`zero_phase` extends a signal by EXTENSION x the design's ``pad`` at each end
EXTENSION = 2
#: relative spread of the time steps below which a log counts as uniform
UNIFORM_RTOL = 1e-3
#: the rigid-body regressor is evaluated and filtered at a rate at least STRIDE_MARGIN x the cutoff
#: (:func:`regressor_stride`)
STRIDE_MARGIN = 10.0


@dataclass(frozen=True, eq=False)
class LowPass:
    """A zero-phase Butterworth low-pass (second-order sections), as :func:`lowpass_design` gives.

    Parameters
    ----------
    sos : ndarray, shape ``(sections, 6)``
        Second-order sections (``scipy.signal.butter(..., output="sos")``).
    fs : float
        Sampling rate it was designed for [Hz].
    cutoff : float
        Cutoff frequency [Hz] (-3 dB for one pass, -6 dB forward and backward).
    order : int
        Butterworth order of one pass (the zero-phase filter's magnitude is its square).
    pad : int
        The extension's length at each end used by :func:`zero_phase` (two cutoff periods: the
        filter's transient decays within it).
    note : str
        One line saying what was chosen and why (for the report).
    """

    sos: np.ndarray
    fs: float
    cutoff: float
    order: int
    pad: int
    note: str = ""

    __repr__ = summary_repr


def lowpass_design(fs: float, cutoff: float | None = None, order: int = 4, why: str = "given") -> LowPass:
    """Design the zero-phase Butterworth low-pass used on ``q``, ``tau`` and regressor columns.

    Default cutoff: ``min(fs / 20, 20 Hz)``. Arm excitation trajectories have their content below
    a few Hz (Fourier series of a fraction of a hertz, 5 harmonics), and identification practice
    puts the cutoff a few times above the excitation bandwidth (10-20 Hz for arms); 20 Hz keeps
    the rigid-body dynamics and removes encoder, torque-sensor and current noise. ``fs / 20``
    keeps the cutoff well below Nyquist on slow logs (100 Hz: 5 Hz), so that central differences
    of the filtered signal are accurate (at least 20 samples per cutoff period: relative error of
    the derivative below ``(pi / 20)^2 / 6 = 0.4 %`` at the cutoff, far less below it).

    Edge length: ``ceil(2 fs / cutoff)`` samples (two cutoff periods), after which the transient
    of the forward-backward filter (with odd extension) has decayed to below 0.3 % of the second
    derivative of a smooth signal.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    cutoff : float, optional
        Cutoff frequency [Hz], below ``fs / 2``. Default above.
    order : int, optional
        Butterworth order of one pass (default 4: -80 dB/decade, twice that forward and backward).
    why : str, optional
        Where a given ``cutoff`` came from, for the note (default ``given``).

    Returns
    -------
    LowPass
        The design, its edge length and a note saying which cutoff was used.

    Raises
    ------
    DataError
        ``fs`` not a positive number, ``cutoff`` not in ``(0, fs / 2)``, ``order`` below 1.
    """
    if not (np.isfinite(fs) and fs > 0):
        raise DataError(f"low-pass: sampling rate must be a positive number of Hz, got {fs!r}")
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 1:
        raise DataError(f"low-pass: order must be a positive integer, got {order!r}")
    if cutoff is None:
        cutoff = min(fs / CUTOFF_DIVISOR, CUTOFF_CAP)
        why = f"default min(fs/{CUTOFF_DIVISOR:g}, {CUTOFF_CAP:g} Hz) at fs = {fs:.6g} Hz"
    if not (np.isfinite(cutoff) and 0 < cutoff < fs / 2):
        raise DataError(f"low-pass: cutoff must be between 0 and fs/2 = {fs / 2:.6g} Hz, got {cutoff!r}")
    sos = signal.butter(int(order), cutoff, btype="low", fs=fs, output="sos")
    pad = edge_samples(fs, cutoff)
    note = (f"low-pass: zero-phase Butterworth order {order} (forward and backward, sosfiltfilt), cutoff "
            f"{cutoff:.4g} Hz ({why}); edges {pad} samples ({EDGE_PERIODS:g} cutoff periods)")
    return LowPass(sos=sos, fs=float(fs), cutoff=float(cutoff), order=int(order), pad=pad, note=note)


def default_cutoff(band: float, fs: float, sub: str = "") -> tuple[float, str]:
    """The low-pass cutoff chosen from the motion's bandwidth when none is given, and its note (the one rule).

    Parameters
    ----------
    band : float
        The motion's bandwidth [Hz] (:func:`excitation_bandwidth`).
    fs : float
        Sampling rate [Hz].
    sub : str, optional
        How the bandwidth was measured, when not on every sample (``; from means of 4 samples``).

    Returns
    -------
    cutoff : float
        :data:`BANDWIDTH_FACTOR` x ``band`` within ``[CUTOFF_FLOOR, min(fs / 20, 20 Hz)]`` [Hz].
    note : str
        ``cutoff 3.333 Hz: 10 x the excitation bandwidth 0.333 Hz (...)``.
    """
    top = min(fs / CUTOFF_DIVISOR, CUTOFF_CAP)
    cutoff = float(np.clip(BANDWIDTH_FACTOR * band, CUTOFF_FLOOR, top))  # the top when the floor is above it
    bounds = (f"within [{CUTOFF_FLOOR:g} Hz, min(fs/{CUTOFF_DIVISOR:g}, {CUTOFF_CAP:g} Hz)]" if top >= CUTOFF_FLOOR else
              f"at most fs/{CUTOFF_DIVISOR:g} = {top:.4g} Hz (the {CUTOFF_FLOOR:g} Hz floor is above it at this rate)")
    return cutoff, (f"cutoff {cutoff:.4g} Hz: {BANDWIDTH_FACTOR:g} x the excitation bandwidth {band:.3g} Hz "
                    f"(99.5 % of the motion's energy{sub}), {bounds}")


def edge_samples(fs: float, cutoff: float) -> int:
    """The low-pass's edge at each end [samples]: :data:`EDGE_PERIODS` periods of its cutoff.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    cutoff : float
        Cutoff [Hz].

    Returns
    -------
    int
        ``ceil(EDGE_PERIODS fs / cutoff)`` (not one more for a rounding error).
    """
    return math.ceil(EDGE_PERIODS * fs / cutoff - 1e-6)


def shortest_log(fs: float, cutoff: float | None = None) -> int:
    """The fewest samples :func:`prepare` filters: more than the low-pass's two edges (the one rule).

    Parameters
    ----------
    fs : float
        Sampling rate [Hz].
    cutoff : float, optional
        The cutoff [Hz]; default the highest :func:`prepare` chooses by itself at ``fs``
        (``min(fs / 20, 20 Hz)``): below this length every log at ``fs`` is refused, whatever its
        motion (a slower motion's lower cutoff asks for more).

    Returns
    -------
    int
        ``2 x edge + 2`` (:func:`edge_samples`): 102 at 500 Hz, 82 at 100 Hz and below.
    """
    top = min(fs / CUTOFF_DIVISOR, CUTOFF_CAP)
    return 2 * edge_samples(fs, top if cutoff is None else cutoff) + 2


def check_length(source: str, n: int, design: LowPass, helps: str = "a longer log, or a higher cutoff") -> None:
    """Refuse a log the low-pass cannot filter: fewer than :func:`shortest_log` samples.

    Parameters
    ----------
    source : str
        The log, for the message.
    n : int
        Its samples (on the filter's grid).
    design : LowPass
        The filter.
    helps : str
        What would help, for the message.

    Raises
    ------
    DataError
        One line: the samples, the rate, the edges, what would help.
    """
    if n < shortest_log(design.fs, design.cutoff):
        raise DataError(f"{source}: {counted(n, 'sample')} at {design.fs:.6g} Hz; the filter edges alone take "
                        f"2 x {design.pad} ({helps})")


def excitation_bandwidth(q, fs: float, energy: float = 0.995) -> float:
    """The frequency below which the motion has ``energy`` of its spectral energy.

    Per joint, the one-sided power spectrum of ``q`` minus its mean (Hann window); the largest
    over the joints of the frequency where the cumulative energy reaches ``energy``. An
    excitation trajectory (a Fourier series of a fraction of a hertz, a few harmonics) gives its
    highest harmonic; encoder noise is far below the motion and does not move it.

    Parameters
    ----------
    q : array_like, shape ``(S, m)``
        Uniformly sampled positions.
    fs : float
        Sampling rate [Hz].
    energy : float
        Fraction of the energy, in ``(0, 1)``.

    Returns
    -------
    float
        The bandwidth [Hz] (0 for a log without motion).
    """
    q = np.asarray(q, dtype=float)
    x = (q - q.mean(axis=0)) * np.hanning(len(q))[:, None]
    p = np.abs(np.fft.rfft(x, axis=0)) ** 2
    total = p.sum(axis=0)
    moving = total > 0
    if not moving.any():
        return 0.0
    cum = np.cumsum(p[:, moving], axis=0) / total[moving]
    k = (cum < energy).sum(axis=0)  # first bin reaching the energy, per joint
    return float(np.fft.rfftfreq(len(q), 1.0 / fs)[min(int(k.max()), p.shape[0] - 1)])


def zero_phase(x, design: LowPass, axis: int = 0) -> np.ndarray:
    """Filter forward and backward with ``design`` (no phase lag; magnitude squared).

    Parameters
    ----------
    x : array_like, shape ``(S, ...)``
        Signals, sampled at ``design.fs`` along ``axis`` (any other axes: columns filtered
        independently, e.g. a regressor ``(S, m, p)``).
    design : LowPass
        The filter (:func:`lowpass_design`).
    axis : int, optional
        The sample axis (default 0).

    Returns
    -------
    ndarray, same shape as ``x``
        The filtered signals (``scipy.signal.sosfiltfilt`` on the signal extended by
        ``min(EXTENSION * design.pad, S - 1)`` samples at each end (four cutoff periods: the initial
        conditions' transient decays to ~1e-4 within them), odd extension with the curvature kept
        (:func:`baseparams.regressor.compiled.edge_extended`: no edge transient on a smooth
        signal's derivatives, and one linear map for every signal); once the compiled kernels are loaded,
        e.g. by a long log's regressor, large arrays go through
        :func:`baseparams.regressor.compiled.sosfiltfilt`: the same arithmetic, columns in parallel).

    Raises
    ------
    DataError
        Fewer than 2 samples.
    """
    x = np.asarray(x, dtype=float)
    n = x.shape[axis]
    if n < 2:
        raise DataError(f"low-pass: {counted(n, 'sample')}; at least 2 are needed")
    pad = min(EXTENSION * design.pad, n - 1)
    if axis in (0, -x.ndim) and x.size >= COMPILED_FILTER_MIN and _compiled_loaded():
        from ..regressor.compiled import sosfiltfilt

        return sosfiltfilt(design.sos, x, pad)  # scipy's arithmetic, columns in parallel
    from ..regressor.compiled import edge_extended

    moved = np.moveaxis(x, axis, 0)
    ext = edge_extended(moved.reshape(n, -1), pad)
    out = signal.sosfiltfilt(design.sos, ext, axis=0, padtype=None)[pad:pad + n]
    return np.moveaxis(out.reshape(moved.shape), 0, axis)


#: values (samples x columns) from which :func:`zero_phase` uses the compiled filter once numba's kernels are loaded
COMPILED_FILTER_MIN = 1 << 16


def _compiled_loaded() -> bool:
    """Whether the compiled kernels are loaded in this process (a long log's regressor loaded them)."""
    from ..regressor import compiled

    return compiled.loaded()


def derivatives(q, fs: float, design: LowPass | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and accelerations of ``q`` by central differences of the low-passed signal.

    Central differences (``np.gradient``, second order inside and at the ends) rather than
    Savitzky-Golay: the low-pass already sets the bandwidth, so the differentiator only has to be
    exact on the band it passes; at 20+ samples per cutoff period its error is below 0.4 % there.
    It is linear and time-invariant away from the ends, which the parallel filtering of the
    regressor relies on, and it adds no second smoothing bandwidth to choose and report.
    ``ddq`` is the central difference of ``dq`` (a 5-point stencil on ``q``).

    Parameters
    ----------
    q : array_like, shape ``(S, ...)``
        Positions [rad or m], uniformly sampled.
    fs : float
        Sampling rate [Hz].
    design : LowPass, optional
        The low-pass applied (zero-phase) before differentiating; ``None`` when ``q`` is already
        filtered.

    Returns
    -------
    dq : ndarray, shape ``(S, ...)``
        Velocities [rad/s or m/s].
    ddq : ndarray, shape ``(S, ...)``
        Accelerations [rad/s^2 or m/s^2].

    Raises
    ------
    DataError
        Fewer than 3 samples or ``fs`` not positive.
    """
    q = np.asarray(q, dtype=float)
    if q.shape[0] < 3:
        raise DataError(f"derivatives: {q.shape[0]} samples; at least 3 are needed")
    if not (np.isfinite(fs) and fs > 0):
        raise DataError(f"derivatives: sampling rate must be a positive number of Hz, got {fs!r}")
    qf = zero_phase(q, design) if design is not None else q
    dq = np.gradient(qf, 1.0 / fs, axis=0, edge_order=2)
    return dq, np.gradient(dq, 1.0 / fs, axis=0, edge_order=2)


def decimate(x, factor: int, design: LowPass | None = None, axis: int = 0) -> np.ndarray:
    """Keep every ``factor``-th sample, after the zero-phase low-pass when ``design`` is given.

    Unlike ``scipy.signal.decimate`` this uses the identification low-pass itself as the
    anti-alias filter, so ``tau`` and regressor columns decimated here went through one and the
    same filter (parallel decimation).

    Parameters
    ----------
    x : array_like, shape ``(S, ...)``
        Signals sampled at ``design.fs`` along ``axis``.
    factor : int
        Keep samples ``0, factor, 2 factor, ...`` (1: all).
    design : LowPass, optional
        Low-pass applied first (zero phase); ``None`` when ``x`` is already filtered. Its cutoff
        must be below the Nyquist rate after decimation, ``fs / (2 factor)``.
    axis : int, optional
        The sample axis (default 0).

    Returns
    -------
    ndarray, shape ``(ceil(S / factor), ...)``
        The kept samples.

    Raises
    ------
    DataError
        ``factor`` not a positive integer, or a cutoff at or above the new Nyquist rate
        (aliasing).
    """
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
        raise DataError(f"decimate: factor must be a positive integer, got {factor!r}")
    x = np.asarray(x, dtype=float)
    if design is not None:
        if design.cutoff >= design.fs / (2 * factor):
            raise DataError(f"decimate: by {factor} the Nyquist rate is {design.fs / (2 * factor):.4g} Hz, not above "
                            f"the cutoff {design.cutoff:.4g} Hz (aliasing); lower the factor or the cutoff")
        x = zero_phase(x, design, axis=axis)
    index = [slice(None)] * x.ndim
    index[axis] = slice(None, None, int(factor))
    return x[tuple(index)]


def remove_slow(data, threshold) -> tuple[np.ndarray, dict[str, int]]:
    """Samples to keep when low speeds are to be left out (Coulomb friction: ``sign(dq)``).

    A sample is removed when ``|dq|`` of any joint is below its threshold.

    Parameters
    ----------
    data : JointLog or array_like, shape ``(S, m)``
        A log with velocities, or the velocities [rad/s or m/s] themselves.
    threshold : float or array_like, shape ``(m,)``
        Smallest speed kept, per joint or for all [rad/s or m/s].

    Returns
    -------
    keep : ndarray of bool, shape ``(S,)``
        True where every joint moves at least as fast as its threshold.
    removed : dict of str to int
        ``{"slow (|dq| < min_speed on a joint)": count}`` (empty when none is removed).

    Raises
    ------
    DataError
        A log without velocities, or a threshold of the wrong shape or negative.
    """
    if isinstance(data, JointLog):
        if data.dq is None:
            raise DataError(f"{data.source}: no dq to find slow samples (derive it first: prepare)")
        dq = data.dq
    else:
        dq = np.asarray(data, dtype=float)
    dq = dq.reshape(len(dq), -1)
    thr = np.asarray(threshold, dtype=float)
    if thr.ndim > 1 or (thr.ndim == 1 and thr.shape != (dq.shape[1],)) or np.any(~(thr >= 0)):
        raise DataError(f"remove_slow: threshold must be a speed >= 0 or one per joint ({dq.shape[1]}), "
                        f"got {threshold!r}")
    keep = np.all(np.abs(dq) >= thr, axis=1)
    count = int((~keep).sum())
    return keep, ({"slow (|dq| < min_speed on a joint)": count} if count else {})


def slow_threshold(joints, min_speed):
    """``min_speed`` per log column: zero (never slow) on a floating base's coordinates, which are no joint.

    Parameters
    ----------
    joints : sequence of str, shape ``(m,)``
        The log's columns (``JointLog.joints``).
    min_speed : float or array_like, shape ``(m,)``
        The slowest speed kept [rad/s or m/s].

    Returns
    -------
    float or ndarray, shape ``(m,)``
        ``min_speed`` as given without a floating base; else per column, zero on the base's.
    """
    from ..kinematics.floating import BASE_COORDINATES

    base = np.isin(np.asarray(joints, dtype=object), BASE_COORDINATES)
    if not base.any():
        return min_speed
    return np.where(base, 0.0, np.broadcast_to(np.asarray(min_speed, dtype=float), base.shape))


def resample(log: JointLog, rate: float | None = None, rtol: float = UNIFORM_RTOL) -> JointLog:
    """The log on a uniform time grid, by linear interpolation of every signal.

    A log whose steps are all within ``rtol`` of their median (and of ``1 / rate`` when given)
    is returned as it is, with a note. Otherwise the grid starts at ``t[0]`` with step
    ``1 / rate`` (default: the median rate) and ends at or before ``t[-1]``; every signal is
    interpolated linearly (vectorised ``np.interp`` over all columns).

    Parameters
    ----------
    log : JointLog
        The log, ``t (S,)`` strictly increasing.
    rate : float, optional
        Sampling rate of the grid [Hz]; default the median of ``1 / diff(t)``.
    rtol : float, optional
        Relative spread of the steps below which the log counts as uniform.

    Returns
    -------
    JointLog
        The resampled log; its notes say how non-uniform the log was (step range, largest gap)
        and the rate used. Samples fewer than before are counted in ``removed``.

    Raises
    ------
    DataError
        Fewer than 2 samples, time not strictly increasing, or ``rate`` not positive.
    """
    t = np.asarray(log.t, dtype=float)
    if len(t) < 2 or np.any(np.diff(t) <= 0):
        raise DataError(f"{log.source}: resample needs at least 2 samples with strictly increasing time")
    dt = np.diff(t)
    med = float(np.median(dt))
    spread = f"dt {dt.min() * 1e3:.4g}-{dt.max() * 1e3:.4g} ms, median {med * 1e3:.4g} ms"
    if rate is not None and not (np.isfinite(rate) and rate > 0):
        raise DataError(f"{log.source}: resample rate must be a positive number of Hz, got {rate!r}")
    uniform = np.all(np.abs(dt - med) <= rtol * med)
    if uniform and (rate is None or abs(rate * med - 1) <= rtol):
        return replace(log, notes=log.notes + (f"time: uniform ({spread}), not resampled",))
    step = med if rate is None else 1.0 / rate
    n = int(np.floor((t[-1] - t[0]) / step * (1 + 1e-12))) + 1
    tn = t[0] + step * np.arange(n)
    off = int(np.sum(np.abs(dt - med) > rtol * med))
    note = (f"time: resampled {len(t)} non-uniform samples ({spread}; {off} steps off the median by more than "
            f"{rtol:.1%}, largest gap {dt.max() / med:.3g} steps) to {n} at {1 / step:.6g} Hz "
            f"({'the median rate' if rate is None else 'rate given'}), linear interpolation")
    removed = dict(log.removed)
    if n < len(t):
        removed["resampling to fewer samples"] = removed.get("resampling to fewer samples", 0) + len(t) - n
    return replace(interpolate(log, tn), removed=removed, notes=log.notes + (note,))


def interpolate(log: JointLog, tn: np.ndarray) -> JointLog:
    """Every signal of a log interpolated linearly at other times (what :func:`resample` does on its grid).

    Parameters
    ----------
    log : JointLog
        The log, ``t (S,)`` strictly increasing, ``S >= 2``.
    tn : ndarray, shape ``(K,)``
        The times [s], increasing; outside ``[t[0], t[-1]]`` the end values are held.

    Returns
    -------
    JointLog
        ``log`` at ``tn``: each signal ``(K, m)`` (``None`` stays ``None``); source, notes and
        counts as ``log``'s.
    """
    t = np.asarray(log.t, dtype=float)
    dt = np.diff(t)
    i = np.clip(np.searchsorted(t, tn, side="right") - 1, 0, len(t) - 2)
    w = np.clip((tn - t[i]) / dt[i], 0.0, 1.0)

    def interp(y):
        if y is None:
            return None
        ww = w.reshape((-1,) + (1,) * (y.ndim - 1))
        return y[i] * (1.0 - ww) + y[i + 1] * ww

    return replace(log, t=tn, q=interp(log.q), tau=interp(log.tau), dq=interp(log.dq), ddq=interp(log.ddq))


@dataclass(frozen=True, eq=False)
class Prepared:
    """A log ready for identification: filtered, differentiated, trimmed and decimated.

    Parameters
    ----------
    t : ndarray, shape ``(S',)``
        Time of the kept samples [s].
    joints : tuple of str, shape ``(m,)``
        The model's joint names of the columns.
    q, dq, ddq, tau : ndarray, shape ``(S', m)``
        Filtered positions [rad or m], velocities, accelerations and generalized forces
        [N m or N] at the kept samples.
    fs : float
        Sampling rate after decimation [Hz].
    design : LowPass
        The zero-phase low-pass used on every signal (at the full rate ``design.fs``).
    factor : int
        Decimation factor (1: none).
    index : ndarray of int, shape ``(S',)``
        Indices of the kept samples in the full-rate (resampled) log :attr:`full`.
    full : JointLog
        The uniform full-rate log, ``S`` samples: filtered ``q`` and ``tau``, ``dq``, ``ddq``
        (derived or filtered). Compute regressors on it, then :meth:`apply`.
    source : str
        Where the log comes from.
    removed : dict of str to int
        Samples removed and why, cumulative with the log's (filter edges, decimation, slow).
    notes : tuple of str
        Every choice made, one line each (the log's notes first).
    stride : int
        The rigid-body regressor's samples: every ``stride``-th full-rate sample, through every
        kept one (:func:`regressor_stride`; 1: every sample).
    trim : int
        Samples left out at each end of :attr:`full` (0: every sample is fitted).
    band : float
        The motion's bandwidth [Hz] (:func:`excitation_bandwidth` of the unfiltered positions of
        :func:`prepare`'s ``columns``) that chose the default cutoff and that the rate is checked
        against; NaN when neither asked for it.
    """

    t: np.ndarray
    joints: tuple[str, ...]
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    tau: np.ndarray
    fs: float
    design: LowPass
    factor: int
    index: np.ndarray
    full: JointLog
    source: str = "<memory>"
    removed: dict[str, int] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    stride: int = 1
    trim: int = 0
    band: float = float("nan")

    __repr__ = summary_repr

    @property
    def n_samples(self) -> int:
        """Number of kept samples ``S'``."""
        return len(self.t)

    @property
    def oversampling(self) -> float:
        """Kept samples per independent sample of the low-passed signals: ``fs / (DECIMATE_MARGIN cutoff)``, >= 1.

        The default decimation keeps about one (2.5 samples per period at the Nyquist rate); every sample of a
        short log keeps more, correlated by the filter: the priors' weights are set against the information
        (:attr:`~baseparams.ident.estimate.RowAccumulator.oversampling`).
        """
        return max(1.0, self.fs / (DECIMATE_MARGIN * self.design.cutoff))

    @property
    def grid(self) -> np.ndarray:
        """The samples smooth columns are evaluated at: every :attr:`stride`-th of :attr:`full`, through every kept one.

        Returns
        -------
        ndarray of int, shape ``(G,)``
            Indices into :attr:`full`: ``phase, phase + stride, ...`` with ``phase = trim mod stride``.
        """
        return np.arange(self.trim % self.stride, self.full.n_samples, self.stride)

    def apply_strided(self, x) -> np.ndarray:
        """:meth:`apply` for columns smooth in the filtered states, evaluated at :attr:`grid` only.

        Filtered with the low-pass of the same cutoff at ``design.fs / stride``
        (:func:`stride_design`; module docstring), then the kept samples taken.

        Parameters
        ----------
        x : array_like, shape ``(G, ...)``
            One row per sample of :attr:`grid` (e.g. gravity torques of ``full.q[grid]``).

        Returns
        -------
        ndarray, shape ``(S', ...)``
            The rows matching :attr:`tau`.

        Raises
        ------
        DataError
            ``x`` without one row per sample of :attr:`grid`.
        """
        x = np.asarray(x, dtype=float)
        phase = self.trim % self.stride
        g = len(range(phase, self.full.n_samples, self.stride))
        if x.ndim == 0 or x.shape[0] != g:
            raise DataError(f"{self.source}: apply_strided needs one row per strided sample ({g}), got shape {x.shape}")
        return zero_phase(x, stride_design(self.design, self.stride), axis=0)[(self.index - phase) // self.stride]

    def apply(self, x) -> np.ndarray:
        """Filter full-rate rows like ``tau`` was and keep the same samples (parallel filtering).

        Parameters
        ----------
        x : array_like, shape ``(S, ...)``
            Full-rate signals, one row per sample of :attr:`full` (e.g. a regressor
            ``(S, m, p)`` computed from ``full.q, full.dq, full.ddq``; a model's rows are cheaper
            with :func:`baseparams.ident.chunks.prepared_rows`, which evaluates the rigid part at
            the stride).

        Returns
        -------
        ndarray, shape ``(S', ...)``
            ``zero_phase(x, design)[index]``: the rows matching :attr:`tau`.

        Raises
        ------
        DataError
            ``x`` without one row per full-rate sample.
        """
        x = np.asarray(x, dtype=float)
        n = self.full.n_samples
        if x.ndim == 0 or x.shape[0] != n:
            raise DataError(f"{self.source}: apply needs one row per full-rate sample ({n}), got shape {x.shape}")
        return zero_phase(x, self.design, axis=0)[self.index]


def prepare(log: JointLog, fs: float | None = None, cutoff: float | None = None, decimate: int | None = None,
            min_speed=None, columns=None) -> Prepared:
    """Resample, low-pass, differentiate, decimate, drop slow samples (every sample kept otherwise, the ends too).

    Parameters
    ----------
    log : JointLog
        The log (:func:`~baseparams.io.logs.read_log`), ``S0`` samples.
    fs : float, optional
        Rate of the uniform grid [Hz]; default the median rate of the log (no resampling when the
        log is already uniform).
    cutoff : float, optional
        Low-pass cutoff [Hz]; default ten times the excitation bandwidth
        (:func:`excitation_bandwidth`), within 1 Hz and :func:`lowpass_design`'s default.
    decimate : int, optional
        Keep every k-th sample after the low-pass; default the largest k with
        ``fs / k >= 5 cutoff`` (the filtered signal is then oversampled 2.5 times past Nyquist);
        1 keeps every sample.
    min_speed : float or array_like, shape ``(m,)``, optional
        Remove samples where any joint is slower than this [rad/s or m/s]
        (:func:`remove_slow`); default none removed.
    columns : array_like of int, optional
        The columns of ``q`` whose motion is measured (the identified coordinates): their
        bandwidth sets the default cutoff and is :attr:`Prepared.band`; default every column
        (measured only for the default cutoff).

    Returns
    -------
    Prepared
        The kept samples, the filter, :meth:`Prepared.apply` for regressor columns, the rate,
        the removal counts and a note per choice.

    Raises
    ------
    DataError
        A malformed log (shapes, non-finite values, time), a log shorter than the two filter
        edges, or bad ``fs``, ``cutoff``, ``decimate`` or ``min_speed``.
    """
    _check_log(log)
    u = resample(log, fs)
    rate = (u.n_samples - 1) / float(u.t[-1] - u.t[0])  # the mean rate: the grid's, or a uniform log's
    given_cutoff = cutoff is not None
    band = (excitation_bandwidth(u.q if columns is None else u.q[:, columns], rate)
            if cutoff is None or columns is not None else float("nan"))  # once: the cutoff's and the rate's
    if cutoff is None:  # from the excitation: 10x its bandwidth, within [1 Hz, min(fs/20, 20 Hz)]
        cutoff, log_note = default_cutoff(band, rate)
        u = replace(u, notes=u.notes + (log_note,))
    design = lowpass_design(rate, cutoff, why="given" if given_cutoff else "from the excitation bandwidth")
    n = u.n_samples
    check_length(log.source, n, design)
    qf, tauf, dqf, ddqf = _filtered_together(design, u.q, u.tau, u.dq, u.ddq)
    dq, ddq, rate_notes = filtered_rates(u, qf, rate, design, dqf, ddqf)
    k, k_note = decimation_factor(decimate, rate, design, n)
    r, r_note = regressor_stride(k, rate, design)
    removed = dict(u.removed)
    inner = np.arange(n)  # every sample: the ends too (EDGE_PERIODS)
    index = inner[::k]
    if k > 1:
        removed[f"decimation by {k}"] = removed.get(f"decimation by {k}", 0) + len(inner) - len(index)
    notes = [design.note, *rate_notes, k_note, r_note, EDGE_NOTE]
    if min_speed is not None:
        keep, slow = remove_slow(dq[index], slow_threshold(u.joints, min_speed))
        index = index[keep]
        for reason, c in slow.items():
            removed[reason] = removed.get(reason, 0) + c
        shown = np.asarray(min_speed) if np.ndim(min_speed) else min_speed  # per joint: one array, however given
        notes.append(f"slow samples: {int((~keep).sum())} with |dq| below {shown} on a joint removed")
    else:
        notes.append("slow samples: kept (min_speed not given)")
    if len(index) == 0:
        raise DataError(f"{log.source}: no sample left after edges, decimation and slow-sample removal")
    full = replace(u, q=qf, tau=tauf, dq=dq, ddq=ddq, notes=u.notes + tuple(notes))
    return Prepared(t=u.t[index], joints=u.joints, q=qf[index], dq=dq[index], ddq=ddq[index], tau=tauf[index],
                    fs=rate / k, design=design, factor=k, index=index, full=full, source=log.source, band=band,
                    removed=removed, notes=full.notes, stride=r)


#: how the ends of a log are treated, for the report
EDGE_NOTE = ("edges: every sample fitted, the ends too (the states filtered through an extension that keeps their "
             "curvature, the torques and the regressor's columns through the same filter)")


def _check_log(log: JointLog) -> None:
    """Shapes ``(S, m)`` matching ``t (S,)`` and ``joints (m,)``, finite values, increasing time."""
    t = np.asarray(log.t)
    m = len(log.joints)
    arrays = {"t": t, "q": log.q, "tau": log.tau, "dq": log.dq, "ddq": log.ddq}
    for name, a in arrays.items():
        if a is None:
            continue
        a = np.asarray(a)
        shape = (len(t),) if name == "t" else (len(t), m)
        if a.shape != shape:
            raise DataError(f"{log.source}: {name} has shape {a.shape}, expected {shape}")
        bad = ~np.isfinite(a)
        if bad.any():
            i = np.unravel_index(int(np.argmax(bad)), a.shape)
            where = f", joint {log.joints[i[1]]!r}" if a.ndim == 2 else ""
            raise DataError(f"{log.source}: {name}{where}, sample {i[0]} (0-based): {a[i]} (not finite)")
    if len(t) >= 2 and np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0)) + 1
        raise DataError(f"{log.source}: t, sample {i} (0-based): {t[i]:.9g} s not after {t[i - 1]:.9g} s")


def _filtered_together(design: LowPass, *signals):
    """``zero_phase`` of each ``(S, m)`` signal (None stays None), in one call (its columns filtered together)."""
    given = [x for x in signals if x is not None]
    out = iter(np.split(zero_phase(np.concatenate(given, axis=1), design), np.cumsum([x.shape[1] for x in given])[:-1],
                        axis=1))
    return [None if x is None else next(out) for x in signals]


def filtered_rates(u: JointLog, qf: np.ndarray, rate: float, design: LowPass, dqf: np.ndarray | None = None,
                   ddqf: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``dq, ddq``: measured ones low-passed with the same filter, or derived from the filtered q.

    Parameters
    ----------
    u : JointLog
        The uniform log (``S`` samples; its ``dq``, ``ddq`` when logged).
    qf : ndarray, shape ``(S, m)``
        The low-passed positions.
    rate : float
        The sampling rate [Hz].
    design : LowPass
        The low-pass.
    dqf, ddqf : ndarray, shape ``(S, m)``, optional
        The measured ``dq``, ``ddq`` already low-passed (else filtered here).

    Returns
    -------
    dq, ddq : ndarray, shape ``(S, m)``
        Velocities and accelerations.
    notes : list of str
        How each was obtained (a measured ``dq``: its RMS difference to d/dt of the filtered q).
    """
    derived, dderived = derivatives(qf, rate)
    notes = []
    if u.dq is not None:
        dq = zero_phase(u.dq, design) if dqf is None else dqf
        p = design.pad
        rms = np.sqrt(np.mean((dq[p:-p] - derived[p:-p]) ** 2, axis=0))
        scale = np.sqrt(np.mean(dq[p:-p] ** 2, axis=0))
        notes.append("dq: measured, low-passed with the same filter; RMS difference to d/dt of the filtered q: "
                     + ", ".join(f"{a:.3g}" for a in rms) + " (RMS dq: " + ", ".join(f"{b:.3g}" for b in scale) + ")")
    else:
        dq = derived
        notes.append("dq: derived, central differences of the filtered q (np.gradient)")
    if u.ddq is not None:
        ddq = zero_phase(u.ddq, design) if ddqf is None else ddqf
        notes.append("ddq: measured, low-passed with the same filter")
    else:
        ddq = np.gradient(dq, 1.0 / rate, axis=0, edge_order=2) if u.dq is not None else dderived
        notes.append("ddq: derived, central differences of dq")
    return dq, ddq, notes


def decimation_factor(decimate: int | None, rate: float, design: LowPass, n: int | None = None) -> tuple[int, str]:
    """The decimation factor (given or default) and its note; a factor that aliases is an error.

    Parameters
    ----------
    decimate : int or None
        The factor given, or None: the largest ``k`` with ``rate / k >= 5 cutoff`` that keeps at
        least :data:`MIN_FITTED` of ``n`` samples, lowered by one when it is a prime above 3 (so that
        a divisor of it is a stride for the regressor, :func:`regressor_stride`).
    rate : float
        The sampling rate [Hz].
    design : LowPass
        The low-pass.
    n : int, optional
        The samples of the log (None: no floor on the samples kept).

    Returns
    -------
    factor : int
        The factor.
    note : str
        One line for the report.

    Raises
    ------
    DataError
        A factor that is not a positive integer or whose Nyquist rate is not above the cutoff.
    """
    if decimate is None:
        k = max(1, int(np.floor(rate / (DECIMATE_MARGIN * design.cutoff) * (1 + 1e-3))))  # 0.1 %: a jittered rate
        why = f"default: largest k with fs/k >= {DECIMATE_MARGIN:g} x cutoff"
        if n is not None and k > max(1, n // MIN_FITTED):
            k = max(1, n // MIN_FITTED)
            why += f" keeping at least {MIN_FITTED} of the {n} samples"
        if k > 3 and all(k % d for d in range(2, math.isqrt(k) + 1)):
            k -= 1
            why += ", less one for a prime"
    else:
        if isinstance(decimate, bool) or not isinstance(decimate, (int, np.integer)) or decimate < 1:
            raise DataError(f"prepare: decimate must be a positive integer, got {decimate!r}")
        k, why = int(decimate), "given"
        if design.cutoff >= rate / (2 * k):
            raise DataError(f"prepare: decimating by {k} leaves a Nyquist rate of {rate / (2 * k):.4g} Hz, not above "
                            f"the cutoff {design.cutoff:.4g} Hz (aliasing); lower decimate or the cutoff")
    return k, f"decimation: 1 sample in {k} kept ({why}), {rate / k:.6g} Hz after"


def regressor_stride(k: int, rate: float, design: LowPass) -> tuple[int, str]:
    """The regressor's stride: the largest divisor ``r`` of ``k`` with ``rate / r >= STRIDE_MARGIN cutoff``.

    The regressor is evaluated at every ``r``-th sample (through every kept one) and
    parallel-filtered at ``rate / r`` (module docstring); with the default decimation (``rate / k
    >= 5 cutoff``, ``k`` not a prime above 3) ``k`` over its smallest prime factor always qualifies.

    Parameters
    ----------
    k : int
        The decimation factor.
    rate : float
        The sampling rate [Hz].
    design : LowPass
        The low-pass (its cutoff).

    Returns
    -------
    stride : int
        ``r`` (1: every sample).
    note : str
        One line for the report.
    """
    r = next(d for d in range(k, 0, -1) if k % d == 0 and (d == 1 or rate / d >= STRIDE_MARGIN * design.cutoff))
    if r == 1:
        return 1, "regressor: evaluated and parallel-filtered at every sample"
    return r, (f"regressor: evaluated at 1 sample in {r} ({rate / r:.6g} Hz, at least {STRIDE_MARGIN:g} x the cutoff; "
               f"the states low-passed at the full rate before) and parallel-filtered at that rate")


def stride_design(design: LowPass, stride: int) -> LowPass:
    """The low-pass of the same cutoff and order at ``design.fs / stride`` (``design`` for stride 1).

    Parameters
    ----------
    design : LowPass
        The full-rate low-pass.
    stride : int
        The regressor's stride (:func:`regressor_stride`).

    Returns
    -------
    LowPass
        The design at the regressor's rate.
    """
    if stride == 1:
        return design
    return lowpass_design(design.fs / stride, design.cutoff, design.order, why="the regressor's rate")


def log_states(log: JointLog, cutoff: float | None, filtered: bool = False) -> tuple[np.ndarray, ...]:
    """States at every sample of a log, for predicting its torques.

    What the log has is used as it is; what it lacks is derived the way identification derives
    it (:func:`prepare`): on a uniform grid (the log's own when its
    time is uniform, else resampled at its median rate), positions low-passed with the zero-phase
    Butterworth filter of the identification's ``cutoff``, ``dq`` by central differences of the
    filtered ``q`` (``np.gradient``), ``ddq`` by central differences of ``dq`` (a measured ``dq``
    low-passed first); derived rates are interpolated back to the log's time stamps (linear).
    No sample is dropped: within ``2 fs / cutoff`` samples of either end the derived rates carry
    the filter's edge transient (odd extension).

    Parameters
    ----------
    log : JointLog
        The log, ``S`` samples (``tau`` may be ``None``).
    cutoff : float or None
        The low-pass cutoff [Hz] (the identification's); ``None``: the default of
        :func:`prepare` for this log.
    filtered : bool
        Low-pass the logged ``q``, ``dq`` and ``ddq`` too (identification's treatment of every
        signal) instead of using them as logged.

    Returns
    -------
    q, dq, ddq : ndarray, shape ``(S, m)``
        States at ``log.t``, columns in ``log.joints`` order.
    notes : tuple of str
        How each was obtained, one line each.

    Raises
    ------
    DataError
        Fewer than 3 samples, time not increasing, a cutoff not below the log's Nyquist rate, or
        a log to filter shorter than the filter's two edges (:func:`check_length`: every predicted
        sample would be the edge transient's, a 5-sample log's torques 100 % off).
    """
    t = np.asarray(log.t, dtype=float)
    if log.dq is not None and log.ddq is not None and not filtered:
        return log.q, log.dq, log.ddq, ("q, dq, ddq: as logged",)
    u = resample(log)
    rate = (u.n_samples - 1) / float(u.t[-1] - u.t[0])
    if cutoff is None:
        cutoff = default_cutoff(excitation_bandwidth(u.q, rate), rate)[0]
    design = lowpass_design(rate, cutoff)
    check_length(log.source, u.n_samples, design,  # shorter: every sample in the filter's edge transient
                 f"at the identification's cutoff {cutoff:.4g} Hz: a log of at least "
                 f"{shortest_log(rate, cutoff) / rate:.3g} s, or one with dq and ddq logged and --raw-states")
    same_grid = u.n_samples == len(t) and np.array_equal(u.t, t)

    def back(x):  # grid -> the log's time stamps
        if same_grid:
            return x
        return np.column_stack([np.interp(t, u.t, x[:, k]) for k in range(x.shape[1])])

    how = f"zero-phase Butterworth low-pass at {cutoff:.4g} Hz"
    grid = "" if same_grid else f" on a uniform {rate:.6g} Hz grid, interpolated back"
    qf = zero_phase(u.q, design)
    q, qn = (back(qf), f"q: {how}{grid}") if filtered else (log.q, "q: as logged")
    if log.dq is not None:
        dqf = zero_phase(u.dq, design)
        dq, dqn = (back(dqf), f"dq: logged, {how}{grid}") if filtered else (log.dq, "dq: as logged")
    else:
        dqf = np.gradient(qf, 1.0 / rate, axis=0, edge_order=2)
        dq, dqn = back(dqf), f"dq: derived, central differences of q after the {how}{grid}"
    if log.ddq is not None:
        ddq, ddqn = ((back(zero_phase(u.ddq, design)), f"ddq: logged, {how}{grid}") if filtered
                     else (log.ddq, "ddq: as logged"))
    else:
        ddq = back(np.gradient(dqf, 1.0 / rate, axis=0, edge_order=2))
        ddqn = f"ddq: derived, central differences of dq{' (logged, low-passed)' if log.dq is not None else ''}{grid}"
    return np.asarray(q, float), np.asarray(dq, float), np.asarray(ddq, float), (qn, dqn, ddqn)


def lowpass_at(t, x, cutoff: float) -> np.ndarray:
    """Signals low-passed as identification filters them, at their own time stamps.

    Parameters
    ----------
    t : array_like, shape ``(S,)``
        Time stamps [s], strictly increasing.
    x : array_like, shape ``(S, k)``
        Signals (e.g. measured and predicted torques).
    cutoff : float
        The cutoff [Hz] (the identification's).

    Returns
    -------
    ndarray, shape ``(S, k)``
        Zero-phase Butterworth low-passed (:func:`zero_phase`) on a
        uniform grid at the median rate (the log's own when uniform), interpolated back.

    Raises
    ------
    DataError
        A cutoff not below the Nyquist rate, fewer than 2 samples.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    u = resample(JointLog(t, tuple(str(k) for k in range(x.shape[1])), x, x))
    rate = (u.n_samples - 1) / float(u.t[-1] - u.t[0])
    f = zero_phase(u.q, lowpass_design(rate, cutoff))
    if u.n_samples == len(t) and np.array_equal(u.t, t):
        return f
    return np.column_stack([np.interp(t, u.t, f[:, k]) for k in range(f.shape[1])])
