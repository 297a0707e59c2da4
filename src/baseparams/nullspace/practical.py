"""Practical rank: deciding a numerically ambiguous rank by each direction's effect on the torques.

The literal check (:mod:`.certify`) decides the rank of the stacked regressor from its
singular-value gap at a relative tolerance of 1e-9; near-degenerate geometry (a CAD export's
axis 1e-5 rad off parallel, offsets written to six digits) leaves directions whose singular values
spread across that tolerance, and the gap (e.g. 3e3) decides nothing. Such directions exist
literally, but what matters for identification is how much they move the joint torques at the
model's own scales. This module measures it:

* each body's parameters in its own frame (about its joint, not the world origin, so that where
  the robot stands in the world changes nothing), in their typical magnitudes: ``M L^u`` (``u``
  each parameter's length exponent: mass, first moments ``M L``, inertias ``M L^2``; ``L`` the
  robot's length, :func:`~baseparams.model.scale.length_scale`; ``M`` a common mass, which
  cancels in the relative figures; on the parameters ``pi / d`` the rank is decided on,
  :func:`~baseparams.model.scale.decision_scale`, these are ``M L_c^u``, ``L_c`` the length
  brought into :data:`~baseparams.model.scale.METRE_BAND`);
* motions at the robot's own rate ``w = sqrt(|g| / L_c)`` (the pendulum rate: velocities ``w``,
  accelerations ``w^2``, so that inertial and gravity torques are of one size: 14 rad/s for a
  hand of 5 cm or less, 3 rad/s for a 1 m arm), on the same random states as the literal check;
* the singular values of that column-scaled regressor, relative to the largest (the torque
  scale): the effect on the torques of a unit change along each direction.

A direction whose effect is below :data:`PRACTICAL_TOL` of the torque scale is counted out, but a
count is stated only at a gap of that spectrum (:func:`~baseparams.numerics.spectrum`: neighbouring
effects at least 100x apart, and 10x the ratios inside the clusters on either side): when the
threshold falls inside a cluster of effects (rounding errors of a file add directions whose effects
spread over a decade or more around it), the count is ``undecided``, and the note lists the clusters,
the count each candidate cut would state, and what would decide it.

Why 1e-6: joint torque sensors and motor-current models resolve 0.1-1 % of the torque scale;
averaging ``N`` independent samples gains ``sqrt(N)``, so an effect ``e`` needs about
``(1e-3 / e)^2`` samples to be seen at all: a million samples (17 minutes at 1 kHz, already a
long identification run) for ``e = 1e-6``, a hundred million for ``1e-7``. Model files are
written to about six significant digits (CAD exports, ``%g``), so geometry is itself known to
about 1e-6: an effect below that is the file's rounding, not the robot. Designed features well
below the robot's size stay above it: a tilt ``a`` [rad] of an axis from a degenerate direction
adds directions whose effects are about ``0.1 a`` (first order) and ``0.01 a^2`` (second order) of
the torque scale, so a 0.03 rad tilt keeps every direction in the test robots and a 0.01 rad tilt
its first-order ones (its second-order ones lie at the threshold). The threshold is used only
where the literal check cannot decide; files it decides are unaffected, and ``literal=True`` keeps
its answer (or ``undecided``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..model.inertia import LENGTH_POWER, hat, transform, unhat
from ..model.robot import Robot
from ..model.scale import METRE_BAND, length_scale
from ..numerics import Cluster, NumericalResult, Spectrum, StreamingQR, rank_decision, spectrum, stacked_regressor

#: a direction moving the torques by less than this fraction of their scale is not identifiable in practice
PRACTICAL_TOL = 1e-6
#: a direction within this factor of the threshold makes the decision borderline (said in the note)
BORDERLINE = 2.0
#: seed offset of the second sample set (as the literal saturation check)
_SECOND_SEED = 7919


@dataclass(frozen=True, eq=False)
class PracticalRank:
    """The rank decided by each direction's effect on the torques (module docstring).

    Parameters
    ----------
    threshold : float
        Directions with a relative effect below this are counted out (:data:`PRACTICAL_TOL`).
    rank, nullity : int
        The practical rank of the scaled regressor (the directions above the threshold) and
        ``10 n - rank``; meaningful only when :attr:`decided`.
    drng_rank : int
        Dimension of DRNG's exact span (part of the practical nullspace).
    literal_rank : int
        The literal check's tentative rank (at its tolerance, not decided).
    literal_gap : float
        The literal singular-value gap at that rank.
    min_gap : float
        The gap the literal check needs to decide.
    largest_out : float
        Effect of the largest direction counted out, relative to the torque scale (0 if none).
    smallest_kept : float
        Effect of the smallest direction kept, relative to the torque scale.
    length : float
        The robot's length ``L`` [m] (:func:`~baseparams.model.scale.length_scale`).
    rate : float
        The rate ``w = sqrt(|g| / L_c)`` of the sampled motions [1/s] (``L_c``: ``L`` brought into
        the metre band; 1 without gravity).
    samples : int
        Random states of each of the two sets (the decision is made on both).
    borderline : bool
        The first set alone gives another count, or a direction lies within a factor
        :data:`BORDERLINE` of the threshold.
    spectrum : Spectrum, optional
        The effects' clusters and gaps (both sets).
    """

    __repr__ = summary_repr

    threshold: float
    rank: int
    nullity: int
    drng_rank: int
    literal_rank: int
    literal_gap: float
    min_gap: float
    largest_out: float
    smallest_kept: float
    length: float
    rate: float
    samples: int
    borderline: bool = False
    spectrum: Spectrum | None = None

    @property
    def counted_out(self) -> int:
        """Directions outside DRNG's exact span counted out: ``nullity - drng_rank``."""
        return self.nullity - self.drng_rank

    @property
    def straddling(self) -> Cluster | None:
        """The cluster of effects the threshold falls inside (the count is then undecided), or None."""
        return None if self.spectrum is None else self.spectrum.straddling(self.threshold)

    @property
    def decided(self) -> bool:
        """Whether the threshold lies in a gap of the effects' spectrum (a count is stated only there)."""
        return self.straddling is None

    @property
    def gap(self) -> float:
        """The ratio of effects across the cut (smallest kept / largest counted out; inf at the ends)."""
        return self.smallest_kept / self.largest_out if self.largest_out > 0 else np.inf

    def candidates(self) -> list[tuple[int, str]]:
        """The counts a cut at the gaps around the straddled cluster would state, and what each means.

        Returns
        -------
        list of (int, str)
            ``(base-parameter count of the scaled regressor, meaning)``; empty when decided.
        """
        c = self.straddling
        if c is None:
            return []
        what = f"the {c.count} direction{'s' if c.count != 1 else ''} between {c.bottom:.2g} and {c.top:.2g}"
        return [(c.first, f"{what} not identifiable (a torque resolution coarser than {c.top:.2g} of the scale)"),
                (c.stop, f"{what} identifiable (a torque resolution finer than {c.bottom:.2g} of the scale)")]

    def clusters_text(self) -> str:
        """The effects' clusters, largest first, with the gaps between them (one phrase).

        Returns
        -------
        str
            E.g. ``34 directions 0.0065 - 1 ...; gap 684 below: rank 34 | 10 directions ...``.
        """
        return " | ".join(self.spectrum.lines()) if self.spectrum is not None else ""

    def note(self) -> str:
        """One line: what was decided and why (or why not).

        Returns
        -------
        str
            E.g. ``practical rank: ... 3 directions outside DRNG's exact span move the torques by less
            than 1e-06 of the torque scale (largest 4e-08; smallest kept 2e-03, a gap of 5e+04) ...``.
        """
        head = (f"practical rank: the literal rank is not decided (singular-value gap {self.literal_gap:.3g} < "
                f"{self.min_gap:g}); at the model's own scales (parameters M, M L, M L^2 with L {self.length:.3g} m, "
                f"motions at {self.rate:.3g} rad/s)")
        if not self.decided:
            c = self.straddling
            cands = "; ".join(f"{n} if {m}" for n, m in self.candidates())
            return (f"{head} the threshold {self.threshold:g} of the torque scale falls inside a cluster of "
                    f"{c.count} directions ({c.bottom:.2g} - {c.top:.2g}): no gap decides the count (UNDECIDED); "
                    f"the clusters: {self.clusters_text()}; candidates: {cands}; what would decide it: the file's "
                    f"right angles and zeros written exactly (or its numbers to more digits), or --literal")
        k = self.counted_out
        dirs = f"{k} direction{'s' if k != 1 else ''} outside DRNG's exact span"
        if k:
            what = (f"{dirs} move the torques by less than {self.threshold:g} of the torque scale (largest "
                    f"{self.largest_out:.2g}; smallest kept {self.smallest_kept:.2g}, a gap of {self.gap:.3g}): "
                    f"counted out")
        else:
            what = (f"every direction outside DRNG's exact span moves the torques by at least "
                    f"{self.smallest_kept:.2g} of their scale (threshold {self.threshold:g}, a gap of "
                    f"{self.gap:.3g} below): kept")
        return (f"{head} {what}; rank {self.rank}, nullity {self.nullity}, decided at that gap "
                f"(below {self.threshold:g} a direction needs more than a million samples at 0.1 % torque "
                f"precision, and six-digit files do not state it)"
                f"{'; borderline: a direction lies near the threshold' if self.borderline else ''}; "
                f"the literal decision: --literal")

    def to_json(self) -> dict:
        """The decision, machine-readable.

        Returns
        -------
        dict
            ``threshold, decided, rank, nullity, counted_out, largest_out, smallest_kept, gap,
            literal_rank, literal_gap, min_gap, length, rate, samples, borderline, clusters[{first,
            count, top, bottom, spread, gap_below}], candidates[{rank, meaning}], note``.
        """
        def num(x: float):
            return None if not np.isfinite(x) else float(x)

        sp = self.spectrum
        clusters = [] if sp is None else [
            {"first": c.first, "count": c.count, "top": c.top, "bottom": c.bottom, "spread": c.spread,
             "gap_below": num(sp.gap(c.stop))} for c in sp.clusters]
        return {"threshold": self.threshold, "decided": self.decided, "rank": self.rank, "nullity": self.nullity,
                "counted_out": self.counted_out, "largest_out": self.largest_out,
                "smallest_kept": self.smallest_kept, "gap": num(self.gap), "literal_rank": self.literal_rank,
                "literal_gap": num(self.literal_gap), "min_gap": self.min_gap, "length": self.length,
                "rate": self.rate, "samples": self.samples, "borderline": self.borderline, "clusters": clusters,
                "candidates": [{"rank": n, "meaning": m} for n, m in self.candidates()], "note": self.note()}


