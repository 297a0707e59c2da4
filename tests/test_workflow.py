"""``baseparams simulate`` / ``excite`` are thin layers over ``bp.simulate`` / ``bp.excite`` (issue 38)."""

import json

import numpy as np
import pytest

import baseparams as bp
from baseparams.cli import build_parser, main


def test_simulate_on_the_command_line_writes_what_bp_simulate_writes(tmp_path, capsys):
    """One implementation: the same files, byte for byte, from the flags and from the keywords."""
    cli, api = tmp_path / "cli.csv", tmp_path / "api.csv"
    assert main(["simulate", "puma560", str(cli), "--duration", "2", "--rate", "100", "--noise", "0.1", "--rotor",
                 "--friction", "viscous,offset", "--seed", "7", "--amplitude", "0.3"]) == 0
    capsys.readouterr()
    bp.simulate("puma560", duration=2, rate=100, noise=0.1, rotor=True, friction="viscous,offset", seed=7,
                amplitude=0.3, out=api)
    assert cli.read_bytes() == api.read_bytes()
    assert (tmp_path / "cli.csv.truth.json").read_bytes() == (tmp_path / "api.csv.truth.json").read_bytes()


def test_excite_on_the_command_line_is_bp_excite(tmp_path, capsys):
    cli, api = tmp_path / "cli.csv", tmp_path / "api.csv"
    assert main(["excite", "puma560", "--harmonics", "3", "--period", "4", "--rate", "50", "--starts", "1",
                 "--grid", "60", "--velocity", "1.5", "--out", str(cli), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    ex = bp.excite("puma560", harmonics=3, period=4, rate=50, starts=1, grid=60, velocity=1.5, out=api)
    assert cli.read_bytes() == api.read_bytes()
    api_doc = json.loads(json.dumps(ex.to_json()))
    assert {k: v for k, v in doc.items() if k != "notes"} == {k: v for k, v in api_doc.items() if k != "notes"}
    assert np.abs(ex.dq).max() <= 1.5 + 1e-9


def test_every_simulate_and_excite_flag_is_a_keyword():
    """The command's options (but output formatting and model loading) are the function's keywords."""
    import inspect

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices
    cli_only = {"help", "model", "json", "output", "verbose", "floating", "gravity", "strict_inertia", "xacro_args",
                "package_path", "old_samples", "func", "command", "out", "allow_infeasible_inertia", "mocap_welds",
                # identify: the logs, and a fleet on Dask (--per-file / --pooled: baseparams.fleet.identify_fleet)
                "data", "per_file", "pooled", "strict", "scheduler", "workers"}
    renamed = {"samples": "analysis_samples", "coupling": "couplings"}
    for name, fn in (("simulate", bp.simulate), ("excite", bp.excite), ("identify", bp.identify)):
        keywords = set(inspect.signature(fn).parameters)
        dests = {a.dest for a in sub[name]._actions} - cli_only
        missing = {d for d in dests if renamed.get(d, d) not in keywords}
        assert not missing, (name, missing)


def test_seed_draws_the_same_robot_with_and_without_a_trajectory(tmp_path, capsys):
    """``simulate --seed S``: the drive terms (friction, rotor) are the seed's whether the motion is drawn or given."""
    drawn, given = tmp_path / "drawn.csv", tmp_path / "given.csv"
    traj = tmp_path / "traj.csv"
    bp.excite("puma560", harmonics=3, period=4, rate=50, starts=1, grid=60, out=traj)
    assert main(["simulate", "puma560", str(drawn), "--seed", "5", "--rotor", "--duration", "2"]) == 0
    assert main(["simulate", "puma560", str(given), "--seed", "5", "--rotor", "--trajectory", str(traj)]) == 0
    capsys.readouterr()
    a, b = (json.loads((tmp_path / f"{n}.csv.truth.json").read_text()) for n in ("drawn", "given"))
    assert a["drives"] == b["drives"] and a["parameters"] == b["parameters"]
    other = bp.simulate("puma560", duration=2, rotor=True, seed=6)[1]
    assert other["drives"] != a["drives"]  # the seed does matter


@pytest.mark.parametrize("kw, words", [({"robots": 2}, "give out="),
                                       ({"robots": 0, "out": "x"}, "robots= must be an integer")])
def test_fleet_keyword_bad_input(kw, words):
    with pytest.raises(bp.BaseparamsError, match=words):
        bp.simulate("puma560", **kw)


def test_fleet_keyword_writes_the_fleet(tmp_path):
    paths, truth = bp.simulate("puma560", duration=1, rate=100, robots=2, rotor=True, out=tmp_path / "fleet")
    assert truth is None and len(paths) == 2 and all(p.is_file() for p in paths)
    one = json.loads(paths[0].with_name(paths[0].name + ".truth.json").read_text())
    assert any(n.startswith("Ia_") for n in one["drives"])  # rotor= reaches every robot of the fleet


@pytest.mark.slow
def test_excite_and_identify_report_one_condition_number_for_one_motion(tmp_path, capsys):
    """The design's condition number and identify's for a log of that design are one measure (the
    motion's regressor, column-scaled, unweighted, every sample): equal to rounding; the fitted rows'
    (filtered, decimated, weighted) is reported beside it under its own name, and saved."""
    traj, log = tmp_path / "traj.csv", tmp_path / "log.csv"
    ex = bp.excite("puma560", drives=True, harmonics=3, starts=1, grid=100, rate=500, out=traj)
    assert main(["simulate", "puma560", str(log), "--trajectory", str(traj), "--noise", "0.01"]) == 0
    capsys.readouterr()
    assert main(["identify", "puma560", str(log), "--json", "--save", str(tmp_path / "res.json")]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["excitation"]["of"] == "motion"
    assert doc["condition_number"] == doc["excitation"]["condition_number"]
    assert abs(doc["condition_number"] / ex.condition_number - 1) < 1e-3, (doc["condition_number"], ex.condition_number)
    fitted = doc["excitation"]["fitted_condition_number"]
    assert abs(fitted / ex.condition_number - 1) > 1e-3  # a different measure, named apart
    back = bp.Identification.load(tmp_path / "res.json", bp.load("puma560"))
    assert back.to_json()["condition_number"] == doc["condition_number"]
    assert main(["identify", "puma560", str(log)]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert f"condition number {doc['condition_number']:.4g} (of the motion" in head and f"{fitted:.4g})" in head
