"""Units and plausibility of a log, checked before any fit.

A log in the wrong units identifies silently wrong values; these checks catch the usual slips and
refuse with one line naming the file, the column and the likely unit
(:class:`~baseparams.errors.DataError`; ``allow_units=True`` / ``--allow-units`` goes on anyway):

* time: a sample rate above 100 kHz; below 5 Hz where the time column read as milli-, micro- or
  nanoseconds gives a robot's rate (10 Hz - 100 kHz), the unit whose joint speeds (implied by the
  positions) are a robot's (:data:`SPEED_RANGE`); below 50 Hz when the joints crawl (under 0.05
  rad/s at their fastest) and read in such a unit they move at a robot's speed;
* velocities: measured ``dq`` against finite differences of ``q`` (a ratio near 57.3: ``dq`` in
  deg/s; near 9.55: rpm; near 1/57.3: ``q`` in degrees; near 1000, 1e6, 1e9: time in milli-, micro-,
  nanoseconds; near 1/1000: ``q`` in mm or mrad);
* accelerations: measured ``ddq`` against d/dt of the velocities (near 57.3: deg/s^2);
* positions: a revolute joint far beyond the model's position limits (by more than 1 rad and half
  the range), or without logged velocities its speeds beyond 3 x the velocity limits, where the
  same numbers read as degrees are within them; with or without limits, the
  model file's torques on the motion read as radians and as degrees: a log that only the degrees
  reading explains (:func:`_degrees_by_model`);
* torques: against the model file's own torques on the same motion (inverse dynamics with the
  file's parameters): a factor near 1000 is mN m or N mm, near 1/1000 kN m; one joint whose ratio
  to the model is 400 times the other joints' and whose torques are 30 times theirs: mN m on that
  joint; torques beyond 10 times the model's effort limit that are within it divided by 1000: mN m;
  a sample beyond 1e6 x the model's RMS is absurd;
* the rate against the motion (:func:`check_rate`, once the low-pass is chosen): fewer than
  :data:`MIN_SAMPLES_PER_PERIOD` samples per period of the motion's fastest content (its
  bandwidth, 99.5 % of its energy: the accelerations by differences are off), or a low-pass
  cutoff below :data:`PASS_RATIO` times that bandwidth (the filter takes the motion itself off):
  the parameters are biased; a 7 Hz log of a 0.5 Hz excitation identified 18 times off.
"""

from __future__ import annotations

import numpy as np

from ..errors import GO_ON, DataError, going_on

DEG = 180.0 / np.pi
#: rad/s to revolutions per minute
RPM = 60.0 / (2.0 * np.pi)
#: a ratio within this factor of a unit factor is taken as that unit
NEAR = 1.6
#: time units a log's time column may be in by mistake: (seconds per unit, name)
TIME_UNITS = ((1e-3, "milliseconds"), (1e-6, "microseconds"), (1e-9, "nanoseconds"))
#: the peak joint speeds robots reach [rad/s or m/s]: telling a time unit from the positions
SPEED_RANGE = (1e-3, 50.0)
#: the fewest samples per period of the motion's bandwidth: second differences off by (pi / 20)^2 / 3 = 0.8 %
#: there (the low-pass's own rule, fs / 20; a 0.5 Hz excitation: 10 Hz identifies 1.4 % off, 7 Hz 6 %)
MIN_SAMPLES_PER_PERIOD = 20.0
#: the lowest low-pass cutoff, in multiples of the motion's bandwidth: the zero-phase Butterworth (order 4,
#: forward and backward) keeps 99.98 % of the motion there (at 2: 0.4 % off, parameters 3 % off; at 1.45: 20 %)
PASS_RATIO = 2.5


def _near(ratio: float, factor: float) -> bool:
    return np.isfinite(ratio) and ratio > 0 and factor / NEAR <= ratio <= factor * NEAR


