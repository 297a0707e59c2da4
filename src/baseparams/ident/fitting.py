"""The estimators' values and their statistics: which estimate, how certain.

:class:`Fit` holds the identified values of an :class:`~baseparams.ident.model.IdentModel` and
predicts the core torques; :func:`fit` chooses the estimate (OLS, WLS, the default estimate with the
model file's prior, the physically consistent fit) on accumulated rows;
:func:`pulled_covariance` gives the covariance of an estimate pulled towards the model file;
:func:`poorly_determined` names the terms the data do not determine.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..display import clip, format_number
from ..errors import BaseparamsError
from .model import REGRESSOR_BYTES, IdentModel
from .select import FOLD_SCOPES, fold_scope

#: bytes of regressor :meth:`Fit.predict` forms at once
PREDICT_BYTES = REGRESSOR_BYTES


@dataclass(frozen=True, eq=False)
class Fit:
    """Identified values of an :class:`~baseparams.ident.model.IdentModel`.

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
        blocks = [a @ self.theta for _, a in self.model.regressor_blocks(q, dq, ddq, PREDICT_BYTES)]
        return blocks[0] if len(blocks) == 1 else np.concatenate(blocks)

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


def fit(model: IdentModel, acc, method: str = "ols", prior_weight: float | None = None,
        mass_bounds=None, blocks=None, estimator: str | None = None, rule: str = "blocks") -> Fit:
    """Estimate the model parameters from accumulated data.

    Parameters
    ----------
    model : IdentModel
        The model.
    acc : RowAccumulator
        The data (:func:`~baseparams.ident.rows.accumulate`).
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
    rule : {"blocks", "recordings", "structure"}
        ``auto`` only: what chooses the estimate (:data:`RULES`). ``blocks``: cross-validation on
        ``blocks``, contiguous pieces of one motion; ``recordings``: the same, each block a whole
        recording (another motion); ``structure``: no cross-validation (the blocks are too short to
        see beyond the motion): the physically consistent fit, pulled towards the model file with the
        weight the data's own distance to it sets (:func:`_structural`).

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
    if method == "auto" and estimator is None and physical_left_out(model):
        estimator = "least squares"
    if method == "auto" and rule == "structure":
        return _structural(model, est, acc, prior_weight, estimator)
    if method == "auto":
        fitted = _auto(model, first, est, acc, blocks or [], prior_weight, estimator)
        if fitted.selection is not None and rule != "blocks":
            fitted = replace(fitted, selection=replace(fitted.selection, rule=rule, scope=fold_scope(rule)))
        return fitted
    if method != "physical":
        return Fit(model, method, est.theta, est)
    from .physical import physical_fit

    kwargs = {} if prior_weight is None else {"prior_weight": prior_weight}
    kwargs["drive_precision"] = _drive_precision_delta(model, acc, est)
    phys = physical_fit(est.R11, est.r12, model.full_map(), model.robot, model.drives.param_kinds,
                        mass_bounds=mass_bounds, **kwargs)
    return Fit(model, method, phys.theta, est, phys)


#: the default (``auto``) does not try the physically consistent fit on models of more parameters than this: its
#: conic program (cvxpy/Clarabel, a dense ``p x p`` objective) is solved once per cross-validation block and
#: once more, and costs ~p^3 per iteration (a 220-link chain, 2 196 parameters: ~250 s and ~2 GB of the
#: identification's 910 s and 2.6 GB; a 60-link chain, 660, ~5 s); ``method="physical"`` still fits it
PHYSICAL_AUTO_PARAMS = 1200


def physical_left_out(model: IdentModel) -> str | None:
    """Why the default estimate does not try the physically consistent fit on this model (None: it does).

    Parameters
    ----------
    model : IdentModel
        The model.

    Returns
    -------
    str or None
        One line for the report (:data:`PHYSICAL_AUTO_PARAMS`), or None.
    """
    if model.n_params <= PHYSICAL_AUTO_PARAMS:
        return None
    return (f"default estimate: the physically consistent fit not tried ({model.n_params} parameters, more than "
            f"{PHYSICAL_AUTO_PARAMS}: its conic program, once per cross-validation block, would take minutes and "
            f"gigabytes); least squares with the model file's prior instead (--method physical fits it)")


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
    s2 = rho2 / max(acc.samples * acc.nrows - rank, 1) * acc.oversampling
    prec = np.diag(drive_precision(model, acc))
    # the prior's rows, each on a row whose factor has the term's column (weighted with that row): one more part
    col2 = acc.column_norms2()
    prior = RowAccumulator(acc.nrows, p)
    for r, f in enumerate(prior.factors):
        ks = [k for k in np.flatnonzero(prec > 0) if col2[r, k] > 0]
        if ks:
            extra = np.zeros((len(ks), p + 1))
            extra[np.arange(len(ks)), ks] = np.sqrt(s2 * prec[ks])
            f.add(extra)
    return RowAccumulator.combine([acc, prior])


def _drive_precision_delta(model: IdentModel, acc, est) -> np.ndarray:
    """The drive terms' weak prior (:func:`~baseparams.ident.select.drive_precision`) per drive parameter.

    In the weighted fit's units (``s2 / sigma_k^2``, ``s2`` the weighted residual variance), on the
    drive parameters ``delta`` the physical fit solves for; 0 for a drive parameter regrouped into a
    base parameter (it has no column of its own).
    """
    from .select import drive_precision

    w = np.asarray(est.weights, dtype=float)
    n_obs = max(acc.samples * acc.nrows, 1)
    s2 = float(np.sum((np.asarray(est.rms) * w) ** 2)) * acc.samples / n_obs * acc.oversampling
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
    res = residual_rms(acc, theta)
    # the least-squares statistics stay: pulled_covariance maps the covariance once it is chosen
    return Fit(model, "auto", theta, replace(base, method="auto", theta=theta, rms=res), selection=sel)


#: what chooses the default estimate (:func:`fit`'s ``rule``) -> how the report says it
RULES = {"blocks": FOLD_SCOPES["blocks"],
         "recordings": FOLD_SCOPES["recordings"],
         "structure": "structure: the cross-validation blocks are too short to see beyond the motion"}


#: the structure rule's weight of the model file's prior from which the data agree with the file (the file within
#: 1 / sqrt(2) ~ 0.7 of its scales, as the whole training span shows it): least squares pulled towards the file;
#: below it the physically consistent fit (:func:`_structural`). The weights the evidence gives fall apart: 0.01-0.24
#: where the physically consistent fit predicts another motion better (simulated 7-DoF arms with files 30 % off,
#: the TX40's short span), 9.9-100 where least squares leaning on the file does (the Panda's 6 s span, short logs
#: of exact or rounded files); 2 is near the middle of that gap on a log scale (10, at its edge, flipped the Panda's
#: choice when the log's ends stopped inflating the noise estimate)
TRUSTED_WEIGHT = 2.0


def _structural(model: IdentModel, est, acc, prior_weight=None, estimator=None) -> Fit:
    """The default when within-motion cross-validation cannot choose: the evidence of the whole span decides.

    The model file's prior ``lam * s2 * S^-1`` (:mod:`baseparams.ident.select`) with ``lam = 1 /
    kappa``, ``kappa`` the file's error as the data show it (:func:`~baseparams.ident.select.prior_error_scale`:
    maximum likelihood of the prior's scale from the least-squares estimate's distance to the file,
    over the whole training span: empirical Bayes, no held-out block), within the candidate weights'
    range, plus the drive terms' weak prior. A file the data agree with (``lam >=``
    :data:`TRUSTED_WEIGHT`): WLS pulled towards it with that weight; a file further off: the
    physically consistent fit (:func:`~baseparams.ident.physical.physical_fit`) on the WLS rows stacked
    with that prior (the structure that generalizes when the file cannot anchor the directions one short
    motion leaves loose; measured in ``benchmarks/cross_recording.py``'s generalization table). Without
    the ``ident`` extra, or with ``estimator="least squares"``, least squares with that prior.
    """
    from .select import (
        LAMBDAS,
        Selection,
        drive_precision,
        nonnegative_terms,
        penalty_of,
        prior_covariance,
        prior_error_scale,
        prior_precision,
        solve,
        system_of,
    )

    nb, theta0 = model.n_base, model.theta(model.robot.parameters("paper"))
    w = np.asarray(est.weights, dtype=float)
    r11, r12, s2 = system_of(acc, w)
    s = prior_covariance(model)
    dprec = drive_precision(model, acc)
    h = r11.T @ r11 + s2 * dprec
    theta_ls = solve(r11, r12, theta0, s2 * dprec)
    cov = s2 * np.linalg.pinv(h, hermitian=True)[:nb, :nb]
    kappa = prior_error_scale(theta_ls[:nb] - theta0[:nb], cov, s)
    positive = [x for x in LAMBDAS if x > 0]
    lam = positive[0] if not np.isfinite(kappa) else float(np.clip(1.0 / max(kappa, 1e-300), positive[0],
                                                                      positive[-1]))
    pen = penalty_of(lam, s2, prior_precision(model, s), dprec)
    prior_cov = np.zeros((model.n_params, model.n_params))
    prior_cov[:nb, :nb] = s / lam
    drive_cov = np.diag(np.where(np.diag(dprec) > 0, 1.0 / np.where(np.diag(dprec) > 0, np.diag(dprec), 1.0), 0.0))
    sel = Selection("wls", lam, tuple(float(x) for x in LAMBDAS), {}, 0, penalty=pen, theta0=theta0,
                    prior_cov=prior_cov, scope=RULES["structure"], drive_cov=drive_cov, rule="structure",
                    kappa_evidence=kappa)
    nonneg = nonnegative_terms(model)
    if estimator is None and lam >= TRUSTED_WEIGHT:
        estimator = "least squares"  # the data agree with the file: least squares pulled towards it
    if estimator != "least squares":
        try:
            import cvxpy  # noqa: F401
        except ImportError:
            estimator = "least squares"
    if estimator == "least squares":
        theta = solve(r11, r12, theta0, pen, nonneg)
        return Fit(model, "auto", theta, replace(est, method="auto", theta=theta, rms=residual_rms(acc, theta)),
                   selection=sel)
    from .physical import physical_fit

    ev, vec = np.linalg.eigh(0.5 * (pen + pen.T))
    rows = (vec * np.sqrt(np.maximum(ev, 0.0))).T
    kw = {} if prior_weight is None else {"prior_weight": prior_weight}
    phys = physical_fit(np.vstack([r11, rows]), np.r_[r12, rows @ theta0], model.full_map(), model.robot,
                        model.drives.param_kinds, **kw)
    return Fit(model, "auto", phys.theta, est, phys, selection=replace(sel, estimator="physical"))


def residual_rms(acc, theta: np.ndarray) -> np.ndarray:
    """The RMS residual of each measured row of accumulated data at the values ``theta``.

    Parameters
    ----------
    acc : RowAccumulator
        The rows (one factor per measured row).
    theta : ndarray, shape ``(p,)``
        The values.

    Returns
    -------
    ndarray, shape ``(m,)``
        ``||A_j theta - tau_j|| / sqrt(S)`` per row ``j`` over the accumulated samples.
    """
    return np.sqrt(acc.row_sse(theta)) / np.sqrt(max(acc.samples, 1))


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
