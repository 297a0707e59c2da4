"""Every rule's columns checked against the regressor before they are used.

DRNG's columns come from the paper's principles and from the extended rules, each a proof that
a parameter change leaves every generalized force unchanged. A rule with a defect (a column
passed on with a block missing, a geometric condition mis-read) would give a wrong count, and
with ``--no-verify`` nothing else would see it; later rules also build on the columns found
before (R-M and R-C emit only what is new to them). So each rule's columns are checked as soon
as they are made, on a few random states, against the regressor of the measured rows:

* a tree of at least :data:`~baseparams.numerics.STRUCTURED_MIN_BODIES` bodies whose joint rows
  are measured: each body's wrench map and each joint's line
  (:func:`.structured.wrench_maps`), every column's worst row relative to the size of its terms
  (:func:`.structured.column_residuals`, linear in the number of bodies);
* otherwise (smaller trees, loops, the base wrench alone): the stacked regressor ``W`` of those
  states (:func:`baseparams.numerics.stacked_regressor`), ``||W b|| / (||W||_2 ||b||)`` on
  parameters ``pi / d`` (:func:`baseparams.model.scale.decision_scale`), as the certification
  measures it (a parameter no row sees has a column of rounding in ``W``, not of zeros: relative
  to its own terms a column on it would look far from the nullspace).

A column above :data:`RULE_TOL` is not used: it is left out of the rule's columns, and
:attr:`RuleCheck.notes` names the rule, the bodies and the residual. The certification that
follows then completes what it would have given (numerically, marked so); the check is coarse
on purpose (rounding of ill-conditioned loop samples must not reject a right column), the
certification's residual test is the fine one.
"""

from __future__ import annotations

import numpy as np

from ..enums import Source
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..model.scale import decision_scale
from ..numerics import STRUCTURED_MIN_BODIES, rows_spec, stacked_regressor
from .columns import Columns, to_dense

#: random states of the check (actuated samples with loops: :data:`RULE_LOOP_SAMPLES`)
RULE_SAMPLES = 3
#: actuated samples with loops (some may not close)
RULE_LOOP_SAMPLES = 8
#: seed of the check's states (not the certification's: other states)
RULE_SEED = 90_001
#: a column whose residual relative to the size of its terms is above this is not in the nullspace
RULE_TOL = 1e-6
#: the paper's bound on a loop sample's ``cond(J_p)``; above it the rates lose precision
_COND_PAPER = 30.0
#: the stacked regressor of the dense check is formed up to this many numbers
DENSE_MAX = 20_000_000


