"""Joint-log readers: round trips through every format, mappings, and one clear line per bad input."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import baseparams
from baseparams.errors import BaseparamsError, DataError
from baseparams.io.logs import read_log
from baseparams.jointlog import JointLog
from baseparams.robots.random import random_robot

PUMA = baseparams.load("puma560")
JOINTS = PUMA.joint_names
def seeded(n: int):
    """Hypothesis settings: derandomized (a fixed seed), ``n`` examples, tmp_path allowed."""
    return settings(max_examples=n, derandomize=True, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


def make_log(rng, n=50, joints=JOINTS, rates=True, t0=0.0) -> JointLog:
    t = t0 + np.cumsum(rng.uniform(0.5e-3, 1.5e-3, n))
    m = len(joints)
    q, dq, tau = rng.uniform(-3, 3, (n, m)), rng.normal(size=(n, m)), rng.normal(scale=20, size=(n, m))
    return JointLog(t=t, joints=tuple(joints), q=q, tau=tau, dq=dq if rates else None, source="mem")


def columns_of(log: JointLog) -> dict[str, np.ndarray]:
    cols = {"t": log.t}
    for kind in ("q", "dq", "ddq", "tau"):
        a = getattr(log, kind)
        if a is not None:
            cols.update({f"{kind}_{j}": a[:, k] for k, j in enumerate(log.joints)})
    return cols


def write_csv(path: Path, cols: dict[str, np.ndarray], delim: str = ",") -> Path:
    names = list(cols)
    block = np.column_stack([cols[n] for n in names])
    np.savetxt(path, block, delimiter=delim, header=delim.join(names), comments="", fmt="%.17g")
    return path


def assert_same(a: JointLog, b: JointLog):
    assert a.joints == b.joints
    for kind in ("t", "q", "dq", "ddq", "tau"):
        x, y = getattr(a, kind), getattr(b, kind)
        assert (x is None) == (y is None), kind
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=kind)


def one_line_error(fn, *args, **kwargs) -> str:
    """The message of the DataError raised, checked to be one line with no chained cause."""
    with pytest.raises(DataError) as info:
        fn(*args, **kwargs)
    msg = str(info.value)
    assert "\n" not in msg and msg.strip() == msg and msg
    assert info.value.__cause__ is None
    assert isinstance(info.value, BaseparamsError)
    return msg


# ---------------------------------------------------------------- round trips
@seeded(25)
@given(st.integers(0, 2**32 - 1), st.integers(2, 40), st.sampled_from([",", "\t", ";", " "]), st.booleans(),
       st.permutations(range(len(JOINTS))))
def test_csv_round_trip(tmp_path, seed, n, delim, rates, order):
    log = make_log(np.random.default_rng(seed), n, rates=rates)
    cols = columns_of(log)
    rank = {c: -1 if c == "t" else order[JOINTS.index(c.split("_", 1)[1])] for c in cols}
    shuffled = {k: cols[k] for k in sorted(cols, key=rank.__getitem__)}  # t first, joints shuffled
    suffix = ".tsv" if delim == "\t" else ".csv" if delim != " " else ".txt"
    back = read_log(write_csv(tmp_path / f"log{suffix}", shuffled, delim), PUMA)
    assert_same(log, back)  # the model's joint order whatever the column order
    assert back.source.endswith(suffix) and back.removed == {}


def test_csv_blank_and_comment_lines_and_row_numbers(tmp_path, rng):
    log = make_log(rng, 6)
    path = write_csv(tmp_path / "log.csv", columns_of(log))
    lines = path.read_text().splitlines()
    lines[3] = lines[3].replace(lines[3].split(",")[2], "nan", 1)  # data row 3, column q_joint2
    text = "# recorded 2024\n\n" + "\n".join(lines[:3]) + "\n\n" + "\n".join(lines[3:]) + "\n"
    path.write_text(text)
    msg = one_line_error(read_log, path, PUMA)
    # file line 7: two lines before the header, a blank line before it
    assert "log.csv" in msg and "column 'q_joint2'" in msg and "line 7 (data row 3)" in msg and "nan" in msg


@seeded(10)
@given(st.integers(0, 2**32 - 1), st.integers(1, 30), st.booleans())
def test_npz_round_trip(tmp_path, seed, n, rates):
    log = make_log(np.random.default_rng(seed), n, rates=rates)
    np.savez(tmp_path / "log.npz", **columns_of(log))
    assert_same(log, read_log(tmp_path / "log.npz", PUMA))


@seeded(10)
@given(st.integers(0, 2**32 - 1), st.integers(1, 30))
def test_parquet_round_trip(tmp_path, seed, n):
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    log = make_log(np.random.default_rng(seed), n)
    pq.write_table(pa.table(columns_of(log)), tmp_path / "log.parquet")
    assert_same(log, read_log(tmp_path / "log.parquet", PUMA))


def test_parquet_timestamp_column_and_null(tmp_path, rng):
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    log = make_log(rng, 8)
    cols = columns_of(log)
    cols["t"] = pa.array((np.arange(8) * 1_000_000).astype("datetime64[ns]"))
    pq.write_table(pa.table(cols), tmp_path / "log.parquet")
    back = read_log(tmp_path / "log.parquet", PUMA)
    np.testing.assert_allclose(back.t, np.arange(8) * 1e-3)
    assert any("timestamp" in n for n in back.notes)
    cols = columns_of(log)
    tau = pa.array(cols.pop("tau_joint4"), mask=np.arange(8) == 5)
    pq.write_table(pa.table(cols | {"tau_joint4": tau}), tmp_path / "null.parquet")
    msg = one_line_error(read_log, tmp_path / "null.parquet", PUMA)
    assert "null.parquet" in msg and "column 'tau_joint4'" in msg and "row 5 (0-based)" in msg and "null" in msg


# ---------------------------------------------------------------- ROS bags
def write_bag(path: Path, log: JointLog, names=None, topic="/joint_states", storage="sqlite3", stamps=True,
              shuffle_rng=None, extra_topics=()):
    """A rosbag2 recording of ``log`` as JointState messages (rosbags' writer; no ROS needed)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    js, header, time = (ts.types[k] for k in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header",
                                               "builtin_interfaces/msg/Time"))
    names = list(names or log.joints)
    ns = np.round(log.t * 1e9).astype(np.int64) + 1_700_000_000_000_000_000
    plugin = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}[storage]
    with Writer(path, version=9, storage_plugin=plugin) as w:
        for other in extra_topics:
            w.add_connection(other, "std_msgs/msg/String", typestore=ts)
        con = w.add_connection(topic, js.__msgtype__, typestore=ts)
        for i in range(log.n_samples):
            order = shuffle_rng.permutation(len(names)) if shuffle_rng is not None else np.arange(len(names))
            stamp = time(sec=int(ns[i] // 10**9), nanosec=int(ns[i] % 10**9)) if stamps else time(sec=0, nanosec=0)
            msg = js(header=header(stamp=stamp, frame_id=""), name=[names[k] for k in order],
                     position=log.q[i, order], velocity=log.dq[i, order] if log.dq is not None else np.zeros(0),
                     effort=log.tau[i, order])
            w.write(con, int(ns[i]), ts.serialize_cdr(msg, js.__msgtype__))
    return path


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_bag_round_trip(tmp_path, rng, storage):
    pytest.importorskip("rosbags")
    log = make_log(rng, 30)
    bag = write_bag(tmp_path / "bag", log, storage=storage, shuffle_rng=rng, extra_topics=["/chatter"])
    back = read_log(bag, PUMA)
    np.testing.assert_allclose(back.t, log.t - log.t[0], atol=2e-9)  # stamps in ns, t = 0 at the first
    for kind in ("q", "dq", "tau"):
        np.testing.assert_array_equal(getattr(back, kind), getattr(log, kind))
    assert back.ddq is None
    single = next(bag.glob(f"*.{'db3' if storage == 'sqlite3' else 'mcap'}"))  # the storage file alone
    assert_same(back, read_log(single, PUMA))


def test_bag_mapping_topic_and_record_time(tmp_path, rng):
    pytest.importorskip("rosbags")
    log = make_log(rng, 12, joints=JOINTS[:2], rates=False)
    bag = write_bag(tmp_path / "bag", log, names=["shoulder", "elbow"], topic="/arm/joint_states", stamps=False)
    mapping = {"topic": "/arm/joint_states",
               "joints": {"joint1": {"name": "shoulder", "gear_ratio": 2.0}, "joint2": {"name": "elbow", "sign": -1}}}
    back = read_log(bag, PUMA, columns=mapping, allow_subset=True)
    np.testing.assert_allclose(back.q, log.q * [0.5, -1.0])
    np.testing.assert_allclose(back.tau, log.tau * [2.0, -1.0])
    assert back.dq is None
    assert any("record time" in n for n in back.notes)
    msg = one_line_error(read_log, bag, PUMA, columns="/nope")
    assert "no topic '/nope'" in msg and "/arm/joint_states" in msg


def test_bag_errors_name_the_message(tmp_path, rng):
    pytest.importorskip("rosbags")
    log = make_log(rng, 10)
    t = log.t.copy()
    t[6] = t[5]
    bag = write_bag(tmp_path / "dup", JointLog(t=t, joints=log.joints, q=log.q, tau=log.tau, dq=log.dq))
    msg = one_line_error(read_log, bag, PUMA)
    assert "dup" in msg and "header stamp on /joint_states" in msg and "message 7" in msg and "repeats" in msg
    q = log.q.copy()
    q[3, 1] = np.nan
    bag = write_bag(tmp_path / "nan", JointLog(t=log.t, joints=log.joints, q=q, tau=log.tau))
    msg = one_line_error(read_log, bag, PUMA)
    assert "position['joint2'] on /joint_states" in msg and "message 4" in msg and "nan" in msg
    bag = write_bag(tmp_path / "unknown", log, names=[*JOINTS[:5], "gripper"])
    msg = one_line_error(read_log, bag, PUMA)
    assert "position['gripper']" in msg and "no joint 'gripper'" in msg


def test_bag_with_split_joint_sets_counts_the_messages_removed(tmp_path, rng):
    """Arm and gripper published as separate JointState messages on one topic."""
    pytest.importorskip("rosbags")
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    js, header, time = (ts.types[k] for k in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header",
                                               "builtin_interfaces/msg/Time"))
    log = make_log(rng, 8)
    with Writer(tmp_path / "split", version=9) as w:
        con = w.add_connection("/joint_states", js.__msgtype__, typestore=ts)
        for i in range(log.n_samples):
            for names, q, tau in ((list(JOINTS), log.q[i], log.tau[i]), (["finger"], np.ones(1), np.ones(1))):
                ns = int(round(log.t[i] * 1e9)) + (0 if len(names) > 1 else 1000)
                msg = js(header=header(stamp=time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=""), name=names,
                         position=q, velocity=np.zeros(0), effort=tau)
                w.write(con, ns, ts.serialize_cdr(msg, js.__msgtype__))
    msg = one_line_error(read_log, tmp_path / "split", PUMA)
    assert "no message has all of the joints" in msg and "[finger] x8" in msg and "columns=" in msg
    back = read_log(tmp_path / "split", PUMA, columns={"joints": {j: {} for j in JOINTS}})
    np.testing.assert_array_equal(back.q, log.q)
    assert back.removed == {"JointState messages without every joint read": 8}


def test_ros1_bag(tmp_path, rng):
    pytest.importorskip("rosbags")
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    js, header, time = (ts.types[k] for k in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header",
                                               "builtin_interfaces/msg/Time"))
    log = make_log(rng, 6)
    with Writer(tmp_path / "arm.bag") as w:
        con = w.add_connection("/joint_states", js.__msgtype__, typestore=ts)
        for i in range(log.n_samples):
            ns = int(round(log.t[i] * 1e9))
            msg = js(header=header(seq=i, stamp=time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=""),
                     name=list(JOINTS), position=log.q[i], velocity=log.dq[i], effort=log.tau[i])
            w.write(con, ns, ts.serialize_ros1(msg, js.__msgtype__))
    back = read_log(tmp_path / "arm.bag", PUMA)
    np.testing.assert_allclose(back.t, log.t - log.t[0], atol=2e-9)
    np.testing.assert_array_equal(back.dq, log.dq)


