"""The command line: help, robots, analyze (human and JSON), one-line errors."""

import json
import subprocess
import sys

import pytest

from baseparams.cli import main


def run(args, capsys):
    code = main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_help_lists_commands(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    assert "analyze" in out and "robots" in out


def test_robots(capsys):
    code, out, _ = run(["robots"], capsys)
    assert code == 0 and "puma560" in out and "go2" in out


def test_analyze_json_schema(capsys):
    code, out, _ = run(["analyze", "puma560", "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    for key in ("model", "n_bodies", "n_params", "gravity", "floating", "nullity", "n_base", "drng",
                "numerical", "certified", "completed", "residual", "base_parameters"):
        assert key in d
    assert d["nullity"] == 24 and d["n_base"] == 36 and d["certified"] is True
    assert d["drng"]["rank"] == 24 and d["numerical"]["samples"] == 100 and d["numerical"]["sv_gap"] > 1e8
    assert len(d["base_parameters"]) == 36 and {"name", "expression"} <= set(d["base_parameters"][0])


def test_analyze_zero_gravity_completes(capsys):
    """Gravity zero: the paper's principles miss 2 directions (numerical completion) and R-A
    (the intersection of axes 1 and 2 never moves) finds them geometrically."""
    code, out, _ = run(["analyze", "puma560", "--gravity", "0", "0", "0", "--json", "--paper-only"], capsys)
    d = json.loads(out)
    assert d["nullity"] == 26 and d["completed"] == 2 and d["status"] == "completed"
    assert d["gravity"] == [0.0, 0.0, 0.0] and d["drng"]["complete"] is False
    code, out, _ = run(["analyze", "puma560", "--gravity", "0", "0", "0", "--json"], capsys)
    d = json.loads(out)
    assert d["nullity"] == 26 and d["completed"] == 0 and d["status"] == "certified"
    assert d["drng"]["complete"] is True and d["drng"]["extended"] is True
    assert d["drng"]["by_rule"] == {"shared points": 18, "fixed points": 4, "planar rotations": 2,
                                    "R-A fixed vectors": 2, "R-B sliding points": 0,
                                    "R-L1 parallelograms": 0, "R-L2 level chains": 0, "R-L3 planar loops": 0,
                                    "R-L4 spatial parallelograms": 0,
                                    "R-M coupled joints": 0, "R-C compound joints": 0,
                                    "numerical": 0}
    assert d["drng"]["by_principle"] == {"shared points": 18, "fixed points": 4, "planar rotations": 2}


def test_analyze_human_report_and_output_file(tmp_path, capsys):
    f = tmp_path / "r.txt"
    code, out, _ = run(["analyze", "go2", "--output", str(f)], capsys)
    assert code == 0
    text = f.read_text()
    assert "94 base parameters" in text and "CERTIFIED" in text and "shared points" in text


def test_no_verify(capsys):
    code, out, _ = run(["analyze", "puma560", "--no-verify", "--json"], capsys)
    d = json.loads(out)
    assert d["certified"] is False and d["status"] == "unverified" and d["nullity"] == 24


def test_errors_are_one_line(capsys):
    code, out, err = run(["analyze", "no-such-robot"], capsys)
    assert code == 2
    assert err.strip().count("\n") == 0 and "no-such-robot: no such file, and not a built-in robot" in err
    r = subprocess.run([sys.executable, "-m", "baseparams.cli", "analyze", "go2", "--rows", "base",
                        "--samples", "0"], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    code, out, err = run(["analyze", "puma560", "--rows", "base"], capsys)
    assert code == 2 and "no floating base" in err and "Traceback" not in err


def test_analyze_loop_model_json(capsys):
    code, out, _ = run(["analyze", "four-bar", "--samples", "500", "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert d["nullity"] == 22 and d["n_base"] == 8 and d["certified"] is True
    assert d["numerical"]["sampling"]["kept"] > 400


def test_loop_model_rejects_rows(capsys):
    code, out, err = run(["analyze", "four-bar", "--rows", "joints"], capsys)
    assert code == 2 and "rows" in err and "Traceback" not in err


#: modules ``analyze`` must not import (issue 25: start-up time; each costs 10-80 ms)
NOT_FOR_ANALYZE = ("scipy", "numpy.ma", "sympy", "numba", "pinocchio", "matplotlib")


def _modules_after(argv: list[str]) -> set[str]:
    """The modules loaded by a fresh ``baseparams`` process running ``argv`` (its JSON checked)."""
    code = ("import json, sys, contextlib, io\nfrom baseparams.cli import main\nbuf = io.StringIO()\n"
            f"with contextlib.redirect_stdout(buf):\n    rc = main({argv!r})\n"
            "assert rc == 0 and json.loads(buf.getvalue())['status'] == 'certified'\nprint(' '.join(sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-500:]
    return set(r.stdout.split())


def _heavy(mods: set[str], heavy) -> list[str]:
    return sorted(m for m in mods if any(m == h or m.startswith(h + ".") for h in heavy))


def test_analyze_imports_only_what_it_needs():
    """A built-in tree: no file readers, loop closure or structured certificate; no scipy."""
    mods = _modules_after(["analyze", "puma560", "--json"])
    assert not _heavy(mods, NOT_FOR_ANALYZE + ("baseparams.io", "baseparams.kinematics.loops",
                                               "baseparams.nullspace.structured", "baseparams.nullspace.coupled",
                                               "baseparams.robots.random",
                                               "baseparams.ident", "baseparams.symbolic"))


def test_analyze_of_a_coupled_urdf_imports_no_scipy():
    """talos_full_v2 (URDF, 12 ``<mimic>``): the structured certificate and regrouping, still no scipy."""
    from erd import urdf_files

    found = [f for f in urdf_files() if f.name == "talos_full_v2.urdf"]
    if not found:
        pytest.skip("example-robot-data not installed")
    mods = _modules_after(["analyze", str(found[0]), "--floating", "--json"])
    assert not _heavy(mods, NOT_FOR_ANALYZE + ("baseparams.io.mjcf", "baseparams.ident", "baseparams.symbolic"))
    assert "baseparams.nullspace.structured" in mods
