"""Physically consistent least squares: every body's pseudo-inertia positive semidefinite.

The estimator of Wensing, Kim & Slotine (2018) with the log-det (Bregman) prior of Lee,
Wensing & Park (2019, "Geometric robot dynamic identification: a convex programming approach",
IEEE T-RO), posed as a convex conic program and solved by Clarabel through cvxpy (the optional
extra ``pip install 'baseparams[ident]'``; imported only when a fit runs).

Parameters are the paper's (:meth:`~baseparams.model.robot.Robot.parameters` with ``"paper"``):
per body the ten entries ``N11 N12 N13 N22 N23 N33 N14 N24 N34 N44`` (``XX XY XZ YY YZ ZZ MX MY
MZ M``) of its spatial pseudo-inertia ``N_i = [[Sigma, h], [h^T, m]]``, world frame at q = 0,
followed by the drive parameters ``delta`` (rotor inertia ``Ia``, viscous ``Fv``, Coulomb ``Fc``
friction, offset ``Fo``). The data arrive compressed: ``theta = G @ phi`` with
``phi = [pi; delta]`` and the fit ``||R11 @ theta - r12||^2`` (the QR of the stacked system).

The program
-----------
minimise over ``N_i`` (symmetric 4x4) and ``delta``::

    ||R11 G phi - r12||^2 / s                                  (fit; s = ||r12||^2)
      + w * sum_i D(N_i || N_i0)                               (log-det prior)
      + w * sum_k c_k (delta_k - delta0_k)^2                   (drive prior, when given)

subject to ``N_i >= min_eig * 1`` (PSD), ``Ia, Fv, Fc >= 0`` (a coupled motor's ``Iam, Fvm, Fcm``
too) and optional mass bounds, with
``D(N || N0) = -log det(N0^-1 N) + tr(N0^-1 N) - 4`` (zero at ``N = N0``, about
``||N0^-1/2 (N - N0) N0^-1/2||_F^2 / 2`` nearby: a squared *relative* deviation, invariant to
units and to the frame) and ``c_k = ||(R11 G)[:, k]||^2 / s`` (the fit's own curvature along
drive parameter ``k`` alone, so ``w`` means the same for the drive pull as a ratio to the data).

Dividing the fit by ``s = ||r12||^2`` makes it dimensionless, 1 at ``phi = 0``: the solver's
tolerances (about 1e-9 here) are then relative to the torques' size, and ``w`` is a ratio. The
default ``w = 1e-6`` (:data:`DEFAULT_PRIOR_WEIGHT`) lets the prior decide only along directions
where changing a body's inertia by 100 % changes the torques by less than about
``sqrt(w) = 0.1 %`` of their size: it makes the solution unique (the fit alone is flat along the
nullspace of ``R11 G``) and costs the fit almost nothing.

The solver works in whitened coordinates ``N_i = L_i Nt_i L_i^T`` (``N_i0 = L_i L_i^T``, a
Cholesky factor of the prior), where ``D = -log det Nt_i + tr Nt_i - 4`` and every body's
variable is about the identity: bodies of very different size (a 30 kg base and a 10 g finger)
are equally well conditioned.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..errors import BaseparamsError
from ..model.inertia import HAT_INDEX, hat, unhat

#: default weight of the prior relative to the normalised fit (module docstring)
DEFAULT_PRIOR_WEIGHT = 1e-6
#: drive parameter kinds constrained >= 0: rotor inertia, viscous, Coulomb friction, per joint and
#: of a coupled motor (:class:`~baseparams.ident.drives.MotorCoupling`)
NONNEGATIVE_KINDS = ("Ia", "Fv", "Fc", "Iam", "Fvm", "Fcm")
#: every drive parameter kind: the non-negative ones and the offset (free)
DRIVE_KINDS = NONNEGATIVE_KINDS + ("Fo",)
#: a prior body is replaced when its smallest eigenvalue is below this fraction of its largest
PRIOR_PD_RTOL = 1e-9
#: floor of a replaced prior body's eigenvalues, relative to max(its largest, the robot's median)
PRIOR_FLOOR = 1e-3
#: default tolerance of :func:`feasibility`: smallest eigenvalue >= -rtol * largest, per body
FEASIBILITY_RTOL = 1e-6
#: Clarabel's tolerances (tighter than its defaults: the prior's pull is ``w`` times the fit)
CLARABEL_OPTIONS = {"tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10, "tol_feas": 1e-10, "max_iter": 400}
_INSTALL = "physical_fit needs cvxpy and clarabel: pip install 'baseparams[ident]'"


@dataclass(frozen=True, eq=False)
class PhysicalFit:
    """The result of :func:`physical_fit`.

    Parameters
    ----------
    pi : ndarray, shape ``(10 n,)``
        Inertial parameters, ``paper`` convention (spatial pseudo-inertia entries ``XX XY XZ YY
        YZ ZZ MX MY MZ M`` per body, world frame at q = 0) [kg, kg m, kg m^2].
    delta : ndarray, shape ``(nd,)``
        Drive parameters in the order of ``drive_kinds`` (units of the model's joints).
    theta : ndarray, shape ``(p,)``
        Model parameters ``G @ [pi; delta]``.
    min_eigenvalues : ndarray, shape ``(n,)``
        Smallest eigenvalue of each body's pseudo-inertia ``N_i`` (absolute; mixed units, as
        the entries of ``N``).
    relative_min_eigenvalues : ndarray, shape ``(n,)``
        The same divided by each body's largest eigenvalue (its scale).
    feasible : bool
        Every body's relative smallest eigenvalue is at least ``-FEASIBILITY_RTOL``.
    masses : ndarray, shape ``(n,)``
        Body masses ``N_i[3, 3]`` [kg].
    objective : float
        The minimised objective (dimensionless: the fit divided by ``fit_scale``, plus the
        weighted priors, constants included).
    fit_residual : float
        The data term alone, ``||R11 @ theta - r12||^2`` (torque units squared; not scaled).
    fit_scale : float
        ``s``, the fit's divisor ``||r12||^2`` (1 when ``r12`` is zero).
    prior_divergence : ndarray, shape ``(n,)``
        ``D(N_i || N_i0)`` per body, against the prior as used (after any replacement).
    solver_status : str
        cvxpy's status (``optimal`` or ``optimal_inaccurate``).
    seconds : float
        Wall time of the fit [s]: checks, problem construction (cvxpy's compilation) and solve,
        not the import of cvxpy.
    notes : tuple of str
        One line per decision: prior bodies replaced, inaccurate solves, no pull on ``delta``.
    """

    pi: np.ndarray
    delta: np.ndarray
    theta: np.ndarray
    min_eigenvalues: np.ndarray
    relative_min_eigenvalues: np.ndarray
    feasible: bool
    masses: np.ndarray
    objective: float
    fit_residual: float
    fit_scale: float
    prior_divergence: np.ndarray
    solver_status: str
    seconds: float
    notes: tuple[str, ...] = ()

    __repr__ = summary_repr

    @property
    def N(self) -> np.ndarray:
        """Pseudo-inertias ``(n, 4, 4)`` of the fit, world frame at q = 0."""
        return unhat(self.pi.reshape(-1, 10))


def feasibility(pi: np.ndarray, n: int, rtol: float = FEASIBILITY_RTOL) -> tuple[np.ndarray, bool]:
    """Physical consistency of a paper-convention parameter vector: ``N_i >= 0`` per body.

    Parameters
    ----------
    pi : array_like, shape ``(10 n,)``
        Ten ``paper`` parameters per body (e.g. a least-squares estimate of the full vector).
    n : int
        Number of bodies.
    rtol : float
        A body passes when its smallest eigenvalue is at least ``-rtol`` times its largest
        (absolute value); a zero body passes.

    Returns
    -------
    min_eig : ndarray, shape ``(n,)``
        The smallest eigenvalue of each body's pseudo-inertia (absolute).
    feasible : bool
        Every body passes.

    Raises
    ------
    BaseparamsError
        ``pi`` does not have ``10 n`` finite entries.
    """
    p = np.asarray(pi, dtype=float)
    if p.size != 10 * n or not np.all(np.isfinite(p)):
        raise BaseparamsError(f"feasibility: expected {10 * n} finite parameters (10 per body), got {p.size}")
    lam = np.linalg.eigvalsh(unhat(p.reshape(n, 10)))
    scale = np.abs(lam).max(axis=1)
    return lam[:, 0], bool(np.all(lam[:, 0] >= -rtol * scale))


#: the cvxpy solver of :func:`physical_fit`: Clarabel (Apache-2.0) handles the PSD and exponential cones with a
#: quadratic objective (no GPL solver)
SOLVER = "CLARABEL"


def physical_fit(R11, r12, G, robot, drive_kinds: Sequence[str] = (), *, prior=None,
                 prior_weight: float = DEFAULT_PRIOR_WEIGHT, mass_bounds=None, drive_prior=None,
                 min_eig: float = 0.0, drive_precision=None) -> PhysicalFit:
    """Least squares over physically consistent parameters, with a log-det prior.

    Solves the program of the module docstring: the fit ``||R11 G phi - r12||^2 / ||r12||^2``
    plus ``prior_weight`` times the log-det divergences of the bodies' pseudo-inertias from the
    prior's, over ``N_i >= min_eig * 1`` and the drive parameters' signs.

    Parameters
    ----------
    R11 : array_like, shape ``(p, p)``
        Triangular factor of the stacked least-squares system in the model parameters
        ``theta`` (any ``(k, p)`` matrix works).
    r12 : array_like, shape ``(p,)`` or ``(k,)``
        The transformed right-hand side (``Q1^T tau``).
    G : array_like, shape ``(p, 10 n + nd)``
        ``theta = G @ [pi; delta]``: ``pi`` in the ``paper`` convention, then the drive
        parameters.
    robot : Robot
        The model (``n`` bodies); its :attr:`~baseparams.model.robot.Robot.N0` is the default
        prior and its names label the notes.
    drive_kinds : sequence of str, length ``nd``
        Kind of each drive parameter, in :data:`DRIVE_KINDS`: those of
        :data:`NONNEGATIVE_KINDS` (``Ia``, ``Fv``, ``Fc`` and a coupled motor's ``Iam``, ``Fvm``,
        ``Fcm``) are constrained ``>= 0``, ``Fo`` is free.
    prior : array_like, shape ``(n, 4, 4)`` or ``(10 n,)``, optional
        Prior pseudo-inertias (world frame at q = 0) or the ``paper`` vector; default
        ``robot.N0`` (the model file's inertias). A body whose prior is not positive definite
        is replaced by its projection with eigenvalues floored at :data:`PRIOR_FLOOR` times
        ``max(its largest eigenvalue, the robot's median)``, with a note.
    prior_weight : float
        ``w >= 0``, relative to the normalised fit (default :data:`DEFAULT_PRIOR_WEIGHT`).
        0: no prior (the solution is then not unique along the fit's nullspace).
    mass_bounds : array_like, shape ``(n, 2)``, optional
        ``[min, max]`` mass [kg] per body; NaN: no bound on that side.
    drive_prior : array_like, shape ``(nd,)``, optional
        Prior drive parameters: adds ``prior_weight * sum_k c_k (delta_k - drive_prior_k)^2``
        (``c_k`` in the module docstring). Without it ``delta`` has no pull.
    min_eig : float
        Lower bound on every ``N_i``'s eigenvalues (``N_i >= min_eig * 1``; 0: PSD).
    drive_precision : array_like, shape ``(nd,)``, optional
        A weak prior of the drive parameters towards zero, in the fit's own units: adds
        ``sum_k drive_precision_k delta_k^2 / s`` (:func:`baseparams.ident.select.drive_precision`
        times the residual variance): a pair of drive terms the data cannot separate takes the
        smallest values that fit.

    Returns
    -------
    PhysicalFit
        The estimate, its eigenvalues, masses, objective terms, solver status and notes.

    Raises
    ------
    BaseparamsError
        cvxpy or the solver is not installed (the message names the extra), inconsistent
        shapes, an unknown drive kind, infeasible mass bounds (min > max), or the solver
        failed (the message names its status).
    """
    cp = _import_cvxpy()
    t0 = time.perf_counter()
    A, r, kinds, n = _check_problem(R11, r12, G, robot, drive_kinds)
    bounds = _check_mass_bounds(mass_bounds, robot)
    w = float(prior_weight)
    if not (np.isfinite(w) and w >= 0) or not (np.isfinite(min_eig) and min_eig >= 0):
        raise BaseparamsError(f"physical_fit: prior_weight and min_eig must be finite and >= 0, "
                              f"got {prior_weight} and {min_eig}")
    n0, notes = prior_pseudo_inertias(robot, prior)
    s = float(r @ r) if float(r @ r) > 0 else 1.0
    if float(r @ r) == 0:
        notes.append("r12 is zero (no torque seen by the fit): the fit is not scaled (s = 1)")
    d0 = None if drive_prior is None else _check_vector(drive_prior, len(kinds), "drive_prior")
    dp = None if drive_precision is None else _check_vector(drive_precision, len(kinds), "drive_precision")
    if dp is not None and not (np.all(np.isfinite(dp)) and np.all(dp >= 0)):
        raise BaseparamsError("physical_fit: drive_precision must be finite and >= 0")
    prob, nts, delta = _build(cp, A, r, s, n0, kinds, bounds, w, d0, min_eig, dp)
    status = _solve(cp, prob, SOLVER)
    if delta.size and d0 is None and w > 0 and (dp is None or not np.any(dp)):
        notes.append("drive parameters: no drive_prior, no pull on delta (only the data and the signs)")
    if status != "optimal":
        notes.append(f"solver status {status}: the solution is less accurate than the tolerances")
    return _result(nts, delta, n0, r, s, G, R11, prob, status, time.perf_counter() - t0, notes)


def prior_pseudo_inertias(robot, prior=None) -> tuple[np.ndarray, list[str]]:
    """The prior as :func:`physical_fit` uses it: positive definite, with a note per change.

    Parameters
    ----------
    robot : Robot
        The model (``n`` bodies); ``robot.N0`` is the default prior, ``robot.names`` label
        the notes.
    prior : array_like, shape ``(n, 4, 4)`` or ``(10 n,)``, optional
        Prior pseudo-inertias (world frame at q = 0) or the ``paper`` parameter vector.

    Returns
    -------
    N0 : ndarray, shape ``(n, 4, 4)``
        The prior with every body positive definite: a body whose smallest eigenvalue is below
        :data:`PRIOR_PD_RTOL` times its largest gets its eigenvalues floored at
        :data:`PRIOR_FLOOR` times ``max(its largest, median of the bodies' largest)``.
    notes : list of str
        One line per replaced body (its name, its smallest eigenvalue and mass, the floor).

    Raises
    ------
    BaseparamsError
        A prior of the wrong shape or with NaN or inf.
    """
    n = robot.n
    if prior is None:
        p = np.array(robot.N0, dtype=float)
    else:
        p = np.asarray(prior, dtype=float)
        p = unhat(p.reshape(n, 10)) if p.size == 10 * n and p.shape != (n, 4, 4) else p
    if p.shape != (n, 4, 4) or not np.all(np.isfinite(p)):
        raise BaseparamsError(f"physical_fit: prior must be {n} finite 4x4 pseudo-inertias or {10 * n} "
                              f"paper parameters, got shape {np.shape(prior)}")
    p = 0.5 * (p + np.swapaxes(p, 1, 2))
    lam, vec = np.linalg.eigh(p)
    top = lam[:, -1]
    typical = float(np.median(top[top > 0])) if np.any(top > 0) else 1.0
    notes = []
    for i in np.flatnonzero(lam[:, 0] <= PRIOR_PD_RTOL * np.maximum(top, 0)):
        floor = PRIOR_FLOOR * max(float(top[i]), typical)
        p[i] = (vec[i] * np.maximum(lam[i], floor)) @ vec[i].T
        notes.append(f"prior of body {robot.names[i]!r} is not positive definite (smallest eigenvalue "
                     f"{lam[i, 0]:.3g}, mass {p[i, 3, 3]:.3g} kg after projection): projected to the nearest "
                     f"positive definite matrix with eigenvalues >= {floor:.3g}")
    return p, notes


# --- steps ------------------------------------------------------------------------------------


def _import_cvxpy():
    try:
        import cvxpy
    except ImportError:
        raise BaseparamsError(_INSTALL) from None
    return cvxpy


def _check_vector(v, size: int, what: str) -> np.ndarray:
    v = np.asarray(v, dtype=float).reshape(-1)
    if v.size != size or not np.all(np.isfinite(v)):
        raise BaseparamsError(f"physical_fit: {what} must have {size} finite entries, got {v.size}")
    return v


def _check_problem(R11, r12, G, robot, drive_kinds) -> tuple[np.ndarray, np.ndarray, tuple[str, ...], int]:
    """``A = R11 @ G``, ``r12`` as a vector, the drive kinds and ``n``; one-line errors."""
    n = robot.n
    R11, G = np.atleast_2d(np.asarray(R11, dtype=float)), np.atleast_2d(np.asarray(G, dtype=float))
    kinds = tuple(str(k) for k in drive_kinds)
    bad = [k for k in kinds if k not in DRIVE_KINDS]
    if bad:
        raise BaseparamsError(f"physical_fit: unknown drive kind(s) {bad}; expected {', '.join(DRIVE_KINDS)}")
    if R11.ndim != 2 or G.ndim != 2 or G.shape != (R11.shape[1], 10 * n + len(kinds)):
        raise BaseparamsError(f"physical_fit: G must be (p, 10 n + nd) = ({R11.shape[-1]}, {10 * n + len(kinds)}) "
                              f"for R11 {R11.shape}, {n} bodies and {len(kinds)} drive kinds; got {G.shape}")
    r = _check_vector(r12, R11.shape[0], "r12")
    if not (np.all(np.isfinite(R11)) and np.all(np.isfinite(G))):
        raise BaseparamsError("physical_fit: R11 and G must be finite")
    return R11 @ G, r, kinds, n


def _check_mass_bounds(mass_bounds, robot) -> np.ndarray | None:
    """``(n, 2)`` bounds (NaN: none), or None; min > max is one error naming the bodies."""
    if mass_bounds is None:
        return None
    b = np.asarray(mass_bounds, dtype=float)
    if b.shape != (robot.n, 2):
        raise BaseparamsError(f"physical_fit: mass_bounds must be ({robot.n}, 2) [min, max] kg, got {b.shape}")
    bad = np.flatnonzero(b[:, 0] > b[:, 1])
    if bad.size:
        which = ", ".join(f"{robot.names[i]!r} ({b[i, 0]:g} > {b[i, 1]:g})" for i in bad)
        raise BaseparamsError(f"physical_fit: infeasible mass bounds, min > max for body {which}")
    return b


def _whitening(n0: np.ndarray) -> np.ndarray:
    """``T (10 n, 16 n)``: ``pi = T @ vec(Nt)`` for ``N_i = L_i Nt_i L_i^T``, ``N0_i = L_i L_i^T``.

    ``vec`` in column-major order (cvxpy's ``order="F"``); block diagonal over bodies.
    """
    n = len(n0)
    L = np.linalg.cholesky(n0)
    rows, cols = np.array(HAT_INDEX).T
    T = np.zeros((10 * n, 16 * n))
    for i in range(n):
        # pi_k = sum_ab L[r_k, a] L[c_k, b] Nt[a, b]; F order: index a + 4 b
        blk = L[i][rows][:, :, None] * L[i][cols][:, None, :]  # (10, a, b)
        T[10 * i:10 * i + 10, 16 * i:16 * i + 16] = blk.transpose(0, 2, 1).reshape(10, 16)
    return T


def _build(cp, A, r, s, n0, kinds, bounds, w, d0, min_eig, dp=None):
    """The cvxpy problem, the whitened body variables ``Nt_i`` and ``delta``."""
    n, nd = len(n0), len(kinds)
    T = _whitening(n0)
    nts = [cp.Variable((4, 4), symmetric=True, name=f"N{i}") for i in range(n)]
    delta = cp.Variable(nd, name="delta")
    x = cp.hstack([cp.vec(v, order="F") for v in nts])
    pi = T @ x
    fit_rows = A[:, :10 * n] @ T
    resid = fit_rows @ x - r
    if nd:
        resid = resid + A[:, 10 * n:] @ delta
    obj = cp.sum_squares(resid) / s
    cons = []
    for i, v in enumerate(nts):
        floor = min_eig * np.linalg.inv(n0[i]) if min_eig > 0 else np.zeros((4, 4))
        cons.append(v - floor >> 0)
    if w > 0:
        obj = obj + w * cp.sum([-cp.log_det(v) + cp.trace(v) - 4.0 for v in nts])
    signed = [k for k, kind in enumerate(kinds) if kind in NONNEGATIVE_KINDS]
    if signed:
        cons.append(delta[signed] >= 0)
    if d0 is not None and nd and w > 0:
        c = np.einsum("ij,ij->j", A[:, 10 * n:], A[:, 10 * n:]) / s
        c = np.where(c > 0, c, 1.0)
        obj = obj + w * cp.sum(cp.multiply(c, cp.square(delta - d0)))
    if dp is not None and nd and np.any(dp):
        obj = obj + cp.sum(cp.multiply(dp / s, cp.square(delta)))
    cons += _mass_constraints(pi, bounds)
    return cp.Problem(cp.Minimize(obj), cons), nts, delta


def _mass_constraints(pi, bounds) -> list:
    if bounds is None:
        return []
    out = []
    for side, sign in ((0, 1.0), (1, -1.0)):
        idx = np.flatnonzero(~np.isnan(bounds[:, side]))
        if idx.size:
            out.append(sign * pi[10 * idx + 9] >= sign * bounds[idx, side])
    return out


def _solve(cp, prob, solver: str) -> str:
    """Solve; the status, or a one-line error naming the solver and its status."""
    opts = CLARABEL_OPTIONS if solver.upper() == "CLARABEL" else {}
    try:
        with warnings.catch_warnings():  # an inaccurate solve is reported by status and a note
            warnings.filterwarnings("ignore", message="Solution may be inaccurate")
            prob.solve(solver=solver, **opts)
    except cp.error.SolverError as exc:
        if solver not in cp.installed_solvers():
            raise BaseparamsError(f"physical_fit: solver {solver} is not installed; {_INSTALL}") from None
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise BaseparamsError(f"physical_fit: solver {solver} failed ({msg})") from None
    status = str(prob.status)
    if status not in ("optimal", "optimal_inaccurate"):
        raise BaseparamsError(f"physical_fit: solver {solver} returned status {status!r} (no solution)")
    return status


def _result(nts, delta, n0, r, s, G, R11, prob, status, seconds, notes) -> PhysicalFit:
    L = np.linalg.cholesky(n0)
    nt = np.array([0.5 * (v.value + v.value.T) for v in nts])
    N = L @ nt @ np.swapaxes(L, 1, 2)
    pi = hat(N).reshape(-1)
    d = np.asarray(delta.value, dtype=float).reshape(-1) if delta.size else np.zeros(0)
    phi = np.concatenate([pi, d])
    theta = G @ phi
    res = R11 @ theta - r
    lam = np.linalg.eigvalsh(N)
    rel = lam[:, 0] / np.maximum(np.abs(lam).max(axis=1), np.finfo(float).tiny)
    lam_t = np.linalg.eigvalsh(nt)
    with np.errstate(divide="ignore", invalid="ignore"):
        div = np.where(lam_t[:, 0] > 0, -np.log(np.clip(lam_t, 1e-300, None)).sum(axis=1) + lam_t.sum(axis=1) - 4,
                       np.inf)
    return PhysicalFit(pi=pi, delta=d, theta=theta, min_eigenvalues=lam[:, 0], relative_min_eigenvalues=rel,
                       feasible=bool(np.all(rel >= -FEASIBILITY_RTOL)), masses=N[:, 3, 3].copy(),
                       objective=float(prob.value), fit_residual=float(res @ res), fit_scale=s,
                       prior_divergence=div, solver_status=status, seconds=seconds, notes=tuple(notes))
