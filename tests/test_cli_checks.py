"""Issue 29: flags, extras and output paths checked before the long work; per-subcommand help;
--analysis-samples; the --floating hint; baseparams.regressor(backend=, out=)."""

import importlib.metadata
import json
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import baseparams
from baseparams.cli import build_parser, main
from baseparams.regressor import compiled


def run(args, capsys):
    code = main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


def _missing(monkeypatch, *modules):
    """Make ``import MODULE`` fail, as without the extra."""
    for m in modules:
        monkeypatch.setitem(sys.modules, m, None)


def _no_work(monkeypatch):
    """Fail the test if the design or the fit starts."""
    def boom(*a, **k):
        raise AssertionError("the long work started")

    monkeypatch.setattr("baseparams.excitation.design_excitation", boom)
    monkeypatch.setattr("baseparams.ident.identify", boom)


def test_excite_plot_without_matplotlib_refused_at_once(tmp_path, capsys, monkeypatch):
    _missing(monkeypatch, "matplotlib", "matplotlib.pyplot")
    _no_work(monkeypatch)
    out, plot = tmp_path / "traj.csv", tmp_path / "traj.png"
    t0 = time.perf_counter()
    code, _, err = run(["excite", "puma560", "--out", str(out), "--plot", str(plot)], capsys)
    assert time.perf_counter() - t0 < 5
    assert code == 2 and "--plot needs matplotlib" in err and "baseparams[plot]" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("extra, argv, words", [
    ("cvxpy", ["identify", "puma560", "LOG.csv", "--method", "physical"], "--method physical needs cvxpy"),
    ("pyarrow", ["identify", "puma560", "LOG.parquet"], "reading Parquet needs pyarrow"),
    ("matplotlib", ["identify", "puma560", "LOG.csv", "--plot", "OUT.png"], "--plot needs matplotlib"),
    ("matplotlib", ["analyze", "puma560", "--plot", "OUT.png"], "--plot needs matplotlib"),
])
def test_missing_extra_refused_before_work(extra, argv, words, tmp_path, capsys, monkeypatch):
    _missing(monkeypatch, extra)
    _no_work(monkeypatch)
    argv = [str(tmp_path / a) if a.isupper() or "." in a and a.split(".")[0].isupper() else a for a in argv]
    code, _, err = run(argv, capsys)
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("model, method, words", [
    ("puma560", "physical", "needs a URDF model file"),
    ("MODEL.xml", "physical", "needs a URDF model file"),
    ("MODEL.urdf", "wls", "--urdf needs --method physical"),
])
def test_identify_urdf_refused_before_the_fit(model, method, words, tmp_path, capsys, monkeypatch):
    _no_work(monkeypatch)
    if model.startswith("MODEL"):
        model = str(tmp_path / model)
        Path(model).write_text("<robot/>")
    code, _, err = run(["identify", model, str(tmp_path / "log.csv"), "--method", method, "--urdf",
                        str(tmp_path / "out.urdf")], capsys)
    assert code == 2 and words in err and "nothing was fitted" in err
    assert not (tmp_path / "out.urdf").exists()


@pytest.mark.parametrize("argv, words", [
    (["identify", "puma560", "LOG", "--output", "LOG"], "would overwrite the input"),
    (["excite", "puma560", "--out", "DIR"], "the format comes from the suffix"),
    (["excite", "puma560", "--out", "DIR/x.csv", "--output", "DIR/x.csv"], "name the same file"),
    (["excite", "puma560", "--plot", "DIR/x.txt"], "the format comes from the suffix"),
    (["excite", "puma560", "--out", "DIR/nope/x.csv"], "does not exist"),
    (["analyze", "puma560", "--output", "DIR"], "not a regular file"),
    (["simulate", "puma560", "DIR/log.parquet"], "the format comes from the suffix"),
    (["excite", "puma560", "--acceleration", "fast"], "--acceleration: expected a number per item"),
    (["excite", "puma560", "--margin", "0.5"], "--margin must be a number in [0, 0.5)"),
])
def test_bad_outputs_and_flags_refused_before_work(argv, words, tmp_path, capsys, monkeypatch):
    _no_work(monkeypatch)
    log = tmp_path / "log.csv"
    log.write_text("t\n0\n")
    argv = [a.replace("DIR", str(tmp_path)).replace("LOG", str(log)) for a in argv]
    code, _, err = run(argv, capsys)
    assert code == 2 and words in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.csv"] and log.read_text() == "t\n0\n"


