"""The TP regressor of the states in a file (``baseparams regressor MODEL --states FILE --out Y``).

The states are read as a log's (``q_``, ``dq_``, ``ddq_<joint>`` columns, a log or an ``excite``
trajectory; rates a file lacks derived as identify derives them) and the regressor ``(S, m, 10 n)``
of the measured coordinates is computed, ``paper`` convention, and written when asked.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import BaseparamsError
from .inputs import input_files, robot_of
from .outputs import check_outputs


@dataclass(frozen=True)
class StatesRegressor:
    """The regressor of a states file (:func:`states_regressor`).

    Parameters
    ----------
    y : ndarray, shape ``(S, m, 10 n)``
        The regressor, ``paper`` convention columns.
    joints : list of str
        The coordinate of each of the ``m`` rows.
    names : list of str
        The ``10 n`` parameter names.
    t : ndarray, shape ``(S,)``
        The states' time stamps.
    seconds : float
        Time spent computing the regressor [s].
    """

    y: np.ndarray
    joints: list
    names: list
    t: np.ndarray
    seconds: float

    def __repr__(self) -> str:
        return f"<StatesRegressor {self.y.shape} (samples, joints, 10 x bodies) in {self.seconds * 1e3:.2f} ms>"


def states_regressor(model, states, *, out=None, notes=None, source=None) -> StatesRegressor:
    """The TP regressor of the states in a file, written to ``out`` when given.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot (fixed base).
    states : str or path
        The states' file (CSV/TSV, NPZ, Parquet; a log or an ``excite`` trajectory).
    out : str or path, optional
        ``.npz`` (``Y (S, m, 10 n)``, ``columns``, ``joints``, ``t``) or ``.csv``/``.tsv``/``.parquet``
        (one row per sample and joint: ``sample, joint`` and one column per parameter; row
        ``s * m + j`` is ``Y[s, j]``).
    notes : callable, optional
        Takes the notes of the reading (rates derived).
    source : str or path, optional
        The model file, when ``model`` is a Robot loaded from it (never overwritten).

    Returns
    -------
    StatesRegressor
        The regressor and its labels.

    Raises
    ------
    BaseparamsError
        A floating base, a file without the measured joints' positions (or without the rates and
        a time to derive them from), an output that cannot be written.
    """
    import time

    from ..analysis import regressor
    from ..base.regroup import parameter_names
    from ..io.logs import read_log

    inputs = input_files(model if source is None else source, states)
    check_outputs("regressor", inputs, out=out)
    robot = robot_of(model, "regressor")
    if robot.floating:
        raise BaseparamsError(f"states=: robot {robot.name!r} has a floating base, whose coordinates are not "
                              f"columns of a states file; use baseparams.regressor in Python")
    joints = robot.coordinate_names(robot.measured_coords)
    log = read_log(states, robot, allow_subset=True, require_tau=False, require_time=False)
    missing = [j for j in joints if j not in log.joints]
    if missing:
        raise BaseparamsError(f"states= {os.fspath(states)}: no q_ columns for {missing} (states need q_<joint>, and "
                              f"dq_, ddq_ or a time column t, for the {'actuated ' if robot.has_loops else ''}joints "
                              f"{joints})")
    q, dq, ddq = _rates(log, states, notes)
    cols = [log.joints.index(j) for j in joints]
    t0 = time.perf_counter()
    y = regressor(robot, q[:, cols], dq[:, cols], ddq[:, cols])
    result = StatesRegressor(y, joints, parameter_names(robot, "paper"), log.t, time.perf_counter() - t0)
    if out is not None:
        _write(result, out, inputs)
    return result


def _rates(log, states, notes) -> tuple:
    """``q, dq, ddq`` of a states log: rates the file lacks derived as identify derives them (needs time)."""
    q, dq, ddq = log.q, log.dq, log.ddq
    if dq is not None and ddq is not None:
        return q, dq, ddq
    from ..ident.preprocess import log_states

    if log.t is None or not np.all(np.isfinite(log.t)):
        raise BaseparamsError(f"states= {os.fspath(states)}: no {'dq_ and ' if dq is None else ''}ddq_ columns and no "
                              "time column t to derive them from")
    q, dq, ddq, derived = log_states(log, None)
    for note in derived[1:]:
        if notes is not None:
            notes(note)
    return q, dq, ddq


def _write(result: StatesRegressor, out, inputs) -> None:
    """The regressor as NPZ arrays, or as a table of one row per (sample, joint)."""
    from ..tables import write_columns

    y, joints = result.y, result.joints
    if Path(os.fspath(out)).suffix.lower() == ".npz":
        write_columns(out, {"Y": y, "columns": np.array(result.names), "joints": np.array(joints), "t": result.t},
                      inputs, "out=")
        return
    s, m, _ = y.shape
    table = {"sample": np.repeat(np.arange(s), m), "joint": np.tile(np.array(joints), s)}
    table.update({n: y[:, :, k].reshape(-1) for k, n in enumerate(result.names)})
    write_columns(out, table, inputs, "out=")
