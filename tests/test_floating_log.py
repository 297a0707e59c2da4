"""Floating-base robots from a log: the base's columns, their conversion, simulate then identify."""

import json

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

import baseparams as bp
from baseparams.cli import main
from baseparams.errors import BaseparamsError, DataError
from baseparams.ident.model import ident_model
from baseparams.ident.simulate import fourier_trajectory
from baseparams.io.logs import read_log, write_log
from baseparams.io.pinocchio import to_pinocchio
from baseparams.jointlog import JointLog
from baseparams.kinematics.floating import BASE_COORDINATES, POSE_COLUMNS, TWIST_COLUMNS
from baseparams.robots import random_robot


def _pose(c):
    """Position and rotation of chart values ``(6,)``, by SciPy (not the package's formulas)."""
    return c[:3], Rotation.from_euler("ZYX", c[[5, 4, 3]]).as_matrix()


def _body_twist(c, dc, ddc, h=1e-5):
    """Pinocchio's free-flyer velocity (base frame ``v, omega``) by central differences of the pose."""
    p0, r0 = _pose(c)
    (pp, rp), (pm, rm) = (_pose(c + s * h * dc + 0.5 * h * h * ddc) for s in (1, -1))
    w = (Rotation.from_matrix(r0.T @ rp).as_rotvec() - Rotation.from_matrix(r0.T @ rm).as_rotvec()) / (2 * h)
    return np.r_[r0.T @ (pp - pm) / (2 * h), w]


