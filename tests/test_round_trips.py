"""Whatever ``simulate`` and ``excite`` write, ``identify`` reads: every joint kind, through the files.

A log holds one column per coordinate (:meth:`baseparams.Robot.coordinate_names`): a 1-dof joint's
name, an MJCF body's own joints for its compound joint (``rootx``, ``rootz``, ``rooty``), the joint's
name and the place for other joints of several coordinates (``p.0``, ``p.1``, ``p.2`` of a URDF
``planar`` joint; a ball, a universal joint). The property: for random robots of every joint kind
(R, P, U, S, C; fixed and floating bases) and for the named cases of issue 51 (a URDF ``planar``
joint, an MJCF body with slide + slide + hinge, Drake's ball and universal joints, loops, couplings),
the log ``simulate`` writes is read by ``identify`` and identifies the simulation's own parameters
(noise-free: to rounding and the filter); a trajectory ``simulate`` would turn into a log
``identify`` refuses is refused at ``simulate`` in one line, nothing written.
"""

from __future__ import annotations

import numpy as np
import pytest

import baseparams as bp
from baseparams.errors import BaseparamsError
from baseparams.robots.random import random_robot

PLANAR_URDF = """<robot name="planar_arm">
 <link name="world"/>
 <link name="base"><inertial><mass value="2"/><origin xyz="0.1 0 0.05"/>
  <inertia ixx="0.1" iyy="0.2" izz="0.15" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <link name="arm"><inertial><mass value="1"/><origin xyz="0.2 0.01 0"/>
  <inertia ixx="0.05" iyy="0.06" izz="0.07" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <joint name="p" type="planar"><parent link="world"/><child link="base"/><axis xyz="0 0 1"/></joint>
 <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0.3 0 0"/>
  <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
</robot>
"""

HOPPER_MJCF = """<mujoco model="hopper">
 <worldbody>
  <body name="torso" pos="0 0 1">
   <joint name="rootx" type="slide" axis="1 0 0"/>
   <joint name="rootz" type="slide" axis="0 0 1"/>
   <joint name="rooty" type="hinge" axis="0 1 0"/>
   <geom type="capsule" size="0.05" fromto="-0.3 0 0 0.3 0 0" mass="3"/>
   <body name="thigh" pos="0.3 0 0">
    <joint name="hip" type="hinge" axis="0 1 0" range="-1 1"/>
    <geom type="capsule" size="0.04" fromto="0 0 0 0 0 -0.4" mass="1"/>
   </body>
  </body>
 </worldbody>
</mujoco>
"""

BALL_UNIVERSAL_URDF = """<robot name="bu" xmlns:drake="http://drake.mit.edu">
 <link name="world"/>
 <link name="a"><inertial><mass value="2"/><origin xyz="0.1 0.02 0.05"/>
  <inertia ixx="0.1" iyy="0.2" izz="0.15" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <link name="b"><inertial><mass value="1"/><origin xyz="0.2 0.01 0.03"/>
  <inertia ixx="0.05" iyy="0.06" izz="0.07" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <joint name="u" type="universal"><parent link="world"/><child link="a"/><axis xyz="1 0 0"/><axis2 xyz="0 1 0"/></joint>
 <drake:joint name="s" type="ball"><drake:parent link="a"/><drake:child link="b"/><origin xyz="0.3 0 0"/></drake:joint>
</robot>
"""

MIMIC_URDF = """<robot name="gripper">
 <link name="world"/>
 <link name="l1"><inertial><mass value="1"/><origin xyz="0.1 0.02 0"/>
  <inertia ixx="0.01" iyy="0.02" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <link name="l2"><inertial><mass value="0.5"/><origin xyz="0.05 0 0.02"/>
  <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <link name="l3"><inertial><mass value="0.3"/><origin xyz="0.02 0.03 0"/>
  <inertia ixx="0.005" iyy="0.006" izz="0.007" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <joint name="j1" type="revolute"><parent link="world"/><child link="l1"/><axis xyz="0 0 1"/>
  <limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
 <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.2 0 0"/><axis xyz="0 1 0"/>
  <limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
 <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.1 0 0"/><axis xyz="0 1 0"/>
  <limit lower="-2" upper="2" effort="10" velocity="3"/><mimic joint="j2" multiplier="-0.5"/></joint>
</robot>
"""

