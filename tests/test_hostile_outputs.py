"""Outputs against every input, streams as targets, and MJCF files that read what they should not.

* no output of any command lands on any file the run reads: the model, every file the model
  includes (MJCF ``<include>``, meshes; xacro includes), the logs, ``--truth``, ``--columns``, the
  saved result, ``--states`` (by any name: a symbolic link too), refused before any work;
* ``/dev/stdout``, ``/dev/null`` and FIFOs are written as streams (the link ``/dev/stdout`` stays a
  link), a FIFO no one reads is refused at once, a target behind a link is replaced (the link
  kept), a target that cannot be replaced is one line and the old content stays;
* an MJCF include or mesh that is a FIFO, a device or huge, and numbers that make MuJoCo allocate
  gigabytes (``<size nuserdata>``, ``<replicate count>``, textures, height fields) are one line,
  in seconds, before MuJoCo opens anything.
"""

from __future__ import annotations

import errno
import hashlib
import os
import struct
import subprocess
import sys
import threading

import pytest

from hostile import api_error, one_line_error, refused_in_a_subprocess

pytest.importorskip("mujoco")


def _stl(path):
    """A binary STL tetrahedron (a valid mesh for MuJoCo)."""
    v = [(0, 0, 0), (0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.1)]
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    data = b"\0" * 80 + struct.pack("<I", len(faces))
    for f in faces:
        data += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *v[k]) for k in f) + b"\0\0"
    path.write_bytes(data)


MAIN = """<mujoco model="arm">
  <include file="parts/options.xml"/>
  <compiler meshdir="meshes"/>
  <asset><mesh name="tet" file="tet.stl"/></asset>
  <worldbody>
    <body name="b1" pos="0 0 0.1"><joint name="j1" type="hinge" axis="0 0 1"/>
      <inertial pos="0.1 0 0" mass="1" diaginertia="0.01 0.02 0.03"/>
      <geom type="mesh" mesh="tet" contype="0" conaffinity="0"/>
      <body name="b2" pos="0.3 0 0"><joint name="j2" type="hinge" axis="0 1 0"/>
        <inertial pos="0.1 0 0.05" mass="0.5" diaginertia="0.01 0.01 0.01"/></body>
    </body>
  </worldbody>
</mujoco>
"""


def _digest(path) -> str:
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    """An MJCF model with an include and a mesh, its log, truth, column map and saved result."""
    from baseparams.cli import main

    d = tmp_path_factory.mktemp("world")
    (d / "parts").mkdir()
    (d / "meshes").mkdir()
    (d / "parts" / "options.xml").write_text('<mujoco><option timestep="0.002"/></mujoco>\n')
    _stl(d / "meshes" / "tet.stl")
    (d / "main.xml").write_text(MAIN)
    assert main(["simulate", str(d / "main.xml"), str(d / "log.csv"), "--duration", "3", "--rate", "100"]) == 0
    (d / "map.toml").write_text('time = "t"\n')
    assert main(["identify", str(d / "main.xml"), str(d / "log.csv"), "--save", str(d / "res.json")]) == 0
    (d / "states.csv").write_bytes((d / "log.csv").read_bytes())
    return d


INPUTS = ["main.xml", "parts/options.xml", "meshes/tet.stl", "log.csv", "log.csv.truth.json", "map.toml", "res.json",
          "states.csv"]

# (argv with M the model, L the log, ...; the output flag; the suffixes it takes, None: any)
COMMANDS = [
    (["analyze", "M"], "--output", None),
    (["analyze", "M"], "--html", None),
    (["identify", "M", "L", "--truth", "T", "--columns", "C"], "--output", None),
    (["identify", "M", "L", "--truth", "T"], "--html", None),
    (["identify", "M", "L", "--truth", "T"], "--save", None),
    (["identify", "M", "L", "--truth", "T", "--holdout", "1"], "--predictions", (".csv", ".tsv", ".parquet")),
    (["identify", "M", "L", "--truth", "T", "--method", "physical"], "--mjcf", (".xml",)),
    (["predict", "M", "R", "L"], "--out", (".csv", ".tsv", ".parquet")),
    (["simulate", "M", "OUT", "--trajectory", "L"], None, (".csv", ".tsv", ".npz")),
    (["excite", "M"], "--out", (".csv", ".tsv")),
    (["excite", "M"], "--output", None),
    (["regressor", "M", "--states", "S"], "--out", (".csv", ".tsv", ".parquet", ".npz")),
]