def check_units(log, cols, torque_model, revolute, limits=None) -> list[str]:
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
    limits : array_like, shape ``(m, 4)``, optional
        The model's ``[lower, upper, velocity, effort]`` of each measured joint (NaN: unknown).

    Returns
    -------
    list of str
        Notes for the report.

    Raises
    ------
    DataError
        Naming the file, the column and the likely unit.
    """
    joints, q, derived, rate = _states(log, cols, revolute, limits)
    return _torques(log, cols, joints, q, derived, rate, torque_model, np.asarray(revolute, dtype=bool), limits)


def _states(log, cols, revolute, limits):
    """The checks that need no torque; ``(joints, q, d/dt of q, rate)`` for the torque checks."""
    t = np.asarray(log.t, dtype=float)
    joints = [log.joints[c] for c in cols]
    q = np.asarray(log.q, dtype=float)[:, cols]
    revolute = np.asarray(revolute, dtype=bool)
    rate = _time_base(log.source, t, q)
    derived = np.gradient(q, t, axis=0)
    _velocities(log, cols, joints, q, derived, revolute)
    _accelerations(log, cols, joints, derived, t, rate, revolute)
    _positions(log.source, joints, q, derived, revolute, limits, log.dq is not None)
    return joints, q, derived, rate


def check_states(log, cols, revolute, limits=None) -> list[str]:
    """A log's states without its torques (what ``predict`` reads): time, velocities, accelerations, positions.

    Parameters
    ----------
    log : JointLog
        The log or trajectory (``tau`` not used).
    cols : ndarray of int, shape ``(m,)``
        Log column of each predicted joint.
    revolute : ndarray of bool, shape ``(m,)``
        Which of them are revolute.
    limits : array_like, shape ``(m, 4)``, optional
        The model's limits of those joints.

    Returns
    -------
    list of str
        One note saying what was checked.

    Raises
    ------
    DataError
        As :func:`check_units`, for the checks that need no torque.
    """
    rate = _states(log, cols, revolute, limits)[3]
    return [f"units: states checked (sample rate {rate:.4g} Hz)"]


def check_prediction_log(model, log, allow_units: bool = False) -> list[str]:
    """:func:`check_states` for a log an identification predicts (``predict``), the model's joints found by name.

    Parameters
    ----------
    model : IdentModel
        The identified model (its robot and measured coordinates).
    log : JointLog
        The log.
    allow_units : bool
        Go on with a warning note instead of refusing.

    Returns
    -------
    list of str
        Notes (none when the log lacks a joint: the prediction says so).

    Raises
    ------
    DataError
        Units that look wrong, unless ``allow_units``.
    """
    robot = model.robot
    names = model.joints
    if log.n_samples < 3 or any(j not in log.joints for j in names):
        return []
    cols = np.array([log.joints.index(j) for j in names])
    revolute = np.array([robot.jtype[robot.dof_body[c]] == "R" for c in model.coords])
    limits = None if robot.limits is None else np.asarray(robot.limits, dtype=float)[np.asarray(model.coords)]
    try:
        return check_states(log, cols, revolute, limits)
    except DataError as exc:
        if not allow_units:
            raise
        return [going_on("units", exc)]


def check_rate(source: str, band: float, span: float, fs: float, cutoff: float, given: bool,
               allow_units: bool = False) -> list[str]:
    """Refuse a log whose rate, or low-pass, cannot carry its motion's dynamics (module docstring).

    Parameters
    ----------
    source : str
        The log, for messages.
    band : float
        The motion's bandwidth [Hz]: :func:`~baseparams.ident.preprocess.excitation_bandwidth` of
        the measured coordinates' positions, unfiltered (0: no motion, nothing checked) — the
        estimate the default cutoff is chosen from (:attr:`~baseparams.ident.preprocess.Prepared.band`),
        quoted as it is.
    span : float
        The time the bandwidth was estimated over [s]: the rate and cutoff are checked against the
        estimate less ``2 / span`` (the Hann window's half main lobe: a short log's spectrum cannot
        tell its content closer; the lines say so), so that only a rate or cutoff clearly too low
        is refused.
    fs : float
        The sample rate [Hz].
    cutoff : float
        The low-pass cutoff used [Hz].
    given : bool
        The cutoff was given (``--cutoff``), not the default.
    allow_units : bool
        Go on with a warning note instead of refusing.

    Returns
    -------
    list of str
        One note: the motion's bandwidth against the rate and the cutoff (a warning when allowed).

    Raises
    ------
    DataError
        One line: the rate, the bandwidth, what it costs, and what would help; unless ``allow_units``.
    """
    low = band - 2.0 / span if span > 0 else 0.0
    if not low > 0:
        return []
    which = (f"the excitation bandwidth {band:.3g} Hz, 99.5 % of its energy, less the {2.0 / span:.2g} Hz that "
             f"{span:.3g} s of log cannot resolve")  # the estimate the cutoff note quotes, less the check's margin
    problem = _rate_problem(low, fs, cutoff, given, which)
    if problem is not None:
        if not allow_units:
            raise DataError(f"{source}: {problem}" + GO_ON)
        return [going_on("rate", f"{source}: {problem}")]
    return [f"rate: {fs:.4g} Hz, {fs / low:.3g} samples per period of the motion's {low:.3g} Hz ({which}); cutoff "
            f"{cutoff:.3g} Hz = {cutoff / low:.2g} x that"]


def _rate_problem(band: float, fs: float, cutoff: float, given: bool, which: str) -> str | None:
    """What the rate or the cutoff cannot carry of a motion of bandwidth ``band`` (:func:`check_rate`), or None.

    ``which`` says the estimate ``band`` comes from (the excitation bandwidth the cutoff note quotes).
    """
    per = fs / band
    if per < MIN_SAMPLES_PER_PERIOD:
        off = (np.pi / per) ** 2 / 3
        best = MIN_SAMPLES_PER_PERIOD * PASS_RATIO * band
        return (f"a {fs:.3g} Hz log of a motion up to {band:.3g} Hz ({which}): {per:.3g} samples per "
                f"period of its fastest content, fewer than the {MIN_SAMPLES_PER_PERIOD:g} the accelerations need "
                f"(by differences {off:.1%} off there, the parameters more); record at {best:.3g} Hz or more (the "
                f"default cutoff, fs/20, then passes the motion; {MIN_SAMPLES_PER_PERIOD * band:.3g} Hz with "
                f"--cutoff {PASS_RATIO * band:.3g}), or a slower motion (up to {fs / MIN_SAMPLES_PER_PERIOD:.3g} Hz)")
    if cutoff < PASS_RATIO * band:
        how = "given" if given else "the default, at most fs/20"
        lost = 1 - 1 / (1 + (band / cutoff) ** 8)
        return (f"low-pass cutoff {cutoff:.3g} Hz ({how}) is {cutoff / band:.2g} x the motion's {band:.3g} Hz "
                f"({which}): the filter takes {lost:.1%} off the motion there and biases every parameter; --cutoff "
                f"{PASS_RATIO * band:.3g} or more ({PASS_RATIO:g} x the bandwidth)")
    return None


def _peak_speed(q: np.ndarray, t: np.ndarray) -> float:
    """The joint speed the positions imply at their fastest (99th percentile over samples and joints)."""
    if len(t) < 3:
        return float("nan")
    v = np.abs(np.diff(q, axis=0)) / np.diff(t)[:, None]
    return float(np.percentile(v, 99)) if v.size else float("nan")


def _time_base(src: str, t: np.ndarray, q: np.ndarray | None = None) -> float:
    """The median sample rate, refused when not a robot's in seconds (the unit named from the joint speeds)."""
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    rate = 1.0 / dt if dt > 0 else np.inf
    if rate > 1e5:
        raise DataError(f"{src}: column t: sample rate {rate:.3g} Hz is not a robot's; time likely in "
                        f"another unit than seconds (or the column is not time)" + GO_ON)
    if rate >= 50:
        return rate
    units = [(k, name) for k, name in TIME_UNITS if 10 <= rate / k <= 1e5]
    if not units and rate < 5:
        if rate < 1e-2:  # no unit makes it a robot's rate: not seconds anyway
            raise DataError(f"{src}: column t: steps of {dt:.3g} (a sample rate of {rate:.3g} Hz): not a robot's "
                            f"time in seconds, nor in ms, us or ns" + GO_ON)
        return rate
    if not units:
        return rate
    speed = _peak_speed(q, t) if q is not None else float("nan")
    fits = [(k, name) for k, name in units if SPEED_RANGE[0] <= speed / k <= SPEED_RANGE[1]]
    if rate >= 5 and not (fits and speed < 50 * SPEED_RANGE[0]):
        return rate  # slow, but the joints move at a robot's speed in seconds
    k, name = (fits or units)[0]
    why = (f"; read as {name} the joints move at up to {speed / k:.3g} rad/s, a robot's speed"
           if np.isfinite(speed) and fits else "")
    raise DataError(f"{src}: column t: sample rate {rate:.3g} Hz (steps of {dt:.3g}); time likely in {name} "
                    f"(x {k:g} to seconds: {rate / k:.4g} Hz){why}" + GO_ON)


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
            elif revolute[k] and _near(ratio, RPM):
                unit = (f"column dq_{j}: measured velocities {ratio:.3g} x d/dt of q: likely rpm (revolutions per "
                        f"minute, not rad/s)")
            elif revolute[k] and _near(ratio, 1 / DEG):
                unit = f"column q_{j}: d/dt of q {1 / ratio:.3g} x the measured velocities: q likely in degrees"
            elif any(_near(ratio, 1 / k_) for k_, _ in TIME_UNITS):
                name = next(n for k_, n in TIME_UNITS if _near(ratio, 1 / k_))
                unit = (f"column t (or dq_{j}): measured velocities {ratio:.4g} x d/dt of q: time likely in "
                        f"{name}")
            elif _near(ratio, 1e-3):
                unit = f"column q_{j}: d/dt of q {1 / ratio:.4g} x the measured velocities: q likely in mm or mrad"
            if unit:
                raise DataError(f"{src}: {unit}" + GO_ON)
    elif np.any(revolute):
        span = np.ptp(q[:, revolute], axis=0)
        if span.size and span.max() > 4 * np.pi * 3:
            k = int(np.flatnonzero(revolute)[np.argmax(span)])
            raise DataError(f"{src}: column q_{joints[k]}: spans {span.max():.4g} (over six turns): positions likely "
                            f"in degrees" + GO_ON)


