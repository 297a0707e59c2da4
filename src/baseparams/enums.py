"""The library's named choices, defined once: parameter conventions, measured rows, certificate
statuses, joint types and the provenance of DRNG columns.

The string-valued ones are :class:`enum.StrEnum`: a member *is* its string (``Status.CERTIFIED
== "certified"``, ``f"{Rows.ALL}" == "all"``, ``json.dumps`` writes ``"certified"``), so every
comparison with the plain strings users pass, every report and every JSON document reads as
before (and their ``repr`` is the string's). The tables of each choice
(:data:`baseparams.model.inertia.SPECS` for conventions, :data:`baseparams.model.robot.NDOF` for
joints) live with the code that uses them and are keyed by these members.
"""

from __future__ import annotations

from enum import IntEnum, StrEnum

__all__ = ["Convention", "JointType", "Rows", "Source", "Status", "values"]


class _Choice(StrEnum):
    """A string choice whose ``repr`` is its string's (``'certified'``): tuples, doctests and
    error messages that show ``repr`` read exactly as with the plain strings.
    """

    def __repr__(self) -> str:
        return repr(self.value)


class Convention(_Choice):
    """A per-body ordering (and frame) of the ten inertial parameters
    (:data:`baseparams.model.inertia.SPECS`).
    """

    PAPER = "paper"
    KHALIL = "khalil"
    PINOCCHIO = "pinocchio"
    IDYNTREE = "idyntree"
    RPNA = "rpna"


class Rows(_Choice):
    """Which generalized forces are measured (:func:`baseparams.numerics.row_mask`)."""

    ALL = "all"
    JOINTS = "joints"  # every coordinate but a floating base's 6
    BASE = "base"  # only the floating base's wrench


class Status(_Choice):
    """Outcome of certification (:class:`baseparams.nullspace.certify.Certificate`);
    ``unverified``: an analysis run without it.
    """

    CERTIFIED = "certified"
    COMPLETED = "completed"
    UNDECIDED = "undecided"
    FAILED = "failed"
    UNVERIFIED = "unverified"

    @property
    def ok(self) -> bool:
        """The nullspace is known (certified, or completed from the numerical one)."""
        return self in (Status.CERTIFIED, Status.COMPLETED)


class JointType(_Choice):
    """Joint types. One enum for tree and loop (cut) joints: ``R P U S F C`` are the tree joints
    a body hangs on (:data:`baseparams.model.robot.JOINT_TYPES`); ``fixed`` is no body's joint
    (the builder and the readers merge a fixed link into its parent) but is a cut joint closing
    a loop rigidly (:data:`baseparams.model.robot.LOOP_TYPES`: ``R P U S fixed``).
    """

    R = "R"  # revolute
    P = "P"  # prismatic
    U = "U"  # universal
    S = "S"  # spherical
    F = "F"  # free (floating base)
    C = "C"  # compound: elementary screws
    FIXED = "fixed"


class Source(IntEnum):
    """Provenance of a DRNG column (``Columns.principle``): the paper's three principles, the
    extended rules (:mod:`baseparams.nullspace.rules`), unmeasured roots, numerical completion.

    Integer-valued (columns store them in integer arrays); the order is the order in which
    :meth:`baseparams.nullspace.drng.DRNGResult.by_principle` takes them, and :attr:`label` is
    the name printed in reports and used as the JSON ``by_rule`` key.
    """

    SHARED_POINTS = 0
    FIXED_POINTS = 1
    PLANAR_ROTATIONS = 2
    R_A = 3
    R_B = 4
    R_L1 = 5
    R_L2 = 6
    UNMEASURED = 7
    NUMERICAL = 8

    @property
    def label(self) -> str:
        return _LABELS[self]

    @property
    def is_paper(self) -> bool:
        """One of the paper's three principles."""
        return self <= Source.PLANAR_ROTATIONS

    @property
    def is_extended(self) -> bool:
        """One of the extended rules R-A, R-B, R-L1, R-L2."""
        return Source.R_A <= self <= Source.R_L2


_LABELS = ("shared points", "fixed points", "planar rotations",
           "R-A fixed vectors", "R-B sliding points", "R-L1 parallelograms", "R-L2 level chains",
           "unmeasured root", "numerical")


def values(members) -> tuple[str, ...]:
    """The members' plain strings, in order (tables, error messages and CLI choices print
    ``('all', 'joints', 'base')``, not the members' reprs).
    """
    return tuple(str(m) for m in members)