# ---------------------------------------------------------------- mappings
def test_toml_mapping_converts_motor_side_signals(tmp_path, rng):
    n = 20
    t_ns = 1_000_000 * np.arange(n) + 5_000_000
    qm, cur, vm = rng.uniform(-50, 50, (n, 2)), rng.normal(size=(n, 2)), rng.normal(size=(n, 2))
    write_csv(tmp_path / "motor.csv", {"stamp": t_ns, "pos_a": qm[:, 0], "pos_b": qm[:, 1], "vel_a": vm[:, 0],
                                       "vel_b": vm[:, 1], "cur_a": cur[:, 0], "cur_b": cur[:, 1], "seq": np.arange(n)})
    (tmp_path / "map.toml").write_text(
        'time = "stamp"\ntime_scale = 1e-9\n'
        '[joints.joint1]\nq = "pos_a"\ndq = "vel_a"\ntau = "cur_a"\ngear_ratio = 100\ntorque_gain = 0.5\n'
        '[joints.joint3]\nq = "pos_b"\ndq = "vel_b"\ntau = "cur_b"\nsign = -1\ngear_ratio = 50\noffset = 1.5\n')
    log = read_log(tmp_path / "motor.csv", PUMA, columns=tmp_path / "map.toml", allow_subset=True)
    assert log.joints == ("joint1", "joint3")
    np.testing.assert_allclose(log.t, t_ns * 1e-9)
    np.testing.assert_allclose(log.q, np.column_stack([qm[:, 0] / 100, -qm[:, 1] / 50 + 1.5]))
    np.testing.assert_allclose(log.dq, np.column_stack([vm[:, 0] / 100, -vm[:, 1] / 50]))
    np.testing.assert_allclose(log.tau, np.column_stack([cur[:, 0] * 0.5 * 100, -cur[:, 1] * 50]))
    assert any("seq" in n and "not read" in n for n in log.notes)
    assert any(n.startswith("joint joint3:") and "gear ratio 50" in n for n in log.notes)
    msg = one_line_error(read_log, tmp_path / "motor.csv", PUMA, columns=tmp_path / "map.toml")
    assert "joint2" in msg and "joint6" in msg and "allow_subset" in msg


