"""The optimisation criterion and its gradient: ``log cond`` or D-optimality on the model regressor.

The regressor of a grid sample depends on that sample's state only, so ``3 m + 1`` batched
evaluations (one finite-difference step per state column, :data:`STEPS`) give every sample's
derivative at once.
"""

from __future__ import annotations

import numpy as np

from ..ident.model import IdentModel
from .problem import Problem, keepout_height

#: finite-difference steps of the regressor per state column: q, dq (rad, rad/s), ddq (exact: linear)
STEPS = (1e-6, 1e-6, 1.0)


def criterion_terms(a: np.ndarray, criterion: str, interest: int | None = None) -> tuple[float, np.ndarray]:
    """The criterion to minimise and its gradient with respect to the information matrix.

    Parameters
    ----------
    a : ndarray, shape ``(S, m, p)``
        Model regressor.
    criterion : {"cond", "logdet"}
        ``cond``: ``log cond`` of the column-scaled stacked regressor; ``logdet``:
        ``-log det(M / S) / p``, ``M = sum_s A_s^T A_s``.
    interest : int, optional
        Only the first ``interest`` columns matter (a payload's ten), the others are nuisance
        parameters fitted with them (drive terms): the criterion is taken on the information left
        for those columns, the Schur complement ``S = M_11 - M_12 M_22^-1 M_21`` (D_s-optimality
        for ``logdet``); ``d value / d M = C^T (d value / d S) C`` with ``C = [1, -M_12 M_22^-1]``.

    Returns
    -------
    value : float
        The value (inf when ``M`` is singular).
    gamma : ndarray, shape ``(p, p)``
        ``d value / d M`` (symmetric): the gradient with respect to ``A`` is ``2 A gamma``.
    """
    p = a.shape[2]
    w = a.reshape(-1, p)
    if interest is not None and interest < p:
        return _schur_terms(w.T @ w, len(a), criterion, int(interest))
    return information_terms(w.T @ w, len(a), criterion)


def _schur_terms(mm: np.ndarray, samples: int, criterion: str, k: int) -> tuple[float, np.ndarray]:
    """:func:`information_terms` of the Schur complement of the nuisance block, mapped back to ``M``."""
    p = len(mm)
    try:
        b = np.linalg.solve(mm[k:, k:], mm[k:, :k]).T  # M_12 M_22^-1
    except np.linalg.LinAlgError:
        return np.inf, np.zeros((p, p))
    c = np.hstack([np.eye(k), -b])
    value, g = information_terms(c @ mm @ c.T, samples, criterion)
    return value, c.T @ g @ c


def information_terms(mm: np.ndarray, samples: int, criterion: str) -> tuple[float, np.ndarray]:
    """The criterion of an information matrix and its gradient (:func:`criterion_terms`).

    Parameters
    ----------
    mm : ndarray, shape ``(p, p)``
        ``M = sum_s A_s^T A_s``.
    samples : int
        ``S`` (``logdet`` is per sample).
    criterion : {"cond", "logdet"}
        As :func:`criterion_terms`.

    Returns
    -------
    value : float
        The value (inf when ``M`` is singular).
    gamma : ndarray, shape ``(p, p)``
        ``d value / d M``.
    """
    p = len(mm)
    d = np.sqrt(np.maximum(np.diag(mm), 0.0))
    if np.any(d <= 0):
        return np.inf, np.zeros((p, p))
    g = mm / np.outer(d, d)
    lam, v = np.linalg.eigh(g)
    if lam[0] <= lam[-1] * 1e-15:
        return np.inf, np.zeros((p, p))
    if criterion == "logdet":
        ginv = (v / lam) @ v.T
        value = -(np.sum(np.log(lam)) + 2 * np.sum(np.log(d)) - p * np.log(samples)) / p
        return float(value), -ginv / np.outer(d, d) / p
    h = 0.5 * (np.outer(v[:, -1], v[:, -1]) / lam[-1] - np.outer(v[:, 0], v[:, 0]) / lam[0])
    gamma = h / np.outer(d, d) - np.diag(np.sum(h * g, axis=1) / d**2)
    return float(0.5 * np.log(lam[-1] / lam[0])), gamma


