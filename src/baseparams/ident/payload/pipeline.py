"""Payload identification, step by step (:func:`identify_payload`).

1. The link (:func:`~.model.body_of`), the joints that move in the log and those of them that carry
   the link (the fitted rows); the model (:func:`~.model.payload_model`): the payload's columns, the
   fitted drive terms, the known robot (the model file, or a saved identification).
2. The log prepared as :func:`baseparams.identify` prepares it, the rows filtered in parallel, the
   slow samples of each row left out (:mod:`baseparams.ident.payload.rows`).
3. What the moving joints identify, structurally (:func:`~.structure.structural`), then at a gap of
   the log's own spectrum.
4. The estimate on the identified directions, weighted, its covariance (HAC; with a saved
   identification, its own covariance propagated), physically consistent (:mod:`baseparams.ident.payload.fit`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...errors import BaseparamsError
from ...model.robot import Robot
from .fit import PayloadFit, covariance, physical_fit, result_covariance, weighted_fit
from .model import body_of, payload_model
from .offsets import choose_offsets
from .options import PayloadOptions
from .result import Payload
from .rows import fitted_rows, log_columns, moving_joints
from .structure import describe, structural


def identify_payload(robot: Robot, log, link: str, options: PayloadOptions | None = None, /, *, result=None,
                     validation=None, progress=None, **keywords) -> Payload:
    """Identify a payload fixed to a link of a known robot from a joint log.

    Parameters
    ----------
    robot : Robot
        The robot without the payload (a fixed-base tree): its model file's, or the one a saved
        identification belongs to.
    log : JointLog
        Positions and torques of every joint, the payload on ``link``.
    link : str
        The link the payload is fixed to (a body of ``robot``, or its joint's name).
    options : PayloadOptions, optional
        How (:class:`~.options.PayloadOptions`); default its defaults.
    result : Identification, optional
        A saved identification of the robot without the payload: the known robot is its
        prediction (else the model file's rigid body).
    validation : JointLog, optional
        Another log with the payload, scored by :meth:`Payload.predict` (held-out RMS per joint).
    progress : callable, optional
        Called with one line of text per step.
    **keywords
        Options as keywords, instead of or over ``options``.

    Returns
    -------
    Payload
        Mass, centre of mass, inertia, their sigmas, what is identified, the notes.

    Raises
    ------
    BaseparamsError
        Bad options, an unknown link, a robot that is not a fixed-base tree, a result of another
        robot, a log missing a joint, a log in which no joint carrying the link moves.
    """
    from ...arguments import check_progress, options_from
    from ...numerics import blas_threads

    opts = options_from(PayloadOptions, options, keywords)
    say = check_progress(progress, "payload") or (lambda msg: None)
    with blas_threads():
        return _identify(robot, log, link, opts, result, validation, say)


def _identify(robot: Robot, log, link: str, opts: PayloadOptions, result, validation, say) -> Payload:
    """:func:`identify_payload`'s steps."""
    from ..preprocess import prepare

    body = body_of(robot, link)
    _check_result(robot, result)
    log = log.checked()
    cols = log_columns(robot, log)
    moving = moving_joints(robot, log, cols, opts.still)
    rows = np.array([c for c in robot.path_dofs(body) if moving[c]], dtype=int)
    model, notes = payload_model(robot, body, rows, opts, result)
    opts = _method(opts, notes)
    say(f"preparing {log.n_samples} samples (resampling, low-pass, derivatives)")
    prep = prepare(log, cutoff=opts.cutoff, decimate=opts.decimate)
    say(f"payload rows of {', '.join(model.joints)} at {prep.n_samples} samples")
    rows_obj, row_notes = fitted_rows(model, log, prep, cols, opts)
    say("which payload parameters the moving joints identify (structural rank)")
    q_log = np.asarray(log.q, dtype=float)[:, cols]
    st = structural(model, q_log, moving, opts.analysis_samples, opts.seed)
    model, rows_obj, st, offsets = choose_offsets(
        model, rows_obj, st, opts, lambda m: structural(m, q_log, moving, opts.analysis_samples, opts.seed),
        _block_periods(log, prep, cols[model.rows]))
    say(f"fitting ({opts.method}, {opts.covariance} covariance)")
    f = _fit(model, rows_obj, st, opts)
    prep_notes = [n for n in prep.notes if not n.startswith("slow samples:")]  # identify's min_speed: not ours
    notes += _joint_notes(robot, body, moving, rows) + row_notes + prep_notes + [offsets] * (offsets is not None)
    notes += _fit_notes(model, f, opts)
    samples = {"read": int(log.n_samples), "kept": int(prep.n_samples), "fitted": int(f.observations)}
    used = replace(opts, cutoff=float(prep.design.cutoff), decimate=int(prep.factor))
    out = Payload(model, f, used, tuple(notes), samples, tuple(robot.coordinate_names(np.flatnonzero(moving))))
    if validation is not None:
        say(f"validating on {validation.n_samples} held-out samples")
        out = replace(out, validation=scores(out, validation))
    return out


def _block_periods(log, prep, state_cols) -> float:
    """Periods of the moving joints' motion bandwidth each cross-validation block of the log spans."""
    from ..preprocess import excitation_bandwidth, resample
    from ..select import FOLDS

    band = excitation_bandwidth(resample(log).q[:, state_cols], prep.design.fs)
    return float(prep.full.t[-1] - prep.full.t[0]) / FOLDS * band


def _method(opts: PayloadOptions, notes: list) -> PayloadOptions:
    """``auto`` resolved: physical when cvxpy and Clarabel are installed, else least squares with a note."""
    if opts.method != "auto":
        return opts
    try:
        import clarabel  # noqa: F401
        import cvxpy  # noqa: F401
    except ImportError:
        notes.append("method auto: least squares (the physically consistent fit needs cvxpy and clarabel: pip install "
                     "'baseparams[ident]')")
        return replace(opts, method="ls")
    return replace(opts, method="physical")


def _check_result(robot: Robot, result) -> None:
    """A saved identification must be of this robot (its structure's fingerprint) and measure every joint."""
    if result is None:
        return
    if type(result).__name__ != "Identification":
        from ...arguments import ArgumentTypeError

        raise ArgumentTypeError(f"payload: result must be an Identification or its saved file, got "
                                f"{type(result).__name__}")
    from ..saved import robot_fingerprint

    theirs = result.fit.model.robot
    if robot_fingerprint(theirs) != robot_fingerprint(robot):
        raise BaseparamsError(f"payload: the identification is of robot {theirs.name!r} (another structure than "
                              f"{robot.name!r}'s)")
    if sorted(int(c) for c in result.fit.model.coords) != list(range(robot.dof)):
        raise BaseparamsError("payload: the identification does not predict every joint (a sub-chain?); identify "
                              "the whole robot without the payload")


def _fit(model, rows, st, opts: PayloadOptions) -> PayloadFit:
    """The weighted fit, its covariance and the physically consistent values."""
    from ...model import inertia as _inertia

    k = model.n_params
    xp = np.zeros(k)
    if opts.prior is not None:
        p = np.asarray(opts.prior)
        xp[:10] = _inertia.to_convention(_inertia.pseudo_inertia(p[0], p[1:4], _sym(p[4:])), "khalil")
    z, r11, r12, cw, yw, t, w, st, x0 = weighted_fit(rows, st, xp)
    n_obs = int(rows.fitted.sum())
    cov_z, label = covariance(opts.covariance, cw, yw, z, r11, rows.rate, n_obs)
    extra = result_covariance(rows, (cw, rows.fitted * w), r11, model.result)
    if extra is not None:
        cov_z = cov_z + extra
        label += "; plus the saved identification's covariance propagated through the known torques"
    x_ls = x0 + t @ z
    x, phys = x_ls, None
    if opts.method == "physical":
        x, phys = physical_fit(r11, r12, x0, st, x_ls, opts.prior is not None, model.drives.n_params)
    res = (rows.y - rows.a @ x) * rows.fitted
    rms = np.sqrt((res**2).sum(axis=0) / np.maximum(rows.fitted.sum(axis=0), 1))
    return PayloadFit(x, x_ls, t @ cov_z @ t.T, w, rms, n_obs, st, label, phys)


def _sym(six) -> np.ndarray:
    xx, xy, xz, yy, yz, zz = six
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]], dtype=float)


