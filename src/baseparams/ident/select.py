"""The default estimate: least squares pulled towards the model file, as much as the data ask.

A log that excites some directions poorly lets least squares fit noise along them: the fit is
good on the recording and poor on another one. The default (``method="auto"``) is the Bayesian
(maximum a posteriori) estimate with the model file's parameters ``theta_0`` as the prior::

    min  ||R11 theta - r12||^2 + lam * s2 * (theta - theta_0)^T S^-1 (theta - theta_0)

``S`` is the prior covariance of the base parameters: each body's ten inertial parameters in its
link frame (``khalil`` order) get standard deviations ``m``, ``m L`` and ``m L^2`` for its mass,
first and second moments (``m`` the file's mass, ``L`` the body's radius of gyration about its
frame, both floored), mapped to the base parameters through the regrouping
(``S = G J D J^T G^T``, :func:`prior_covariance`; a body whose file mass or inertia is zero
gets no prior). ``s2`` is the residual variance of the
(weighted) least-squares fit and ``lam = 1 / alpha^2``: the file is trusted to within ``alpha``
times those scales. A parameter the data determine to well within the prior's scale keeps its
least-squares value (its shrink is ``var_LS / (var_LS + alpha^2 var_prior)``), a direction the
data leave undetermined takes the file's value: unlike a pull proportional to each column's
information, well-excited logs are not biased towards a file that may be poor. Drive terms
(friction, offsets, rotor) have no prior: the file has none.

The row weighting (OLS, or WLS with per-joint noise) and ``lam`` (0 = no pull is a candidate)
are chosen by **blocked cross-validation on the training data**: the training rows are cut
into ``K`` contiguous time blocks (serially correlated samples stay together), each block is
predicted from the others (unweighted RMS, the measure a user checks), and the pair with the
smallest median RMS over the folds is kept: a fold whose held-out block brings what the others
lack (a short log's only reversal of a joint, extrapolated through its Coulomb and offset
columns, can be off by 1e5) cannot decide alone. Only the training
data are used; the factors are the streamed ``(p + 1, p + 1)`` triangles of each block, so
memory does not grow with the log.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .estimate import RowAccumulator, stacked_factor
from .uncertainty import psd

#: candidate weights ``lam = 1 / alpha^2`` of the prior (module docstring); 0 = no pull
LAMBDAS = (0.0, 0.01, 0.1, 1.0, 10.0, 100.0)
#: number of contiguous blocks of the cross-validation
FOLDS = 5
#: the row weightings tried
WEIGHTINGS = ("ols", "wls")
#: what a cross-validation fold is -> how every note and report says it (one home: the default estimate's choice,
#: the model terms', rotor inertia's and the text report's heading): contiguous blocks of one motion, or whole
#: recordings (several in one identification, each another motion)
FOLD_SCOPES = {"blocks": "blocked cross-validation on the training data",
               "recordings": "cross-validation with each recording one fold"}


def fold_scope(unit: str) -> str:
    """How the notes and reports name a cross-validation whose folds are ``unit``.

    Parameters
    ----------
    unit : {"blocks", "recordings"}
        Contiguous blocks of one log, or whole recordings (several in one identification).

    Returns
    -------
    str
        The words (:data:`FOLD_SCOPES`).
    """
    return FOLD_SCOPES[unit]


@dataclass(frozen=True, eq=False)
class Selection:
    """The outcome of the cross-validation.

    Parameters
    ----------
    weighting : str
        The rows' weighting chosen: ``ols`` or ``wls``.
    lam : float
        The chosen weight of the prior (0: none).
    lambdas : tuple of float
        The candidate weights.
    cv_rms : dict of str to tuple of float
        Median over the folds of each candidate weight's held-out RMS, per weighting [N m or N,
        unweighted].
    folds : int
        Number of contiguous blocks.
    penalty : ndarray, shape ``(p, p)``, optional
        ``lam * s2 * S^-1`` (zero rows and columns for the drive terms) of the chosen pair, in the
        chosen weighting's units; ``None`` when ``lam = 0``.
    theta0 : ndarray, shape ``(p,)``, optional
        The prior's values (the model file's parameters).
    prior_cov : ndarray, shape ``(p, p)``, optional
        The prior's covariance ``S / lam`` as the penalty states it (zero for the drive terms).
    kappa : float, optional
        The file's error in units of ``prior_cov`` as the data show it
        (:func:`prior_error_scale`; NaN: not measurable), once the covariance is computed.
    no_prior : tuple of str
        Bodies the file gives no mass or inertia: left to the data (:func:`no_prior_bodies`).
    scope : str
        What was cross-validated, for the note (a fleet's blocks are whole logs).
    drive_cov : ndarray, shape ``(p, p)``, optional
        The drive terms' weak prior as a covariance (diagonal ``sigma_k^2``,
        :func:`drive_precision`; zero elsewhere).
    physical_cv : float, optional
        Median over the folds of the physically consistent estimate's held-out RMS (None when
        not tried: the ``ident`` extra missing, or too few blocks).
    estimator : str
        ``least squares`` (the weighting and prior above) or ``physical`` (the physically
        consistent estimate predicted the held-out blocks better, or the rule chose it).
    rule : str
        What decided (:data:`baseparams.ident.fitting.RULES`): ``blocks`` (cross-validation on
        contiguous blocks of one motion), ``recordings`` (each block a whole recording) or
        ``structure`` (no cross-validation: the blocks are too short to see beyond the motion; the
        prior's weight then comes from ``kappa_evidence``).
    kappa_evidence : float, optional
        ``structure`` only: the file's error as the whole training span shows it
        (:func:`prior_error_scale`), whose inverse set ``lam``.
    """

    weighting: str
    lam: float
    lambdas: tuple[float, ...]
    cv_rms: dict
    folds: int
    penalty: np.ndarray | None = field(default=None, repr=False)
    theta0: np.ndarray | None = field(default=None, repr=False)
    prior_cov: np.ndarray | None = field(default=None, repr=False)
    kappa: float | None = None
    no_prior: tuple = ()
    scope: str = FOLD_SCOPES["blocks"]
    drive_cov: np.ndarray | None = field(default=None, repr=False)
    physical_cv: float | None = None
    estimator: str = "least squares"
    rule: str = "blocks"
    kappa_evidence: float | None = None

    def __repr__(self) -> str:
        if self.rule == "structure":
            return f"<Selection: {self.estimator}, prior weight {self.lam:g} by the evidence (blocks too short)>"
        return (f"<Selection: {self.weighting.upper()}, prior weight {self.lam:g} of {len(self.lambdas)} by "
                f"{self.folds}-fold {self.scope}>")

    def to_json(self) -> dict:
        """The choice, machine-readable.

        Returns
        -------
        dict
            ``weighting, lam, lambdas, cv_rms{weighting: [...]}, folds, kappa, no_prior, physical_cv,
            estimator``.
        """
        k, ke = self.kappa, self.kappa_evidence
        return {"weighting": self.weighting, "lam": self.lam, "lambdas": list(self.lambdas),
                "cv_rms": {w: list(v) for w, v in self.cv_rms.items()}, "folds": self.folds,
                "kappa": None if k is None or not np.isfinite(k) else float(k), "no_prior": list(self.no_prior),
                "physical_cv": self.physical_cv, "estimator": self.estimator, "rule": self.rule,
                "kappa_evidence": None if ke is None or not np.isfinite(ke) else float(ke)}

    def _structure_note(self) -> str:
        """:meth:`note` when no cross-validation decided (``rule="structure"``)."""
        k = self.kappa_evidence
        seen = ("the data cannot measure the file's error (too ill-conditioned): the weakest candidate weight"
                if k is None or not np.isfinite(k) else
                f"the file is off by about {np.sqrt(k):.2g} x each body's scales as the whole training span shows it "
                f"(empirical Bayes), weight 1 / {k:.3g} within [{min(x for x in self.lambdas if x > 0):g}, "
                f"{max(self.lambdas):g}]")
        what = ("physically consistent least squares (every body's pseudo-inertia positive semidefinite, friction "
                "and rotor inertia >= 0; the data do not agree with the file closely enough to lean on it)"
                if self.estimator == "physical" else
                f"{self.weighting.upper()} (the data agree with the file: least squares leaning on it)")
        return (f"default estimate: {what} with the model file's parameters as a prior, weight {self.lam:g} ({seen}); "
                f"chosen by the rule for short motions, not by cross-validation: its blocks each span less than a "
                f"period of the motion's bandwidth, so they cannot tell which estimate predicts another motion "
                f"(several recordings in one identification, or a longer one, let cross-validation choose)")

    def note(self) -> str:
        """One line for the report: what was chosen and why.

        Returns
        -------
        str
            The weighting, the prior's weight, the number of blocks and the held-out RMS with
            and without the prior.
        """
        if self.rule == "structure":
            return self._structure_note()
        rms = self.cv_rms[self.weighting]
        best, plain = rms[self.lambdas.index(self.lam)], rms[0]
        other = [w for w in self.cv_rms if w != self.weighting]
        alt = "".join(f", {w.upper()} {min(self.cv_rms[w]):.4g}" for w in other)
        how = "weighted (per joint)" if self.weighting == "wls" else "ordinary"
        if self.no_prior:
            alt += f"; no prior for {', '.join(self.no_prior)} (no mass or inertia in the file)"
        if self.physical_cv is not None:
            alt += f"; physically consistent {self.physical_cv:.4g}"
        if self.estimator == "physical":
            return (f"default estimate: physically consistent least squares (every body's pseudo-inertia positive "
                    f"semidefinite, friction and rotor inertia >= 0, a log-det pull towards the model file), chosen "
                    f"by {self.folds}-fold {self.scope} (more than 5 % better): held-out RMS {self.physical_cv:.4g}, "
                    f"least squares "
                    f"{best:.4g} ({how}, prior weight {self.lam:g}){alt.split('; physically')[0]}")
        if self.lam == 0:
            return (f"default estimate: {how} least squares, chosen by {self.folds}-fold {self.scope} "
                    f"(held-out RMS {plain:.4g}{alt}); the model file's parameters as a prior did not predict better")
        return (f"default estimate: {how} least squares with the model file's parameters as a prior, trusted to "
                f"within {1 / np.sqrt(self.lam):.3g} x each body's mass and size scales (weight {self.lam:g}): "
                f"terms the data determine keep their fitted values, the others move towards the file; chosen by "
                f"{self.folds}-fold {self.scope} (held-out RMS {best:.4g}, without the prior {plain:.4g}{alt})")


def ridge(r11: np.ndarray, r12: np.ndarray, theta0: np.ndarray, penalty: np.ndarray | None) -> np.ndarray:
    """The regularised solution ``(R11^T R11 + P)^-1 (R11^T r12 + P theta0)`` (module docstring).

    Parameters
    ----------
    r11 : ndarray, shape ``(p, p)``
        Triangular factor of the (weighted) regressor.
    r12 : ndarray, shape ``(p,)``
        Its right-hand side.
    theta0 : ndarray, shape ``(p,)``
        The prior (the model file's parameters in the model's parameterisation).
    penalty : ndarray, shape ``(p, p)``, optional
        ``P``, symmetric positive semidefinite (``None``: least squares).

    Returns
    -------
    ndarray, shape ``(p,)``
        The estimate.
    """
    return solve(r11, r12, theta0, penalty)


def solve(r11: np.ndarray, r12: np.ndarray, theta0: np.ndarray, penalty: np.ndarray | None,
          nonneg: np.ndarray | None = None) -> np.ndarray:
    """:func:`ridge` with some terms kept non-negative (friction, rotor inertia).

    ``min ||R11 theta - r12||^2 + (theta - theta0)^T P (theta - theta0)`` subject to
    ``theta[nonneg] >= 0``: the unconstrained solution when it is admissible, else the active-set
    solution of the normal equations (:func:`bounded_quadratic`).

    Parameters
    ----------
    r11 : ndarray, shape ``(p, p)``
        Triangular factor of the (weighted) regressor.
    r12 : ndarray, shape ``(p,)``
        Its right-hand side.
    theta0 : ndarray, shape ``(p,)``
        The prior's values.
    penalty : ndarray, shape ``(p, p)``, optional
        ``P``, symmetric positive semidefinite.
    nonneg : ndarray of bool, shape ``(p,)``, optional
        The terms kept ``>= 0``.

    Returns
    -------
    ndarray, shape ``(p,)``
        The estimate.
    """
    h = r11.T @ r11
    g = r11.T @ r12
    if penalty is not None:
        h = h + penalty
        g = g + penalty @ theta0
    return bounded_quadratic(h, g, nonneg)


def bounded_quadratic(h: np.ndarray, g: np.ndarray, nonneg: np.ndarray | None = None) -> np.ndarray:
    """``argmin 1/2 x^T h x - g^T x`` subject to ``x[nonneg] >= 0`` (an active-set method).

    Lawson and Hanson's active set on the normal equations: variables that come out negative are
    held at 0, one that the gradient would move up is released, until both hold. The unbounded
    variables are eliminated first (their Schur complement), so each step is one dense solve of the
    bounded ones (a 60-link chain: 180 drive terms instead of 596 parameters, ~30x cheaper).

    Parameters
    ----------
    h : ndarray, shape ``(p, p)``
        Symmetric positive (semi)definite.
    g : ndarray, shape ``(p,)``
        The linear term.
    nonneg : ndarray of bool, shape ``(p,)``, optional
        The variables kept ``>= 0``.

    Returns
    -------
    ndarray, shape ``(p,)``
        The minimiser.
    """

    def lin(a, b):
        try:
            return np.linalg.solve(a, b)
        except np.linalg.LinAlgError:
            return np.linalg.lstsq(a, b, rcond=None)[0]

    x = lin(h, g)
    if nonneg is None or not np.any(nonneg) or np.all(x[nonneg] >= 0):
        return x
    nonneg = np.asarray(nonneg, dtype=bool)
    if not nonneg.all():  # free variables eliminated once (Schur complement): the active set on the bounded ones
        u, v = np.flatnonzero(~nonneg), np.flatnonzero(nonneg)
        z = lin(h[np.ix_(u, u)], np.column_stack([h[np.ix_(u, v)], g[u]]))
        hv = h[np.ix_(v, v)] - h[np.ix_(v, u)] @ z[:, :-1]
        xv = bounded_quadratic((hv + hv.T) / 2, g[v] - h[np.ix_(v, u)] @ z[:, -1], np.ones(len(v), dtype=bool))
        x = np.empty_like(g)
        x[v], x[u] = xv, z[:, -1] - z[:, :-1] @ xv
        return x
    scale = max(float(np.max(np.abs(g))), 1e-300)
    active = np.asarray(nonneg, dtype=bool) & (x < 0)
    for _ in range(4 * len(g) + 10):
        free = ~active
        x = np.zeros_like(g)
        x[free] = lin(h[np.ix_(free, free)], g[free])
        bad = nonneg & free & (x < 0)
        if bad.any():
            active |= bad
            continue
        grad = h @ x - g
        release = active & (grad < -1e-10 * scale)
        if not release.any():
            return x
        active[int(np.argmin(np.where(release, grad, np.inf)))] = False
    x[nonneg] = np.maximum(x[nonneg], 0.0)
    return x


def nonnegative_terms(model) -> np.ndarray:
    """The model parameters kept ``>= 0``: rotor inertia, viscous and Coulomb friction not regrouped.

    Parameters
    ----------
    model : IdentModel
        The model.

    Returns
    -------
    ndarray of bool, shape ``(p,)``
        True for a drive parameter of kind ``Ia``, ``Fv``, ``Fc`` (or a coupled motor's) that
        stands alone (a regrouped one is part of a base parameter, which has any sign).
    """
    from .physical import NONNEGATIVE_KINDS

    nb = len(model.analysis.base_names)
    kinds = model.drives.param_kinds
    return np.array([i >= nb and kinds[i - nb] in NONNEGATIVE_KINDS for i in model.regrouping.independent],
                    dtype=bool)


def drive_precision(model, acc: RowAccumulator, weights: np.ndarray | None = None) -> np.ndarray:
    """A weak prior on the drive terms: zero, within the torque they could explain alone.

    Drive parameter ``k`` (a column ``a_k`` on its rows) gets the prior ``N(0, sigma_k^2)`` with
    ``sigma_k = ||tau|| / ||a_k||`` over its rows: the value at which it would explain the whole
    measured torque alone (a Coulomb term: the torque's RMS). A term the data determine (its
    least-squares variance far below ``sigma_k^2``) keeps its fitted value; a pair the log cannot
    separate (Coulomb friction and offset of a joint that never reverses, an offset and a gravity
    term of a joint that hardly moves) takes the smallest values that fit instead of large
    opposite ones. Returned as precisions ``1 / sigma_k^2``, to be multiplied by the residual
    variance like the file's prior (:func:`select`).

    Parameters
    ----------
    model : IdentModel
        The model.
    acc : RowAccumulator
        The training rows (their factors give every column's and torque's norm per row).
    weights : ndarray, shape ``(m,)``, optional
        Row weights (``sigma_k`` is a ratio: the same weighted or not, for one-row terms).

    Returns
    -------
    ndarray, shape ``(p, p)``
        Diagonal, zero for the base parameters.
    """
    p = model.n_params
    w = np.ones(acc.nrows) if weights is None else np.asarray(weights, dtype=float)
    norms2 = acc.column_norms2() * (w**2)[:, None]
    col2, tau2 = norms2[:, :p], norms2[:, p]
    nb = len(model.analysis.base_names)
    out = np.zeros((p, p))
    for k, i in enumerate(model.regrouping.independent):
        if i < nb:
            continue
        rows = col2[:, k] > 0
        a2, t2 = float(col2[rows, k].sum()), float(tau2[rows].sum())
        if a2 > 0 and t2 > 0:
            out[k, k] = a2 / t2
    return out


def full_prior_covariance(robot) -> np.ndarray:
    """The prior covariance of the standard parameters at ``alpha = 1`` (module docstring).

    Parameters
    ----------
    robot : Robot
        The model file's robot (``n`` bodies).

    Returns
    -------
    ndarray, shape ``(10 n, 10 n)``
        Block diagonal, one ``(10, 10)`` block per body: ``J D^2 J^T`` with ``D`` the standard
        deviations ``m L^2`` (second moments), ``m L`` (first moments), ``m`` (mass) in the body's
        link frame and ``J`` the map to the ``paper`` convention (world frame at q = 0).
    """
    n = robot.n
    kh = robot.parameters("khalil").reshape(n, 10)  # XX XY XZ YY YZ ZZ MX MY MZ M, link frame
    mass = np.abs(kh[:, 9])
    second = kh[:, 0] + kh[:, 3] + kh[:, 5]
    given = no_prior_bodies(robot) == 0
    moving = mass[given]
    m_floor = 0.05 * (float(np.median(moving)) if moving.size else 1.0)
    m = np.maximum(mass, m_floor)
    gyr = np.sqrt(np.maximum(second, 0.0) / (2.0 * m))
    sizes = gyr[given & (gyr > 0)]
    length = np.maximum(gyr, 0.25 * (float(np.median(sizes)) if sizes.size else 0.1))
    # a body the file gives no mass or no inertia: practically no prior (30 x the robot's largest
    # mass, 3 x its largest size: its directions are the data's)
    m = np.where(given, m, 30.0 * float(m[given].max() if given.any() else 1.0))
    length = np.where(given, length, 3.0 * float(length[given].max() if given.any() else 0.1))
    std = np.column_stack([np.repeat((m * length**2)[:, None], 6, axis=1),
                           np.repeat((m * length)[:, None], 3, axis=1), m]).reshape(n, 10)
    # J: khalil (link frames) -> paper (world frame at q = 0), block diagonal: one column per slot
    jac = np.zeros((n, 10, 10))
    for k in range(10):
        unit = np.zeros((n, 10))
        unit[:, k] = 1.0
        jac[:, :, k] = robot.with_parameters(unit.reshape(-1), "khalil").parameters("paper").reshape(n, 10)
    blocks = np.einsum("bij,bj,bkj->bik", jac, std**2, jac)
    out = np.zeros((10 * n, 10 * n))
    for b in range(n):
        out[10 * b:10 * b + 10, 10 * b:10 * b + 10] = blocks[b]
    return out


def prior_covariance(model) -> np.ndarray:
    """``S``: the prior covariance of the base parameters at ``alpha = 1`` (module docstring).

    Parameters
    ----------
    model : IdentModel
        The model: its robot's file parameters and the regrouping ``G``
        (:meth:`~baseparams.ident.model.IdentModel.full_map`).

    Returns
    -------
    ndarray, shape ``(n_base, n_base)``
        Symmetric positive definite; base parameters in the model's order and convention.
    """
    n = model.robot.n
    g = model.full_map()[: model.n_base, : 10 * n]
    s = g @ full_prior_covariance(model.robot) @ g.T
    s = 0.5 * (s + s.T)
    return s + 1e-12 * max(float(np.trace(s)) / max(len(s), 1), 1e-300) * np.eye(len(s))


def complete(model, theta: np.ndarray) -> np.ndarray:
    """Standard parameters with the given base parameters, the closest to the model file's.

    The maximum a posteriori ``pi`` given ``G pi = theta_base`` under the prior
    ``N(pi_0, Sigma)`` (:func:`full_prior_covariance`): ``pi_0 + Sigma G^T (G Sigma G^T)^-1
    (theta_base - G pi_0)``. Directions the base parameters do not see keep the file's values.

    Parameters
    ----------
    model : IdentModel
        The model.
    theta : ndarray, shape ``(p,)``
        Model parameters (only the base ones are used; a drive term regrouped into a base
        parameter is lumped into the bodies' parameters).

    Returns
    -------
    ndarray, shape ``(10 n,)``
        ``paper`` convention (world frame at q = 0).
    """
    nb = model.n_base
    cache = model.__dict__.get("_completion")
    if cache is None:
        g = model.full_map()[:nb, : 10 * model.robot.n]
        pi0 = model.robot.parameters("paper")
        gs = g @ full_prior_covariance(model.robot)
        cache = (g @ pi0, pi0, gs.T @ np.linalg.pinv(gs @ g.T, hermitian=True))
        model.__dict__["_completion"] = cache  # IdentModel is frozen: cached like its column map
    g_pi0, pi0, gain = cache
    return pi0 + gain @ (np.asarray(theta, dtype=float)[:nb] - g_pi0)


def no_prior_bodies(robot) -> np.ndarray:
    """Bodies the model file gives no inertia: zero mass or zero rotational inertia.

    Parameters
    ----------
    robot : Robot
        The model.

    Returns
    -------
    ndarray of bool, shape ``(n,)``
        True where the file's mass or the trace of its second moments is zero: the prior
        leaves those bodies to the data (:func:`prior_covariance`).
    """
    kh = robot.parameters("khalil").reshape(robot.n, 10)
    return (np.abs(kh[:, 9]) <= 0) | (kh[:, 0] + kh[:, 3] + kh[:, 5] <= 0)


def prior_precision(model, s: np.ndarray | None = None) -> np.ndarray:
    """``S^-1`` on the base parameters, zero on the drive terms.

    Parameters
    ----------
    model : IdentModel
        The model.
    s : ndarray, shape ``(n_base, n_base)``, optional
        ``S`` when already computed (:func:`prior_covariance`).

    Returns
    -------
    ndarray, shape ``(p, p)``
        Symmetric positive semidefinite.
    """
    nb = model.n_base
    out = np.zeros((model.n_params, model.n_params))
    s = prior_covariance(model) if s is None else s
    try:
        c = np.linalg.cholesky(s)
        inv = np.linalg.solve(c.T, np.linalg.solve(c, np.eye(nb)))
    except np.linalg.LinAlgError:
        inv = np.linalg.pinv(s, hermitian=True)
    out[:nb, :nb] = 0.5 * (inv + inv.T)
    return out


def system_of(acc: RowAccumulator, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The weighted least-squares system of accumulated rows and its residual variance.

    Parameters
    ----------
    acc : RowAccumulator
        The rows.
    weights : ndarray, shape ``(m,)``
        Row weights.

    Returns
    -------
    r11 : ndarray, shape ``(p, p)``
        Triangular factor.
    r12 : ndarray, shape ``(p,)``
        Its right-hand side.
    s2 : float
        The weighted residual variance (:func:`noise_variance`) per independent sample (times the
        rows' :attr:`~baseparams.ident.estimate.RowAccumulator.oversampling`): what the priors are
        weighted with.
    """
    r11, r12, rho2, n_obs = _system([acc], weights)
    return r11, r12, noise_variance(r11, rho2, n_obs) * acc.oversampling


def _system(blocks: list[RowAccumulator], weights: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, int]:
    p = blocks[0].nparams
    acc = RowAccumulator.combine(blocks)  # each block's stacked factor once per weighting (cached)
    r = stacked_factor(acc, weights)
    r = np.vstack([r, np.zeros((max(p + 1 - r.shape[0], 0), p + 1))])
    return r[:p, :p], r[:p, p], float(r[p, p] ** 2), acc.samples * acc.nrows


def _sse(block: RowAccumulator, theta: np.ndarray) -> float:
    return float(np.sum(block.row_sse(theta)))


def noise_variance(r11: np.ndarray, rho2: float, n_obs: int) -> float:
    """``s2``: the residual variance of the (weighted) least-squares fit.

    Parameters
    ----------
    r11 : ndarray, shape ``(p, p)``
        Triangular factor.
    rho2 : float
        Residual sum of squares of the least-squares fit.
    n_obs : int
        Number of observations.

    Returns
    -------
    float
        ``rho2 / (n_obs - p)`` (``rho2 / n_obs`` when not positive).
    """
    dof = n_obs - r11.shape[0]
    return rho2 / dof if dof > 0 else rho2 / max(n_obs, 1)


def select(blocks: list[RowAccumulator], weightings: dict, theta0: np.ndarray, precision: np.ndarray,
           lambdas=LAMBDAS, drive_prec: np.ndarray | None = None, nonneg: np.ndarray | None = None
           ) -> Selection | None:
    """Choose the rows' weighting and the prior's weight by blocked cross-validation.

    Parameters
    ----------
    blocks : list of RowAccumulator
        The training rows of each contiguous time block, in time order.
    weightings : dict of str to ndarray, shape ``(m,)``
        Row weights of each candidate weighting (``ols``: ones; ``wls``: ``1 / sigma_r``).
    theta0 : ndarray, shape ``(p,)``
        The prior.
    precision : ndarray, shape ``(p, p)``
        ``S^-1`` (:func:`prior_precision`): zero for the terms without a prior.
    lambdas : sequence of float
        Candidate weights, 0 first.
    drive_prec : ndarray, shape ``(p, p)``, optional
        The drive terms' weak prior (:func:`drive_precision`), in every candidate.
    nonneg : ndarray of bool, shape ``(p,)``, optional
        Terms kept ``>= 0`` (:func:`nonnegative_terms`).

    Returns
    -------
    Selection or None
        None when there are fewer than 2 usable blocks (nothing to cross-validate).
    """
    blocks = [b for b in blocks if b.samples > 0]
    if len(blocks) < 2:
        return None
    cands, fold_rms, s2 = [], [], {}
    counts = np.array([b.samples * b.nrows for b in blocks], dtype=float)
    for name, w in weightings.items():
        r11, _, rho2, n_obs = _system(blocks, w)
        s2[name] = noise_variance(r11, rho2, n_obs) * max(b.oversampling for b in blocks)  # per independent sample
        sse = np.zeros((len(lambdas), len(blocks)))
        for k, held in enumerate(blocks):
            a11, a12, _, _ = _system(blocks[:k] + blocks[k + 1:], w)
            for i, lam in enumerate(lambdas):
                pen = penalty_of(lam, s2[name], precision, drive_prec)
                sse[i, k] = _sse(held, solve(a11, a12, theta0, pen, nonneg))
        for i in range(len(lambdas)):
            cands.append((name, i))
            fold_rms.append(np.sqrt(sse[i] / np.maximum(counts, 1)))
    rms = np.array(fold_rms)  # (candidates, folds)
    # the median over the folds: one fold whose held-out block brings what the others lack (a
    # short log's only reversal of a joint, extrapolated through its Coulomb and offset columns)
    # cannot decide alone
    med = np.median(np.where(np.isfinite(rms), rms, np.inf), axis=1)
    best = min(range(len(cands)), key=lambda c: (med[c], cands[c][1]))  # ties: the weaker prior
    name, i = cands[best]
    cv = {w: tuple(float(med[c]) for c in range(len(cands)) if cands[c][0] == w) for w in weightings}
    lam = float(lambdas[i])
    return Selection(name, lam, tuple(float(x) for x in lambdas), cv, len(blocks),
                     penalty_of(lam, s2[name], precision, drive_prec))


def penalty_of(lam: float, s2: float, precision: np.ndarray, drive_prec: np.ndarray | None = None
               ) -> np.ndarray | None:
    """The penalty ``s2 (lam S^-1 + D)`` of a candidate: the file's prior and the drive terms' weak one.

    Parameters
    ----------
    lam : float
        The file prior's weight (0: none).
    s2 : float
        The residual variance.
    precision : ndarray, shape ``(p, p)``
        ``S^-1`` (:func:`prior_precision`).
    drive_prec : ndarray, shape ``(p, p)``, optional
        ``D`` (:func:`drive_precision`).

    Returns
    -------
    ndarray, shape ``(p, p)``, or None
        None when both are absent.
    """
    pen = lam * precision if lam else None
    if drive_prec is not None and np.any(drive_prec):
        pen = drive_prec if pen is None else pen + drive_prec
    return None if pen is None else s2 * pen


def fold_parts(a: np.ndarray, tau: np.ndarray, folds: int = FOLDS, oversampling: float = 1.0) -> list[RowAccumulator]:
    """The cross-validation's blocks of fitted rows: ``folds`` consecutive pieces, split by count.

    Parameters
    ----------
    a : ndarray, shape ``(S, m, p)``
        Fitted (filtered, decimated) regressor rows, in time order.
    tau : ndarray, shape ``(S, m)``
        Their torques.
    folds : int
        Number of blocks.
    oversampling : float
        The rows' :attr:`~baseparams.ident.estimate.RowAccumulator.oversampling`.

    Returns
    -------
    list of RowAccumulator
        One accumulator per block.
    """
    out = [RowAccumulator(a.shape[1], a.shape[2]).add(a[idx], tau[idx]) for idx in np.array_split(np.arange(len(a)),
                                                                                                    folds)]
    for b in out:
        b.oversampling = float(oversampling)
    return out


def split_blocks(acc_parts: list[RowAccumulator], folds: int = FOLDS) -> list[RowAccumulator]:
    """Group consecutive accumulators (time-ordered chunks) into at most ``folds`` blocks.

    Parameters
    ----------
    acc_parts : list of RowAccumulator
        Time-ordered pieces of the training rows.
    folds : int
        Number of blocks wanted.

    Returns
    -------
    list of RowAccumulator
        ``min(folds, len(acc_parts))`` blocks.
    """
    k = min(folds, len(acc_parts))
    groups = np.array_split(np.arange(len(acc_parts)), k)
    out = []
    for g in groups:
        out.append(RowAccumulator.combine([acc_parts[i] for i in g]))
    return out


def prior_error_scale(d: np.ndarray, cov_ls: np.ndarray, prior_cov: np.ndarray) -> float:
    """``kappa >= 0``: the file's error in units of the prior's stated covariance, from the data.

    Under the prior, ``d = theta_LS - theta0 ~ N(0, C + kappa Sigma0)`` on the base parameters;
    ``kappa`` is its maximum-likelihood value (empirical Bayes): in ``C``-whitened coordinates
    where ``Sigma0`` is ``diag(g)``, it maximises ``-sum log(1 + kappa g_i) - sum d_i^2 / (1 +
    kappa g_i)`` (the first zero of its derivative; 0 when the derivative is not positive at 0),
    so the directions the data determine well (large ``g_i``) say how far the file is from the
    truth. 0 when the data agree with the file to within their own noise; large when
    the file is further off than the cross-validated weight states.

    Parameters
    ----------
    d : ndarray, shape ``(nb,)``
        Least-squares estimate minus the prior, base parameters.
    cov_ls : ndarray, shape ``(nb, nb)``
        Covariance ``C`` of the least-squares estimate (positive definite).
    prior_cov : ndarray, shape ``(nb, nb)``
        ``Sigma0``, the prior's stated covariance.

    Returns
    -------
    float
        ``kappa`` in ``[0, 1e8]``; NaN when it cannot be estimated (``C`` not positive, or no
        stationary point below 1e8: an ill-conditioned fit).
    """
    w, v = np.linalg.eigh(psd(cov_ls))
    if not np.all(np.isfinite(w)) or w.max() <= 0:
        return float("nan")
    inv_l = (v / np.sqrt(np.maximum(w, w.max() * 1e-12))).T  # C^-1/2 on the numerically positive part
    g, u = np.linalg.eigh(inv_l @ psd(prior_cov) @ inv_l.T)
    g = np.maximum(g, 0.0)
    dt2 = (u.T @ (inv_l @ d)) ** 2

    def score(kappa: float) -> float:  # d loglik / d kappa (times 2)
        a = 1.0 + kappa * g
        return float(np.sum(g * (dt2 / a**2 - 1.0 / a)))

    if score(0.0) <= 0:
        return 0.0  # the data agree with the file to within their own noise
    grid = np.logspace(-6, 8, 57)
    signs = np.array([score(k) for k in grid])
    down = np.flatnonzero(signs <= 0)
    if not down.size:
        return float("nan")  # beyond any plausible scale: the data cannot say
    k = int(down[0])
    lo, hi = (np.log10(grid[k - 1]) if k else -12.0), np.log10(grid[k])
    for _ in range(60):  # bisection on the first stationary point (continuous in the data)
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if score(10.0**mid) > 0 else (lo, mid)
    return float(10.0 ** (0.5 * (lo + hi)))



def physical_cv(model, blocks: list[RowAccumulator], weights: np.ndarray, drive_prec: np.ndarray,
                prior_weight: float | None = None) -> float | None:
    """Median over the folds of the physically consistent estimate's held-out RMS.

    The same contiguous blocks as :func:`select`: each predicted from the physical fit
    (:func:`~baseparams.ident.physical.physical_fit`) on the others, WLS-weighted with the whole
    training span's weights and drive prior.

    Parameters
    ----------
    model : IdentModel
        The model.
    blocks : list of RowAccumulator
        The training rows' contiguous blocks.
    weights : ndarray, shape ``(m,)``
        WLS row weights.
    drive_prec : ndarray, shape ``(nd,)``
        The drive terms' weak prior in the weighted fit's units (per drive parameter).
    prior_weight : float, optional
        The physical fit's prior weight.

    Returns
    -------
    float or None
        The median RMS (unweighted, like :func:`select`'s), or None without cvxpy or with fewer
        than 2 blocks.
    """
    from ..errors import BaseparamsError
    from .physical import physical_fit

    blocks = [b for b in blocks if b.samples > 0]
    if len(blocks) < 2:
        return None
    try:
        import cvxpy  # noqa: F401
    except ImportError:
        return None
    kw = {} if prior_weight is None else {"prior_weight": prior_weight}
    rms = []
    g = model.full_map()
    for k, held in enumerate(blocks):
        a11, a12, _, _ = _system(blocks[:k] + blocks[k + 1:], weights)
        try:
            ph = physical_fit(a11, a12, g, model.robot, model.drives.param_kinds, drive_precision=drive_prec, **kw)
        except BaseparamsError:
            return None
        rms.append(np.sqrt(_sse(held, ph.theta) / max(held.samples * held.nrows, 1)))
    return float(np.median(rms))
