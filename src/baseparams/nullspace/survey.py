"""Completeness survey: the geometric nullspace against the certified numerical one, on many robots.

The geometric nullspace is the paper's principles and the extended rules; the survey is the
evidence asked for by the extended-principles issue.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..enums import Status
from ..model.robot import Robot
from .certify import certify
from .drng import drng


@dataclass(frozen=True, eq=False)
class SurveyCase:
    """One robot of the survey, as recorded by :func:`survey_case`.

    ``nullity`` (certified), ranks of the paper's principles and of the extended DRNG, the worst
    relative residual of an emitted column, and the certification status.

    Parameters
    ----------
    name : str
        The robot's name.
    description : str
        One line: joint types with parents, gravity (:func:`describe`).
    nullity : int
        The certified nullspace dimension (``-1`` when not certified).
    paper_rank : int
        Rank of the paper's three principles alone (``drng(robot, extended=False)``).
    extended_rank : int
        Rank of the extended DRNG (principles and rules R-A, R-B, R-L1, R-L2).
    by_rule : dict
        Rank added by each source (:meth:`~.drng.DRNGResult.by_principle` of the extended DRNG).
    max_column_residual : float
        The worst relative residual of an emitted column (``Certificate.max_column_residual``).
    status : Status
        The certification status.
    """

    name: str
    description: str
    nullity: int
    paper_rank: int
    extended_rank: int
    by_rule: dict
    max_column_residual: float
    status: Status

    __repr__ = summary_repr

    @property
    def paper_complete(self) -> bool:
        """The nullspace is known and the paper's principles alone span it."""
        return Status(self.status).ok and self.paper_rank == self.nullity

    @property
    def complete(self) -> bool:
        """Certified without completion, and the extended DRNG spans the whole nullspace."""
        return self.status == Status.CERTIFIED and self.extended_rank == self.nullity


def describe(robot: Robot) -> str:
    """One line: joint types with parents, gravity.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).

    Returns
    -------
    str
        ``"{n} bodies [T<p ...], gravity G"``: each joint type ``T`` with its parent ``p``
        (``-1``: the fixed base); ``G`` is ``zero``, ``along x|y|z`` (one nonzero component) or
        ``generic``.
    """
    g = robot.gravity
    gtxt = "zero" if not np.any(g) else ("along " + "xyz"[int(np.argmax(np.abs(g)))] if np.count_nonzero(g) == 1
                                         else "generic")
    joints = " ".join(f"{t}<{p}" for t, p in zip(robot.jtype, robot.parent))
    return f"{robot.n} bodies [{joints}], gravity {gtxt}"


def survey_case(robot: Robot, samples: int | None = None, seed: int = 0) -> SurveyCase:
    """Certify the extended DRNG of ``robot`` and record the paper's principles' rank too.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    samples : int, optional
        Random states for :func:`~.certify.certify` (default: its default).
    seed : int, default 0
        Seed of the random states.

    Returns
    -------
    SurveyCase
        The robot's record.
    """
    ext = drng(robot)
    c = certify(robot, samples, seed, result=ext)
    paper = drng(robot, extended=False)
    return SurveyCase(robot.name, describe(robot), c.nullity if c.certified else -1, paper.rank, ext.rank,
                      ext.by_principle(), c.max_column_residual, c.status)


def summarize(cases: list[SurveyCase]) -> dict:
    """Counts and the incomplete cases (JSON-ready).

    Parameters
    ----------
    cases : list of SurveyCase
        The surveyed robots.

    Returns
    -------
    dict
        ``robots``, ``certified``, ``paper_complete``, ``extended_complete`` (counts),
        ``max_column_residual`` (worst over the cases), ``failed`` (``"name: status"`` of the
        cases whose nullspace is not known) and ``incomplete`` (certified or completed cases the
        extended DRNG does not span, with ranks).
    """
    n = len(cases)
    return {
        "robots": n,
        "certified": sum(Status(c.status).ok for c in cases),
        "paper_complete": sum(c.paper_complete for c in cases),
        "extended_complete": sum(c.complete for c in cases),
        "max_column_residual": max((c.max_column_residual for c in cases), default=0.0),
        "failed": [f"{c.name}: {c.status}" for c in cases if not Status(c.status).ok],
        "incomplete": [f"{c.name} ({c.description}): extended rank {c.extended_rank} of nullity {c.nullity}"
                       for c in cases if not c.complete and Status(c.status).ok],
    }
