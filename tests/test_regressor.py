"""The TP regressor against an independent Newton-Euler, and its rank facts."""

import numpy as np
import pytest

from baseparams.kinematics import forward_kinematics
from baseparams.numerics import numerical_nullspace
from baseparams.regressor import bar, regressor, regressor_tensor
from baseparams.robots import go2, puma560, random_robot

from oracles import rnea

CASES = [(seed, jt, fl) for seed in range(4) for jt, fl in
         [("R", False), ("P", False), ("U", False), ("S", False), ("RPUS", False), ("RPUS", True), ("R", True)]]


@pytest.mark.parametrize("seed, types, floating", CASES)
def test_regressor_matches_newton_euler(seed, types, floating):
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, int(rng.integers(2, 8)), joint_types=types, floating=floating,
                         gravity=rng.normal(scale=5, size=3))
    s = 5
    q, dq, ddq = rng.uniform(-2, 2, (3, s, robot.dof))
    tau = regressor(robot, q, dq, ddq) @ robot.parameters("paper")
    ref = np.array([rnea(robot, q[k], dq[k], ddq[k]) for k in range(s)])
    assert np.abs(tau - ref).max() <= 1e-10 * np.abs(ref).max()


@pytest.mark.parametrize("make", [puma560, go2])
def test_builtin_regressor_matches_newton_euler(make, rng):
    robot = make()
    q, dq, ddq = rng.uniform(-1, 1, (3, 4, robot.dof))
    tau = regressor(robot, q, dq, ddq) @ robot.parameters("paper")
    ref = np.array([rnea(robot, q[k], dq[k], ddq[k]) for k in range(4)])
    assert np.abs(tau - ref).max() <= 1e-10 * np.abs(ref).max()


def test_tensor_form_matches_matrix_form(rng):
    robot = random_robot(rng, 5, floating=True)
    q, dq, ddq = rng.uniform(-1, 1, (3, 3, robot.dof))
    r = regressor_tensor(robot, q, dq, ddq)
    assert r.shape == (3, robot.dof, robot.n, 4, 4)
    assert np.allclose(bar(r).reshape(3, robot.dof, -1), regressor(robot, q, dq, ddq), atol=1e-12)


def test_chunking_is_transparent(rng):
    robot = random_robot(rng, 4)
    q, dq, ddq = rng.uniform(-1, 1, (3, 50, robot.dof))
    assert np.allclose(regressor(robot, q, dq, ddq, chunk=7), regressor(robot, q, dq, ddq))


def test_jacobian_lines_are_twist_derivatives(rng):
    """V_i = sum_j L_j^i dq_j, and the Jacobian lines match finite differences of g_i."""
    robot = random_robot(rng, 5, joint_types="RPUS")
    q = rng.uniform(-1, 1, robot.dof)
    dq = rng.uniform(-1, 1, robot.dof)
    st = forward_kinematics(robot, q, dq)
    jl = st.jacobian_lines()[0]
    assert np.allclose(np.einsum("jic,j->ic", jl, dq), st.V[0])
    h = 1e-6
    gp = forward_kinematics(robot, q + h * dq).g[0]
    gm = forward_kinematics(robot, q - h * dq).g[0]
    gdot = (gp - gm) / (2 * h)
    # spatial twist: gdot g^-1 = V^
    from baseparams.pga import hat, inverse_transform

    assert np.allclose(gdot @ inverse_transform(st.g[0]), hat(st.V[0]), atol=1e-6)


@pytest.mark.parametrize("gravity, rank", [((0, 0, -9.81), 36), ((-9.81, 0, 0), 38)])
def test_puma560_rank(gravity, rank):
    res = numerical_nullspace(puma560(gravity=gravity), samples=100, seed=0)
    assert res.rank == rank and res.decided


def test_go2_rank_with_base_rows():
    res = numerical_nullspace(go2(), samples=100, seed=0)
    assert res.rank == 94 and res.decided
