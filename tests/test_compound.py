"""Compound (C) joints: several elementary screws in one body (MJCF bodies with several joints)."""

from __future__ import annotations

import numpy as np
import pytest

from baseparams.errors import ModelError
from baseparams.kinematics import re_reference
from baseparams.model import Inertia, RobotBuilder
from baseparams.model.robot import compound_screw
from baseparams.nullspace.certify import certify
from baseparams.nullspace.drng import drng
from baseparams.numerics import numerical_nullspace, stacked_regressor
from baseparams.regressor import regressor
from baseparams.robots.random import random_robot

from oracles import rnea

CASES = [(seed, types, fl) for seed in range(6) for types, fl in [("C", False), ("RC", False), ("CPU", True)]]


@pytest.mark.parametrize("seed, types, floating", CASES)
def test_compound_regressor_matches_newton_euler(seed, types, floating):
    rng = np.random.default_rng(100 + seed)
    robot = random_robot(rng, int(rng.integers(2, 6)), joint_types=types, floating=floating,
                         gravity=rng.normal(scale=5, size=3))
    assert "C" in robot.jtype or types != "C"
    q, dq, ddq = rng.uniform(-2, 2, (3, 4, robot.dof))
    tau = regressor(robot, q, dq, ddq) @ robot.parameters("paper")
    ref = np.array([rnea(robot, q[k], dq[k], ddq[k]) for k in range(4)])
    assert np.abs(tau - ref).max() <= 1e-10 * np.abs(ref).max()


@pytest.mark.parametrize("seed, types, floating", CASES)
def test_compound_columns_in_nullspace_and_certified(seed, types, floating):
    rng = np.random.default_rng(200 + seed)
    gravity = [(0, 0, -9.81), (0, 0, 0), tuple(rng.normal(size=3))][seed % 3]
    robot = random_robot(rng, int(rng.integers(2, 6)), joint_types=types, floating=floating, gravity=gravity)
    res = drng(robot)
    b = res.dense()
    w = stacked_regressor(robot, 60, seed)
    if b.shape[1]:
        col = np.linalg.norm(w @ (b / np.linalg.norm(b, axis=0)), axis=0) / np.linalg.norm(w, 2)
        assert col.max() < 1e-10
    c = certify(robot, samples=60, seed=seed)
    assert c.certified and c.nullity == numerical_nullspace(robot, 60, seed).nullity


def _planar():
    inert = Inertia(2.0, com=(0.1, 0.0, 0.2), inertia=(0.1, 0.2, 0.25))
    b = RobotBuilder("planar", gravity=(0, 0, -9.81))
    b.add_link("torso", joint="C", axis=[compound_screw((1, 0, 0), slide=True), compound_screw((0, 0, 1), slide=True),
                                          compound_screw((0, 1, 0), point=(0, 0, 0.1))], inertia=inert,
               armature=(0.0, 0.0, 0.3))
    b.add_link("thigh", parent="torso", joint="R", axis=(0, 1, 0), origin=np.eye(4), inertia=inert)
    return b.build()


def test_compound_principle_1_is_the_common_kernel():
    robot = _planar()
    assert robot.jtype == ("C", "R") and robot.dof == 4 and robot.ndofs.tolist() == [3, 1]
    assert robot.armature.tolist() == [0, 0, 0.3, 0]
    res = drng(robot, extended=False)
    p1 = res.columns.subset(res.columns.principle == 0)
    c_cols = p1.subset(p1.joint == 0)
    # slide x, slide z, hinge y: only the y direction is fixed by every screw -> sym(y, y)
    assert len(c_cols) == 1
    assert np.allclose(c_cols.h[0] / np.linalg.norm(c_cols.h[0]),
                       __import__("baseparams").model.inertia.hat(np.diag([0, 1.0, 0, 0])).ravel() / 1.0)


def test_compound_at_re_references_exactly():
    from baseparams.kinematics import forward_kinematics

    rng = np.random.default_rng(7)
    robot = random_robot(rng, 4, joint_types="C")
    q0 = rng.uniform(-1, 1, robot.dof)
    moved = re_reference(robot, q0)
    q = rng.uniform(-1, 1, robot.dof)
    g_old = forward_kinematics(robot, q).g[0] @ robot.M0
    g_new = forward_kinematics(moved, q - q0).g[0] @ moved.M0
    assert np.allclose(g_old, g_new, atol=1e-10)


def test_compound_axes_are_checked():
    b = RobotBuilder("bad")
    b.add_link("a", joint="C", axis=[[0, 0, 2.0, 0, 0, 0]])
    with pytest.raises(ModelError, match="not a unit rotation"):
        b.build()
    b = RobotBuilder("bad")
    b.add_link("a", joint="C", axis=[[0, 0, 0, 0, 0, 0.5]])
    with pytest.raises(ModelError, match="neither a unit rotation nor a unit translation"):
        b.build()