FILES = {"planar.urdf": PLANAR_URDF, "hopper.xml": HOPPER_MJCF, "ball_universal.urdf": BALL_UNIVERSAL_URDF,
         "mimic.urdf": MIMIC_URDF}


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    d = tmp_path_factory.mktemp("models")
    for name, text in FILES.items():
        (d / name).write_text(text)
    return d


def _header(path) -> list[str]:
    return path.read_text().splitlines()[0].split(",")


def _round_trip(model, robot, folder, **kw) -> float:
    """simulate -> a CSV file -> identify (noise-free): the relative error of the identified parameters."""
    out = folder / "log.csv"
    log, truth = bp.simulate(model, friction="none", out=out, **kw)
    header = _header(out)
    names = robot.coordinate_names()
    for kind in ("q", "dq", "tau"):  # one column per coordinate (a floating base's: its pose columns)
        assert [h.removeprefix(f"{kind}_") for h in header if h.startswith(f"{kind}_")] == names, header
    result = bp.identify(model, out, method="ols", friction="none", terms="none")
    assert list(result.joints) == [j for j in names]
    true = {p["name"]: p["value"] for p in truth["parameters"]}
    err = np.array([v - true[n] for n, v in zip(result.names, result.values)])
    return float(np.linalg.norm(err) / np.linalg.norm(list(true.values())))


@pytest.mark.parametrize("seed", range(6))
def test_random_robots_of_every_joint_kind_round_trip(seed, tmp_path):
    """Random trees of R, P, U, S and C joints (fixed base): the file simulate writes identifies its truth."""
    rng = np.random.default_rng(4100 + seed)
    robot = random_robot(rng, n=3, joint_types="RPUSC" if seed % 2 else "USC")
    assert len(set(robot.coordinate_names())) == robot.dof
    assert _round_trip(robot, robot, tmp_path, duration=6.0, rate=200.0, seed=seed) < 1e-3


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(4))
def test_random_floating_robots_round_trip(seed, tmp_path):
    """A floating base (its pose and twist columns) with joints of every kind below it."""
    rng = np.random.default_rng(4200 + seed)
    robot = random_robot(rng, n=4, joint_types="RPUSC", floating=True)
    out = tmp_path / "log.csv"
    bp.simulate(robot, duration=8.0, rate=200.0, friction="none", seed=seed, out=out)
    result = bp.identify(robot, out, method="ols", friction="none", terms="none")
    assert list(result.joints) == robot.coordinate_names(np.flatnonzero(np.asarray(robot.jtype)[robot.dof_body]
                                                                        != "F"))


@pytest.mark.parametrize("name", ["planar.urdf", "hopper.xml", "ball_universal.urdf", "mimic.urdf"])
def test_issue_51_models_round_trip_through_their_files(name, models, tmp_path):
    """A URDF planar joint, an MJCF slide+slide+hinge root (was 'q_rootx+rootz+rooty', 'a C joint', refused),
    Drake's ball and universal joints, a mimic coupling: the log simulate writes, identify reads."""
    robot = bp.load(str(models / name))
    assert _round_trip(str(models / name), robot, tmp_path, duration=10.0, rate=200.0) < 1e-3


def test_the_mjcf_body_s_columns_are_its_joints(models):
    robot = bp.load(str(models / "hopper.xml"))
    assert robot.coordinate_names() == ["rootx", "rootz", "rooty", "hip"]
    assert bp.load(str(models / "planar.urdf")).coordinate_names() == ["p.0", "p.1", "p.2", "j"]


