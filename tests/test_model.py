"""Robot model validation, builder, and parameter conventions."""

import numpy as np
import pytest

from baseparams.errors import ModelError
from baseparams.model import Inertia, Robot, RobotBuilder, pose
from baseparams.model import inertia as I
from baseparams.regressor import regressor
from baseparams.robots import puma560, random_robot
from baseparams.robots.random import random_inertia


def _robot(**kw):
    base = dict(name="t", names=("a", "b"), joint_names=("ja", "jb"), jtype=("R", "R"),
                parent=np.array([-1, 0]), M0=np.stack([np.eye(4)] * 2),
                axes=(np.array([[0, 0, 1.0]]), np.array([[0, 1.0, 0]])), N_body=np.zeros((2, 4, 4)))
    base.update(kw)
    return Robot(**base)


@pytest.mark.parametrize("kw, match", [
    (dict(jtype=("R", "Q")), "body 'b' .*unknown joint type 'Q'"),
    (dict(parent=np.array([-1, 1])), "body 'b' .*parent index 1 must come before"),
    (dict(axes=(np.array([[0, 0, 0.0]]), np.array([[0, 1.0, 0]]))), "body 'a' .*zero joint axis"),
    (dict(axes=(np.array([[0, 0, 2.0]]), np.array([[0, 1.0, 0]]))), "body 'a' .*not a unit vector"),
    (dict(M0=np.stack([np.eye(4), np.diag([2.0, 1, 1, 1])])), "body 'b' .*not rigid"),
    (dict(M0=np.stack([np.eye(4), np.full((4, 4), np.nan)])), "body 'b' .*NaN"),
    (dict(M0=np.eye(4)), "M0 must have shape"),
    (dict(names=("a", "a")), "duplicate body name 'a'"),
    (dict(jtype=("R", "F")), "body 'b' .*floating .* must connect the fixed base"),
    (dict(N_body=np.stack([np.zeros((4, 4)), np.diag([0, 0, 0, np.nan])])), "body 'b' .*finite symmetric"),
    (dict(gravity=np.array([0, 0, np.inf])), "gravity must be 3 finite numbers"),
    (dict(jtype=("U", "R")), "body 'a' .*needs 2 axis"),
])
def test_validation_errors_name_the_body(kw, match):
    with pytest.raises(ModelError, match=match):
        _robot(**kw)


def test_builder_errors():
    b = RobotBuilder("x")
    with pytest.raises(ModelError, match="unknown parent link 'nope'"):
        b.add_link("a", parent="nope")
    with pytest.raises(ModelError, match="unknown joint type 'helical'"):
        b.add_link("a", joint="helical")
    with pytest.raises(ModelError, match="zero joint axis"):
        b.add_link("a", axis=(0, 0, 0))
    with pytest.raises(ModelError, match="universal joint needs axis2"):
        b.add_link("a", joint="U")
    b.add_link("a")
    with pytest.raises(ModelError, match="duplicate link name 'a'"):
        b.add_link("a")
    with pytest.raises(ModelError, match="no moving links"):
        RobotBuilder("empty").build()