def test_each_subcommand_has_its_own_model_help():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices
    helps = {name: next(a.help for a in p._actions if a.dest == "model") for name, p in sub.items() if name != "robots"}
    assert "glob" in helps["analyze"]
    assert all("analyze" not in h and "glob" not in h for name, h in helps.items() if name != "analyze")
    assert len(set(helps.values())) == len(helps)


def test_analysis_samples_and_the_deprecated_spelling(tmp_path, capsys):
    out = tmp_path / "log.csv"
    code, _, err = run(["simulate", "puma560", str(out), "--duration", "0.3", "--samples", "30"], capsys)
    assert code == 0 and "--samples is deprecated" in err and "--analysis-samples" in err
    code, _, err = run(["simulate", "puma560", str(out), "--duration", "0.3", "--analysis-samples", "30"], capsys)
    assert code == 0 and "deprecated" not in err
    assert (tmp_path / "log.csv.truth.json").is_file()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary file left
    with pytest.raises(SystemExit):
        main(["analyze", "puma560", "--analysis-samples", "30"])  # analyze keeps --samples


def _solo12():
    try:
        files = importlib.metadata.files("example-robot-data") or []
    except importlib.metadata.PackageNotFoundError:
        return None
    hit = [f for f in files if str(f).endswith("solo_description/robots/solo12.urdf")]
    return Path(hit[0].locate()) if hit else None


@pytest.mark.skipif(_solo12() is None, reason="needs the example-robot-data package (the test extra)")
def test_solo12_without_floating_gets_a_hint(capsys):
    code, _, err = run(["analyze", str(_solo12())], capsys)
    hint = [line for line in err.splitlines() if "--floating" in line]
    assert code == 0 and len(hint) == 1 and hint[0].startswith("baseparams: note: ") and "4 chains" in hint[0]
    code, _, err = run(["analyze", str(_solo12()), "--floating"], capsys)
    assert "pass --floating" not in err


def test_no_hint_for_an_arm(tmp_path, capsys):
    from baseparams.cli import floating_hint

    assert floating_hint(baseparams.load("puma560")) == ""
    assert floating_hint(baseparams.load("go2")) == ""  # already floating


@pytest.mark.parametrize("model", ["puma560", "four-bar"])
def test_regressor_backend_and_out_give_the_same_matrix(model):
    robot = baseparams.load(model)
    m = len(robot.actuated) if robot.has_loops else robot.dof
    rng = np.random.default_rng(1)
    q, dq, ddq = 0.3 * rng.normal(size=(3, 64, m))
    ref = baseparams.regressor(robot, q, dq, ddq, backend="numpy")
    buf = np.empty_like(ref)
    got = baseparams.regressor(robot, q, dq, ddq, backend="auto", out=buf)
    assert got is buf
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    if compiled.available():
        fast = baseparams.regressor(robot, q, dq, ddq, backend="compiled")
        np.testing.assert_allclose(fast, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    with pytest.raises(baseparams.BaseparamsError, match="backend"):
        baseparams.regressor(robot, q, dq, ddq, backend="gpu")


def test_all_extra_names_every_extra():
    import tomllib

    meta = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())["project"]
    extras = meta["optional-dependencies"]
    named = extras["all"][0].split("[")[1].rstrip("]").split(",")
    assert set(named) == set(extras) - {"all", "test", "docs"}  # test and docs: the developers' tools
    assert not any(d.startswith("mujoco>") or d == "mujoco" for d in meta["dependencies"])  # no GUI packages
    assert any(d.startswith("mujoco-core") for d in meta["dependencies"])


