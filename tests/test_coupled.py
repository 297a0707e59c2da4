"""R-M (``nullspace/coupled.py``): the directions joint couplings (``<mimic>``) add, checked against
the numerical nullspace (the independent judge) on random hands whose fingers move in lockstep."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from baseparams.enums import Source
from baseparams.model import RobotBuilder
from baseparams.model.robot import Coupling
from baseparams.nullspace import drng
from baseparams.nullspace.certify import certify
from baseparams.nullspace.columns import Columns, to_dense
from baseparams.nullspace.coupled import coupled_columns, coupled_coordinates, coupled_groups, sample_values
from baseparams.numerics import stacked_regressor
from baseparams.robots import random_robot
from baseparams.robots.random import random_inertia, random_rotation

RATIOS = (1.0, -1.0, 2.0, -0.5)


def _origin(rng, keep_axes: bool) -> np.ndarray:
    t = np.eye(4)
    if not keep_axes:
        t[:3, :3] = random_rotation(rng)
    t[:3, 3] = rng.normal(scale=0.1, size=3)
    return t


def mimic_hand(rng, offsets: bool = False, prismatic: float = 0.3):
    """A random arm (fixed, or floating) carrying a hand of 2-3 fingers of 1-2 links on R or P
    joints, every finger joint coupled to the first one or to an earlier follower (chains of
    mimics), with axes often parallel (lockstep fingers) and ratios from :data:`RATIOS`."""
    b = RobotBuilder("hand", gravity=(0.0, 0.0, -9.81) if rng.random() < 0.8 else (0.0, 0.0, 0.0))
    parent, floating = None, rng.random() < 0.3
    for i in range(int(rng.integers(0, 3)) + (1 if floating else 0)):
        jt = "F" if floating and i == 0 else "R"
        b.add_link(f"arm{i}", parent=parent, joint=jt, origin=_origin(rng, False), axis=rng.normal(size=3),
                   inertia=random_inertia(rng))
        parent = f"arm{i}"
    axis = rng.normal(size=3)
    finger_links = []
    for f in range(int(rng.integers(2, 4))):
        up = parent
        for k in range(int(rng.integers(1, 3))):
            keep = rng.random() < 0.7
            jt = "P" if rng.random() < prismatic else "R"
            name = f"f{f}l{k}"
            b.add_link(name, parent=up, joint=jt, origin=_origin(rng, keep),
                       axis=axis if keep else rng.normal(size=3), inertia=random_inertia(rng))
            finger_links.append(name)
            up = name
    robot = b.build()
    qi = [int(robot.q_index[robot.names.index(nm)]) for nm in finger_links]
    couplings = []
    for j in range(1, len(qi)):
        pred = qi[0] if rng.random() < 0.6 else qi[int(rng.integers(0, j))]
        off = float(rng.uniform(-0.3, 0.3)) if offsets and rng.random() < 0.5 else 0.0
        couplings.append(Coupling(f"mimic{j}", pred, qi[j], float(rng.choice(RATIOS)), off))
    independent = tuple(k for k in range(robot.dof) if k not in qi[1:])
    return replace(robot, couplings=tuple(couplings), independent=independent,
                   q_box=np.tile([-3.0, 3.0], (len(independent), 1)))


def test_coupled_coordinates_compose_chains_and_skip_multi_term_couplings():
    robot = random_robot(np.random.default_rng(0), n=5, joint_types="R", branching=0.0)
    cs = (Coupling("a", 0, 2, 2.0, 0.1), Coupling("b", 2, 3, -0.5, 0.2), Coupling("c", 1, 4, 1.0, more=((0, 1.0),)))
    robot = replace(robot, couplings=cs, independent=(0, 1))
    lead, ratio, offset = coupled_coordinates(robot)
    assert list(lead) == [0, 1, 0, 0, -1]
    assert np.allclose(ratio[:4], [1, 1, 2, -1]) and np.allclose(offset[:4], [0, 0, 0.1, -0.5 * 0.1 + 0.2])
    # the chain b0-b1-b2-b3-b4: b2 and b3 (one group) hang from b1; b0 alone under the world is a
    # plain tree joint; b4 is not grouped
    assert coupled_groups(robot) == [(1, [2, 3])]


def test_sample_values_determine_the_conditions():
    """N = 2K + 1 equally spaced values in each of D + 1 periods: a combination of q^a cos(k f0 q),
    q^a sin(k f0 q) (a <= D, k <= K) vanishing there vanishes identically (full column rank)."""
    b = RobotBuilder("chain")
    b.add_link("a", joint="R", axis=(0, 0, 1))
    b.add_link("b", parent="a", joint="R", axis=(0, 1, 0))
    b.add_link("c", parent="b", joint="P", axis=(1, 0, 0))
    robot = replace(b.build(), couplings=(Coupling("m1", 0, 1, 1.5), Coupling("m2", 0, 2, -0.5)), independent=(0,))
    _, ratio, _ = coupled_coordinates(robot)
    q = sample_values(robot, [0, 1, 2], ratio)
    f0, k, d = 0.5, 10, 2  # rates 1 and 1.5: f0 = 1/2, K = 2 (1 + 1.5) / f0; one slide: D = 2
    assert len(q) == (2 * k + 1) * (d + 1)
    u = q / np.abs(q).max()
    cols = [u**a * f(j * f0 * q) for a in range(d + 1) for j in range(k + 1) for f in (np.cos, np.sin)
            if j or f is np.cos]
    assert np.linalg.matrix_rank(np.array(cols).T) == len(cols)
    # an irrational rate has no common period: the group is skipped, not guessed
    robot = replace(robot, couplings=(Coupling("m1", 0, 1, np.sqrt(2)),), independent=(0, 2))
    assert sample_values(robot, [0, 1], coupled_coordinates(robot)[1]) is None


def test_no_couplings_no_columns():
    robot = random_robot(np.random.default_rng(1), n=6, joint_types="RP")
    assert len(coupled_columns(robot)) == 0
    assert drng(robot).by_principle()[Source.R_M.label] == 0


@pytest.mark.parametrize("seed", range(40))
def test_random_mimic_hands_complete_geometrically(seed):
    """DRNG alone (R-M included) is complete and certified: its rank equals the numerical nullity,
    nothing is completed numerically, and every R-M column is in the numerical nullspace."""
    robot = mimic_hand(np.random.default_rng(seed), offsets=seed % 4 == 3)
    res = drng(robot)
    cert = certify(robot, seed=seed, result=res)
    assert cert.certified, cert.message
    assert cert.completed == 0
    rm = res.columns.subset(res.columns.principle == Source.R_M)
    if len(rm):
        w = stacked_regressor(robot, 120, seed + 100)
        b = to_dense(rm, robot.n)
        b /= np.linalg.norm(b, axis=0)
        assert np.max(np.linalg.norm(w @ b, axis=0)) < 1e-9 * np.linalg.norm(w, 2)


@pytest.mark.parametrize("seed", [34, 87, 206, 221])
def test_mimic_offsets_are_sampled_from_the_coupled_reference(seed):
    """Couplings with offsets: at q = 0 the driven joints sit at their offsets, not at 0. The
    samples start from that reference (it was taken for a singular loop reference: a refusal
    naming parallelograms, on a plain mimic chain)."""
    robot = mimic_hand(np.random.default_rng(seed), offsets=True)
    assert any(c.offset != 0 for c in robot.couplings)
    cert = certify(robot, result=drng(robot))
    assert cert.certified and cert.completed == 0, cert.message


def test_a_rank_decided_by_its_gap():
    """A five-body group (zero gravity, ratios 1, -0.5, 0.5) whose conditions have singular values
    at 3e-6 .. 5e-5 of the largest above its 35 zeros (~1e-17): the rank is decided by the gap
    (GAP times the largest zero), not by a fixed window, so the group is solved (11 directions
    that were completed numerically)."""
    robot = mimic_hand(np.random.default_rng(119), offsets=False)
    res = drng(robot)
    cert = certify(robot, result=res)
    assert cert.certified and cert.completed == 0, cert.message
    assert res.by_principle()["R-M coupled joints"] == 11


def test_mimic_hands_need_the_rule():
    """Without R-M the same hands are incomplete: the rule closes a real gap (lockstep fingers)."""
    gaps = 0
    for seed in range(12):
        robot = mimic_hand(np.random.default_rng(seed))
        full = drng(robot).rank
        without = full - drng(robot).by_principle()[Source.R_M.label]
        gaps += full > without
    assert gaps >= 6


def test_parallel_lockstep_fingers_share_rotational_inertia():
    """Two fingers on parallel R axes with ratio 1, on a freely moving hand: the six direction
    parameters (rotational inertia about the centre) transfer between them (same orientation
    always), beyond what the principles find; certified."""
    b = RobotBuilder("two", gravity=(0, 0, -9.81))
    b.add_link("hand", joint="F", inertia=random_inertia(np.random.default_rng(0)))
    for k, x in enumerate((0.05, -0.05)):
        t = np.eye(4)
        t[:3, 3] = (x, 0.0, 0.1)
        b.add_link(f"finger{k}", parent="hand", joint="R", origin=t, axis=(0, 1, 0),
                   inertia=random_inertia(np.random.default_rng(k + 1)))
    robot = b.build()
    robot = replace(robot, couplings=(Coupling("mimic", 6, 7, 1.0),), independent=tuple(range(7)),
                    q_box=np.tile([-0.8, 0.8], (7, 1)))
    res = drng(robot)
    assert res.by_principle()[Source.R_M.label] >= 5
    cert = certify(robot, seed=0, result=res)
    assert cert.certified and cert.completed == 0
    assert "coupled group on hand" in res.provenance(int(np.flatnonzero(res.columns.principle == Source.R_M)[0]))


def test_wide_columns_rank_and_expand_consistently():
    """Columns with blocks on further bodies (``Columns.more``, R-M's widest): the O(n) block rank
    equals the dense rank, with dependent columns among them, and the scaled copy keeps it."""
    from baseparams.nullspace.columns import Columns
    from baseparams.nullspace.rank import block_rank

    rng = np.random.default_rng(5)
    n, k = 9, 7
    h, hp, he = rng.normal(size=(3, k, 10))
    more = np.array([(np.array([2, 0]), rng.normal(size=(2, 10))) for _ in range(k)] + [None], dtype=object)[:-1]
    z = np.zeros(k, dtype=int)
    wide = Columns(h, z + 8, z + 6, z + int(Source.R_M), z + 8, np.full(k, "", dtype=object), hp=hp,
                   extra=z + 4, he=he, more=more)
    # three more columns: combinations of the first three (dependent), and one narrow column
    c = rng.normal(size=(3, 3))
    dep = Columns(c @ h[:3], z[:3] + 8, z[:3] + 6, z[:3], z[:3] + 8, np.full(3, "", dtype=object), hp=c @ hp[:3],
                  extra=z[:3] + 4, he=c @ he[:3],
                  more=np.array([(np.array([2, 0]), np.einsum("j,jab->ab", c[i], np.stack([m[1] for m in more[:3]])))
                                 for i in range(3)] + [None], dtype=object)[:-1])
    narrow = Columns(rng.normal(size=(1, 10)), np.array([3]), np.array([-1]), np.array([0]), np.array([3]),
                     np.array([""], dtype=object))
    cols = Columns.concat([wide, dep, narrow])
    dense = to_dense(cols, n)
    assert cols.has_more().sum() == k + 3
    assert np.allclose(dense[[20, 0], 0], [more[0][1][0, 0], more[0][1][1, 0]])  # body 2's XX, body 0's XX
    assert block_rank(cols, n) == np.linalg.matrix_rank(dense) == k + 1
    assert block_rank(cols.scaled(np.linspace(1, 2, 10)), n) == k + 1


@pytest.mark.parametrize("s", [1e-3, 1e3])
def test_rule_does_not_depend_on_the_unit_of_length(s):
    """The same hands drawn with every length times 1e-3 or 1e3 (revolute fingers: a change of
    unit changes nothing else): R-M finds the same number of directions and DRNG stays complete."""
    from test_regroup_scale import scaled

    for seed in range(6):
        robot = mimic_hand(np.random.default_rng(seed), offsets=seed % 2 == 1, prismatic=0.0)
        big = scaled(robot, s)
        ref, res = drng(robot), drng(big)
        assert res.rank == ref.rank
        assert res.by_principle()[Source.R_M.label] == ref.by_principle()[Source.R_M.label]
        cert = certify(big, seed=seed, result=res)
        assert cert.certified and cert.completed == 0, cert.message


GRIPPER_MJCF = """<mujoco model="gripper">
  <worldbody>
    <body name="arm" pos="0 0 0.5">
      <joint name="a1" type="hinge" axis="0 0 1"/>
      <inertial pos="0.1 0 0" mass="2" diaginertia="0.01 0.02 0.03"/>
      <body name="hand" pos="0.3 0 0">
        <joint name="a2" type="hinge" axis="0 1 0"/>
        <inertial pos="0.05 0.01 0" mass="1" diaginertia="0.004 0.003 0.002"/>
        <body name="left" pos="0.1 0.03 0">
          <joint name="fl" type="slide" axis="0 1 0"/>
          <inertial pos="0.02 0 0.01" mass="0.1" diaginertia="0.0002 0.0003 0.0001"/>
        </body>
        <body name="right" pos="0.1 -0.03 0">
          <joint name="fr" type="slide" axis="0 -1 0"/>
          <inertial pos="0.02 0 -0.01" mass="0.12" diaginertia="0.0002 0.0001 0.0003"/>
        </body>
      </body>
    </body>
  </worldbody>
  <equality>
    <joint name="mimic" joint1="fr" joint2="fl" polycoef="0 1 0 0 0"/>
  </equality>
</mujoco>"""


def test_mjcf_equality_joint_gripper_completes_geometrically(tmp_path):
    """An MJCF parallel gripper whose fingers slide in opposite directions tied by
    ``<equality><joint polycoef>``: R-M finds the three first-moment directions (each finger's
    ``b``, ``-2 b`` on the hand) that were completed numerically; the certified nullity is the
    numerical method's."""
    from baseparams.loading import load_model

    path = tmp_path / "gripper.xml"
    path.write_text(GRIPPER_MJCF)
    robot, _ = load_model(str(path))
    assert len(robot.couplings) == 1
    res = drng(robot)
    cert = certify(robot, seed=0, result=res)
    assert cert.certified and cert.completed == 0, cert.message
    assert cert.nullity == 27 and res.by_principle()[Source.R_M.label] == 3


MIMIC_ARM = """<?xml version="1.0"?>
<robot name="mimic_arm">
  <link name="base"/>
  <link name="upper"><inertial><mass value="2"/><origin xyz="0.2 0 0"/>
    <inertia ixx="0.01" iyy="0.05" izz="0.05" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="lower"><inertial><mass value="1"/><origin xyz="0.15 0 0"/>
    <inertia ixx="0.01" iyy="0.03" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="finger_a"><inertial><mass value="0.1"/><origin xyz="0.02 0.01 0"/>
    <inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="finger_b"><inertial><mass value="0.1"/><origin xyz="0.02 -0.01 0"/>
    <inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" velocity="2" effort="50"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="lower"/><origin xyz="0.4 0 0"/>
    <axis xyz="0 1 0"/><limit lower="0.3" upper="2.5" velocity="2" effort="30"/></joint>
  <joint name="grip_a" type="prismatic"><parent link="lower"/><child link="finger_a"/><origin xyz="0.3 0 0"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" velocity="0.2" effort="20"/></joint>
  <joint name="grip_b" type="prismatic"><parent link="lower"/><child link="finger_b"/><origin xyz="0.3 0 0"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="0.04" velocity="0.2" effort="20"/>
    <mimic joint="grip_a" multiplier="1" offset="0"/></joint>
</robot>
"""


def test_a_mimic_only_robot_is_not_described_with_loop_words(tmp_path, capsys):
    """A gripper's <mimic> (no loop joint): the reports say coupled joints, never loops; ``excite`` designs it
    although q = 0 is outside the elbow's range (a loop robot's reference must be inside; a linear coupling
    holds anywhere), and the fingers are excited (offsets inside the finger's range, not at its edge)."""
    from baseparams.cli import main

    urdf = tmp_path / "mimic_arm.urdf"
    urdf.write_text(MIMIC_ARM)
    assert main(["analyze", str(urdf)]) == 0
    out = capsys.readouterr().out
    assert "1 coupled joints (linear couplings), 3 actuated" in out and "coupled joints: " in out
    assert "loop joints" not in out and "loop sampling" not in out and "loop residual" not in out
    assert main(["excite", str(urdf), "--starts", "1", "--harmonics", "3", "--grid", "60", "--rate", "100"]) == 0
    out = capsys.readouterr().out
    assert "coupled joints: designed in the actuated coordinates" in out and "loop" not in out.lower()
    assert main(["simulate", str(urdf), str(tmp_path / "log.csv"), "--duration", "2"]) == 0
    out = capsys.readouterr().out
    assert "coupled joints' sampling box" in out and "loops" not in out


# ---------------------------------------------------------------- polynomial couplings (MJCF polycoef; issue 39)
def poly_hand(seed: int):
    """:func:`mimic_hand` with most couplings made polynomial (terms in q^2 and q^3 of the leader)."""
    rng = np.random.default_rng(seed)
    robot = mimic_hand(rng, offsets=True)
    cs = []
    for c in robot.couplings:
        k = int(rng.integers(0, 3))
        poly = tuple(float(x) for x in rng.normal(scale=0.2, size=k)) if rng.random() < 0.7 else ()
        cs.append(replace(c, poly=poly))
    return replace(robot, couplings=tuple(cs))


def _without_sampled_rm(monkeypatch):
    from baseparams.nullspace import coupled

    orig = coupled.group_nullspace

    def linear_only(robot, anchor, bodies, *a, **k):
        _, coef = coupled.coupled_polynomials(robot, k.get("extra", ()))
        return None if np.any(coef[robot.q_index[bodies], 2:]) else orig(robot, anchor, bodies, *a, **k)

    monkeypatch.setattr(coupled, "group_nullspace", linear_only)


def test_closed_states_follow_polynomial_couplings_exactly():
    """Positions on the polynomial, and velocities and accelerations its exact derivatives along a motion."""
    from baseparams.kinematics.loops import close_loops

    robot = poly_hand(3)
    assert any(c.poly for c in robot.couplings)
    t = np.linspace(0.0, 1.0, 2001)
    na = len(robot.actuated)
    w = np.random.default_rng(0).uniform(0.5, 1.5, na)
    qa, dqa, ddqa = np.sin(np.outer(t, w)), np.cos(np.outer(t, w)) * w, -np.sin(np.outer(t, w)) * w ** 2
    cs = close_loops(robot, qa, dqa, ddqa, cond_max=np.inf)
    assert cs.kept == len(t)
    for c in robot.couplings:
        x = cs.q[:, c.pred]
        np.testing.assert_allclose(cs.q[:, c.succ], np.polynomial.polynomial.polyval(x, c.coefficients()), atol=1e-12)
    h = t[1] - t[0]
    np.testing.assert_allclose(np.gradient(cs.q, h, axis=0)[5:-5], cs.dq[5:-5], atol=1e-5)
    np.testing.assert_allclose(np.gradient(cs.dq, h, axis=0)[5:-5], cs.ddq[5:-5], atol=1e-4)


def test_re_referencing_shifts_a_polynomial_coupling_exactly():
    from baseparams.kinematics import re_reference
    from baseparams.kinematics.loops import close_loops

    robot = poly_hand(3)
    rng = np.random.default_rng(1)
    q0 = close_loops(robot, rng.uniform(-0.5, 0.5, (1, len(robot.actuated))), cond_max=np.inf).q[0]
    moved = re_reference(robot, q0)
    qa = rng.uniform(-1, 1, (20, len(robot.actuated)))
    old = close_loops(robot, qa, cond_max=np.inf).q
    new = close_loops(moved, qa - q0[robot.actuated], cond_max=np.inf).q
    np.testing.assert_allclose(new + q0, old, atol=1e-10)


@pytest.mark.parametrize("seed", range(20))
def test_polynomial_couplings_complete_and_certified(seed):
    """R-M on polynomially coupled groups: the conditions sampled (not proven: analytic, not trigonometric
    polynomials) at generic values, a solution kept only when twice as many values keep it; certified by the
    independent check, nothing completed numerically."""
    c = certify(poly_hand(seed), seed=0)
    assert c.status == "certified" and c.completed == 0, c.message


@pytest.mark.slow
def test_sampled_rm_is_needed_on_polynomial_couplings(monkeypatch):
    _without_sampled_rm(monkeypatch)
    left = [certify(poly_hand(seed), seed=0).completed for seed in range(20)]
    assert sum(k > 0 for k in left) >= 4


#: a knee as OpenSim-converted MJCF writes it (MyoSuite): the tibia and the patella on slides and a hinge
#: whose coordinates are polynomials of the knee angle (joint equalities with a nonlinear polycoef)
KNEE = """<mujoco model="knee">
  <compiler angle="radian" inertiafromgeom="false"/>
  <worldbody>
    <body name="femur" pos="0 0 1">
      <joint name="hip" type="hinge" axis="0 1 0" range="-1 1"/>
      <inertial pos="0 0 -0.2" mass="5" diaginertia="0.1 0.1 0.02"/>
      <body name="tibia" pos="0 0 -0.4">
        <joint name="knee_tx" type="slide" axis="1 0 0"/>
        <joint name="knee_tz" type="slide" axis="0 0 1"/>
        <joint name="knee" type="hinge" axis="0 1 0" range="-2 0.1"/>
        <inertial pos="0.01 0.02 -0.2" mass="3" diaginertia="0.05 0.06 0.01"/>
        <body name="foot" pos="0 0 -0.4">
          <joint name="ankle" type="hinge" axis="0 1 0"/>
          <inertial pos="0.05 0 -0.03" mass="1" diaginertia="0.01 0.01 0.005"/>
        </body>
      </body>
      <body name="patella" pos="0.05 0 -0.38" euler="0.1 0 0">
        <joint name="pat_tx" type="slide" axis="1 0 0"/>
        <joint name="pat_tz" type="slide" axis="0 0 1"/>
        <joint name="pat_r" type="hinge" axis="0 1 0"/>
        <inertial pos="0.005 0.001 0.002" mass="0.1" diaginertia="1e-4 1e-4 5e-5"/>
      </body>
    </body>
  </worldbody>
  <equality>
    <joint joint1="knee_tx" joint2="knee" polycoef="0 -0.004 0.0033 -0.0012 0.0002"/>
    <joint joint1="knee_tz" joint2="knee" polycoef="0 0.002 -0.0051 0.0011 0"/>
    <joint joint1="pat_tx" joint2="knee" polycoef="0 0.02 -0.01 0.003 0"/>
    <joint joint1="pat_tz" joint2="knee" polycoef="0 0.015 0.008 0 0"/>
    <joint joint1="pat_r" joint2="knee" polycoef="0 0.3 -0.05 0.01 0"/>
  </equality>
</mujoco>
"""


def test_mjcf_knee_with_polynomial_couplings_is_mujocos(tmp_path):
    """The joint equalities are read as polynomial couplings (were refused); the certified count equals the rank
    of MuJoCo's own inverse dynamics on its constraint manifold; DRNG complete."""
    import warnings

    import baseparams as bp

    from mujoco_oracle import mujoco_rank

    path = tmp_path / "knee.xml"
    path.write_text(KNEE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = bp.load(str(path))
    assert sum(bool(c.poly) for c in robot.couplings) == 5
    a = bp.analyze(robot)
    assert a.status == "certified" and a.certificate.completed == 0
    rank, gap = mujoco_rank(path)
    assert gap > 1e6 and a.n_base == rank == 19


# ---------------------------------------------------------------- couplings with several drivers (a tendon; issue 39)
def tendon_leg(seed):
    """A leg (on the world or a floating torso): a universal hip whose second axis is often parallel to the
    knee's and the ankle's, its pitch tied to them by a tendon ``pitch = r1 knee + r2 ankle`` (dm_control's
    quadruped: ``-knee - ankle``, the foot keeping the hip's pitch)."""
    rng = np.random.default_rng(seed)
    b = RobotBuilder("leg", gravity=(0, 0, -9.81) if rng.random() < 0.8 else (0, 0, 0))
    par = "torso" if rng.random() < 0.5 else None
    if par:
        b.add_link("torso", joint="F", inertia=random_inertia(rng))
    axis = rng.normal(size=3)
    keep = rng.random() < 0.7
    a1 = rng.normal(size=3)
    a1 -= (a1 @ axis) / (axis @ axis) * axis
    b.add_link("thigh", parent=par, joint="U", origin=_origin(rng, False), axis=a1, axis2=axis,
               inertia=random_inertia(rng))
    for name, up in (("shin", "thigh"), ("foot", "shin")):
        b.add_link(name, parent=up, joint="R", origin=_origin(rng, keep), axis=axis if keep else rng.normal(size=3),
                   inertia=random_inertia(rng))
    r = b.build()
    k0 = 6 if par else 0
    pitch, knee, ankle = k0 + 1, k0 + 2, k0 + 3
    ratios = (-1.0, -1.0) if rng.random() < 0.6 else tuple(float(x) for x in rng.choice([-1, 0.5, 2, -0.5], 2))
    c = Coupling("tendon", knee, pitch, ratios[0], 0.0, more=((ankle, ratios[1]),))
    ind = tuple(k for k in range(r.dof) if k != pitch)
    return replace(r, couplings=(c,), independent=ind,
                   q_box=None if par else np.tile([-1.0, 1.0], (len(ind), 1)))


@pytest.mark.parametrize("seed", range(12))
def test_groups_driven_by_several_coordinates_complete_and_certified(seed):
    c = certify(tendon_leg(seed), seed=0)
    assert c.status == "certified" and c.completed == 0, c.message


def test_several_drivers_are_needed(monkeypatch):
    """Without R-M's groups driven by several coordinates: dm_control's quadruped (4 directions) and about half
    of the random legs are left to the numerics."""
    import importlib.util
    import warnings
    from pathlib import Path

    from baseparams.loading import load_model
    from baseparams.nullspace import coupled

    spec = importlib.util.find_spec("dm_control")
    path = Path(spec.origin).parent / "suite" / "quadruped.xml"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot, _ = load_model(str(path))
    assert len(coupled.multi_groups(robot)) == 4 and certify(robot, seed=0).completed == 0
    monkeypatch.setattr(coupled, "multi_group_columns", lambda *a, **k: Columns.empty())
    assert certify(robot, seed=0).completed == 4
    assert sum(certify(tendon_leg(s), seed=0).completed > 0 for s in range(12)) >= 3
