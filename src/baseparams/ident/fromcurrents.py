"""Identification from a log of motor currents: the pipeline, its result's gains, and its predictions.

:func:`identify_currents` is :func:`~baseparams.ident.identify` for a log that has motor currents
(``cur_<joint>`` [A]) and no joint-torque sensors, or whose currents are to be used
(``effort="current"``). The steps are the torque pipeline's (the model of
:func:`~baseparams.ident.model.model_for` with rotor inertia always modelled, the same zero-phase
filter and decimation on the currents and on every regressor column), then the estimator of
:mod:`baseparams.ident.currents`: the gains and the parameters together, the scale from the
anchor.

What a result from currents predicts (:class:`~baseparams.ident.gains.CurrentGains`): the
joint-side torques and the currents.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..display import counted
from ..errors import BaseparamsError, DataError
from .currents import GainAnchor, Transmission, parse_anchors, transmission_for
from .gains import CurrentGains, joint_side_fit

#: the input kinds of an identification (``effort``): torques or currents, or whichever the log has
EFFORTS = ("auto", "torque", "current")


def parse_effort(effort: str, log) -> str:
    """The input kind of an identification: ``torque`` or ``current``.

    Parameters
    ----------
    effort : {"auto", "torque", "current"}
        ``auto``: currents when the log has them and no torques, else torques.
    log : JointLog
        The log.

    Returns
    -------
    str
        ``torque`` or ``current``.

    Raises
    ------
    BaseparamsError
        An unknown kind, or a log without the signal asked for.
    """
    if effort not in EFFORTS:
        raise BaseparamsError(f"effort {effort!r}: choose {', '.join(EFFORTS)}")
    kind = effort if effort != "auto" else ("current" if log.cur is not None and log.tau is None else "torque")
    if kind == "current" and log.cur is None:
        raise DataError(f"{log.source}: no motor currents (columns cur_<joint> [A], or cur = ... in a columns= map)")
    if kind == "torque" and log.tau is None:
        raise DataError(f"{log.source}: no joint torques (columns tau_<joint>)"
                        + ("; its currents: effort=current" if log.cur is not None else ""))
    return kind


def anchor_of(text: str | None, tx: Transmission) -> tuple[tuple[GainAnchor, ...], list[int]]:
    """The anchors of ``--gain-anchor`` and their motors' indices.

    Parameters
    ----------
    text : str, optional
        ``JOINT=K[,JOINT=K...]``, or None (the model file's scale).
    tx : Transmission
        The motors.

    Returns
    -------
    anchors : tuple of GainAnchor
        The anchors (empty for None).
    index : list of int
        Their motors' indices in ``tx.motors``.

    Raises
    ------
    BaseparamsError
        A malformed anchor, or a joint that is not a motor of the log.
    """
    if text is None:
        return (), []
    anchors = parse_anchors(text)
    for anchor in anchors:
        if anchor.motor not in tx.motors:
            raise BaseparamsError(f"gain_anchor= {text!r}: {anchor.motor!r} is not a measured joint's motor; the "
                                  f"motors: {', '.join(tx.motors)}")
    return anchors, [tx.motors.index(a.motor) for a in anchors]


def currents_of(log):
    """The log with its currents in the torques' place (what the preprocessing filters like torques).

    Parameters
    ----------
    log : JointLog
        A log with currents.

    Returns
    -------
    JointLog
        ``tau`` = the currents [A], ``cur`` None.
    """
    return replace(log, tau=log.cur, cur=None)


def idx_of(anchors, tx: Transmission) -> list[int]:
    """The motors' indices of anchors (:class:`~baseparams.ident.currents.GainAnchor`).

    Parameters
    ----------
    anchors : sequence of GainAnchor
        The anchors.
    tx : Transmission
        The motors.

    Returns
    -------
    list of int
        Each anchor's motor's index.
    """
    return [tx.motors.index(a.motor) for a in anchors]


def transmission_of(model) -> Transmission:
    """The transmission of a model's measured joints and its motor couplings (:func:`transmission_for`).

    Parameters
    ----------
    model : IdentModel
        The model.

    Returns
    -------
    Transmission
        Motors named after the measured joints.

    Raises
    ------
    BaseparamsError
        A robot with loops or a floating base (not supported from currents), or a coupling not
        named after one of its joints.
    """
    r = model.robot
    if r.has_loops or r.floating:
        what = "closed loops" if r.has_loops else "a floating base"
        raise BaseparamsError(f"robot {r.name!r}: identification from currents is for fixed-base serial and tree "
                              f"arms; {what} is not supported (convert the currents to torques with known gains: "
                              f"a columns= map's torque_gain)")
    return transmission_for(model.joints, model.drives.couplings)


def identify_currents(robot, log, opts, validation=None, say=None):
    """Identify base parameters, drive terms and the motors' gains from a log of motor currents.

    Parameters
    ----------
    robot : Robot
        The model (fixed-base tree).
    log : JointLog
        Positions and motor currents ``cur`` [A] of the measured joints (torques, when the log
        also has joint-torque sensors, are scored against, never fitted).
    opts : IdentOptions
        The options (``gain_anchor`` fixes the scale; ``rotor`` is always on: a motor's current
        carries its rotor's inertia).
    validation : JointLog, optional
        Another log to score on (exclusive with ``opts.holdout``).
    say : callable, optional
        Progress, one line per step.

    Returns
    -------
    Identification
        Values (joint side, the anchor's scale), standard deviations, the gains
        (``result.currents``: :class:`CurrentGains`), scores on the currents [A] and, where the
        log has joint torques, on the joint-side torques (``train["joint_torque"]``).

    Raises
    ------
    BaseparamsError
        Options that do not apply to currents, a log without currents, a robot with loops or a
        floating base, an anchor that is not a motor, data that do not excite the model.
    """
    from .model import model_for
    from .rows import log_columns
    from .validation import split_log

    say = say or (lambda line: None)
    opts, notes = _current_options(opts)
    say(f"analysing {robot.name} (base parameters, drive model, motors)")
    model = model_for(robot, opts)
    tx = transmission_of(model)
    anchors, idx = anchor_of(opts.gain_anchor, tx)
    cols = log_columns(model, log)
    train, held = split_log(log, opts.holdout) if opts.holdout is not None else (log, validation)
    say(f"preprocessing {train.n_samples} training samples (resampling, low-pass, derivatives)")
    prep, a, cur, acc_note = _fitted_rows(model, train, cols, opts)
    am = tx.motor_rows(a)
    say(f"fitting {counted(model.n_params, 'parameter')} and {counted(len(tx.motors), 'gain')} "
        "(errors in the currents)")
    q = prep.q[:, cols][:: max(1, len(cur) // 400)]  # states the file's gravity torques give the scale at
    gf, cov, label, scale_std = _gain_fit(model, am, cur, anchors, idx, opts, q)
    f, gains = _result_parts(model, tx, am, cur, gf, cov, label, anchors, scale_std, opts.method)
    say("scoring (every sample, against the raw measured currents and any joint torques)")
    train_s, val_s = _scores(f, gains, log, held, opts, float(prep.design.cutoff))
    notes += [*prep.notes, acc_note, *_gain_notes(f, gains, gf), f"standard deviations: {label}"]
    series = current_series(f, gains, (prep, cols), held, opts.memory_mb)
    return _assembled(f, gains, train, prep, opts, (train_s, val_s, series), notes)


def _current_options(opts):
    """The options as currents use them (rotor inertia on, no model terms), and a note for each change."""
    notes = []
    if not opts.rotor_columns:
        opts = replace(opts, rotor=True)
        notes.append("rotor inertia: modelled (a motor's current carries its rotor's inertia, Ia ddq, which a "
                     "joint-torque sensor after the gear does not see)")
    if opts.terms not in ("auto", "none"):
        raise BaseparamsError(f"model terms ({opts.terms}) are not fitted from currents (terms=none)")
    if opts.terms == "auto":
        opts = replace(opts, terms="none")
        notes.append("model terms: not tried from currents (the linear core with the gains)")
    return opts, notes


def _fitted_rows(model, train, cols, opts):
    """The training currents prepared like torques, and the filtered, decimated rows with them."""
    from .preprocess import prepare
    from .rows import accumulate_prepared

    ilog = currents_of(train)
    try:
        prep = prepare(ilog, cutoff=opts.cutoff, decimate=opts.decimate, min_speed=opts.min_speed)
    except DataError as exc:
        if opts.holdout is None:
            raise
        raise DataError(f"{exc}; holdout={opts.holdout:g} s leaves too little to train on (a shorter "
                        f"holdout=)") from None
    kept: list = []
    _, note = accumulate_prepared(model, prep, cols, opts.memory_mb, ilog, opts.min_speed, keep=kept)
    if not kept:
        raise BaseparamsError(f"{train.source}: the fitted rows of this log do not fit in memory_mb "
                              f"{opts.memory_mb:g} MB; identification from currents holds them (a larger "
                              f"IdentOptions.memory_mb, or a stronger decimate=)")
    a = np.concatenate([x for x, _ in kept])
    cur = np.concatenate([y for _, y in kept])
    return prep, a, cur, note


def _gain_fit(model, am, cur, anchors, idx, opts, q):
    """The estimate, its covariance, and the scale (the anchors', or the model file's) with its relative std."""
    from ..numerics import blas_threads
    from .currents import covariance, fit_gains

    if anchors:  # the fit's own anchor: the given one of the largest torque (current spread x gain), best determined
        first = int(np.argmax([abs(a.gain) * np.std(cur[:, r]) for a, r in zip(anchors, idx)]))
        anchors, idx = (anchors[first], *anchors[:first], *anchors[first + 1:]), [idx[first], *idx[:first],
                                                                                      *idx[first + 1:]]
    fixed = (idx[0], 1.0 / anchors[0].gain) if anchors else None
    with blas_threads():
        gf = fit_gains(am, cur, model.names, tuple(model.joints), anchor=fixed, weighted=opts.method != "ols")
        cov, label = covariance(am, cur, gf, opts.covariance)
    if anchors:
        gf, cov, rel = _anchors_scaled(am, gf, cov, anchors, idx)
    else:
        gf, cov, rel = _file_scaled(model, gf, cov, q)
    if opts.method == "physical":  # at the final scale: the physical fit's prior is the file's inertias
        with blas_threads():
            gf = _physical(model, am, cur, gf, opts.prior_weight)
    return gf, cov, label, rel


def _rescaled(gf, cov, s: float):
    """Every parameter times ``s``, every inverse gain divided by it (the one direction currents leave free)."""
    p = len(gf.theta)
    d = np.r_[np.full(p, s), np.full(cov.shape[0] - p, 1.0 / s)]
    gf = replace(gf, theta=gf.theta * s, g=gf.g / s)
    return gf, cov * np.outer(d, d)


def _anchors_scaled(am, gf, cov, anchors, idx):
    """Several anchors: the scale from the determined ones, and the others' gains.

    The scale is the geometric mean of the determined anchors' ratios, its std their spread over the root of
    their number; an anchor on a motor the currents do not determine gives that motor's gain (its own terms
    follow).
    """
    scale = [(a, r) for a, r in zip(anchors, idx) if r not in gf.left_out]
    if len(scale) > 1:
        ratio = np.array([a.gain * gf.g[r] for a, r in scale])  # given / fitted
        if not np.all(ratio > 0):
            raise BaseparamsError(f"gain_anchor= {', '.join(str(a) for a, _ in scale)}: their signs disagree with the "
                                  f"fitted gains' ({', '.join(f'{a.motor} {1 / gf.g[r]:.4g}' for a, r in scale)} at "
                                  f"the first's scale)")
        logs = np.log(ratio)
        gf, cov = _rescaled(gf, cov, float(np.exp(logs.mean())))
        rel = float(np.std(logs, ddof=1) / np.sqrt(len(logs)))
    else:
        rel = 0.0
    theta, g = gf.theta.copy(), gf.g.copy()
    touched = (am != 0).any(axis=0)  # (m, p): the rows each column acts on
    for a, r in zip(anchors, idx):
        if r in gf.left_out:  # the current fits g_r times its own terms: given g_r, they follow
            own = touched[r] & (touched.sum(axis=0) == 1)
            theta[own] *= g[r] * a.gain
            g[r] = 1.0 / a.gain
    return replace(gf, theta=theta, g=g), cov, rel


def _file_scaled(model, gf, cov, q):
    """The estimate scaled to the model file's gravity torques (:func:`~baseparams.ident.currents.file_scale`)."""
    from .currents import file_scale

    nb = model.n_base
    zero = np.zeros_like(q)
    grav = model.regressor(q, zero, zero)[:, :, :nb]
    s, rel = file_scale(grav @ gf.theta[:nb], grav @ model.theta(model.robot.parameters("paper"))[:nb])
    gf, cov = _rescaled(gf, cov, s)
    return gf, cov, rel


def _physical(model, am, cur, gf, prior_weight):
    """The physically consistent parameters at the fitted gains, the free gains refitted to them (twice)."""
    from .currents import row_factors
    from .physical import physical_fit

    factors = row_factors(am, cur)
    p = am.shape[2]
    kw = {} if prior_weight is None else {"prior_weight": prior_weight}
    g, theta, phys = gf.g.copy(), gf.theta, None
    for _ in range(2):
        stack = np.concatenate([f * np.r_[np.full(p, g[k] * gf.weights[k]), gf.weights[k]]
                                for k, f in enumerate(factors)])
        r = np.linalg.qr(stack, mode="r")
        phys = physical_fit(r[:p, :p], r[:p, p], model.full_map(), model.robot, model.drives.param_kinds, **kw)
        theta = phys.theta
        tau = am @ theta
        num, den = np.einsum("sr,sr->r", tau, cur), np.einsum("sr,sr->r", tau, tau)
        g = np.where(gf.free & (den > 0), num / np.where(den > 0, den, 1.0), g)
    return replace(gf, theta=theta, g=g, physical=phys)


def _result_parts(model, tx, am, cur, gf, cov, label, anchors, scale_std, method):
    """The fit (its estimate's statistics in the currents' weighting) and the gains of a result."""
    from .currents import row_factors
    from .estimate import Estimate, condition_number
    from .fitting import Fit
    from .uncertainty import psd

    p = len(gf.theta)
    std = np.sqrt(np.maximum(np.diag(cov)[:p], 0.0))
    with np.errstate(divide="ignore"):
        pct = np.where(gf.theta != 0, 100 * std / np.abs(gf.theta), np.inf)
    e = cur - gf.g * (am @ gf.theta)
    rms = np.sqrt(np.mean(e**2, axis=0))
    stack = np.concatenate([f * np.r_[np.full(p, gf.g[k] * gf.weights[k]), gf.weights[k]]
                            for k, f in enumerate(row_factors(am, cur))])
    r = np.linalg.qr(stack, mode="r")
    cond = condition_number(r[:p, :p])
    est = Estimate(method, gf.theta, std, pct, gf.weights, rms, float(np.sqrt(np.mean(e**2))), cond, len(cur),
                   r[:p, :p], r[:p, p], psd(cov[:p, :p]), f"{label}; the gains' uncertainty included")
    f = Fit(model, method, gf.theta, est, gf.physical)
    k = np.where(gf.g != 0, 1.0 / np.where(gf.g != 0, gf.g, 1.0), np.inf)
    sg = np.zeros(len(k))
    sg[gf.free] = np.sqrt(np.maximum(np.diag(cov)[p:], 0.0))
    given = idx_of(anchors, tx)
    sg[[r for r in gf.left_out if r not in given]] = np.nan  # not determined: no std claimed
    sk = np.where(gf.g != 0, sg / np.where(gf.g != 0, gf.g, 1.0) ** 2, np.inf)
    gains = CurrentGains(tx, k, np.abs(sk), ",".join(map(str, anchors)) or "model file", float(scale_std),
                         np.where(gf.weights > 0, 1.0 / np.where(gf.weights > 0, gf.weights, 1.0), np.nan),
                         tuple(tx.motors[r] for r in gf.left_out), tuple(_groups(model, tx, gf, k, anchors)),
                         rotor_split(model))
    return f, gains


def rotor_split(model) -> dict:
    """The model file's armature of each rotor inertia regrouped into a base parameter, as that parameter's part.

    Parameters
    ----------
    model : IdentModel
        The model (its regrouping, its robot's ``armature``).

    Returns
    -------
    dict of str to float
        ``{base parameter: sum K armature}`` over the regrouped rotor inertias whose joint the file
        gives an armature; empty when it gives none.
    """
    reg, robot = model.regrouping, model.robot
    nb = len(model.analysis.base_names)
    arm = robot.armature if robot.armature is not None else np.zeros(robot.dof)
    coord = dict(zip(model.drives.joints, (model.coords[r] for r in model.drives.rows)))
    out: dict = {}
    for col, d in enumerate(reg.dependent):
        if d < nb or model.drives.param_kind(int(d - nb)) != "Ia":
            continue
        joint = reg.names[d].split("_", 1)[1]
        value = float(arm[coord[joint]]) if joint in coord else 0.0
        for row, i in enumerate(reg.independent):
            if value and reg.K[row, col]:
                out[reg.names[i]] = out.get(reg.names[i], 0.0) + float(reg.K[row, col]) * value
    return out


def _groups(model, tx, gf, k, anchors=()) -> list[dict]:
    """What currents cannot separate: the scale, drive terms regrouped, gains not determined, weak directions."""
    reg = model.regrouping
    nb = len(model.analysis.base_names)
    out = [{"kind": "scale", "members": ["every gain", "every parameter"],
            "note": "currents fix the gains and the parameters only up to one common factor: the anchor's"}]
    for col, d in enumerate(reg.dependent):
        if d < nb:
            continue
        into = [reg.names[i] for row, i in enumerate(reg.independent) if reg.K[row, col] != 0]
        term = reg.names[d]
        split = rotor_split(model)
        how = (f"the model file's armature ({', '.join(f'{n} {v:.4g}' for n, v in split.items() if n in into)}) is "
               f"taken out of the joint-side torque predicted" if any(n in split for n in into) else
               "the joint-side torque predicted includes it (a sensor after the gear would not see it; the model "
               "file states no armature to take out)")
        out.append({"kind": "regrouped", "members": [term, *into],
                    "note": f"{term} (motor side) is one column with {', '.join(into)}: {how}"})
    given = {a.motor for a in anchors}
    for r in gf.left_out:
        m = tx.motors[r]
        how = (f"its gain is the anchor's, {k[r]:.4g} (given)" if m in given else
               f"its gain, regressed afterwards on the torque the other joints' parameters predict on its row "
               f"({k[r]:.4g}: what predicts its currents), is not a measurement (that torque is at the noise, "
               f"and its errors bias the regression)")
        out.append({"kind": "undetermined", "members": [f"k_{m}", f"the terms only {m}'s row has"],
                    "note": f"the currents do not determine the gain of {m} against the others (its rigid-body "
                            f"torque is at its current's noise, or weaker than its rotor and friction terms): its "
                            f"row is left out of the parameters' fit; {how}; {m}'s joint-side torque comes from the "
                            f"other joints' parameters"})
    for grp in gf.groups:
        out.append({"kind": "weak", "members": list(grp["members"]),
                    "note": f"a direction this log does not determine (singular value {grp['singular_value']:.2g} "
                            f"of the largest, column-scaled): fitted values along it are not meaningful"})
    return out


def _gain_notes(f, gains: CurrentGains, gf) -> list[str]:
    """One line per gain, the scale, the groups, the search."""
    from .currents import POOR_GAIN

    unit = f.model.torque_unit
    parts = []
    for m, k, s in zip(gains.motors, gains.gains, gains.std):
        how = ("anchor" if m in gains.anchors else "NOT DETERMINED" if m in gains.undetermined else
               f"+- {s:.3g}" + (" POORLY DETERMINED" if not s <= POOR_GAIN * abs(k) else ""))
        parts.append(f"{m} {k:.5g} ({how})")
    notes = [f"gains [{unit}/A at the joint side]: " + ", ".join(parts), gains.scale_note()]
    notes += [f"cannot separate ({g['kind']}): {g['note']}" for g in gains.groups if g["kind"] != "scale"]
    if not gains.transmission.identity:
        notes.append("transmission: coupled motors' currents mapped to their joints (C^-1 per sample)")
    notes.append(f"estimate: errors in the currents (residual in amperes, per-motor noise "
                 f"{', '.join(f'{s:.3g}' for s in gains.sigma)} A), variable projection over the gains "
                 f"({gf.evaluations} evaluations)")
    return notes


def _scores(f, gains: CurrentGains, log, held, opts, cutoff: float):
    """Training and held-out scores: currents [A] and, where logged, joint-side torques, at every sample."""
    holdout = opts.holdout
    train = _score(f, gains, log, None if holdout is None else log.t < log.t[-1] - holdout, cutoff, opts, "training")
    if held is None:
        return train, None
    if holdout is not None:
        return train, _score(f, gains, log, log.t >= log.t[-1] - holdout, cutoff, opts, "held-out")
    return train, _score(f, gains, held, None, cutoff, opts, "held-out")


def _score(f, gains: CurrentGains, log, mask, cutoff: float, opts, what: str) -> dict:
    """One log's scores: the currents (when logged), the joint-side torques (when logged)."""
    from .validation import predict_log, validation_scores

    out = None
    if log.cur is not None:
        pred = gains.currents(predict_log(f, log, cutoff))
        out = validation_scores(replace(log, tau=log.cur), pred, list(gains.motors), mask, opts.score_cutoff)
        out.update(unit="A", measure=f"RMS of predicted minus raw measured currents [A] at every {what} sample")
    if log.tau is not None:
        pred = predict_log(joint_side_fit(f, gains), log, cutoff)
        jt = validation_scores(log, pred, f.model.joints, mask, opts.score_cutoff)
        jt.update(unit=f.model.torque_unit, measure=f"RMS of the predicted joint-side torque (rigid body; motor-side "
                  f"friction and rotor inertia excluded) minus the logged joint torques at every {what} sample")
        if out is None:
            return jt
        out["joint_torque"] = jt
    if out is None:
        raise DataError(f"{log.source}: neither currents nor joint torques to score against")
    return out


def _assembled(f, gains: CurrentGains, train, prep, opts, scores, notes):
    """The result: the counts, the options as used, the gains."""
    from .result import Identification

    samples = {"read": int(train.n_samples), "used": int(f.estimate.samples), "removed": dict(prep.removed)}
    options = replace(opts, cutoff=float(prep.design.cutoff), decimate=int(prep.factor))
    return Identification(f, samples, scores[0], scores[1], tuple(notes), scores[2], options, None, currents=gains)


def current_series(f, gains: CurrentGains, train: tuple, held, memory_mb: float) -> dict:
    """The report's series of a fit from currents: measured and predicted currents [A], as compared (filtered).

    Parameters
    ----------
    f : Fit
        The fit (joint-level torques, motor terms included, at the anchor's scale).
    gains : CurrentGains
        The motors' gains.
    train : tuple
        ``(prep, cols)``: the prepared training currents and the log column of each state column.
    held : JointLog or None
        The held-out log (the hold-out's end, or the validation log); its series only when it has
        currents.
    memory_mb : float
        Largest regressor formed at once.

    Returns
    -------
    dict
        ``{"train", "validation"}``, each None or ``{"t" (S',), "tau" (S', m) measured currents,
        "tau_hat" (S', m) predicted currents, "joints" (m,) the motors, "unit": "A"}``.
    """
    from .preprocess import prepare
    from .rows import log_columns
    from .validation import report_series

    prep, cols = train
    motors = list(gains.motors)

    def of(p, c):
        s = report_series(f.model, p, c, f, motors, memory_mb)
        return {**s, "tau_hat": gains.currents(s["tau_hat"]), "unit": "A"}

    out = {"train": of(prep, cols), "validation": None}
    if held is not None and held.cur is not None:
        vprep = prepare(currents_of(held), cutoff=prep.design.cutoff, decimate=prep.factor)
        out["validation"] = of(vprep, log_columns(f.model, held))
    return out
