"""Hostile and careless input: nothing in a file runs code, no output lands on an input, one line.

Each case is a class of problem closed at its source: the allow-list grammar of the symbolic
tables (``baseparams.symbolic.expr``), the one atomic writer (``baseparams.files``).
"""

import os
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

sp = pytest.importorskip("sympy")

from baseparams.symbolic.expr import ExpressionError, parse  # noqa: E402

TABLE = """name evil
convention modified
j  ant  sigma  alpha   d   theta  r
1  0    0      0       0   0      0
2  1    0      -pi/2   {entry}  0      0
"""

ATTACKS = [
    "__import__('pathlib').Path('{marker}').touch()",
    "(lambda: __import__('os').system('touch {marker}'))()",
    "open('{marker}','w')",
    "D2.__class__",
    "getattr(D2,'x')",
    "[x for x in ().__class__.__bases__]",
    "exec('1')",
    "D2 if 1 else 0",
    "'text'",
    "9**9**9**9",
    "(" * 500 + "1" + ")" * 500,
    "D2 " * 100,
    "Symbol('x')",
    "sin(x, y)",
    "cos(x=1)",
    "nan",
    "1e999",
]


@pytest.mark.parametrize("attack", ATTACKS)
def test_a_dh_table_never_runs_code(attack, tmp_path, capsys):
    from baseparams.cli import main

    marker = tmp_path / "pwned"
    f = tmp_path / "evil.dh"
    f.write_text(TABLE.format(entry=attack.format(marker=marker)))
    code = main(["analyze", str(f), "--symbolic"])
    err = capsys.readouterr().err.strip().splitlines()
    assert not marker.exists()
    if attack == "nan":  # a plain name: a symbol called nan, read as such
        return
    assert code == 2 and len(err) == 1 and str(f) in err[0], err


def test_the_same_attack_in_a_subprocess_leaves_no_file(tmp_path):
    marker = tmp_path / "pwned"
    f = tmp_path / "evil.dh"
    f.write_text(TABLE.format(entry=f"__import__('os').system('touch {marker}')"))
    r = subprocess.run([sys.executable, "-m", "baseparams", "analyze", str(f), "--symbolic"], capture_output=True,
                       text=True, timeout=120, env={**os.environ})
    assert r.returncode == 2 and "Traceback" not in r.stderr and not marker.exists()


_names = st.sampled_from(["a", "b", "D3", "RL4", "pi"])
_numbers = st.one_of(st.integers(-50, 50), st.floats(-10, 10, allow_nan=False).map(lambda x: round(x, 4)))


def _exprs():
    leaf = st.one_of(_names, _numbers.map(lambda x: f"({x})"))
    return st.recursive(leaf, lambda e: st.one_of(
        st.tuples(e, st.sampled_from(["+", "-", "*"]), e).map(lambda t: f"({t[0]} {t[1]} {t[2]})"),
        st.tuples(e, st.integers(0, 3)).map(lambda t: f"({t[0]})**{t[1]}"),
        e.map(lambda x: f"sin({x})"), e.map(lambda x: f"sqrt(({x})**2)"), e.map(lambda x: f"-{x}")), max_leaves=8)


@settings(max_examples=150, deadline=None)
@given(_exprs())
def test_allowed_expressions_read_as_sympy_reads_them(text):
    ns = {n: sp.Symbol(n, real=True) for n in ("a", "b", "D3", "RL4")}
    expected = sp.sympify(text, locals={**ns, "pi": sp.pi}, rational=True)  # the oracle: trusted text only
    assert sp.simplify(parse(text) - expected) == 0


@pytest.mark.parametrize("text, words", [("__x", "may not start"), ("a.b", "attribute"), ("a[0]", "subscript"),
                                        ("f(1)", "only sin"), ("2**a", "exponent"), ("1/0", "division by zero"),
                                        ("x" * 300, "longer than")])
def test_refusals_say_what_was_found(text, words):
    with pytest.raises(ExpressionError, match=words):
        parse(text)


# ---------------------------------------------------------------- non-regular paths, absurd numbers
import time  # noqa: E402

from hostile import deadline as _deadline  # noqa: E402, F401  (the helpers every attack test shares)
from hostile import one_line_error as _one_line_error  # noqa: E402