@pytest.mark.parametrize("mapping, expect", [
    ({"clock": "t"}, "unknown key 'clock'"),
    ({"joints": {"joint1": {"gain": 2}}}, "joints.joint1: unknown key 'gain'"),
    ({"joints": {"joint1": {"sign": 2}}}, "joints.joint1.sign: expected +1 or -1"),
    ({"joints": {"joint1": {"gear_ratio": 0}}}, "joints.joint1.gear_ratio: expected a finite nonzero number"),
    ({"joints": {"joint1": {"q": 3}}}, "joints.joint1.q: expected a column name"),
    ({"joints": {"wrist": {}}}, "joints.wrist: robot 'puma560' has no joint 'wrist'"),
    ({"time_scale": -1}, "time_scale: expected a finite number in [1e-12, 1e+06], got -1"),
    ({"topic": "/js"}, "'topic' applies to ROS bags only"),
])
def test_bad_mappings(tmp_path, rng, mapping, expect):
    path = write_csv(tmp_path / "log.csv", columns_of(make_log(rng, 5)))
    assert expect in one_line_error(read_log, path, PUMA, columns=mapping)


def test_bad_toml_file(tmp_path, rng):
    path = write_csv(tmp_path / "log.csv", columns_of(make_log(rng, 5)))
    (tmp_path / "bad.toml").write_text("time = \n")
    msg = one_line_error(read_log, path, PUMA, columns=tmp_path / "bad.toml")
    assert "bad.toml" in msg and "not a valid TOML" in msg