def practical_scales(robot: Robot, d: np.ndarray) -> tuple[float, float, np.ndarray]:
    """The length, rate and per-parameter scales of the practical decision.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    d : ndarray, shape ``(10 n,)``
        :func:`~baseparams.model.scale.decision_scale` (``paper`` convention): the parameters
        the rank is decided on are ``pi / d``.

    Returns
    -------
    length : float
        ``L`` [m]: the robot's length scale.
    rate : float
        ``sqrt(|g| / L_c)`` [1/s] (``L_c``: ``L`` brought into the metre band), 1 without gravity
        (then the rate cancels).
    scale : ndarray, shape ``(10 n,)``
        ``L_c^u`` of each parameter of ``pi / d`` (``M L^u`` of ``pi``; paper convention; the
        common mass cancels).
    """
    lo, hi = METRE_BAND
    length = length_scale(robot)
    clipped = float(min(max(length, lo), hi))
    g = float(np.linalg.norm(robot.gravity))
    rate = float(np.sqrt(g / clipped)) if g > 0 else 1.0
    scale = clipped ** np.tile(LENGTH_POWER["paper"], robot.n).astype(float)
    return float(length), rate, scale


def local_map(robot: Robot, d: np.ndarray) -> np.ndarray:
    """Each body's parameters in its own frame to the coordinates the rank is decided on.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies; ``M0`` their frames at q = 0).
    d : ndarray, shape ``(10 n,)``
        :func:`~baseparams.model.scale.decision_scale` (paper convention).

    Returns
    -------
    ndarray, shape ``(n, 10, 10)``
        Per body ``T_i``: ``(pi_world / d)_i = T_i (pi_local / d)_i``, both in the ``paper``
        convention (pseudo-inertia entries), world frame at q = 0 and body frame.
    """
    t = np.swapaxes(hat(transform(unhat(np.eye(10))[None], robot.M0[:, None])), 1, 2)
    db = d.reshape(robot.n, 10)
    return t * db[:, None, :] / db[:, :, None]


