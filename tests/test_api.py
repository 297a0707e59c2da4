"""The front door: ``import baseparams``; ``load``, ``analyze``, ``regressor`` and ``Analysis``'s maps; the whole
loop ``excite`` -> ``simulate`` -> ``identify`` -> ``predict`` with the command line's names (issue 26)."""

import doctest
import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import baseparams
from baseparams.cli import main
from baseparams.numerics import closed_samples, row_mask
from baseparams.regressor import closed_regressor
from baseparams.regressor.tp import regressor as tree_regressor

from paths import SHARED

SRC = str(Path(baseparams.__file__).resolve().parents[1])
PUBLIC = {"Analysis", "BaseparamsError", "CONVENTIONS", "Inertia", "ModelError", "ModelWarning", "Robot",
          "RobotBuilder", "analyze", "load", "pose", "regressor", "__version__",
          "Excitation", "Identification", "analyze_symbolic", "excite", "identify", "predict", "simulate",
          "identify_payload"}
#: what ``import baseparams`` must not import (the functions that need them do)
HEAVY = ("scipy", "mujoco", "pinocchio", "cvxpy", "clarabel", "sympy", "matplotlib", "dask", "distributed", "numba",
         "pyarrow", "pandas")


def _env():
    return {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}


@pytest.fixture(scope="module")
def puma():
    robot = baseparams.load("puma560")
    return robot, baseparams.analyze(robot)


