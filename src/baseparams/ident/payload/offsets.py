"""The moving joints' torque offsets: kept by the data (blocked cross-validation on the log), or always fitted.

A torque offset per moving joint is a constant column on its row. With only the wrist moving, the
payload's mass reaches the wrist's torques through the link's origin off the joints' axes: a term
that changes little over the motion, so an offset column takes up much of its information (on the
issue's simulated wrist-only motions the mass's standard deviation doubles with the offsets,
0.18 -> 0.40 %). Whether the offsets are there is the data's to say, by the model terms' rule
(:func:`baseparams.ident.terms.fit.verdict`): the payload's weighted fit (:func:`~.fit.weighted_fit`)
with and without the offset columns, each of ``FOLDS`` contiguous blocks of the fitted rows
predicted from the others; the offsets stay when the cross-validated RMS is lower with them by more
than :data:`~baseparams.ident.terms.fit.KEEP_GAIN` in most blocks. They are kept without trying when
the blocks are shorter than a period of the motion's bandwidth (the model terms' rule,
:data:`~baseparams.ident.pipeline.MIN_BLOCK_PERIODS`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...errors import BaseparamsError


def offset_columns(model) -> np.ndarray:
    """The indices of the torque offsets' columns (``Fo_joint``, or ``dFo_joint`` with a saved identification).

    Parameters
    ----------
    model : PayloadModel
        The model.

    Returns
    -------
    ndarray of int
        Into :attr:`~.model.PayloadModel.names`.
    """
    return np.array([i for i, n in enumerate(model.names) if n.removeprefix("d").startswith("Fo_")], dtype=int)


def cross_validated(rows, st, folds: int) -> tuple[float, list[float]]:
    """The payload fit's blocked cross-validated RMS on its fitted rows, in the torques' units.

    Parameters
    ----------
    rows : Rows
        The fitted rows (:func:`~.rows.fitted_rows`).
    st : Structure
        The structural decision of their model.
    folds : int
        Contiguous blocks of the kept samples.

    Returns
    -------
    rms : float
        Over every fitted entry, each block predicted from the others' weighted fit.
    sse : list of float
        Each block's sum of squared errors.
    """
    from .fit import weighted_fit
    from .rows import Rows

    blocks = np.array_split(np.arange(rows.samples), folds)
    sse = []
    for k, held in enumerate(blocks):
        train = np.concatenate([b for i, b in enumerate(blocks) if i != k])
        part = Rows(rows.a[train], rows.y[train], rows.fitted[train], rows.speeds, None, rows.rate)
        z, _, _, _, _, t, _, _, x0 = weighted_fit(part, st, np.zeros(rows.a.shape[2]))
        e = (rows.y[held] - rows.a[held] @ (x0 + t @ z)) * rows.fitted[held]
        sse.append(float(np.sum(e**2)))
    return float(np.sqrt(sum(sse) / max(int(rows.fitted.sum()), 1))), sse


def choose_offsets(model, rows, st, opts, structure_of, periods: float) -> tuple:
    """Keep the moving joints' torque offsets or not (module docstring).

    Parameters
    ----------
    model : PayloadModel
        The model with the offsets (``offset`` among ``opts.friction``).
    rows : Rows
        Its fitted rows.
    st : Structure
        Its structural decision.
    opts : PayloadOptions
        ``offsets`` (``auto``: decide; ``fit``: keep) and what rebuilds the model without them.
    structure_of : callable
        ``structure_of(model)``: the structural decision of another model of the same rows.
    periods : float
        Periods of the motion's bandwidth each block spans.

    Returns
    -------
    tuple
        ``(model, rows, st, note)``: without the offsets' columns when the data do not ask for them;
        ``note`` None when nothing was decided.
    """
    from ..pipeline import MIN_BLOCK_PERIODS
    from ..select import FOLDS
    from ..terms.fit import KEEP_FLOOR, verdict
    from .model import payload_model
    from .rows import Rows

    cols = offset_columns(model)
    if opts.offsets != "auto" or not len(cols):
        return model, rows, st, None
    head = "torque offsets of the moving joints (offsets=auto, blocked cross-validation on the log)"
    if periods < MIN_BLOCK_PERIODS:
        return model, rows, st, (f"{head}: fitted, not tried (each of the {FOLDS} blocks spans {periods:.2g} "
                                 f"periods of the motion's bandwidth, at least {MIN_BLOCK_PERIODS:g} needed)")
    without, _ = payload_model(model.robot, model.body, model.rows,
                               replace(opts, friction=tuple(f for f in opts.friction if f != "offset")), model.result)
    keep = np.setdiff1d(np.arange(model.n_params), cols)
    if [model.names[i] for i in keep] != without.names:
        return model, rows, st, f"{head}: fitted, not tried (the model without them has other columns)"
    rows0 = Rows(rows.a[:, :, keep], rows.y, rows.fitted, rows.speeds, rows.result_a, rows.rate)
    try:
        st0 = structure_of(without)
        score, trial = cross_validated(rows, st, FOLDS)
        current, folds = cross_validated(rows0, st0, FOLDS)
    except BaseparamsError as exc:
        return model, rows, st, f"{head}: fitted, not tried ({exc})"
    floor = KEEP_FLOOR * float(np.sqrt(np.mean(rows.y[rows.fitted] ** 2)))
    ok, why = verdict(score, current, trial, folds, floor)
    if ok:
        return model, rows, st, f"{head}: KEPT ({why}); offsets=fit forces them"
    return without, rows0, st0, f"{head}: not fitted ({why}); offsets=fit forces them"
