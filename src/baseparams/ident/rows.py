"""Regressor rows from states or from a log, accumulated on a streaming QR within a memory bound.

:func:`log_columns` says which log column feeds each state column; :func:`accumulate` turns states
and torques into row factors, :func:`accumulate_prepared` a prepared (filtered, decimated) log, all
at once or chunk by chunk with overlapping filter edges (:mod:`baseparams.ident.chunks`).
"""

from __future__ import annotations

import numpy as np

from ..errors import BaseparamsError
from .model import IdentModel


def accumulate(model: IdentModel, q, dq, ddq, tau, chunk: int = 20000, transform=None):
    """The model regressor and torques accumulated row by row (streaming QR).

    Parameters
    ----------
    model : IdentModel
        The model.
    q, dq, ddq : ndarray, shape ``(S, state_columns)``
        States.
    tau : ndarray, shape ``(S, m)``
        Measured generalized forces of the measured rows.
    chunk : int
        Samples per block (memory ``chunk * m * p`` floats).
    transform : callable, optional
        Applied to the whole regressor ``(S, m, p)`` and to ``tau`` before accumulation (the
        parallel filter and decimation); the blocks are then the transformed arrays' (the whole
        regressor is formed once).

    Returns
    -------
    RowAccumulator
        The accumulated factors.
    """
    from .estimate import RowAccumulator

    acc = RowAccumulator(len(model.coords), model.n_params)
    tau = np.asarray(tau, dtype=float)
    if transform is not None:
        return acc.add(transform(model.regressor(q, dq, ddq)), transform(tau))
    for k in range(0, len(tau), chunk):
        sl = slice(k, k + chunk)
        acc.add(model.regressor(q[sl], dq[sl], ddq[sl]), tau[sl])
    return acc


def log_columns(model: IdentModel, log) -> np.ndarray:
    """The log column of each state column of the model.

    Parameters
    ----------
    model : IdentModel
        The model (its states: a tree's coordinates, or a loop robot's actuated ones).
    log : JointLog
        The log.

    Returns
    -------
    ndarray of int, shape ``(state_columns,)``
        Index into ``log.joints`` per state column.

    Raises
    ------
    BaseparamsError
        A state coordinate whose joint is not in the log (naming the joints).
    """
    from ..kinematics.floating import BASE_COORDINATES

    r = model.robot
    coords = r.measured_coords
    names = r.coordinate_names(coords)
    wanted = [BASE_COORDINATES[c] if r.jtype[r.dof_body[c]] == "F" else names[k] for k, c in enumerate(coords)]
    where = {j: k for k, j in enumerate(log.joints)}
    if len(where) < len(log.joints):
        twice = sorted({j for j in log.joints if log.joints.count(j) > 1})
        raise BaseparamsError(f"{log.source}: the log names {twice} more than once: one column per coordinate, "
                              f"named as the robot's (Robot.coordinate_names: {names})")
    missing = [j for j in wanted if j not in where]
    if missing and r.floating and missing[0] == BASE_COORDINATES[0]:
        raise BaseparamsError(f"{log.source}: robot {r.name!r} has a floating base and the log has no base pose "
                              "(columns base_x, base_y, base_z, base_qw, base_qx, base_qy, base_qz: "
                              "docs/guides/log-layout.md)")
    if missing:
        what = "actuated joints" if r.has_loops else "joints"
        raise BaseparamsError(f"{log.source}: the log has no column for the {what} {missing} of {r.name!r}")
    return np.array([where[j] for j in wanted], dtype=int)


def accumulate_prepared(model: IdentModel, prep, cols: np.ndarray, memory_mb: float, log=None, min_speed=None,
                        parts_out: list | None = None, keep=None):
    """Rows accumulated from a prepared log, with parallel filtering.

    All at once when the regressor fits in ``memory_mb``, else chunk by chunk with overlaps
    (:mod:`baseparams.ident.chunks`), which gives the same factors to rounding.

    Parameters
    ----------
    model : IdentModel
        The model.
    prep : Prepared
        The log prepared (:func:`baseparams.ident.preprocess.prepare`).
    cols : ndarray of int
        Log column of each state column (:func:`log_columns`).
    memory_mb : float
        Largest regressor formed at once.
    log : JointLog, optional
        The unfiltered log ``prep`` came from (needed for the chunked path).
    min_speed : float, optional
        The slow-sample threshold ``prep`` used.
    parts_out : list, optional
        When given, receives time-ordered pieces of the rows (RowAccumulator each; their
        combination is ``acc``), for the blocked cross-validation of the default estimate.
    keep : list, optional
        When given, ``(A, tau)`` of the fitted samples are appended to it, in time order, when
        they fit in ``memory_mb`` (always on the at-once path; per chunk on the chunked path): the
        covariance's second pass (:mod:`baseparams.ident.uncertainty`) then needs no second
        regressor.

    Returns
    -------
    acc : RowAccumulator
        The row factors.
    note : str
        How the parallel filtering was done.
    """
    acc, note = _accumulated(model, prep, cols, memory_mb, log, min_speed, parts_out, keep)
    for a in [acc, *(parts_out or [])]:
        a.oversampling = prep.oversampling
    return acc, note


