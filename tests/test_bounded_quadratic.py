"""The non-negative drive terms' quadratic program (``select.bounded_quadratic``) against cvxpy.

Seeded random convex problems with some variables bounded below by zero and others free (the
free ones are eliminated first, by their Schur complement): the minimiser equals Clarabel's and
satisfies the KKT conditions.
"""

from __future__ import annotations

import numpy as np
import pytest

from baseparams.ident.select import bounded_quadratic

cp = pytest.importorskip("cvxpy")


@pytest.mark.parametrize("seed", range(12))
def test_bounded_quadratic_is_the_convex_minimiser(seed):
    rng = np.random.default_rng(seed)
    p = int(rng.integers(3, 40))
    a = rng.standard_normal((p + 5, p)) * np.exp(rng.uniform(-3, 3, p))  # badly scaled columns
    h = a.T @ a + 1e-6 * np.eye(p)
    g = rng.standard_normal(p) * 10
    nonneg = rng.random(p) < (0.3 if seed % 3 else 1.0)  # every third problem: every variable bounded
    nonneg[0] = True
    x = bounded_quadratic(h, g, nonneg)
    # KKT: bounded variables >= 0; gradient zero on free and inactive ones, >= 0 where held at 0
    grad = h @ x - g
    tol = 1e-7 * max(np.abs(g).max(), 1.0)
    assert np.all(x[nonneg] >= -1e-12)
    inactive = ~nonneg | (x > 1e-10)
    assert np.all(np.abs(grad[inactive]) <= tol * (1 + np.abs(np.diag(h))[inactive]))
    assert np.all(grad[nonneg & ~inactive] >= -tol)
    # an independent solver agrees
    v = cp.Variable(p)
    l_chol = np.linalg.cholesky(h)
    cons = [v[np.flatnonzero(nonneg)] >= 0]
    cp.Problem(cp.Minimize(0.5 * cp.sum_squares(l_chol.T @ v) - g @ v), cons).solve(solver=cp.CLARABEL)
    obj = lambda y: 0.5 * y @ h @ y - g @ y  # noqa: E731
    assert obj(x) <= obj(np.where(nonneg, np.maximum(v.value, 0), v.value)) + 1e-6 * max(1.0, abs(obj(x)))