URDF = """<robot name="r">
 <link name="base"/>
 <link name="l1"><inertial><origin xyz="{com}"/><mass value="{mass}"/>
  <inertia ixx="{ixx}" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <link name="l2"><inertial><origin xyz="0.1 0 0"/><mass value="1"/>
  <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="{xyz}" rpy="{rpy}"/>
  <axis xyz="{axis}"/></joint>
 <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3" rpy="1.5707963 0 0"/>
  <axis xyz="0 0 1"/></joint>
</robot>
"""
URDF_OK = dict(com="0 0 0.1", mass="1", ixx="0.1", xyz="0 0 0.2", rpy="0 0 0", axis="0 0 1")

MJCF = """<mujoco model="m"><worldbody>
 <body name="b1" pos="{pos}"><joint name="j1" type="hinge" axis="{axis}"/>
  <inertial pos="{ipos}" mass="{mass}" diaginertia="{inertia} {inertia} {inertia}"/>
  <body name="{name}" pos="0 0 0.3"><joint name="j2" type="hinge" axis="1 0 0"/>
   <inertial pos="0 0 0.1" mass="1" diaginertia="0.1 0.1 0.1"/></body>
 </body></worldbody></mujoco>
"""
MJCF_OK = dict(pos="0 0 0.1", axis="0 0 1", ipos="0 0 0.1", mass="1", inertia="0.1", name="b2")


def _not_regular(kind, tmp_path, name):
    """A path called ``name`` that is a device, a FIFO or a folder."""
    p = tmp_path / name
    if kind == "device":
        p.symlink_to("/dev/zero")
    elif kind == "fifo":
        os.mkfifo(p)
    else:
        p.mkdir()
    return p


def _log(tmp_path):
    log = tmp_path / "ok.csv"
    log.write_text("t,q_j1,tau_j1\n0,0,0\n0.1,0,0\n")
    return log


READERS = {  # argv with {p} the hostile path
    "urdf": (["analyze", "{p}"], "robot.urdf"),
    "mjcf": (["analyze", "{p}"], "robot.xml"),
    "dh": (["analyze", "{p}", "--symbolic"], "robot.dh"),
    "log": (["identify", "puma560", "{p}"], "log.csv"),
    "bag file": (["identify", "puma560", "{p}"], "log.mcap"),
    "columns": (["identify", "puma560", "{log}", "--columns", "{p}"], "map.toml"),
    "trajectory": (["simulate", "puma560", "{out}", "--trajectory", "{p}"], "traj.csv"),
}


# a folder given as a log is read as a ROS 2 bag (refused for its missing metadata.yaml: tests/test_logs.py)
CASES = [(r, k) for r in READERS for k in ("device", "fifo", "folder")
         if not (k == "folder" and r in ("log", "bag file"))]


@pytest.mark.parametrize("reader, kind", CASES)
def test_every_reader_refuses_what_is_not_a_regular_file(reader, kind, tmp_path, capsys):
    argv, name = READERS[reader]
    p = _not_regular(kind, tmp_path, name)
    argv = [a.format(p=p, log=_log(tmp_path), out=tmp_path / "out.csv") for a in argv]
    err = _one_line_error(argv, capsys, seconds=20)
    assert err == f"baseparams: error: {p}: not a regular file", err


@pytest.mark.parametrize("name", ["big.urdf", "big.xml", "big.dh"])
def test_a_robot_file_beyond_64_mb_is_refused_before_reading(name, tmp_path, capsys):
    p = tmp_path / name
    with open(p, "wb") as fh:
        fh.truncate(65 * 2**20)  # sparse: no disk used, and never read
    err = _one_line_error(["analyze", p] + (["--symbolic"] if name.endswith(".dh") else []), capsys, seconds=20)
    assert str(p) in err and "64 MB" in err


@pytest.mark.parametrize("field, value, words", [
    ("xyz", "0 0 1e308", "<joint name='j1'> <origin xyz>"), ("xyz", "1e154 0 0", "<origin xyz>"),
    ("rpy", "1e308 0 0", "<origin rpy>"), ("axis", "0 0 1e308", "<axis xyz>"),
    ("com", "0 0 1e200", "<inertial> <origin xyz>"), ("mass", "1e308", "<mass value>"),
    ("ixx", "1e154", "<inertia ixx>")])