@pytest.fixture(scope="module")
def analyses(puma):
    """(robot, analysis) pairs covering conventions, measured rows and a loop robot."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", baseparams.ModelWarning)
        go2 = baseparams.load("go2")
    four = baseparams.load("four-bar")
    return {"puma560": puma,
            "go2-joints-pinocchio": (go2, baseparams.analyze(go2, rows="joints", convention="pinocchio")),
            "go2-all-paper": (go2, baseparams.analyze(go2, convention="paper")),
            "four-bar-idyntree": (four, baseparams.analyze(four, samples=500, convention="idyntree"))}


# ---------------------------------------------------------------- names, imports, packaging
def test_public_names_importable():
    assert set(baseparams.__all__) == PUBLIC
    ns = {}
    exec("from baseparams import *", ns)  # noqa: S102
    assert set(ns) >= PUBLIC
    assert callable(baseparams.regressor) and callable(baseparams.load) and callable(baseparams.analyze)
    assert baseparams.CONVENTIONS == ("paper", "khalil", "pinocchio", "idyntree", "rpna")
    assert issubclass(baseparams.ModelError, baseparams.BaseparamsError)
    assert issubclass(baseparams.ModelWarning, UserWarning)
    assert "puma560" in baseparams.robots.BUILTINS  # submodules on first use
    with pytest.raises(AttributeError):
        baseparams.no_such_name  # noqa: B018
    # the subpackage stays importable under the function's name
    from baseparams.regressor import regressor_tensor  # noqa: F401
    assert sys.modules["baseparams.regressor"].regressor is tree_regressor


def test_import_is_light():
    """``import baseparams`` (and reaching the loop's functions) loads numpy and the model: not SciPy, MuJoCo,
    Pinocchio, cvxpy, SymPy, matplotlib or Dask."""
    code = ("import sys, baseparams as bp; fs = [bp.excite, bp.simulate, bp.identify, bp.predict, "
            "bp.analyze_symbolic]; d = dir(bp); "
            f"print(sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), check=True)
    assert out.stdout.strip() == "[]"
    # the check itself sees a heavy import
    code = code.replace("d = dir(bp)", "import scipy.optimize")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), check=True)
    assert "scipy" in out.stdout


def test_package_docstring_examples():
    res = doctest.testmod(baseparams, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert res.attempted >= 5 and res.failed == 0


def test_python_dash_m():
    out = subprocess.run([sys.executable, "-m", "baseparams", "robots"], capture_output=True, text=True,
                         env=_env(), check=False)
    assert out.returncode == 0 and out.stdout.startswith("puma560") and "go2" in out.stdout
    out = subprocess.run([sys.executable, "-m", "baseparams", "analyze", "no-such-robot"], capture_output=True,
                         text=True, env=_env(), check=False)
    assert out.returncode == 2 and out.stderr.startswith("baseparams: error:")


def test_py_typed_is_shipped():
    assert (Path(baseparams.__file__).parent / "py.typed").is_file()


# ---------------------------------------------------------------- load
def test_load_builtin():
    robot = baseparams.load("PUMA560")
    assert isinstance(robot, baseparams.Robot) and (robot.n, robot.dof) == (6, 6)
    g = baseparams.load("puma560", gravity=(0, 0, -1.62))
    assert np.allclose(g.gravity, [0, 0, -1.62])
    with pytest.raises(baseparams.BaseparamsError, match="built-in"):
        baseparams.load("puma560", floating=True)
    with pytest.raises(baseparams.BaseparamsError, match="no such file"):
        baseparams.load("no-such-robot")


@pytest.mark.shared
def test_load_urdf_loops_are_assembled_with_a_warning():
    path = SHARED / "urdfplus/four_bar.urdf"
    with pytest.warns(baseparams.ModelWarning, match="assembled"):
        robot = baseparams.load(path)  # a PathLike
    assert robot.has_loops and len(robot.actuated) == 1 and robot.n == 3


@pytest.mark.shared
def test_load_infeasible_inertia_warns_or_raises():
    path = SHARED / "urdfplus/planar_leg_linkage.urdf"
    with pytest.warns(baseparams.ModelWarning, match="(?i)inertia"):
        baseparams.load(str(path))
    with pytest.raises(baseparams.ModelError):
        baseparams.load(str(path), strict_inertia=True)


@pytest.mark.shared
def test_load_mjcf():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", baseparams.ModelWarning)  # stripped mesh assets
        robot = baseparams.load(str(SHARED / "mjcf/unitree_go2/go2.xml"))
        fl = baseparams.load(str(SHARED / "mjcf/unitree_go2/go2.xml"), gravity=(0, 0, -1))
    assert robot.floating and (robot.n, robot.dof) == (13, 18)
    assert np.allclose(fl.gravity, [0, 0, -1])


# ---------------------------------------------------------------- analyze vs the CLI
@pytest.mark.parametrize("model", ["puma560", "go2"])
def test_analyze_equals_cli_json(model, capsys):
    assert main(["analyze", model, "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", baseparams.ModelWarning)
        a = baseparams.analyze(baseparams.load(model))
    assert (a.nullity, a.n_base, a.status) == (cli["nullity"], cli["n_base"], cli["status"])
    assert a.expressions() == cli["base_parameters"]
    assert [e["name"] for e in cli["base_parameters"]] == a.base_names
    j = a.to_json()
    for key in ("nullity", "n_base", "status", "certified", "convention", "base_parameters",
                "base_parameters_paper", "unidentifiable", "n_params", "rows"):
        assert j[key] == cli[key], key
    assert set(j) == set(cli)
    json.dumps(j)  # JSON-able as is


def test_analysis_accessors_and_repr(puma):
    robot, a = puma
    assert repr(a) == "<Analysis puma560: nullity 24, 36 base parameters (khalil), certified>"
    assert "\n" not in repr(a)
    assert a.convention == "khalil" and a.certified and a.certificate.nullity == 24
    assert a.basis.shape == (60, 24) and np.allclose(a.basis.T @ a.basis, np.eye(24))
    assert np.abs(tree_regressor(robot, *np.random.default_rng(3).uniform(0, 1, (3, 20, 6))) @ a.basis).max() < 1e-9
    assert len(a.names) == 60 and a.names[0] == "link1.XX"
    assert len(a.base_names) == a.n_base == 36 and a.base_names[0] == "link1.ZZR"
    assert a.expressions()[0]["name"] == "link1.ZZR"


def test_analysis_is_not_value_comparable(puma):
    robot, a = puma
    b = baseparams.analyze(robot)
    assert a != b and len({a, b}) == 2 and [a].count(a) == 1  # identity, never a numpy truth-value error


def test_analyze_options():
    robot = baseparams.load("puma560")
    u = baseparams.analyze(robot, verify=False, extended=False, convention="paper")
    assert u.status == "unverified" and u.certificate is None and u.nullity == 24 and not u.certified
    assert repr(u).endswith("(paper), unverified>")
    assert u.expressions()[0]["name"].split(".")[1] in ("XX", "XXR", "YY", "YYR", "ZZ", "ZZR", "XY", "XYR")
    with pytest.raises(baseparams.BaseparamsError, match="convention= must be one of"):
        baseparams.analyze(robot, convention="urdf")
    with pytest.raises(baseparams.BaseparamsError, match="load"):
        baseparams.analyze("puma560")
    with pytest.raises(TypeError):
        baseparams.analyze(robot, 10)  # keyword-only options


# ---------------------------------------------------------------- maps to and from the base parameters
def _states(robot, rng, s=7):
    """Tree states ``(S, dof)``; loop robots: loop-closed actuated states ``(S, na)`` and the
    closed states themselves."""
    if robot.has_loops:
        cs = closed_samples(robot, 4 * s, rng)
        assert cs.kept >= s
        qa = cs.q[:s, robot.actuated]
        return (qa, cs.dq[:s, robot.actuated], cs.ddq[:s, robot.actuated]), closed_regressor(robot, cs)[:s]
    q, dq, ddq = rng.uniform(-1, 1, (3, s, robot.dof))
    return (q, dq, ddq), tree_regressor(robot, q, dq, ddq)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("case", ["puma560", "go2-joints-pinocchio", "go2-all-paper", "four-bar-idyntree"])
def test_base_regressor_reproduces_the_forces(analyses, case, seed):
    """``base_regressor @ to_base(pi)`` = measured rows of ``Y @ pi`` for random parameters."""
    robot, a = analyses[case]
    rng = np.random.default_rng(seed)
    states, y = _states(robot, rng)
    if not robot.has_loops:
        y = y[:, row_mask(robot, a.rows)]
    yb = a.base_regressor(*states)
    assert yb.shape == (len(states[0]), y.shape[1], a.n_base)
    from baseparams.base import paper_from

    for pi_c in (robot.parameters(a.convention), rng.normal(size=10 * robot.n)):
        pi_paper = paper_from(robot, a.convention) @ pi_c
        tau = y @ pi_paper
        scale = max(1.0, np.abs(tau).max())
        assert np.abs(yb @ a.to_base(pi_c, a.convention) - tau).max() < 1e-9 * scale
    # the own parameters, through the public regressor
    tau = baseparams.regressor(robot, *states) @ robot.parameters("paper")
    if not robot.has_loops:
        tau = tau[:, row_mask(robot, a.rows)]
    assert np.allclose(yb @ a.to_base(robot.parameters(a.convention), a.convention), tau, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("case", ["puma560", "go2-joints-pinocchio", "four-bar-idyntree"])
def test_to_base_from_base_round_trip(analyses, case, seed):
    robot, a = analyses[case]
    rng = np.random.default_rng(100 + seed)
    beta = rng.normal(size=a.n_base)
    pi = a.from_base(beta)
    assert pi.shape == (10 * robot.n,)
    assert np.allclose(a.to_base(pi, a.convention), beta, atol=1e-10)
    # from_base(to_base(pi)) differs from pi by a nullspace direction only: the same forces
    pi2 = rng.normal(size=10 * robot.n)
    back = a.from_base(a.to_base(pi2, a.convention))
    from baseparams.base import paper_from

    d = paper_from(robot, a.convention) @ (back - pi2)  # paper convention, like the basis
    assert np.linalg.norm(d - a.basis @ (a.basis.T @ d)) < 1e-9 * max(1.0, np.linalg.norm(pi2))


def test_to_base_needs_the_right_convention(puma):
    robot, a = puma
    with pytest.raises(baseparams.BaseparamsError, match="khalil"):
        a.to_base(robot.parameters("paper"), "paper")
    with pytest.raises(TypeError):
        a.to_base(robot.parameters("khalil"))  # the convention is required
    with pytest.raises(baseparams.BaseparamsError, match="shape"):
        a.to_base(np.zeros(59), "khalil")
    with pytest.raises(baseparams.BaseparamsError):
        a.from_base(np.zeros(35))


# ---------------------------------------------------------------- regressor
def test_regressor_tree(puma):
    robot, _ = puma
    q, dq, ddq = np.random.default_rng(0).uniform(0, 1, (3, 5, robot.dof))
    y = baseparams.regressor(robot, q, dq, ddq)
    assert y.shape == (5, 6, 60) and np.array_equal(y, tree_regressor(robot, q, dq, ddq))
    assert baseparams.regressor(robot, q[0]).shape == (1, 6, 60)  # one state; dq, ddq default to 0
    with pytest.raises(baseparams.BaseparamsError, match="shape"):
        baseparams.regressor(robot, q[:, :5])


def test_regressor_loops_takes_actuated_coordinates(analyses):
    robot, _ = analyses["four-bar-idyntree"]
    states, y = _states(robot, np.random.default_rng(5), s=4)
    got = baseparams.regressor(robot, *states)
    assert got.shape == (4, len(robot.actuated), 10 * robot.n) and np.allclose(got, y, atol=1e-9)
    with pytest.raises(baseparams.BaseparamsError, match="actuated"):
        baseparams.regressor(robot, np.zeros((2, robot.dof)))  # tree coordinates: said, not guessed


def test_regressor_loops_unreachable_state_is_an_error():
    robot = baseparams.load("pkm-2rru-1rrs")
    with pytest.raises(baseparams.BaseparamsError, match="do not close the loops"):
        baseparams.regressor(robot, np.full((2, len(robot.actuated)), 50.0))


# ---------------------------------------------------------------- the whole loop at the front door (issue 26)
#: keywords of the front door with no flag of the same name on the command line (Python objects, or ``-v``)
PYTHON_ONLY = {"limits", "max_iter", "progress", "verify", "couplings"}
#: the CLI subcommands and the front door's function of the same name
LOOP = ("analyze", "regressor", "excite", "simulate", "identify", "predict")


def _cli_names(command: str) -> set[str]:
    """The flags (``--min-speed`` as ``min_speed``) and positional arguments of a subcommand."""
    from baseparams.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")  # noqa: SLF001  (argparse's own)
    out = set()
    for action in sub.choices[command]._actions:  # noqa: SLF001
        out |= {s.lstrip("-").replace("-", "_") for s in action.option_strings if s.startswith("--")}
        if not action.option_strings:
            out.add(action.dest)
    return out


def test_every_subcommand_has_its_function():
    from baseparams.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")  # noqa: SLF001
    assert set(sub.choices) == {"robots", "payload", *LOOP}  # payload: identify_payload (tests/test_payload.py)
    for name in LOOP:
        assert callable(getattr(baseparams, name)) and name in baseparams.__all__ and name in dir(baseparams)
    assert "puma560" in baseparams.robots.BUILTINS  # ``baseparams robots``
    assert baseparams.Excitation is baseparams.excitation.Excitation
    assert baseparams.Identification is sys.modules["baseparams.ident"].Identification


@pytest.mark.parametrize("name", ["excite", "simulate", "identify", "predict", "analyze_symbolic"])
def test_keywords_are_the_cli_flags(name):
    """Every keyword of the front door's loop is a flag (or argument) of the subcommand of the same name."""
    import inspect

    command = "analyze" if name == "analyze_symbolic" else name
    params = inspect.signature(getattr(baseparams, name)).parameters
    keywords = {p for p, v in params.items() if v.kind is inspect.Parameter.KEYWORD_ONLY
                and not p.startswith("_")} - PYTHON_ONLY
    assert keywords and keywords <= _cli_names(command), keywords - _cli_names(command)
    if name == "identify":
        assert "coupling" in _cli_names(command)  # couplings=: the repeatable --coupling
    if name == "analyze_symbolic":
        assert {"symbolic", "no_verify"} <= _cli_names(command)


@pytest.fixture(scope="module")
def loop(tmp_path_factory):
    """design -> record (simulated) -> identify -> export, as docs/tutorials/the-loop.md, in a scratch folder."""
    folder = tmp_path_factory.mktemp("loop")
    robot = baseparams.load("puma560")
    traj = baseparams.excite(robot, period=5, rate=100, harmonics=3, grid=24, starts=1, out=folder / "traj.csv")
    log, truth = baseparams.simulate(robot, traj, noise=0.05, out=folder / "log.csv")
    ident = baseparams.identify(robot, log, save=folder / "result.json")
    return {"folder": folder, "robot": robot, "traj": traj, "log": log, "truth": truth, "ident": ident}


def test_loop_end_to_end(loop):
    robot, traj, log, truth, ident = (loop[k] for k in ("robot", "traj", "log", "truth", "ident"))
    folder = loop["folder"]
    assert isinstance(traj, baseparams.Excitation) and isinstance(ident, baseparams.Identification)
    assert traj.joints == tuple(robot.joint_names) and traj.q.shape == (501, 6) and traj.condition_number < 20
    # record: the log is the designed motion, at rest at both ends
    assert np.array_equal(log.t, traj.t) and np.array_equal(log.q, traj.q) and np.abs(log.dq[[0, -1]]).max() < 1e-9
    # identify: the truth comes back (noise 0.05 N m), within the reported uncertainty
    cmp = ident.compare_truth(truth)
    assert cmp["rel_error"] < 0.02 and cmp["rms_z"] < 3
    # export and check: the saved result, loaded back, predicts what the object does
    back = baseparams.Identification.load(folder / "result.json", robot)
    assert np.array_equal(back.values, ident.values)
    tau = baseparams.predict(robot, folder / "result.json", log)
    assert tau.shape == (501, 6) and np.allclose(tau, ident.predict(log), rtol=0, atol=1e-12)
    assert np.sqrt(np.mean((tau - log.tau) ** 2)) < 0.2  # the noise (0.05) and the filter's edge transients
    # the files are the CLI's: the trajectory and the log read back exactly
    from baseparams.excitation import read_trajectory
    from baseparams.io.logs import read_log

    for got, want in zip(read_trajectory(folder / "traj.csv", robot), traj.trajectory):
        assert np.array_equal(got, want)
    assert np.array_equal(read_log(folder / "log.csv", robot).tau, log.tau)
    assert json.loads((folder / "log.csv.truth.json").read_text()) == truth


def test_loop_from_files_equals_the_cli(loop, capsys):
    """``bp.identify(model, "log.csv")`` and ``baseparams identify MODEL log.csv --save`` give the same values; the
    trajectory file simulates as the object does."""
    folder = loop["folder"]
    ident = baseparams.identify("puma560", str(folder / "log.csv"))
    assert np.array_equal(ident.values, loop["ident"].values)
    assert main(["identify", "puma560", str(folder / "log.csv"), "--save", str(folder / "cli.json")]) == 0
    capsys.readouterr()
    cli = baseparams.Identification.load(folder / "cli.json", loop["robot"])
    assert np.array_equal(cli.values, ident.values)
    log, truth = baseparams.simulate("puma560", folder / "traj.csv", noise=0.05)
    assert np.array_equal(log.tau, loop["log"].tau) and truth == loop["truth"]
    # a predicted trajectory (no torques): the torques to expect on the robot
    assert baseparams.predict(loop["robot"], loop["ident"], folder / "traj.csv").shape == (501, 6)


def test_loop_refuses_bad_input_in_one_line(loop, tmp_path):
    robot, folder = loop["robot"], loop["folder"]
    with pytest.raises(baseparams.BaseparamsError, match="period= or base_frequency="):
        baseparams.excite(robot, period=5, base_frequency=0.2)
    with pytest.raises(baseparams.BaseparamsError, match="model must be"):
        baseparams.identify(np.zeros(3), loop["log"])
    with pytest.raises(baseparams.BaseparamsError, match="noise"):
        baseparams.simulate(robot, loop["traj"], noise=-1)
    with pytest.raises(baseparams.BaseparamsError, match="does not exist"):  # checked before the design
        baseparams.excite(robot, out=tmp_path / "no" / "traj.csv")
    with pytest.raises(baseparams.BaseparamsError, match="input"):  # never onto an input, checked before the fit
        baseparams.identify(robot, folder / "log.csv", save=folder / "log.csv")
    with pytest.raises(baseparams.BaseparamsError, match=".csv or .tsv"):
        loop["traj"].save(tmp_path / "traj.npz")
    with pytest.raises(baseparams.BaseparamsError, match="input"):
        loop["traj"].save(folder / "log.csv", inputs=[folder / "log.csv"], what="--out")
    with pytest.raises(baseparams.BaseparamsError, match="not this robot .four-bar."):
        baseparams.predict("four-bar", folder / "result.json", loop["log"])


def test_loop_accepts_an_analysis_and_cli_strings(loop):
    """An Analysis as the model (its robot); ``friction="viscous"`` and ``couplings=["m:joint5=1,joint6=1"]`` as
    the CLI writes them."""
    a = baseparams.analyze(loop["robot"])
    ident = baseparams.identify(a, loop["log"], friction="viscous,coulomb,offset", method="ols")
    assert ident.model.n_drive == loop["ident"].model.n_drive
    few = baseparams.identify(a, loop["log"], friction="viscous", couplings=["m:joint5=1,joint6=1"], method="ols")
    assert few.model.n_drive < ident.model.n_drive and any(n.endswith("_m") for n in few.names)


def test_analyze_symbolic_equals_cli_json(capsys):
    pytest.importorskip("sympy")
    sa = baseparams.analyze_symbolic("scara-symbolic")
    assert main(["analyze", "scara-symbolic", "--symbolic", "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    assert sa.n_base == cli["n_base"]
    assert any(c.effect for c in sa.conditions)  # probed, as the CLI does