def _smooth(x: np.ndarray, rate: float) -> np.ndarray:
    """A 50 ms moving average per column (tames differentiated noise)."""
    width = max(1, int(round(0.05 * rate)))
    if width == 1:
        return x
    kernel = np.ones(width) / width
    return np.apply_along_axis(lambda c: np.convolve(c, kernel, mode="same"), 0, x)


def _accelerations(log, cols, joints, derived, t, rate, revolute) -> None:
    """Measured accelerations against d/dt of the (measured or derived) velocities: deg/s^2."""
    if log.ddq is None or len(t) < 5:
        return
    ddq = np.asarray(log.ddq, dtype=float)[:, cols]
    dq = np.asarray(log.dq, dtype=float)[:, cols] if log.dq is not None else derived
    dd = _smooth(np.gradient(_smooth(dq, rate), t, axis=0), rate)
    for k, j in enumerate(joints):
        den = float(dd[:, k] @ dd[:, k])
        if not revolute[k] or den <= 0 or float(ddq[:, k] @ ddq[:, k]) <= 0:
            continue
        ratio = float(ddq[:, k] @ dd[:, k]) / den
        if _near(ratio, DEG):
            raise DataError(f"{log.source}: column ddq_{j}: measured accelerations {ratio:.3g} x d/dt of the "
                            f"velocities: likely deg/s^2 (not rad/s^2)" + GO_ON)


