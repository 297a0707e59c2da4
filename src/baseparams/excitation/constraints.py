"""The design's constraints on the grid: linear (positions, velocities, accelerations) and nonlinear.

Nonlinear rows: the model's own torques within the effort limits, a loop robot's ``cond(J_p)``
bound and a link's keep-out height. :class:`Evaluator` computes the criterion, the constraints
and their gradients at a point once and keeps the best feasible point seen.
"""

from __future__ import annotations

import numpy as np

from .criterion import grid_gradients, grid_values
from .problem import FEAS_TOL, KEEPOUT_MARGIN, LIMIT_STRIDE, LOOP_MARGIN, MARGIN, Problem, shrunk_range


class Evaluator:
    """The criterion, the nonlinear constraints and their gradients at ``x``, cached.

    Values and gradients are computed on demand (a line search needs values only). Keeps the best
    feasible point seen (``best``: value, x).

    Parameters
    ----------
    prob : Problem
        The design problem.
    lin : tuple of ndarray
        ``(C (r, m k), c (r,))``: the linear constraints ``C x + c >= 0`` (:func:`linear_constraints`),
        for the feasibility of the best point.
    """

    def __init__(self, prob: Problem, lin: tuple[np.ndarray, np.ndarray]):
        self.prob, self.lin = prob, lin
        self.x = None
        self.val: dict | None = None
        self.out: dict = {}
        self.best = (np.inf, None)

    def __call__(self, x: np.ndarray, grad: bool = False) -> dict:
        """``{"value", "cons", "valid"}`` at ``x (m k,)``, and ``"grad", "jac"`` with ``grad``."""
        prob = self.prob
        if self.x is None or not np.array_equal(x, self.x):
            self.x, self.states = x.copy(), prob.states(x)
            self.val = grid_values(prob, *self.states)
            self.out = self._value_part(x)
        if grad and "grad" not in self.out:
            d = grid_gradients(prob, *self.states, self.val) if self.val is not None else None
            if d is None:
                self.out.update(grad=np.zeros_like(x), jac=np.zeros((n_nonlinear(prob), x.size)))
            else:
                self.out.update(grad=sum(d["g"][i] @ prob.bases[i] for i in range(3)).reshape(-1),
                                jac=_nonlinear_jacobian(prob, d))
        return self.out

    def _value_part(self, x: np.ndarray) -> dict:
        """Value and constraints at ``x``; the best feasible point updated."""
        if self.val is None:  # outside the workspace: reject the step
            return {"value": 1e3, "cons": -np.ones(n_nonlinear(self.prob)), "valid": False}
        cons = _nonlinear_values(self.prob, self.val)
        value = self.val["value"]
        feasible = np.all(self.lin[0] @ x + self.lin[1] >= -FEAS_TOL) and np.all(cons >= -FEAS_TOL)
        if np.isfinite(value) and feasible and value < self.best[0]:
            self.best = (value, x.copy())
        return {"value": value if np.isfinite(value) else 1e3, "cons": cons, "valid": True}


def n_nonlinear(prob: Problem) -> int:
    """Number of nonlinear constraint rows: torques (two per grid sample and limited joint), loops, keep-out.

    Parameters
    ----------
    prob : Problem
        The design problem.

    Returns
    -------
    int
        The rows of :func:`_nonlinear_values`.
    """
    n = 0 if prob.theta is None else 2 * prob.t.size * int(np.isfinite(prob.limits[:, 4]).sum())
    return n + (prob.t.size if prob.cond_max is not None else 0) + prob.t.size * len(prob.keepout or ())


def _nonlinear_values(prob: Problem, val: dict) -> np.ndarray:
    """Torque rows ``MARGIN -+ tau / effort >= 0`` then loop rows ``log(LOOP_MARGIN cond_max / cond(J_p)) >= 0``."""
    out = [np.zeros(0)]
    if val["tau"] is not None:
        eff = prob.limits[:, 4]
        rows = np.flatnonzero(np.isfinite(eff))
        frac = val["tau"][:, rows] / eff[rows]  # torques as fractions of the effort limits
        out += [(MARGIN - frac).reshape(-1), (MARGIN + frac).reshape(-1)]
    if val["logc"] is not None:
        out.append(np.log(LOOP_MARGIN * prob.cond_max) - val["logc"])
    if val["z"] is not None:  # keep-out: heights above the floors [m], sample by sample
        out.append((val["z"] - prob.keepout_min - KEEPOUT_MARGIN).reshape(-1))
    return np.concatenate(out)