def trajectory_criterion(model: IdentModel, q, dq, ddq, chunk: int = 4000) -> tuple[float, float]:
    """Condition number and ``log det`` of a trajectory's model regressor (the numbers a design reports).

    Parameters
    ----------
    model : IdentModel
        The identification model (its regressor's columns: base and drive parameters).
    q, dq, ddq : array_like, shape ``(S, state_columns)``
        The states (a loop robot's actuated coordinates).
    chunk : int
        Samples per regressor block (memory ``chunk * m * p`` floats).

    Returns
    -------
    cond : float
        Condition number of the column-scaled stacked regressor, unweighted, every sample
        (:func:`baseparams.ident.estimate.motion_factor`, :func:`~baseparams.ident.estimate.excitation`;
        inf when singular): the measure ``identify`` reports for a log's motion.
    logdet : float
        ``log det(M / S)``, ``M`` the information matrix ``A^T A`` (SI units).
    """
    from ..ident.estimate import condition_number, motion_factor

    r = motion_factor(model, q, dq, ddq, chunk)
    cond = condition_number(r)
    diag = np.abs(np.diag(r))
    logdet = float(2 * np.sum(np.log(diag)) - model.n_params * np.log(len(q))) if np.all(diag > 0) else -np.inf
    return float(cond), logdet


def _perturbed(q: np.ndarray, dq: np.ndarray, ddq: np.ndarray) -> tuple[np.ndarray, ...]:
    """The ``3 m`` perturbations of the states, one column and kind at a time: ``3 m G`` samples each."""
    m = q.shape[1]
    out = []
    for kind, x in enumerate((q, dq, ddq)):
        blocks = []
        for which in range(3):
            for j in range(m):
                y = x.copy()
                if which == kind:
                    y[:, j] += STEPS[kind]
                blocks.append(y)
        out.append(np.concatenate(blocks))
    return tuple(out)


def grid_values(prob: Problem, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray) -> dict | None:
    """The criterion and the nonlinear constraints' data at grid states.

    Parameters
    ----------
    prob : Problem
        The design problem.
    q, dq, ddq : ndarray, shape ``(G, m)``
        States of the designed coordinates on the grid.

    Returns
    -------
    dict or None
        ``{"a" (G, m, p): the model regressor, "value", "gamma" (p, p) (:func:`criterion_terms`),
        "tau" (G, m) or None: the prior model's torques, "logc" (G,) or None: log cond(J_p) (loops),
        "z" (G, K) or None: the kept-out links' heights [m]}``; ``None`` when a sample does not close the loops
        from the reference (outside the workspace).
    """
    from ..kinematics.loops import close_loops

    logc, cs = None, None
    if prob.cond_max is not None:
        cs = close_loops(prob.model.robot, q, dq, ddq, cond_max=np.inf)
        if cs.kept != len(q):
            return None
        logc = np.log(cs.cond)
    a = prob.model.regressor(q, dq, ddq, closed=cs)
    value, gamma = criterion_terms(a, prob.criterion, getattr(prob.model, "interest", None))
    return {"a": a, "value": value, "gamma": gamma, "tau": None if prob.theta is None else a @ prob.theta,
            "logc": logc, "z": None if prob.keepout is None else keepout_height(prob, q)}


def grid_gradients(prob: Problem, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, val: dict) -> dict | None:
    """Derivatives per grid sample and state column, by batched finite differences.

    Parameters
    ----------
    prob : Problem
        The design problem.
    q, dq, ddq : ndarray, shape ``(G, m)``
        States of the designed coordinates on the grid.
    val : dict
        :func:`grid_values` at these states.

    Returns
    -------
    dict or None
        ``{"g" (3, m, G): d value / d (q, dq, ddq), "dtau" (3, m, G, m) or None, "dlogc" (m, G) or
        None, "dz" (m, G, K) or None}``; ``None`` when a perturbed sample does not close the loops.
    """
    from ..kinematics.loops import close_loops

    g, m = q.shape
    out = {"dtau": None, "dlogc": None, "dz": None}
    states, cs = _perturbed(q, dq, ddq), None
    if prob.keepout is not None:  # the first m blocks move q
        out["dz"] = (keepout_height(prob, states[0][: g * m]).reshape(m, g, -1) - val["z"]) / STEPS[0]
    if prob.cond_max is not None:  # the first m blocks move q: cond(J_p) changes with them only
        cs = close_loops(prob.model.robot, *states, cond_max=np.inf)
        if cs.kept != 3 * g * m:
            return None
        out["dlogc"] = (np.log(cs.cond[: g * m]).reshape(m, g) - val["logc"]) / STEPS[0]
    big = prob.model.regressor(*states, closed=cs).reshape(3 * m, g, m, -1)
    deriv = (big - val["a"]) / np.repeat(STEPS, m)[:, None, None, None]  # (3 m, G, m, p)
    grad = np.einsum("kgrp,grp->kg", deriv, 2.0 * val["a"] @ val["gamma"]).reshape(3, m, g)
    grad[1][(np.abs(dq) < 2 * STEPS[1]).T] = 0.0  # sign(dq) columns jump there: no derivative
    out["g"] = grad
    if prob.theta is not None:
        out["dtau"] = (deriv @ prob.theta).reshape(3, m, g, m)
    return out
