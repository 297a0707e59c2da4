"""The library's named choices, defined once.

Parameter conventions, measured rows, certificate statuses, joint types and the provenance of
DRNG columns.

The string-valued ones are :class:`enum.StrEnum`: a member *is* its string (``Status.CERTIFIED
== "certified"``, ``f"{Rows.ALL}" == "all"``, ``json.dumps`` writes ``"certified"``), so every
comparison with the plain strings users pass, every report and every JSON document reads as
before (and their ``repr`` is the string's). The tables of each choice
(:data:`baseparams.model.inertia.SPECS` for conventions, :data:`baseparams.model.robot.NDOF` for
joints) live with the code that uses them and are keyed by these members.
"""

from __future__ import annotations

from enum import IntEnum, StrEnum

__all__ = ["Convention", "JointType", "MocapWelds", "Rows", "Source", "Status", "values"]


# ``numpydoc ignore=PR01`` on the enums below: the signature numpydoc's validator checks for an
# enum class is ``EnumType.__call__`` (the functional API: value, names, module, ...; ``*values``
# from Python 3.12), not a constructor of ours, so there are no parameters to document.


class _Choice(StrEnum):
    """A string choice whose ``repr`` is its string's (``'certified'``).

    Tuples, doctests and error messages that show ``repr`` read exactly as with the plain strings.
    """

    def __repr__(self) -> str:
        return repr(self.value)


class Convention(_Choice):  # numpydoc ignore=PR01
    """A per-body ordering (and frame) of the ten inertial parameters.

    The orderings and frames are tabulated in :data:`baseparams.model.inertia.SPECS`, keyed by
    these members: ``paper``, ``khalil``, ``pinocchio``, ``idyntree``, ``rpna``.

    Notes
    -----
    ``Convention("khalil")`` is ``Convention.KHALIL`` (an unknown string raises
    ``ValueError``).
    """

    PAPER = "paper"
    KHALIL = "khalil"
    PINOCCHIO = "pinocchio"
    IDYNTREE = "idyntree"
    RPNA = "rpna"


class Rows(_Choice):  # numpydoc ignore=PR01
    """Which generalized forces are measured.

    ``all``; ``joints`` (every coordinate but a floating base's 6); ``base`` (only the floating
    base's wrench). A set of measured joints is given by the forms of
    :data:`baseparams.numerics.ROW_FORMS` (``joints:NAME,...``, ``base+joints:NAME,...``,
    ``passive:NAME,...``) or a list of joint names. The mask of a robot's rows is
    :func:`baseparams.numerics.row_mask`.

    Notes
    -----
    ``Rows("joints")`` is ``Rows.JOINTS``.
    """

    ALL = "all"
    JOINTS = "joints"  # every coordinate but a floating base's 6
    BASE = "base"  # only the floating base's wrench


class Status(_Choice):  # numpydoc ignore=PR01
    """Outcome of certification (:class:`baseparams.nullspace.certify.Certificate`).

    ``certified``, ``completed``, ``undecided``, ``failed``; ``unverified``: an analysis run
    without certification.

    Notes
    -----
    ``Status("certified")`` is ``Status.CERTIFIED``.
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


class MocapWelds(_Choice):  # numpydoc ignore=PR01
    """What an MJCF file's welds and connects to mocap bodies are read as.

    A mocap body is a control device the simulation moves every step (Meta-World's and
    gymnasium's Fetch hands are welded to one: "mocap welds that we use for actuation"):
    ``drop`` (the default) leaves such an equality out, with a note, and the arm is the tree its
    users drive; ``keep`` reads it as a loop joint to the world, placed where the hand is at the
    reference.

    Notes
    -----
    ``MocapWelds("keep")`` is ``MocapWelds.KEEP``.
    """

    DROP = "drop"
    KEEP = "keep"


class JointType(_Choice):  # numpydoc ignore=PR01
    """Joint types.

    One enum for tree and loop (cut) joints: ``R P U S F C`` are the tree joints a body hangs on
    (:data:`baseparams.model.robot.JOINT_TYPES`); ``fixed`` is no body's joint (the builder and
    the readers merge a fixed link into its parent) but is a cut joint closing a loop rigidly
    (:data:`baseparams.model.robot.LOOP_TYPES`: ``R P U S fixed``).

    Notes
    -----
    ``JointType("R")`` is ``JointType.R``.
    """

    R = "R"  # revolute
    P = "P"  # prismatic
    U = "U"  # universal
    S = "S"  # spherical
    F = "F"  # free (floating base)
    C = "C"  # compound: elementary screws
    FIXED = "fixed"


class Source(IntEnum):  # numpydoc ignore=PR01
    """Provenance of a DRNG column (``Columns.principle``).

    The paper's three principles, the extended rules (:mod:`baseparams.nullspace.rules`),
    unmeasured roots, the measured rows' own rules (bodies no measured row sees, passive joints),
    numerical completion.

    Integer-valued (columns store them in integer arrays); the order is the order in which
    :meth:`baseparams.nullspace.drng.DRNGResult.by_principle` takes them, and :attr:`label` is
    the name printed in reports and used as the JSON ``by_rule`` key.

    Notes
    -----
    ``Source(0)`` is ``Source.SHARED_POINTS``.
    """

    SHARED_POINTS = 0
    FIXED_POINTS = 1
    PLANAR_ROTATIONS = 2
    R_A = 3
    R_B = 4
    R_L1 = 5
    R_L2 = 6
    R_L3 = 7
    R_L4 = 8
    R_M = 9
    R_C = 10
    UNMEASURED = 11
    UNSEEN = 12
    PASSIVE = 13
    NUMERICAL = 14

    @property
    def label(self) -> str:
        """The name printed in reports and used as the JSON ``by_rule`` key (e.g. ``shared points``)."""
        return _LABELS[self]

    @property
    def is_paper(self) -> bool:
        """One of the paper's three principles."""
        return self <= Source.PLANAR_ROTATIONS

    @property
    def is_extended(self) -> bool:
        """One of the extended rules R-A, R-B, R-L1, R-L2, R-L3, R-L4, R-M, R-C."""
        return Source.R_A <= self <= Source.R_C

    @property
    def is_rows(self) -> bool:
        """A column that comes from which rows are measured: unmeasured root or body, passive joint."""
        return Source.UNMEASURED <= self <= Source.PASSIVE


_LABELS = ("shared points", "fixed points", "planar rotations",
           "R-A fixed vectors", "R-B sliding points", "R-L1 parallelograms", "R-L2 level chains",
           "R-L3 planar loops", "R-L4 spatial parallelograms", "R-M coupled joints", "R-C compound joints",
           "unmeasured root", "unmeasured body", "passive joint", "numerical")


def values(members) -> tuple[str, ...]:
    """The members' plain strings, in order.

    Tables, error messages and CLI choices print ``('all', 'joints', 'base')``, not the members'
    reprs.

    Parameters
    ----------
    members : iterable of enum members
        E.g. an enum class such as :class:`Rows` (iterated in definition order).

    Returns
    -------
    tuple of str
        ``str(m)`` for each member ``m``, e.g. ``values(Rows) == ('all', 'joints', 'base')``.
    """
    return tuple(str(m) for m in members)