class RuleCheck:
    """The regressor of a few random states, and what each rule's columns did against it.

    Made once per :func:`.drng.drng` run; :meth:`keep` checks a rule's columns.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    rows : str
        The measured generalized forces (:func:`baseparams.numerics.rows_spec`).
    """

    def __init__(self, robot: Robot, rows: str = "all") -> None:
        self.robot, self.rows = robot, rows_spec(rows)
        self.notes: list[str] = []
        self._data = None  # sampled on first use

    def _sample(self):
        """``("tree", (x, lines, dofs, coupled))``, ``("dense", (W, column norms^2, tol))`` or ``("none", why)``."""
        robot, rows = self.robot, self.rows
        try:
            if robot.n >= STRUCTURED_MIN_BODIES:  # structured's import costs start-up time: large robots only
                from . import structured

                if structured.applicable(robot, rows):
                    *states, big_g, _ = structured.sampled_states(robot, RULE_SAMPLES, RULE_SEED)
                    x, lines = structured.wrench_maps(robot, RULE_SAMPLES, RULE_SEED, np.ones(10),
                                                      states=tuple(states))
                    return "tree", (x, lines, *structured.row_groups(robot, rows, big_g))
            samples = RULE_LOOP_SAMPLES if robot.has_loops else RULE_SAMPLES
            if samples * max(robot.dof, 1) * 10 * robot.n > DENSE_MAX:
                return "none", f"the regressor of {samples} states would hold more than {DENSE_MAX:.0e} numbers"
            info: dict = {}
            w = stacked_regressor(robot, samples, RULE_SEED, rows, info)
        except BaseparamsError as err:
            return "none", str(err)
        cond = float(info.get("cond_max", 0.0) or 0.0)
        # loop samples with cond(J_p) up to c carry ddq errors ~c^2 times the closure's rounding
        tol = RULE_TOL * max(1.0, (cond / _COND_PAPER) ** 3) if np.isfinite(cond) else np.inf
        d = decision_scale(robot, "paper")
        w = w * d
        return "dense", (w, d, _norm2(w), tol)

    def residuals(self, cols: Columns) -> tuple[np.ndarray, float]:
        """Each column's residual relative to the size of its terms, and the tolerance it is held to.

        Parameters
        ----------
        cols : Columns
            ``k`` columns (``paper`` convention, SI, world frame at q = 0).

        Returns
        -------
        ndarray, shape ``(k,)``
            The residuals (zeros when the robot could not be sampled: :attr:`notes` says why).
        float
            The tolerance (:data:`RULE_TOL`, raised for ill-conditioned loop samples).
        """
        if not len(cols):
            return np.zeros(0), RULE_TOL
        if self._data is None:
            self._data = self._sample()
            if self._data[0] == "none":
                self.notes.append(f"the rules' columns were not checked against the regressor: {self._data[1]}")
        kind, data = self._data
        if kind == "none":
            return np.zeros(len(cols)), RULE_TOL
        if kind == "tree":
            from .structured import column_residuals

            return column_residuals(cols, self.robot, *data[:2], data[2], RULE_TOL, data[3]), RULE_TOL
        w, d, w2, tol = data
        b = to_dense(cols, self.robot.n) / d[:, None]  # (10 n, k): the dense check is for robots of modest size
        den = w2 * np.linalg.norm(b, axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            res = np.linalg.norm(w @ b, axis=0) / np.where(den > 0, den, 1.0)  # a zero column spans nothing: 0
        return res, tol

    def keep(self, cols: Columns) -> Columns:
        """The columns in the nullspace on the check's states; the others left out and named in :attr:`notes`.

        Parameters
        ----------
        cols : Columns
            A rule's (or several rules') columns.

        Returns
        -------
        Columns
            ``cols`` without the columns above the tolerance.
        """
        res, tol = self.residuals(cols)
        bad = ~(res <= tol)
        if not bad.any():
            return cols
        for src in sorted({int(s) for s in cols.principle[bad]}):
            mine = cols.principle == src
            worst = int(np.flatnonzero(mine & bad)[np.argmax(res[mine & bad])])
            self.notes.append(f"{Source(src).label}: {int(np.sum(mine & bad))} of {int(mine.sum())} columns are not "
                              f"in the nullspace of the regressor (worst residual {res[worst]:.2g} on random states, "
                              f"tolerance {tol:.2g}; {_column_text(self.robot, cols, worst)}): left out, a defect of "
                              f"the rule; the certification completes what they should have given")
        return cols.subset(~bad)


def _norm2(w: np.ndarray, steps: int = 30) -> float:
    """``||W||_2`` by power iteration (an SVD of a large ``W`` would cost more than the check)."""
    v = np.random.default_rng(0).normal(size=w.shape[1])
    s = 0.0
    for _ in range(steps):
        v = w.T @ (w @ v)
        s = float(np.linalg.norm(v))
        if s == 0.0:
            return 0.0
        v /= s
    return float(np.sqrt(s)) if s > 0 else 0.0


def _column_text(robot: Robot, cols: Columns, k: int) -> str:
    """``bodies a, b, c: label`` of column ``k``, every body it has a block on."""
    bodies = [cols.child[k], cols.parent[k], cols.extra[k]]
    if cols.more[k] is not None:
        bodies += list(cols.more[k][0])
    names = ", ".join(robot.names[int(b)] for b in bodies if b >= 0)
    return f"bodies {names}: {cols.label[k]}"
