"""Identification: base-parameter and drive values from measured joint torques.

The pipeline (:func:`identify`):

1. the base-parameter analysis of the robot (:func:`baseparams.analyze`, certified);
2. the drive model (rotor inertia, friction) of the measured joints and which of its
   parameters regroup with base parameters (:class:`IdentModel`, decided on sampled states);
3. the log (:class:`~baseparams.ident.data.JointLog`) preprocessed: resampled, zero-phase
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

from dataclasses import dataclass

import numpy as np

from ..analysis import analyze
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..numerics import blas_threads
from .model import IdentModel, ident_model


@dataclass(frozen=True, eq=False)
class Fit:
    """Identified values of an :class:`IdentModel`.

    Parameters
    ----------
    model : IdentModel
        The model identified.
    method : str
        ``ols``, ``wls`` or ``physical``.
    theta : ndarray, shape ``(p,)``
        Model parameter values (regrouped base parameters in the analysis's convention, then
        drive parameters).
    estimate : Estimate
        The least-squares estimate (OLS, or WLS for ``wls`` and as the physical fit's
        statistics).
    physical : object, optional
        The physically consistent fit (:class:`baseparams.ident.physical.PhysicalFit`), or
        ``None``.
    """

    model: IdentModel
    method: str
    theta: np.ndarray
    estimate: object
    physical: object = None

    def predict(self, q, dq, ddq) -> np.ndarray:
        """Predicted generalized forces of the measured rows.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, state_columns)``
            States.

        Returns
        -------
        ndarray, shape ``(S, m)``
            ``A(q, dq, ddq) @ theta``.
        """
        return self.model.regressor(q, dq, ddq) @ self.theta

    def rms(self, q, dq, ddq, tau) -> tuple[np.ndarray, float]:
        """Prediction error on (held-out) data.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, state_columns)``
            States.
        tau : array_like, shape ``(S, m)``
            Measured generalized forces of the measured rows.

        Returns
        -------
        rms : ndarray, shape ``(m,)``
            Per-row RMS of ``tau - predict(...)``.
        total : float
            RMS over all rows.
        """
        e = np.asarray(tau, dtype=float) - self.predict(q, dq, ddq)
        return np.sqrt(np.mean(e**2, axis=0)), float(np.sqrt(np.mean(e**2)))


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


def fit(model: IdentModel, acc, method: str = "ols", prior_weight: float | None = None,
        mass_bounds=None) -> Fit:
    """Estimate the model parameters from accumulated data.

    Parameters
    ----------
    model : IdentModel
        The model.
    acc : RowAccumulator
        The data (:func:`accumulate`).
    method : {"ols", "wls", "physical"}
        The estimator. ``physical``: full parameters with every ``N_i`` positive semidefinite,
        rotor inertia and friction non-negative, pulled towards the model file's inertias
        (log-det divergence, weight ``prior_weight``), on the WLS-weighted compressed system.
    prior_weight : float, optional
        Weight of the prior (``physical`` only; default that of
        :func:`baseparams.ident.physical.physical_fit`).
    mass_bounds : ndarray, shape ``(n, 2)``, optional
        Mass bounds per body [kg] (``physical`` only).

    Returns
    -------
    Fit
        The values and their statistics.

    Raises
    ------
    BaseparamsError
        An unknown method, or data that do not excite the model.
    """
    from .estimate import ols, wls

    if method not in ("ols", "wls", "physical"):
        raise BaseparamsError(f"unknown identification method {method!r}; choose ols, wls or physical")
    est = ols(acc, model.names) if method == "ols" else wls(acc, model.names)
    if method != "physical":
        return Fit(model, method, est.theta, est)
    from .physical import physical_fit

    kwargs = {} if prior_weight is None else {"prior_weight": prior_weight}
    phys = physical_fit(est.R11, est.r12, model.full_map(), model.robot, model.drives.param_kinds,
                        mass_bounds=mass_bounds, **kwargs)
    return Fit(model, method, phys.theta, est, phys)


@dataclass(frozen=True, eq=False)
class Identification:
    """The result of :func:`identify`: values, statistics, validation, what was done to the data.

    Parameters
    ----------
    fit : Fit
        The identified values (and the model).
    samples : dict
        ``{"read": int, "used": int, "removed": {reason: count}}`` for the training data.
    train : dict
        ``{"rms": {joint: float}, "rms_total": float}`` on the training samples (filtered).
    validation : dict, optional
        The same on held-out data, or ``None``.
    notes : tuple of str
        Every decision taken on the data and the model, one line each.
    series : dict, optional
        ``{"train": {...}, "validation": {...} or None}``, each ``{"t" (S,), "tau" (S, m),
        "tau_hat" (S, m), "joints" (m,)}``: the filtered measured and predicted torques (plots);
        ``train`` also has ``"spectrum"``: the excitation spectrum of the training positions
        (:func:`position_spectrum`).
    """

    fit: Fit
    samples: dict
    train: dict
    validation: dict | None
    notes: tuple[str, ...]
    series: dict | None = None

    @property
    def model(self) -> IdentModel:
        """The identified model."""
        return self.fit.model

    def base_parameters(self) -> list[dict]:
        """The regrouped base parameters (drive terms regrouped into them included).

        Returns
        -------
        list of dict
            ``{"name", "expression", "value", "std", "pct_sigma"}`` per model parameter that is not
            a drive parameter; values in the analysis's convention (SI units).
        """
        m = self.model
        est = self.fit.estimate
        nb = len(m.analysis.base_names)
        exprs = dict(zip(m.analysis.base_names, (e["expression"] for e in m.analysis.expressions())))
        out = []
        for k, (i, extra) in enumerate(zip(m.regrouping.independent, m.regrouping.expressions())):
            if i >= nb:
                continue
            name = m.regrouping.names[i]
            tail = extra[len(name):]
            out.append({"name": name, "expression": exprs.get(name, name) + tail, "value": float(self.fit.theta[k]),
                        "std": float(est.std[k]), "pct_sigma": float(est.pct_sigma[k])})
        return out

    def drives(self) -> list[dict]:
        """Drive parameters per joint.

        Returns
        -------
        list of dict
            ``{"joint", "Ia", "Fv", "Fc", "Fo", "std"}``: a value, ``None`` when not modelled, or
            ``"regrouped into <base parameter>"`` when the data cannot separate it; ``std``: the
            standard deviation of each identified value (``{kind: float}``).
        """
        m = self.model
        pos = {name: k for k, name in enumerate(m.names)}
        absorbed = {}
        for row, i in enumerate(m.regrouping.independent):
            for col, d in enumerate(m.regrouping.dependent):
                if m.regrouping.K[row, col] != 0:
                    absorbed[m.regrouping.names[d]] = m.regrouping.names[i]
        out = []
        std = self.fit.estimate.std
        for joint in m.drives.joints:
            entry = {"joint": joint, "std": {}}
            for kind in ("Ia", "Fv", "Fc", "Fo"):
                name = f"{kind}_{joint}"
                if kind not in m.drives.kinds:
                    entry[kind] = None
                elif name in pos:
                    entry[kind] = float(self.fit.theta[pos[name]])
                    entry["std"][kind] = float(std[pos[name]])
                else:
                    entry[kind] = f"regrouped into {absorbed.get(name, '?')}"
            out.append(entry)
        return out

    def couplings(self) -> list[dict]:
        """Coupled-motor parameters (:class:`~baseparams.ident.drives.MotorCoupling`).

        Returns
        -------
        list of dict
            ``{"name", "joints": {joint: weight}, "Iam", "Fvm", "Fcm", "std"}`` per coupling: a
            value, ``None`` when not modelled, or ``"regrouped into <parameter>"``; ``std``: the
            standard deviation of each identified value.
        """
        m = self.model
        pos = {name: k for k, name in enumerate(m.names)}
        absorbed = {m.regrouping.names[d]: m.regrouping.names[i]
                    for row, i in enumerate(m.regrouping.independent)
                    for col, d in enumerate(m.regrouping.dependent) if m.regrouping.K[row, col] != 0}
        out = []
        std = self.fit.estimate.std
        for c in m.drives.couplings:
            entry = {"name": c.name, "joints": dict(zip(c.joints, c.weights)), "std": {}}
            for kind in ("Iam", "Fvm", "Fcm"):
                name = f"{kind}_{c.name}"
                if kind not in m.drives.coupled_kinds:
                    entry[kind] = None
                elif name in pos:
                    entry[kind] = float(self.fit.theta[pos[name]])
                    entry["std"][kind] = float(std[pos[name]])
                else:
                    entry[kind] = f"regrouped into {absorbed.get(name, '?')}"
            out.append(entry)
        return out

    def to_json(self) -> dict:
        """One JSON-able object (schema in the README's identification section).

        Returns
        -------
        dict
            ``method, covariance, model, convention, n_samples{read, used, removed}, condition_number,
            excitation{condition_number, weak, all_excited}, base_parameters, drives, couplings,
            train, validation, physical, notes``; ``weak`` names the parameters carrying
            directions whose singular value is below 1e-3 of the largest (column-scaled regressor);
            ``covariance`` says how every ``std`` was computed.
        """
        f = self.fit
        phys = None
        if f.physical is not None:
            p = f.physical
            phys = {"feasible": bool(p.feasible), "min_eigenvalue": float(np.min(p.min_eigenvalues)),
                    "masses": {b: float(v) for b, v in zip(self.model.robot.names, p.masses)},
                    "solver_status": str(p.solver_status)}
        from .estimate import excitation

        cond, weak = excitation(f.estimate.R11, self.model.names)
        return {"method": f.method, "covariance": f.estimate.covariance, "model": self.model.robot.name,
                "convention": self.model.analysis.convention,
                "n_samples": self.samples, "condition_number": float(f.estimate.condition_number),
                "excitation": {"condition_number": cond, "weak": weak,
                               "all_excited": not weak},
                "base_parameters": self.base_parameters(), "drives": self.drives(),
                "couplings": self.couplings(), "train": self.train,
                "validation": self.validation, "physical": phys, "notes": list(self.notes)}


def identify(robot: Robot, log, *, method: str = "wls", rotor: bool = False,
             friction=("viscous", "coulomb", "offset"), coulomb_width: float | None = None,
             holdout: float | None = None, validation=None, cutoff: float | None = None,
             decimate: int | None = None, min_speed=None, prior_weight: float | None = None,
             convention: str = "khalil", memory_mb: float = 128.0, couplings=(), progress=None,
             covariance: str = "hac", allow_units: bool = False) -> Identification:
    """Identify base-parameter and drive values from a joint log.

    Parameters
    ----------
    robot : Robot
        The model (fixed base, or loops closed by the actuated joints).
    log : JointLog
        The log (:func:`baseparams.io.logs.read_log`): positions and torques of the measured
        joints (every joint of a tree; the actuated joints of a robot with loops).
    method : {"ols", "wls", "physical"}
        The estimator (:func:`fit`).
    rotor : bool
        Model each joint's rotor inertia ``Ia``.
    friction : iterable of str
        Friction terms: ``viscous``, ``coulomb``, ``offset`` (empty: none).
    coulomb_width : float, optional
        Smooth Coulomb friction's velocity scale [rad/s].
    holdout : float, optional
        Hold out the last ``holdout`` seconds of the log for validation.
    validation : JointLog, optional
        Another log to validate on (exclusive with ``holdout``).
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
    progress : callable, optional
        Called with one line of text at each step (analysis, preprocessing, accumulation, fit,
        validation, report series).
    covariance : {"hac", "white"}
        The standard deviations' covariance: ``hac`` (default) Newey-West, true under correlated
        residuals; ``white`` the least-squares formula (:mod:`baseparams.ident.uncertainty`).
    allow_units : bool
        Go on when the units look wrong (:mod:`baseparams.ident.plausibility`: velocities,
        time base, torques against the model file's, absurd samples), which otherwise refuses.

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
    if robot.floating:
        raise BaseparamsError(f"robot {robot.name!r}: identification from a joint log needs a fixed base (a floating "
                              f"base's motion and wrench are not in a joint log); use the Python API with states")
    if holdout is not None and validation is not None:
        raise BaseparamsError("give either holdout seconds or a validation log, not both")
    with blas_threads():
        return _identify(robot, log, method, rotor, friction, coulomb_width, holdout, validation, cutoff, decimate,
                         min_speed, prior_weight, convention, memory_mb, tuple(couplings), progress, covariance,
                         allow_units)


def _identify(robot, log, method, rotor, friction, coulomb_width, holdout, validation, cutoff, decimate, min_speed,
              prior_weight, convention, memory_mb, couplings=(), progress=None, covariance="hac",
              allow_units=False) -> Identification:
    """:func:`identify`'s steps (arguments as there)."""
    from .preprocess import prepare

    say = progress or (lambda msg: None)
    train, held = (split_log(log, holdout) if holdout is not None else (log, validation))
    say(f"analysing {robot.name} (base parameters, drive model)")
    model = ident_model(analyze(robot, convention=convention), rotor, tuple(friction), coulomb_width,
                        couplings=couplings)
    cols = log_columns(model, log)
    unit_notes = _units(model, train, cols, allow_units)
    say(f"preprocessing {train.n_samples} training samples (resampling, low-pass, derivatives)")
    prep = prepare(train, cutoff=cutoff, decimate=decimate, min_speed=min_speed)
    say(f"accumulating the regressor of {prep.n_samples} samples ({model.n_params} parameters)")
    kept = []
    acc, acc_note = accumulate_prepared(model, prep, cols, memory_mb, train, min_speed, keep=kept)
    say(f"fitting ({method})")
    f = fit(model, acc, method, prior_weight)
    f, cov_note = _uncertainty(f, acc, covariance, kept, model, prep, cols, memory_mb, train, min_speed, say)
    say("predicted torques and excitation spectrum for the report")
    names = [model.robot.joint_names[model.robot.dof_body[c]] for c in model.coords]
    res = np.array([np.linalg.norm(fr.r @ np.r_[f.theta, -1.0]) for fr in acc.factors]) / np.sqrt(acc.samples)
    train_rms = {"rms": dict(zip(names, res.tolist())), "rms_total": float(np.sqrt(np.mean(res**2)))}
    val, series = None, {"train": _series(model, prep, cols, f.theta, names, memory_mb), "validation": None}
    series["train"]["spectrum"] = position_spectrum(train, cols, prep.design.fs, prep.design.cutoff, prep.full.t)
    if held is not None:
        say(f"validating on {held.n_samples} held-out samples")
        vprep = prepare(held, cutoff=prep.design.cutoff, decimate=prep.factor)
        vcols = log_columns(model, held)
        vacc, _ = accumulate_prepared(model, vprep, vcols, memory_mb, held)
        vres = np.array([np.linalg.norm(fr.r @ np.r_[f.theta, -1.0]) for fr in vacc.factors]) / np.sqrt(vacc.samples)
        val = {"rms": dict(zip(names, vres.tolist())), "rms_total": float(np.sqrt(np.mean(vres**2))),
               "samples": int(vacc.samples), "source": held.source}
        series["validation"] = _series(model, vprep, vcols, f.theta, names, memory_mb)
    samples = {"read": int(train.n_samples), "used": int(acc.samples), "removed": dict(prep.removed)}
    notes = (*prep.notes, acc_note, *_model_notes(model), *(f.physical.notes if f.physical is not None else ()),
             cov_note, *unit_notes)
    return Identification(f, samples, train_rms, val, tuple(notes), series)


def _units(model: IdentModel, log, cols, allow_units: bool) -> list[str]:
    """Units and plausibility of the log before any fit (:func:`~baseparams.ident.plausibility.check_units`)."""
    from ..analysis import regressor
    from ..errors import DataError
    from .plausibility import check_units

    robot = model.robot
    params = robot.parameters("paper")
    coords = np.asarray(robot.actuated, dtype=int) if robot.has_loops else np.arange(robot.dof)
    revolute = np.array([robot.jtype[robot.dof_body[c]] == "R" for c in coords])
    try:
        return check_units(log, cols, lambda q, dq, ddq: regressor(robot, q, dq, ddq) @ params, revolute)
    except DataError as exc:
        if not allow_units:
            raise
        return [f"units: WARNING, going on (allow_units): {exc}"]


def _uncertainty(f: Fit, acc, covariance, kept, model, prep, cols, memory_mb, train, min_speed, say):
    """The fit's standard deviations from the chosen covariance (a second pass for HAC)."""
    from .uncertainty import apply_covariance, fitted_rows

    if covariance == "hac":
        say("covariance (HAC: a second pass over the fitted rows)")
    rows = kept if kept else (lambda: fitted_rows(model, prep, cols, memory_mb, train, min_speed))
    return apply_covariance(f, acc, rows, covariance, prep.design.fs / prep.factor)


def _series(model: IdentModel, prep, cols: np.ndarray, theta: np.ndarray, names: list[str], memory_mb: float):
    """Measured and predicted torques of a prepared log, as they were compared (filtered)."""
    full = prep.full
    q, dq, ddq = full.q[:, cols], full.dq[:, cols], full.ddq[:, cols]
    size_mb = full.n_samples * len(model.coords) * model.n_params * 8 / 1e6
    if size_mb <= memory_mb:
        tau_hat = prep.apply(model.regressor(q, dq, ddq)) @ theta
    else:
        idx = prep.index
        tau_hat = np.concatenate([model.regressor(q[idx[k:k + 20000]], dq[idx[k:k + 20000]],
                                                  ddq[idx[k:k + 20000]]) @ theta for k in range(0, len(idx), 20000)])
    return {"t": prep.t, "tau": prep.tau[:, cols], "tau_hat": tau_hat, "joints": names}


def position_spectrum(log, cols, fs: float, cutoff: float | None = None, t=None, bands: int = 300,
                      segment: int = 2**16, max_segments: int = 64) -> dict:
    """The amplitude spectrum of a log's positions per joint (the excitation spectrum).

    The raw (unfiltered) positions on a uniform grid, split into Hann-windowed segments of at most
    ``segment`` samples (half overlapping, at most ``max_segments`` spread over the log), their
    power averaged; then, for plotting on a log axis, the largest amplitude in each of ``bands``
    log-spaced frequency bands.

    Parameters
    ----------
    log : JointLog
        The log (``t (S,)``, ``q (S, joints)``).
    cols : array_like of int, shape ``(m,)``
        The log columns to analyse.
    fs : float
        The uniform grid's rate [Hz].
    cutoff : float, optional
        The low-pass cutoff [Hz] used on the log (recorded, for the plot).
    t : ndarray, optional
        The uniform grid (default: ``log.t``, taken as uniform); positions are interpolated on it.
    bands : int
        Log-spaced frequency bands of the result.
    segment : int
        Longest segment [samples]: the frequency resolution is ``fs / segment``.
    max_segments : int
        Most segments averaged (a very long log is sampled, not read whole).

    Returns
    -------
    dict
        ``{"f": ndarray (F,) [Hz], "amplitude": ndarray (F, m) [rad or m], "cutoff": float or None,
        "fs": float, "of": "q"}``: ``F <= bands`` band frequencies (mean of each band's bins) and
        the largest single-sided amplitude in the band (a sinusoid of amplitude ``A`` reads ``A``).
    """
    cols = np.asarray(cols, dtype=int)
    t = log.t if t is None else np.asarray(t, dtype=float)
    seg = int(min(len(t), segment))
    w = np.hanning(seg)
    starts = np.unique(np.linspace(0, len(t) - seg, min(max_segments, (len(t) - seg) // max(seg // 2, 1) + 1))
                       .astype(int))
    power = np.zeros((seg // 2 + 1, len(cols)))
    for k in starts:
        x = np.column_stack([np.interp(t[k:k + seg], log.t, log.q[:, c]) for c in cols])
        power += np.abs(np.fft.rfft((x - x.mean(axis=0)) * w[:, None], axis=0)) ** 2
    amp = (2 * np.sqrt(power / len(starts)) / w.sum())[1:]
    f = np.fft.rfftfreq(seg, 1.0 / fs)[1:]
    band = np.floor(np.log(f / f[0]) / np.log(max(f[-1] / f[0], 1.0 + 1e-12)) * bands).clip(0, bands - 1)
    first = np.flatnonzero(np.r_[True, np.diff(band) > 0])
    return {"f": np.add.reduceat(f, first) / np.diff(np.r_[first, len(f)]),
            "amplitude": np.maximum.reduceat(amp, first, axis=0), "cutoff": cutoff, "fs": float(fs), "of": "q"}


def split_log(log, seconds: float):
    """The log split into training and the last ``seconds`` held out.

    Parameters
    ----------
    log : JointLog
        The log.
    seconds : float
        Length of the held-out tail [s].

    Returns
    -------
    train, held : JointLog
        The two parts (each filtered on its own later: no information crosses the split).

    Raises
    ------
    BaseparamsError
        ``seconds`` not inside the log's duration.
    """
    from dataclasses import replace

    t = log.t
    if not 0 < seconds < t[-1] - t[0]:
        raise BaseparamsError(f"{log.source}: holdout {seconds} s must be inside the log's {t[-1] - t[0]:.6g} s")
    cut = int(np.searchsorted(t, t[-1] - seconds))

    def part(sl):
        rates = {k: None if getattr(log, k) is None else getattr(log, k)[sl] for k in ("dq", "ddq")}
        return replace(log, t=t[sl], q=log.q[sl], tau=log.tau[sl], **rates)

    return part(slice(0, cut)), replace(part(slice(cut, None)), source=f"{log.source} (last {seconds:g} s)")


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
    r = model.robot
    coords = np.asarray(r.actuated, dtype=int) if r.has_loops else np.arange(r.dof)
    wanted = [r.joint_names[r.dof_body[c]] for c in coords]
    where = {j: k for k, j in enumerate(log.joints)}
    missing = [j for j in wanted if j not in where]
    if missing:
        what = "actuated joints" if r.has_loops else "joints"
        raise BaseparamsError(f"{log.source}: the log has no column for the {what} {missing} of {r.name!r}")
    return np.array([where[j] for j in wanted], dtype=int)


def accumulate_prepared(model: IdentModel, prep, cols: np.ndarray, memory_mb: float, log=None, min_speed=None,
                        keep=None):
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
    keep : list, optional
        When given and the regressor is formed at once, ``(A, tau)`` of the fitted samples are
        appended to it (no longer than the regressor formed: the covariance's second pass,
        :mod:`baseparams.ident.uncertainty`, then needs no second regressor).

    Returns
    -------
    acc : RowAccumulator
        The row factors.
    note : str
        How the parallel filtering was done.
    """
    from .estimate import RowAccumulator

    full = prep.full
    size_mb = full.n_samples * len(model.coords) * model.n_params * 8 / 1e6
    if size_mb <= memory_mb or log is None:
        q, dq, ddq = full.q[:, cols], full.dq[:, cols], full.ddq[:, cols]
        acc = RowAccumulator(len(model.coords), model.n_params)
        a, tau = prep.apply(model.regressor(q, dq, ddq)), prep.tau[:, cols]
        acc.add(a, tau)
        if keep is not None:
            keep.append((a, tau))
        return acc, (f"parallel filtering: the regressor's {model.n_params} columns filtered like the torques "
                     f"({size_mb:.0f} MB at once)")
    from . import chunks
    from .preprocess import resample

    grid = chunks.Grid(full.n_samples, prep.design.pad, prep.factor, prep.design.cutoff, min_speed)
    margin = chunks.overlap(prep.design)
    per_sample_mb = len(model.coords) * model.n_params * 8 * 4 / 1e6  # the filter's copies: ~4x
    size = max(4 * margin, int(memory_mb / per_sample_mb) - 2 * margin)
    uniform = resample(log)  # the grid prepare() filtered on (it resamples with the same default)
    parts = [chunks.chunk_factors(uniform, c, grid, model.regressor, cols, model.n_params)[0]
             for c in chunks.plan(full.n_samples, size, margin)]
    return chunks.combine(parts), (f"parallel filtering in {len(parts)} chunks of {size} samples with "
                                   f"{margin}-sample overlaps (equal to the whole log's to rounding)")


def _model_notes(model: IdentModel) -> list[str]:
    """One line per drive parameter regrouped into a base parameter."""
    return [f"regrouped: {e}" for e in model.regrouping.expressions() if " + " in e or " - " in e]