def test_fixed_joint_merges_inertia_exactly(rng):
    """A link on a fixed joint behaves as a P-jointed link held still (same torques)."""
    for seed in range(5):
        r = np.random.default_rng(seed)
        poses = [pose(r.normal(size=3), r.normal(size=3)) for _ in range(3)]
        inert = [random_inertia(r) for _ in range(3)]

        def build(fixed: bool):
            b = RobotBuilder("m")
            b.add_link("a", joint="R", origin=poses[0], axis=(0, 0, 1), inertia=inert[0])
            b.add_link("tool", parent="a", joint="fixed" if fixed else "P", origin=poses[1],
                       axis=(1, 0, 0), inertia=inert[1])
            b.add_link("c", parent="tool", joint="R", origin=poses[2], axis=(0, 1, 0), inertia=inert[2])
            return b.build()

        merged, full = build(True), build(False)
        assert merged.n == 2 and full.n == 3
        q = r.uniform(-1, 1, (5, 2))
        dq, ddq = r.uniform(-1, 1, (2, 5, 2))
        ins = lambda x: np.insert(x, 1, 0.0, axis=1)  # noqa: E731
        t_merged = regressor(merged, q, dq, ddq) @ merged.parameters("paper")
        t_full = regressor(full, ins(q), ins(dq), ins(ddq)) @ full.parameters("paper")
        assert np.allclose(t_merged, np.delete(t_full, 1, axis=1), rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("conv", I.CONVENTIONS)
def test_convention_round_trip(conv, rng):
    n = np.stack([random_inertia(rng).pseudo() for _ in range(4)])
    p = I.to_convention(n, conv)
    assert p.shape == (4, 10)
    assert np.allclose(I.from_convention(p, conv), n)
    for other in I.CONVENTIONS:
        assert np.allclose(I.convert(I.convert(p, conv, other), other, conv), p)


def test_conventions_match_pinocchio_and_named_entries(rng):
    pin = pytest.importorskip("pinocchio")
    inert = random_inertia(rng)
    n = inert.pseudo()
    pi = pin.Inertia(inert.mass, np.asarray(inert.com), inert.inertia_matrix())
    assert np.allclose(I.to_convention(n, "pinocchio"), pi.toDynamicParameters())
    m, h, j = I.split(n)
    kh = I.to_convention(n, "khalil")
    assert np.isclose(kh[0], j[0, 0]) and np.isclose(kh[1], j[0, 1]) and np.isclose(kh[9], m)
    idt = I.to_convention(n, "idyntree")
    assert np.isclose(idt[6], j[0, 2]) and np.isclose(idt[7], j[1, 1])
    rp = I.to_convention(n, "rpna")
    assert np.isclose(rp[5], j[1, 1]) and np.isclose(rp[9], j[0, 1])
    # the paper's N = int [p;1][p;1]^T dm: Sigma = tr(J)/2 - J, h = m c
    assert np.allclose(n[:3, :3], 0.5 * np.trace(j) * np.eye(3) - j)
    assert np.allclose(n[:3, 3], inert.mass * np.asarray(inert.com))
    assert I.is_physically_consistent(n)


def test_parameters_round_trip_through_robot(rng):
    r = random_robot(rng, 5)
    for conv in I.CONVENTIONS:
        p = r.parameters(conv)
        assert p.shape == (50,)
        assert np.allclose(r.with_parameters(p, conv).parameters("paper"), r.parameters("paper"))


def test_inertia_input_forms():
    a = Inertia(1.0, inertia=(1, 2, 3)).inertia_matrix()
    b = Inertia(1.0, inertia=(1, 2, 3, 0, 0, 0)).inertia_matrix()
    assert np.allclose(a, b) and np.allclose(a, np.diag([1, 2, 3]))
    with pytest.raises(ValueError, match="inertia must be"):
        Inertia(1.0, inertia=(1, 2)).inertia_matrix()


def test_puma560_structure():
    r = puma560()
    assert r.n == 6 and r.dof == 6 and r.jtype == ("R",) * 6
    assert list(r.parent) == [-1, 0, 1, 2, 3, 4]
    # joint 2 axis is horizontal (DH alpha1 = pi/2), joints 2 and 3 parallel
    s = r.screws
    assert np.allclose(np.cross(s[1, :3], s[2, :3]), 0)
    assert abs(s[0, :3] @ s[1, :3]) < 1e-12


def test_array_holding_objects_compare_by_identity():
    """Dataclasses that hold arrays use identity equality: ``==`` never raises (numpy's
    elementwise comparison has no truth value) and a copy is a different object."""
    from dataclasses import replace

    from baseparams.nullspace import drng
    from baseparams.robots import puma560

    robot = puma560()
    assert robot == robot and not robot != robot  # noqa: SIM202 (both operators)
    assert replace(robot) != robot
    assert robot in [robot] and len({robot, robot}) == 1
    res = drng(robot)
    assert res == res and res.columns == res.columns and res != drng(robot)
    assert robot.loops == ()