# ---------------------------------------------------------------- found by a newcomer's review
@pytest.mark.parametrize("name", ["four-bar", "pkm-2rru-1rrs"])
def test_a_loop_robot_simulated_on_the_command_line_identifies_from_its_actuated_joints(name, tmp_path, capsys):
    log = tmp_path / "loop.csv"
    assert main(["simulate", name, str(log), "--duration", "10", "--rate", "200"]) == 0  # default amplitude
    capsys.readouterr()
    assert main(["identify", name, str(log), "--holdout", "2", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    robot = baseparams.load(name)
    actuated = [robot.joint_names[robot.dof_body[k]] for k in robot.actuated]
    assert list(j["validation"]["rms"]) == actuated and j["validation"]["rms_total"] < 1e-2


def test_a_loop_robot_s_default_excursion_is_the_largest_whose_loops_close(tmp_path, capsys):
    """four-bar: 0.8 of its box's half-width (a fifth gave condition numbers near 1e8); pkm-2rru-1rrs falls back."""
    from baseparams.ident.simulate import amplitude_ladder

    four, pkm = baseparams.load("four-bar"), baseparams.load("pkm-2rru-1rrs")
    assert amplitude_ladder(four)[0] == pytest.approx(0.24)
    assert main(["simulate", "four-bar", str(tmp_path / "f.csv"), "--duration", "10", "--rate", "200"]) == 0
    assert "excursion 0.24" in capsys.readouterr().out
    assert main(["identify", "four-bar", str(tmp_path / "f.csv"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["condition_number"] < 1e6
    assert main(["simulate", "pkm-2rru-1rrs", str(tmp_path / "p.csv"), "--duration", "5", "--rate", "200"]) == 0
    truth = json.loads((tmp_path / "p.csv.truth.json").read_text())
    assert truth["amplitude"] < amplitude_ladder(pkm)[0]  # its workspace is narrower than its box


def test_the_symbolic_package_without_sympy_says_which_extra(tmp_path):
    import subprocess

    code = "import sys; sys.modules['sympy'] = None\nimport baseparams.symbolic"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode != 0 and "pip install 'baseparams[symbolic]'" in r.stderr


@pytest.mark.parametrize("argv, words", [
    (["--holdout", "5", "--predictions", "{d}/p.csv", "--save", "{d}/p.csv"], "name the same file"),
    (["--joints", ","], "--joints needs joint names"),
    (["--prior-weight", "1"], "--prior-weight applies to --method physical"),
    (["--holdout", "5", "--score-cutoff", "1000"], "--score-cutoff 1000 Hz"),
    (["--holdout", "9.9"], "--holdout 9.9 s leaves 0.08 s to train on"),  # too little left to train on
])
def test_identify_flags_that_cannot_be_honoured_are_one_line(argv, words, tmp_path, capsys):
    log = tmp_path / "sim.csv"
    assert main(["simulate", "puma560", str(log), "--duration", "10", "--rate", "100"]) == 0
    capsys.readouterr()
    assert main(["identify", "puma560", str(log), *[a.format(d=tmp_path) for a in argv]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len([e for e in err if e.startswith("baseparams: error")]) == 1 and words in err[-1]
    assert not (tmp_path / "p.csv").exists()


def test_simulate_refuses_a_negative_noise(tmp_path, capsys):
    assert main(["simulate", "puma560", str(tmp_path / "s.csv"), "--noise", "-1"]) == 2
    assert "--noise" in capsys.readouterr().err and not (tmp_path / "s.csv").exists()


def test_regressor_states_derive_the_rates_a_file_lacks(tmp_path, capsys):
    log = tmp_path / "sim.csv"
    assert main(["simulate", "puma560", str(log), "--duration", "5", "--rate", "200"]) == 0  # q, dq; no ddq
    out = tmp_path / "Y.npz"
    assert main(["regressor", "puma560", "--states", str(log), "--out", str(out)]) == 0
    y = np.load(out)["Y"]
    assert y.shape == (1000, 6, 60) and np.all(np.isfinite(y))
