"""What is predicted and how it is scored: held-out error the way an outsider measures it.

:func:`split_log` holds out a log's tail; :func:`predict_log` predicts every sample of a log
(states filtered as the fit's were, :func:`~baseparams.ident.preprocess.log_states`);
:func:`model_torques` adds the model terms to the core torques; :func:`validation_scores` compares
with the raw measured torques; :func:`report_series` and :func:`position_spectrum` are the report's
curves.
"""

from __future__ import annotations

import numpy as np

from ..errors import BaseparamsError
from ..numerics import blas_threads
from .fitting import Fit
from .model import IdentModel
from .rows import log_columns


def split_log(log, seconds: float):
    """The log split into training and the last ``seconds`` held out.

    Parameters
    ----------
    log : JointLog
        The log.
    seconds : float
        Length of the held-out tail [s].

    Returns
    -------
    train, held : JointLog
        The two parts (each filtered on its own later: no information crosses the split).

    Raises
    ------
    BaseparamsError
        ``seconds`` not inside the log's duration.
    """
    from dataclasses import replace

    t = log.t
    if not 0 < seconds < t[-1] - t[0]:
        raise BaseparamsError(f"{log.source}: holdout {seconds} s must be inside the log's {t[-1] - t[0]:.6g} s")
    cut = int(np.searchsorted(t, t[-1] - seconds))

    def part(sl):  # every per-sample signal the log has (torques, rates, currents)
        rest = {k: None if getattr(log, k) is None else getattr(log, k)[sl] for k in ("tau", "dq", "ddq", "cur")}
        return replace(log, t=t[sl], q=log.q[sl], **rest)

    return part(slice(0, cut)), replace(part(slice(cut, None)), source=f"{log.source} (last {seconds:g} s)")


def predict_log(f: Fit, log, cutoff: float | None, smooth: bool = True) -> np.ndarray:
    """Predicted torques ``(S, m)`` at every sample of ``log`` (:meth:`~baseparams.ident.Identification.predict`).

    Parameters
    ----------
    f : Fit
        The identified values (and model terms).
    log : JointLog
        ``S`` samples of the measured joints.
    cutoff : float or None
        The identification's low-pass cutoff [Hz] (None: the log's default).
    smooth : bool
        Filtered states (default), or the states as logged.

    Returns
    -------
    ndarray, shape ``(S, m)``
        Columns the measured joints in the model's order.
    """
    from .preprocess import log_states

    cols = log_columns(f.model, log)
    q, dq, ddq, _ = log_states(log, cutoff, smooth)
    return model_torques(f, log.t, log.q[:, cols[f.model.row_states]], q[:, cols], dq[:, cols], ddq[:, cols])


def model_torques(f: Fit, t: np.ndarray, q_raw: np.ndarray, q: np.ndarray, dq: np.ndarray,
                  ddq: np.ndarray) -> np.ndarray:
    """The fitted model's torques as the sensors measure them, the model terms included.

    The core ``A(q, dq, ddq) theta`` (:meth:`Fit.predict`, in blocks), each term's contribution (Dahl's state along
    ``q_raw``, the tilt's gravity torque), then the sensors' scales and delays
    (:mod:`baseparams.ident.terms`).

    Parameters
    ----------
    f : Fit
        The fit.
    t : ndarray, shape ``(S,)``
        Time stamps [s] (the delays shift along them).
    q_raw : ndarray, shape ``(S, m)``
        Positions of the measured coordinates as logged (unfiltered).
    q, dq, ddq : ndarray, shape ``(S, state_columns)``
        The states.

    Returns
    -------
    ndarray, shape ``(S, m)``
        Predicted measured torques.
    """
    with blas_threads():
        tau = f.predict(q, dq, ddq)  # in blocks of PREDICT_BYTES
    for term in f.terms:
        tau = term.adjust_model(f, q_raw, q, dq, ddq, tau)
    for term in f.terms:
        tau = term.adjust_measured(np.asarray(t, dtype=float), tau)
    if not np.isfinite(tau).all():  # values or states beyond floating point: never NaN predictions
        from ..errors import DataError

        i = int(np.argmax(~np.isfinite(tau).all(axis=1)))
        raise DataError(f"the predicted torques are not finite from sample {i} on (t = {float(t[i]):.6g} s): the "
                        f"log's states or the values are beyond floating point")
    return tau