def _positions(src, joints, q, derived, revolute, limits, has_dq: bool) -> None:
    """Revolute positions against the model's limits: outside them as radians, within them as degrees."""
    if limits is None or not np.any(revolute):
        return
    lim = np.asarray(limits, dtype=float)
    if lim.shape != (len(joints), 4):
        return
    for k, j in enumerate(joints):
        if not revolute[k]:
            continue
        lo, hi, vmax = lim[k, 0], lim[k, 1], lim[k, 2]
        qmin, qmax = float(q[:, k].min()), float(q[:, k].max())
        if np.isfinite(lo) and np.isfinite(hi) and hi > lo:
            margin = max(0.1, 0.05 * (hi - lo))
            far = max(lo - qmin, qmax - hi) > max(1.0, 0.5 * (hi - lo))  # well outside: not a trajectory's slip
            as_deg = lo - margin <= qmin / DEG and qmax / DEG <= hi + margin
            if far and as_deg:
                raise DataError(f"{src}: column q_{j}: positions {qmin:.4g} to {qmax:.4g}, outside the model's limits "
                                f"[{lo:.4g}, {hi:.4g}] rad; as degrees they are within them: q likely in degrees"
                                + GO_ON)
        if not has_dq and np.isfinite(vmax) and vmax > 0:
            speed = float(np.percentile(np.abs(derived[:, k]), 99))
            if speed > 3 * vmax and speed / DEG <= 1.5 * vmax:
                raise DataError(f"{src}: column q_{j}: the positions move at up to {speed:.4g} per second, "
                                f"{speed / vmax:.3g} x the model's velocity limit {vmax:.4g} rad/s; as degrees "
                                f"within it: q likely in degrees" + GO_ON)