def practical_rank(robot: Robot, samples: int, seed: int, rows: str, literal: NumericalResult, drng_rank: int,
                   d: np.ndarray, tol: float = PRACTICAL_TOL) -> tuple[PracticalRank, np.ndarray]:
    """Decide the rank by each direction's effect on the torques at the model's own scales.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    samples : int
        Random states of each of the two sample sets (as the literal check).
    seed : int
        Seed of the first set (the second: ``seed + 7919``).
    rows : str
        Measured generalized forces (:func:`baseparams.numerics.row_mask`).
    literal : NumericalResult
        The literal check's (undecided) rank decision.
    drng_rank : int
        Dimension of DRNG's exact span.
    d : ndarray, shape ``(10 n,)``
        :func:`~baseparams.model.scale.decision_scale` (paper convention).
    tol : float, default :data:`PRACTICAL_TOL`
        Relative effect below which a direction is counted out.

    Returns
    -------
    (PracticalRank, ndarray of shape ``(10 n, nullity)``)
        The decision (on both sample sets; ``decided`` only when the threshold lies in a gap of
        the effects' spectrum; ``borderline`` when the first set alone differs or a direction lies
        near the threshold) and an orthonormal basis of the directions below the threshold in the
        coordinates ``pi / d`` (the practical nullspace when decided).
    """
    length, rate, scale = practical_scales(robot, d)
    ncols, n = 10 * robot.n, robot.n
    # parameters theta: pi_local / d = scale * theta per body, pi_world / d = T (pi_local / d)
    t = local_map(robot, d) * scale.reshape(n, 1, 10)
    counts, qr = [], StreamingQR(ncols)
    for s in (seed, seed + _SECOND_SEED):
        w = (stacked_regressor(robot, samples, s, rows, time_scale=rate) * d).reshape(-1, n, 10)
        qr.add(np.einsum("rik,ikl->ril", w, t).reshape(-1, ncols))
        counts.append(rank_decision(qr.r, rtol=tol, min_gap=0.0))
    one, both = counts
    spec = spectrum(both.singular_values)
    sv = spec.values
    rank = both.rank
    largest_out = float(sv[rank]) if rank < ncols else 0.0
    smallest_kept = float(sv[rank - 1]) if rank else 0.0
    near = bool(np.any((sv > tol / BORDERLINE) & (sv < tol * BORDERLINE)))
    unstable = one.rank != rank or spectrum(one.singular_values).straddling(tol) is not None
    pr = PracticalRank(tol, rank, ncols - rank, drng_rank, literal.rank, float(literal.gap), literal.min_gap,
                       largest_out, smallest_kept, length, rate, samples, near or unstable, spec)
    # back from the scaled local coordinates theta to pi / d, orthonormal
    k = both.null_basis.shape[1]
    null = np.einsum("ikl,ilj->ikj", t, both.null_basis.reshape(n, 10, k)).reshape(ncols, k)
    null = np.linalg.qr(null)[0] if null.shape[1] else null
    return pr, null
