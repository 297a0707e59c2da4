"""Compound (C) joints: several elementary screws in one body (MJCF bodies with several joints)."""

from __future__ import annotations

import numpy as np
import pytest

from baseparams.enums import Source
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


# ---------------------------------------------------------------- R-C: compound joints as chains (issue 39)
def _without_rc(monkeypatch):
    """R-C taken out: the compound joints' directions left to the numerics."""
    from baseparams.nullspace import compound
    from baseparams.nullspace.columns import Columns

    monkeypatch.setattr(compound, "compound_columns", lambda *a, **k: Columns.empty())


def _planar_robot(rng):
    """A planar robot as gymnasium and dm_control write them: a root of two slides and a hinge about the
    plane's normal (random order, anchor off the body origin), a tree of hinges parallel to it (anchors off
    their bodies' origins, two legs sometimes), random inertias; gravity in the plane, along the normal,
    oblique or zero."""
    from baseparams.robots.random import random_inertia, random_rotation

    rot = random_rotation(rng) if rng.random() < 0.5 else np.eye(3)
    n, e1 = rot[:, 1], rot[:, 0]
    e2 = np.cross(e1, n)
    screws = [compound_screw(e1, slide=True), compound_screw(e2, slide=True),
              compound_screw(n, point=rng.uniform(-0.3, 0.3, 3) * (1 - np.abs(n)))]
    order = rng.permutation(3) if rng.random() < 0.5 else [0, 1, 2]
    gravity = [-9.81 * e2, 9.81 * n, rng.normal(size=3) * 5, np.zeros(3)][int(rng.integers(4))]
    b = RobotBuilder("planar", gravity=gravity)
    b.add_link("torso", joint="C", axis=[screws[k] for k in order], inertia=random_inertia(rng),
               origin=np.r_[np.c_[np.eye(3), rng.uniform(-1, 1, 3)], [[0, 0, 0, 1]]])
    for leg in range(int(rng.integers(1, 3))):
        parent = "torso"
        for k in range(int(rng.integers(1, 4))):
            t = np.eye(4)
            t[:3, 3] = rng.uniform(-0.4, 0.4, 3) * (1 - np.abs(n))  # in the plane: the bodies stay in it
            name = f"leg{leg}_{k}"
            b.add_link(name, parent=parent, joint="R", axis=n * (1 if rng.random() < 0.5 else -1), origin=t,
                       inertia=random_inertia(rng))
            parent = name
    return b.build()


@pytest.mark.parametrize("seed", range(16))
def test_rc_completes_planar_robots_on_a_slide_slide_hinge_root(seed):
    robot = _planar_robot(np.random.default_rng(300 + seed))
    res = drng(robot)
    c = certify(robot, result=res, seed=seed)
    assert c.status == "certified" and c.completed == 0, c.message
    assert c.nullity == numerical_nullspace(robot, seed=seed + 1).nullity
    b = res.dense()
    rc = b[:, res.columns.principle == Source.R_C]
    w = stacked_regressor(robot, 60, seed)
    assert rc.shape[1] and np.abs(w @ (rc / np.linalg.norm(rc, axis=0))).max() < 1e-10 * np.linalg.norm(w, 2)


def test_rc_is_needed_on_planar_robots(monkeypatch):
    """Without R-C, the planar robots' out-of-plane and transfer directions are left to the numerics."""
    robots = [_planar_robot(np.random.default_rng(300 + seed)) for seed in range(16)]
    _without_rc(monkeypatch)
    left = [certify(r, seed=0).completed for r in robots]
    assert sum(k > 0 for k in left) >= 12 and all(certify(r, seed=0).certified for r in robots[:3])


@pytest.mark.parametrize("seed", range(40))
def test_rc_completes_random_compound_robots(seed):
    """Random compound joints (two to four random slides and hinges, random anchors, with R, P, U joints;
    fixed or floating, gravity along z, zero or random): DRNG complete, certified."""
    rng = np.random.default_rng(5000 + seed)
    types = ["C", "RC", "CPU", "RPC", "CR"][seed % 5]
    gravity = [(0, 0, -9.81), (0, 0, 0), tuple(rng.normal(size=3))][seed % 3]
    robot = random_robot(rng, int(rng.integers(2, 6)), joint_types=types, floating=seed % 7 == 0, gravity=gravity)
    c = certify(robot, seed=seed)
    assert c.status == "certified" and c.completed == 0, c.message


def test_rc_is_needed_on_random_compound_robots(monkeypatch):
    _without_rc(monkeypatch)
    left = 0
    for seed in range(40):
        rng = np.random.default_rng(5000 + seed)
        types = ["C", "RC", "CPU", "RPC", "CR"][seed % 5]
        gravity = [(0, 0, -9.81), (0, 0, 0), tuple(rng.normal(size=3))][seed % 3]
        robot = random_robot(rng, int(rng.integers(2, 6)), joint_types=types, floating=seed % 7 == 0,
                             gravity=gravity)
        left += certify(robot, seed=seed).completed > 0
    assert left >= 4


def test_expanded_chain_has_the_robots_regressor():
    """The chain R-C reasons on (one elementary joint per body, massless links between) has the robot's own
    regressor on the real bodies' columns and none on the massless links."""
    from baseparams.nullspace.compound import expand_compound

    rng = np.random.default_rng(11)
    robot = random_robot(rng, 5, joint_types="RCP", floating=True, gravity=(0, 0, -9.81))
    chain, index, virtual = expand_compound(robot)
    assert chain.n == robot.n + len(virtual) and chain.dof == robot.dof and set(chain.jtype) <= {"R", "P", "F"}
    q, dq, ddq = rng.uniform(-2, 2, (3, 6, robot.dof))
    y, yc = regressor(robot, q, dq, ddq), regressor(chain, q, dq, ddq).reshape(6, -1, chain.n, 10)
    np.testing.assert_allclose(yc[:, :, index].reshape(y.shape), y, atol=1e-10 * np.abs(y).max())
    assert np.allclose(chain.N_body[virtual], 0)
