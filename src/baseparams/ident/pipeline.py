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
"""

from __future__ import annotations

import numpy as np

from ..analysis import analyze
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..numerics import blas_threads
from .fitting import Fit, fit, pulled_covariance
from .model import IdentModel, ident_model
from .notes import check_log_units, drive_notes, floating_notes, model_notes, term_note
from .result import Identification
from .rows import accumulate_prepared, log_columns, log_rows
from .validation import position_spectrum, predict_log, report_series, split_log, validation_scores


def identify(robot: Robot, log, *, method: str = "auto", rotor: bool = False,
             friction=("viscous", "coulomb", "offset"), coulomb_width: float | None = None,
             holdout: float | None = None, validation=None, cutoff: float | None = None,
             decimate: int | None = None, min_speed=None, prior_weight: float | None = None,
             convention: str = "khalil", memory_mb: float = 128.0, couplings=(), progress=None,
             samples: int | None = None, score_cutoff: float | None = None, covariance: str = "hac",
             allow_units: bool = False, literal: bool = False, terms="auto", seed: int = 0) -> Identification:
    """Identify base-parameter and drive values from a joint log.

    Parameters
    ----------
    robot : Robot
        The model (fixed base, or loops closed by the actuated joints).
    log : JointLog
        The log (:func:`baseparams.io.logs.read_log`): positions and torques of the measured
        joints (every joint of a tree; the actuated joints of a robot with loops).
    method : {"auto", "ols", "wls", "physical"}
        The estimator (:func:`fit`).
    rotor : bool
        Model each joint's rotor inertia ``Ia``.
    friction : iterable of str
        Friction terms: ``viscous``, ``coulomb``, ``offset`` (empty: none).
    coulomb_width : float, optional
        Smooth Coulomb friction's velocity scale [rad/s].
    holdout : float, optional
        Hold out the samples with ``t >= t_end - holdout`` for validation (training: the
        samples before).
    validation : JointLog, optional
        Another log to validate on (exclusive with ``holdout``). Validation predicts every
        held-out sample (:meth:`Identification.predict`) and compares with the raw measured
        torques (:func:`validation_scores`).
    cutoff : float, optional
        Low-pass cutoff [Hz] (default :func:`baseparams.ident.preprocess.lowpass_design`'s).
    decimate : int, optional
        Decimation factor (default from the rate and the cutoff).
    min_speed : float, optional
        Remove samples where a joint moves slower than this [rad/s] (Coulomb friction).
    prior_weight : float, optional
        ``physical`` only: the weight of the model file's inertias.
    convention : str
        Convention of the base parameters' names and values.
    memory_mb : float
        Largest regressor formed at once for the parallel filter (the filter's copies make the
        peak about 4x this); longer logs are processed in chunks with overlapping filter edges,
        which gives the same estimate to rounding (:mod:`baseparams.ident.chunks`).
    couplings : iterable of MotorCoupling
        Motors driving several joints (:class:`~baseparams.ident.drives.MotorCoupling`, e.g. a
        coupled wrist): their rotor inertia and viscous and Coulomb friction ``Iam``, ``Fvm``,
        ``Fcm`` (those whose per-joint kind is modelled).
    score_cutoff : float, optional
        Also score the validation against the measured torques low-passed at this cutoff [Hz]
        (zero-phase Butterworth, order 4), labelled with it.
    progress : callable, optional
        Called with one line of text at each step (analysis, preprocessing, accumulation, fit,
        validation, report series).
    samples : int, optional
        Random states of the base-parameter analysis the model is built on (default: the
        analysis's own).
    covariance : {"hac", "white"}
        The standard deviations' covariance: ``hac`` (default) Newey-West, true under correlated
        residuals; ``white`` the least-squares formula (:mod:`baseparams.ident.uncertainty`).
    allow_units : bool
        Go on when the units look wrong (:mod:`baseparams.ident.plausibility`: velocities,
        time base, torques against the model file's, absurd samples), which otherwise refuses.
    literal : bool
        Identify the model exactly as the file states it; by default geometry stated to within
        rounding of a right angle or zero is taken as that value when the directions it adds
        are not identifiable in practice (:func:`baseparams.analyze`'s ``literal``, said in the
        notes): those directions are not fitted.
    terms : str or iterable of str
        Model terms beyond the linear core (:mod:`baseparams.ident.terms`): ``"auto"``
        (default) tries pre-sliding friction, a mounting tilt, delays and torque scales and keeps
        each one that blocked cross-validation on the training data asks for; ``"none"``: the
        linear core alone; names (``"dahl,tilt"``) force those (with ``auto``: and try the rest).
        Every term tried is in :attr:`Fit.term_choices` and the notes.
    seed : int
        Seed of the base-parameter analysis' random states (:func:`baseparams.analyze`).

    Returns
    -------
    Identification
        Values, standard deviations, residuals, validation, counts and notes.

    Raises
    ------
    BaseparamsError
        A floating base, a log that misses a measured joint, ``holdout`` with ``validation``, bad
        data (:class:`~baseparams.errors.DataError`), a bad coupling or data that do not excite
        the model.
    """
    if holdout is not None and validation is not None:
        raise BaseparamsError("give either holdout seconds or a validation log, not both")
    log, validation = log.checked(), None if validation is None else validation.checked()  # finite, increasing
    with blas_threads():
        return _identify(robot, log, method, rotor, friction, coulomb_width, holdout, validation, cutoff, decimate,
                         min_speed, prior_weight, convention, memory_mb, tuple(couplings), progress, samples,
                         score_cutoff, covariance, allow_units, literal, terms, seed)


def _identify(robot, log, method, rotor, friction, coulomb_width, holdout, validation, cutoff, decimate, min_speed,
              prior_weight, convention, memory_mb, couplings=(), progress=None, samples=None,
              score_cutoff=None, covariance="hac", allow_units=False, literal=False, terms="auto",
              seed=0) -> Identification:
    """:func:`identify`'s steps (arguments as there)."""
    from .estimate import excitation, motion_factor
    from .preprocess import prepare

    say = progress or (lambda msg: None)
    train, held = (split_log(log, holdout) if holdout is not None else (log, validation))
    say(f"analysing {robot.name} (base parameters, drive model)")
    model = ident_model(analyze(robot, samples=samples, seed=seed, convention=convention, rows=log_rows(robot),
                                literal=literal),
                        rotor, tuple(friction), coulomb_width, couplings=couplings, log_base=robot.floating)
    cols = log_columns(model, log)
    unit_notes = check_log_units(model, train, cols, allow_units)
    say(f"preprocessing {train.n_samples} training samples (resampling, low-pass, derivatives)")
    prep = _prepare_training(train, holdout, cutoff=cutoff, decimate=decimate, min_speed=min_speed)
    say(f"accumulating the regressor of {prep.n_samples} samples ({model.n_params} parameters)")
    parts: list = []
    kept: list = []
    acc, acc_note = accumulate_prepared(model, prep, cols, memory_mb, train, min_speed, parts_out=parts,
                                        keep=kept)
    say(f"fitting ({method})")
    f = fit(model, acc, method, prior_weight, blocks=parts)
    f, acc, kept, term_notes, raw_q = _with_terms(f, acc, kept, prep, train, cols, method, prior_weight, terms, say)
    f, cov_note = _uncertainty(f, acc, covariance, kept, model, prep, cols, memory_mb, train, min_speed, say)
    f = pulled_covariance(f)
    say("predicted torques and excitation spectrum for the report")
    names = [model.robot.joint_names[model.robot.dof_body[c]] for c in model.coords]
    res = np.array([np.linalg.norm(fr.r @ np.r_[f.theta, -1.0]) for fr in acc.factors]) / np.sqrt(acc.samples)
    # one measure for training and validation: predictions at every sample against the raw measured torques
    pred_log = predict_log(f, log, float(prep.design.cutoff))
    tmask = log.t < log.t[-1] - holdout if holdout is not None else None
    train_rms = validation_scores(log, pred_log, names, tmask)
    train_rms["measure"] = "RMS of predicted minus raw measured torques at every training sample"
    train_rms.update(fit_rms=dict(zip(names, res.tolist())), fit_rms_total=float(np.sqrt(np.mean(res**2))))
    val, series = None, {"train": report_series(model, prep, cols, f, names, memory_mb, raw_q), "validation": None}
    series["train"]["spectrum"] = position_spectrum(train, cols[model.row_states], prep.design.fs, prep.design.cutoff,
                                                    prep.full.t)
    if held is not None:
        say(f"validating on {held.n_samples} held-out samples (every one, against the raw measured torques)")
        whole, mask = (log, log.t >= log.t[-1] - holdout) if holdout is not None else (held, None)
        pred = pred_log if holdout is not None else predict_log(f, whole, float(prep.design.cutoff))
        val = validation_scores(whole, pred, names, mask, score_cutoff)
        vprep = prepare(held, cutoff=prep.design.cutoff, decimate=prep.factor)
        vcols = log_columns(model, held)
        series["validation"] = report_series(model, vprep, vcols, f, names, memory_mb,
                                             _raw_positions(held, vcols[model.row_states]) if f.terms else None)
    samples = {"read": int(train.n_samples), "used": int(acc.samples), "removed": dict(prep.removed)}
    notes = (*prep.notes, acc_note, *model_notes(model), *floating_notes(robot), *term_notes, *drive_notes(f, acc),
             *(f.physical.notes if f.physical is not None else ()),
             *((f.selection.note(),) if f.selection is not None else ()), cov_note, *unit_notes)
    options = {"method": method, "convention": convention, "rows": str(model.analysis.rows), "rotor": bool(rotor),
               "friction": tuple(friction), "coulomb_width": coulomb_width, "couplings": tuple(couplings),
               "cutoff": float(prep.design.cutoff), "decimate": int(prep.factor), "min_speed": min_speed,
               "literal": bool(literal), "terms": terms if isinstance(terms, str) else ",".join(terms)}
    motion = {"condition_number": excitation(motion_factor(model, prep.full.q[:, cols], prep.full.dq[:, cols],
                                                           prep.full.ddq[:, cols]), model.names)[0],
              "samples": int(prep.full.n_samples)}
    return Identification(f, samples, train_rms, val, tuple(notes), series, options, motion)


def _raw_positions(log, cols: np.ndarray) -> np.ndarray:
    """Unfiltered positions of the given log columns on the log's uniform grid (what ``prepare`` filters)."""
    from .preprocess import resample

    return resample(log).q[:, cols]


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
        return Inner(w, theta0, s2 * drive_precision(model, acc, w), nonnegative_terms(model))
    return Inner(w, theta0)


#: model terms are tried when each cross-validation block spans at least this many periods of the motion's
#: bandwidth (shorter blocks each see a different piece of one motion: a term then fits the motion, not an effect;
#: measured on simulated 3 s logs, where spurious delays and scales won up to 24 % of cross-validated RMS and lost
#: 8-15 % on the next recording)
MIN_BLOCK_PERIODS = 1.0


def _with_terms(f: Fit, acc, kept: list, prep, train, cols, method: str, prior_weight, terms, say):
    """Model terms selected on the training rows and the core refitted with them (:mod:`.terms`).

    Returns the fit, the accumulated rows and kept rows the covariance uses, the notes, and the
    unfiltered positions on the training grid (None without terms).
    """
    from dataclasses import replace

    from . import chunks
    from .select import FOLDS, fold_parts
    from .terms.base import TermContext
    from .terms.fit import core_rows, parse_terms, select_terms

    candidates, forced = parse_terms(terms)
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
    raw_q = _raw_positions(train, cols[model.row_states])
    if raw_q.shape[0] != prep.full.n_samples:
        return f, acc, kept, ["model terms: not considered (the training grid is not the filter's)"], None
    from .preprocess import excitation_bandwidth

    span = float(prep.full.t[-1] - prep.full.t[0])
    band = excitation_bandwidth(raw_q, prep.design.fs)
    periods = span / FOLDS * band
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
    parts = fold_parts(x, y)
    acc2 = chunks.combine(parts)
    say(f"refitting the core ({method}) with the model terms")
    chosen = None if f.selection is None else f.selection.estimator
    f2 = fit(model, acc2, method, prior_weight, blocks=parts, estimator=chosen)
    if f2.selection is not None and f.selection is not None:  # the choice and its figures are the first fit's
        f2 = replace(f2, selection=replace(f2.selection, physical_cv=f.selection.physical_cv))
    return replace(f2, terms=tuple(tf.terms), term_choices=tf.choices), acc2, [(x, y)], notes, raw_q


def _prepare_training(train, holdout, **kw):
    """:func:`~baseparams.ident.preprocess.prepare` of the training part; a too short one names ``--holdout``."""
    from ..errors import DataError
    from .preprocess import prepare

    try:
        return prepare(train, **kw)
    except DataError as exc:
        if holdout is None:
            raise
        span = float(train.t[-1] - train.t[0]) if train.n_samples else 0.0
        raise DataError(f"{exc}; --holdout {holdout:g} s leaves {span:.3g} s to train on "
                        "(a shorter --holdout)") from None


def _uncertainty(f: Fit, acc, covariance, kept, model, prep, cols, memory_mb, train, min_speed, say):
    """The fit's standard deviations from the chosen covariance (a second pass for HAC)."""
    from .uncertainty import apply_covariance, fitted_rows

    if covariance == "hac":
        say("covariance (HAC: a second pass over the fitted rows)")
    rows = kept if kept else (lambda: fitted_rows(model, prep, cols, memory_mb, train, min_speed))
    return apply_covariance(f, acc, rows, covariance, prep.design.fs / prep.factor)


