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

from dataclasses import dataclass

import numpy as np

from ..analysis import analyze
from ..display import clip, data_frame, format_number, text_table
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..numerics import blas_threads
from .model import IdentModel, ident_model

#: bytes of regressor :meth:`Fit.predict` forms at once
PREDICT_BYTES = 32e6


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
    selection : object, optional
        ``auto``: the cross-validated pull towards the model file
        (:class:`baseparams.ident.select.Selection`), or ``None``.
    terms : tuple of Term
        The model terms kept beyond the linear core (:mod:`baseparams.ident.terms`: pre-sliding
        friction, tilt, delays, scales), with their values.
    term_choices : tuple of Choice
        Every term tried: kept or rejected and why (:func:`baseparams.ident.terms.fit.select_terms`).
    """

    model: IdentModel
    method: str
    theta: np.ndarray
    estimate: object
    physical: object = None
    selection: object = None
    terms: tuple = ()
    term_choices: tuple = ()

    def __repr__(self) -> str:
        m = self.model
        how = self.method
        if self.physical is not None:
            how += ": physical" if self.method != "physical" else ""
            how += " (feasible)" if getattr(self.physical, "feasible", False) else " (not feasible)"
        if self.terms:
            how += " with " + "+".join(t.name for t in self.terms)
        rms = getattr(self.estimate, "rms_total", None)
        tail = "" if rms is None else f", residual RMS {format_number(rms, 3)} {m.torque_unit}"
        return clip(f"<Fit {m.robot.name}: {how}, {m.n_base} base + {m.n_drive} drive terms{tail}>")

    def predict(self, q, dq, ddq) -> np.ndarray:
        """Predicted generalized forces of the measured rows.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, state_columns)``
            States.

        Returns
        -------
        ndarray, shape ``(S, m)``
            ``A(q, dq, ddq) @ theta``, the regressor formed :data:`PREDICT_BYTES` at a time (a large
            robot's rows are wide: 60 links, 596 columns, 0.3 MB per sample).
        """
        q, dq, ddq = np.atleast_2d(q), np.atleast_2d(dq), np.atleast_2d(ddq)
        step = max(1, int(PREDICT_BYTES // (8 * max(len(self.model.coords), 1) * max(self.model.n_params, 1))))
        if len(q) <= step:
            return self.model.regressor(q, dq, ddq) @ self.theta
        return np.concatenate([self.model.regressor(q[k:k + step], dq[k:k + step], ddq[k:k + step]) @ self.theta
                               for k in range(0, len(q), step)])

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
        mass_bounds=None, blocks=None, estimator: str | None = None) -> Fit:
    """Estimate the model parameters from accumulated data.

    Parameters
    ----------
    model : IdentModel
        The model.
    acc : RowAccumulator
        The data (:func:`accumulate`).
    method : {"auto", "ols", "wls", "physical"}
        The estimator. ``auto``: OLS or WLS with the model file's parameters as a prior
        (maximum a posteriori; terms the data determine keep their fitted values), the weighting
        and the prior's weight chosen by blocked cross-validation on ``blocks``
        (:mod:`baseparams.ident.select`; plain WLS without blocks). ``physical``: full parameters
        with every ``N_i`` positive semidefinite, rotor inertia and friction non-negative,
        pulled towards the model file's inertias (log-det divergence, weight ``prior_weight``),
        on the WLS-weighted compressed system.
    prior_weight : float, optional
        Weight of the prior (``physical`` only; default that of
        :func:`baseparams.ident.physical.physical_fit`).
    mass_bounds : ndarray, shape ``(n, 2)``, optional
        Mass bounds per body [kg] (``physical`` only).
    blocks : list of RowAccumulator, optional
        Time-ordered pieces of ``acc``'s rows (``auto`` only).
    estimator : {"least squares", "physical"}, optional
        ``auto`` only: take this estimator instead of cross-validating least squares against the
        physical fit (a refit on rows the model terms transformed keeps the first choice).

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

    if method not in ("auto", "ols", "wls", "physical"):
        raise BaseparamsError(f"unknown identification method {method!r}; choose auto, ols, wls or physical")
    try:
        first = ols(acc, model.names)
    except BaseparamsError as exc:
        if method in ("ols", "wls") or "do not excite" not in str(exc):
            raise _plain_refusal(model, exc, method) from None
        # the default and physical estimates: directions no data see are held by the drive terms' weak prior
        # (pseudo-observations), e.g. Coulomb friction and offset of a joint that never reverses
        acc = _with_drive_prior_rows(model, acc)
        first = ols(acc, model.names)
    est = first if method == "ols" else wls(acc, model.names, first)
    if method == "auto":
        return _auto(model, first, est, acc, blocks or [], prior_weight, estimator)
    if method != "physical":
        return Fit(model, method, est.theta, est)
    from .physical import physical_fit

    kwargs = {} if prior_weight is None else {"prior_weight": prior_weight}
    kwargs["drive_precision"] = _drive_precision_delta(model, acc, est)
    phys = physical_fit(est.R11, est.r12, model.full_map(), model.robot, model.drives.param_kinds,
                        mass_bounds=mass_bounds, **kwargs)
    return Fit(model, method, phys.theta, est, phys)


def _plain_refusal(model: IdentModel, exc: BaseparamsError, method: str) -> BaseparamsError:
    """Plain least squares on data that do not separate its terms: what would help, when drive terms are the cause."""
    text = str(exc)
    weak = text.split("weakest: ")[-1].split(".")[0].split(", ") if "weakest: " in text else []
    drive = set(model.drives.names)
    if weak and all(w in drive for w in weak):
        return BaseparamsError(f"{text.rstrip('.')}; these are drive terms the log cannot separate (a joint that "
                               f"hardly moves, or never reverses: its Coulomb friction and offset are one column): "
                               f"plain least squares (--method {method}) cannot fit them; the default estimate holds "
                               f"them with a weak prior, or drop a term (--friction)")
    return exc


def _with_drive_prior_rows(model: IdentModel, acc):
    """The rows with the drive terms' weak prior added as pseudo-observations (each term ``~ N(0, sigma_k^2)``).

    For data that leave some drive terms undetermined (:func:`~baseparams.ident.select.drive_precision`);
    the prior's rows ``sqrt(s2 / sigma_k^2) e_k`` with right-hand side 0, ``s2`` the residual
    variance of the minimum-norm least-squares fit.
    """
    from .estimate import RowAccumulator, stacked_factor
    from .select import drive_precision

    p = model.n_params
    r = stacked_factor(acc, np.ones(acc.nrows))
    r = np.vstack([r, np.zeros((max(p + 1 - r.shape[0], 0), p + 1))])
    theta, *_ = np.linalg.lstsq(r[:p, :p], r[:p, p], rcond=1e-12)
    rank = int(np.linalg.matrix_rank(r[:p, :p], tol=1e-12 * max(float(np.abs(r[:p, :p]).max()), 1e-300)))
    rho2 = float(np.sum((r[:p, :p] @ theta - r[:p, p]) ** 2) + r[p, p] ** 2)
    s2 = rho2 / max(acc.samples * acc.nrows - rank, 1)
    prec = np.diag(drive_precision(model, acc))
    out = RowAccumulator(acc.nrows, p)
    out.samples = acc.samples
    for f, g in zip(out.factors, acc.factors):
        f.add(g.r)
        ks = [k for k in np.flatnonzero(prec > 0) if np.any(g.r[:, k])]
        if ks:
            extra = np.zeros((len(ks), p + 1))
            extra[np.arange(len(ks)), ks] = np.sqrt(s2 * prec[ks])
            f.add(extra)
    return out


def _drive_precision_delta(model: IdentModel, acc, est) -> np.ndarray:
    """The drive terms' weak prior (:func:`~baseparams.ident.select.drive_precision`) per drive parameter.

    In the weighted fit's units (``s2 / sigma_k^2``, ``s2`` the weighted residual variance), on the
    drive parameters ``delta`` the physical fit solves for; 0 for a drive parameter regrouped into a
    base parameter (it has no column of its own).
    """
    from .select import drive_precision

    w = np.asarray(est.weights, dtype=float)
    n_obs = max(acc.samples * acc.nrows, 1)
    s2 = float(np.sum((np.asarray(est.rms) * w) ** 2)) * acc.samples / n_obs
    prec = np.diag(drive_precision(model, acc, w))
    nb = len(model.analysis.base_names)
    out = np.zeros(model.drives.n_params)
    for k, i in enumerate(model.regrouping.independent):
        if i >= nb:
            out[i - nb] = s2 * prec[k]
    return out


#: the default takes the physically consistent estimate when its cross-validated RMS is lower than least squares'
#: by more than this fraction: within it, blocked cross-validation cannot rank them (on the Panda's periodic log
#: it ranked physical 3 % better while least squares predicts the next period 15 % better); on short logs
#: physical wins by 9-30 %
PHYSICAL_MARGIN = 0.05


def _auto(model: IdentModel, first, est, acc, blocks: list, prior_weight=None, estimator=None) -> Fit:
    """OLS or WLS with the model file as a prior, or the physical estimate, as blocked cross-validation asks.

    Drive terms get a weak prior towards zero (:func:`~baseparams.ident.select.drive_precision`)
    and rotor inertia, viscous and Coulomb friction stay non-negative, in every candidate. The
    least-squares candidates' best is then compared with the physically consistent estimate on
    the same blocks (:func:`~baseparams.ident.select.physical_cv`, when the ``ident`` extra is
    installed): on short or poorly exciting logs the physical constraints predict another
    recording better, on rich ones least squares with the prior does (measured by the
    cross-recording suite, ``benchmarks/cross_recording.py``).
    """
    from dataclasses import replace

    from .select import (
        drive_precision,
        no_prior_bodies,
        nonnegative_terms,
        prior_covariance,
        prior_precision,
        select,
        solve,
        split_blocks,
    )

    theta0 = model.theta(model.robot.parameters("paper"))
    nonneg = nonnegative_terms(model)
    if len(blocks) < 2:
        return Fit(model, "auto", solve(est.R11, est.r12, theta0, None, nonneg), est)
    s = prior_covariance(model)
    sel = select(split_blocks(blocks), {"ols": first.weights, "wls": est.weights}, theta0, prior_precision(model, s),
                 drive_prec=drive_precision(model, acc), nonneg=nonneg)
    if sel is None:
        return Fit(model, "auto", solve(est.R11, est.r12, theta0, None, nonneg), est)
    base = first if sel.weighting == "ols" else est
    nb = model.n_base
    prior_cov = np.zeros((model.n_params, model.n_params))
    if sel.lam:
        prior_cov[:nb, :nb] = s / sel.lam
    names = tuple(n for n, x in zip(model.robot.names, no_prior_bodies(model.robot)) if x)
    dprec = np.diag(drive_precision(model, acc))
    drive_cov = np.diag(np.where(dprec > 0, 1.0 / np.where(dprec > 0, dprec, 1.0), 0.0))
    sel = replace(sel, theta0=theta0, prior_cov=prior_cov if sel.lam else None, no_prior=names if sel.lam else (),
                  drive_cov=drive_cov)
    from .select import physical_cv

    cv_blocks = split_blocks(blocks)
    dp = _drive_precision_delta(model, acc, est)
    ls_cv = sel.cv_rms[sel.weighting][sel.lambdas.index(sel.lam)]
    if estimator is None:
        phys_cv = physical_cv(model, cv_blocks, est.weights, dp, prior_weight)
        take_physical = phys_cv is not None and phys_cv < (1.0 - PHYSICAL_MARGIN) * ls_cv
    else:
        phys_cv, take_physical = None, estimator == "physical"
    sel = replace(sel, physical_cv=phys_cv)
    if take_physical:
        from .physical import physical_fit

        kw = {} if prior_weight is None else {"prior_weight": prior_weight}
        phys = physical_fit(est.R11, est.r12, model.full_map(), model.robot, model.drives.param_kinds,
                            drive_precision=dp, **kw)
        return Fit(model, "auto", phys.theta, est, phys, selection=replace(sel, estimator="physical"))
    theta = solve(base.R11, base.r12, theta0, sel.penalty, nonneg)
    res = np.array([np.linalg.norm(f.r @ np.r_[theta, -1.0]) for f in acc.factors]) / np.sqrt(max(acc.samples, 1))
    # the least-squares statistics stay: pulled_covariance maps the covariance once it is chosen
    return Fit(model, "auto", theta, replace(base, method="auto", theta=theta, rms=res), selection=sel)


def pulled_covariance(f: Fit) -> Fit:
    """The covariance of the estimate with the model file's prior: its noise and the file's error.

    The estimate is ``theta = M theta_LS + (I - M) theta0`` with ``M = (H + P)^-1 H`` (``H =
    R11^T R11`` of the chosen weighting, ``P`` the prior's penalty,
    :class:`~baseparams.ident.select.Selection`), so its error is ``M (theta_LS - theta) + (I -
    M) (theta0 - theta)``: covariance ``M C M^T + (I - M) kappa Sigma0 (I - M)^T`` with ``C`` the
    least-squares covariance (HAC or white), ``Sigma0`` the prior's stated covariance and
    ``kappa >= 0`` its scale estimated from the file's distance to the least-squares estimate
    (maximum likelihood, :func:`~baseparams.ident.select.prior_error_scale`): a term taken from a
    file the data contradict is as uncertain as that file, not as certain as the prior's weight
    alone would say.

    Parameters
    ----------
    f : Fit
        The fit (``auto`` with a prior; others are returned as they are).

    Returns
    -------
    Fit
        The fit with the covariance ``(p, p)`` and its label.
    """
    from dataclasses import replace

    from .select import prior_error_scale
    from .uncertainty import psd, with_covariance

    sel, est = f.selection, f.estimate
    if sel is None or sel.penalty is None or getattr(est, "cov", None) is None or f.physical is not None:
        return f
    gram = est.R11.T @ est.R11
    m = np.linalg.solve(gram + sel.penalty, gram)
    nb = f.model.analysis.n_base
    cov = psd(est.cov)  # rounding on an ill-conditioned fit can make the sandwich indefinite
    kappa = float("nan")
    if sel.prior_cov is not None and sel.theta0 is not None:
        d = np.linalg.solve(est.R11, est.r12)[:nb] - sel.theta0[:nb]
        kappa = prior_error_scale(d, cov[:nb, :nb], sel.prior_cov[:nb, :nb])
    rest = np.eye(len(m)) - m
    if np.isfinite(kappa):
        how = f"the file's error as the data show it: about {np.sqrt(kappa / sel.lam):.2g} x each body's scales"
    else:
        how = "the file's error as the prior states it: the data are too ill-conditioned to measure it"
    prior_cov = sel.prior_cov if sel.prior_cov is not None else np.zeros_like(cov)
    prior_cov = (kappa if np.isfinite(kappa) else 1.0) * prior_cov
    if sel.drive_cov is not None:
        prior_cov = prior_cov + sel.drive_cov
    cov = psd(m @ cov @ m.T + rest @ prior_cov @ rest.T)
    label = (f"{est.covariance}, with the model file's prior (weight {sel.lam:g}; {how})" if sel.lam else
             f"{est.covariance}")
    if sel.drive_cov is not None and np.any(sel.drive_cov):
        label += "; drive terms with a weak prior towards zero (std: the torque each could explain alone)"
    return replace(f, estimate=with_covariance(est, f.theta, cov, label), selection=replace(sel, kappa=kappa))


#: a term is poorly determined when its std exceeds this percentage of its value ...
POORLY_DETERMINED_PCT = 100.0
#: ... and collinearity with the other terms inflates its std more than this factor
POORLY_DETERMINED_INFLATION = 10.0


def poorly_determined(est, names: list[str]) -> list[str]:
    """The terms the data do not determine: std above their value, inflated by collinearity.

    A term's inflation is ``std_k ||A_k|| / (sqrt(n_obs) rho)`` (``A_k`` its weighted regressor
    column, ``rho`` the weighted residual RMS): about ``sqrt(VIF_k)``, 1 for a column orthogonal
    to the others. A term whose value is near zero but known to within the noise (inflation
    near 1) is determined, whatever its %sigma.

    Parameters
    ----------
    est : Estimate
        The estimate (``std``, ``pct_sigma``, ``R11``, ``weights``, ``rms``, ``samples``).
    names : list of str, shape ``(p,)``
        The terms' names.

    Returns
    -------
    list of str
        The poorly determined terms, in model order.
    """
    w = np.asarray(est.weights, dtype=float)
    rho = float(np.sqrt(np.sum((np.asarray(est.rms) * w) ** 2) / max(len(w), 1)))
    n_obs = max(int(est.samples) * len(w), 1)
    infl = np.asarray(est.std) * np.linalg.norm(est.R11, axis=0) / np.sqrt(n_obs) / max(rho, np.finfo(float).tiny)
    pct = np.asarray(est.pct_sigma, dtype=float)
    return [n for n, s, i in zip(names, pct, infl)
            if not s <= POORLY_DETERMINED_PCT and not i <= POORLY_DETERMINED_INFLATION]
#: a body's identified mass "moved far" from the model file's beyond this factor either way
MASS_FACTOR = 2.0


def _masses_moved(robot: Robot, masses: np.ndarray) -> dict:
    """Bodies whose physically consistent mass is beyond :data:`MASS_FACTOR` of the model file's."""
    prior = robot.N_body[:, 3, 3]
    out = {}
    for name, m0, m in zip(robot.names, prior, masses):
        if m0 > 0 and not (m0 / MASS_FACTOR <= m <= m0 * MASS_FACTOR):
            out[name] = {"file": float(m0), "identified": float(m)}
    return out


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
        ``{"rms": {joint: float}, "rms_total": float, "samples", "t_start", "t_end", "source",
        "measure"}``: predicted minus raw measured torques at every training sample (the
        validation's measure); ``fit_rms``, ``fit_rms_total``: the same on the fit's own rows
        (filtered and decimated as fitted), when computed.
    validation : dict, optional
        The same on held-out data, or ``None``.
    notes : tuple of str
        Every decision taken on the data and the model, one line each.
    series : dict, optional
        ``{"train": {...}, "validation": {...} or None}``, each ``{"t" (S,), "tau" (S, m),
        "tau_hat" (S, m), "joints" (m,)}``: the filtered measured and predicted torques (plots);
        ``train`` also has ``"spectrum"``: the excitation spectrum of the training positions
        (:func:`position_spectrum`).
    options : dict, optional
        How the model was built and the data prepared, what :meth:`save` writes and
        :meth:`load` rebuilds the model from: ``{"method", "convention", "rows", "rotor",
        "friction" (tuple), "coulomb_width", "couplings" (tuple of MotorCoupling), "cutoff" [Hz],
        "decimate", "min_speed"}``.
    motion : dict, optional
        ``{"condition_number", "samples"}``: the condition number of the training motion's model
        regressor at the log's (filtered) states, unweighted, every sample, column-scaled: the
        measure ``excite`` reports for a design (:func:`baseparams.ident.estimate.motion_factor`);
        None when not computed (a streamed log).
    truth : dict, optional
        The comparison with a simulation's true parameters (:meth:`compare_truth`), when
        :func:`baseparams.identify` was given ``truth``; in :meth:`to_json` as ``truth``.
    """

    fit: Fit
    samples: dict
    train: dict
    validation: dict | None
    notes: tuple[str, ...]
    series: dict | None = None
    options: dict | None = None
    motion: dict | None = None
    truth: dict | None = None

    def predict(self, log, smooth: bool = True, columns=None) -> np.ndarray:
        """Predicted joint torques at every sample of a log (its own time stamps).

        ``smooth`` (default): the model's torques on the log's states low-passed with the
        identification's cutoff (zero-phase on the log's time base; rates it lacks derived from
        the filtered ``q``): the states the fit was computed from, without the measurement noise
        of the logged rates. The torques themselves are not filtered, so Coulomb friction keeps
        its steps. A function of the logged motion only (no torque enters). ``smooth=False``: the
        model's torques on the states as logged (rates it lacks derived as above).

        No sample is dropped: the first and last ``2 fs / cutoff`` samples carry the filter's
        edge transient (:func:`baseparams.ident.results.log_states`).

        Parameters
        ----------
        log : JointLog, str or path
            ``S`` samples of the model's measured joints (``tau`` may be ``None``), or a log or
            trajectory file (read for this robot by :func:`baseparams.io.logs.read_log`, ``tau``
            columns optional).
        smooth : bool
            Filtered states (default), or the states as logged.
        columns : str, path or dict, optional
            A layout mapping for a log file (README "Log layout").

        Returns
        -------
        ndarray, shape ``(S, m)``
            Predicted torques [N m or N]: columns the measured joints in the model's order
            (:attr:`joints`), rows the log's samples.

        Raises
        ------
        BaseparamsError
            A log missing a measured joint, too short or too slowly sampled for the cutoff.
        """
        import os

        from ..arguments import ArgumentTypeError, check_flags
        from ..jointlog import JointLog

        check_flags("predict", smooth=smooth)
        if columns is not None and not isinstance(columns, (str, os.PathLike, dict)):
            raise ArgumentTypeError(f"predict: columns= must be a TOML file, a dict or a topic, got "
                                    f"{type(columns).__name__}")
        if columns is not None and not isinstance(log, (str, os.PathLike)):
            raise BaseparamsError("predict: columns= maps the columns of a log file; log is a JointLog already")
        if isinstance(log, (str, os.PathLike)):
            from ..io.logs import read_log

            log = read_log(log, self.model.robot, columns=columns, allow_subset=True, require_tau=False)
        elif not isinstance(log, JointLog):
            raise ArgumentTypeError(f"predict: log must be a log file's path or a JointLog, got {type(log).__name__}")
        return predict_log(self.fit, log.checked(), (self.options or {}).get("cutoff"), smooth)

    @property
    def joints(self) -> list[str]:
        """The measured joints ``(m,)``, the columns of :meth:`predict`."""
        r = self.model.robot
        return [r.joint_names[r.dof_body[c]] for c in self.model.coords]

    def compare_truth(self, truth: dict, source: str = "truth") -> dict:
        """Compare with the true parameters of a simulation (``OUT.truth.json``).

        Parameters
        ----------
        truth : dict
            :func:`~baseparams.ident.simulate.simulate_log`'s truth.
        source : str
            Its file, for messages.

        Returns
        -------
        dict
            Per term ``true, estimate, error, std, z`` (:func:`baseparams.ident.results.compare_truth`).
        """
        from .results import compare_truth

        return compare_truth(self.model.names, self.fit.theta, self.fit.estimate.std, truth, source)

    def document(self) -> dict:
        """The JSON object :meth:`save` writes (:mod:`baseparams.ident.results` describes it).

        Returns
        -------
        dict
            Format, version, the robot's name and fingerprint, the options, the model
            parameters' names, values and std, the readable tables, the estimate's statistics
            and triangular factor, the physical fit, counts and notes.
        """
        from dataclasses import fields

        from ..version import version
        from .results import FORMAT, VERSION, numbers, robot_fingerprint

        r = self.model.analysis.source_robot
        opts = dict(self.options or {})
        opts["friction"] = list(opts.get("friction", ()))
        opts["couplings"] = [{"name": c.name, "joints": list(c.joints), "weights": list(c.weights)}
                             for c in opts.get("couplings", ())]
        est = self.fit.estimate
        phys = self.fit.physical
        body = self.to_json()
        doc = {"format": FORMAT, "version": VERSION, "baseparams": version(),
               "robot": {"name": r.name, "fingerprint": robot_fingerprint(r), "bodies": r.n, "dof": r.dof,
                         "parameters": 10 * r.n, "joints": self.joints},
               "options": opts,
               "parameters": {"names": list(self.model.names), "values": numbers(self.fit.theta),
                              "std": numbers(est.std)},
               "base_parameters": body["base_parameters"], "drives": body["drives"], "couplings": body["couplings"],
               "estimate": {f.name: (numbers(getattr(est, f.name)) if isinstance(getattr(est, f.name), np.ndarray)
                                     else getattr(est, f.name)) for f in fields(est) if f.name != "pct_sigma"},
               "physical": None if phys is None else {
                   f.name: (numbers(getattr(phys, f.name)) if isinstance(getattr(phys, f.name), np.ndarray)
                            else list(getattr(phys, f.name)) if isinstance(getattr(phys, f.name), tuple)
                            else getattr(phys, f.name)) for f in fields(phys)},
               "samples": self.samples, "train": self.train, "validation": self.validation, "notes": list(self.notes),
               "terms": [t.to_json(self.joints) for t in self.fit.terms],
               "term_choices": [{"name": c.name, "kept": c.kept, "why": c.why, "cv_rms": c.cv_rms}
                                for c in self.fit.term_choices],
               "motion": self.motion}
        return _plain(doc)

    def save(self, path, inputs=(), what: str = "output"):
        """Write the result to a JSON file (atomically; :func:`baseparams.files.write_text`).

        Parameters
        ----------
        path : str or path
            The file (``RESULT.json``).
        inputs : iterable of str or path
            The run's input files, which the output must not overwrite.
        what : str
            The output's role, for messages (``--save``).

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        BaseparamsError
            An output onto an input, a missing folder, a non-regular target.
        """
        import json

        from ..files import write_text

        return write_text(path, json.dumps(self.document(), indent=1, allow_nan=False) + "\n", inputs, what)

    @classmethod
    def load(cls, path, robot: Robot) -> Identification:
        """Read a saved result back, for the robot it was identified on.

        The model is rebuilt from the saved options (analysis, drive model and regrouping, as
        :func:`identify` built it) and its parameter names checked against the saved ones; the
        values, statistics, counts and notes are the saved ones (``series`` is not saved:
        ``None``).

        Parameters
        ----------
        path : str or path
            The file (:meth:`save`).
        robot : Robot
            The model: its structure's fingerprint must be the saved one.

        Returns
        -------
        Identification
            The result; :meth:`predict` gives the same torques as the saved object's.

        Raises
        ------
        BaseparamsError
            No such file, another format, another version, another robot (both fingerprints
            named), or a model whose rebuilt parameters differ from the saved ones.
        """
        from .drives import MotorCoupling
        from .estimate import Estimate
        from .physical import PhysicalFit
        from .results import array, check_robot, read_document

        doc = read_document(path)  # checked against baseparams.schema.RESULT: types, shapes, finite values
        check_robot(doc, robot, str(path))
        o = dict(doc["options"])
        o["friction"] = tuple(o.get("friction", ()))
        o["couplings"] = tuple(MotorCoupling(c["name"], tuple(c["joints"]), tuple(c["weights"]))
                               for c in o.get("couplings", ()))
        model = ident_model(analyze(robot, convention=o["convention"], rows=o.get("rows", "all"),
                                    literal=bool(o.get("literal", False))), o["rotor"],
                            o["friction"], o.get("coulomb_width"), couplings=o["couplings"],
                            log_base=robot.floating)
        names = doc["parameters"]["names"]
        if list(model.names) != list(names):
            diff = next((f"{a} vs {b}" for a, b in zip(model.names, names) if a != b),
                        f"{len(model.names)} vs {len(names)} parameters")
            raise BaseparamsError(f"{path}: the model rebuilt for {robot.name!r} has other parameters than the "
                                  f"saved ones ({diff}); saved by another baseparams version?")
        theta = array(doc["parameters"]["values"])
        e = doc["estimate"]
        std = array(e["std"])
        with np.errstate(divide="ignore", invalid="ignore"):
            pct = 100 * std / np.abs(theta if e.get("cov") is not None else array(e["theta"]))
        extra = {k: e[k] for k in ("covariance",) if e.get(k) is not None}
        if e.get("cov") is not None:
            extra["cov"] = array(e["cov"])
        est = Estimate(e["method"], array(e["theta"]), std, pct, array(e["weights"]), array(e["rms"]),
                       float(e["rms_total"]), float(e["condition_number"]), int(e["samples"]), array(e["R11"]),
                       array(e["r12"]), **extra)
        phys = None
        if doc.get("physical") is not None:
            p = doc["physical"]
            phys = PhysicalFit(**{k: (array(v) if isinstance(v, list) and k != "notes" else
                                      tuple(v) if k == "notes" else v) for k, v in p.items()})
        from .terms.fit import Choice
        from .terms.registry import make_term

        joints = [robot.joint_names[robot.dof_body[c]] for c in model.coords]
        terms = []
        for t in doc.get("terms") or ():
            term = make_term(t["name"], bool(t.get("forced", False)))
            term.load(t, joints, model)
            term.std = dict(t.get("std") or {})
            terms.append(term)
        choices = tuple(Choice(c["name"], bool(c["kept"]), str(c["why"]),
                               float("nan") if c.get("cv_rms") is None else float(c["cv_rms"]))
                        for c in doc.get("term_choices") or ())
        f = Fit(model, o.get("method", e["method"]), theta, est, phys, terms=tuple(terms), term_choices=choices)
        return cls(f, doc["samples"], doc["train"], doc["validation"], (*doc["notes"], *doc["_notes"]), None, o,
                   doc.get("motion"))

    @property
    def model(self) -> IdentModel:
        """The identified model."""
        return self.fit.model

    def __repr__(self) -> str:
        m = self.model
        held = self.validation is not None
        rms = (self.validation if held else self.train)["rms_total"]
        return clip(f"<Identification {m.robot.name}: {self.fit.method}, {m.n_base} base + {m.n_drive} drive terms, "
                    f"{'held-out' if held else 'training'} RMS {format_number(rms, 3)} {m.torque_unit}>")

    @property
    def names(self) -> np.ndarray:
        """Names of every identified term ``(p,)``: base parameters, then drive terms.

        The order of :attr:`values`, :attr:`std`, :meth:`table` and :meth:`to_frame`; the names of
        :meth:`base_parameters` and (``<kind>_<joint>``) of :meth:`drives` and :meth:`couplings`.
        """
        return np.array(self.model.names, dtype=object)  # Python strings, as pandas holds them

    @property
    def values(self) -> np.ndarray:
        """The identified values ``(p,)`` in :attr:`names`' order (SI units, the analysis's convention)."""
        return np.array(self.fit.theta, dtype=float)

    @property
    def std(self) -> np.ndarray:
        """Standard deviations ``(p,)`` of :attr:`values` (the least-squares estimate's)."""
        return np.array(self.fit.estimate.std, dtype=float)

    def _columns(self) -> dict[str, list]:
        """Every identified term's name, kind, value, std, %sigma and expression, in :attr:`names`' order."""
        m = self.model
        nb = len(m.analysis.base_names)
        base = {b["name"]: b["expression"] for b in self.base_parameters()}
        exprs = m.regrouping.expressions()
        kinds = ["base" if i < nb else "drive" for i in m.regrouping.independent]
        names = list(m.names)
        return {"name": names, "kind": kinds, "value": self.values.tolist(), "std": self.std.tolist(),
                "pct_sigma": np.asarray(self.fit.estimate.pct_sigma, dtype=float).tolist(),
                "expression": [base[n] if k == "base" else e for n, k, e in zip(names, kinds, exprs)]}

    def table(self) -> str:
        """Every identified term as a text table.

        Returns
        -------
        str
            Columns ``name, kind, value, std, pct_sigma, expression``, one row per term in
            :attr:`names`' order (values at 6 significant digits, std and %sigma at 3).
        """
        return text_table(self._columns(), digits={"value": 6, "std": 3, "pct_sigma": 3})

    def to_frame(self):
        """Every identified term as a pandas DataFrame (pandas is optional).

        Returns
        -------
        pandas.DataFrame
            Columns ``name, kind`` (``base`` or ``drive``), ``value, std, pct_sigma,
            expression``; one row per term in :attr:`names`' order, values at full precision.

        Raises
        ------
        BaseparamsError
            pandas is not installed.
        """
        return data_frame(self._columns())

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
        return [self._terms({"joint": joint}, joint, ("Ia", "Fv", "Fc", "Fo"), m.drives.kinds)
                for joint in m.drives.joints]

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
        return [self._terms({"name": c.name, "joints": dict(zip(c.joints, c.weights))}, c.name,
                            ("Iam", "Fvm", "Fcm"), m.drives.coupled_kinds) for c in m.drives.couplings]

    def _terms(self, entry: dict, owner: str, kinds, modelled) -> dict:
        """``entry`` with each drive term ``KIND_owner``: value and std, None or regrouped.

        ``None`` when the kind is not modelled, ``"regrouped into <base parameter>"`` when the
        data cannot separate it.
        """
        m = self.model
        pos = {name: k for k, name in enumerate(m.names)}
        absorbed = {m.regrouping.names[d]: m.regrouping.names[i]
                    for row, i in enumerate(m.regrouping.independent)
                    for col, d in enumerate(m.regrouping.dependent) if m.regrouping.K[row, col] != 0}
        entry["std"] = {}
        for kind in kinds:
            name = f"{kind}_{owner}"
            if kind not in modelled:
                entry[kind] = None
            elif name in pos:
                entry[kind] = float(self.fit.theta[pos[name]])
                entry["std"][kind] = float(self.fit.estimate.std[pos[name]])
            else:
                entry[kind] = f"regrouped into {absorbed.get(name, '?')}"
        return entry

    def to_json(self) -> dict:
        """One JSON-able object (schema in the README's identification section).

        Returns
        -------
        dict
            ``method, estimator, selection, covariance, model, convention, n_samples{read, used, removed},
            condition_number,
            excitation{condition_number, of, fitted_condition_number, weak, poorly_determined,
            above_100, all_excited}, base_parameters, drives, couplings,
            train, validation, physical, notes, terms``; ``condition_number`` is the training motion's
            (:attr:`motion`: the measure ``excite`` reports, ``of`` says ``"motion"``; ``"fitted
            rows"`` when not computed), ``fitted_condition_number`` the fitted rows' (filtered,
            decimated, weighted as fitted); ``weak`` names the parameters carrying directions whose
            singular value is below 1e-3 of the largest (column-scaled fitted rows); ``above_100``
            the terms whose %sigma exceeds 100 (``all_excited`` needs none); ``covariance`` says how
            every ``std`` was computed.
        """
        f = self.fit
        phys = None
        if f.physical is not None:
            p = f.physical
            phys = {"feasible": bool(p.feasible), "min_eigenvalue": float(np.min(p.min_eigenvalues)),
                    "masses": {b: float(v) for b, v in zip(self.model.robot.names, p.masses)},
                    "solver_status": str(p.solver_status)}
        from .estimate import excitation

        fitted, weak = excitation(f.estimate.R11, self.model.names)
        cond = fitted if self.motion is None else float(self.motion["condition_number"])
        loose = poorly_determined(f.estimate, self.model.names)
        pct = np.asarray(f.estimate.pct_sigma, dtype=float)
        above = [n for n, x in zip(self.model.names, pct) if not x <= POORLY_DETERMINED_PCT]
        if phys is not None:
            phys["masses_moved"] = _masses_moved(self.model.robot, f.physical.masses)
        sel = f.selection
        estimator = f.method if sel is None else (f"{f.method}: {sel.weighting.upper()}" + (
            f" with the model file's prior, weight {sel.lam:g}" if sel.lam else ""))
        if sel is not None and sel.estimator == "physical":
            estimator = f"{f.method}: physically consistent (cross-validated against {sel.weighting.upper()}"
            estimator += f" with the file's prior, weight {sel.lam:g})" if sel.lam else ")"
        return {"method": f.method, "estimator": estimator, "selection": None if sel is None else sel.to_json(),
                "covariance": f.estimate.covariance,
                "model": self.model.robot.name, "convention": self.model.analysis.convention,
                "n_samples": self.samples, "condition_number": cond,
                "excitation": {"condition_number": cond, "of": "fitted rows" if self.motion is None else "motion",
                               "fitted_condition_number": fitted, "weak": weak, "poorly_determined": loose,
                               "above_100": above, "all_excited": not weak and not loose and not above},
                "base_parameters": self.base_parameters(), "drives": self.drives(),
                "couplings": self.couplings(), "train": self.train,
                "validation": self.validation, "physical": phys, "notes": list(self.notes),
                "terms": self.terms_json(), **({"truth": self.truth} if self.truth is not None else {})}

    def terms_json(self) -> list[dict]:
        """Every model term tried: kept or rejected, why, its cross-validated figure, values and std.

        Returns
        -------
        list of dict
            ``{"name", "kept", "why", "cv_rms", "values", "std", "description"}`` per term tried
            (``values``, ``std`` and ``description`` for the kept ones), in the order tried.
        """
        kept = {t.name: t for t in self.fit.terms}
        out = []
        for c in self.fit.term_choices:
            entry = {"name": c.name, "kept": c.kept, "why": c.why,
                     "cv_rms": None if not np.isfinite(c.cv_rms) else float(c.cv_rms)}
            t = kept.get(c.name)
            if t is not None:
                entry.update(values=t.values(self.joints), std=t.std, description=t.describe(self.joints))
            out.append(entry)
        return out


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


def log_rows(robot: Robot) -> str:
    """The generalized forces a joint log measures: ``"joints"`` with a floating base (no base wrench), else all.

    Parameters
    ----------
    robot : Robot
        The model.

    Returns
    -------
    str
        ``"joints"`` or ``"all"``.
    """
    return "joints" if robot.floating else "all"


def floating_notes(robot: Robot) -> list[str]:
    """What a floating base's identification from a joint log assumes (one line), else nothing.

    Parameters
    ----------
    robot : Robot
        The model.

    Returns
    -------
    list of str
        Notes for the report.
    """
    if not robot.floating:
        return []
    return ["floating base: the base's motion is the log's pose and twist; the joint torques are modelled with no "
            "external force on any other link (a foot on the ground pushes: measured contact wrenches belong on the "
            "measured side, baseparams.kinematics.wrench_forces in Python), the base wrench is not measured"]


#: two drive columns of one joint whose cosine exceeds this cannot be told apart by the log
COLLINEAR_COS = 0.99


def drive_notes(f: Fit, acc) -> list[str]:
    """Drive terms to say something about: negative friction or rotor inertia, pairs the log cannot separate.

    A pair of one joint's drive terms whose columns on its rows have a cosine above
    :data:`COLLINEAR_COS` (Coulomb friction and offset of a joint that hardly reverses) is named,
    with how it was resolved: by the drive terms' weak prior (the default and physical
    estimates: the smallest values that fit) or not at all (plain least squares). Negative
    viscous or Coulomb friction or rotor inertia (only plain least squares can give them) is named.

    Parameters
    ----------
    f : Fit
        The fit.
    acc : RowAccumulator
        Its rows.

    Returns
    -------
    list of str
        Notes, one line each.
    """
    from .physical import NONNEGATIVE_KINDS

    model = f.model
    nb = len(model.analysis.base_names)
    kinds = model.drives.param_kinds
    plain = f.method in ("ols", "wls")
    drive = {k: kinds[i - nb] for k, i in enumerate(model.regrouping.independent) if i >= nb}
    notes = []
    negative = [f"{model.names[k]} = {f.theta[k]:.3g}" for k, kind in drive.items()
                if kind in NONNEGATIVE_KINDS and f.theta[k] < 0]
    if negative:
        notes.append(f"NEGATIVE drive terms ({', '.join(negative)}): friction and rotor inertia cannot be negative; "
                     f"plain least squares (--method {f.method}) fits what the log shows (a poorly excited joint or "
                     f"a model error); the default and physical estimates keep them >= 0")
    seen = set()
    for fr in acc.factors:
        g = fr.r.T @ fr.r
        ks = [k for k in drive if g[k, k] > 0]
        for a_i, a in enumerate(ks):
            for b in ks[a_i + 1:]:
                cos = abs(g[a, b]) / np.sqrt(g[a, a] * g[b, b])
                if cos <= COLLINEAR_COS or (a, b) in seen:
                    continue
                seen.add((a, b))
                how = ("plain least squares: their separate values are not meaningful, only their sum on this motion"
                       if plain else f"resolved by the drive terms' weak prior: {model.names[a]} = {f.theta[a]:.3g}, "
                       f"{model.names[b]} = {f.theta[b]:.3g}")
                notes.append(f"{model.names[a]} and {model.names[b]} cannot be told apart by this log (their columns' "
                             f"cosine {cos:.4f}: the joint hardly reverses or hardly moves); {how}")
    return notes


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


def term_note(tf, joints: list[str]) -> str:
    """One line: every model term tried, kept or rejected, with its cross-validated figure and values.

    Parameters
    ----------
    tf : TermsFit
        :func:`~baseparams.ident.terms.fit.select_terms`'s outcome.
    joints : list of str
        The measured joints.

    Returns
    -------
    str
        The note.
    """
    kept = {t.name: t for t in tf.terms}
    parts = []
    for c in tf.choices:
        if c.kept:
            parts.append(f"{c.name} KEPT ({c.why}): {kept[c.name].describe(joints)}")
        else:
            parts.append(f"{c.name} rejected ({c.why})")
    return (f"model terms (blocked cross-validation on the training data, linear core alone {tf.cv_rms:.4g}): "
            + "; ".join(parts))


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


def check_log_units(model: IdentModel, log, cols, allow_units: bool) -> list[str]:
    """Units and plausibility of the log before any fit (:func:`~baseparams.ident.plausibility.check_units`).

    Parameters
    ----------
    model : IdentModel
        The model (its robot's own torques are the comparison).
    log : JointLog
        The (training) log.
    cols : ndarray of int, shape ``(state_columns,)``
        Log column of each state column.
    allow_units : bool
        Go on with a warning note instead of refusing.

    Returns
    -------
    list of str
        Notes for the report.

    Raises
    ------
    DataError
        Units that look wrong, unless ``allow_units``.
    """
    from ..analysis import regressor
    from ..errors import DataError
    from .plausibility import check_units

    robot = model.robot
    params = robot.parameters("paper")
    coords = np.asarray(robot.actuated, dtype=int) if robot.has_loops else np.arange(robot.dof)
    revolute = np.array([robot.jtype[robot.dof_body[c]] == "R" or (model.log_base and 3 <= c < 6) for c in coords])

    def torques(q, dq, ddq):
        if not model.log_base:
            return regressor(robot, q, dq, ddq) @ params
        from ..kinematics.floating import robot_states

        tau = regressor(robot, *robot_states(robot, q, dq, ddq)) @ params
        tau[:, :6] = 0.0  # the base wrench is not measured (the log's zeros)
        return tau

    try:
        limits = None if robot.limits is None else np.asarray(robot.limits, dtype=float)[coords]
        return check_units(log, cols, torques, revolute, limits)
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


def report_series(model: IdentModel, prep, cols: np.ndarray, theta, names: list[str], memory_mb: float,
                  raw_q: np.ndarray | None = None):
    """Measured and predicted torques of a prepared log, as they were compared (filtered).

    Parameters
    ----------
    model : IdentModel
        The model.
    prep : Prepared
        The prepared log.
    cols : ndarray of int, shape ``(state_columns,)``
        Log column of each state column.
    theta : ndarray, shape ``(p,)``, or Fit
        The identified values, or the fit (with its model terms; ``raw_q`` then gives the
        unfiltered positions on ``prep.full``'s grid for Dahl's state).
    names : list of str, shape ``(m,)``
        The measured joints.
    memory_mb : float
        Largest regressor formed at once (beyond, the predicted torques are not parallel-filtered).
    raw_q : ndarray, shape ``(S, m)``, optional
        With a fit whose terms need them: the measured coordinates' unfiltered positions.

    Returns
    -------
    dict
        ``{"t" (S',), "tau" (S', m), "tau_hat" (S', m), "joints" (m,)}`` at the kept samples.
    """
    full = prep.full
    q, dq, ddq = full.q[:, cols], full.dq[:, cols], full.ddq[:, cols]
    fit_ = theta if isinstance(theta, Fit) else None
    if fit_ is not None and fit_.terms:
        raw = q[:, model.row_states] if raw_q is None else raw_q
        tau_hat = prep.apply(model_torques(fit_, full.t, raw, q, dq, ddq))
        return {"t": prep.t, "tau": prep.tau[:, cols[model.row_states]], "tau_hat": tau_hat, "joints": names}
    theta = fit_.theta if fit_ is not None else theta
    size_mb = full.n_samples / prep.stride * len(model.coords) * model.n_params * 8 / 1e6
    if size_mb <= memory_mb:
        from . import chunks

        tau_hat = chunks.prepared_rows(model, prep, cols) @ theta
    else:
        idx = prep.index
        tau_hat = np.concatenate([model.regressor(q[idx[k:k + 20000]], dq[idx[k:k + 20000]],
                                                  ddq[idx[k:k + 20000]]) @ theta for k in range(0, len(idx), 20000)])
    return {"t": prep.t, "tau": prep.tau[:, cols[model.row_states]], "tau_hat": tau_hat, "joints": names}


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
    from ..kinematics.floating import BASE_COORDINATES

    r = model.robot
    coords = np.asarray(r.actuated, dtype=int) if r.has_loops else np.arange(r.dof)
    wanted = [BASE_COORDINATES[c] if r.jtype[r.dof_body[c]] == "F" else r.joint_names[r.dof_body[c]] for c in coords]
    where = {j: k for k, j in enumerate(log.joints)}
    missing = [j for j in wanted if j not in where]
    if missing and r.floating and missing[0] == BASE_COORDINATES[0]:
        raise BaseparamsError(f"{log.source}: robot {r.name!r} has a floating base and the log has no base pose "
                              "(columns base_x, base_y, base_z, base_qw, base_qx, base_qy, base_qz: README, "
                              "Log layout)")
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
    from .estimate import RowAccumulator

    full = prep.full
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

    grid = chunks.Grid(full.n_samples, prep.design.pad, prep.factor, prep.design.cutoff, min_speed,
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
    return chunks.combine(parts), (f"parallel filtering in {len(parts)} chunks of {size} samples with "
                                   f"{margin}-sample overlaps (equal to the whole log's to rounding)")


def _plain(x):
    """Numpy scalars and tuples as JSON types; non-finite floats as ``None``."""
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    return x


def model_notes(model: IdentModel) -> list[str]:
    """One line per drive parameter regrouped into a base parameter.

    Parameters
    ----------
    model : IdentModel
        The model.

    Returns
    -------
    list of str
        ``regrouped: <expression>`` lines.
    """
    a = model.analysis
    practical = [] if a.practical is None else [a.practical.note(a.n_base).replace(
        "; the literal count: --literal", "; these directions are not fitted (identify --literal fits them)")]
    return practical + [f"regrouped: {e}" for e in model.regrouping.expressions() if " + " in e or " - " in e]


def predict_log(f: Fit, log, cutoff: float | None, smooth: bool = True) -> np.ndarray:
    """Predicted torques ``(S, m)`` at every sample of ``log`` (:meth:`Identification.predict`).

    Parameters
    ----------
    f : Fit
        The identified values (and model terms).
    log : JointLog
        ``S`` samples of the measured joints.
    cutoff : float or None
        The identification's low-pass cutoff [Hz] (None: the log's default).
    smooth : bool
        Filtered states (default), or the states as logged.

    Returns
    -------
    ndarray, shape ``(S, m)``
        Columns the measured joints in the model's order.
    """
    from .results import log_states

    cols = log_columns(f.model, log)
    q, dq, ddq, _ = log_states(log, cutoff, smooth)
    return model_torques(f, log.t, log.q[:, cols[f.model.row_states]], q[:, cols], dq[:, cols], ddq[:, cols])


def model_torques(f: Fit, t: np.ndarray, q_raw: np.ndarray, q: np.ndarray, dq: np.ndarray,
                  ddq: np.ndarray) -> np.ndarray:
    """The fitted model's torques as the sensors measure them, the model terms included.

    The core ``A(q, dq, ddq) theta`` (:meth:`Fit.predict`, in blocks), each term's contribution (Dahl's state along
    ``q_raw``, the tilt's gravity torque), then the sensors' scales and delays
    (:mod:`baseparams.ident.terms`).

    Parameters
    ----------
    f : Fit
        The fit.
    t : ndarray, shape ``(S,)``
        Time stamps [s] (the delays shift along them).
    q_raw : ndarray, shape ``(S, m)``
        Positions of the measured coordinates as logged (unfiltered).
    q, dq, ddq : ndarray, shape ``(S, state_columns)``
        The states.

    Returns
    -------
    ndarray, shape ``(S, m)``
        Predicted measured torques.
    """
    with blas_threads():
        tau = f.predict(q, dq, ddq)  # in blocks of PREDICT_BYTES
    for term in f.terms:
        tau = term.adjust_model(f, q_raw, q, dq, ddq, tau)
    for term in f.terms:
        tau = term.adjust_measured(np.asarray(t, dtype=float), tau)
    if not np.isfinite(tau).all():  # values or states beyond floating point: never NaN predictions
        from ..errors import DataError

        i = int(np.argmax(~np.isfinite(tau).all(axis=1)))
        raise DataError(f"the predicted torques are not finite from sample {i} on (t = {float(t[i]):.6g} s): the "
                        f"log's states or the values are beyond floating point")
    return tau


def validation_scores(log, pred: np.ndarray, names: list[str], mask=None, score_cutoff: float | None = None) -> dict:
    """Held-out error the way an outsider measures it: against the raw measured torques.

    Parameters
    ----------
    log : JointLog
        The log whose samples were predicted (``S`` samples, measured torques ``tau``).
    pred : ndarray, shape ``(S, m)``
        Predicted torques of the measured joints ``names`` (:func:`predict_log`).
    names : list of str, shape ``(m,)``
        The measured joints, in ``pred``'s column order.
    mask : ndarray of bool, shape ``(S,)``, optional
        The held-out samples (default: all).
    score_cutoff : float, optional
        Also score against the measured torques low-passed at this cutoff [Hz] (zero-phase
        Butterworth order 4 on the held-out samples).

    Returns
    -------
    dict
        ``rms`` (per joint), ``rms_total`` (over every held-out sample and joint), ``samples``,
        ``t_start``, ``t_end``, ``source``, ``measure``; with ``score_cutoff`` also
        ``score_cutoff``, ``rms_lowpassed`` and ``rms_lowpassed_total``.
    """
    from .results import lowpass_at

    mask = np.ones(log.n_samples, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    where = {j: k for k, j in enumerate(log.joints)}
    measured = log.tau[:, [where[j] for j in names]][mask]
    err = pred[mask] - measured
    out = {"rms": dict(zip(names, np.sqrt(np.mean(err**2, axis=0)).tolist())),
           "rms_total": float(np.sqrt(np.mean(err**2))), "samples": int(mask.sum()),
           "t_start": float(log.t[mask][0]), "t_end": float(log.t[mask][-1]), "source": log.source,
           "measure": "RMS of predicted minus raw measured torques at every held-out sample"}
    if score_cutoff is not None:
        try:
            lp = lowpass_at(log.t[mask], measured, float(score_cutoff))
        except BaseparamsError as exc:
            raise BaseparamsError(f"--score-cutoff {score_cutoff:g} Hz on {log.source}'s held-out samples: "
                                  f"{exc}") from None
        e2 = pred[mask] - lp
        out.update({"score_cutoff": float(score_cutoff),
                    "rms_lowpassed": dict(zip(names, np.sqrt(np.mean(e2**2, axis=0)).tolist())),
                    "rms_lowpassed_total": float(np.sqrt(np.mean(e2**2)))})
    return out
