"""Loops whose reference is singular, and MuJoCo mocap welds (issue 39).

Meta-World's scenes weld the Sawyer's hand to a mocap body (a control device the simulation moves)
with the arm straight at ``qpos0``: the loop is singular there. The weld is actuation, left out by
default (issue 46: the tree); ``mocap_welds="keep"`` / ``--mocap-welds keep`` honours it (a loop to
the world whose anchor may be placed where the hand is), the reference moved to a regular
configuration nearby. The robots are written here.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import baseparams as bp
from baseparams.cli import main
from baseparams.kinematics.loops import close_loops

#: a 6-joint arm standing straight up at qpos0 (joint axes z, y, z, y, z, y: 1, 3, 5 coaxial), its hand
#: welded to a mocap body, two finger slides on the hand; {joints} adds joints
ARM = """<mujoco model="mocap_arm">
  <worldbody>
    <body name="mocap" mocap="true" pos="0 0 1.3"/>
    <body name="base" pos="0 0 0.1">
      <body name="l1" pos="0 0 0.1"><joint name="j1" axis="0 0 1" range="-3 3"/>
        <inertial pos="0 0.01 0.05" mass="2" diaginertia="0.02 0.02 0.01"/>
        <body name="l2" pos="0 0 0.1"><joint name="j2" axis="0 1 0" range="-2 2"/>
          <inertial pos="0.01 0 0.15" mass="2" diaginertia="0.03 0.03 0.01"/>
          <body name="l3" pos="0 0 0.3"><joint name="j3" axis="0 0 1" range="-3 3"/>
            <inertial pos="0 0.01 0.1" mass="1.5" diaginertia="0.02 0.02 0.005"/>
            <body name="l4" pos="0 0 0.2"><joint name="j4" axis="0 1 0" range="-2.5 2.5"/>
              <inertial pos="0.01 0 0.1" mass="1.2" diaginertia="0.01 0.01 0.004"/>
              <body name="l5" pos="0 0 0.2"><joint name="j5" axis="0 0 1" range="-3 3"/>
                <inertial pos="0 0.01 0.05" mass="1" diaginertia="0.008 0.008 0.003"/>
                <body name="hand" pos="0 0 0.1"><joint name="j6" axis="0 1 0" range="-2 2"/>{joints}
                  <inertial pos="0 0.01 0.03" mass="0.5" diaginertia="0.002 0.002 0.001"/>
                  <body name="finger_l" pos="0 0.03 0.05"><joint name="fl" type="slide" axis="0 1 0" range="0 0.04"/>
                    <inertial pos="0.01 0 0.02" mass="0.05" diaginertia="1e-5 2e-5 1e-5"/></body>
                  <body name="finger_r" pos="0 -0.03 0.05"><joint name="fr" type="slide" axis="0 -1 0" range="0 0.04"/>
                    <inertial pos="0.01 0 0.02" mass="0.05" diaginertia="1e-5 2e-5 1e-5"/></body>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <equality><weld body1="mocap" body2="hand" solref="0.02 1"/></equality>
  <actuator><motor joint="j1"/><motor joint="fl"/><motor joint="fr"/></actuator>
</mujoco>
"""
#: the same hand and fingers with the arm rigid: the oracle's robot (two slides on a fixed hand)
HAND = """<mujoco model="hand">
  <worldbody>
    <body name="hand" pos="0.2 0.1 1.1" euler="0.3 0.2 0.1">
      <inertial pos="0 0.01 0.03" mass="0.5" diaginertia="0.002 0.002 0.001"/>
      <body name="finger_l" pos="0 0.03 0.05"><joint name="fl" type="slide" axis="0 1 0"/>
        <inertial pos="0.01 0 0.02" mass="0.05" diaginertia="1e-5 2e-5 1e-5"/></body>
      <body name="finger_r" pos="0 -0.03 0.05"><joint name="fr" type="slide" axis="0 -1 0"/>
        <inertial pos="0.01 0 0.02" mass="0.05" diaginertia="1e-5 2e-5 1e-5"/></body>
    </body>
  </worldbody>
