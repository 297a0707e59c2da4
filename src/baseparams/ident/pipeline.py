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
from .fitting import Fit, fit, pulled_covariance, residual_rms
from .model import IdentModel, model_for
from .notes import check_log_units, drive_notes, floating_notes, model_notes, term_note
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
        default estimate's cross-validation (another motion: :func:`_identify_many`).
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
    notes = (*account.data, account.rows, *model_notes(model), *floating_notes(model.robot), *account.terms,
             *drive_notes(f, acc), *(f.physical.notes if f.physical is not None else ()),
             *((f.selection.note(),) if f.selection is not None else ()), account.covariance, *account.units)
    samples = {"read": int(account.read), "used": int(acc.samples), "removed": dict(account.removed)}
    options = replace(opts, cutoff=float(account.cutoff), decimate=int(account.factor))
    return Identification(f, samples, train, validation, tuple(notes), series, options, motion)


def _identify(robot: Robot, log, opts: IdentOptions, validation, say) -> Identification:
    """:func:`identify`'s steps (arguments as there, ``say`` the progress)."""
    from .estimate import excitation, motion_factor, motion_stride
    from .model import check_size, fit_cost

    train, held = (split_log(log, opts.holdout) if opts.holdout is not None else (log, validation))
    say(f"analysing {robot.name} (base parameters, drive model)")
    model = model_for(robot, opts)
    cols = log_columns(model, log)
    unit_notes = check_log_units(model, train, cols, opts.allow_units)
    say(f"preprocessing {train.n_samples} training samples (resampling, low-pass, derivatives)")
    prep = _prepare_training(train, opts)
    m = len(model.coords)
    check_size(robot, f"fitting {model.n_params} parameters on {prep.n_samples} samples x {m} rows",
               fit_cost(model.n_params, m, prep.n_samples * m))
    band = excitation_bandwidth(train.q[:, cols], prep.design.fs)  # unfiltered: what the low-pass may take off
    unit_notes += check_rate(train.source, band, float(train.t[-1] - train.t[0]), prep.design.fs,
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
    f, acc, kept, term_notes, raw_q = _with_terms(f, acc, kept, prep, train, cols, opts, say, motion_span)
    f, cov_note = _uncertainty(f, acc, kept, prep, train, cols, opts, say)
    f = pulled_covariance(f)
    train_rms, val, series = _scores(f, acc, log, held, prep, cols, raw_q, opts, say)
    series["train"]["spectrum"] = position_spectrum(train, cols[model.row_states], prep.design.fs, prep.design.cutoff,
                                                    prep.full.t)
    k = motion_stride(model, prep.full.n_samples)  # 1 but for a large model's long log
    f_q, f_dq, f_ddq = (x[::k, cols] for x in (prep.full.q, prep.full.dq, prep.full.ddq))
    motion = {"condition_number": excitation(motion_factor(model, f_q, f_dq, f_ddq), model.names)[0],
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
    from .preprocess import excitation_bandwidth, resample
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
    from dataclasses import replace

    from . import chunks
    from .select import FOLDS, fold_parts
    from .terms.base import TermContext
    from .terms.fit import core_rows, parse_terms, select_terms

    method = opts.method
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
    tf = select_terms(ctx, _inner(f, model, acc, method), candidates, forced, progress=say)
    notes = [term_note(tf, ctx.joints)]
    if not tf.terms:
        return replace(f, term_choices=tf.choices), acc, kept, notes, None
    x, y = core_rows(ctx, tf.state)
    parts = fold_parts(x, y, oversampling=acc.oversampling)
    acc2 = chunks.combine(parts)
    say(f"refitting the core ({method}) with the model terms")
    chosen = None if f.selection is None else f.selection.estimator
    rule = "blocks" if f.selection is None else f.selection.rule
    f2 = fit(model, acc2, method, opts.prior_weight, blocks=parts, estimator=chosen, rule=rule)
    if f2.selection is not None and f.selection is not None:  # the choice and its figures are the first fit's
        f2 = replace(f2, selection=replace(f2.selection, physical_cv=f.selection.physical_cv))
    return replace(f2, terms=tuple(tf.terms), term_choices=tf.choices), acc2, [(x, y)], notes, raw_q


def _prepare_training(train, opts: IdentOptions):
    """:func:`~baseparams.ident.preprocess.prepare` of the training part; a too short one names ``--holdout``."""
    from ..errors import DataError
    from .preprocess import prepare

    holdout = opts.holdout
    try:
        return prepare(train, cutoff=opts.cutoff, decimate=opts.decimate, min_speed=opts.min_speed)
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
    fitting one motion). Model terms are not tried across recordings (each would need its own states).
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
    rows = [r for k in kept for r in k] if all(k is not None for k in kept) else None
    f, cov_note = _uncertainty(f, acc, rows or [], preps[0], logs[0], cols[0],
                               opts if rows else replace(opts, covariance="white"), say)
    f = pulled_covariance(f)
    train_rms, val, series = _scores_many(f, acc, logs, preps, cols, validation, opts, say)
    first = preps[0]
    series["train"]["spectrum"] = position_spectrum(logs[0], cols[0][model.row_states], first.design.fs,
                                                    first.design.cutoff, first.full.t)
    removed: dict = {}
    for p in preps:
        for k, v in p.removed.items():
            removed[k] = removed.get(k, 0) + v
    data = (f"several recordings: {len(logs)} ({', '.join(x.source for x in logs)}), their rows fitted as one "
            f"system (the report's series show the first)", *first.notes)
    terms = ("model terms: not tried across several recordings (each recording's terms would need its own states; "
             "the linear core)",) if opts.terms != "none" else ()
    account = Account(sum(x.n_samples for x in logs), removed, float(first.design.cutoff), int(first.factor),
                      data, "; ".join(notes), terms, cov_note if rows else cov_note + " (white: rows of several "
                      "recordings not kept in memory_mb)", tuple(units))
    return assemble(f, acc, opts, account, train_rms, val, series, _motion_many(model, preps, cols))


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


def _scores_many(f: Fit, acc, logs, preps, cols, validation, opts: IdentOptions, say):
    """Training scores over every recording (every sample against the raw torques), validation and series."""
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
    series = {"train": report_series(f.model, preps[0], cols[0], f, names, opts.memory_mb, None), "validation": None}
    if validation is None:
        return train, None, series
    say(f"validating on {validation.n_samples} held-out samples (every one, against the raw measured torques)")
    val = validation_scores(validation, predict_log(f, validation, cutoff), names, None, opts.score_cutoff)
    return train, val, series


def _motion_many(model: IdentModel, preps, cols) -> dict:
    """The condition number of every recording's motion together."""
    from .estimate import excitation, motion_factor

    def stack(attr):
        return np.concatenate([getattr(p.full, attr)[:, c] for p, c in zip(preps, cols)])

    factor = motion_factor(model, stack("q"), stack("dq"), stack("ddq"))
    return {"condition_number": excitation(factor, model.names)[0], "samples": int(sum(p.full.n_samples
                                                                                     for p in preps))}