# ---------------------------------------------------------------- bad input: one line naming file, column, row
def corrupt(path: Path, data_row: int, column: str, value: str) -> Path:
    lines = path.read_text().splitlines()
    names = lines[0].split(",")
    cells = lines[data_row].split(",")
    cells[names.index(column)] = value
    lines[data_row] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("column, value, expect", [
    ("q_joint2", "nan", "nan (not finite"),
    ("tau_joint6", "inf", "inf (not finite"),
    ("dq_joint1", "-inf", "-inf (not finite"),
    ("q_joint4", "abc", "'abc' is not a number"),
    ("q_joint4", "", "an empty field"),
    ("q_joint5", "1e400", "inf (not finite"),
    ("q_joint3", "180.0", "degrees given as radians?"),
])
def test_bad_values_name_file_column_row(tmp_path, rng, column, value, expect):
    path = corrupt(write_csv(tmp_path / "run 1.csv", columns_of(make_log(rng, 9))), 4, column, value)
    msg = one_line_error(read_log, path, PUMA)
    assert str(path) in msg and f"column {column!r}" in msg and "line 5 (data row 4)" in msg and expect in msg


@pytest.mark.parametrize("step, expect", [(0.0, "repeats"), (-1e-3, "is before")])
def test_time_not_increasing(tmp_path, rng, step, expect):
    log = make_log(rng, 9)
    t = log.t.copy()
    t[6] = t[5] + step
    path = write_csv(tmp_path / "log.csv", columns_of(JointLog(t=t, joints=log.joints, q=log.q, tau=log.tau)))
    msg = one_line_error(read_log, path, PUMA)
    assert "log.csv" in msg and "column 't'" in msg and "line 8 (data row 7)" in msg and expect in msg
    assert "strictly increasing" in msg