def test_the_log_coordinates_drive_the_regressor_as_pinocchios_free_flyer(rng):
    """A random floating robot whose root frame is rotated at q = 0: the joint torques from the log's
    base coordinates (position, Z-Y-X angles, their derivatives) equal Pinocchio's RNEA at the free-flyer
    state built from the same pose by SciPy and finite differences; the log's base twist columns are
    Pinocchio's free-flyer velocity."""
    robot = random_robot(np.random.default_rng(11), 5, joint_types="RP", floating=True)
    assert not np.allclose(robot.M0[0][:3, :3], np.eye(3))
    model = ident_model(bp.analyze(robot, rows="joints"), rotor=False, friction=(), log_base=True)
    t, c, dc, ddc = fourier_trajectory(robot.dof, 10.0, 100.0, rng, amplitude=1.2)
    tau = model.regressor(c, dc, ddc) @ model.theta(robot.parameters("paper"))
    pm = to_pinocchio(robot)
    data = pm.createData()
    m0inv = np.linalg.inv(robot.M0[0])
    log = JointLog(t, BASE_COORDINATES + tuple(f"j{k}" for k in range(robot.dof - 6)), c, np.zeros_like(c), dq=dc)
    from baseparams.io.logs import log_columns_of

    cols = log_columns_of(log)
    worst = 0.0
    for k in range(0, len(t), 37):
        p, r = _pose(c[k])
        rel = m0inv @ np.block([[r, p[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]])
        q_pin = np.r_[rel[:3, 3], Rotation.from_matrix(rel[:3, :3]).as_quat(), c[k, 6:]]
        v_b = _body_twist(c[k], dc[k], ddc[k])
        a_b = (_body_twist(c[k] + 1e-4 * dc[k] + 5e-9 * ddc[k], dc[k] + 1e-4 * ddc[k], ddc[k])
               - _body_twist(c[k] - 1e-4 * dc[k] + 5e-9 * ddc[k], dc[k] - 1e-4 * ddc[k], ddc[k])) / 2e-4
        tau_pin = pin.rnea(pm, data, q_pin, np.r_[v_b, dc[k, 6:]], np.r_[a_b, ddc[k, 6:]])[6:]
        worst = max(worst, np.abs(tau_pin - tau[k]).max() / np.abs(tau_pin).max())
        logged = np.array([cols[n][k] for n in TWIST_COLUMNS])
        assert np.allclose(logged, v_b, rtol=1e-6, atol=1e-8)  # the documented frame: Pinocchio's
    assert worst < 1e-6


def test_base_columns_round_trip_through_a_file(tmp_path, rng):
    """Written as pose and twist columns and read back: the same base coordinates and rates, yaw turning
    three times (unwrapped), the quaternion's sign free."""
    robot = bp.load("go2")
    t, c, dc, _ = fourier_trajectory(robot.dof, 4.0, 250.0, rng, amplitude=0.4)
    c[:, 5] += 3 * 2 * np.pi * t / t[-1]  # yaw: three turns
    dc[:, 5] += 3 * 2 * np.pi / t[-1]
    names = BASE_COORDINATES + tuple(robot.joint_names[1:])
    log = JointLog(t, names, c, np.c_[np.zeros((len(t), 6)), rng.normal(size=(len(t), 12))], dq=dc)
    path = tmp_path / "log.csv"
    write_log(path, log)
    header = path.read_text().splitlines()[0].split(",")
    assert all(n in header for n in POSE_COLUMNS + TWIST_COLUMNS) and "q_base_x" not in header
    back = read_log(path, robot)
    assert back.joints == names and back.floating and back.n_joints == 12
    assert np.allclose(back.q, c, atol=1e-12) and np.allclose(back.dq, dc, atol=1e-10)
    assert np.array_equal(back.tau, log.tau)
    text = path.read_text().splitlines()
    k = header.index("base_qw")
    rows = [line.split(",") for line in text[1:]]
    for row in rows[::3]:  # q and -q are one orientation
        row[k:k + 4] = [repr(-float(x)) for x in row[k:k + 4]]
    path.write_text("\n".join([text[0]] + [",".join(r) for r in rows]) + "\n")
    assert np.allclose(read_log(path, robot).q, c, atol=1e-12)


def test_base_columns_bad_input_is_one_line(tmp_path):
    robot = bp.load("go2")
    log, _ = bp.simulate(robot, duration=1, rate=100)
    path = tmp_path / "log.csv"
    write_log(path, log)
    cols = path.read_text().splitlines()
    header = cols[0].split(",")

    def edited(drop=(), change=None):
        keep = [i for i, n in enumerate(header) if n not in drop]
        rows = [line.split(",") for line in cols]
        if change:
            name, row, value = change
            rows[row][header.index(name)] = value
        out = tmp_path / "bad.csv"
        out.write_text("\n".join(",".join(r[i] for i in keep) for r in rows) + "\n")
        return out

    with pytest.raises(DataError, match=r"floating base: the log needs its pose.*missing base_qw"):
        read_log(edited(drop=("base_qw",)), robot)
    with pytest.raises(DataError, match=r"base twist columns .* without base_wz"):
        read_log(edited(drop=("base_wz",)), robot)
    with pytest.raises(DataError, match=r"base_qw..base_qz, line 6 .*not a unit quaternion"):
        read_log(edited(change=("base_qw", 5, "3.0")), robot)
    steep = edited(change=("base_qw", 5, "0.7071067811865476"))
    text = steep.read_text().splitlines()
    row = text[5].split(",")
    for name, value in (("base_qx", "0"), ("base_qy", "0.7071067811865476"), ("base_qz", "0")):
        row[header.index(name)] = value
    text[5] = ",".join(row)
    steep.write_text("\n".join(text) + "\n")
    with pytest.raises(DataError, match=r"line 6 .*the base pitches 90.0 deg"):
        read_log(steep, robot)
    no_base = JointLog(log.t, log.joints[6:], log.q[:, 6:], log.tau[:, 6:], dq=log.dq[:, 6:])
    with pytest.raises(BaseparamsError, match=r"has a floating base and the log has no base pose"):
        bp.identify(robot, no_base)
    for trajectory in ((log.t, log.q, log.dq, log.dq), tmp_path / "log.csv"):
        with pytest.raises(BaseparamsError, match=r"floating base's motion is not in a trajectory file"):
            bp.simulate(robot, trajectory)
    with pytest.raises(BaseparamsError, match=r"sub-chains \(joints=\) of a floating base"):
        bp.identify(robot, log, joints="FL_hip_joint")


@pytest.mark.slow
def test_go2_simulated_then_identified_on_the_command_line(tmp_path, capsys):
    """The acceptance: ``simulate go2 log.csv`` then ``identify go2 log.csv --truth`` exits 0, error <= 5 %
    (here with torque noise too; noise-free it is ~1e-5)."""
    log = tmp_path / "log.csv"
    assert main(["simulate", "go2", str(log), "--noise", "0.05"]) == 0
    assert "of 12 joints and the floating base" in capsys.readouterr().out
    assert main(["identify", "go2", str(log), "--truth", str(log) + ".truth.json", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["truth"]["rel_error"] <= 0.05
    assert len(doc["base_parameters"]) == 84  # the joint torques' base parameters (README, --rows joints)
    assert any(n.startswith("floating base: ") and "no external force" in n for n in doc["notes"])


def test_random_floating_robot_simulated_then_identified(rng):
    """Python route, a random floating tree (R and P joints, rotated root frame), noise on the torques."""
    robot = random_robot(np.random.default_rng(4), 4, joint_types="RP", floating=True)
    log, truth = bp.simulate(robot, duration=20, rate=200, noise=0.01, seed=2)
    assert log.floating and log.n_joints == robot.dof - 6
    ident = bp.identify(robot, log, method="ols")
    assert ident.compare_truth(truth)["rel_error"] <= 0.05
    assert ident.predict(log).shape == (log.n_samples, robot.dof - 6)


# ---------------------------------------------------------------- one log, every format (issue 51)
def _floating_log(seed: int, samples: int = 300):
    """A random floating robot and a log of it: base pose and base-frame twist, joints with dq and tau."""
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, int(rng.integers(2, 5)), joint_types="RP", floating=True)
    t, c, dc, _ = fourier_trajectory(robot.dof, samples / 200.0, 200.0, rng, amplitude=0.6)
    names = BASE_COORDINATES + tuple(robot.joint_names[1:])
    tau = np.c_[np.zeros((len(t), 6)), rng.normal(size=(len(t), robot.dof - 6))]
    return robot, JointLog(t, names, c, tau, dq=dc)


def write_floating_bag(path, log, odom_every: int = 1, odom_shift_ns: int = 0, storage: str = "sqlite3"):
    """A rosbag2 recording: the joints as JointState, the base as nav_msgs/msg/Odometry (pose in the world
    frame, twist in the base frame: REP 105), every ``odom_every``-th sample, stamps shifted by ``odom_shift_ns``."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    from baseparams.io.logs import log_columns_of

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    cols = log_columns_of(log)
    ns = np.round(log.t * 1e9).astype(np.int64) + 1_700_000_000_000_000_000

    def header(k, shift=0):
        n = int(ns[k]) + shift
        return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=n // 10**9, nanosec=n % 10**9),
                                         frame_id="odom")

    def vec(kind, a, b, c):
        return T[f"geometry_msgs/msg/{kind}"](x=float(a), y=float(b), z=float(c))

    plugin = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}[storage]
    joints = list(log.joints[6:])
    with Writer(path, version=9, storage_plugin=plugin) as w:
        js = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=ts)
        od = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        for k in range(log.n_samples):
            msg = T["sensor_msgs/msg/JointState"](header=header(k), name=joints, position=log.q[k, 6:],
                                                  velocity=log.dq[k, 6:], effort=log.tau[k, 6:])
            w.write(js, int(ns[k]), ts.serialize_cdr(msg, msg.__msgtype__))
            if k % odom_every:
                continue
            g = {n: cols[n][k] for n in cols}
            pose = T["geometry_msgs/msg/Pose"](
                position=vec("Point", g["base_x"], g["base_y"], g["base_z"]),
                orientation=T["geometry_msgs/msg/Quaternion"](x=g["base_qx"], y=g["base_qy"], z=g["base_qz"],
                                                             w=g["base_qw"]))
            twist = T["geometry_msgs/msg/Twist"](linear=vec("Vector3", g["base_vx"], g["base_vy"], g["base_vz"]),
                                                angular=vec("Vector3", g["base_wx"], g["base_wy"], g["base_wz"]))
            msg = T["nav_msgs/msg/Odometry"](
                header=header(k, odom_shift_ns), child_frame_id="base",
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
                twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)))
            w.write(od, int(ns[k]) + odom_shift_ns, ts.serialize_cdr(msg, msg.__msgtype__))
    return path


@pytest.mark.parametrize("seed", range(4))
def test_one_floating_log_reads_the_same_from_every_format(tmp_path, seed):
    """Property (issue 51: NPZ and Parquet refused a floating log that CSV read): one log of a random floating
    robot, written as CSV, TSV, NPZ, Parquet and a ROS 2 bag (JointState + Odometry), reads to the same JointLog
    (the bag's time to its nanosecond stamps)."""
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    pytest.importorskip("rosbags")
    from baseparams.io.logs import log_columns_of

    robot, log = _floating_log(seed)
    files = [write_log(tmp_path / f"log.{ext}", log) for ext in ("csv", "tsv", "npz")]
    pq.write_table(pa.table(log_columns_of(log)), tmp_path / "log.parquet")
    storage = ("sqlite3", "mcap")[seed % 2]
    files += [tmp_path / "log.parquet", write_floating_bag(tmp_path / "bag", log, storage=storage)]
    ref = read_log(files[0], robot)
    assert ref.joints == log.joints and ref.floating
    assert np.allclose(ref.q, log.q, atol=1e-12) and np.allclose(ref.dq, log.dq, atol=1e-9)
    for f in files[1:]:
        back = read_log(f, robot)
        assert back.joints == ref.joints, f
        if f.name == "bag":
            np.testing.assert_allclose(back.t, ref.t - ref.t[0], atol=2e-9)
        else:
            assert np.array_equal(back.t, ref.t), f
        for kind in ("q", "dq", "tau"):
            assert np.array_equal(getattr(back, kind), getattr(ref, kind)), (f, kind)
        assert back.ddq is None and back.removed == ref.removed, f


def test_a_bag_base_between_joint_stamps_is_interpolated_and_outside_it_counted(tmp_path):
    """Odometry at half the joints' rate: its own stamps read exactly, the others interpolated (noted), the
    last joint sample after the last odometry removed and counted."""
    pytest.importorskip("rosbags")
    robot, log = _floating_log(7, samples=401)
    ref = read_log(write_log(tmp_path / "log.csv", log), robot)
    assert read_log(write_floating_bag(tmp_path / "bag", log, odom_every=2), robot).removed == {}  # 401: both ends
    even = JointLog(log.t[:400], log.joints, log.q[:400], log.tau[:400], dq=log.dq[:400])
    back = read_log(write_floating_bag(tmp_path / "bag2", even, odom_every=2), robot)
    assert back.removed == {"JointState messages outside the base odometry's time span (/odom)": 1}
    assert any("interpolated at 199 JointState stamps" in n for n in back.notes), back.notes
    np.testing.assert_array_equal(back.q[:, 6:], ref.q[:399, 6:])
    np.testing.assert_array_equal(back.q[::2, :6], ref.q[:399:2, :6])  # at its own stamps: exactly
    np.testing.assert_allclose(back.q[1::2, :6], ref.q[1:399:2, :6], atol=1e-4)  # between: a smooth motion


def test_a_bag_without_the_base_odometry_is_one_line(tmp_path):
    pytest.importorskip("rosbags")
    from test_logs import write_bag

    robot, log = _floating_log(3)
    joints = JointLog(log.t, log.joints[6:], log.q[:, 6:], log.tau[:, 6:], dq=log.dq[:, 6:])
    bag = write_bag(tmp_path / "bag", joints)
    with pytest.raises(DataError, match=r"floating base: the bag needs its pose and twist on a nav_msgs/msg/Odometry"):
        read_log(bag, robot)
    with pytest.raises(DataError, match=r"no topic '/base' \(base_topic\)"):
        read_log(bag, robot, columns={"base_topic": "/base"})
    with pytest.raises(DataError, match=r"'base_topic' applies to ROS bags only"):
        read_log(write_log(tmp_path / "log.csv", log), robot, columns={"base_topic": "/odom"})