def test_absurd_magnitudes_in_a_urdf_are_refused_at_load_time(field, value, words, tmp_path, capsys):
    f = tmp_path / "r.urdf"
    f.write_text(URDF.format(**{**URDF_OK, field: value}))
    err = _one_line_error(["analyze", f], capsys, seconds=20)
    assert f"{f}: " in err and words in err and "exceeds the bound" in err, err


@pytest.mark.parametrize("field, value, words", [
    ("pos", "0 0 1e308", "<body name='b1'> pos"), ("pos", "1e154 0 0", "<body name='b1'> pos"),
    ("ipos", "0 0 1e200", "<body name='b1'> inertial pos"), ("mass", "1e308", "<body name='b1'> mass"),
    ("axis", "0 0 1e308", "<joint name='j1'> axis"), ("inertia", "1e200", "<body name='b1'> inertia")])
def test_absurd_magnitudes_in_an_mjcf_are_refused_at_load_time(field, value, words, tmp_path, capsys):
    pytest.importorskip("mujoco")
    f = tmp_path / "m.xml"
    f.write_text(MJCF.format(**{**MJCF_OK, field: value}))
    err = _one_line_error(["analyze", f], capsys, seconds=20)
    assert f"{f}: " in err and words in err, err


def test_a_hanging_magnitude_ends_in_a_subprocess_in_seconds(tmp_path):
    """The run that hung past 300 s (``1e308`` in a joint origin): one line, exit 2, no traceback."""
    f = tmp_path / "r.urdf"
    f.write_text(URDF.format(**{**URDF_OK, "xyz": "0 0 1e308"}))
    r = subprocess.run([sys.executable, "-m", "baseparams", "analyze", str(f)], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr


def test_a_linear_algebra_failure_is_one_line(monkeypatch, capsys):
    import numpy as np

    from baseparams.cli import common

    def fail(args):
        raise np.linalg.LinAlgError("SVD did not converge")
    monkeypatch.setattr(common, "load_robot", fail)
    err = _one_line_error(["analyze", "puma560"], capsys)
    assert "puma560" in err and "SVD did not converge" in err


@pytest.mark.parametrize("text, words", [
    (MJCF.format(**{**MJCF_OK, "name": "b\udcff2"}), "is not UTF-8 text (byte 0xff)"),
    ("<mujoco><worldbody><body name='a'><joint/><geom size='0.1'/></body></worldbody>\n<</mujoco>",
     "XML parse error"),
    ("<mujoco><worldbody><body name='a'><joint/><geom size='0.1'/></body></worldbody>\n<bogus/></mujoco>",
     "unrecognized element"),
])
def test_mjcf_errors_are_one_line_with_their_reason(text, words, tmp_path, capsys):
    pytest.importorskip("mujoco")
    f = tmp_path / "m.xml"
    f.write_bytes(text.encode("utf-8", "surrogateescape"))
    err = _one_line_error(["analyze", f], capsys)
    assert f"{f}: " in err and words in err, err
    if "parse error" in words:  # the reason, not only MuJoCo's first line ("XML parse error 15:")
        assert "Line number=2" in err or "line 2" in err.lower(), err
    if "unrecognized" in words:
        assert "bogus" in err, err


# ---------------------------------------------------------------- the environment: Dask, numba's cache
@pytest.fixture(scope="module")
def two_logs(tmp_path_factory):
    pytest.importorskip("distributed")
    import baseparams
    from baseparams.fleet import simulate_fleet

    folder = tmp_path_factory.mktemp("logs")
    simulate_fleet(baseparams.load("puma560"), folder, robots=2, duration=2.0, rate=200.0, seed=3)
    return folder


@pytest.mark.parametrize("address, env", [("tcp://127.0.0.1:1", False), ("tcp://no-such-host.invalid:8786", False),
                                          ("garbage", False), ("garbage", True), ("tcp://[::1", False)])
@pytest.mark.slow
def test_an_unreachable_or_malformed_scheduler_is_one_line_in_seconds(address, env, two_logs, capsys, monkeypatch):
    argv = ["identify", "puma560", two_logs / "*.npz", "--per-file"]
    if env:
        monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", address)
    else:
        argv += ["--scheduler", address]
    t0 = time.perf_counter()
    err = _one_line_error(argv, capsys, seconds=30)
    assert address in err and "cannot connect to a Dask scheduler" in err, err
    assert ("DASK_SCHEDULER_ADDRESS" in err) == env and time.perf_counter() - t0 < 15


def test_numba_without_a_writable_cache_compiles_in_memory_with_a_note(tmp_path):
    """A read-only install, HOME and NUMBA_CACHE_DIR unwritable (paths under a regular file: root ignores modes)."""
    pytest.importorskip("numba")
    import shutil

    import baseparams

    src = tmp_path / "src"
    shutil.copytree(os.path.dirname(baseparams.__file__), src / "baseparams",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (src / "baseparams" / "regressor" / "__pycache__").write_text("")  # no cache beside the code
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    env = {**os.environ, "PYTHONPATH": str(src), "HOME": str(blocker), "NUMBA_CACHE_DIR": str(blocker / "cache"),
           "PYTHONDONTWRITEBYTECODE": "1"}
    code = ("import warnings\nfrom baseparams.cli import _one_line_notes\n_one_line_notes()\n"
            "from baseparams.regressor import compiled\nk = compiled._kernels()\nprint(k.CACHE)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 0 and r.stdout.strip() == "False" and "Traceback" not in r.stderr, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("baseparams: note: numba cannot cache"), lines


# ---------------------------------------------------------------- a text column the layout does not read
def test_a_text_column_the_layout_does_not_read_is_ignored_with_a_note(tmp_path):
    import baseparams
    from baseparams.errors import DataError
    from baseparams.io.logs import read_log

    robot = baseparams.load("puma560")
    names = [f"{k}_{j}" for k in ("q", "tau") for j in robot.joint_names]
    rows = [",".join(["t"] + names + ["comment"])]
    rows += [",".join([f"{0.01 * i}"] + ["0.1"] * len(names) + ["warm-up" if i % 2 else "ok, fine"[:2]])
             for i in range(20)]
    f = tmp_path / "log.csv"
    f.write_text("\n".join(rows) + "\n")
    log = read_log(f, robot)
    assert log.n_samples == 20 and any("comment (text)" in n for n in log.notes), log.notes
    bad = rows[:4] + [rows[4].replace("0.1", "oops", 1)] + rows[5:]
    f.write_text("\n".join(bad) + "\n")
    with pytest.raises(DataError, match=r"column 'q_joint1', line 5 \(data row 4\): 'oops' is not a number"):
        read_log(f, robot)


def test_a_model_beyond_the_memory_available_is_refused_before_allocating(monkeypatch):
    """A 10 000-link chain asked for 22 GB inside DRNG; now one line before any allocation."""
    import time

    import numpy as np

    import baseparams
    from baseparams import analysis
    from baseparams.errors import BaseparamsError
    from baseparams.robots.random import random_robot

    # 30 bodies: below the structured certificate's size, the dense check's memory grows as n^2
    robot = random_robot(np.random.default_rng(0), n=30, joint_types="R", branching=0.0)
    monkeypatch.setattr(analysis, "_available_bytes", lambda: 10e6)  # a small machine: 10 MB free
    t0 = time.perf_counter()
    refused = r"30 bodies: the certified analysis needs about 0\.022 GB .* --no-verify"
    with pytest.raises(BaseparamsError, match=refused):
        baseparams.analyze(robot)
    assert time.perf_counter() - t0 < 1.0
    assert baseparams.analyze(robot, verify=False).nullity > 0  # 0.0072 GB: fits
    # a large tree is certified body by body: its need grows with the bodies' depths, refused the same way
    chain = random_robot(np.random.default_rng(0), n=200, joint_types="R", branching=0.0)
    monkeypatch.setattr(analysis, "_available_bytes", lambda: 1e6)
    with pytest.raises(BaseparamsError, match=r"200 bodies: the analysis needs about .* GB and .* available") as auto:
        baseparams.analyze(chain)  # the recursive form (auto from 200 bodies): linear in size, still refused here
    with pytest.raises(BaseparamsError) as expanded:  # issue 51: written from the recursive form, the same need
        baseparams.analyze(chain, form="expanded")
    assert str(expanded.value) == str(auto.value)