def validation_scores(log, pred: np.ndarray, names: list[str], mask=None, score_cutoff: float | None = None) -> dict:
    """Held-out error the way an outsider measures it: against the raw measured torques.

    Parameters
    ----------
    log : JointLog
        The log whose samples were predicted (``S`` samples, measured torques ``tau``).
    pred : ndarray, shape ``(S, m)``
        Predicted torques of the measured joints ``names`` (:func:`predict_log`).
    names : list of str, shape ``(m,)``
        The measured joints, in ``pred``'s column order.
    mask : ndarray of bool, shape ``(S,)``, optional
        The held-out samples (default: all).
    score_cutoff : float, optional
        Also score against the measured torques low-passed at this cutoff [Hz] (zero-phase
        Butterworth order 4 on the held-out samples).

    Returns
    -------
    dict
        ``rms`` (per joint), ``rms_total`` (over every held-out sample and joint), ``samples``,
        ``t_start``, ``t_end``, ``source``, ``measure``; with ``score_cutoff`` also
        ``score_cutoff``, ``rms_lowpassed`` and ``rms_lowpassed_total``.
    """
    from .preprocess import lowpass_at

    mask = np.ones(log.n_samples, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    where = {j: k for k, j in enumerate(log.joints)}
    measured = log.tau[:, [where[j] for j in names]][mask]
    err = pred[mask] - measured
    out = {"rms": dict(zip(names, np.sqrt(np.mean(err**2, axis=0)).tolist())),
           "rms_total": float(np.sqrt(np.mean(err**2))), "samples": int(mask.sum()),
           "t_start": float(log.t[mask][0]), "t_end": float(log.t[mask][-1]), "source": log.source,
           "measure": "RMS of predicted minus raw measured torques at every held-out sample"}
    if score_cutoff is not None:
        try:
            lp = lowpass_at(log.t[mask], measured, float(score_cutoff))
        except BaseparamsError as exc:
            raise BaseparamsError(f"--score-cutoff {score_cutoff:g} Hz on {log.source}'s held-out samples: "
                                  f"{exc}") from None
        e2 = pred[mask] - lp
        out.update({"score_cutoff": float(score_cutoff),
                    "rms_lowpassed": dict(zip(names, np.sqrt(np.mean(e2**2, axis=0)).tolist())),
                    "rms_lowpassed_total": float(np.sqrt(np.mean(e2**2)))})
    return out


def report_series(model: IdentModel, prep, cols: np.ndarray, theta, names: list[str], memory_mb: float,
                  raw_q: np.ndarray | None = None):
    """Measured and predicted torques of a prepared log, as they were compared (filtered).

    Parameters
    ----------
    model : IdentModel
        The model.
    prep : Prepared
        The prepared log.
    cols : ndarray of int, shape ``(state_columns,)``
        Log column of each state column.
    theta : ndarray, shape ``(p,)``, or Fit
        The identified values, or the fit (with its model terms; ``raw_q`` then gives the
        unfiltered positions on ``prep.full``'s grid for Dahl's state).
    names : list of str, shape ``(m,)``
        The measured joints.
    memory_mb : float
        Largest regressor formed at once (beyond, the predicted torques are not parallel-filtered).
    raw_q : ndarray, shape ``(S, m)``, optional
        With a fit whose terms need them: the measured coordinates' unfiltered positions.

    Returns
    -------
    dict
        ``{"t" (S',), "tau" (S', m), "tau_hat" (S', m), "joints" (m,)}`` at the kept samples.
    """
    full = prep.full
    q, dq, ddq = full.q[:, cols], full.dq[:, cols], full.ddq[:, cols]
    fit_ = theta if isinstance(theta, Fit) else None
    if fit_ is not None and fit_.terms:
        raw = q[:, model.row_states] if raw_q is None else raw_q
        tau_hat = prep.apply(model_torques(fit_, full.t, raw, q, dq, ddq))
        return {"t": prep.t, "tau": prep.tau[:, cols[model.row_states]], "tau_hat": tau_hat, "joints": names}
    theta = fit_.theta if fit_ is not None else theta
    size_mb = full.n_samples / prep.stride * len(model.coords) * model.n_params * 8 / 1e6
    if size_mb <= memory_mb:
        from . import chunks

        tau_hat = chunks.prepared_rows(model, prep, cols) @ theta
    else:
        idx = prep.index
        tau_hat = np.concatenate([a @ theta for _, a in model.regressor_blocks(q[idx], dq[idx], ddq[idx])])
    return {"t": prep.t, "tau": prep.tau[:, cols[model.row_states]], "tau_hat": tau_hat, "joints": names}


def position_spectrum(log, cols, fs: float, cutoff: float | None = None, t=None, bands: int = 300,
                      segment: int = 2**16, max_segments: int = 64) -> dict:
    """The amplitude spectrum of a log's positions per joint (the excitation spectrum).

    The raw (unfiltered) positions on a uniform grid, split into Hann-windowed segments of at most
    ``segment`` samples (half overlapping, at most ``max_segments`` spread over the log), their
    power averaged; then, for plotting on a log axis, the largest amplitude in each of ``bands``
    log-spaced frequency bands.

    Parameters
    ----------
    log : JointLog
        The log (``t (S,)``, ``q (S, joints)``).
    cols : array_like of int, shape ``(m,)``
        The log columns to analyse.
    fs : float
        The uniform grid's rate [Hz].
    cutoff : float, optional
        The low-pass cutoff [Hz] used on the log (recorded, for the plot).
    t : ndarray, optional
        The uniform grid (default: ``log.t``, taken as uniform); positions are interpolated on it.
    bands : int
        Log-spaced frequency bands of the result.
    segment : int
        Longest segment [samples]: the frequency resolution is ``fs / segment``.
    max_segments : int
        Most segments averaged (a very long log is sampled, not read whole).

    Returns
    -------
    dict
        ``{"f": ndarray (F,) [Hz], "amplitude": ndarray (F, m) [rad or m], "cutoff": float or None,
        "fs": float, "of": "q"}``: ``F <= bands`` band frequencies (mean of each band's bins) and
        the largest single-sided amplitude in the band (a sinusoid of amplitude ``A`` reads ``A``).
    """
    cols = np.asarray(cols, dtype=int)
    t = log.t if t is None else np.asarray(t, dtype=float)
    seg = int(min(len(t), segment))
    w = np.hanning(seg)
    starts = np.unique(np.linspace(0, len(t) - seg, min(max_segments, (len(t) - seg) // max(seg // 2, 1) + 1))
                       .astype(int))
    power = np.zeros((seg // 2 + 1, len(cols)))
    for k in starts:
        x = np.column_stack([np.interp(t[k:k + seg], log.t, log.q[:, c]) for c in cols])
        power += np.abs(np.fft.rfft((x - x.mean(axis=0)) * w[:, None], axis=0)) ** 2
    amp = (2 * np.sqrt(power / len(starts)) / w.sum())[1:]
    f = np.fft.rfftfreq(seg, 1.0 / fs)[1:]
    band = np.floor(np.log(f / f[0]) / np.log(max(f[-1] / f[0], 1.0 + 1e-12)) * bands).clip(0, bands - 1)
    first = np.flatnonzero(np.r_[True, np.diff(band) > 0])
    return {"f": np.add.reduceat(f, first) / np.diff(np.r_[first, len(f)]),
            "amplitude": np.maximum.reduceat(amp, first, axis=0), "cutoff": cutoff, "fs": float(fs), "of": "q"}
