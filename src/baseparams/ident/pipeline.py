"""Identification: base-parameter and drive values from measured joint torques.

The pipeline (:func:`identify`):

1. the base-parameter analysis of the robot (:func:`baseparams.analyze`, certified);
2. the drive model (rotor inertia, friction) of the measured joints and which of its
   parameters regroup with base parameters (:class:`IdentModel`, decided on sampled states);
3. the log (:class:`~baseparams.jointlog.JointLog`) preprocessed: resampled, zero-phase
   low-pass filtered, velocities and accelerations derived, the same filter applied to the
   torques and to every regressor column (parallel filtering), decimated
   (:mod:`baseparams.ident.preprocess`);
4. the model regressor accumulated row by row on a streaming QR
   (:class:`~baseparams.ident.estimate.RowAccumulator`): memory independent of the log length;
5. OLS, WLS (per-joint weights) or the physically consistent estimate (every body's
   pseudo-inertia ``N_i`` positive semidefinite, rotor inertia and friction non-negative, a
   log-det pull towards the model file's inertias; :mod:`baseparams.ident.physical`);
6. validation on held-out data: per-joint RMS of the predicted torques.

Parameters keep their conventions: base parameters are named and valued in the analysis's
convention (``khalil`` by default); full parameter vectors say theirs.

This module holds the order of the steps; each step's work is in its room (:mod:`baseparams.ident.rows`,
:mod:`.fitting`, :mod:`.notes`, :mod:`.validation`, ...). :func:`assemble` makes the result of
every path (this one, and a log streamed from its file: :mod:`.stream`), from the options it was
given (:class:`~baseparams.ident.options.IdentOptions`) and an :class:`Account` of what was done
to the data.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import BaseparamsError
from ..model.robot import Robot
from ..numerics import blas_threads
from .fitting import Fit, fit, physical_left_out, pulled_covariance, residual_rms
from .model import IdentModel, model_for
from .notes import (
    check_log_units,
    drive_notes,
    floating_notes,
    model_notes,
    rotor_not_tried,
    rotor_note,
    term_note,
)
from .options import IdentOptions, options_of
from .plausibility import check_rate
from .preprocess import excitation_bandwidth
from .result import Identification
from .rows import accumulate_prepared, log_columns
from .validation import position_spectrum, predict_log, report_series, split_log, validation_scores


def identify(robot: Robot, log, options: IdentOptions | None = None, /, *, validation=None, progress=None,
             **keywords) -> Identification:
    """Identify base-parameter and drive values from a joint log.

    Parameters
    ----------
    robot : Robot
        The model (fixed base, or loops closed by the actuated joints).
    log : JointLog or list of JointLog
        The log (:func:`baseparams.io.logs.read_log`): positions and torques of the measured
        joints (every joint of a tree; the actuated joints of a robot with loops). Several
        recordings of the robot: their rows fitted as one system, each recording one block of the
        default estimate's and the model terms' cross-validation (another motion: :func:`_identify_many`).
    options : IdentOptions, optional
        How (:class:`~baseparams.ident.options.IdentOptions`: the estimator, the drive model, the
        filter, the hold-out, the model terms, ...); default its defaults.
    validation : JointLog, optional
        Another log to validate on (exclusive with ``holdout``). Validation predicts every
        held-out sample (:meth:`Identification.predict`) and compares with the raw measured
        torques (:func:`~baseparams.ident.validation.validation_scores`).
    progress : callable, optional
        Called with one line of text at each step (analysis, preprocessing, accumulation, fit,
        validation, report series).
    **keywords
        Options as keywords, instead of or over ``options`` (``method="ols"``, ``holdout=2.0``:
        the fields of :class:`~baseparams.ident.options.IdentOptions`).

    Returns
    -------
    Identification
        Values, standard deviations, residuals, validation, counts, notes and the options (the
        cutoff and decimation as used).

    Raises
    ------
    BaseparamsError
        Bad options, a log that misses a measured joint, ``holdout`` with ``validation``, bad
        data (:class:`~baseparams.errors.DataError`) or data that do not excite the model.
    """
    opts = options_of(options, keywords)
    if opts.holdout is not None and validation is not None:
        raise BaseparamsError("give either holdout seconds or a validation log, not both")
    logs = list(log) if isinstance(log, (list, tuple)) else [log]
    if not logs:
        raise BaseparamsError("identify: no log given (one JointLog, or a list of them)")
    logs = [x.checked() for x in logs]  # finite, increasing
    validation = None if validation is None else validation.checked()
    from .fromcurrents import identify_currents, parse_effort

    efforts = {parse_effort(opts.effort, x) for x in logs}
    if "current" in efforts:  # motor currents with unknown gains: their own estimator
        if len(logs) > 1:
            raise BaseparamsError("identify: several recordings of motor currents are not identified together yet; "
                                  "identify each recording, or convert the currents to joint torques")
        return identify_currents(robot, logs[0], opts, validation, progress)
    if opts.gain_anchor is not None:
        raise BaseparamsError("identify: gain_anchor= applies to motor currents; this log is identified from its "
                              "joint torques (effort=current to use its currents)")
    with blas_threads():
        if len(logs) > 1:
            return _identify_many(robot, logs, opts, validation, progress or (lambda msg: None))
        return _identify(robot, logs[0], opts, validation, progress or (lambda msg: None))


@dataclass(frozen=True)
class Account:
    """What a path did to the data, for its result: the counts and one line per step.

    Parameters
    ----------
    read : int
        Training samples read.
    removed : dict of str to int
        Samples removed, by reason.
    cutoff : float
        The low-pass cutoff used [Hz].
    factor : int
        The decimation used.
    data : tuple of str
        How the data were prepared (resampling, filter, decimation, slow samples).
    rows : str
        How the rows were accumulated (parallel filtering, chunks).
    terms : tuple of str
        The model terms tried, kept or not.
    covariance : str
        How the standard deviations were computed.
    units : tuple of str
        The unit checks' notes.
    run : {"log", "recordings", "stream"}
        The kind of run: one log read whole (it tries ``rotor="auto"``'s rotor inertia), several
        recordings, or a log streamed from its file (they do not: :func:`~.notes.rotor_not_tried`).
    """

    read: int
    removed: dict
    cutoff: float
    factor: int
    data: tuple = ()
    rows: str = ""
    terms: tuple = ()
    covariance: str = ""
    units: tuple = ()
    run: str = "log"

    def __repr__(self) -> str:
        return f"<Account {self.read} samples read, cutoff {self.cutoff:.4g} Hz, 1 in {self.factor} kept>"


def assemble(f: Fit, acc, opts: IdentOptions, account: Account, train: dict, validation: dict | None,
             series: dict | None, motion: dict | None = None) -> Identification:
    """The result of any path (in memory, streamed from a file): one assembly, one set of notes and options.

    Parameters
    ----------
    f : Fit
        The fit, with its covariance.
    acc : RowAccumulator
        Its rows.
    opts : IdentOptions
        The options it was made with (the result keeps them with the cutoff and decimation used).
    account : Account
        What was done to the data.
    train, validation : dict
        The training and held-out scores (:func:`~baseparams.ident.validation.validation_scores`;
        ``validation`` None without held-out data).
    series : dict, optional
        The report's series.
    motion : dict, optional
        The training motion's condition number.

    Returns
    -------
    Identification
        The result.
    """
    model = f.model
    left_out = physical_left_out(model) if opts.method == "auto" else None
    notes = (*account.data, account.rows, *model_notes(model), *floating_notes(model.robot), *account.terms,
             *drive_notes(f, acc), *(f.physical.notes if f.physical is not None else ()),
             *((f.selection.note(),) if f.selection is not None else ()),
             *((left_out,) if left_out else ()),
             account.covariance, *account.units,
             *((rotor_not_tried(account.run),) if isinstance(opts.rotor, str)
               and not any(c.name == "rotor" for c in f.term_choices) else ()))
    samples = {"read": int(account.read), "used": int(acc.samples), "removed": dict(account.removed)}
    rotor = opts.rotor if opts.rotor_columns or not isinstance(opts.rotor, str) else any(
        k in ("Ia", "Iam") for k in model.drives.param_kinds)  # rotor="auto": as kept
    options = replace(opts, cutoff=float(account.cutoff), decimate=int(account.factor), rotor=bool(rotor))
    return Identification(f, samples, train, validation, tuple(notes), series, options, motion)


def _identify(robot: Robot, log, opts: IdentOptions, validation, say) -> Identification:
    """:func:`identify`'s steps (arguments as there, ``say`` the progress)."""
    from .estimate import condition_number, motion_factor, motion_stride
    from .model import check_size, fit_cost

    train, held = (split_log(log, opts.holdout) if opts.holdout is not None else (log, validation))
    say(f"analysing {robot.name} (base parameters, drive model)")
    model = model_for(robot, opts)
    cols = log_columns(model, log)
    unit_notes = check_log_units(model, train, cols, opts.allow_units)
    say(f"preprocessing {train.n_samples} training samples (resampling, low-pass, derivatives)")
    prep = _prepare_training(train, opts, cols)
    m = len(model.coords)
    check_size(robot, f"fitting {model.n_params} parameters on {prep.n_samples} samples x {m} rows",
               fit_cost(model.n_params, m, prep.n_samples * m))
    unit_notes += check_rate(train.source, prep.band, float(train.t[-1] - train.t[0]), prep.design.fs,
                             prep.design.cutoff, opts.cutoff is not None, opts.allow_units)
    say(f"accumulating the regressor of {prep.n_samples} samples ({model.n_params} parameters)")
    parts: list = []
    kept: list = []
    acc, acc_note = accumulate_prepared(model, prep, cols, opts.memory_mb, train, opts.min_speed, parts_out=parts,
                                        keep=kept)
    motion_span = block_periods(prep, train, cols[model.row_states])
    rule = "structure" if motion_span[0] < MIN_BLOCK_PERIODS else "blocks"
    say(f"fitting ({opts.method})")
    f = fit(model, acc, opts.method, opts.prior_weight, blocks=parts, rule=rule)
    done = _with_terms(f, acc, kept, prep, train, cols, opts, say, motion_span)
    (f, acc, kept, term_notes, raw_q), rotor = _rotor_choice(f, (acc, parts, kept), done, (robot, prep, train, cols),
                                                             opts, say, motion_span)
    if rotor is not None:  # the core's own term, tried after the model terms
        f = replace(f, term_choices=(*f.term_choices, rotor))
        term_notes = [*term_notes, rotor_note(rotor)]
    acc.release()  # the fitting is done: its cached factors (a large model's: hundreds of MB) before the covariance
    f, cov_note = _uncertainty(f, acc, kept, prep, train, cols, opts, say)
    f = pulled_covariance(f)
    train_rms, val, series = _scores(f, acc, log, held, prep, cols, raw_q, opts, say)
    series["train"]["spectrum"] = position_spectrum(train, cols[model.row_states], prep.design.fs, prep.design.cutoff,
                                                    prep.full.t)
    k = motion_stride(model, prep.full.n_samples)  # 1 but for a large model's long log
    f_q, f_dq, f_ddq = (x[::k, cols] for x in (prep.full.q, prep.full.dq, prep.full.ddq))
    motion = {"condition_number": condition_number(motion_factor(model, f_q, f_dq, f_ddq)),
              "samples": int(len(f_q))}
    account = Account(train.n_samples, dict(prep.removed), float(prep.design.cutoff), int(prep.factor),
                      tuple(prep.notes), acc_note, tuple(term_notes), cov_note, tuple(unit_notes))
    return assemble(f, acc, opts, account, train_rms, val, series, motion)


def _scores(f: Fit, acc, log, held, prep, cols, raw_q, opts: IdentOptions, say):
    """Training and held-out scores (every sample against the raw measured torques) and the report's series."""
    from .preprocess import prepare, resample

    say("predicted torques and excitation spectrum for the report")
    model, holdout, cutoff = f.model, opts.holdout, float(prep.design.cutoff)
    names = model.joints
    res = residual_rms(acc, f.theta)
    # one measure for training and validation: predictions at every sample against the raw measured torques
    pred_log = predict_log(f, log, cutoff)
    tmask = log.t < log.t[-1] - holdout if holdout is not None else None
    train_rms = validation_scores(log, pred_log, names, tmask)
    train_rms["measure"] = "RMS of predicted minus raw measured torques at every training sample"
    train_rms.update(fit_rms=dict(zip(names, res.tolist())), fit_rms_total=float(np.sqrt(np.mean(res**2))))
    series = {"train": report_series(model, prep, cols, f, names, opts.memory_mb, raw_q), "validation": None}
    if held is None:
        return train_rms, None, series
    say(f"validating on {held.n_samples} held-out samples (every one, against the raw measured torques)")
    whole, mask = (log, log.t >= log.t[-1] - holdout) if holdout is not None else (held, None)
    pred = pred_log if holdout is not None else predict_log(f, whole, cutoff)
    val = validation_scores(whole, pred, names, mask, opts.score_cutoff)
    vprep = prepare(held, cutoff=prep.design.cutoff, decimate=prep.factor)
    vcols = log_columns(model, held)
    series["validation"] = report_series(model, vprep, vcols, f, names, opts.memory_mb,
                                         resample(held).q[:, vcols[model.row_states]] if f.terms else None)
    return train_rms, val, series


def _inner(f: Fit, model: IdentModel, acc, method: str):
    """The linear estimator the model terms are fitted with, for each method.

    ``auto``: its own weighting and sign bounds, without its priors (the refit with the terms
    chooses its prior again): with the drive terms' weak prior towards zero, a torque-sensor scale
    grew to shrink a joint's friction (a simulated Puma with a 2 ms Dahl distance, a tilt and a
    scale: wrist scales 0.6-2.0 instead of 1.0 +- 0.05, the next recording predicted 0.116 N m
    instead of 0.072; the Panda's outside measure 0.0627 -> 0.0621); ``ols``, ``wls``: plain;
    ``physical``: WLS with the drive terms' weak prior and the sign bounds (the physical fit itself
    runs once the terms are fixed).
    """
    from .select import drive_precision, nonnegative_terms
    from .terms.fit import Inner

    theta0 = model.theta(model.robot.parameters("paper"))
    w = np.asarray(f.estimate.weights, dtype=float)
    if method == "auto" and f.physical is None:
        return Inner(w, theta0, None, nonnegative_terms(model))
    if f.physical is not None:
        est = f.estimate
        n_obs = max(est.samples * len(w), 1)
        s2 = float(np.sum((np.asarray(est.rms) * w) ** 2)) / n_obs * max(est.samples, 1) / max(n_obs / len(w), 1)
        s2 *= acc.oversampling
        return Inner(w, theta0, s2 * drive_precision(model, acc, w), nonnegative_terms(model))
    return Inner(w, theta0)


#: model terms are tried when each cross-validation block spans at least this many periods of the motion's
#: bandwidth (shorter blocks each see a different piece of one motion: a term then fits the motion, not an effect;
#: measured on simulated 3 s logs, where spurious delays and scales won up to 24 % of cross-validated RMS and lost
#: 8-15 % on the next recording)
MIN_BLOCK_PERIODS = 1.0


def block_periods(prep, train, state_cols) -> tuple[float, float, float, np.ndarray]:
    """How many periods of the motion's bandwidth each cross-validation block spans.

    Parameters
    ----------
    prep : Prepared
        The training log prepared (its full-rate grid).
    train : JointLog
        The training log as read.
    state_cols : ndarray of int
        The log columns of the measured rows' states.

    Returns
    -------
    periods : float
        ``span / FOLDS * bandwidth``.
    span : float
        The training span [s].
    band : float
        The motion's bandwidth [Hz] (:func:`~baseparams.ident.preprocess.excitation_bandwidth`).
    raw_q : ndarray, shape ``(S, m)``
        The unfiltered positions on the grid ``prep`` filtered.
    """
    from .preprocess import resample
    from .select import FOLDS

    raw_q = resample(train).q[:, state_cols]
    span = float(prep.full.t[-1] - prep.full.t[0])
    band = excitation_bandwidth(raw_q, prep.design.fs)
    return span / FOLDS * band, span, band, raw_q


def _with_terms(f: Fit, acc, kept: list, prep, train, cols, opts: IdentOptions, say, motion_span):
    """Model terms selected on the training rows and the core refitted with them (:mod:`.terms`).

    ``motion_span`` is :func:`block_periods`' result. Returns the fit, the accumulated rows and kept
    rows the covariance uses, the notes, and the unfiltered positions on the training grid (None
    without terms).
    """
    from .select import FOLDS
    from .terms.base import TermContext
    from .terms.fit import parse_terms

    candidates, forced = parse_terms(opts.terms)
    if not candidates:
        return f, acc, kept, [], None
    model = f.model
    if model.robot.floating:
        return f, acc, kept, ["model terms: not tried for a floating base (not implemented)"], None
    total = sum(len(a) for a, _ in kept)
    if not kept or total != len(prep.index):
        return f, acc, kept, ["model terms: not considered (the fitted rows do not fit in memory_mb; the linear core "
                              "alone)"], None
    a = np.concatenate([x for x, _ in kept])
    periods, span, band, raw_q = motion_span  # raw_q: unfiltered positions on the grid prepare() filters
    if raw_q.shape[0] != prep.full.n_samples:
        return f, acc, kept, ["model terms: not considered (the training grid is not the filter's)"], None

    if periods < MIN_BLOCK_PERIODS:
        why = (f"{span:.3g} s of training data: each of the {FOLDS} cross-validation blocks spans {periods:.2g} "
               f"periods of the motion's {band:.3g} Hz bandwidth (at least {MIN_BLOCK_PERIODS:g} needed), so "
               f"cross-validation cannot tell a physical effect from a fit to this one motion")
        if not forced:
            return f, acc, kept, [f"model terms: not tried ({why}; --terms NAME forces one)"], None
        candidates = forced
        say(f"model terms: only the forced ones ({why})")
    folds = [np.asarray(i) for i in np.array_split(np.arange(len(a)), FOLDS)]
    ctx = TermContext(model, a, prep, raw_q, cols, folds)
    say(f"model terms: {', '.join(candidates)} by {FOLDS}-fold blocked cross-validation on the training data")
    f, acc, kept, notes = _select_and_refit(f, acc, kept, ctx, candidates, forced, opts, say)
    return f, acc, kept, notes, (raw_q if f.terms else None)


def _select_and_refit(f: Fit, acc, kept: list, ctx, candidates, forced, opts: IdentOptions, say):
    """The model terms selected on a context's folds (:func:`~.terms.fit.select_terms`), the core refitted with them.

    One log (its blocks) or several recordings (each one fold, :meth:`~.terms.base.TermContext.stacked`): the
    kept terms fitted on every row, the core refitted on the rows they transform with the first fit's estimator
    and rule, its cross-validation blocks the context's folds. Returns the fit, the accumulated rows, the rows
    kept for the covariance (one piece per recording) and the note.
    """
    from dataclasses import replace

    from . import chunks
    from .estimate import RowAccumulator
    from .terms.fit import core_rows, select_terms

    method, model = opts.method, f.model
    tf = select_terms(ctx, _inner(f, model, acc, method), candidates, forced, progress=say)
    notes = [term_note(tf, ctx.joints, ctx.fold_unit)]
    if not tf.terms:
        return replace(f, term_choices=tf.choices), acc, kept, notes
    x, y = core_rows(ctx, tf.state)
    parts = [RowAccumulator(x.shape[1], x.shape[2]).add(x[i], y[i]) for i in ctx.folds]
    for b in parts:
        b.oversampling = float(acc.oversampling)
    acc2 = chunks.combine(parts)
    say(f"refitting the core ({method}) with the model terms")
    chosen = None if f.selection is None else f.selection.estimator
    rule = "blocks" if f.selection is None else f.selection.rule
    f2 = fit(model, acc2, method, opts.prior_weight, blocks=parts, estimator=chosen, rule=rule)
    if f2.selection is not None and f.selection is not None:  # the choice and its figures are the first fit's
        f2 = replace(f2, selection=replace(f2.selection, physical_cv=f.selection.physical_cv))
    rows = [(x, y)] if len(ctx.recordings) == 1 else [(x[i], y[i]) for i in ctx.recording_rows]
    return replace(f2, terms=tuple(tf.terms), term_choices=tf.choices), acc2, rows, notes


#: ``rotor="auto"`` tries the rotor inertia columns when each cross-validation block spans at least this many
#: periods of the motion's bandwidth: a core term changes every estimate's directions (each joint's inertia about its
#: axis, which the file's prior anchors), and blocks of 1.4 periods misled it on the TX40's real log (kept with +5.4 %
#: cross-validated in 5 of 5 blocks; the default estimate then predicted the motion's last 30 % 14 % worse, though
#: least squares and the physical fit predicted it 5-9 % better; its wrist's coupling, motor 6 turning joints 5 and 6,
#: not given there: one rotor per joint does not model it, joint 5's held-out error rose from 7.5 to 8.9 N m)
ROTOR_BLOCK_PERIODS = 2.0


def _rotor_why_not(model: IdentModel, kept: list, prep, motion_span) -> str | None:
    """Why ``rotor="auto"`` does not try the rotor inertia columns (None: it does)."""
    from .select import FOLDS

    periods, span, band, _ = motion_span
    if model.robot.floating:
        return "not tried for a floating base (not implemented; --rotor forces it)"
    if not kept or sum(len(a) for a, _ in kept) != len(prep.index):
        return "not tried (the fitted rows do not fit in memory_mb; --rotor forces it)"
    if periods < ROTOR_BLOCK_PERIODS:
        return (f"not tried ({span:.3g} s of training data: each of the {FOLDS} cross-validation blocks spans "
                f"{periods:.2g} periods of the motion's {band:.3g} Hz bandwidth, at least {ROTOR_BLOCK_PERIODS:g} "
                f"needed for a term of the core; --rotor forces it)")
    return None


def _rotor_choice(f: Fit, rows: tuple, done: tuple, where: tuple, opts: IdentOptions, say, motion_span):
    """``rotor="auto"``: each joint's rotor inertia tried last, with the model terms kept, by their rule.

    ``f`` is the core's fit without rotor inertia, ``rows`` its ``(acc, parts, kept)``, ``done`` what
    :func:`_with_terms` made of it (the fit with the terms kept, its rows, notes, raw positions) and
    ``where`` ``(robot, prep, train, cols)``. The core with the rotor inertia columns
    (:func:`~baseparams.ident.model.model_for` with ``rotor=True``) and the core without them, each with
    the kept terms, are cross-validated on the same contiguous blocks of the training rows
    (:func:`~baseparams.ident.terms.fit.select_columns`; tried after the terms, as
    :func:`~baseparams.ident.terms.fit.select_terms` adds each term given those before it: on the linear
    core alone, rotor columns stood in for a delay). Kept, the core is the one with them, fitted and its
    terms selected again. Returns ``done`` or its like with rotor inertia, and the
    :class:`~baseparams.ident.terms.fit.Choice` (None when ``rotor`` is not ``"auto"``).
    """
    from ..errors import BaseparamsError
    from .select import FOLDS
    from .terms.base import TermContext
    from .terms.fit import Choice, prepare_terms, select_columns

    if not isinstance(opts.rotor, str):
        return done, None
    robot, prep, train, cols = where
    acc, parts, kept = rows
    model = f.model
    why = _rotor_why_not(model, kept, prep, motion_span)
    if why is None:
        model_r = model_for(robot, replace(opts, rotor=True))
        if not set(model.names) <= set(model_r.names) or len(model_r.names) == len(model.names):
            why = "not tried (every rotor inertia regroups with the base parameters: no column of its own)"
    if why is not None:
        return done, Choice("rotor", False, why)
    say("rotor inertia: cross-validating the core with and without it on the training data")
    parts_r: list = []
    kept_r: list = []
    acc_r, _ = accumulate_prepared(model_r, prep, cols, opts.memory_mb, train, opts.min_speed, parts_out=parts_r,
                                   keep=kept_r)
    a0, a_r = (np.concatenate([x for x, _ in k]) for k in (kept, kept_r))
    folds = [np.asarray(i) for i in np.array_split(np.arange(len(a0)), FOLDS)]
    ctx0, ctx_r = (TermContext(m, a, prep, motion_span[3], cols, folds) for m, a in ((model, a0), (model_r, a_r)))
    names = [t.name for t in done[0].terms]
    try:
        for ctx in (ctx0, ctx_r):
            prepare_terms(ctx, names)
        choice = select_columns("rotor", ctx0, _inner(f, model, acc, opts.method), ctx_r,
                                _inner(f, model_r, acc_r, opts.method), names)
    except (BaseparamsError, np.linalg.LinAlgError) as exc:
        return done, Choice("rotor", False, f"not kept: its cross-validation failed ({exc})")
    if not choice.kept:
        return done, choice
    rule = "blocks" if f.selection is None else f.selection.rule
    f_r = fit(model_r, acc_r, opts.method, opts.prior_weight, blocks=parts_r, rule=rule)
    return _with_terms(f_r, acc_r, kept_r, prep, train, cols, opts, say, motion_span), choice


def _prepare_training(train, opts: IdentOptions, cols=None):
    """:func:`~baseparams.ident.preprocess.prepare` of the training part; a too short one names ``--holdout``.

    The bandwidth of its ``cols`` (the measured coordinates) chooses the cutoff and checks the rate.
    """
    from ..errors import DataError
    from .preprocess import prepare

    holdout = opts.holdout
    try:
        return prepare(train, cutoff=opts.cutoff, decimate=opts.decimate, min_speed=opts.min_speed, columns=cols)
    except DataError as exc:
        if holdout is None:
            raise
        span = float(train.t[-1] - train.t[0]) if train.n_samples else 0.0
        raise DataError(f"{exc}; --holdout {holdout:g} s leaves {span:.3g} s to train on "
                        "(a shorter --holdout)") from None


def _uncertainty(f: Fit, acc, kept, prep, train, cols, opts: IdentOptions, say):
    """The fit's standard deviations from the chosen covariance (a second pass for HAC)."""
    from .uncertainty import apply_covariance, fitted_rows

    if opts.covariance == "hac":
        say("covariance (HAC: a second pass over the fitted rows)")
    rows = kept if kept else getattr(acc, "fitted_blocks", None) or (
        lambda: fitted_rows(f.model, prep, cols, opts.memory_mb, train, opts.min_speed))
    return apply_covariance(f, acc, rows, opts.covariance, prep.design.fs / prep.factor)




# ---------------------------------------------------------------- several recordings of one robot
def _identify_many(robot: Robot, logs: list, opts: IdentOptions, validation, say) -> Identification:
    """:func:`identify` of several recordings: one system of rows, each recording a cross-validation block.

    Each recording is prepared on its own (one common cutoff: the largest of their defaults, within
    every recording's limit) and its rows accumulated; the estimate is chosen by cross-validation with
    each recording one block (rule ``recordings``: a block is another motion, the strongest guard against
    fitting one motion); the model terms too, each recording filtered, differentiated, shifted and scanned on its
    own (:func:`_terms_many`).
    """
    from .chunks import combine

    if opts.holdout is not None:
        raise BaseparamsError("holdout with several recordings: validate on another recording (validation=, "
                              "--validate) or leave one out of the list")
    say(f"analysing {robot.name} (base parameters, drive model)")
    model = model_for(robot, opts)
    cols = [log_columns(model, x) for x in logs]
    units = [n for x, c in zip(logs, cols) for n in check_log_units(model, x, c, opts.allow_units)]
    preps = _prepare_many(logs, opts, say)
    accs, kept, notes = [], [], []
    for x, prep, c in zip(logs, preps, cols):
        say(f"accumulating the regressor of {prep.n_samples} samples of {x.source}")
        rows: list = []
        acc, note = accumulate_prepared(model, prep, c, opts.memory_mb, x, opts.min_speed, keep=rows)
        accs.append(acc)
        kept.append(rows if sum(len(a) for a, _ in rows) == len(prep.index) else None)
        notes.append(f"{x.source}: {note}")
    acc = combine(accs)
    say(f"fitting ({opts.method}; {len(logs)} recordings, each one cross-validation block)")
    f = fit(model, acc, opts.method, opts.prior_weight, blocks=accs, rule="recordings")
    f, acc, rows, terms, raw_q = _terms_many(f, acc, kept, logs, preps, cols, opts, say)
    f, cov_note = _uncertainty(f, acc, rows or [], preps[0], logs[0], cols[0],
                               opts if rows else replace(opts, covariance="white"), say)
    f = pulled_covariance(f)
    train_rms, val, series = _scores_many(f, acc, logs, preps, cols, validation, opts, say, raw_q)
    first = preps[0]
    series["train"]["spectrum"] = position_spectrum(logs[0], cols[0][model.row_states], first.design.fs,
                                                    first.design.cutoff, first.full.t)
    removed: dict = {}
    for p in preps:
        for k, v in p.removed.items():
            removed[k] = removed.get(k, 0) + v
    data = (f"several recordings: {len(logs)} ({', '.join(x.source for x in logs)}), their rows fitted as one "
            f"system (the report's series show the first)", *first.notes)
    account = Account(sum(x.n_samples for x in logs), removed, float(first.design.cutoff), int(first.factor),
                      data, "; ".join(notes), tuple(terms), cov_note if rows else cov_note + " (white: rows of several "
                      "recordings not kept in memory_mb)", tuple(units), run="recordings")
    return assemble(f, acc, opts, account, train_rms, val, series, _motion_many(model, preps, cols))


def _terms_many(f: Fit, acc, kept: list, logs: list, preps: list, cols: list, opts: IdentOptions, say):
    """The model terms of several recordings, each recording one cross-validation fold (:func:`_select_and_refit`).

    Each recording keeps its own context (its filter, full-rate grid, unfiltered positions and columns:
    :meth:`~.terms.base.TermContext.stacked`); a fold is a whole other motion, so the rule that stops the terms on
    blocks shorter than a period of one motion (:data:`MIN_BLOCK_PERIODS`) does not apply. ``kept``: each
    recording's fitted rows (None when they did not fit in ``memory_mb``). Returns the fit, the accumulated rows,
    the rows kept for the covariance (None: not every recording's), the notes, and the first recording's
    unfiltered positions (None without terms).
    """
    from .preprocess import resample
    from .terms.base import TermContext
    from .terms.fit import parse_terms

    rows = [r for k in kept for r in k] if all(k is not None for k in kept) else None
    candidates, forced = parse_terms(opts.terms)
    if not candidates:
        return f, acc, rows, [], None
    if f.model.robot.floating:
        return f, acc, rows, ["model terms: not tried for a floating base (not implemented)"], None
    if rows is None:
        return f, acc, rows, ["model terms: not considered (the fitted rows of every recording do not fit in "
                              "memory_mb; the linear core alone)"], None
    contexts = []
    for x, prep, c, k in zip(logs, preps, cols, kept):
        raw_q = resample(x).q[:, c[f.model.row_states]]  # unfiltered positions on the grid prepare() filtered
        if raw_q.shape[0] != prep.full.n_samples:
            return f, acc, rows, [f"model terms: not considered ({x.source}'s grid is not the filter's)"], None
        contexts.append(TermContext(f.model, np.concatenate([a for a, _ in k]), prep, raw_q, c))
    ctx = TermContext.stacked(contexts)
    say(f"model terms: {', '.join(candidates)} by cross-validation with each of the {len(logs)} recordings one fold")
    f, acc, rows, notes = _select_and_refit(f, acc, rows, ctx, candidates, forced, opts, say)
    return f, acc, rows, notes, (contexts[0].raw_q if f.terms else None)


def _prepare_many(logs: list, opts: IdentOptions, say) -> list:
    """Each recording prepared with one cutoff: the given one, or the largest default within every recording's limit."""
    from .preprocess import CUTOFF_CAP, CUTOFF_DIVISOR

    say(f"preprocessing {len(logs)} recordings (resampling, low-pass, derivatives)")
    preps = [_prepare_training(x, opts) for x in logs]
    if opts.cutoff is not None:
        return preps
    cap = min(min(p.full.n_samples / float(p.full.t[-1] - p.full.t[0]) / CUTOFF_DIVISOR, CUTOFF_CAP) for p in preps)
    cutoff = min(max(p.design.cutoff for p in preps), cap)
    return [p if p.design.cutoff == cutoff else _prepare_training(x, replace(opts, cutoff=cutoff))
            for p, x in zip(preps, logs)]


def _scores_many(f: Fit, acc, logs, preps, cols, validation, opts: IdentOptions, say, raw_q=None):
    """Training scores over every recording (every sample against the raw torques), validation and series.

    ``raw_q``: the first recording's unfiltered positions on its grid (its series with the model terms).
    """
    names = f.model.joints
    cutoff = float(preps[0].design.cutoff)
    parts = [validation_scores(x, predict_log(f, x, cutoff), names) for x in logs]
    total = sum(p["samples"] for p in parts)
    res = residual_rms(acc, f.theta)
    train = {"rms": {j: float(np.sqrt(sum(p["rms"][j] ** 2 * p["samples"] for p in parts) / total)) for j in names},
             "rms_total": float(np.sqrt(sum(p["rms_total"] ** 2 * p["samples"] for p in parts) / total)),
             "samples": int(total), "t_start": parts[0]["t_start"], "t_end": parts[-1]["t_end"],
             "source": " + ".join(p["source"] for p in parts), "recordings": parts,
             "measure": "RMS of predicted minus raw measured torques at every training sample of every recording",
             "fit_rms": dict(zip(names, res.tolist())), "fit_rms_total": float(np.sqrt(np.mean(res**2)))}
    series = {"train": report_series(f.model, preps[0], cols[0], f, names, opts.memory_mb, raw_q), "validation": None}
    if validation is None:
        return train, None, series
    say(f"validating on {validation.n_samples} held-out samples (every one, against the raw measured torques)")
    val = validation_scores(validation, predict_log(f, validation, cutoff), names, None, opts.score_cutoff)
    return train, val, series


def _motion_many(model: IdentModel, preps, cols) -> dict:
    """The condition number of every recording's motion together."""
    from .estimate import condition_number, motion_factor

    def stack(attr):
        return np.concatenate([getattr(p.full, attr)[:, c] for p, c in zip(preps, cols)])

    factor = motion_factor(model, stack("q"), stack("dq"), stack("ddq"))
    return {"condition_number": condition_number(factor), "samples": int(sum(p.full.n_samples
                                                                                     for p in preps))}