def _argv(world, argv, flag, target):
    names = {"M": "main.xml", "L": "log.csv", "T": "log.csv.truth.json", "C": "map.toml", "R": "res.json",
             "S": "states.csv"}
    out = [str(world / names[a]) if a in names else a for a in argv]
    if flag is None:
        return [str(target) if a == "OUT" else a for a in out]
    return out + [flag, str(target)]


def _reads(world, argv) -> set[str]:
    """The inputs a command line reads: the model's files always, the others when named."""
    named = {a for a in argv if a in ("L", "T", "C", "R", "S")}
    files = {"main.xml", "parts/options.xml", "meshes/tet.stl"}
    files |= {f for k, f in (("L", "log.csv"), ("T", "log.csv.truth.json"), ("C", "map.toml"), ("R", "res.json"),
                             ("S", "states.csv")) if k in named}
    return files


CASES = [(k, name) for k, (argv, flag, suffixes) in enumerate(COMMANDS) for name in INPUTS
         if name in _reads(None, argv) and (suffixes is None or os.path.splitext(name)[1] in suffixes)]


@pytest.mark.parametrize("k, name", CASES, ids=[f"{COMMANDS[k][0][0]}-{COMMANDS[k][1] or 'OUT'}-{n}" for k, n in CASES])
@pytest.mark.parametrize("alias", [False, True], ids=["path", "link"])
def test_no_output_lands_on_an_input(world, capsys, k, name, alias, tmp_path):
    argv, flag, _ = COMMANDS[k]
    target = world / name
    if alias:  # the same file by another name
        link = tmp_path / ("alias" + os.path.splitext(name)[1])
        link.symlink_to(target)
        target = link
    before = {n: _digest(world / n) for n in INPUTS}
    err = one_line_error(_argv(world, argv, flag, target), capsys, seconds=30)
    assert "would overwrite the input" in err, err
    assert {n: _digest(world / n) for n in INPUTS} == before


def test_the_guard_sees_xacro_includes(tmp_path, capsys):
    pytest.importorskip("xacro")
    (tmp_path / "arm.xacro").write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:macro name="arm">'
        '<link name="base"/><link name="l1"><inertial><mass value="1"/>'
        '<inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/></joint>'
        '</xacro:macro></robot>\n')
    (tmp_path / "robot.urdf.xacro").write_text(
        '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:include filename="arm.xacro"/>'
        '<xacro:arm/></robot>\n')
    before = _digest(tmp_path / "arm.xacro")
    err = one_line_error(["analyze", tmp_path / "robot.urdf.xacro", "--output", tmp_path / "arm.xacro"], capsys)
    assert "would overwrite the input" in err and "arm.xacro" in err
    assert _digest(tmp_path / "arm.xacro") == before


def test_api_outputs_see_the_model_files(world):
    import baseparams

    msg = api_error(baseparams.identify, str(world / "main.xml"), str(world / "log.csv"),
                    save=str(world / "parts" / "options.xml"))
    assert "would overwrite the input" in msg