def test_rows_of_different_lengths(tmp_path, rng):
    path = write_csv(tmp_path / "log.csv", columns_of(make_log(rng, 9)))
    lines = path.read_text().splitlines()
    lines[3] = lines[3].rsplit(",", 1)[0]
    path.write_text("\n".join(lines) + "\n")
    msg = one_line_error(read_log, path, PUMA)
    assert "log.csv" in msg and "line 4 (data row 3)" in msg and "18 fields, the header has 19" in msg


def test_npz_errors(tmp_path, rng):
    cols = columns_of(make_log(rng, 9))
    np.savez(tmp_path / "short.npz", **(cols | {"tau_joint2": cols["tau_joint2"][:-1]}))
    msg = one_line_error(read_log, tmp_path / "short.npz", PUMA)
    assert "short.npz" in msg and "'tau_joint2' has 8 rows" in msg and "different lengths" in msg
    bad = cols["q_joint6"].copy()
    bad[2] = np.nan
    np.savez(tmp_path / "nan.npz", **(cols | {"q_joint6": bad}))
    msg = one_line_error(read_log, tmp_path / "nan.npz", PUMA)
    assert "nan.npz" in msg and "array 'q_joint6'" in msg and "index 2 (0-based)" in msg
    np.savez(tmp_path / "empty.npz")
    assert "empty file" in one_line_error(read_log, tmp_path / "empty.npz", PUMA)
    np.savez(tmp_path / "2d.npz", **(cols | {"q_joint1": np.zeros((9, 2))}))
    assert "'q_joint1' has shape (9, 2)" in one_line_error(read_log, tmp_path / "2d.npz", PUMA)


