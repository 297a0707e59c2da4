"""The payload's fitted rows from a log: which joints move, the filtered regressor, the slow samples.

The log is prepared as :func:`baseparams.identify` prepares it (resampled, zero-phase low-pass,
derivatives, edges trimmed, decimated: :func:`~baseparams.ident.preprocess.prepare`); the payload's
columns, the drive columns and the known robot's torques are computed at the full-rate filtered
states and filtered the same way (parallel filtering), then taken at the kept samples. On each
fitted row, the samples where that joint is slower than its ``min_speed`` are not fitted (Coulomb
friction is not a step at a reversal), and counted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...display import summary_repr
from ...errors import DataError


def log_columns(robot, log) -> np.ndarray:
    """The log column of every robot coordinate (a fixed-base tree: one per joint).

    Parameters
    ----------
    robot : Robot
        The robot.
    log : JointLog
        The log.

    Returns
    -------
    ndarray of int, shape ``(dof,)``
        Index into ``log.joints`` per coordinate.

    Raises
    ------
    DataError
        A joint the log does not have (the known robot's torques need every joint's state).
    """
    where = {j: k for k, j in enumerate(log.joints)}
    names = robot.coordinate_names()
    missing = [j for j in names if j not in where]
    if missing:
        raise DataError(f"{log.source}: no column for the joint(s) {', '.join(missing)} (the robot's own torques "
                        f"need every joint's position)")
    return np.array([where[j] for j in names], dtype=int)


def moving_joints(robot, log, cols: np.ndarray, still: float) -> np.ndarray:
    """Which coordinates move in the log: a logged range of at least ``still``.

    Parameters
    ----------
    robot : Robot
        The robot.
    log : JointLog
        The log.
    cols : ndarray of int, shape ``(dof,)``
        :func:`log_columns`.
    still : float
        The smallest range of a moving joint [rad or m].

    Returns
    -------
    ndarray of bool, shape ``(dof,)``
        True where the joint moves.
    """
    return np.ptp(np.asarray(log.q, dtype=float)[:, cols], axis=0) >= still


@dataclass(frozen=True, eq=False)
class Rows:
    """The fitted rows of a payload log.

    Parameters
    ----------
    a : ndarray, shape ``(S', r, k)``
        Filtered columns (payload, then drive terms) at the kept samples.
    y : ndarray, shape ``(S', r)``
        Filtered measured torques minus the known robot's, at the kept samples.
    fitted : ndarray of bool, shape ``(S', r)``
        The entries fitted (False: the joint is slower than its ``min_speed`` there).
    speeds : ndarray, shape ``(r,)``
        Each row's ``min_speed`` [rad/s or m/s].
    result_a : ndarray, shape ``(S', r, p)``, optional
        The saved identification's filtered model regressor (its covariance's propagation).
    rate : float
        The kept samples' rate [Hz].
    """

    a: np.ndarray
    y: np.ndarray
    fitted: np.ndarray
    speeds: np.ndarray
    result_a: np.ndarray | None
    rate: float

    __repr__ = summary_repr

    @property
    def samples(self) -> int:
        """Kept samples ``S'``."""
        return len(self.y)


def _check_memory(prep, model, memory_mb: float) -> None:
    """Refuse a log whose full-rate regressor would exceed ``memory_mb`` (one line saying how long it may be)."""
    width = model.n_params + 1 + (model.result.fit.model.n_params if model.result is not None else 0)
    per = len(model.rows) * width * 8 * 3 / 1e6  # the columns, the filter's copy and the kept rows
    n = prep.full.n_samples
    if n * per > memory_mb:
        rate = (n - 1) / float(prep.full.t[-1] - prep.full.t[0])
        raise DataError(f"{prep.source}: {n} samples need {n * per:.0f} MB for the payload's rows "
                        f"(memory_mb {memory_mb:g}): a payload log of at most {memory_mb / per / rate:.0f} s at "
                        f"{rate:.4g} Hz (cut it, or raise memory_mb)")


def fitted_rows(model, log, prep, cols: np.ndarray, options) -> tuple[Rows, list[str]]:
    """The payload's rows of a prepared log (module docstring).

    Parameters
    ----------
    model : PayloadModel
        The model.
    log : JointLog
        The log as read (unfiltered: a saved identification's model terms use its positions).
    prep : Prepared
        ``log`` prepared (:func:`~baseparams.ident.preprocess.prepare`).
    cols : ndarray of int, shape ``(dof,)``
        :func:`log_columns`.
    options : PayloadOptions
        ``min_speed``, ``slow_fraction``, ``memory_mb``.

    Returns
    -------
    rows : Rows
        The fitted rows.
    notes : list of str
        The slow samples left out per joint.
    """
    from ..chunks import filtered_rows
    from ..preprocess import resample

    _check_memory(prep, model, options.memory_mb)
    f = prep.full
    q, dq, ddq = f.q[:, cols], f.dq[:, cols], f.ddq[:, cols]
    a, rigid = model.columns(q, dq, ddq)
    known = model.known(f.t, resample(log).q[:, cols], q, dq, ddq, rigid)
    a = filtered_rows(a, prep.design, prep.index)
    y = prep.tau[:, cols[model.rows]] - filtered_rows(known, prep.design, prep.index)
    res_a = None
    if model.result is not None:
        res_a = filtered_rows(model.result_rows(q, dq, ddq), prep.design, prep.index)
    speed = np.abs(prep.dq[:, cols[model.rows]])
    peak = speed.max(axis=0)
    vmin = (np.full(len(model.rows), options.min_speed) if options.min_speed is not None
            else options.slow_fraction * peak)
    fitted = speed >= vmin
    fitted[:, peak <= 0] = False
    names = model.joints
    left = [f"{n} {int((~fitted[:, k]).sum())} (|dq| < {vmin[k]:.3g})" for k, n in enumerate(names)]
    how = "min_speed" if options.min_speed is not None else f"{options.slow_fraction:g} x each joint's peak speed"
    notes = [f"slow samples not fitted on their joint's row ({how}; Coulomb friction is not a step at a reversal): "
             + ", ".join(left) + f" of {len(y)}"]
    return Rows(a, y, fitted, vmin, res_a, prep.fs), notes