# ---------------------------------------------------------------- streams and links as targets
def test_dev_stdout_is_written_as_a_stream_and_stays_a_link(tmp_path):
    link = os.readlink("/dev/stdout") if os.path.islink("/dev/stdout") else None
    out = tmp_path / "captured.txt"
    with open(out, "w") as fh:
        r = subprocess.run([sys.executable, "-m", "baseparams", "analyze", "puma560", "--html", "/dev/stdout"],
                           stdout=fh, stderr=subprocess.PIPE, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    text = out.read_text()
    assert "<html" in text.lower() and "puma560" in text
    assert (os.readlink("/dev/stdout") if os.path.islink("/dev/stdout") else None) == link


@pytest.mark.parametrize("flag", ["--output", "--html"])
def test_dev_null_takes_the_output(flag, capsys):
    from baseparams.cli import main

    assert main(["analyze", "puma560", flag, "/dev/null"]) == 0
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")


def test_a_fifo_nobody_reads_is_refused_at_once_and_one_that_is_read_gets_the_content(tmp_path, capsys):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    err = one_line_error(["analyze", "puma560", "--output", fifo], capsys, seconds=20)
    assert "no process reads it" in err
    got = []
    def read():
        with open(fifo, "rb") as fh:
            got.append(fh.read())
    reader = threading.Thread(target=read)
    reader.start()
    import time

    from baseparams.cli import main

    for _ in range(100):  # the reader opens the FIFO first
        time.sleep(0.02)
        if main(["analyze", "puma560", "--output", str(fifo)]) == 0:
            break
    reader.join(10)
    assert got and b"36 base parameters" in got[0]


def test_a_link_to_a_file_replaces_the_file_and_keeps_the_link(tmp_path, capsys):
    from baseparams.cli import main

    real = tmp_path / "real.txt"
    real.write_text("old\n")
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    assert main(["analyze", "puma560", "--output", str(link)]) == 0
    assert link.is_symlink() and "36 base parameters" in real.read_text()
    dangling = tmp_path / "new-link.txt"
    dangling.symlink_to(tmp_path / "created.txt")
    assert main(["analyze", "puma560", "--output", str(dangling)]) == 0
    assert dangling.is_symlink() and (tmp_path / "created.txt").is_file()


@pytest.mark.parametrize("target", ["/dev/baseparams-no-such-file.txt", "/proc/baseparams.txt"])
def test_no_new_file_in_system_folders(target, capsys):
    err = one_line_error(["analyze", "puma560", "--output", target], capsys)
    assert "no new file is created" in err and not os.path.exists(target)


def test_a_target_that_cannot_be_replaced_is_one_line_and_keeps_its_content(tmp_path, capsys, monkeypatch):
    from baseparams import files

    out = tmp_path / "report.txt"
    out.write_text("kept\n")

    def immutable(src, dst):
        raise PermissionError(errno.EPERM, "Operation not permitted", str(dst))
    monkeypatch.setattr(files.os, "replace", immutable)
    err = one_line_error(["analyze", "puma560", "--output", out], capsys)
    assert "Operation not permitted" in err and "nothing was written" in err
    assert out.read_text() == "kept\n" and [p.name for p in tmp_path.iterdir()] == ["report.txt"]


def test_an_immutable_file_for_real_when_the_system_allows_it(tmp_path):
    out = tmp_path / "report.txt"
    out.write_text("kept\n")
    if subprocess.run(["chattr", "+i", str(out)], capture_output=True).returncode != 0:
        pytest.skip("chattr +i is not allowed here (needs CAP_LINUX_IMMUTABLE)")
    try:
        err = refused_in_a_subprocess(["analyze", "puma560", "--output", out])
        assert "cannot write" in err and out.read_text() == "kept\n"
    finally:
        subprocess.run(["chattr", "-i", str(out)], capture_output=True)


# ---------------------------------------------------------------- MJCF files that read what they should not
def _mjcf(tmp_path, head="", body="", name="m.xml"):
    f = tmp_path / name
    f.write_text(f'<mujoco model="m">{head}<worldbody><body name="b1"><joint name="j1" type="hinge"/>'
                 f'<inertial pos="0 0 0.1" mass="1" diaginertia="0.1 0.1 0.1"/>{body}</body></worldbody></mujoco>\n')
    return f


def _fifo(p):
    os.mkfifo(p)
    return p


def _sparse(p, size):
    with open(p, "wb") as fh:
        fh.truncate(size)
    return p


MJCF_ATTACKS = {
    "include fifo": (lambda d: (_fifo(d / "inc.xml"), '<include file="inc.xml"/>', "")[1:], "not a regular file"),
    "include dev zero": (lambda d: ((d / "inc.xml").symlink_to("/dev/zero"), '<include file="inc.xml"/>', "")[1:],
                         "not a regular file"),
    "mesh fifo": (lambda d: (_fifo(d / "a.stl"), '<asset><mesh name="a" file="a.stl"/></asset>',
                             '<geom type="mesh" mesh="a"/>')[1:], "not a regular file"),
    "texture dev zero": (lambda d: ((d / "t.png").symlink_to("/dev/zero"),
                                    '<asset><texture name="t" type="2d" file="t.png"/></asset>', "")[1:],
                         "not a regular file"),
    "huge mesh": (lambda d: (_sparse(d / "a.stl", 300 * 2**20),
                             '<asset><mesh name="a" file="a.stl"/></asset>', "")[1:], "larger than"),
    "nuserdata": (lambda d: ('<size nuserdata="650000000"/>', ""), "nuserdata"),
    "memory": (lambda d: ('<size memory="8G"/>', ""), "memory"),
    "nstack": (lambda d: ('<size nstack="10000000000"/>', ""), "nstack"),
    "replicate": (lambda d: ("", '<replicate count="1000000"><body name="r"><geom size="0.1"/></body></replicate>'),
                  "replicate"),
    "nested replicate": (lambda d: ("", '<replicate count="1000"><replicate count="1000"><body name="r">'
                                        '<geom size="0.1"/></body></replicate></replicate>'), "replicate"),
    "texture pixels": (lambda d: ('<asset><texture name="t" type="2d" builtin="checker" width="100000" '
                                  'height="100000"/></asset>', ""), "pixels"),
    "hfield": (lambda d: ('<asset><hfield name="h" nrow="100000" ncol="100000" size="1 1 1 1"/></asset>', ""),
               "samples"),
}


@pytest.mark.parametrize("case", list(MJCF_ATTACKS))
def test_mjcf_attacks_are_one_line_in_seconds(case, tmp_path, capsys):
    make, words = MJCF_ATTACKS[case]
    head, body = make(tmp_path)
    f = _mjcf(tmp_path, head, body)
    err = one_line_error(["analyze", f], capsys, seconds=20)
    assert str(tmp_path) in err and words in err, err


@pytest.mark.parametrize("case", ["nuserdata", "replicate", "include fifo"])
def test_mjcf_attacks_in_a_bounded_subprocess(case, tmp_path):
    make, words = MJCF_ATTACKS[case]
    head, body = make(tmp_path)
    f = _mjcf(tmp_path, head, body)
    assert words in refused_in_a_subprocess(["analyze", f], seconds=60)


def test_include_cycles_and_deep_chains(tmp_path, capsys):
    (tmp_path / "a.xml").write_text('<mujoco><include file="b.xml"/></mujoco>')
    (tmp_path / "b.xml").write_text('<mujoco><include file="a.xml"/></mujoco>')
    f = _mjcf(tmp_path, '<include file="a.xml"/>')
    one_line_error(["analyze", f], capsys, seconds=20)
    for k in range(40):
        (tmp_path / f"c{k}.xml").write_text(f'<mujoco><include file="c{k + 1}.xml"/></mujoco>' if k < 39 else
                                            "<mujoco/>")
    f = _mjcf(tmp_path, '<include file="c0.xml"/>', name="deep.xml")
    err = one_line_error(["analyze", f], capsys, seconds=20)
    assert "nested more than" in err or "include" in err.lower(), err


def test_a_urdf_mesh_that_is_a_fifo_is_refused_before_mujoco_imports_it(tmp_path):
    from baseparams.io.sources import check_urdf_meshes

    _fifo(tmp_path / "m.stl")
    f = tmp_path / "r.urdf"
    f.write_text('<robot name="r"><link name="a"><visual><geometry><mesh filename="m.stl"/></geometry></visual>'
                 '</link></robot>')
    msg = api_error(check_urdf_meshes, f)
    assert "m.stl" in msg and "not a regular file" in msg


@pytest.mark.parametrize("target", ["/dev/stdin", "/dev/fd/0", "/proc/self/fd/0"])
def test_the_standard_input_is_not_an_output(target, capsys):
    err = one_line_error(["analyze", "puma560", "--output", target], capsys)
    assert "the standard input is not an output" in err


# ---------------------------------------------------------------- interrupts of a streamed identification (issue 51)
_SWALLOW = """
import os, signal, time
import baseparams.io.logs as logs
_parse, _calls = logs._fast_block, []
def _swallowing(*a, **k):  # what pyarrow importing pandas lazily did with a SIGINT in pass 1's first block
    _calls.append(1)
    if len(_calls) == 1:
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.5)
        except KeyboardInterrupt:
            pass
    return _parse(*a, **k)
logs._fast_block = _swallowing
"""


@pytest.fixture(scope="module")
def streamed(tmp_path_factory):
    """A 12 MB CSV log identified with --stream on in a few seconds (several blocks per pass)."""
    import baseparams
    from baseparams.ident.simulate import simulate_log
    from baseparams.io.logs import write_log

    folder = tmp_path_factory.mktemp("streamed")
    log, _ = simulate_log(baseparams.load("puma560"), duration=60.0, rate=500.0, noise=0.01, seed=3)
    return write_log(folder / "log.csv", log)


_SLOW_AFTER_A_LINE = """
import time
import baseparams.cli.common as common
import baseparams.ident.stream as stream
_said, _call, _check = [], common.Progress.__call__, stream.Interrupts.check  # the class of baseparams.interrupts
def _call_and_mark(self, msg):  # a line printed: the next check waits longer than any signal's delay
    _said.append(1)
    return _call(self, msg)
def _check_slowly(self):
    if _said:
        _said.clear()
        time.sleep(0.6)
    return _check(self)
common.Progress.__call__, stream.Interrupts.check = _call_and_mark, _check_slowly
"""


_SLOW_LINES = """
import time
import baseparams.cli.common as common
_call = common.Progress.__call__
def _call_slowly(self, msg):  # every progress line followed by a pause longer than any signal's delay
    _call(self, msg)
    time.sleep(0.6)
common.Progress.__call__ = _call_slowly
"""


def _interrupted(streamed, tmp_path, marker=None, delay=0.0, sig=None, preamble="", stream="on"):
    """``identify --stream on`` with every output in a subprocess, signalled ``delay`` s after the progress line
    containing ``marker``: ``(exit code, stderr, files left in the output folder, files left in TMPDIR)``."""
    import signal
    import time

    out, tmp = tmp_path / "out", tmp_path / "tmp"
    out.mkdir()
    tmp.mkdir()
    argv = ["identify", "puma560", str(streamed), "-v", "--stream", stream, "--holdout", "15", "--save",
            str(out / "r.json"), "--predictions", str(out / "p.csv"), "--html", str(out / "r.html")]
    code = preamble + f"\nimport sys\nfrom baseparams.cli import main\nsys.exit(main({argv!r}))\n"
    env = {**os.environ, "TMPDIR": str(tmp), "OPENBLAS_NUM_THREADS": "1"}
    p = subprocess.Popen([sys.executable, "-c", code], stderr=subprocess.PIPE, text=True, env=env, cwd=out)
    seen = []
    for line in p.stderr:
        seen.append(line)
        if marker is not None and marker in line:
            time.sleep(delay)
            p.send_signal(sig or signal.SIGINT)
            break
    rest = p.stderr.read()
    rc = p.wait(timeout=120)
    return rc, "".join(seen) + rest, sorted(os.listdir(out)), sorted(os.listdir(tmp))


def test_a_sigint_swallowed_by_a_library_in_the_first_pass_still_stops_the_run(streamed, tmp_path):
    """Issue 51: SIGINT 0.05 s into the first pass was swallowed (pyarrow's lazy pandas import caught the
    KeyboardInterrupt) and the run went on to exit 0. The signal is remembered: the next block stops the run."""
    from baseparams.cli import EXIT_INTERRUPTED

    rc, err, left, tmp = _interrupted(streamed, tmp_path, preamble=_SWALLOW)
    assert rc == EXIT_INTERRUPTED and "baseparams: interrupted" in err, (rc, err[-500:])
    assert "pass 2" not in err and left == [] and tmp == [], (left, tmp)


@pytest.mark.slow
@pytest.mark.parametrize("name, marker, delay", [
    *(("SIGINT", m, d) for m, d in [("pass 1", 0.05), ("pass 1", 0.3), ("pass 2", 0.05), ("pass 3", 0.05),
                                    ("pass 3", 0.5), ("fitting", 0.05), ("pass 5", 0.05), ("pass 5", 0.4)]),
    ("SIGTERM", "pass 1", 0.05), ("SIGTERM", "pass 3", 0.3), ("SIGTERM", "pass 5", 0.1)])
def test_an_interrupt_at_any_moment_of_a_streamed_run_leaves_nothing(streamed, tmp_path, marker, delay, name):
    """SIGINT (or SIGTERM) at several moments of every pass: exit EXIT_INTERRUPTED (or 143), no output written,
    no temporary file left (the outputs' nor the passes')."""
    import signal

    from baseparams.cli import EXIT_INTERRUPTED
    from baseparams.interrupts import EXIT_TERMINATED

    # every line shown at once (-v) and the step after it slowed (a fast machine finished the run before the signal)
    rc, err, left, tmp = _interrupted(streamed, tmp_path, marker, delay, getattr(signal, name), _SLOW_AFTER_A_LINE)
    assert rc == (EXIT_INTERRUPTED if name == "SIGINT" else EXIT_TERMINATED), (rc, err[-800:])
    assert "Traceback" not in err and left == [] and tmp == [], (left, tmp, err[-500:])


@pytest.mark.slow
@pytest.mark.parametrize("name, marker", [("SIGINT", "validating on"), ("SIGTERM", "reading"),
                                          ("SIGTERM", "cross-validating tilt")])
def test_an_interrupt_of_a_run_read_whole_leaves_nothing(streamed, tmp_path, name, marker):
    """Issue 51: outside a streamed run SIGTERM ended the process at once (exit -15, an output's temporary
    file left behind, nothing said). The command line's guard: exit 130 (143), one line, no file left."""
    import signal

    from baseparams.cli import EXIT_INTERRUPTED
    from baseparams.interrupts import EXIT_TERMINATED

    rc, err, left, tmp = _interrupted(streamed, tmp_path, marker, 0.1, getattr(signal, name), _SLOW_LINES, "off")
    said = "baseparams: interrupted" if name == "SIGINT" else "baseparams: terminated (SIGTERM)"
    assert rc == (EXIT_INTERRUPTED if name == "SIGINT" else EXIT_TERMINATED), (rc, err[-800:])
    assert said in err and "Traceback" not in err and left == [] and tmp == [], (left, tmp, err[-500:])


def test_an_uninterrupted_streamed_run_writes_every_output(streamed, tmp_path):
    rc, err, left, tmp = _interrupted(streamed, tmp_path)
    assert rc == 0 and left == ["p.csv", "r.html", "r.json"] and tmp == [], (rc, left, tmp, err[-500:])


@pytest.mark.parametrize("module", ["baseparams", "baseparams.cli"])
def test_an_interrupt_while_the_package_imports_is_one_line(module, tmp_path):
    """Ctrl-C in the ~0.2 s the command line spends importing (before its handler exists) was a 40-line traceback:
    a KeyboardInterrupt raised inside the package's own imports (deterministically: from the import of a submodule
    the package imports) prints one line and keeps the interrupt's exit status; importing the package as a library
    leaves the interpreter's hook as it was."""
    import signal

    hook = tmp_path / "sitecustomize.py"  # interrupts the import of baseparams.model (imported by the package)
    hook.write_text("import sys\nclass _F:\n    def find_spec(self, name, path=None, target=None):\n"
                    "        if name == 'baseparams.model':\n            raise KeyboardInterrupt\n        return None\n"
                    "sys.meta_path.insert(0, _F())\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}
    p = subprocess.run([sys.executable, "-c", f"import {module}"], env=env, capture_output=True, text=True, timeout=60)
    assert p.returncode in (-signal.SIGINT, 130), p.stderr
    assert p.stderr.strip().splitlines() == ["baseparams: interrupted while starting (nothing was written)"]
    done = subprocess.run([sys.executable, "-c", f"import sys, {module}; print(sys.excepthook is sys.__excepthook__)"],
                          capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == "True", done.stderr  # a program importing it keeps its hook
