"""The payload's estimate: weighted least squares on the identified directions, its covariance, physical consistency.

1. Least squares on the identified directions only (:class:`~.structure.Structure`; what the motion
   does not identify is held at the prior, or at zero and not reported): ordinary, then weighted per
   row by the residuals' standard deviation (Gautier's weighting), each row's slow samples left out.
2. Standard deviations: the HAC (Newey-West) sandwich of :mod:`baseparams.ident.uncertainty` over the
   fitted samples (correlated residuals), or the least-squares formula; with a saved identification
   the propagation of its own covariance through the known torques is added (its errors move the
   payload's estimate: ``d x / d theta = -(C^T C)^-1 C^T A``).
3. Physically consistent (cvxpy and Clarabel): the same weighted fit over payloads whose 4x4
   pseudo-inertia (LINK's frame) is positive semidefinite, the mass positive; when the least-squares
   payload is not realizable the constraint is active and named, with the kind of body at the boundary
   (a point mass, a rod, a flat body).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...display import summary_repr
from ...errors import BaseparamsError
from ...model import inertia as _inertia
from .structure import Structure, with_log_gap

#: the smallest mass of a physically consistent payload [kg]
MIN_MASS = 1e-6
#: a pseudo-inertia eigenvalue at most this fraction of the largest counts as zero (the body's rank)
RANK_RTOL = 1e-6
#: the physically consistent fit is "active" when it moves the identified values by more than this (the weighted
#: rows' norm of the change: the noise is about 1 per fitted entry there)
ACTIVE_SHIFT = 1e-3
#: the pull of the unidentified directions towards the prior (relative to the normalised fit: the data's identified
#: values win where the prior is not compatible with them), and towards zero without a prior (only to make the
#: solution unique)
PRIOR_PULL = 1e-6
FREE_PULL = 1e-12
#: the kind of body a singular pseudo-inertia of each rank is
BODY_OF_RANK = {1: "a point mass", 2: "mass on a line (a thin rod)", 3: "mass on a plane (a flat body)"}


@dataclass(frozen=True, eq=False)
class PayloadFit:
    """The payload's estimate and its statistics.

    Parameters
    ----------
    x : ndarray, shape ``(k,)``
        The reported values: the payload's ten parameters (``khalil``, LINK's frame, about its
        origin), then the drive terms; physically consistent when ``physical`` is set.
    x_ls : ndarray, shape ``(k,)``
        The least-squares values.
    cov : ndarray, shape ``(k, k)``
        Covariance of ``x_ls`` (zero along the unidentified directions).
    weights : ndarray, shape ``(r,)``
        Row weights ``1 / sigma_r``.
    rms : ndarray, shape ``(r,)``
        Per-row residual RMS of ``x`` on the fitted entries [N m or N].
    observations : int
        Fitted entries (samples x rows, slow ones left out).
    structure : Structure
        What the motion identifies (with the log's gap, when one).
    covariance : str
        How ``cov`` was computed.
    physical : dict, optional
        ``{"active", "shift", "constraint", "min_eigenvalue", "rank", "status"}`` of the physically
        consistent fit, or None (least squares).
    """

    x: np.ndarray
    x_ls: np.ndarray
    cov: np.ndarray
    weights: np.ndarray
    rms: np.ndarray
    observations: int
    structure: Structure
    covariance: str
    physical: dict | None = None

    __repr__ = summary_repr

    @property
    def std(self) -> np.ndarray:
        """Standard deviations ``(k,)`` of the values."""
        return np.sqrt(np.maximum(np.diag(self.cov), 0.0))


def _coordinates(st: Structure, a: np.ndarray, y: np.ndarray, x0: np.ndarray):
    """The columns in the identified coordinates ``z`` (``x = x0 + free z / scale``) and the torques less ``a x0``."""
    t = st.free / st.scale[:, None]
    return np.einsum("srk,kf->srf", a, t), y - a @ x0, t


def _solve(c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least squares of ``(N, f)`` rows: ``(z, R11, r12)`` from a QR of ``[c | y]``."""
    f = c.shape[1]
    r = np.linalg.qr(np.column_stack([c, y]), mode="r")
    r11, r12 = r[:f, :f], r[:f, f]
    if f and not np.all(np.abs(np.diag(r11)) > 1e-12 * max(np.abs(r11).max(), 1e-300)):
        raise BaseparamsError("the payload's rows are singular in the identified directions (the log does not excite "
                              "them); record a richer motion")
    return (np.linalg.solve(r11, r12) if f else np.zeros(0)), r11, r12


def held(st: Structure, xp: np.ndarray) -> np.ndarray:
    """``x0 (k,)``: the part of ``xp`` along the unidentified directions (the values held there).

    Parameters
    ----------
    st : Structure
        The decision.
    xp : ndarray, shape ``(k,)``
        The prior's values (zero drive terms), or zero.

    Returns
    -------
    ndarray, shape ``(k,)``
        ``null null^T (scale xp) / scale`` (scaled coordinates).
    """
    u = st.null
    return (u @ (u.T @ (st.scale * xp))) / st.scale


def weighted_fit(rows, st: Structure, xp: np.ndarray) -> tuple:
    """Ordinary then weighted least squares, each row's slow samples left out; the log's gap applied.

    Parameters
    ----------
    rows : Rows
        The fitted rows.
    st : Structure
        The structural decision.
    xp : ndarray, shape ``(k,)``
        The prior's values (zero drive terms), or zero: held along the unidentified directions
        (:func:`held`).

    Returns
    -------
    tuple
        ``(z, R11, r12, cw (S', r, f), yw (S', r), t (k, f), weights (r,), structure, x0 (k,))``.
    """
    mask = rows.fitted.astype(float)
    x0 = held(st, xp)
    c, y0, t = _coordinates(st, rows.a, rows.y, x0)
    n = mask.sum(axis=0)
    if np.any(n < 2):
        raise BaseparamsError("a fitted joint has fewer than 2 samples above its min_speed: lower min_speed")
    z, _, _ = _solve((c * mask[..., None]).reshape(-1, c.shape[2]), (y0 * mask).reshape(-1))
    res = (y0 - c @ z) * mask
    sigma = np.sqrt((res**2).sum(axis=0) / np.maximum(n - c.shape[2] / c.shape[1], 1.0))
    w = 1.0 / np.maximum(sigma, max(float(sigma.max()) * 1e-6, 1e-300))
    cw = c * (mask * w)[..., None]
    st2 = with_log_gap(st, cw.reshape(-1, c.shape[2]))
    if st2 is not st:
        x0 = held(st2, xp)
        c, y0, t = _coordinates(st2, rows.a, rows.y, x0)
        cw = c * (mask * w)[..., None]
    yw = y0 * mask * w
    z, r11, r12 = _solve(cw.reshape(-1, cw.shape[2]), yw.reshape(-1))
    return z, r11, r12, cw, yw, t, w, st2, x0


def covariance(kind: str, cw: np.ndarray, yw: np.ndarray, z: np.ndarray, r11: np.ndarray, rate: float,
               observations: int) -> tuple[np.ndarray, str]:
    """The covariance of ``z``: HAC over the fitted samples, or the least-squares formula.

    Parameters
    ----------
    kind : {"hac", "white"}
        The covariance.
    cw : ndarray, shape ``(S', r, f)``
        The weighted rows (zero where not fitted).
    yw : ndarray, shape ``(S', r)``
        The weighted torques.
    z : ndarray, shape ``(f,)``
        The estimate.
    r11 : ndarray, shape ``(f, f)``
        Its triangular factor.
    rate : float
        The samples' rate [Hz].
    observations : int
        Fitted entries.

    Returns
    -------
    cov : ndarray, shape ``(f, f)``
        The covariance.
    label : str
        How it was computed.
    """
    from ..uncertainty import describe, hac_covariance, psd

    f = len(z)
    if not f:
        return np.zeros((0, 0)), describe(kind)
    if kind == "white":
        e = yw - cw @ z
        inv = np.linalg.inv(r11)
        return float((e**2).sum()) / max(observations - f, 1) * inv @ inv.T, describe("white")
    cov, b = hac_covariance([(cw, yw)], r11, z, np.ones(cw.shape[1]), observations, len(yw))
    return psd(cov), describe("hac", b, rate)


def result_covariance(rows, cw_mask_w: np.ndarray, r11: np.ndarray, result) -> np.ndarray | None:
    """The saved identification's covariance propagated to ``z`` through the known torques.

    Parameters
    ----------
    rows : Rows
        The fitted rows (``result_a``: the result's filtered regressor).
    cw_mask_w : tuple of ndarray
        ``(cw (S', r, f), weights (S', r))``: the weighted rows and the entries' weights.
    r11 : ndarray, shape ``(f, f)``
        The fit's triangular factor.
    result : Identification
        The saved identification (its ``fit.estimate.cov``, else its standard deviations).

    Returns
    -------
    ndarray, shape ``(f, f)`` or None
        ``G cov_theta G^T``, ``G = -(R11^T R11)^-1 cw^T (W A)``; None without a result.
    """
    if rows.result_a is None or result is None:
        return None
    cw, w = cw_mask_w
    est = result.fit.estimate
    cov_t = est.cov if getattr(est, "cov", None) is not None else np.diag(np.asarray(est.std, dtype=float) ** 2)
    cross = np.einsum("srf,srp->fp", cw, rows.result_a * w[..., None])
    inv = np.linalg.inv(r11)
    g = -(inv @ inv.T) @ cross
    return g @ cov_t @ g.T


def link_pseudo(phi: np.ndarray) -> np.ndarray:
    """The payload's 4x4 pseudo-inertia in LINK's frame from its ten ``khalil`` parameters.

    Parameters
    ----------
    phi : ndarray, shape ``(10,)``
        ``XX XY XZ YY YZ ZZ MX MY MZ M`` (LINK's frame, about its origin).

    Returns
    -------
    ndarray, shape ``(4, 4)``
        ``[[Sigma, h], [h^T, m]]``.
    """
    return _inertia.from_convention(np.asarray(phi, dtype=float), "khalil")


def physical_fit(r11, r12, x0, st: Structure, x_ls, held: bool, nd: int) -> tuple[np.ndarray, dict]:
    """The physically consistent payload nearest the data: ``min ||R11 z(x) - r12||^2`` over realizable payloads.

    Parameters
    ----------
    r11, r12 : ndarray
        The weighted fit in the identified coordinates ``z`` (``(f, f)``, ``(f,)``; ``x = x0 + free z / scale``).
    x0 : ndarray, shape ``(k,)``
        The values held along the unidentified directions.
    st : Structure
        The decision (its unidentified directions).
    x_ls : ndarray, shape ``(k,)``
        The least-squares values.
    held : bool
        The unidentified directions are held at ``x0`` (a prior); else they are free, kept small.
    nd : int
        Drive terms.

    Returns
    -------
    x : ndarray, shape ``(k,)``
        The physically consistent values.
    info : dict
        ``{"active", "shift", "prior_moved", "constraint", "min_eigenvalue", "rank", "status"}``:
        ``shift`` the change of the identified values in the weighted rows' norm (noise about 1 per
        entry), ``active`` above :data:`ACTIVE_SHIFT`; ``prior_moved`` the relative change of the
        held directions (a prior not compatible with the identified values).

    Raises
    ------
    BaseparamsError
        cvxpy or Clarabel missing (naming the extra), or the solver failed.
    """
    cp = _cvxpy()
    n_ls = link_pseudo(x_ls[:10])
    lam_ls = np.linalg.eigvalsh(n_ls)
    ref = _reference(n_ls)
    lchol = np.linalg.cholesky(ref)
    nt = cp.Variable((4, 4), symmetric=True)
    delta = cp.Variable(nd) if nd else None
    n_expr = lchol @ nt @ lchol.T
    phi = _khalil_of(cp, n_expr)
    x = cp.hstack([phi, delta]) if nd else phi
    zmap = st.free.T * st.scale  # z = free^T scale (x - x0): the identified coordinates
    resid = r11 @ (zmap @ (x - x0)) - r12
    s = max(float(r12 @ r12), 1e-300)
    obj = cp.sum_squares(resid) / s
    u = st.null
    if u.shape[1]:
        pull = (u.T * st.scale) @ (x - x0)
        obj = obj + (PRIOR_PULL if held else FREE_PULL) * cp.sum_squares(pull)
    prob = cp.Problem(cp.Minimize(obj), [nt >> 0, n_expr[3, 3] >= MIN_MASS])
    status = _solve_cp(cp, prob)
    xv = np.asarray(x.value, dtype=float).reshape(-1)
    n = link_pseudo(xv[:10])
    lam = np.linalg.eigvalsh(n)
    rank = int(np.sum(lam > RANK_RTOL * lam.max()))
    moved = float(np.linalg.norm(r11 @ (zmap @ (xv - x_ls))))  # in the weighted rows' units: noise ~ 1 per entry
    active = moved > ACTIVE_SHIFT
    complete = not st.payload_null.shape[1] or held
    pn = (st.null.T * st.scale)
    prior_moved = float(np.linalg.norm(pn @ (xv - x0)) / max(np.linalg.norm(pn @ x0), 1e-300)) if held and u.shape[1] \
        else 0.0
    return xv, {"active": active, "shift": moved, "prior_moved": prior_moved,
                "constraint": _constraint_text(n_ls, lam_ls, rank, active, complete),
                "min_eigenvalue": float(lam[0]), "rank": rank, "status": status}


def _cvxpy():
    try:
        import cvxpy
    except ImportError:
        raise BaseparamsError("the physically consistent payload needs cvxpy and clarabel: pip install "
                              "'baseparams[ident]' (or method='ls')") from None
    return cvxpy


def _solve_cp(cp, prob) -> str:
    """Solve with Clarabel; the status, or one line naming the failure."""
    import warnings

    from ..physical import CLARABEL_OPTIONS

    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="Solution may be inaccurate")
            prob.solve(solver="CLARABEL", **CLARABEL_OPTIONS)
    except cp.error.SolverError as exc:
        raise BaseparamsError(f"payload: the physically consistent fit failed (Clarabel: "
                              f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    if prob.status not in ("optimal", "optimal_inaccurate"):
        raise BaseparamsError(f"payload: the physically consistent fit failed (Clarabel status {prob.status!r})")
    return str(prob.status)


def _reference(n: np.ndarray) -> np.ndarray:
    """A positive definite 4x4 of the payload's size: ``n`` with its eigenvalues floored (the solver's whitening)."""
    lam, v = np.linalg.eigh(0.5 * (n + n.T))
    top = max(float(np.abs(lam).max()), 1e-9)
    return (v * np.maximum(np.abs(lam), 1e-3 * top)) @ v.T


def _khalil_of(cp, n):
    """The ten ``khalil`` parameters (cvxpy expressions) of a pseudo-inertia expression ``n``: ``J = tr(S) 1 - S``."""
    tr = n[0, 0] + n[1, 1] + n[2, 2]
    j = [[tr - n[0, 0], -n[0, 1], -n[0, 2]], [None, tr - n[1, 1], -n[1, 2]], [None, None, tr - n[2, 2]]]
    return cp.hstack([j[0][0], j[0][1], j[0][2], j[1][1], j[1][2], j[2][2], n[0, 3], n[1, 3], n[2, 3], n[3, 3]])


def _constraint_text(n_ls: np.ndarray, lam_ls: np.ndarray, rank: int, active: bool, complete: bool) -> str:
    """One line: whether physical consistency was active and what it changed."""
    if not active:
        return ("not active: the least-squares payload is a realizable body" if complete else
                "not active: a realizable payload has the least-squares values of the identified combinations (the "
                "others chosen only to make it one, not reported)")
    if not complete:
        return ("active: no realizable payload has the least-squares values of the identified combinations; the fit "
                "is the nearest one that has (in the data's metric; the unidentified combinations chosen only to make "
                "it realizable, not reported)")
    m = n_ls[3, 3]
    if m < MIN_MASS:
        why = f"its mass is {m:.3g} kg"
    else:
        c = n_ls[:3, 3] / m
        sig_c = n_ls[:3, :3] - m * np.outer(c, c)  # second moments about the centre of mass
        mom = np.linalg.eigvalsh(np.trace(sig_c) * np.eye(3) - sig_c)
        shown = ", ".join(f"{v:.3g}" for v in mom)
        why = (f"its principal moments about the centre of mass {shown} kg m^2 are not all positive" if mom[0] < 0
               else f"its principal moments about the centre of mass {shown} kg m^2 break the triangle inequality"
               if np.linalg.eigvalsh(sig_c)[0] < 0 else f"its pseudo-inertia has the eigenvalue {lam_ls[0]:.3g}")
    body = BODY_OF_RANK.get(rank, "a solid body")
    return (f"active: the least-squares payload is not a realizable body ({why}); the fit is the nearest realizable "
            f"one in the data's metric, {body} (pseudo-inertia of rank {rank})")
