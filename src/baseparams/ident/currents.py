"""Identification from motor currents with unknown current-to-torque gains: the estimator.

An arm without joint-torque sensors logs its motor currents ``i`` [A]. Motor ``r``'s current
makes the torque ``k_r i_r`` (its gain ``k_r`` [N m/A at the joint side]: torque constant x gear
ratio x efficiency, known only roughly) and a transmission (:class:`Transmission`: the identity,
or a coupled wrist whose last motor turns two joints) takes it to the joints::

    C diag(k) i = Y_b beta + D delta = A theta        (joint side, the model of :class:`IdentModel`)

``beta`` the rigid body's base parameters (rotor inertias regrouped into them where they share a
column), ``delta`` the drive terms the motor side adds (rotor inertia, friction, coupled motors).
Every gain is unknown but one, or none: the anchor.

**Where the noise is.** The current is what is measured, with its noise; the regressor comes from
the encoders. The estimate is the errors-in-variables one with the residual in amperes,

    min_{theta, g}  sum_r || i_r - g_r (C^-1 A theta)_r ||^2 / sigma_r^2,     g_r = 1 / k_r,

the maximum-likelihood estimate under Gaussian current noise ``sigma_r`` per motor. Fitting the
torques instead (``A theta - diag(i) k = 0`` with one gain fixed) collapses: shrinking ``k_r``
shrinks row ``r``'s target, and least squares takes the small targets (a 7-DoF arm: six of seven
gains fitted near zero). Here ``k_r -> 0`` (``g_r -> inf``) costs unless row ``r``'s torque vanishes,
and ``k_r -> inf`` (``g_r -> 0``) leaves ``i_r`` unexplained; parametrised by ``g`` the model is
smooth through every value and a gain's sign is the data's.

**Variable projection.** For fixed gains the problem is a weighted linear least squares in
``theta`` (row ``r`` scaled by ``g_r / sigma_r``): on the streamed factors ``R_r`` of ``[A_r | i_r]``
(``(p + 1)^2`` numbers per motor, whatever the log's length) its solution and residual are one QR of
``m (p + 1)`` rows. :func:`solve_gains` minimises that projected residual over the free gains
(:func:`scipy.optimize.least_squares`), exactly (Golub and Pereyra 1973).

**The scale.** ``theta -> s theta``, ``g -> g / s`` leaves every current unchanged: the one direction
the currents cannot fix (the homogeneous system, :func:`homogeneous`). An anchor fixes it: a catalogue gain ``k_a``
(``--gain-anchor JOINT=K``), or by default the model file's inertial parameters (:func:`file_scale`:
the common factor that brings the identified base parameters closest to the file's, weighted by
the file's stated uncertainty and the estimate's). A relative error ``e`` of the anchor scales every
gain, base parameter, drive term and predicted torque by ``1 + e``.

**What currents cannot tell.** Beyond the scale, a direction of the model's Jacobian whose singular
value lies below a gap (:func:`baseparams.numerics.spectrum`, column-scaled) is a group this log does
not determine (:func:`weak_groups`); a gain in such a group (a joint whose rigid-body torque is below
its current's noise: a symmetric wrist, a link with no load) is held at its value from the model
file's torques (:func:`determined_motors`) and named, never fitted as if determined. A drive term the
model regroups into a base parameter (the first joint's rotor inertia with the first link's ``ZZ``)
stays there: the joint-side torque a sensor after the gear would read is known only up to it.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..errors import BaseparamsError

#: directions below a spectrum gap and below this fraction of the largest singular value (column-scaled
#: Jacobian) are groups the log does not determine (:func:`weak_groups`)
WEAK_RATIO = 1e-6
#: a gain's relative standard deviation beyond which the report calls it poorly determined
POOR_GAIN = 0.3
#: members of a group named (the largest components of its direction)
GROUP_MEMBERS = 6
_ANCHOR = re.compile(r"^\s*([^=\s]+)\s*=\s*(\S+)\s*$")


@dataclass(frozen=True)
class GainAnchor:
    """One gain given by the user, fixing the scale: ``JOINT=K`` (``--gain-anchor``).

    Parameters
    ----------
    motor : str
        The motor (the joint whose current column is its, :class:`Transmission`).
    gain : float
        Its gain ``k`` [N m/A, or N/A for a prismatic joint, at the joint side], non-zero.

    Raises
    ------
    BaseparamsError
        A gain that is zero or not finite.
    """

    motor: str
    gain: float

    def __post_init__(self):
        g = float(self.gain)
        if not math.isfinite(g) or g == 0 or abs(g) > 1e9:
            raise BaseparamsError(f"gain_anchor= {self.motor}={self.gain}: the gain must be finite and non-zero "
                                  f"[N m/A at the joint side], at most 1e9 in size")
        object.__setattr__(self, "gain", g)

    @classmethod
    def parse(cls, text: str) -> GainAnchor:
        """An anchor from ``JOINT=K`` (e.g. ``joint2=12.5``).

        Parameters
        ----------
        text : str
            The joint (its motor's current column) and the gain [N m/A].

        Returns
        -------
        GainAnchor
            The anchor.

        Raises
        ------
        BaseparamsError
            Not of that form, or a gain that is not a non-zero number.
        """
        m = _ANCHOR.match(text) if isinstance(text, str) else None
        if m is None:
            raise BaseparamsError(f"gain_anchor= {text!r}: expected JOINT=K (a joint whose current is logged and its "
                                  f"catalogue gain in N m/A at the joint side, e.g. joint2=12.5)")
        try:
            gain = float(m.group(2))
        except ValueError:
            raise BaseparamsError(f"gain_anchor= {text!r}: {m.group(2)!r} is not a number") from None
        return cls(m.group(1), gain)

    def __str__(self) -> str:
        return f"{self.motor}={self.gain:g}"

    def __repr__(self) -> str:
        return f"GainAnchor({self.motor!r}, {self.gain!r})"


def parse_anchors(text: str) -> tuple[GainAnchor, ...]:
    """Anchors from ``JOINT=K[,JOINT=K...]`` (``--gain-anchor``): one gain, or several (their geometric mean).

    Parameters
    ----------
    text : str
        Comma-separated ``JOINT=K``.

    Returns
    -------
    tuple of GainAnchor
        The anchors, in the order given.

    Raises
    ------
    BaseparamsError
        A malformed item, or a joint named twice.
    """
    if not isinstance(text, str) or not text.strip():
        raise BaseparamsError(f"gain_anchor= {text!r}: expected JOINT=K (a joint whose current is logged and its "
                              f"catalogue gain in N m/A at the joint side, e.g. joint2=12.5)")
    out = tuple(GainAnchor.parse(item) for item in text.split(","))
    names = [a.motor for a in out]
    if len(set(names)) != len(names):
        raise BaseparamsError(f"gain_anchor= {text!r}: a joint is named twice")
    return out


@dataclass(frozen=True, eq=False)
class Transmission:
    """Which motor's current reaches which joints: ``tau = C diag(k) i``.

    Each motor is named after the joint whose current column (``cur_<joint>``) it logs. A motor
    coupling (:class:`~baseparams.ident.drives.MotorCoupling`) named after one of its joints is that
    joint's motor: its torque reaches every joint of the coupling with the coupling's weights (a
    Stäubli wrist: ``joint_6:joint_5=1,joint_6=1``, motor 6 turning joints 5 and 6).

    Parameters
    ----------
    motors : tuple of str, shape ``(m,)``
        The motors: the measured joints' names, in the model's row order.
    matrix : ndarray, shape ``(m, m)``
        ``C``: rows the joints, columns the motors; invertible.
    """

    motors: tuple[str, ...]
    matrix: np.ndarray

    __repr__ = summary_repr

    @property
    def identity(self) -> bool:
        """Every motor turns its own joint only."""
        return bool(np.array_equal(self.matrix, np.eye(len(self.motors))))

    def motor_rows(self, a: np.ndarray) -> np.ndarray:
        """Joint-side rows mapped to the motors: ``C^-1 A`` per sample.

        Parameters
        ----------
        a : ndarray, shape ``(S, m, ...)``
            Joint-side rows (a regressor ``(S, m, p)`` or torques ``(S, m)``).

        Returns
        -------
        ndarray, shape ``(S, m, ...)``
            The motors' rows: ``g_r`` times row ``r`` is motor ``r``'s current.
        """
        if self.identity:
            return a
        return np.einsum("rj,sj...->sr...", np.linalg.inv(self.matrix), a)

    def to_json(self) -> dict:
        """The transmission as JSON types.

        Returns
        -------
        dict
            ``{"motors": [...], "matrix": [[...]]}``.
        """
        return {"motors": list(self.motors), "matrix": self.matrix.tolist()}


def transmission_for(joints, couplings=()) -> Transmission:
    """The transmission of the measured joints and the motor couplings.

    Parameters
    ----------
    joints : sequence of str, shape ``(m,)``
        The measured joints, in row order (each logs its motor's current ``cur_<joint>``).
    couplings : iterable of MotorCoupling
        Motors driving several joints; each must be named after one of its joints (whose current
        column is the coupled motor's).

    Returns
    -------
    Transmission
        ``C``: the identity, with a coupled motor's column its weights.

    Raises
    ------
    BaseparamsError
        A coupling not named after one of its joints, two couplings on one joint's motor, or a
        singular transmission.
    """
    joints = tuple(joints)
    where = {j: k for k, j in enumerate(joints)}
    c = np.eye(len(joints))
    seen = set()
    for cp in couplings:
        if cp.name not in cp.joints:
            raise BaseparamsError(f"motor coupling {cp.name!r}: with currents, name a coupling after the joint whose "
                                  f"current column is its motor's (e.g. couplings={cp.joints[-1]}:"
                                  f"{','.join(f'{j}={w:g}' for j, w in zip(cp.joints, cp.weights))})")
        if cp.name in seen:
            raise BaseparamsError(f"motor couplings: two on the motor of {cp.name!r}")
        seen.add(cp.name)
        col = np.zeros(len(joints))
        for j, w in zip(cp.joints, cp.weights):
            col[where[j]] = w
        c[:, where[cp.name]] = col
    if abs(np.linalg.det(c)) < 1e-12 * max(1.0, float(np.abs(c).max())) ** len(joints):
        raise BaseparamsError(f"motor couplings {[cp.name for cp in couplings]}: the transmission from the motors' "
                              f"currents to the joints is singular (each motor must add a direction)")
    return Transmission(joints, c)


@dataclass(frozen=True, eq=False)
class GainFit:
    """The fitted gains, values and what the data determine (:func:`fit_gains`).

    Parameters
    ----------
    theta : ndarray, shape ``(p,)``
        The model parameters (joint side, SI units, the anchor's scale).
    g : ndarray, shape ``(m,)``
        Inverse gains ``1 / k`` [A per N m].
    weights : ndarray, shape ``(m,)``
        ``1 / sigma_r`` [1/A], the current noise per motor the fit weighted with.
    free : ndarray of bool, shape ``(m,)``
        The gains fitted with the parameters (not the anchor's, not those left out).
    left_out : tuple of int
        The motors whose gains the currents do not determine: their rows left out of the
        parameters' fit, each gain (and its row's own terms) regressed afterwards on the others'
        parameters (:func:`determined_motors`).
    groups : tuple of dict
        The directions beyond the scale the log does not determine (:func:`weak_groups`).
    cost : float
        The weighted residual sum of squares.
    evaluations : int
        Projected-residual evaluations of the search.
    physical : PhysicalFit, optional
        The physically consistent fit at the gains (``method="physical"``).
    """

    theta: np.ndarray
    g: np.ndarray
    weights: np.ndarray
    free: np.ndarray
    left_out: tuple = ()
    groups: tuple = ()
    cost: float = float("nan")
    evaluations: int = 0
    physical: object = None

    __repr__ = summary_repr


def row_factors(a: np.ndarray, cur: np.ndarray) -> list[np.ndarray]:
    """Per motor, the triangular factor of ``[A_r | i_r]`` over the samples.

    Parameters
    ----------
    a : ndarray, shape ``(S, m, p)``
        The motors' rows (:meth:`Transmission.motor_rows`).
    cur : ndarray, shape ``(S, m)``
        The currents [A].

    Returns
    -------
    list of ndarray, each shape ``(p + 1, p + 1)``
        ``R_r`` with ``||[A_r | i_r] x|| = ||R_r x||`` for every ``x``.
    """
    from ..numerics import StreamingQR

    p = a.shape[2]
    return [StreamingQR(p + 1).add(a[:, r], cur[:, r]).r for r in range(a.shape[1])]


def _padded(r: np.ndarray, n: int) -> np.ndarray:
    """A triangular factor with fewer rows than columns padded with zero rows."""
    return r if r.shape[0] >= n else np.vstack([r, np.zeros((n - r.shape[0], r.shape[1]))])


def projected(factors: list[np.ndarray], g: np.ndarray, w: np.ndarray, prior=None) -> tuple[np.ndarray, np.ndarray]:
    """The least-squares ``theta`` for fixed gains, and the residual vector it leaves.

    Parameters
    ----------
    factors : list of ndarray, each shape ``(p + 1, p + 1)``
        :func:`row_factors`.
    g : ndarray, shape ``(m,)``
        Inverse gains.
    w : ndarray, shape ``(m,)``
        Row weights ``1 / sigma_r``.
    prior : tuple of ndarray, optional
        ``(L (k, p), L theta0 (k,))``: rows ``L (theta - theta0)`` added to the residual.

    Returns
    -------
    theta : ndarray, shape ``(p,)``
        Minimises ``sum_r w_r^2 ||i_r - g_r A_r theta||^2`` (plus the prior's rows).
    residual : ndarray
        Its residual, one block of ``p + 1`` per motor (then the prior's): its squared norm is the
        cost.
    """
    theta, res, _, _ = _projection(factors, g, w, prior)
    return theta, res


def _projection(factors, g, w, prior=None):
    """:func:`projected`, with the orthonormal factor ``Q`` of the stacked rows and the rows themselves."""
    p = factors[0].shape[1] - 1
    blocks = [_padded(r, p + 1) * np.r_[np.full(p, g[k] * w[k]), -w[k]] for k, r in enumerate(factors)]
    if prior is not None:
        blocks.append(np.column_stack([prior[0], -prior[1]]))
    s = np.concatenate(blocks)
    q, rr = np.linalg.qr(s[:, :p])
    d = np.abs(np.diag(rr))
    tol = 1e-10 * max(float(d.max()), np.finfo(float).tiny)
    if d.min() <= tol:  # rank-deficient at these gains (a row left out, a gain at zero): a negligible ridge
        cols = np.linalg.norm(s[:, :p], axis=0)
        ridge = np.diag(tol * np.where(cols > 0, cols / max(float(cols.max()), np.finfo(float).tiny), 1.0))
        q, rr = np.linalg.qr(np.vstack([s[:, :p], ridge]))
        q = q[: len(s)]
    theta = np.linalg.solve(rr, -(q.T @ s[:, p]))
    return theta, s[:, :p] @ theta + s[:, p], q, s


def homogeneous(factors: list[np.ndarray], w: np.ndarray) -> np.ndarray:
    """The currents' columns of ``[A | -diag(i)]`` projected off the regressor's span: their Gram matrix.

    ``A theta = diag(i) k`` is linear and homogeneous in ``(theta, k)``; eliminating ``theta`` by
    least squares leaves ``k^T G k`` (row ``r`` weighted by ``w_r``), the naive torque residual of
    gains ``k``. From the streamed factors: the triangular factor of the stacked ``[A_r | -i_r e_r]``
    (``p + m`` columns), whose trailing ``m x m`` block ``R22`` gives ``G = R22^T R22``.

    Parameters
    ----------
    factors : list of ndarray, each shape ``(p + 1, p + 1)``
        :func:`row_factors`.
    w : ndarray, shape ``(m,)``
        Row weights.

    Returns
    -------
    ndarray, shape ``(m, m)``
        ``G``, symmetric positive semidefinite.
    """
    from ..numerics import StreamingQR

    m, p = len(factors), factors[0].shape[1] - 1
    qr = StreamingQR(p + m)
    for r, f in enumerate(factors):
        blk = np.zeros((f.shape[0], p + m))
        blk[:, :p] = f[:, :p] * w[r]
        blk[:, p + r] = -f[:, p] * w[r]
        qr.add(blk)
    r22 = _padded(qr.r, p + m)[p:, p:]
    return r22.T @ r22


def noise_levels(factors: list[np.ndarray], samples: int) -> np.ndarray:
    """Each motor's current noise: the residual of its current regressed on every column of its row.

    The row's own least squares with no gain tying it to the others (any ``k_r``, every column
    free): what no model of this form explains, per sample.

    Parameters
    ----------
    factors : list of ndarray
        :func:`row_factors`.
    samples : int
        Samples fitted.

    Returns
    -------
    ndarray, shape ``(m,)``
        ``sigma_r`` [A] (floored at ``1e-12`` of the largest).
    """
    p = factors[0].shape[1] - 1
    out = np.zeros(len(factors))
    for r, f in enumerate(factors):
        f = _padded(f, p + 1)
        used = int(np.count_nonzero(np.abs(np.diag(f)[:p]) > 1e-12 * max(float(np.abs(f).max()), 1e-300)))
        out[r] = abs(f[p, p]) / math.sqrt(max(samples - used, 1))
    return np.maximum(out, 1e-12 * max(float(out.max()), np.finfo(float).tiny))


def total_least_squares(factors: list[np.ndarray], w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The gains' directions in closed form: the eigenvectors of ``G``, least eigenvalue first.

    ``min_k k^T G k / k^T k`` (:func:`homogeneous`, rows weighted by ``w_r = 1 / sigma_r``,
    :func:`noise_levels`): errors only in the currents, each of unit variance after the weighting,
    so the denominator is the noise's size in every direction and nothing collapses (shrinking a
    gain shrinks both); the global minimum, no starting point (total least squares with the noise's
    known shape). The start of the maximum-likelihood search (:func:`fit_gains`), not its estimate.
    The eigenvalues are noise-normalised: the first is the noise's floor, a gain direction the
    currents do not fix (a joint whose rigid-body torque is below its noise) is another at that
    floor, and a determined one lies above it by its signal-to-noise ratio
    (:func:`determined_motors`).

    Parameters
    ----------
    factors : list of ndarray
        :func:`row_factors`.
    w : ndarray, shape ``(m,)``
        Row weights ``1 / sigma_r``.

    Returns
    -------
    vectors : ndarray, shape ``(m, m)``
        Column ``j``: the gains ``k`` of eigenvalue ``j`` (up to a common factor), orthonormal;
        the first the estimate's start.
    eigenvalues : ndarray, shape ``(m,)``
        Ascending.
    """
    lam, vec = np.linalg.eigh(homogeneous(factors, w))
    return vec, lam


#: a second eigenvalue of the currents' homogeneous system within this factor of the first: a second gain
#: direction the currents do not fix (its signal below the noise's; :func:`determined_motors`)
SECOND = 2.0


def determined_motors(factors: list[np.ndarray], w: np.ndarray, anchor: int | None,
                      motors: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """The motors whose gains the currents determine, and the start of their gains.

    While the homogeneous system (:func:`total_least_squares`) of the motors kept has a second
    eigenvalue within :data:`SECOND` x its first, a second direction of the gains is at the noise's
    floor: the motor whose own axis lies most inside the directions at that floor (a joint whose
    rigid-body torque is below its current's noise, a symmetric wrist: changing its gain alone
    changes nothing) is left out, and the rest decided again; never the anchor.

    Parameters
    ----------
    factors : list of ndarray
        :func:`row_factors`.
    w : ndarray, shape ``(m,)``
        Row weights ``1 / sigma_r`` (:func:`noise_levels`).
    anchor : int, optional
        The anchored motor (never left out).
    motors : tuple of str
        Their names, for messages.

    Returns
    -------
    used : ndarray of bool, shape ``(m,)``
        The motors kept.
    k : ndarray, shape ``(m,)``
        Their gains' direction (0 for those left out).
    left_out : list of int
        The motors left out, in order.

    Raises
    ------
    BaseparamsError
        Nothing but the anchor left with another motor (not reached: one motor alone stops).
    """
    used = np.ones(len(factors), dtype=bool)
    left: list[int] = []
    while True:
        sub = np.flatnonzero(used)
        vec, lam = total_least_squares([factors[r] for r in sub], w[sub])
        if len(sub) < 2 or not lam[1] < SECOND * max(lam[0], np.finfo(float).tiny):
            break
        near = lam < SECOND * max(lam[0], np.finfo(float).tiny)  # the directions at the noise's floor
        inside = np.sum(vec[:, near] ** 2, axis=1)  # how much of each motor's own axis lies among them
        if anchor is not None:
            inside[sub == anchor] = -1.0
        drop = int(sub[np.argmax(inside)])
        if drop == anchor:  # pragma: no cover - the anchor is never the only motor left with another
            raise BaseparamsError(f"gain_anchor= {motors[anchor]}: the currents do not determine the others' gains")
        used[drop] = False
        left.append(drop)
    k = np.zeros(len(factors))
    k[sub] = vec[:, 0]
    return used, k, left


def solve_gains(factors: list[np.ndarray], g: np.ndarray, free: np.ndarray, w: np.ndarray,
                prior=None) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Variable projection: the free gains minimising the projected residual (:func:`projected`).

    Parameters
    ----------
    factors : list of ndarray, each shape ``(p + 1, p + 1)``
        :func:`row_factors`.
    g : ndarray, shape ``(m,)``
        Inverse gains: the fixed ones' values, the free ones' starting values.
    free : ndarray of bool, shape ``(m,)``
        The gains searched.
    w : ndarray, shape ``(m,)``
        Row weights ``1 / sigma_r``.
    prior : tuple of ndarray, optional
        Prior rows (:func:`projected`).

    Returns
    -------
    g : ndarray, shape ``(m,)``
        Inverse gains at the minimum.
    theta : ndarray, shape ``(p,)``
        The model parameters there.
    cost : float
        The weighted residual sum of squares.
    evaluations : int
        Projected-residual evaluations.
    """
    from scipy.optimize import least_squares

    g = np.array(g, dtype=float)
    evaluations = 1
    if free.any():
        fun, jac = _varpro(factors, g, free, w, prior)
        sol = least_squares(fun, g[free], jac=jac, x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12,
                            max_nfev=500)
        g[free] = sol.x
        evaluations = int(sol.nfev)
    theta, res = projected(factors, g, w, prior)
    return g, theta, float(res @ res), evaluations


def _varpro(factors, g, free, w, prior):
    """The projected residual of the free gains and its Jacobian (Kaufman's approximation), sharing one QR."""
    cols = np.flatnonzero(free)
    p = factors[0].shape[1] - 1
    sizes = [len(_padded(r, p + 1)) for r in factors]
    starts = np.r_[0, np.cumsum(sizes)]
    cache: dict = {}

    def solve(x):
        key = x.tobytes()
        if key not in cache:
            gg = g.copy()
            gg[cols] = x
            cache.clear()
            cache[key] = _projection(factors, gg, w, prior)
        return cache[key]

    def fun(x):
        return solve(x)[1]

    def jac(x):
        theta, _, q, s = solve(x)
        d = np.zeros((len(s), len(cols)))
        for k, r in enumerate(cols):  # d(rows of motor r) / d g_r, applied to theta
            sl = slice(starts[r], starts[r + 1])
            d[sl, k] = _padded(factors[r], p + 1)[:, :p] @ theta * w[r]
        return d - q @ (q.T @ d)

    return fun, jac


def jacobian(a: np.ndarray, theta: np.ndarray, g: np.ndarray, free: np.ndarray) -> np.ndarray:
    """The currents' model ``g_r A_r theta`` differentiated by ``theta`` and the free inverse gains.

    Parameters
    ----------
    a : ndarray, shape ``(S, m, p)``
        The motors' rows.
    theta : ndarray, shape ``(p,)``
        Model parameters.
    g : ndarray, shape ``(m,)``
        Inverse gains.
    free : ndarray of bool, shape ``(m,)``
        The gains that are parameters.

    Returns
    -------
    ndarray, shape ``(S, m, p + f)``
        ``[g_r A_r | (A_r theta) e_r]`` (unweighted; ``f`` free gains): at ``[theta; 0]`` it gives
        the predicted currents, so it is the linearised model's regressor.
    """
    tau = a @ theta
    cols = np.flatnonzero(free)
    extra = np.zeros(a.shape[:2] + (len(cols),))
    for k, r in enumerate(cols):
        extra[:, r, k] = tau[:, r]
    return np.concatenate([a * g[None, :, None], extra], axis=2)


def weak_groups(jac: np.ndarray, w: np.ndarray, names: list[str], ratio: float = WEAK_RATIO) -> list[dict]:
    """The directions the log does not determine: below a spectrum gap and ``ratio`` of the largest value.

    Parameters
    ----------
    jac : ndarray, shape ``(S, m, q)``
        :func:`jacobian` (its columns the model parameters, then the free gains).
    w : ndarray, shape ``(m,)``
        Row weights.
    names : list of str, shape ``(q,)``
        The columns' names (the gains as ``g_<motor>``); a column no weighted row sees is left out.
    ratio : float
        Largest relative singular value of an undetermined direction.

    Returns
    -------
    list of dict
        ``{"members": [name, ...], "weights": [...], "singular_value": float}`` per direction,
        members by decreasing weight (at most :data:`GROUP_MEMBERS`, those above a tenth of the
        largest), column-scaled.
    """
    from ..numerics import spectrum

    x = (jac * w[None, :, None]).reshape(-1, jac.shape[2])
    scale = np.linalg.norm(x, axis=0)
    seen = np.flatnonzero(scale > 0)  # a left-out row's own terms: seen by no fitted row, not a direction here
    names = [names[i] for i in seen]
    _, s, vt = np.linalg.svd(x[:, seen] / scale[seen], full_matrices=False)
    spec = spectrum(s)
    rel = spec.values
    cut = next((c for c in spec.cuts if c < len(rel) and rel[c] <= ratio), None) if len(rel) else None
    if cut is None:
        return []
    out = []
    for k in range(cut, len(rel)):
        v = vt[k] / np.abs(vt[k]).max()  # column-scaled: which columns take part
        order = [i for i in np.argsort(-np.abs(v)) if abs(v[i]) >= 0.1][:GROUP_MEMBERS]
        out.append({"members": [names[i] for i in order], "weights": [float(v[i]) for i in order],
                    "singular_value": float(rel[k])})
    return out


def fit_gains(a: np.ndarray, cur: np.ndarray, names: list[str], motors: tuple[str, ...],
              anchor: tuple[int, float] | None = None, weighted: bool = True) -> GainFit:
    """The errors-in-variables estimate of the model parameters and the gains (module docstring).

    Starting gains: the closed-form total least squares of the homogeneous system
    (:func:`total_least_squares`), the global minimum of its own criterion, so no seed from the
    model file can put a gain in the wrong basin (a tool the file lacks, a joint the file barely
    loads). The free gains are then searched by variable projection (:func:`solve_gains`) with
    per-motor weights ``1 / sigma_r`` (each row's own residual first, :func:`noise_levels`, then the
    estimate's); a gain in
    a direction the log does not determine (:func:`weak_groups`), or known to worse than its own
    size, is scanned once along its axis (:func:`scan_gain`: out of a collapse's flat valley), then
    left out like the motors the closed form leaves out (:func:`determined_motors`).

    Parameters
    ----------
    a : ndarray, shape ``(S, m, p)``
        The motors' rows (:meth:`Transmission.motor_rows` of the fitted, filtered rows).
    cur : ndarray, shape ``(S, m)``
        Currents [A], filtered like the rows.
    names : list of str, shape ``(p,)``
        Model parameter names.
    motors : tuple of str, shape ``(m,)``
        The motors' names (a gain is named ``g_<motor>`` in a group).
    anchor : (int, float), optional
        The anchored motor and its inverse gain ``1 / k``; default the motor of the largest
        torque, at gain 1 (:func:`file_scale` then sets the scale).
    weighted : bool
        Weights ``1 / sigma_r`` (maximum likelihood); False: every ampere alike.

    Returns
    -------
    GainFit
        The estimate.

    Raises
    ------
    BaseparamsError
        The anchored motor's current is explained by no torque of the model (it cannot carry the
        scale to the others).
    """
    m = a.shape[1]
    factors = row_factors(a, cur)
    spread = np.std(cur, axis=0)
    sigma = noise_levels(factors, len(cur))
    w = np.ones(m) if not weighted else 1.0 / sigma
    used, k0, left = determined_motors(factors, 1.0 / sigma, None if anchor is None else anchor[0], motors)
    idx = int(np.argmax(np.abs(k0) * spread * used)) if anchor is None else anchor[0]  # default: largest torque
    if not abs(k0[idx]) > 0:
        raise BaseparamsError(f"motor {motors[idx]}: its current is explained by no torque of the model (it cannot "
                              f"carry the scale to the others)")
    g0 = np.zeros(m)
    g0[used] = (k0[idx] / k0[used]) * (anchor[1] if anchor is not None else 1.0 / k0[idx])
    free = used & (np.arange(m) != idx)
    groups: list[dict] = []
    scanned, g = set(), g0.copy()
    for _ in range(2 * m + 1):  # each gain scanned once, then left out
        fitted = _weighted_search(factors, a, cur, g, free, w * used, weighted)
        g, theta = fitted[0].copy(), fitted[1]
        gnames = [f"g_{motors[r]}" for r in np.flatnonzero(free)]
        groups = weak_groups(jacobian(a, theta, g, free), fitted[2], list(names) + gnames)
        loose = _undetermined_gains(groups, gnames, fitted[4], g, free)
        if not loose:
            break
        for r in loose:  # a collapse (the gain run to 0 or infinity) or a flat basin: scanned once, then left out
            g[r] = scan_gain(factors, g, r, fitted[2], abs(g0[r]))
        stuck = [r for r in loose if r in scanned]
        scanned |= set(loose)
        used[stuck], free[stuck], g[stuck] = False, False, 0.0
        left += stuck
    theta, g = _left_out_rows(a, cur, theta, g, left)
    return GainFit(theta, g, fitted[2] * used, free, tuple(left), tuple(groups), fitted[3], fitted[5])


def _left_out_rows(a, cur, theta, g, left):
    """Each left-out motor's current regressed on the kept motors' torque on its row and its own terms.

    What predicts its currents; its gain is not determined (that torque is at the noise, and its
    errors bias the regression): no standard deviation is claimed for it.
    """
    theta, g = theta.copy(), g.copy()
    touched = (a != 0).any(axis=0)  # (m, p): the rows each column acts on
    for r in left:
        own = touched[r] & (touched.sum(axis=0) == 1)
        x = np.column_stack([a[:, r, ~own] @ theta[~own], a[:, r, own]])
        scale = np.linalg.norm(x, axis=0)
        scale[scale == 0] = 1.0
        coef = np.linalg.lstsq(x / scale, cur[:, r], rcond=1e-10)[0] / scale
        g[r] = coef[0]
        if g[r] != 0:
            theta[own] = coef[1:] / g[r]
    return theta, g


#: the factors a gain is scanned over, each sign, around its closed-form start (:func:`scan_gain`)
SCAN = 10.0 ** np.linspace(-2.0, 2.0, 33)


def scan_gain(factors: list[np.ndarray], g: np.ndarray, r: int, w: np.ndarray, around: float) -> float:
    """The best inverse gain of one motor on a grid, the others fixed (the parameters re-fitted).

    Along one gain the projected cost has a basin at the physical value and runs flat towards a
    collapse (the gain to zero or infinity, its row's torque bent to nothing); a start in the flat
    part runs away. The grid spans two decades either way, both signs.

    Parameters
    ----------
    factors : list of ndarray
        :func:`row_factors`.
    g : ndarray, shape ``(m,)``
        Inverse gains (``r``'s is replaced).
    r : int
        The motor.
    w : ndarray, shape ``(m,)``
        Row weights.
    around : float
        The grid's centre, an inverse gain's size.

    Returns
    -------
    float
        The grid's best inverse gain of motor ``r``.
    """
    gg = np.array(g, dtype=float)
    cands = np.r_[SCAN, -SCAN] * around
    costs = []
    for c in cands:
        gg[r] = c
        res = projected(factors, gg, w)[1]
        costs.append(float(res @ res))
    return float(cands[int(np.argmin(costs))])


def _weighted_search(factors, a, cur, g0, free, w, weighted: bool):
    """:func:`solve_gains` with the weights re-estimated from its residuals once (WLS), and the gains' relative std."""
    g, theta, cost, nfev = solve_gains(factors, g0, free, w)
    if weighted:
        e = cur - g * (a @ theta)
        rms = np.sqrt(np.mean(e**2, axis=0))
        w = np.where(w > 0, 1.0 / np.where(rms > 0, rms, np.max(rms) if np.max(rms) > 0 else 1.0), 0.0)
        g, theta, cost, more = solve_gains(factors, g, free, w)
        nfev += more
    rel = _relative_std(a, cur, theta, g, free, w)
    return g, theta, w, cost, rel, nfev


def _relative_std(a, cur, theta, g, free, w) -> np.ndarray:
    """``std(g_r) / |g_r|`` of the free gains by the white formula (inf where the Jacobian is singular)."""
    jac = jacobian(a, theta, g, free)
    x = (jac * w[None, :, None]).reshape(-1, jac.shape[2])
    e = ((cur - g * (a @ theta)) * w).reshape(-1)
    scale = np.linalg.norm(x, axis=0)
    seen = scale > 0  # a left-out row's own terms: no fitted row sees them
    s2 = float(e @ e) / max(len(e) - int(seen.sum()), 1)
    nf = int(free.sum())
    if not seen[a.shape[2]:].all():
        return np.full(nf, np.inf)
    try:
        inv = np.linalg.inv(np.linalg.qr(x[:, seen] / scale[seen], mode="r"))
    except np.linalg.LinAlgError:
        return np.full(nf, np.inf)
    var = np.sum(inv**2, axis=1)[len(inv) - nf:] * s2 / scale[a.shape[2]:] ** 2
    gf = np.abs(g[free])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(gf > 0, np.sqrt(var) / gf, np.inf)


def _undetermined_gains(groups: list[dict], gnames: list[str], rel: np.ndarray, g: np.ndarray,
                        free: np.ndarray) -> list[int]:
    """The free gains to hold: the largest gain of each undetermined group, and any known to worse than its size."""
    cols = np.flatnonzero(free)
    loose = set()
    for grp in groups:
        gains = [n for n in grp["members"] if n in gnames]
        if gains:
            loose.add(int(cols[gnames.index(gains[0])]))
    loose |= {int(cols[k]) for k in np.flatnonzero(~(rel <= 1.0))}
    return sorted(loose)


def covariance(a: np.ndarray, cur: np.ndarray, fit: GainFit, kind: str = "hac") -> tuple[np.ndarray, str]:
    """The covariance of the model parameters and the free inverse gains, on the linearised model.

    At the estimate the model ``g_r A_r theta`` is linear in ``[theta; dg]`` with the regressor
    :func:`jacobian`; its (weighted) least-squares covariance is the estimate's to first order: the
    white formula, or the HAC sandwich (:func:`baseparams.ident.uncertainty.hac_covariance`) for the
    correlated residuals real currents have.

    Parameters
    ----------
    a : ndarray, shape ``(S, m, p)``
        The motors' rows.
    cur : ndarray, shape ``(S, m)``
        Currents [A].
    fit : GainFit
        The estimate.
    kind : {"hac", "white"}
        The covariance.

    Returns
    -------
    cov : ndarray, shape ``(p + f, p + f)``
        Of ``[theta; g_free]`` (``f`` free gains); the anchor's gain and those left out are fixed;
        NaN on the diagonal of a term no fitted row sees (a left-out motor's own terms).
    label : str
        How it was computed.
    """
    from .uncertainty import describe, hac_covariance, psd

    full = jacobian(a, fit.theta, fit.g, fit.free)
    seen = np.linalg.norm((full * fit.weights[None, :, None]).reshape(-1, full.shape[2]), axis=0) > 0
    jac = full[:, :, seen]  # a left-out row's own terms: no fitted row sees them (their std: NaN)
    x = (jac * fit.weights[None, :, None]).reshape(-1, jac.shape[2])
    scale = np.linalg.norm(x, axis=0)
    r = np.linalg.qr(x / scale, mode="r") * scale[None, :]  # R^T R = x^T x, rows scaled for conditioning
    lin = np.r_[fit.theta, np.zeros(full.shape[2] - len(fit.theta))][seen]
    if kind == "white":
        e = ((cur - jac @ lin) * fit.weights).reshape(-1)
        inv = np.linalg.inv(r)
        sub, label = psd(inv @ inv.T * float(e @ e) / max(len(e) - len(lin), 1)), describe("white")
    else:
        sub, b = hac_covariance([(jac, cur)], r, lin, fit.weights, cur.size, len(cur))
        sub, label = psd(sub), describe("hac", b)
    cov = np.diag(np.where(seen, 0.0, np.nan))
    cov[np.ix_(seen, seen)] = sub
    return cov, label


def file_scale(tau: np.ndarray, tau_file: np.ndarray) -> tuple[float, float]:
    """The common factor ``s`` that brings identified gravity torques closest to the model file's.

    Masses and the centres of mass are what a model file knows best (a CAD model's, a
    manufacturer's); their gravity torques along the log's motion, ``tau_g``, are the scale's
    reference: ``s = <tau_file, tau> / <tau, tau>`` over every joint and sample. Its relative
    standard deviation is the spread of the joints' own factors ``s_j`` about it (each weighted by
    its gravity torque's size): how far the file's mass distribution disagrees with the currents.

    Parameters
    ----------
    tau : ndarray, shape ``(S, m)``
        Gravity torques of the identified parameters at an arbitrary scale.
    tau_file : ndarray, shape ``(S, m)``
        The model file's, at the same states.

    Returns
    -------
    s : float
        The factor.
    rel_std : float
        Its relative standard deviation.

    Raises
    ------
    BaseparamsError
        No gravity torque along the motion (a robot moving in a horizontal plane): the file cannot
        give the scale (give an anchor).
    """
    num = np.einsum("sj,sj->j", tau, tau_file)
    den = np.einsum("sj,sj->j", tau, tau)
    if not den.sum() > 0 or not np.einsum("sj,sj->", tau_file, tau_file) > 0:
        raise BaseparamsError("the gains' scale: no gravity torque along this motion to compare with the model file's "
                              "masses; give gain_anchor=JOINT=K")
    s = float(num.sum() / den.sum())
    live = den > 0
    sj = num[live] / den[live]
    spread = math.sqrt(float(np.sum(den[live] * (sj - s) ** 2) / den[live].sum()))
    return s, spread / abs(s)