def _nonlinear_jacobian(prob: Problem, d: dict) -> np.ndarray:
    """The Jacobian ``(rows, m k)`` of :func:`_nonlinear_values`."""
    g, m, k = prob.t.size, prob.m, prob.k
    jac = [np.zeros((0, m * k))]
    if d["dtau"] is not None:
        rows = np.flatnonzero(np.isfinite(prob.limits[:, 4]))
        dt = sum(np.einsum("jsr,sk->srjk", d["dtau"][i][:, :, rows], prob.bases[i]) for i in range(3))
        dt = dt / prob.limits[rows, 4][None, :, None, None]
        dt = dt.reshape(g * len(rows), m * k)
        jac += [-dt, dt]
    if d["dlogc"] is not None:
        jl = -d["dlogc"].T[:, :, None] * prob.bases[0][:, None, :]  # (G, m, k)
        jac.append(jl.reshape(g, m * k))
    if d["dz"] is not None:  # (m, G, K) -> rows (G, K), columns (m, k)
        jac.append(np.einsum("jgl,gb->gljb", d["dz"], prob.bases[0]).reshape(-1, m * k))
    return np.vstack(jac)


def linear_constraints(prob: Problem) -> tuple[np.ndarray, np.ndarray]:
    """``(C, c)``: position, velocity and acceleration limits on the grid, ``C x + c >= 0``.

    Each row is divided by its limit (the range's width for positions): values are fractions. Every
    ``LIMIT_STRIDE``-th grid sample only: the rows cost SLSQP more than the criterion does, and the
    controller-rate check closes the gaps.

    Parameters
    ----------
    prob : Problem
        The design problem.

    Returns
    -------
    C : ndarray, shape ``(r, m k)``
        The rows, over the variables ``x`` (:meth:`Problem.states`).
    c : ndarray, shape ``(r,)``
        The constants.
    """
    c, rhs, _ = linear_rows(prob)
    return c, rhs


def linear_rows(prob: Problem) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int]]]:
    """:func:`linear_constraints` and, per row, what it limits.

    Parameters
    ----------
    prob : Problem
        The design problem.

    Returns
    -------
    C : ndarray, shape ``(r, m k)``
        The rows.
    c : ndarray, shape ``(r,)``
        The constants.
    labels : list of tuple of (int, int), length ``r``
        ``(kind, joint)`` per row: kind 0, 1, 2 position, velocity, acceleration; ``joint`` the
        designed coordinate.
    """
    m, k = prob.m, prob.k
    bases = [b[::LIMIT_STRIDE] for b in prob.bases]
    g = len(bases[0])
    lim = prob.limits
    lo, hi = shrunk_range(lim)
    rows, rhs, labels = [], [], []
    for j in range(m):
        for kind, lower, upper, unit in ((0, lo[j], hi[j], lim[j, 1] - lim[j, 0]),
                                         (1, -MARGIN * lim[j, 2], MARGIN * lim[j, 2], lim[j, 2]),
                                         (2, -MARGIN * lim[j, 3], MARGIN * lim[j, 3], lim[j, 3])):
            if not np.isfinite(upper):
                continue
            block = np.zeros((g, m * k))
            block[:, j * k:(j + 1) * k] = bases[kind] / unit
            rows += [block, -block]
            rhs += [np.full(g, -lower / unit), np.full(g, upper / unit)]
            labels += [(kind, j)] * (2 * g)
    if not rows:
        return np.zeros((0, m * k)), np.zeros(0), []
    return np.vstack(rows), np.concatenate(rhs), labels


def nonlinear_labels(prob: Problem) -> list[tuple[int, int]]:
    """What each row of :func:`_nonlinear_values` limits.

    Parameters
    ----------
    prob : Problem
        The design problem.

    Returns
    -------
    list of tuple of (int, int)
        ``(kind, joint)`` per row: kind 3 torque (``joint`` the designed coordinate), 4 loops (``joint``
        -1), 5 keep-out (``joint`` the index in ``prob.keepout``).
    """
    g = prob.t.size
    out = []
    if prob.theta is not None:
        rows = np.flatnonzero(np.isfinite(prob.limits[:, 4]))
        out += [(3, int(rows[i % len(rows)])) for i in range(g * len(rows))] * 2
    if prob.cond_max is not None:
        out += [(4, -1)] * g
    if prob.keepout is not None:
        out += [(5, k) for _ in range(g) for k in range(len(prob.keepout))]
    return out