def _joint_notes(robot: Robot, body: int, moving: np.ndarray, rows: np.ndarray) -> list[str]:
    """Which joints move, which carry the link, which are held (welded) and why their rows are not fitted."""
    names = robot.coordinate_names()
    carry = set(int(c) for c in robot.path_dofs(body))
    still = [names[c] for c in sorted(carry) if not moving[c]]
    out = [f"fitted rows: {', '.join(names[c] for c in rows)} (the moving joints that carry "
           f"{robot.names[body]!r})"]
    if still:
        out.append(f"joints that carry {robot.names[body]!r} but do not move: {', '.join(still)}: held at their "
                   f"median (welded) in the structural analysis; their rows are not fitted (a held joint's torque "
                   f"has an unknown static friction)")
    return out


def _fit_notes(model, f: PayloadFit, opts: PayloadOptions) -> list[str]:
    """The structural decision, the log's gap, the covariance, the estimator and its constraint, in words."""
    st = f.structure
    k = len(st.scale)
    warn = _rotor_warning(model, f)
    out = [f"structural rank {st.rank + st.weak} of {k} columns (payload 10, drive terms {k - 10}), decided at a gap "
           f"of {st.gap:.3g} at random states of the moving joints"]
    if st.weak:
        out.append(f"{st.weak} direction(s) below a gap of {st.log_gap:.3g} in the log's own spectrum: not identified "
                   f"by this log (a richer motion: excite --payload)")
    unid = describe(st, model.names[10:])
    if unid:
        held = ("held at the prior" if opts.prior is not None
                else "not fitted and not reported (give a prior to hold them)")
        out.append(f"not identified by this motion ({held}): " + "; ".join(unid))
    out.append(f"standard deviations: {f.covariance}")
    if opts.method == "physical":
        out.append(f"physically consistent payload (positive mass, 4x4 pseudo-inertia positive semidefinite; "
                   f"cvxpy/Clarabel): constraint {f.physical['constraint']}; standard deviations at these values "
                   f"with the least-squares covariance (an active constraint is not credited)")
        moved = f.physical.get("prior_moved", 0.0)
        if moved > 1e-3:
            out.append(f"the prior is not compatible with the identified values: the combinations it holds moved by "
                       f"{100 * moved:.3g} % to make the payload realizable")
    else:
        out.append("least squares (not constrained to a realizable body)")
    return out + warn


