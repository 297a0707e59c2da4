"""Certification and completion of the geometric nullspace by exact numerics.

DRNG's columns are checked against the stacked TP regressor ``W`` of random samples:
``||W B|| / ||W|| ~ 0`` (every column in the nullspace) and ``rank(B) + rank(W) = 10 n``
(nothing missed). Where the principles miss directions, the basis is completed from the
numerical nullspace and those directions are marked ``numerical``. Where the singular-value
gap is too small to decide the rank, the result says so instead of guessing.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..enums import Status
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..model.scale import decision_scale
from ..numerics import (
    STRUCTURED_MIN_BODIES,
    NumericalResult,
    StreamingQR,
    default_samples,
    numerical_nullspace,
    rows_spec,
    stacked_regressor,
)
from ..pga.linalg import column_basis
from .columns import Columns, to_dense
from .drng import DRNGResult, drng
from .practical import PRACTICAL_TOL, PracticalRank

#: how :func:`certify` decides the rank
METHODS = ("auto", "dense", "structured")
#: the structured check forms the dense orthonormal basis only up to this many entries (10 n x nullity)
DENSE_BASIS_MAX = 4_000_000


@dataclass(frozen=True, eq=False)
class Certificate:
    """Outcome of checking DRNG against the numerical method.

    Returned by :func:`certify`. The checks are made on parameters ``pi / d`` (``d``: ones for a
    robot of ordinary size, :func:`baseparams.model.scale.decision_scale`), with ``W`` their
    stacked regressor; they are the paper's criteria (eq. "criteria": ``||W B_null||_F = 0`` and
    the ranks) with tolerances. ``certified`` is true when the nullspace is known (``status``
    certified or completed); ``nullity`` is ``basis.shape[1]``.

    Parameters
    ----------
    drng : DRNGResult
        The DRNG result that was checked.
    numerical : NumericalResult
        The numerical method's rank decision on ``W`` (:func:`baseparams.numerics.numerical_nullspace`).
        From the structured check (:mod:`.structured`, large trees): ``rank`` is the rank proven
        block by block, no singular values or bases (empty arrays), ``tol`` the ``rtol`` of the
        magnitude-normalised blocks and ``gap`` the smallest singular value kept over the
        blocks divided by the worst column residual.
    basis : ndarray, shape ``(10 n, nullity)``, or None
        Orthonormal nullspace basis (paper convention: spatial pseudo-inertia entries ``XX XY
        XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at q = 0; SI units), DRNG's span
        first, then the ``completed`` numerical directions. ``None`` from the structured check
        when it would exceed :data:`DENSE_BASIS_MAX` entries (``columns`` spans the nullspace).
    drng_rank : int
        Dimension of DRNG's span (rank of its columns on ``pi / d``).
    completed : int
        Number of directions added from the numerical nullspace (marked ``numerical``).
    residual : float
        ``||W B_drng||_F / ||W||_F`` with orthonormal ``B_drng`` (structured check: the root mean
        square of the column residuals, each relative to the size of its terms).
    max_column_residual : float
        The worst single DRNG column (unit norm): ``||W b|| / ||W||_2`` (structured check:
        relative to the size of its terms, :func:`.structured.column_residuals`).
    status : Status or str
        ``certified``, ``completed``, ``undecided`` or ``failed`` (a
        :class:`~baseparams.enums.Status`; a string given is converted, an unknown one refused).
    message : str
        Why: the ranks compared, the tolerance and singular-value gap, or what to try instead.
    seconds : float
        Wall-clock time of the whole check (DRNG included when :func:`certify` ran it).
    sampling : dict, optional
        What the sampling did (``requested``, ``kept`` and, for loops, ``cond_max``,
        ``not_converged``, ``branch_jumps``, ``ill_conditioned``, ``max_loop_residual``).
    span : ndarray, shape ``(10 n, nullity)``, optional
        The same nullspace, SI units, each entry exact to its own scale (columns not
        orthonormal): what regrouping should be given, since an SI-orthonormal basis carries
        only absolute precision in its small (millimetre-scale) entries. ``None`` with ``basis``.
    columns : Columns, optional
        From the structured check: ``nullity`` linearly independent columns in compact form
        spanning the nullspace (SI ``paper`` convention), what
        :func:`baseparams.base.sparse.tree_base_parameters` regroups.
    practical : PracticalRank, optional
        Where the literal singular-value gap could not decide and ``certify(practical=True)``:
        the rank decided by each direction's effect on the torques at the model's own scales
        (:mod:`.practical`); the nullspace is then DRNG's span completed by the directions
        counted out. ``None``: the literal decision.

    Raises
    ------
    ValueError
        An unknown ``status`` string.
    """

    drng: DRNGResult
    numerical: NumericalResult
    basis: np.ndarray
    drng_rank: int
    completed: int
    residual: float
    max_column_residual: float
    status: Status
    message: str
    seconds: float
    sampling: dict | None = None
    span: np.ndarray | None = None
    columns: Columns | None = None
    practical: PracticalRank | None = None

    __repr__ = summary_repr

    def __post_init__(self) -> None:
        object.__setattr__(self, "status", Status(self.status))

    @property
    def certified(self) -> bool:
        """True when the nullspace is known: ``status`` certified or completed."""
        return self.status.ok

    @property
    def nullity(self) -> int:
        """Dimension of the (certified or completed) nullspace: ``drng_rank + completed``."""
        return self.drng_rank + self.completed


def certify(robot: Robot, samples: int | None = None, seed: int = 0, rows: str = "all",
            result: DRNGResult | None = None, rtol: float = 1e-9, min_gap: float = 1e4,
            residual_tol: float = 1e-8, method: str = "auto", practical: bool = False,
            practical_tol: float = PRACTICAL_TOL) -> Certificate:
    """Certify (and if needed complete) DRNG's nullspace with ``samples`` random states.

    Steps: the stacked regressor ``W`` and its numerical nullspace; every DRNG column checked
    against ``W`` (:func:`_column_residuals`); the ranks compared (:func:`_verdict`); where DRNG
    misses directions and more samples do not raise the rank, the basis is completed
    (:func:`_complete`). The paper's check (eq. "criteria": ``rank(Y B) = rank(B)`` and
    ``||Y B_null||_F = 0``) with tolerances, on parameters ``pi / d``
    (:func:`baseparams.model.scale.decision_scale`) so that the decision does not depend on the
    unit of length.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies, ``10 n`` parameters).
    samples : int, optional
        Random states; default :func:`baseparams.numerics.default_samples` (100 for trees, the
        paper's 5 000 actuated samples for small loop robots); the structured check's default is
        :data:`.structured.STRUCTURED_SAMPLES` (each diagonal block still has far more rows than
        its at most ten columns).
    seed : int, default 0
        Seed of the random states (the saturation check draws a second set with another seed).
    rows : str or sequence of str, default "all"
        The measured generalized forces: ``all``, ``joints``, ``base`` or a set of joints
        (:func:`baseparams.numerics.row_mask`; loop robots: ``"all"`` only). The check is the
        regressor restricted to those rows, whatever DRNG's rules for them.
    result : DRNGResult, optional
        DRNG's result to check; default ``drng(robot, rows=rows)``.
    rtol : float, default 1e-9
        Singular-value threshold of the numerical rank, relative to the largest.
    min_gap : float, default 1e4
        Smallest singular-value gap ``s[rank-1] / s[rank]`` that decides the numerical rank.
    residual_tol : float, default 1e-8
        Largest relative residual ``||W b|| / ||W||_2`` of a DRNG column (unit norm) in the
        nullspace; a worse column fails the check.
    method : {"auto", "dense", "structured"}, default "auto"
        ``dense``: the stacked regressor and its SVD (memory quadratic in ``n``). ``structured``:
        for a tree whose joint rows are measured (all or some of them), rank decided body by body
        (:func:`.structured.structured_check`, memory linear in ``n``); where it cannot decide
        (a deficiency no merge explains) the dense check runs if it fits in memory, else the
        result is ``undecided``. ``auto``: structured for such trees of at least
        :data:`.structured.STRUCTURED_MIN_BODIES` bodies, dense otherwise.
    practical : bool, default False
        Where the singular-value gap is below ``min_gap`` (the rank is not decided, or more
        samples change it), decide it by each direction's effect on the torques at the model's
        own mass, size and rate scales (:func:`.practical.practical_rank`): directions below
        ``practical_tol`` of the torque scale are counted out, the nullspace completed by them,
        and the certificate's ``practical`` says so. ``False``: such a rank is ``undecided``.
    practical_tol : float, default :data:`.practical.PRACTICAL_TOL`
        The practical decision's threshold, relative to the torque scale.

    Returns
    -------
    Certificate
        The verdict (``certified``, ``completed``, ``undecided`` or ``failed``, with a message)
        and the orthonormal nullspace basis ``(10 n, nullity)`` in the ``paper`` convention
        (world frame at q = 0, SI units), DRNG's span first.

    Raises
    ------
    BaseparamsError
        Unknown ``rows`` or ``method``, ``rows`` other than ``"all"`` on a loop robot, no sample
        closing the loops (from :func:`baseparams.numerics.stacked_regressor`), or ``structured``
        where it does not apply.
    """
    t0 = time.perf_counter()
    rows = rows_spec(rows)
    res = drng(robot, rows=rows) if result is None else result
    if res.rows != rows:
        raise BaseparamsError(f"robot {robot.name!r}: the DRNG result was computed for rows {res.rows!r}, "
                              f"certification asked for {rows!r}")
    if uses_structured(robot, rows, method):
        from .structured import STRUCTURED_SAMPLES

        dense_samples = default_samples(robot) if samples is None else samples
        cert = _structured(robot, res, STRUCTURED_SAMPLES if samples is None else samples, seed, rows, rtol,
                           min_gap, residual_tol, t0, dense_samples)
        if cert is not None:
            return cert
    samples = default_samples(robot) if samples is None else samples
    sampling: dict = {}
    # ranks are decided on pi / d (model.scale.decision_scale): d = 1 for a robot of ordinary
    # size; a robot drawn in millimetres or kilometres is brought to an ordinary-sized equivalent
    d = decision_scale(robot, "paper")
    # W (S * rows, 10 n) enters only through its triangular factor R: same singular values,
    # nullspace and norms ||W x|| = ||R x||, at (10 n)^2 memory
    qr = StreamingQR(10 * robot.n).add(stacked_regressor(robot, samples, seed, rows, sampling) * d)
    w = qr.r
    num = numerical_nullspace(robot, samples, seed, rows, rtol, min_gap, w=w)
    raw = res.dense() / d[:, None]
    bd = column_basis(raw)
    r_d = bd.shape[1]
    residual = float(np.linalg.norm(w @ bd) / np.linalg.norm(w)) if r_d and np.linalg.norm(w) > 0 else 0.0
    col_res, worst = _column_residuals(raw, w, num)

    def done(status: Status, message: str, basis: np.ndarray = bd, completed: int = 0, decided=None) -> Certificate:
        # back to SI parameters (the paper convention), orthonormal, DRNG's span first
        span = d[:, None] * basis
        basis = np.linalg.qr(span)[0] if basis.shape[1] else np.zeros((len(d), 0))
        return Certificate(res, num, basis, r_d, completed, residual, worst, status, message,
                           time.perf_counter() - t0, sampling, span, practical=decided)

    def by_effect(status: Status, message: str) -> Certificate:  # the gap does not decide: the effect may
        if not practical:
            return done(status, message)
        return done(*_by_effect(robot, (samples, seed, rows), num, bd, d, practical_tol, status, message))

    verdict = _verdict(res, num, qr.rows, r_d, col_res, worst, rtol, min_gap, residual_tol, sampling)
    if verdict is not None:
        gap_only = verdict[0] == Status.UNDECIDED and _gap_undecided(num, qr.rows, worst, residual_tol)
        return by_effect(*verdict) if gap_only else done(*verdict)
    # completion needs saturated numerics: more samples must not raise the rank
    qr.add(stacked_regressor(robot, samples, seed + 7919, rows) * d)
    num2 = numerical_nullspace(robot, samples, seed, rows, rtol, min_gap, w=qr.r)
    if num2.rank != num.rank or not num2.decided:
        return by_effect(Status.UNDECIDED, f"the numerical rank is not saturated ({num.rank} with {samples} samples, "
                                           f"{num2.rank} with twice as many); use more samples")
    basis, missing, distance = _complete(bd, num)
    return done(Status.COMPLETED, f"DRNG found {r_d} of {num.nullity} nullspace directions; {missing} completed from "
                             f"the numerical nullspace (distance of the added directions to DRNG's span: "
                             f"{distance:.3g} of 1); {_gap_text(num, rtol)}", basis, missing)


def _by_effect(robot: Robot, sampling: tuple, num: NumericalResult, bd: np.ndarray, d: np.ndarray, tol: float,
               status: Status, message: str) -> tuple:
    """``done``'s arguments for a rank decided by effect (:func:`.practical.practical_rank`).

    ``sampling``: ``(samples, seed, rows)``; ``bd``: DRNG's orthonormal span in ``pi / d``.
    The undecided ``(status, message)`` when the practical nullspace does not hold DRNG's span.
    """
    from .practical import practical_rank

    r_d = bd.shape[1]
    pr, null = practical_rank(robot, *sampling, num, r_d, d, tol)
    if not pr.decided:
        c = pr.straddling
        cands = "; ".join(f"{nb} base parameters if {m}" for nb, m in pr.candidates())
        return (Status.UNDECIDED, f"{message}; by each direction's effect on the torques at the model's own scales "
                                  f"the threshold {tol:g} of the torque scale falls inside a cluster of {c.count} "
                                  f"directions ({c.bottom:.2g} - {c.top:.2g} of the torque scale): no gap decides "
                                  f"({cands}); the clusters: {pr.clusters_text()}; what would decide it: the "
                                  f"file's right angles and zeros written exactly, or its numbers to more digits",
                bd, 0, pr)
    inside = float(np.max(np.linalg.norm(bd - null @ (null.T @ bd), axis=0))) if r_d else 0.0
    if pr.nullity < r_d or inside > _SPAN_TOL:
        return status, (message + f"; the practical decision does not contain DRNG's span (distance "
                                  f"{inside:.2g}): not used")
    basis, missing, _ = _complete(bd, null, pr.nullity)
    why = (f"{message}; decided by each direction's effect on the torques at the model's own scales: "
           f"{pr.counted_out} below {pr.threshold:g} of the torque scale counted out (largest "
           f"{pr.largest_out:.2g}, smallest kept {pr.smallest_kept:.2g}: decided at a gap of {pr.gap:.3g}); the "
           f"literal decision: --literal")
    return Status.COMPLETED if missing else Status.CERTIFIED, why, basis, missing, pr


def _gap_text(num: NumericalResult, rtol: float) -> str:
    return f"tolerance {num.tol:.3g} (rtol {rtol:g}), singular-value gap {num.gap:.3g}"


def _column_residuals(raw: np.ndarray, w: np.ndarray, num: NumericalResult) -> tuple[np.ndarray, float]:
    """``||W b|| / ||W||_2`` of every DRNG column ``b`` of ``raw`` (normalised) ``(k,)`` and the worst."""
    if not raw.shape[1]:
        return np.zeros(0), 0.0
    w2 = num.singular_values[0] if num.singular_values[0] > 0 else 1.0
    norms = np.linalg.norm(raw, axis=0)
    raw = raw / np.where(norms > 0, norms, 1.0)  # a zero column (spans nothing) has residual 0
    col_res = np.linalg.norm(w @ raw, axis=0) / w2
    return col_res, float(col_res.max())


#: the paper's bound on cond(J_p) of loop samples; above it the rates lose precision
_COND_PAPER = 30.0


def _conditioning_tol(residual_tol: float, sampling: dict | None) -> float:
    """The column residual that rounding can explain in ill-conditioned loop samples.

    Loop samples with ``cond(J_p)`` up to ``c`` carry ``dq`` errors of about ``c`` and ``ddq``
    errors of about ``c^2`` times the closure's rounding, and ``ddq`` enters the regressor
    linearly: a residual up to ``residual_tol (c / 30)^3`` is not evidence against a column.
    """
    c = float((sampling or {}).get("cond_max", 0.0) or 0.0)
    return residual_tol * (c / _COND_PAPER) ** 3 if np.isfinite(c) and c > _COND_PAPER else residual_tol


def _verdict(res: DRNGResult, num: NumericalResult, nrows: int, r_d: int, col_res: np.ndarray, worst: float,
             rtol: float, min_gap: float, residual_tol: float,
             sampling: dict | None = None) -> tuple[Status, str] | None:
    """``(status, message)`` when the check decides without completion, else ``None``."""
    ncols = 10 * res.robot.n
    gap_txt = _gap_text(num, rtol)
    if worst > residual_tol:
        bad = np.argsort(col_res)[::-1][: int(np.sum(col_res > residual_tol))]
        where = "; ".join(res.provenance(int(k)) for k in bad[:3])
        if worst <= _conditioning_tol(residual_tol, sampling):  # rounding near a singularity can explain it
            return Status.UNDECIDED, (
                f"{len(bad)} DRNG column(s) have relative residual up to {worst:.2e} (> {residual_tol:g}), within "
                f"what the loop samples' conditioning (cond(J_p) up to {sampling['cond_max']:.3g}) can cause: "
                f"{where}; the reference is close to a singular configuration: move it away, or narrow the "
                f"actuated box to its well-conditioned side")
        return Status.FAILED, (f"{len(bad)} DRNG column(s) are not in the numerical nullspace (worst relative "
                          f"residual {worst:.2e}): {where}")
    if num.rank >= nrows or nrows < ncols:
        return Status.UNDECIDED, (f"too few samples: the stacked regressor has {nrows} rows for {ncols} "
                             f"parameters (rank {num.rank}); use more samples")
    if not num.decided:
        return Status.UNDECIDED, (f"numerical rank not decided: {gap_txt} {_undecided_why(num, min_gap)}; try "
                             f"more samples, another seed, or fix rounded angles in the model")
    if r_d + num.rank == ncols:
        return Status.CERTIFIED, f"DRNG is complete: rank(B) {r_d} + rank(W) {num.rank} = {ncols}; {gap_txt}"
    if r_d + num.rank > ncols:
        return Status.FAILED, (f"rank(B) {r_d} + rank(W) {num.rank} > {ncols}: DRNG columns and the numerical "
                          f"rank disagree ({gap_txt}); try more samples")
    return None


def _undecided_why(num: NumericalResult, min_gap: float) -> str:
    """Why a literal rank is not decided: the tolerance inside a cluster (named), or a gap below ``min_gap``."""
    spec = num.spectrum
    c = None if spec is None else spec.straddling(num.rtol)
    if c is None:
        return f"is below {min_gap:g}"
    return (f"lies inside a cluster of {c.count} singular values ({c.bottom:.2g} - {c.top:.2g} of the largest): no "
            f"gap decides between rank {c.first} and {c.stop} (clusters: {' | '.join(spec.lines())})")


#: DRNG's exact columns lie in the practical nullspace to within this (orthonormal bases)
_SPAN_TOL = 1e-3


def _gap_undecided(num: NumericalResult, nrows: int, worst: float, residual_tol: float) -> bool:
    """Whether the literal check is undecided only because of the singular-value gap."""
    return worst <= residual_tol and num.rank < nrows and nrows >= len(num.singular_values) and not num.decided


def _complete(bd: np.ndarray, num: NumericalResult | np.ndarray,
              nullity: int | None = None) -> tuple[np.ndarray, int, float]:
    """DRNG's orthonormal basis ``bd (10 n, r)`` completed by the numerical nullspace's directions outside its span.

    ``num``: the numerical result, or an orthonormal nullspace basis with its ``nullity``.
    Returns ``(basis, number added, distance of the last added to span(bd))``.
    """
    r_d = bd.shape[1]
    nb, nullity = (num.null_basis, num.nullity) if isinstance(num, NumericalResult) else (num, nullity)
    missing = nullity - r_d
    if missing == 0:
        return bd, 0, 0.0
    rest = nb - bd @ (bd.T @ nb) if r_d else nb
    u, s, _ = np.linalg.svd(rest, full_matrices=False)
    return np.concatenate([bd, u[:, :missing]], axis=1), missing, float(s[missing - 1])


def uses_structured(robot: Robot, rows: str, method: str = "auto") -> bool:
    """Whether :func:`certify` takes the structured (body-by-body) path first.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    rows : str
        The measured generalized forces.
    method : {"auto", "dense", "structured"}
        As for :func:`certify`.

    Returns
    -------
    bool
        ``structured``: always (an error later if it does not apply); ``auto``: for a tree whose
        joint rows are measured with at least :data:`.structured.STRUCTURED_MIN_BODIES` bodies.

    Raises
    ------
    BaseparamsError
        An unknown ``method``.
    """
    if method not in METHODS:
        raise BaseparamsError(f"unknown certification method {method!r}; expected one of {METHODS}")
    if method == "structured":
        return True
    if method != "auto" or robot.n < STRUCTURED_MIN_BODIES:
        return False
    from .structured import applicable  # imported only for robots that may take the path (start-up time)

    return applicable(robot, rows)


def _structured(robot: Robot, res: DRNGResult, samples: int, seed: int, rows: str, rtol: float, min_gap: float,
                residual_tol: float, t0: float, dense_samples: int) -> Certificate | None:
    """The structured check as a :class:`Certificate`, or ``None`` when the dense check should decide."""
    from . import structured  # imported for robots that take this path only (start-up time)

    chk = structured.structured_check(robot, res, samples, seed, rows, rtol, residual_tol)
    n10 = 10 * robot.n
    if chk.status == Status.UNDECIDED and structured.dense_fits(robot, dense_samples, rows):
        return None  # the dense check decides, and completes what DRNG missed
    d = decision_scale(robot, "paper")
    if chk.independent is not None and n10 * chk.rank_b > DENSE_BASIS_MAX:
        span = None  # the regrouping takes the columns; a dense basis would be quadratic
    elif chk.independent is not None:
        span = to_dense(chk.independent, robot.n)
    else:
        span = d[:, None] * column_basis(res.dense() / d[:, None])
    gap = chk.smallest_sv / chk.worst if chk.worst > 0 else np.inf
    num = NumericalResult(chk.rank_w, n10 - chk.rank_w, np.zeros(0), rtol, rtol, float(gap), np.zeros((n10, 0)),
                          np.zeros((n10, 0)), samples, chk.seconds, min_gap)
    message = chk.message
    if chk.status == Status.UNDECIDED:
        need = structured.dense_bytes(robot, dense_samples, rows)
        message += (f"; the dense check, which would decide and complete the missing directions, does not fit in "
                    f"memory (about {need / 1e9:.2g} GB); --no-verify gives DRNG's span alone")
    basis = None if span is None else np.linalg.qr(span)[0] if span.shape[1] else np.zeros((n10, 0))
    rms = float(np.sqrt(np.mean(chk.column_residuals ** 2))) if len(chk.column_residuals) else 0.0
    return Certificate(res, num, basis, chk.rank_b, 0, rms, chk.worst, chk.status, message,
                       time.perf_counter() - t0, chk.sampling, span, chk.independent)