def _fit_quality(tau: np.ndarray, model: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """Per joint, the relative residual of ``tau - model ~ Fv dq + Fc sign(dq) + Fo`` (least squares).

    The model's torques enter as they are (no fitted scale: a scale would let any torque shaped like
    the acceleration pass). 1 where the model explains less than 0.3 (of the relative residual)
    beyond the friction terms alone: a friction-dominated joint says nothing about the units.
    """
    out = np.ones(tau.shape[1])
    for k in range(tau.shape[1]):
        f = np.column_stack([dq[:, k], np.sign(dq[:, k]), np.ones(len(tau))])
        norm = float(np.linalg.norm(tau[:, k]))
        if norm <= 0 or not np.all(np.isfinite(model[:, k])) or not np.all(np.isfinite(f)):
            continue
        rest = tau[:, k] - model[:, k]
        with_model = float(np.linalg.norm(rest - f @ np.linalg.lstsq(f, rest, rcond=None)[0])) / norm
        without = float(np.linalg.norm(tau[:, k] - f @ np.linalg.lstsq(f, tau[:, k], rcond=None)[0])) / norm
        out[k] = with_model if without - with_model > 0.3 else 1.0
    return out


def _degrees_by_model(src, joints, tau, q, dq, ddq, torque_model, revolute) -> None:
    """The model file's torques on the motion as logged and with its revolute columns read as degrees.

    Refused when only the degrees reading explains the measured torques: some joint's relative
    residual is below 0.3 read as degrees and above 0.6 (and 3 times more) as logged, and no joint
    shows the reverse (each per joint, with friction terms and an offset fitted alongside).
    """
    if not np.any(revolute):
        return
    conv = np.where(revolute, np.pi / 180, 1.0)
    given = _fit_quality(tau, np.asarray(torque_model(q, dq, ddq), dtype=float), dq)
    as_deg = _fit_quality(tau, np.asarray(torque_model(q * conv, dq * conv, ddq * conv), dtype=float), dq * conv)
    deg_better = (as_deg < 0.3) & (given > np.maximum(0.6, 3 * as_deg))
    rad_better = (given < 0.3) & (as_deg > np.maximum(0.6, 3 * given))
    if deg_better.any() and not rad_better.any():
        k = int(np.argmin(np.where(deg_better, as_deg, np.inf)))
        raise DataError(f"{src}: column q_{joints[k]}: the model file's torques explain the measured ones only with "
                        f"the revolute positions read as degrees (relative residual {as_deg[k]:.2g} vs "
                        f"{given[k]:.2g} as radians): q (and its rates) likely in degrees" + GO_ON)


def _torques(log, cols, joints, q, derived, rate, torque_model, revolute=None, limits=None) -> list[str]:
    """Measured torques against the model file's on the same motion; absurd samples."""
    src, t = log.source, np.asarray(log.t, dtype=float)
    tau = np.asarray(log.tau, dtype=float)[:, cols]
    step = max(1, len(t) // 400)
    sel = np.arange(0, len(t), step)
    dq_used = (np.asarray(log.dq, dtype=float)[:, cols] if log.dq is not None else derived)
    ddq = _smooth(np.gradient(dq_used, t, axis=0), rate)  # a 50 ms moving average tames differentiated noise
    model = np.asarray(torque_model(q[sel], dq_used[sel], ddq[sel]), dtype=float)
    model_rms = float(np.sqrt(np.mean(model**2)))
    if not model_rms > 0:
        return ["units: no model torques to compare with (the file's parameters give zero)"]
    peak = np.abs(tau).max(axis=0)
    if np.any(peak > 1e6 * model_rms):
        k = int(np.argmax(peak))
        i = int(np.argmax(np.abs(tau[:, k])))
        raise DataError(f"{src}: column tau_{joints[k]}, sample {i}: {tau[i, k]:.4g} is beyond any plausible "
                        f"torque of this model (its RMS on this motion: {model_rms:.3g})" + GO_ON)
    ratio = float(np.sqrt(np.mean(tau[sel] ** 2))) / model_rms
    per = np.sqrt(np.mean(tau[sel] ** 2, axis=0)) / np.maximum(np.sqrt(np.mean(model**2, axis=0)), 1e-300)
    # the joint that makes the overall ratio: the largest measured torques (above), the lowest ratio (below)
    worst = joints[int(np.argmax(np.mean(tau[sel] ** 2, axis=0)))] if ratio > 1 else joints[int(np.argmin(per))]
    if ratio > 1000 / NEAR / 1.5:
        raise DataError(f"{src}: column tau_{worst}: measured torques {ratio:.4g} x the model file's on the same "
                        f"motion: likely mN m or N mm (not N m)" + GO_ON)
    if ratio < 1.5 * NEAR / 1000:
        raise DataError(f"{src}: column tau_{worst}: measured torques {ratio:.3g} x the model file's on the same "
                        f"motion: likely kN m (not N m)" + GO_ON)
    _one_joint(src, joints, tau[sel], model)
    _efforts(src, joints, tau, limits)
    if revolute is not None:
        _degrees_by_model(src, joints, tau[sel], q[sel], dq_used[sel], ddq[sel], torque_model, revolute)
    return [f"units: checked (measured torques {ratio:.3g} x the model file's on the same motion; "
            f"sample rate {rate:.4g} Hz" + ("; measured velocities match d/dt of q)" if log.dq is not None else ")")]


def _one_joint(src, joints, tau: np.ndarray, model: np.ndarray) -> None:
    """One joint in mN m among joints in N m: its ratio to the model 400 x the others', its torques 30 x theirs.

    The others' ratio is their median over the joints the model's torques reach (at least 1 % of
    the largest joint's): a wrist whose torques are mostly friction has a large ratio in N m too.
    """
    m = len(joints)
    if m < 2:
        return
    rms = np.sqrt(np.mean(tau**2, axis=0))
    model_rms = np.sqrt(np.mean(model**2, axis=0))
    ratio = rms / np.maximum(model_rms, 1e-300)
    seen = model_rms >= 0.01 * model_rms.max()  # joints the model's torques reach (not friction-only wrists)
    for k in range(m):
        others = np.delete(np.arange(m), k)
        ref = others[seen[others]]
        if not len(ref):
            continue
        r_other, t_other = float(np.median(ratio[ref])), float(np.median(rms[others]))
        if r_other > 0 and t_other > 0 and ratio[k] > 1000 / NEAR / 1.5 * r_other and rms[k] > 30 * t_other:
            raise DataError(f"{src}: column tau_{joints[k]}: measured torques {ratio[k]:.3g} x the model file's, the "
                            f"other joints' {r_other:.3g} x (and {rms[k] / t_other:.3g} x their size): likely mN m or "
                            f"N mm on this joint (not N m)" + GO_ON)


def _efforts(src, joints, tau: np.ndarray, limits) -> None:
    """Torques far beyond the model's effort limits that in N m (/ 1000) are within them: mN m."""
    if limits is None:
        return
    lim = np.asarray(limits, dtype=float)
    if lim.shape != (len(joints), 4):
        return
    for k, j in enumerate(joints):
        e = lim[k, 3]
        if not (np.isfinite(e) and e > 0):
            continue
        peak = float(np.percentile(np.abs(tau[:, k]), 99.9))
        if peak > 10 * e and peak / 1000 <= 1.5 * e:
            raise DataError(f"{src}: column tau_{j}: measured torques up to {peak:.4g}, {peak / e:.3g} x the model's "
                            f"effort limit {e:.4g}; / 1000 within it: likely mN m or N mm (not N m)" + GO_ON)
