"""DRNG's result: the columns with provenance and their exact rank, decided in decision coordinates.

:class:`DRNGResult` is what :func:`.drng.drng` returns; :func:`scaled_rank` decides a column set's
rank in the coordinates of :func:`decision_columns` (each body's parameters about its own origin,
ordinary-sized: :func:`baseparams.model.scale.decision_frames`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..enums import Source
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..model.scale import NOISE_FACTOR, decision_frames, length_scale
from ..pga.linalg import column_basis
from .columns import PAPER, Columns, to_dense, to_sparse
from .rank import block_rank


@dataclass(frozen=True, eq=False)
class DRNGResult:
    """The DRNG output: columns with provenance, their exact rank and timing.

    Returned by :func:`drng`. The columns span (part of) the nullspace of the TP regressor in the
    ``paper`` convention (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of
    each body, world frame at q = 0); they are redundant, so their rank, not their number, is
    the dimension found (``docs/paper-corrections.md``: never certify by counting columns).

    Parameters
    ----------
    robot : Robot
        The analysed robot (``n`` moving bodies, ``10 n`` parameters).
    columns : Columns
        The ``k`` columns in compact form, with provenance (:class:`~.columns.Columns`).
    rank : int
        Exact rank of ``columns`` (:func:`scaled_rank`).
    seconds : float
        Wall-clock time DRNG took.
    extended : bool, default True
        Whether the extended rules (R-A, R-B, R-L1, R-L2, R-L3, R-M) ran besides the paper's principles.
    rows : str, default "all"
        The measured rows the columns were computed for (``joints`` adds the floating root's
        unmeasured columns, a set of joints those of :func:`~.drng.unmeasured_columns`; the
        string form of :func:`baseparams.numerics.rows_spec`);
        :func:`~baseparams.nullspace.certify.certify` checks it.
    notes : tuple of str, default ()
        What the check of each rule's columns against the regressor found
        (:class:`~.checks.RuleCheck`): a rule whose columns were left out, named, or why the
        check could not run. Empty when every column passed.
    """

    robot: Robot
    columns: Columns
    rank: int
    seconds: float
    extended: bool = True
    rows: str = "all"
    notes: tuple[str, ...] = ()

    __repr__ = summary_repr

    @property
    def n_columns(self) -> int:
        """Number of columns ``k`` (not the rank: the columns are redundant)."""
        return len(self.columns)

    def sparse(self):
        """``B_null (10 n, k)`` sparse, paper convention.

        Returns
        -------
        scipy.sparse.csc_matrix, shape ``(10 n, k)``
            The columns expanded (:func:`~.columns.to_sparse`): the paper's ``B_null``
            (Algorithm "DRNG"), spatial pseudo-inertia entries of each body, world frame at q = 0.
        """
        return to_sparse(self.columns, self.robot.n)

    def dense(self) -> np.ndarray:
        """``B_null (10 n, k)`` as a dense array, paper convention.

        Returns
        -------
        ndarray, shape ``(10 n, k)``
            :meth:`sparse` as a dense array (built without scipy.sparse).
        """
        return to_dense(self.columns, self.robot.n)

    def orthonormal(self, rtol: float = 1e-10) -> np.ndarray:
        """An orthonormal basis ``(10 n, rank)`` of the columns' span.

        Parameters
        ----------
        rtol : float, default 1e-10
            Singular-value threshold relative to the largest
            (:func:`baseparams.pga.linalg.column_basis`, each column first normalised).

        Returns
        -------
        ndarray, shape ``(10 n, rank)``
            Orthonormal columns spanning the DRNG columns, paper convention (SI units, world
            frame at q = 0).
        """
        return column_basis(self.dense(), rtol)

    def by_principle(self) -> dict[str, int]:
        """Rank contributed by each source, taken in order.

        The order is the paper's principles 1, 2, 3, then the extended rules R-A, R-B, R-L1,
        R-L2, R-L3, R-M (those run), then the measured rows' own (unmeasured root, unmeasured body,
        passive joint; present only when some rows are not measured).
        Each source's share is the rank it adds to the sources before it (:func:`scaled_rank`
        of the cumulative set), so the values sum to :attr:`rank`.

        Returns
        -------
        dict of str to int
            Source label (:attr:`baseparams.enums.Source.label`) -> rank added, in the order
            above.
        """
        out, prev = {}, 0
        sources = [s for s in Source if s.is_paper or (self.extended and s.is_extended)]
        sources += [s for s in Source if s.is_rows and np.any(self.columns.principle == s)]
        for s in sources:
            keep = self.columns.principle <= s
            if np.any(self.columns.principle == s):
                r = scaled_rank(self.columns.subset(keep), self.robot)
            else:
                r = prev
            out[s.label] = r - prev
            prev = r
        return out

    @property
    def paper_rank(self) -> int:
        """Rank of the paper's principles alone."""
        return sum(v for k, v in self.by_principle().items() if k in PAPER)

    def provenance(self, k: int) -> str:
        """Human-readable origin of column ``k``.

        Parameters
        ----------
        k : int
            Column index, ``0 <= k < n_columns``.

        Returns
        -------
        str
            The source, then: for the paper's principles the joint (tree joint or loop joint, with
            its type), the bodies and the points; for the extended rules every body the column has
            a block on and the rule's label; for an unmeasured root the body and parameter name.
        """
        c = self.columns
        names = self.robot.names
        body = names[c.child[k]]
        lower = [c.parent[k], c.extra[k], *([] if c.more[k] is None else c.more[k][0])]
        par = "".join(f" / {names[int(b)]}" for b in lower if b >= 0)  # every body the column has a block on
        j = int(c.joint[k])
        if j >= self.robot.n:
            lj = self.robot.loops[j - self.robot.n]
            joint = f"loop joint {lj.name!r} ({lj.type})"
        else:
            joint = f"joint {self.robot.joint_names[j]!r} ({self.robot.jtype[j]})"
        src = Source(int(c.principle[k]))
        if src is Source.UNMEASURED:
            return f"{src.label}: body {body}, {c.label[k]} (no measured row sees the floating root's own parameters)"
        if src is Source.UNSEEN:
            return f"{src.label}: body {body}, {c.label[k]} (no joint on its path to the root is measured)"
        if src is Source.PASSIVE:
            return f"{src.label}: bodies {body}{par}, {c.label[k]}"
        if not src.is_paper:
            return f"{src.label}: bodies {body}{par}, {c.label[k]}"
        return f"{src.label}: {joint}, bodies {body}{par}, points {c.label[k]}"