#: a rotor inertia the saved identification lacks is "seen" beyond this many standard deviations
ROTOR_Z = 5.0


def _rotor_warning(model, f: PayloadFit) -> list[str]:
    """A WARNING when a saved identification without rotor inertia meets a log that shows some."""
    if model.result is None:
        return []
    names = model.names
    seen = [f"{n[1:]} {f.x[k]:.3g} +- {f.std[k]:.2g}" for k, n in enumerate(names)
            if n.startswith("dIa_") and f.std[k] > 0 and abs(f.x[k]) > ROTOR_Z * f.std[k]]
    if not seen:
        return []
    return [f"WARNING: the saved identification models no rotor inertia and this log shows some ({', '.join(seen)} "
            f"kg m^2): its base parameters absorbed it on its own motion, so they mispredict this one and bias the "
            f"payload; identify the robot without the payload again with --rotor (or leave --result out: the model "
            f"file's robot)"]


def scores(payload: Payload, log) -> dict:
    """Held-out scores of a payload on another log: RMS of predicted minus measured torques per joint.

    Parameters
    ----------
    payload : Payload
        The identified payload.
    log : JointLog
        Another log with the payload (every sample predicted: :meth:`Payload.predict`).

    Returns
    -------
    dict
        ``{"rms": {joint: float}, "rms_fitted": float, "samples", "source"}``: ``rms_fitted`` over
        the fitted joints.
    """
    robot = payload.model.robot
    log = log.checked()
    cols = log_columns(robot, log)
    e = np.asarray(log.tau, dtype=float)[:, cols] - payload.predict(log)
    rms = np.sqrt(np.mean(e**2, axis=0))
    names = robot.coordinate_names()
    return {"rms": dict(zip(names, map(float, rms))),
            "rms_fitted": float(np.sqrt(np.mean(e[:, payload.model.rows] ** 2))),
            "samples": int(log.n_samples), "source": str(log.source)}
