"""Pre-sliding (Dahl) friction: Coulomb friction that builds up over a few milliradians of travel.

A joint's Coulomb torque does not jump when its velocity changes sign: the contacts first deform
elastically (pre-sliding) and the friction torque follows the displacement since the last
reversal. Dahl's model in its rate-independent form, a state ``z_j`` in ``[-1, 1]`` per joint::

    dz/dq = (1 - z sgn(dq)) / delta_j,        Coulomb torque = Fc_j z_j

replaces the core's ``Fc_j sign(dq_j)``. ``delta_j`` [rad or m] is the travel over which the
friction builds up (about 63 % after one ``delta``); ``delta -> 0`` is plain Coulomb friction.
Along a monotone stretch of travel ``|dq|`` the state moves exactly as
``z' = s + (z - s) exp(-|dq| / delta)`` (``s`` the direction), so the state is integrated exactly
along the measured positions, sample by sample (:func:`dahl_state`), starting at ``z = 0``.

Fitting: ``Fc_j`` stays the core's linear parameter (non-negative); ``delta_j`` is chosen per
joint on the grid :data:`DELTAS` (:data:`DELTAS_PRISMATIC` for sliders) by the training error,
two sweeps over the joints.
"""

from __future__ import annotations

import numpy as np

from ... import schema as sc
from .base import Term, TermContext, complete_docs, per_joint

#: candidate pre-sliding distances of revolute joints [rad] (the first: plain Coulomb, in effect)
DELTAS = (1e-6, 1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 3e-3, 5e-3, 1e-2, 2e-2, 5e-2)
#: candidate pre-sliding distances of prismatic joints [m]
DELTAS_PRISMATIC = (1e-8, 1e-6, 2e-6, 5e-6, 1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3)
#: block length of the exact scan, in units of delta (exp(500) stays finite)
_BLOCK = 500.0