#: singular values of a decision block at most this (relative) are null, unless rounding is larger
RANK_RTOL = 1e-10
#: rounding above this (relative, :func:`baseparams.model.scale.decision_frames`) leaves no rank
#: decision standing: the robot is refused (a body ~20 000 length scales from the world origin)
RANK_RTOL_MAX = 1e-4


def decision_columns(cols: Columns, robot: Robot) -> tuple[Columns, np.ndarray]:
    """The columns in the coordinates rank decisions are made in, and the threshold of each body.

    Each body's blocks about its own origin, ordinary-sized
    (:func:`baseparams.model.scale.decision_frames`: a block-diagonal invertible map, so every
    rank is kept), each column then of unit norm (a rule may give a direction as a point far
    from the body, thousands of times longer than its neighbours: thresholds relative to the
    largest entry would then drop the others); the threshold :data:`RANK_RTOL`, or the rounding
    the map brings when larger.

    Parameters
    ----------
    cols : Columns
        Columns in compact form, ``paper`` convention (SI units, world frame at q = 0).
    robot : Robot
        The robot the columns belong to (``n`` bodies).

    Returns
    -------
    Columns
        The same columns in decision coordinates, each of unit norm (a zero column stays zero).
    ndarray, shape ``(n,)``
        The relative singular-value threshold of each body's decisions (:func:`.rank.block_rank`).

    Raises
    ------
    BaseparamsError
        A body so far from the world origin that the rounding of its world-frame blocks exceeds
        :data:`RANK_RTOL_MAX`: no rank decision would stand.
    """
    f, _, noise = decision_frames(robot)
    if len(noise) and noise.max() > RANK_RTOL_MAX:
        far = int(np.argmax(noise))
        dist = float(np.linalg.norm(robot.M0[far][:3, 3]))
        raise BaseparamsError(f"robot {robot.name!r}: body {robot.names[far]!r} is {dist:.3g} m from the world origin, "
                              f"{dist / length_scale(robot):.3g} times the robot's length scale: nullspace columns in "
                              f"the world frame at q = 0 carry rounding of ~{noise[far] / NOISE_FACTOR:.1g} there, too "
                              f"much to decide a rank; put the model's origin near its bodies")
    local = cols.transformed(f)
    norms = local.norms()
    return local.times(1.0 / np.where(norms > 0, norms, 1.0)), np.maximum(RANK_RTOL, noise)


def scaled_rank(cols: Columns, robot: Robot) -> int:
    """Exact rank (:func:`.rank.block_rank`) of the columns in decision coordinates.

    :func:`decision_columns`: each body's blocks about its own origin and brought to an ordinary
    size, so that the decision depends neither on the unit of length nor on how far a body is
    from the world origin (a block-diagonal change of coordinates: the rank is kept).

    Parameters
    ----------
    cols : Columns
        Columns in compact form, ``paper`` convention (SI units).
    robot : Robot
        The robot the columns belong to (``n`` bodies).

    Returns
    -------
    int
        The rank of ``B (10 n, k)``.
    """
    local, rtol = decision_columns(cols, robot)
    return block_rank(local, robot.n, rtol)
