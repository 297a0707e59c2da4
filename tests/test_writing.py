"""Safe output (``baseparams.files``): atomic writes, never onto an input, never a partial file."""

import ast
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import baseparams
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


_WRITERS = {"write_text", "write_bytes", "savefig", "to_parquet", "to_csv", "savez", "savez_compressed",
            "write_table", "tofile"}


def _temporary(node) -> bool:
    """The written target is a temporary of ``files.atomic_path`` (by the project's naming) or an open handle."""
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "str" and node.args:
        return _temporary(node.args[0])
    return isinstance(node, ast.Name) and (node.id.startswith("tmp") or node.id in ("fh", "buf", "pw"))


def _direct_writes(path: Path) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.Call):
            continue
        f, first = node.func, (node.args[0] if node.args else None)
        if isinstance(f, ast.Attribute) and f.attr in _WRITERS:
            ok = _temporary(f.value) or any(_temporary(a) for a in node.args[:2])
        elif isinstance(f, ast.Name) and f.id == "open":
            mode = node.args[1] if len(node.args) > 1 else next((k.value for k in node.keywords if k.arg == "mode"),
                                                                  None)
            writes = isinstance(mode, ast.Constant) and any(c in str(mode.value) for c in "wax+")
            ok = not writes or (first is not None and _temporary(first))
        else:
            continue
        if not ok:
            found.append(f"{path.name}:{node.lineno}: {ast.unparse(node)[:90]}")
    return found


def test_every_writer_of_the_package_goes_through_the_atomic_writer():
    # the class of problem, not one input: a file is written only to a temporary of files.atomic_path
    # (then renamed), so no writer can leave a partial file under the final name or write onto an input
    src = Path(baseparams.__file__).parent
    offenders = [w for p in sorted(src.rglob("*.py")) if p.name != "files.py" for w in _direct_writes(p)]
    assert offenders == []


def test_the_scan_finds_a_direct_write(tmp_path):
    # the scan above is not vacuous
    bad = tmp_path / "bad.py"
    bad.write_text("import json\nfrom pathlib import Path\nPath('x').write_text('y')\nopen(out, 'w')\n"
                   "fig.savefig(path)\nwith open(tmp, 'w') as fh: fh.write('ok')\n")
    assert [w.split(":")[1] for w in _direct_writes(bad)] == ["3", "4", "5"]