def _accumulated(model: IdentModel, prep, cols: np.ndarray, memory_mb: float, log, min_speed, parts_out, keep):
    """:func:`accumulate_prepared`'s rows, before their oversampling is set."""
    from .estimate import RowAccumulator

    full = prep.full
    spilled = _spilled(model, prep, cols, memory_mb, parts_out)
    if spilled is not None:
        return spilled
    size_mb = full.n_samples / prep.stride * len(model.coords) * model.n_params * 8 / 1e6
    if size_mb <= memory_mb or log is None:
        from . import chunks

        a, tau = chunks.prepared_rows(model, prep, cols), prep.tau[:, cols[model.row_states]]
        if parts_out is None:
            acc = RowAccumulator(len(model.coords), model.n_params).add(a, tau)
        else:
            from .select import fold_parts

            parts_out.extend(fold_parts(a, tau))
            acc = chunks.combine(parts_out)
        if keep is not None:
            keep.append((a, tau))
        return acc, (f"parallel filtering: the regressor's {model.n_params} columns filtered like the torques "
                     f"({size_mb:.0f} MB at once)")
    from . import chunks
    from .preprocess import resample

    grid = chunks.Grid(full.n_samples, prep.trim, prep.factor, prep.design.cutoff, min_speed,
                       stride=prep.stride)
    margin = chunks.overlap(prep.design)
    size = chunks.window_size(model, memory_mb, margin, prep.stride)
    uniform = resample(log)  # the grid prepare() filtered on (it resamples with the same default)
    # the fitted (decimated) rows are kept for the covariance's second pass when they fit in memory_mb
    # (a fraction 1 / factor of the full-rate regressor); else that pass recomputes them
    fitted_mb = full.n_samples / max(prep.factor, 1) * len(model.coords) * (model.n_params + 1) * 8 / 1e6
    held = keep if keep is not None and fitted_mb <= memory_mb else None
    parts = [chunks.chunk_factors(uniform, c, grid, model, cols, held, model.row_states)[0]
             for c in chunks.plan(full.n_samples, size, margin)]
    if parts_out is not None and held:
        # the cross-validation's blocks from the fitted rows, split as the at-once path splits them
        from .select import fold_parts

        parts_out.extend(fold_parts(np.concatenate([x for x, _ in held]), np.concatenate([y for _, y in held])))
    elif parts_out is not None:
        parts_out.extend(parts)  # blocks at chunk boundaries (the fitted rows do not fit in memory_mb)
    floor = chunks.floor_note(model, memory_mb, margin, size, prep.stride, full.n_samples)
    return chunks.combine(parts), (f"parallel filtering in {len(parts)} chunks of {size} samples with "
                                   f"{margin}-sample overlaps (equal to the whole log's to rounding)"
                                   + (f"; {floor}" if floor else ""))


def _spilled(model: IdentModel, prep, cols: np.ndarray, memory_mb: float, parts_out):
    """A large model's rows written to a temporary file (:mod:`.spilled`), or None: held in memory.

    The whole's accumulator and its note; the cross-validation's folds appended to ``parts_out``.
    """
    from . import spilled
    from .select import FOLDS

    if not spilled.spills(model, prep.n_samples, memory_mb):
        return None
    acc = spilled.spill(model, prep, cols, memory_mb, FOLDS)
    if acc is None:  # no room on the disk: held in memory, as before
        return None
    if parts_out is not None:
        parts_out.extend(acc.children)
    held = spilled.factor_mb(model, prep.n_samples)
    return acc, (f"parallel filtering: the regressor's {model.n_params} columns filtered like the torques, a few of "
                 f"the {len(model.coords)} measured rows at a time; the fitted rows ({held:.0f} MB of row factors, "
                 f"more than memory_mb) held in a temporary file and read back a block at a time")
