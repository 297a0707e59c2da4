"""The structured certificate's climb to the root (prismatic chains): run by run, the row-by-row walk's results."""

from dataclasses import replace

import numpy as np
import pytest

from baseparams.nullspace import drng
from baseparams.nullspace import structured as st
from baseparams.nullspace.certify import certify
from baseparams.nullspace.columns import Columns
from baseparams.robots import random_robot


def _robot(seed: int, n: int, kinds: str, branching: float):
    return random_robot(np.random.default_rng(seed), n, kinds, branching=branching)


def _row_by_row(lines, l2, dofs, par):
    """The climb as the walk did it before it was vectorised: each column, each body's rows in turn, up to the root."""
    def one(w, d2, x, worst, tol):
        while x >= 0:
            for m in dofs[x]:
                num = np.sum(np.einsum("sc,sc->s", lines[m], w) ** 2)
                worst = max(worst, float(st._ratio(num, np.sum(l2[m] * d2))))
            if worst > tol:
                return worst
            x = int(par[x])
        return worst

    def climb(w, d2, x, worst, tol, runs):
        return np.array([one(w[j], d2[j], x, float(worst[j]), tol) for j in range(len(w))])
    return climb


def _perturbed(cols: Columns, seed: int) -> Columns:
    """The columns and copies with noise of sizes 1e-13 .. 1e-5: they leave the nullspace at various heights."""
    rng = np.random.default_rng(seed)
    scale = 10.0 ** rng.uniform(-13, -5, size=(len(cols), 1))
    noisy = replace(cols, h=cols.h + scale * rng.normal(size=cols.h.shape))
    return Columns.concat([cols, noisy])


@pytest.mark.parametrize("seed, kinds, branching", [(1, "P", 0.0), (2, "P", 0.4), (3, "RP", 0.0), (4, "RP", 0.4),
                                                    (5, "R", 0.0), (6, "RPUS", 0.4), (7, "PC", 0.0)])
def test_the_climb_gives_the_row_by_row_residuals(seed, kinds, branching, monkeypatch):
    robot = _robot(seed, 60, kinds, branching)
    cols = _perturbed(drng(robot).columns, seed).scaled(1.0 / st.decision_scale(robot, "paper")[:10])
    *states, big_g, _ = st.sampled_states(robot, 12, seed)
    x, lines = st.wrench_maps(robot, 12, seed, st.decision_scale(robot, "paper")[:10], states=tuple(states))
    dofs, coupled = st.row_groups(robot, "all", big_g)
    par = np.asarray(robot.parent, dtype=int)
    for tol in (1e-8, 1e-11):
        fast = st.column_residuals(cols, robot, x, lines, dofs, tol, coupled)
        with monkeypatch.context() as m:
            m.setattr(st, "_climb", _row_by_row(lines, np.sum(lines * lines, axis=2), dofs, par))
            slow = st.column_residuals(cols, robot, x, lines, dofs, tol, coupled)
        assert np.array_equal(fast, slow)  # bit for bit: the certificate's figures do not move
        assert np.any(fast > tol) and np.any((fast > 0) & (fast <= tol))  # both outcomes were exercised


def test_root_runs_cover_every_path_in_few_runs():
    robot = _robot(8, 200, "RP", 0.4)
    par = np.asarray(robot.parent, dtype=int)
    dofs = [np.arange(robot.q_index[i], robot.q_index[i] + robot.ndofs[i]) for i in range(robot.n)]
    lines = np.random.default_rng(0).normal(size=(robot.dof, 3, 6))
    _, head, pos, order, ptr, owner, lines_o, _ = st._root_runs(par, dofs, lines, np.sum(lines ** 2, axis=2))
    assert sorted(order) == list(range(robot.n))
    for b in range(robot.n):
        path, x, runs = [], b, 0
        while x >= 0:  # the runs, read upwards, are the path to the root
            path.extend(order[pos[head[x]]:pos[x] + 1][::-1])
            x, runs = par[head[x]], runs + 1
        truth = [b]
        while par[truth[-1]] >= 0:
            truth.append(par[truth[-1]])
        assert path == truth and runs <= np.log2(robot.n) + 1
    for p, b in enumerate(order):  # each position's rows are its body's
        assert np.array_equal(lines_o[ptr[p]:ptr[p + 1]], lines[dofs[b]]) and np.all(owner[ptr[p]:ptr[p + 1]] == p)


@pytest.mark.parametrize("seed, kinds, branching", [(11, "P", 0.0), (12, "P", 0.4), (13, "RP", 0.0), (14, "PR", 0.4)])
def test_structured_equals_dense_on_prismatic_trees(seed, kinds, branching):
    robot = _robot(seed, 16, kinds, branching)
    res = drng(robot)
    dense = certify(robot, result=res, method="dense")
    cert = certify(robot, result=res, method="structured")
    assert dense.status == cert.status == "certified" and cert.nullity == dense.nullity == res.rank
    assert np.linalg.svd(cert.basis.T @ dense.basis, compute_uv=False).min() > 1 - 1e-8
