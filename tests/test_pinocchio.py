"""Pinocchio as a test-time peer: torques and regressor ranks on Puma560 and Go2."""

import numpy as np
import pinocchio as pin
import pytest

from baseparams.io.pinocchio import forces_from_pinocchio, state_to_pinocchio, to_pinocchio
from baseparams.regressor import regressor
from baseparams.robots import go2, puma560, random_robot


def _samples(robot, s, seed):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1, 1, (3, s, robot.dof))


@pytest.mark.parametrize("make", [puma560, go2, lambda: random_robot(np.random.default_rng(3), 7, "RP", True)])
def test_torques_match_pinocchio(make):
    robot = make()
    model = to_pinocchio(robot)
    data = model.createData()
    q, dq, ddq = _samples(robot, 10, 1)
    tau = regressor(robot, q, dq, ddq) @ robot.parameters("paper")
    for k in range(len(q)):
        qp, vp, ap = state_to_pinocchio(robot, q[k], dq[k], ddq[k])
        ref = forces_from_pinocchio(robot, q[k], pin.rnea(model, data, qp, vp, ap))
        assert np.abs(tau[k] - ref).max() <= 1e-10 * np.abs(ref).max()
        # Pinocchio's own regressor reproduces its torques with its own parameters
        ypin = pin.computeJointTorqueRegressor(model, data, qp, vp, ap)
        ppin = np.concatenate([model.inertias[j].toDynamicParameters() for j in range(1, model.njoints)])
        assert np.allclose(forces_from_pinocchio(robot, q[k], ypin @ ppin), ref, rtol=1e-10, atol=1e-9)


@pytest.mark.parametrize("make, rank", [(puma560, 36), (lambda: puma560(gravity=(-9.81, 0, 0)), 38), (go2, 94)])
def test_stacked_rank_equals_pinocchio(make, rank):
    robot = make()
    model = to_pinocchio(robot)
    data = model.createData()
    q, dq, ddq = _samples(robot, 60, 2)
    w_ours = regressor(robot, q, dq, ddq).reshape(-1, 10 * robot.n)
    rows = []
    for k in range(len(q)):
        qp, vp, ap = state_to_pinocchio(robot, q[k], dq[k], ddq[k])
        y = pin.computeJointTorqueRegressor(model, data, qp, vp, ap)
        # express Pinocchio's rows in our generalized forces (root wrench re-expressed)
        rows.append(np.stack([forces_from_pinocchio(robot, q[k], y[:, c]) for c in range(y.shape[1])], 1))
    w_pin = np.concatenate(rows)

    def rk(w):
        s = np.linalg.svd(w, compute_uv=False)
        return int(np.sum(s > 1e-9 * s[0]))

    assert rk(w_ours) == rk(w_pin) == rk(np.hstack([w_ours, w_pin])) == rank