def test_joint_errors(tmp_path, rng):
    cols = columns_of(make_log(rng, 5))
    msg = one_line_error(read_log, write_csv(tmp_path / "a.csv", cols | {"q_elbow": cols["t"]}), PUMA)
    assert "a.csv" in msg and "column 'q_elbow'" in msg and "no joint 'elbow'" in msg
    some = {k: v for k, v in cols.items() if not k.endswith(("joint5", "joint6"))}
    msg = one_line_error(read_log, write_csv(tmp_path / "b.csv", some), PUMA)
    assert "b.csv" in msg and "joints joint5, joint6 of robot 'puma560': no columns" in msg and "allow_subset" in msg
    assert read_log(tmp_path / "b.csv", PUMA, allow_subset=True).joints == JOINTS[:4]
    no_tau = {k: v for k, v in cols.items() if k != "tau_joint3"}
    msg = one_line_error(read_log, write_csv(tmp_path / "c.csv", no_tau), PUMA)
    assert "c.csv" in msg and "no column 'tau_joint3' for joint 'joint3'" in msg
    part = {k: v for k, v in cols.items() if k != "dq_joint2"}
    msg = one_line_error(read_log, write_csv(tmp_path / "d.csv", part), PUMA)
    assert "d.csv" in msg and "dq given for joints joint1, joint3" in msg and "not for joint2" in msg
    no_t = {k: v for k, v in cols.items() if k != "t"}
    assert "no time column 't'" in one_line_error(read_log, write_csv(tmp_path / "e.csv", no_t), PUMA)


def test_file_level_errors(tmp_path, rng):
    (tmp_path / "empty.csv").write_text("\n  \n")
    assert one_line_error(read_log, tmp_path / "empty.csv", PUMA).endswith("empty file (expected a header row and "
                                                                            "data rows)")
    (tmp_path / "header.csv").write_text("t,q_joint1,tau_joint1\n")
    assert "no data rows after the header (line 1)" in one_line_error(read_log, tmp_path / "header.csv", PUMA)
    (tmp_path / "noheader.csv").write_text("0,1,2\n1,2,3\n")
    assert "expected a header row" in one_line_error(read_log, tmp_path / "noheader.csv", PUMA)
    (tmp_path / "twice.csv").write_text("t,q_joint1,q_joint1\n0,1,2\n")
    assert "column 'q_joint1' appears twice" in one_line_error(read_log, tmp_path / "twice.csv", PUMA)
    assert "no such file" in one_line_error(read_log, tmp_path / "missing.csv", PUMA)
    (tmp_path / "log.xlsx").write_text("x")
    assert "unknown log type '.xlsx'" in one_line_error(read_log, tmp_path / "log.xlsx", PUMA)
    (tmp_path / "latin.csv").write_bytes(b"t,q\xe9\n")
    assert "not a UTF-8 text file" in one_line_error(read_log, tmp_path / "latin.csv", PUMA)
    (tmp_path / "folder").mkdir()
    assert "metadata.yaml" in one_line_error(read_log, tmp_path / "folder", PUMA)


