"""DRNG: the regressor nullspace from the three principles and the extended rules, ranked.

:mod:`.principles` gives the paper's columns (with its slips fixed), :mod:`.rules` the rules
that close its gaps, :func:`unmeasured_columns` what the measured rows add; :mod:`.rank`
decides their exact rank. :func:`drng` runs them all and returns a :class:`DRNGResult`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..enums import Source
from ..model.inertia import PAPER_NAMES
from ..model.robot import Robot
from ..model.scale import decision_scale, ordinary_size
from ..numerics import row_mask
from ..pga.linalg import column_basis
from .columns import EXTENDED, PAPER, PRINCIPLES, UNMEASURED, Columns, to_dense, to_sparse
from .principles import drng_columns
from .rank import block_rank
from .rules import rule_columns

__all__ = ["DRNGResult", "drng", "unmeasured_columns", "PAPER", "EXTENDED", "UNMEASURED", "PRINCIPLES"]


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
        Whether the extended rules (R-A, R-B, R-L1, R-L2, R-M) ran besides the paper's principles.
    rows : str, default "all"
        The measured rows the columns were computed for (``joints`` adds the floating root's
        unmeasured columns); :func:`~baseparams.nullspace.certify.certify` checks it.
    """

    robot: Robot
    columns: Columns
    rank: int
    seconds: float
    extended: bool = True
    rows: str = "all"

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
        R-L2, R-M (those run), then the unmeasured root's own parameters (joint-torque rows only).
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
        if np.any(self.columns.principle == Source.UNMEASURED):
            sources.append(Source.UNMEASURED)
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
            its type), the bodies and the points; for the extended rules the bodies and the rule's
            label; for an unmeasured root the body and parameter name.
        """
        c = self.columns
        names = self.robot.names
        body = names[c.child[k]]
        par = "" if c.parent[k] < 0 else f" / {names[c.parent[k]]}"
        j = int(c.joint[k])
        if j >= self.robot.n:
            lj = self.robot.loops[j - self.robot.n]
            joint = f"loop joint {lj.name!r} ({lj.type})"
        else:
            joint = f"joint {self.robot.joint_names[j]!r} ({self.robot.jtype[j]})"
        src = Source(int(c.principle[k]))
        if src is Source.UNMEASURED:
            return f"{src.label}: body {body}, {c.label[k]} (no measured row sees the floating root's own parameters)"
        if not src.is_paper:
            return f"{src.label}: bodies {body}{par}, {c.label[k]}"
        return f"{src.label}: {joint}, bodies {body}{par}, points {c.label[k]}"


def scaled_rank(cols: Columns, robot: Robot) -> int:
    """Exact rank (:func:`.rank.block_rank`) of the columns for parameters ``pi / d``.

    ``d`` is :func:`baseparams.model.scale.decision_scale` (ones for a robot of ordinary size):
    a per-entry scaling of every body block, the same for all bodies, so the block structure is
    kept and the decision does not depend on the unit of length.

    Parameters
    ----------
    cols : Columns
        Columns in compact form, ``paper`` convention (SI units).
    robot : Robot
        The robot the columns belong to (``n`` bodies; its length scale gives ``d``).

    Returns
    -------
    int
        The rank of ``B (10 n, k)`` after scaling.
    """
    if ordinary_size(robot):  # d = 1: the columns as they are
        return block_rank(cols, robot.n)
    inv = 1.0 / decision_scale(robot, "paper")[:10]
    return block_rank(cols.scaled(inv), robot.n)


def unmeasured_columns(robot: Robot, rows: str) -> Columns:
    """Columns that the measured rows add.

    With joint torques alone (``rows="joints"``) on a floating robot, no row sees the floating
    root's own ten parameters (joint ``j``'s torque is its line against the wrenches of the bodies
    it carries, and no joint carries the root), so each is a nullspace direction on its own. With
    the base wrench alone (``"base"``) nothing is added: it sees every direction the full
    dynamics see (Ayusawa et al. 2014, the paper's remark; certification checks it).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    rows : {"all", "joints", "base"}
        The measured generalized forces (:func:`baseparams.numerics.row_mask`).

    Returns
    -------
    Columns
        Ten single-body unit columns per floating (``F``) root, labelled with the parameter names
        and marked ``unmeasured root``, when ``rows="joints"``; otherwise none.

    Raises
    ------
    BaseparamsError
        ``rows`` is not one of the three (checked unless it is ``"all"``).
    """
    if rows == "all":
        return Columns.empty()
    mask = row_mask(robot, rows)
    roots = [i for i in range(robot.n) if robot.jtype[i] == "F"]
    if rows != "joints" or not roots or mask.all():
        return Columns.empty()
    k = 10 * len(roots)
    child = np.repeat(np.array(roots, dtype=int), 10)
    z = np.zeros(k, dtype=int)
    labels = np.array(list(PAPER_NAMES) * len(roots), dtype=object)
    return Columns(np.tile(np.eye(10), (len(roots), 1)), child, z - 1, np.full(k, Source.UNMEASURED),
                   child.copy(), labels, hp=np.zeros((k, 10)))


def drng(robot: Robot, tol: float = 1e-9, extended: bool = True, rows: str = "all") -> DRNGResult:
    """Run DRNG (corrected) on ``robot``: columns with provenance and their exact rank.

    The paper's Algorithm "DRNG" with slips E1-E5 fixed (:func:`.principles.drng_columns`), then
    the extended rules (:func:`.rules.rule_columns`, then :func:`.coupled.coupled_columns` for
    joint couplings, given the columns before), then :func:`unmeasured_columns`; the rank
    is decided by :func:`scaled_rank`.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies, ``10 n`` parameters).
    tol : float, default 1e-9
        Geometric tolerance of the principles and rules (parallel axes, zero gravity, ...).
    extended : bool, default True
        Add the rules that close the paper's gaps (:mod:`.rules`: R-A, R-B, R-L1, R-L2;
        :mod:`.coupled`: R-M);
        ``False`` gives the paper's three principles alone.
    rows : {"all", "joints", "base"}, default "all"
        The measured generalized forces (see :func:`unmeasured_columns`).

    Returns
    -------
    DRNGResult
        The columns ``B_null (10 n, k)`` in the ``paper`` convention (spatial pseudo-inertia
        entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at q = 0) with
        provenance, their exact rank and the time taken.

    Raises
    ------
    BaseparamsError
        Unknown ``rows`` (see :func:`unmeasured_columns`).
    """
    t0 = time.perf_counter()
    cols = drng_columns(robot, tol)
    if extended:
        cols = Columns.concat([cols, rule_columns(robot, tol)])
        if robot.couplings:  # R-M (its module imported for robots with couplings only: start-up time)
            from .coupled import coupled_columns

            cols = Columns.concat([cols, coupled_columns(robot, tol, prior=cols)])
    extra = unmeasured_columns(robot, rows)
    if len(extra):
        cols = Columns.concat([cols, extra])
    rank = scaled_rank(cols, robot)
    return DRNGResult(robot, cols, rank, time.perf_counter() - t0, extended, str(rows))
