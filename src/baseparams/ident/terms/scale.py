"""A torque-sensor scale per joint: ``y_j = s_j M_j``, one joint fixed to 1.

A joint torque sensor's gain, or a motor's torque constant times its gear ratio, is known to a
few percent; the model's parameters then absorb a common scale but not one joint's. Scaling every
joint by the same factor is indistinguishable from scaling every parameter, so the joint with the
largest torque (the best-determined gain) is the reference, ``s = 1``; the others are fitted
relative to it by Gauss-Newton steps: the linearised column of joint ``j`` is the model's torque
``M_j`` on its own row (``y_j / s_j = M_j`` with the measured rows divided exactly). A weak prior
keeps a scale the log cannot determine near 1 (:data:`PRIOR_STD`); scales are bounded to
[:data:`LOWEST`, :data:`HIGHEST`].
"""

from __future__ import annotations

import numpy as np

from ... import schema as sc
from .base import Term, TermContext, complete_docs, per_joint, per_row

#: bounds of a scale
LOWEST, HIGHEST = 0.5, 2.0
#: a scale's weak prior: 1 to within this (a sensor's gain is known to a few percent)
PRIOR_STD = 0.1


@complete_docs
class Scale(Term):
    """A torque scale per joint, the reference joint's fixed to 1 (module docstring).

    Parameters
    ----------
    forced : bool
        Kept whatever the cross-validation says.
    factors : array_like, shape ``(m,)``, optional
        Scales (a saved result's).
    reference : int
        The joint fixed to 1.
    """

    name = "scale"
    label = "torque sensor scale"
    FIELDS = {"factors": per_joint(sc.Num(lo=LOWEST, hi=HIGHEST)),
              "reference": sc.Str(max_len=1000, among="joints")}
    STD = {"factors": per_row(sc.Num(lo=0.0))}

    @classmethod
    def rule(cls, values: dict) -> str | None:
        """The reference joint's scale is 1 (the others are relative to it)."""
        s = values["factors"][values["reference"]]
        return None if s == 1.0 else f"factors.{values['reference']} is {s!r}, but the reference joint's factor is 1"

    def __init__(self, forced: bool = False, factors=None, reference: int = 0):
        super().__init__(forced)
        self.factors = None if factors is None else np.asarray(factors, dtype=float)
        self.reference = int(reference)

    def available(self, ctx: TermContext) -> str | None:
        """Needs two measured joints or more."""
        return None if len(ctx.joints) > 1 else "one measured joint: its scale is the parameters'"

    def reset(self, ctx: TermContext) -> None:
        """All 1; the reference is the joint with the largest torque RMS."""
        self.factors = np.ones(len(ctx.joints))
        self.reference = int(np.argmax(np.sqrt(np.mean(ctx.tau**2, axis=0))))

    def scales(self, m: int) -> np.ndarray:
        """The scales ``(m,)``."""
        return self.factors

    def _free(self) -> np.ndarray:
        return np.array([j for j in range(len(self.factors)) if j != self.reference], dtype=int)

    def columns(self, ctx: TermContext, state: dict) -> tuple[np.ndarray, list[str]]:
        """The model's torque ``M_j`` on joint ``j``'s row, for every joint but the reference."""
        model = state["model"]
        free = self._free()
        out = np.zeros(model.shape + (len(free),))
        out[:, free, np.arange(len(free))] = model[:, free]
        return out, [f"scale_{ctx.joints[j]}" for j in free]

    def prior(self) -> tuple[np.ndarray, np.ndarray]:
        """``s_j (1 + c_j) ~ N(1, PRIOR_STD^2)``: precision ``s_j^2 / PRIOR_STD^2``, target ``1 / s_j - 1``."""
        s = self.factors[self._free()]
        return s**2 / PRIOR_STD**2, 1.0 / s - 1.0

    def absorb(self, coefs: np.ndarray, std: np.ndarray | None = None) -> float:
        """A Gauss-Newton step ``s_j <- s_j (1 + c_j)``, bounded."""
        free = self._free()
        new = self.factors.copy()
        new[free] = np.clip(new[free] * (1.0 + coefs), LOWEST, HIGHEST)
        change = float(np.max(np.abs(new - self.factors))) / 1e-3 if len(free) else 0.0
        self.factors = new
        if std is not None:
            full = np.zeros(len(new))
            full[free] = np.asarray(std) * new[free]
            self.std = {"factors": [float(s) for s in full]}
        return change

    def at_bound(self) -> bool:
        """A scale at :data:`LOWEST` or :data:`HIGHEST`."""
        return bool(np.any((self.factors <= LOWEST) | (self.factors >= HIGHEST)))

    def adjust_measured(self, t: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """``s_j M_j``."""
        return tau * self.factors

    def values(self, joints: list[str]) -> dict:
        """``{"factors": {joint: s}, "reference": joint}``."""
        return {"factors": {j: float(s) for j, s in zip(joints, self.factors)}, "reference": joints[self.reference]}

    def describe(self, joints: list[str]) -> str:
        """E.g. ``panda_joint6 1.12, ... (panda_joint2 = 1)``."""
        rest = ", ".join(f"{j} {s:.3g}" for k, (j, s) in enumerate(zip(joints, self.factors)) if k != self.reference)
        return f"{rest} (reference {joints[self.reference]} = 1)"

    def export(self) -> dict:
        """Not representable in a model file (a property of the sensors)."""
        return {"not": ["torque sensor scales (a property of the sensors: divide the logged torques by them)"]}

    def load(self, doc: dict, joints: list[str], model) -> None:
        """The scales of a saved result."""
        v = doc["values"]
        self.factors = np.array([float(v["factors"][j]) for j in joints])
        self.reference = joints.index(v["reference"])