</mujoco>
"""


def _load(path, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = bp.load(str(path), **kw)
    return robot, [str(w.message) for w in caught]


def test_a_mocap_weld_on_a_straight_arm_is_honoured_off_the_singular_reference(tmp_path):
    """Straight at qpos0 the welded arm is singular (constraint Jacobian of rank 3): the mocap anchor is
    placed where the hand is at a regular configuration nearby; the arm is then held still by the weld
    (six joints, six constraints) and only the fingers move: their two masses along the slides."""
    from mujoco_oracle import mujoco_rank

    path = tmp_path / "arm.xml"
    path.write_text(ARM.format(joints=""))
    robot, notes = _load(path, mocap_welds="keep")
    assert any("ties 'hand' to the mocap body 'mocap', a control device" in n and "mocap_welds='keep'" in n
               for n in notes)
    assert any("q = 0 is a singular configuration of the loops (constraint Jacobian of rank 3" in n
               and "re-anchored where the hand is at a regular configuration nearby" in n for n in notes)
    assert [robot.joint_names[robot.dof_body[k]] for k in robot.actuated] == ["fl", "fr"]
    lim = robot.limits[:, :2]  # the new reference is inside every joint range
    assert np.all(lim[:, 0] <= 1e-12) and np.all(lim[:, 1] >= -1e-12)
    a = bp.analyze(robot)
    assert a.status == "certified" and a.certificate.completed == 0
    oracle = tmp_path / "hand.xml"
    oracle.write_text(HAND)
    assert a.n_base == mujoco_rank(oracle)[0] == 2


def test_held_bodies_rule_is_needed(tmp_path, monkeypatch):
    """Without the bodies held still by the weld (and the fingers analysed on a fixed hand), 32 directions are
    left to the numerics."""
    import sys

    from baseparams.nullspace import rules

    drng = sys.modules["baseparams.nullspace.drng"]

    path = tmp_path / "arm.xml"
    path.write_text(ARM.format(joints=""))
    robot, _ = _load(path, mocap_welds="keep")
    assert rules.locked_bodies(robot).tolist() == [True] * 6 + [False] * 2
    monkeypatch.setattr(rules, "locked_body_columns", lambda r: rules.Columns.empty())
    monkeypatch.setattr(drng, "_unlocked", lambda r: None)
    c = bp.analyze(robot).certificate
    assert c.status == "completed" and c.completed == 32


def test_mocap_welds_are_left_out_by_default_and_kept_on_request(tmp_path, capsys):
    """The default reads the tree MuJoCo itself has without the equality; ``keep`` (and the API's keyword) the loop."""
    from mujoco_oracle import mujoco_rank

    path = tmp_path / "arm.xml"
    path.write_text(ARM.format(joints=""))
    robot, notes = _load(path)
    assert not robot.loops and robot.dof == 8
    assert any("ties 'hand' to the mocap body 'mocap', a control device the simulation moves (actuation): left out"
               in n and "--mocap-welds keep" in n for n in notes)
    a = bp.analyze(robot)
    tree = tmp_path / "tree.xml"  # MuJoCo's own tree: the file without its equality
    tree.write_text(ARM.format(joints="").replace('<equality><weld body1="mocap" body2="hand" solref="0.02 1"/>'
                                                   '</equality>', ""))
    assert a.status == "certified" and a.certificate.completed == 0 and a.n_base == mujoco_rank(tree)[0]
    kept, _ = _load(path, mocap_welds="keep")
    assert len(kept.loops) == 1 and kept.loops[0].anchor_free
    for flags in ([], ["--mocap-welds", "drop"], ["--drop-mocap-welds"]):  # the old flag: the default now
        assert main(["analyze", str(path), "--json", *flags]) == 0
        out = capsys.readouterr()
        assert f'"n_base": {a.n_base}' in out.out and "left out" in out.err
        assert "(--mocap-welds keep, keeps it" in out.err and "mocap_welds=" not in out.err, out.err  # the flag once
    assert main(["analyze", str(path), "--json", "--mocap-welds", "keep"]) == 0
    out = capsys.readouterr()
    assert '"n_base": 2' in out.out and "kept as a loop joint to the world (--mocap-welds keep)" in out.err, out.err


def test_mocap_welds_keyword_is_checked(tmp_path, capsys):
    path = tmp_path / "arm.xml"
    path.write_text(ARM.format(joints=""))
    for bad in (True, "yes", None):
        with pytest.raises(bp.BaseparamsError, match="mocap_welds= must be one of drop, keep"):
            bp.load(str(path), mocap_welds=bad)
    assert main(["analyze", str(path), "--mocap-welds", "maybe"]) == 2
    assert "--mocap-welds must be one of drop, keep, got 'maybe'" in capsys.readouterr().err


def test_a_redundant_arm_welded_straight_gets_one_independent_coordinate(tmp_path):
    """Seven joints and a weld: one degree of freedom (the elbow's swivel); at the straight reference the
    Jacobian's rank (3) would have given four independent coordinates, and no sample closed the loops."""
    path = tmp_path / "arm7.xml"
    path.write_text(ARM.format(joints='<joint name="j7" axis="0 0 1" range="-3 3"/>').replace(
        '<motor joint="j1"/>', '<motor joint="j7"/>'))
    robot, notes = _load(path, mocap_welds="keep")
    assert any("re-anchored" in n for n in notes)
    assert len(robot.actuated) == 3  # the swivel and the two fingers
    rng = np.random.default_rng(0)
    cs = close_loops(robot, rng.uniform(-0.3, 0.3, (200, 3)), cond_max=1e3)
    assert cs.kept > 100 and cs.max_residual < 1e-9  # was: none of 5000 closed the loops


#: a spatial 3R arm whose tip is tied to a mocap body by a connect: three joints, three constraints (issue 51)
LOCKED = """<mujoco model="arm3c">
  <worldbody>
    <body name="mocap" mocap="true" pos="0.5 0 0.3"/>
    <body name="l1"><joint name="j1" axis="0 0 1"/><inertial pos="0 0.01 0.05" mass="1" diaginertia="0.01 0.01 0.01"/>
      <body name="l2" pos="0 0 0.3"><joint name="j2" axis="0 1 0"/>
        <inertial pos="0.1 0 0" mass="1" diaginertia="0.01 0.02 0.01"/>
        <body name="l3" pos="0.3 0 0" euler="0 30 0"><joint name="j3" axis="0 1 0"/>
          <inertial pos="0.1 0 0.01" mass="1" diaginertia="0.01 0.01 0.02"/></body></body></body>
  </worldbody>
  <equality><connect body1="l3" body2="mocap" anchor="0.3 0 0"/></equality>
</mujoco>
"""


def test_a_mocap_connect_that_locks_the_arm_is_refused_in_one_line(tmp_path, capsys):
    """Kept, the connect leaves the arm no motion: one line naming the file and the constraint (not an internal
    invariant); by default it is left out and the arm is MuJoCo's own tree."""
    from baseparams.errors import NoMotionError

    from mujoco_oracle import mujoco_rank

    path = tmp_path / "arm3c.xml"
    path.write_text(LOCKED)
    with pytest.raises(NoMotionError, match=r"arm3c.xml: robot 'arm3c': the constraints \(connect0\) leave this "
                                            r"mechanism no motion .* leave it out \(mocap_welds='drop'"):
        _load(path, mocap_welds="keep")
    assert main(["analyze", str(path), "--mocap-welds", "keep"]) != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "leave this mechanism no motion" in err and "Traceback" not in err
    tree = tmp_path / "tree.xml"
    tree.write_text(LOCKED.replace('<equality><connect body1="l3" body2="mocap" anchor="0.3 0 0"/></equality>', ""))
    robot, _ = _load(path)
    assert not robot.loops and bp.analyze(robot).n_base == mujoco_rank(tree)[0]
