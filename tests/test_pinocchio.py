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


# ---------------------------------------------------------------- URDF planar joints (issue 39)
def _planar_urdf(rng, axis="0 0 1"):
    """A mobile base on a URDF planar joint, an arm of 2-4 random R/P joints on it."""
    def inertial():
        a = rng.uniform(0.01, 0.05, 3)
        return (f'<inertial><origin xyz="{" ".join(map(str, rng.uniform(-0.1, 0.1, 3)))}"/>'
                f'<mass value="{rng.uniform(0.5, 3)}"/><inertia ixx="{a[1] + a[2]}" ixy="0.001" ixz="0" '
                f'iyy="{a[0] + a[2]}" iyz="0" izz="{a[0] + a[1]}"/></inertial>')

    def xyz():
        return " ".join(f"{v:.4f}" for v in rng.uniform(-0.3, 0.3, 3))

    axis_el = "" if axis is None else f'<axis xyz="{axis}"/>'
    text = ['<robot name="mobile"><link name="world"/>',
            f'<joint name="base_joint" type="planar"><parent link="world"/><child link="base"/>'
            f'<origin xyz="{xyz()}" rpy="{xyz()}"/>{axis_el}</joint>', f'<link name="base">{inertial()}</link>']
    parent = "base"
    for k in range(int(rng.integers(2, 5))):
        kind = "prismatic" if rng.random() < 0.25 else "revolute"
        text.append(f'<joint name="j{k}" type="{kind}"><parent link="{parent}"/><child link="l{k}"/>'
                    f'<origin xyz="{xyz()}" rpy="{xyz()}"/><axis xyz="{xyz()}"/>'
                    f'<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
                    f'<link name="l{k}">{inertial()}</link>')
        parent = f"l{k}"
    return "\n".join(text + ["</robot>"])


@pytest.mark.parametrize("seed", range(6))
def test_urdf_planar_joint_is_pinocchios(seed, tmp_path):
    """A URDF ``planar`` joint (axis z) as Pinocchio reads it: the same link poses at every configuration
    (Pinocchio's q = (x, y, cos, sin)), and the certified nullity equals Pinocchio's rank deficiency; DRNG is
    complete (R-C, the planar joint as two slides and a hinge without mass between them)."""
    import warnings

    import baseparams as bp
    from baseparams.kinematics.tree import forward_kinematics

    from erd import pinocchio_nullity

    rng = np.random.default_rng(seed)
    path = tmp_path / "mobile.urdf"
    path.write_text(_planar_urdf(rng))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # random inertias may be infeasible: noted only
        robot = bp.load(str(path))
    assert robot.jtype[0] == "C" and robot.ndofs[0] == 3
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    q = rng.uniform(-2, 2, (5, robot.dof))
    g = forward_kinematics(robot, q).g
    for k in range(len(q)):
        qp = np.r_[q[k, :2], np.cos(q[k, 2]), np.sin(q[k, 2]), q[k, 3:]]
        pin.framesForwardKinematics(model, data, qp)
        for i, name in enumerate(robot.names):
            ours = g[k, i] @ robot.M0[i]
            np.testing.assert_allclose(ours, data.oMf[model.getFrameId(name)].homogeneous, atol=1e-10)
    a = bp.analyze(robot)
    assert a.status == "certified" and a.certificate.completed == 0
    assert a.nullity == pinocchio_nullity(model, path, 200)[0]
