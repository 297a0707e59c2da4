"""Units and plausibility of a log, checked before any fit.

A log in the wrong units identifies silently wrong values; these checks catch the usual slips and
refuse with one line naming the file, the column and the likely unit
(:class:`~baseparams.errors.DataError`; ``allow_units=True`` / ``--allow-units`` goes on anyway):

* velocities: measured ``dq`` against finite differences of ``q`` (a ratio near 57.3: ``dq`` in
  deg/s; near 1/57.3: ``q`` in degrees; near 1/1000: time in milliseconds);
* time: a sample rate above 100 kHz, or below 5 Hz where 1000x would be a robot's rate;
* torques: against the model file's own torques on the same motion (inverse dynamics with the
  file's parameters): a factor near 1000 is mN m or N mm, near 1/1000 kN m; a sample beyond
  1e6 x the model's RMS is absurd.
"""

from __future__ import annotations

import numpy as np

from ..errors import DataError

DEG = 180.0 / np.pi
#: a ratio within this factor of a unit factor is taken as that unit
NEAR = 1.6


def _near(ratio: float, factor: float) -> bool:
    return np.isfinite(ratio) and ratio > 0 and factor / NEAR <= ratio <= factor * NEAR


def _go_on() -> str:
    return "; --allow-units (allow_units=True) to go on anyway"


def check_units(log, cols, torque_model, revolute) -> list[str]:
    """Refuse a log whose units look wrong; else the lines saying what was checked.

    Parameters
    ----------
    log : JointLog
        The log (training part).
    cols : ndarray of int, shape ``(m,)``
        Log column of each measured joint.
    torque_model : callable
        ``(q, dq, ddq) -> (S, m)``: the model file's torques of the measured rows.
    revolute : ndarray of bool, shape ``(m,)``
        Which measured joints are revolute (degrees apply to those only).

    Returns
    -------
    list of str
        Notes for the report.

    Raises
    ------
    DataError
        Naming the file, the column and the likely unit.
    """
    t = np.asarray(log.t, dtype=float)
    joints = [log.joints[c] for c in cols]
    rate = _time_base(log.source, t)
    q = np.asarray(log.q, dtype=float)[:, cols]
    derived = np.gradient(q, t, axis=0)
    _velocities(log, cols, joints, q, derived, revolute)
    return _torques(log, cols, joints, q, derived, rate, torque_model)


def _time_base(src: str, t: np.ndarray) -> float:
    """The median sample rate, refused when not a robot's in seconds."""
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    rate = 1.0 / dt if dt > 0 else np.inf
    if rate > 1e5:
        raise DataError(f"{src}: column t: sample rate {rate:.3g} Hz is not a robot's; time likely in "
                        f"microseconds or another unit than seconds" + _go_on())
    if rate < 5 and 10 <= rate * 1000 <= 1e5:
        raise DataError(f"{src}: column t: sample rate {rate:.3g} Hz (steps of {dt:.3g}); time likely in "
                        f"milliseconds (x 1e-3 to seconds)" + _go_on())
    return rate


def _velocities(log, cols, joints, q, derived, revolute) -> None:
    """Measured velocities against d/dt of q (or, without them, the positions' span)."""
    src = log.source
    if log.dq is not None:
        dq = np.asarray(log.dq, dtype=float)[:, cols]
        for k, j in enumerate(joints):
            den = float(derived[:, k] @ derived[:, k])
            if den <= 0 or float(dq[:, k] @ dq[:, k]) <= 0:
                continue
            ratio = float(dq[:, k] @ derived[:, k]) / den
            unit = None
            if revolute[k] and _near(ratio, DEG):
                unit = f"column dq_{j}: measured velocities {ratio:.3g} x d/dt of q: likely deg/s (not rad/s)"
            elif revolute[k] and _near(ratio, 1 / DEG):
                unit = f"column q_{j}: d/dt of q {1 / ratio:.3g} x the measured velocities: q likely in degrees"
            elif _near(ratio, 1000.0):
                unit = (f"column t (or dq_{j}): measured velocities {ratio:.4g} x d/dt of q: time likely in "
                        f"milliseconds")
            elif _near(ratio, 1e-3):
                unit = f"column q_{j}: d/dt of q {1 / ratio:.4g} x the measured velocities: q likely in mm or mrad"
            if unit:
                raise DataError(f"{src}: {unit}" + _go_on())
    elif np.any(revolute):
        span = np.ptp(q[:, revolute], axis=0)
        if span.size and span.max() > 4 * np.pi * 3:
            k = int(np.flatnonzero(revolute)[np.argmax(span)])
            raise DataError(f"{src}: column q_{joints[k]}: spans {span.max():.4g} (over six turns): positions likely "
                            f"in degrees" + _go_on())


def _torques(log, cols, joints, q, derived, rate, torque_model) -> list[str]:
    """Measured torques against the model file's on the same motion; absurd samples."""
    src, t = log.source, np.asarray(log.t, dtype=float)
    tau = np.asarray(log.tau, dtype=float)[:, cols]
    step = max(1, len(t) // 400)
    sel = np.arange(0, len(t), step)
    dq_used = (np.asarray(log.dq, dtype=float)[:, cols] if log.dq is not None else derived)
    ddq = np.gradient(dq_used, t, axis=0)
    width = max(1, int(round(0.05 * rate)))  # a 50 ms moving average tames differentiated noise
    kernel = np.ones(width) / width
    ddq = np.apply_along_axis(lambda x: np.convolve(x, kernel, mode="same"), 0, ddq)
    model = np.asarray(torque_model(q[sel], dq_used[sel], ddq[sel]), dtype=float)
    model_rms = float(np.sqrt(np.mean(model**2)))
    if not model_rms > 0:
        return ["units: no model torques to compare with (the file's parameters give zero)"]
    peak = np.abs(tau).max(axis=0)
    if np.any(peak > 1e6 * model_rms):
        k = int(np.argmax(peak))
        i = int(np.argmax(np.abs(tau[:, k])))
        raise DataError(f"{src}: column tau_{joints[k]}, sample {i}: {tau[i, k]:.4g} is beyond any plausible "
                        f"torque of this model (its RMS on this motion: {model_rms:.3g})" + _go_on())
    ratio = float(np.sqrt(np.mean(tau[sel] ** 2))) / model_rms
    per = np.sqrt(np.mean(tau[sel] ** 2, axis=0)) / np.maximum(np.sqrt(np.mean(model**2, axis=0)), 1e-300)
    worst = joints[int(np.argmax(per))] if ratio > 1 else joints[int(np.argmin(per))]
    if ratio > 1000 / NEAR / 1.5:
        raise DataError(f"{src}: column tau_{worst}: measured torques {ratio:.4g} x the model file's on the same "
                        f"motion: likely mN m or N mm (not N m)" + _go_on())
    if ratio < 1.5 * NEAR / 1000:
        raise DataError(f"{src}: column tau_{worst}: measured torques {ratio:.3g} x the model file's on the same "
                        f"motion: likely kN m (not N m)" + _go_on())
    return [f"units: checked (measured torques {ratio:.3g} x the model file's on the same motion; "
            f"sample rate {rate:.4g} Hz" + ("; measured velocities match d/dt of q)" if log.dq is not None else ")")]
