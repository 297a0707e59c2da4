"""A delay per joint between the state channels and the torque channel.

A torque sensor read through another bus, a filter in the drive or a time stamp taken at the
wrong moment makes the measured torque of joint ``j`` the model's torque ``d_j`` seconds late:
``y_j(t) = M_j(t - d_j)``. The fit shifts the measured rows instead (``y_j(t + d_j)``, by linear
interpolation of the filtered full-rate torque, exact up to the interpolation) and takes
Gauss-Newton steps in ``d_j``: the linearised column of joint ``j`` is ``-dy_j/dt`` on its own
row. Predictions shift the model's torque: ``M_j(t - d_j)`` at the log's own time stamps.
Delays are bounded by :data:`MAX_DELAY` and by a quarter of the filter's edge.
"""

from __future__ import annotations

import numpy as np

from ... import schema as sc
from .base import Term, TermContext, complete_docs, per_joint, per_row

#: the largest delay considered [s]
MAX_DELAY = 0.05
#: a delay's weak prior: 0 to within this [s]
PRIOR_STD = 0.01


@complete_docs
class Delay(Term):
    """A delay per measured joint [s] (module docstring).

    Parameters
    ----------
    forced : bool
        Kept whatever the cross-validation says.
    seconds : array_like, shape ``(m,)``, optional
        Delays [s] (a saved result's).
    """

    name = "delay"
    label = "torque channel delay"
    FIELDS = {"seconds": per_joint(sc.Num(lo=-MAX_DELAY, hi=MAX_DELAY))}
    STD = {"seconds": per_row(sc.Num(lo=0.0))}

    def __init__(self, forced: bool = False, seconds=None):
        super().__init__(forced)
        self.seconds = None if seconds is None else np.asarray(seconds, dtype=float)
        self._limit = MAX_DELAY

    def reset(self, ctx: TermContext) -> None:
        """No delay; the bound from the filter's edge (the shortest edge of several recordings)."""
        self.seconds = np.zeros(len(ctx.joints))
        self._limit = min(MAX_DELAY, *(0.25 * c.prep.design.pad / c.prep.design.fs for c in ctx.recordings))

    def delays(self, m: int) -> np.ndarray:
        """The delays ``(m,)`` [s]."""
        return self.seconds

    def columns(self, ctx: TermContext, state: dict) -> tuple[np.ndarray, list[str]]:
        """``-dy_j/dt`` on joint ``j``'s row, one column per joint."""
        dy = state["dy"]
        m = dy.shape[1]
        out = np.zeros(dy.shape + (m,))
        out[:, np.arange(m), np.arange(m)] = -dy
        return out, [f"delay_{j}" for j in ctx.joints]

    def prior(self) -> tuple[np.ndarray, np.ndarray]:
        """``d_j ~ N(0, PRIOR_STD^2)`` on the step ``c_j`` (target ``-d_j``)."""
        return np.full(len(self.seconds), 1.0 / PRIOR_STD**2), -self.seconds

    def absorb(self, coefs: np.ndarray, std: np.ndarray | None = None) -> float:
        """A Gauss-Newton step, bounded."""
        new = np.clip(self.seconds + coefs, -self._limit, self._limit)
        change = float(np.max(np.abs(new - self.seconds))) / 1e-4
        self.seconds = new
        if std is not None:
            self.std = {"seconds": [float(s) for s in std]}
        return change

    def at_bound(self) -> bool:
        """A delay at its bound (:data:`MAX_DELAY` or the filter's edge)."""
        return bool(np.any(np.abs(self.seconds) >= self._limit))

    def adjust_measured(self, t: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """``M_j(t - d_j)``, linear interpolation at the log's time stamps (held at the ends)."""
        out = tau.copy()
        for j, d in enumerate(self.seconds):
            if d:
                out[:, j] = np.interp(t - d, t, tau[:, j])
        return out

    def values(self, joints: list[str]) -> dict:
        """``{"seconds": {joint: delay}}``."""
        return {"seconds": {j: float(d) for j, d in zip(joints, self.seconds)}}

    def describe(self, joints: list[str]) -> str:
        """E.g. ``panda_joint1 +1.2 ms, ...``."""
        return ", ".join(f"{j} {1e3 * d:+.2g} ms" for j, d in zip(joints, self.seconds))

    def export(self) -> dict:
        """Not representable in a model file."""
        return {"not": ["torque channel delays (a property of the data acquisition, not of the robot)"]}

    def load(self, doc: dict, joints: list[str], model) -> None:
        """The delays of a saved result."""
        d = doc["values"]["seconds"]
        self.seconds = np.array([float(d[j]) for j in joints])
