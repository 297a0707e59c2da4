"""Safe output (``baseparams.files``): atomic writes, never onto an input, never a partial file."""

import os
import signal
import subprocess
import sys
import textwrap

import pytest

from baseparams.errors import BaseparamsError
from baseparams.files import atomic_path, refuse_inputs, write_text


def test_an_error_inside_the_block_leaves_the_old_file_and_no_temporary(tmp_path):
    f = tmp_path / "out.csv"
    f.write_text("old\n")
    with pytest.raises(RuntimeError), atomic_path(f) as tmp:
        tmp.write_text("half")
        raise RuntimeError("interrupted")
    assert f.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]


def test_the_temporary_keeps_the_suffix_and_the_result_replaces_the_file(tmp_path):
    f = tmp_path / "out.parquet"
    with atomic_path(f) as tmp:
        assert tmp.suffix == ".parquet" and tmp.parent == tmp_path and tmp != f
        tmp.write_bytes(b"new")
    assert f.read_bytes() == b"new"


@pytest.mark.parametrize("alias", ["same", "relative", "symlink", "hardlink"])
def test_an_output_onto_an_input_is_refused_by_any_name(alias, tmp_path, monkeypatch):
    inp = tmp_path / "robot.urdf"
    inp.write_text("<robot/>")
    monkeypatch.chdir(tmp_path)
    out = {"same": inp, "relative": "robot.urdf", "symlink": tmp_path / "link.urdf",
           "hardlink": tmp_path / "hard.urdf"}[alias]
    if alias == "symlink":
        os.symlink(inp, out)
    if alias == "hardlink":
        os.link(inp, out)
    with pytest.raises(BaseparamsError, match="would overwrite the input"):
        write_text(out, "x", inputs=[str(inp)], what="--output")
    assert inp.read_text() == "<robot/>"
    refuse_inputs(tmp_path / "other.urdf", [inp, None, "puma560"])  # another file, None, a built-in name


def test_a_folder_or_a_missing_folder_is_one_error(tmp_path):
    with pytest.raises(BaseparamsError, match="not a regular file"):
        write_text(tmp_path, "x")
    with pytest.raises(BaseparamsError, match="does not exist"):
        write_text(tmp_path / "no" / "f.txt", "x")


def test_a_killed_writer_never_leaves_a_partial_file(tmp_path):
    f = tmp_path / "log.csv"
    f.write_text("complete old content\n")
    code = textwrap.dedent(f"""
        import sys, time
        from baseparams.files import atomic_path
        with atomic_path({str(f)!r}) as tmp:
            with open(tmp, "w") as fh:
                fh.write("partial " * 1000)
                fh.flush()
                print("writing", flush=True)
                time.sleep(30)
    """)
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "writing"
    p.send_signal(signal.SIGTERM)
    p.wait(timeout=20)
    assert f.read_text() == "complete old content\n"