def test_prismatic_and_multi_dof_joints(tmp_path):
    robot = random_robot(np.random.default_rng(3), n=5, joint_types="RPU")  # U R U P R
    assert robot.jtype == ("U", "R", "U", "P", "R")
    n = 6
    cols = {"t": np.arange(n) * 0.01}
    for j in ("b1_joint", "b3_joint", "b4_joint"):
        cols |= {f"q_{j}": np.full(n, 0.1), f"tau_{j}": np.ones(n)}
    msg = one_line_error(read_log, write_csv(tmp_path / "some.csv", cols), robot)  # a U joint's coordinates: needed
    assert "joints b0_joint.0, b0_joint.1, b2_joint.0, b2_joint.1 of robot 'random5': no columns" in msg
    log = read_log(tmp_path / "some.csv", robot, allow_subset=True)
    assert log.joints == ("b1_joint", "b3_joint", "b4_joint")
    for j in ("b0_joint.0", "b0_joint.1", "b2_joint.0", "b2_joint.1"):  # one column per coordinate
        cols |= {f"q_{j}": np.full(n, 0.2), f"tau_{j}": np.ones(n)}
    log = read_log(write_csv(tmp_path / "ok.csv", cols), robot)
    assert log.joints == tuple(robot.coordinate_names()) and log.q.shape == (n, robot.dof)
    cols["q_b3_joint"] = np.full(n, 250.0)  # mm
    msg = one_line_error(read_log, write_csv(tmp_path / "mm.csv", cols), robot)
    assert "column 'q_b3_joint'" in msg and "line 2 (data row 1)" in msg and "millimetres given as metres?" in msg
    assert read_log(tmp_path / "mm.csv", robot, max_travel=None).q[0, 5] == 250.0
    msg = one_line_error(read_log, write_csv(tmp_path / "u.csv", cols | {"q_b0_joint": np.zeros(n)}), robot)
    assert "column 'q_b0_joint'" in msg and "joint 'b0_joint' has 2 coordinates, logged one column each" in msg


@seeded(40)
@given(st.integers(0, 2**32 - 1), st.integers(1, 12), st.integers(1, 18),
       st.sampled_from(["nan", "x", "", "inf", "1,5", "1e999", "--1", "0x10"]))
def test_any_corrupted_cell_is_one_line_naming_column_and_line(tmp_path, seed, row, col, value):
    log = make_log(np.random.default_rng(seed), 12)
    path = write_csv(tmp_path / "fuzz.csv", columns_of(log))
    column = path.read_text().splitlines()[0].split(",")[col]
    corrupt(path, row, column, value)
    msg = one_line_error(read_log, path, PUMA)
    assert "fuzz.csv" in msg
    if value == "1,5":  # one field more on that row
        assert f"line {row + 1} (data row {row})" in msg and "fields" in msg
    else:
        assert f"column {column!r}" in msg and f"line {row + 1} (data row {row})" in msg


def test_degrees_are_caught_after_the_conversion(tmp_path, rng):
    """A motor-side angle with its gear ratio is fine; without it, the same values are not."""
    log = make_log(rng, 5, joints=("joint1",))
    cols = {"t": log.t, "q_joint1": log.q[:, 0] * 100, "tau_joint1": log.tau[:, 0]}
    path = write_csv(tmp_path / "motor.csv", cols)
    read_log(path, PUMA, columns={"joints": {"joint1": {"gear_ratio": 100}}}, allow_subset=True)
    msg = one_line_error(read_log, path, PUMA, allow_subset=True)
    assert re.search(r"\|q\| = [\d.]+ rad > 12.57 for revolute joint 'joint1': degrees given as radians\?", msg)


def test_identify_end_to_end_from_a_ros2_bag(tmp_path, capsys):
    """A simulated Puma560 log recorded as a ROS 2 bag (MCAP, JointState): `baseparams identify`
    reads it and returns the true parameters within their standard deviations."""
    import json

    import baseparams
    from baseparams.cli import main
    from baseparams.ident.simulate import simulate_log

    robot = baseparams.load("puma560")
    log, truth = simulate_log(robot, duration=20.0, rate=200.0, noise=0.05, seed=7, friction=("viscous",))
    bag = write_bag(tmp_path / "run1", log, storage="mcap")
    assert main(["identify", "puma560", str(bag), "--friction", "viscous", "--method", "ols", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["n_samples"]["read"] == log.n_samples
    true = {p["name"]: p["value"] for p in truth["parameters"]}
    z = [(b["value"] - true[b["name"]]) / b["std"] for b in j["base_parameters"]]
    assert len(z) == 36 and np.sqrt(np.mean(np.square(z))) < 5
    assert [d["Fv"] for d in j["drives"]] == pytest.approx([truth["drives"][f"Fv_joint{k}"] for k in range(1, 7)],
                                                           rel=0.05)