def test_a_loop_robot_round_trips_on_its_actuated_joints(tmp_path):
    robot = bp.load("four-bar")  # a one-dof loop at a small excursion: the filter's bias is a few 1e-3
    assert _round_trip("four-bar", robot, tmp_path, duration=10.0, rate=200.0) < 1e-2


def test_excite_writes_one_column_per_coordinate_and_simulate_then_identify_read_it(models, tmp_path):
    """excite on a planar robot wrote 2 position columns for 4 coordinates: now 4, read back by simulate."""
    model = str(models / "hopper.xml")
    traj = tmp_path / "traj.csv"
    bp.excite(model, harmonics=2, period=4.0, rate=200.0, starts=1, grid=40, out=traj)
    header = _header(traj)
    assert [h for h in header if h.startswith("q_")] == ["q_rootx", "q_rootz", "q_rooty", "q_hip"]
    log = tmp_path / "log.csv"
    bp.simulate(model, trajectory=traj, friction="none", out=log)
    result = bp.identify(model, log, method="ols", friction="none", terms="none")
    assert list(result.joints) == ["rootx", "rootz", "rooty", "hip"]


def _edited(traj, tmp_path, name, edit):
    lines = traj.read_text().splitlines()
    path = tmp_path / name
    path.write_text("\n".join([lines[0], *edit(lines[1:])]) + "\n")
    return path


def _big(rows):
    cells = rows[3].split(",")
    cells[1] = "1e300"
    return [*rows[:3], ",".join(cells), *rows[4:]]


@pytest.mark.parametrize("name, edit, words", [
    ("reversed.csv", lambda rows: rows[::-1], "is before the one before"),
    ("repeated.csv", lambda rows: [*rows[:5], rows[4], *rows[6:]], "repeats the one before"),
    ("huge.csv", _big, "|q| = 1e+300"),
])
def test_a_trajectory_identify_would_refuse_is_refused_at_simulate(name, edit, words, tmp_path, capsys):
    """Time reversed, a repeated stamp, |q| = 1e300: one line at simulate, naming the file, nothing written."""
    from baseparams.cli import main

    traj = tmp_path / "traj.csv"
    bp.excite("puma560", harmonics=2, period=2.0, rate=50.0, starts=1, grid=40, out=traj)
    bad = _edited(traj, tmp_path, name, edit)
    out = tmp_path / "out.csv"
    with pytest.raises(BaseparamsError, match=f"{name}.*{words.replace('|', '.').replace('+', '.')}"):
        bp.simulate("puma560", trajectory=bad, out=out)
    assert main(["simulate", "puma560", str(out), "--trajectory", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0] and name in err[0]
    assert not out.exists() and not (tmp_path / "out.csv.truth.json").exists()


def test_arrays_identify_would_refuse_are_refused_at_simulate():
    t = np.linspace(0.0, 1.0, 50)
    q = np.zeros((50, 6))
    q[10, 2] = 1e300
    with pytest.raises(BaseparamsError, match=r"q of 'joint3', sample 10: \|q\| = 1e\+300 rad"):
        bp.simulate("puma560", trajectory=(t, q, np.zeros_like(q), np.zeros_like(q)))


def test_a_log_naming_a_coordinate_twice_is_refused_not_misread():
    """The JointLog simulate made before (one name per joint: 'p', 'p', 'p') was read as three copies of one
    column, a silently wrong estimate (relative error 10 to 200): such a log is now refused in one line."""
    from baseparams.jointlog import JointLog

    robot = bp.load("puma560")
    log, _ = bp.simulate(robot, duration=2.0, rate=100.0)
    joints = list(log.joints)
    joints[1] = joints[0]
    twice = JointLog(log.t, tuple(joints), log.q, log.tau, dq=log.dq, source="twice")
    with pytest.raises(BaseparamsError, match=r"twice: the log names \['joint1'\] more than once"):
        bp.identify(robot, twice, method="ols")