def dahl_state(q: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """Dahl's state along measured positions, exactly per monotone step (module docstring).

    Parameters
    ----------
    q : array_like, shape ``(S, m)``
        Positions of ``m`` joints at ``S`` samples, in time order [rad or m].
    delta : array_like, shape ``(m,)``
        Pre-sliding distance per joint, ``> 0``.

    Returns
    -------
    ndarray, shape ``(S, m)``
        ``z`` in ``[-1, 1]``, 0 at the first sample.
    """
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        q = q[:, None]
    delta = np.broadcast_to(np.asarray(delta, dtype=float), (q.shape[1],))
    z = np.zeros_like(q)
    if len(q) < 2:
        return z
    dq = np.diff(q, axis=0)
    for j in range(q.shape[1]):
        step = np.minimum(np.abs(dq[:, j]) / delta[j], 50.0)  # exp(-50): saturated; keeps a block's exponents finite
        drive = -np.expm1(-step) * np.sign(dq[:, j])  # (1 - e) s, accurate for small steps
        path = np.concatenate([[0.0], np.cumsum(step)])
        starts = np.unique(np.searchsorted(path, np.arange(0.0, path[-1], _BLOCK), side="right") - 1)
        starts = np.append(starts[starts < len(q) - 1], len(q) - 1)
        zs = 0.0
        for s, e in zip(starts[:-1], starts[1:]):
            # samples s..e: z_k = exp(-(L_k - L_s)) (z_s + sum_{i<k} exp(L_{i+1} - L_s) drive_i)
            rel = path[s:e + 1] - path[s]
            acc = np.concatenate([[0.0], np.cumsum(np.exp(rel[1:]) * drive[s:e])])
            seg = np.exp(-rel) * (zs + acc)
            z[s:e + 1, j] = seg
            zs = seg[-1]
    return np.clip(z, -1.0, 1.0)


@complete_docs
class Dahl(Term):
    """Pre-sliding friction (module docstring): ``delta_j`` per joint with a Coulomb term.

    Parameters
    ----------
    forced : bool
        Kept whatever the cross-validation says.
    delta : array_like, shape ``(m,)``, optional
        Pre-sliding distances [rad or m] (a saved result's).
    """

    name = "dahl"
    label = "pre-sliding (Dahl) friction"
    FIELDS = {"delta": per_joint(sc.Num(lo=min(DELTAS_PRISMATIC), hi=max(DELTAS)))}

    def __init__(self, forced: bool = False, delta=None):
        super().__init__(forced)
        self.delta = None if delta is None else np.asarray(delta, dtype=float)
        self._grid = None

    def _coulomb(self, ctx: TermContext) -> list[tuple[int, int]]:
        """``(row, column)`` of every joint's own Coulomb parameter in the core."""
        pos = {n: k for k, n in enumerate(ctx.model.names)}
        return [(j, pos[f"Fc_{name}"]) for j, name in enumerate(ctx.joints) if f"Fc_{name}" in pos]

    def available(self, ctx: TermContext) -> str | None:
        """Needs a Coulomb term of its own on some joint (``friction`` with ``coulomb``)."""
        if not self._coulomb(ctx):
            return "no joint has a Coulomb term of its own (--friction without coulomb)"
        return None

    def _grids(self, ctx: TermContext) -> np.ndarray:
        r = ctx.model.robot
        prismatic = np.array([r.jtype[r.dof_body[c]] == "P" for c in ctx.model.coords])
        return np.where(prismatic[None, :], np.array(DELTAS_PRISMATIC)[:, None], np.array(DELTAS)[:, None])

    def prepare(self, ctx: TermContext) -> None:
        """Dahl's state at every grid value, filtered and decimated like the fitted rows."""
        grids = self._grids(ctx)
        self._deltas = grids
        # each recording's state from its own start (z = 0), along its own positions, through its own filter
        self._grid = np.stack([ctx.each(lambda c, g=g: c.apply(dahl_state(c.raw_q, grids[g])))
                               for g in range(len(grids))])
        self._pairs = self._coulomb(ctx)

    def reset(self, ctx: TermContext) -> None:
        """Start at 2 mrad (2 micrometres for sliders): a typical pre-sliding distance."""
        self._choice = np.full(len(ctx.joints), int(np.argmin(np.abs(np.array(DELTAS) - 2e-3))))
        self._sync()

    def _sync(self) -> None:
        self.delta = self._deltas[self._choice, np.arange(len(self._choice))]

    def core(self, ctx: TermContext, x: np.ndarray) -> np.ndarray:
        """The Coulomb columns replaced by the filtered state ``z_j`` of the chosen ``delta_j``."""
        x = x.copy()
        for j, k in self._pairs:
            x[:, j, k] = self._grid[self._choice[j], :, j]
        return x

    def search(self, ctx: TermContext, trial) -> None:
        """``delta_j`` per joint on the grid, two sweeps.

        ``trial(j, k, column, commit=False)`` returns the training error with joint ``j``'s
        Coulomb column ``k`` replaced by ``column (S',)``; ``commit=True`` keeps it.
        """
        for _ in range(2):
            changed = False
            for j, k in self._pairs:
                errors = [trial(j, k, self._grid[g, :, j]) for g in range(len(self._deltas))]
                best = int(np.argmin(errors))
                changed |= best != self._choice[j]
                self._choice[j] = best
                trial(j, k, self._grid[best, :, j], commit=True)
            self._sync()
            if not changed:
                break

    def adjust_model(self, fit, q_raw, q, dq, ddq, tau: np.ndarray) -> np.ndarray:
        """``Fc_j (z_j - core Coulomb column)`` added, ``z_j`` integrated along the logged positions."""
        model = fit.model
        pos = {n: k for k, n in enumerate(model.names)}
        joints = model.joints
        sel = model.row_states
        out = tau.copy()
        z = dahl_state(q_raw, np.where(np.isfinite(self.delta), self.delta, 1.0))
        for j, name in enumerate(joints):
            k = pos.get(f"Fc_{name}")
            if k is None or not np.isfinite(self.delta[j]):
                continue
            v, a = dq[:, sel[j]], ddq[:, sel[j]]
            out[:, j] += fit.theta[k] * (z[:, j] - model.drives.column("Fc", v, a))
        return out

    def values(self, joints: list[str]) -> dict:
        """``{"delta": {joint: distance}}`` [rad or m]."""
        return {"delta": {j: float(d) for j, d in zip(joints, self.delta)}}

    def describe(self, joints: list[str]) -> str:
        """E.g. ``delta 2 mrad (panda_joint1), ...``."""
        return "pre-sliding distance " + ", ".join(f"{j} {d:.2g}" for j, d in zip(joints, self.delta))

    def export(self) -> dict:
        """Not representable: MuJoCo's ``frictionloss`` is Coulomb friction without pre-sliding."""
        return {"not": ["pre-sliding (Dahl) friction: the files carry Coulomb friction (MJCF frictionloss) without "
                        "its pre-sliding distance"]}

    def load(self, doc: dict, joints: list[str], model) -> None:
        """The distances of a saved result."""
        d = doc["values"]["delta"]
        self.delta = np.array([float(d[j]) for j in joints])
