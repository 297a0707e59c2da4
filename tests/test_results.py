"""Results go back in: save/load, predict, ``identify --save/--truth``, ``predict``, ``regressor --states``."""

import json
from dataclasses import replace

import numpy as np
import pytest

import baseparams
from baseparams.cli import main
from baseparams.errors import BaseparamsError
from baseparams.ident import Fit, Identification, identify
from baseparams.ident.saved import FORMAT, robot_fingerprint
from baseparams.ident.simulate import fourier_trajectory, simulate_log
from baseparams.io.logs import read_log, write_log

from paths import IDENT


@pytest.fixture(scope="module")
def puma():
    return baseparams.load("puma560")


@pytest.fixture(scope="module")
def exact(puma):
    """A noise-free simulated log with its exact accelerations, and its true parameters."""
    t, q, dq, ddq = fourier_trajectory(6, 10.0, 200.0, np.random.default_rng(3), amplitude=0.5)
    log, truth = simulate_log(puma, rotor=True, seed=1, trajectory=(t, q, dq, ddq))
    return log, ddq, truth


@pytest.fixture(scope="module")
def ident(puma, exact):
    return identify(puma, exact[0], method="ols", rotor=True)


def test_round_trip_gives_identical_predictions(puma, exact, ident, tmp_path):
    path = ident.save(tmp_path / "res.json")
    doc = json.loads(path.read_text())
    assert doc["format"] == FORMAT and doc["version"] == 1
    assert doc["robot"]["fingerprint"] == robot_fingerprint(puma)
    assert doc["parameters"]["names"] == ident.model.names
    assert doc["options"]["rotor"] is True and doc["options"]["cutoff"] > 0
    back = Identification.load(path, baseparams.load("puma560"))  # a fresh load of the same model
    assert np.array_equal(back.fit.theta, ident.fit.theta)
    assert np.array_equal(back.fit.estimate.std, ident.fit.estimate.std)
    assert np.array_equal(back.predict(exact[0]), ident.predict(exact[0]))
    assert back.to_json() == ident.to_json()  # every table, statistic and note read back


@pytest.mark.parametrize("name", ["puma560", "go2"])
def test_a_loaded_result_predicts_a_log_file_as_bp_predict_does(name, tmp_path):
    """``Identification.load(f, robot).predict("log.csv")``: a path, as ``bp.predict`` takes (floating base too)."""
    robot = baseparams.load(name)
    log, _ = baseparams.simulate(robot, duration=6, rate=200, seed=2, out=tmp_path / "log.csv")
    baseparams.identify(robot, log, method="ols", save=tmp_path / "res.json")
    back = Identification.load(tmp_path / "res.json", robot)
    by_path = back.predict(str(tmp_path / "log.csv"))
    assert by_path.shape == (log.n_samples, log.n_joints)
    assert np.array_equal(by_path, back.predict(read_log(tmp_path / "log.csv", robot)))
    assert np.array_equal(by_path, baseparams.predict(robot, tmp_path / "res.json", tmp_path / "log.csv"))
    assert np.sqrt(np.mean((by_path - log.tau[:, -log.n_joints:]) ** 2)) < 1e-2 * np.sqrt(np.mean(log.tau**2))


def test_load_refuses_another_robot_and_another_version(ident, tmp_path):
    path = ident.save(tmp_path / "res.json")
    other = baseparams.load("go2")
    with pytest.raises(BaseparamsError, match="identified on robot 'puma560' .*not this robot 'go2'") as exc:
        Identification.load(path, other)
    assert "\n" not in str(exc.value) and str(exc.value).count("sha256:") == 2
    moved = baseparams.load("puma560", gravity=(0.0, 0.0, -9.7))  # same names, another structure
    with pytest.raises(BaseparamsError, match="not this robot"):
        Identification.load(path, moved)
    doc = json.loads(path.read_text())
    doc["version"] = 2
    newer = tmp_path / "newer.json"
    newer.write_text(json.dumps(doc))
    with pytest.raises(BaseparamsError, match="version 2; this baseparams reads version 1 .*upgrade"):
        Identification.load(newer, baseparams.load("puma560"))
    newer.write_text(json.dumps({"format": "something-else"}))
    with pytest.raises(BaseparamsError, match="not a saved identification"):
        Identification.load(newer, baseparams.load("puma560"))


def test_fingerprint_is_structural(puma):
    assert robot_fingerprint(puma) == robot_fingerprint(baseparams.load("puma560"))
    heavier = puma.with_parameters(1.5 * puma.parameters("paper"), "paper")  # inertias are not structure
    assert robot_fingerprint(heavier) == robot_fingerprint(puma)
    assert robot_fingerprint(puma) != robot_fingerprint(baseparams.load("go2"))


def test_predict_reproduces_simulated_torques(puma, exact, ident):
    log, ddq, truth = exact
    theta = np.array([p["value"] for p in truth["parameters"]])
    true = replace(ident, fit=Fit(ident.model, "ols", theta, ident.fit.estimate))
    scale = np.abs(log.tau).max()
    tau = true.predict(replace(log, ddq=ddq), smooth=False)  # exact states as logged: the model itself
    assert tau.shape == log.tau.shape
    assert np.abs(tau - log.tau).max() <= 1e-8 * scale
    derived = true.predict(log, smooth=False)  # ddq derived as identify derives it: differences, filter edges
    pad = int(np.ceil(2 * 200.0 / ident.options.cutoff))
    assert np.abs(derived - log.tau)[pad:-pad].max() <= 1e-4 * scale
    assert np.abs(derived - log.tau).max() <= 1e-2 * scale
    # the identified values predict to the identification's accuracy
    assert np.abs(ident.predict(log, smooth=False) - log.tau)[pad:-pad].max() <= 2e-3 * scale
    # smooth (default): states and prediction low-passed at the cutoff; the motion is well below it
    assert np.abs(true.predict(log) - log.tau)[pad:-pad].max() <= 2e-3 * scale


def test_cli_predict_csv_and_parquet(tmp_path, capsys):
    sim = tmp_path / "sim.csv"
    assert main(["simulate", "puma560", str(sim), "--duration", "12", "--rate", "200", "--noise", "0.02"]) == 0
    res = tmp_path / "res.json"
    assert main(["identify", "puma560", str(sim), "--save", str(res)]) == 0
    capsys.readouterr()
    robot = baseparams.load("puma560")
    log = read_log(sim, robot)
    names = ["t"] + [f"tau_{j}" for j in log.joints]
    out = tmp_path / "pred.csv"
    assert main(["predict", "puma560", str(res), str(sim), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "RMS vs the raw measured torques:" in text and "edge transient" in text
    assert main(["predict", "puma560", str(res), str(sim), "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    edge = j["edge_samples"]
    mid = slice(edge, log.n_samples - edge)
    interior = Identification.load(res, robot).predict(log)[mid] - log.tau[mid]
    assert j["rms_interior"]["total"] == pytest.approx(np.sqrt(np.mean(interior**2)), rel=1e-9)
    assert j["rms_interior"]["total"] < j["rms"]["total"]  # the filter's edges are what the headline leaves out
    rows = out.read_text().splitlines()
    assert rows[0].split(",") == names and len(rows) == 1 + log.n_samples
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.array_equal(table[:, 0], log.t)
    expected = Identification.load(res, robot).predict(log)
    assert np.array_equal(table[:, 1:], expected)
    pq = pytest.importorskip("pyarrow.parquet")
    outp = tmp_path / "pred.parquet"
    assert main(["predict", "puma560", str(res), str(sim), "--out", str(outp), "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["samples"] == log.n_samples and j["rms"]["total"] < 0.05
    t = pq.read_table(outp)
    assert t.column_names == names and t.num_rows == log.n_samples
    assert np.array_equal(t.column("tau_joint3").to_numpy(), expected[:, 2])
    # a trajectory without torques (states only) is predicted too; no RMS then
    traj = tmp_path / "traj.csv"
    write_log(traj, replace(log, tau=None))
    assert main(["predict", "puma560", str(res), str(traj), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["rms"] is None
    # another robot: one line, exit 2, nothing written
    assert main(["predict", "go2", str(res), str(sim), "--out", str(tmp_path / "no.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "not this robot 'go2'" in err and not (tmp_path / "no.csv").exists()


@pytest.mark.slow
def test_identify_save_checked_before_the_fit_and_truth(tmp_path, capsys):
    sim = tmp_path / "sim.csv"
    assert main(["simulate", "puma560", str(sim), "--duration", "20", "--rate", "200", "--noise", "0.05",
                 "--rotor", "--seed", "2"]) == 0
    truth = tmp_path / "sim.csv.truth.json"
    capsys.readouterr()
    assert main(["identify", "puma560", str(sim), "--rotor", "--save", str(tmp_path / "missing" / "r.json")]) == 2
    assert "--save" in capsys.readouterr().err
    assert main(["identify", "puma560", str(sim), "--rotor", "--save", str(sim)]) == 2
    assert "would overwrite the input" in capsys.readouterr().err
    assert main(["identify", "puma560", str(sim), "--rotor", "--truth", str(truth)]) == 0
    text = capsys.readouterr().out
    assert "compared with" in text and "largest |z|" in text
    assert main(["identify", "puma560", str(sim), "--rotor", "--truth", str(truth), "--json"]) == 0
    cmp = json.loads(capsys.readouterr().out)["truth"]
    assert len(cmp["terms"]) == 40 + 18 and {"true", "estimate", "error", "std", "z"} <= set(cmp["terms"][0])
    assert cmp["rel_error"] < 0.01  # errors small
    assert 0.3 < cmp["rms_z"] < 5 and cmp["max_abs_z"] < 10  # |z| reasonable: the std are honest
    # a truth of another model (no rotor) is refused in one line
    assert main(["identify", "puma560", str(sim), "--no-rotor", "--truth", str(truth)]) == 2
    assert "not the identified model" in capsys.readouterr().err


def test_regressor_states_out(puma, tmp_path, capsys):
    rng = np.random.default_rng(0)
    q, dq, ddq = rng.uniform(-1, 1, (3, 25, puma.dof))
    cols = {"t": np.arange(25) * 0.01}
    for kind, x in (("q", q), ("dq", dq), ("ddq", ddq)):
        cols.update({f"{kind}_{j}": x[:, k] for k, j in enumerate(puma.joint_names)})
    states = tmp_path / "states.npz"
    np.savez(states, **cols)
    y = baseparams.regressor(puma, q, dq, ddq)
    out = tmp_path / "y.npz"
    assert main(["regressor", "puma560", "--states", str(states), "--out", str(out)]) == 0
    with np.load(out) as z:
        assert np.array_equal(z["Y"], y) and len(z["columns"]) == y.shape[2] and list(z["joints"]) == list(
            puma.joint_names)
    csv = tmp_path / "y.csv"
    assert main(["regressor", "puma560", "--states", str(states), "--out", str(csv)]) == 0
    lines = csv.read_text().splitlines()
    header = lines[0].split(",")
    assert header[:2] == ["sample", "joint"] and len(lines) == 1 + 25 * puma.dof
    vals = np.array([[float(v) for v in ln.split(",")[2:]] for ln in lines[1:]])
    assert np.array_equal(vals, y.reshape(-1, y.shape[2]))
    assert main(["regressor", "puma560", "--out", str(csv)]) == 2  # --out without --states
    assert "--states" in capsys.readouterr().err


@pytest.mark.shared
@pytest.mark.slow
def test_panda_save_then_predict_whole_log(tmp_path, capsys):
    """The real Panda log (Gaz et al. 2019): identify with --save, predict every sample of the log."""
    panda = IDENT / "panda_gaz2019"
    urdf = str(panda / "panda_mdh_gaz2019.urdf")
    robot = baseparams.load(urdf)
    sig = {k: np.loadtxt(panda / f"exciting_traj_{f}.txt").reshape(-1, 7)
           for k, f in (("q", "positions"), ("dq", "velocity"), ("tau", "torques"))}
    t = np.loadtxt(panda / "exciting_traj_time.txt")
    log_path = tmp_path / "panda.csv"
    header = ["t"] + [f"{k}_{j}" for k in sig for j in robot.joint_names]
    np.savetxt(log_path, np.column_stack([t, *sig.values()]), delimiter=",", header=",".join(header), comments="",
               fmt="%.17g")
    res, pred = tmp_path / "panda.json", tmp_path / "pred.csv"
    assert main(["identify", urdf, str(log_path), "--method", "ols", "--save", str(res)]) == 0
    capsys.readouterr()
    assert main(["predict", urdf, str(res), str(log_path), "--out", str(pred), "--json", "--score-cutoff", "5"]) == 0
    j = json.loads(capsys.readouterr().out)
    rows = pred.read_text().splitlines()
    assert len(rows) == 1 + len(t) == 1 + j["samples"]
    assert rows[0] == ",".join(["t"] + [f"tau_{n}" for n in robot.joint_names])
    # against the raw measured torques: the sensor's content above the motion's band dominates (0.27 N m alone)
    assert j["rms"]["total"] < 0.30
    assert j["rms_lowpassed"]["total"] <= 0.15  # against the measured torques low-passed at 5 Hz


def test_round_trip_physical_with_coupling_and_smooth_coulomb(puma, tmp_path):
    """The physical fit, a coupled motor and a Coulomb width are saved and rebuilt."""
    pytest.importorskip("cvxpy")
    from baseparams.ident.drives import MotorCoupling

    log, _ = simulate_log(puma, duration=10, rate=200, noise=0.01, seed=1)
    res = identify(puma, log, method="physical", coulomb_width=0.05,
                   couplings=(MotorCoupling("m6", ("joint5", "joint6"), (1.0, 1.0)),))
    back = Identification.load(res.save(tmp_path / "phys.json"), puma)
    assert back.options.coulomb_width == 0.05 and back.options.couplings[0].name == "m6"
    assert back.options == replace(res.options, couplings=back.options.couplings)  # every option saved
    assert back.fit.physical.feasible and np.array_equal(back.fit.physical.pi, res.fit.physical.pi)
    assert np.array_equal(back.predict(log), res.predict(log)) and back.to_json() == res.to_json()


@pytest.mark.parametrize("seed", range(3))
def test_predict_refuses_a_log_shorter_than_the_filters_edges_and_predicts_one_just_long_enough(exact, ident, seed):
    """A log whose every sample lies in the low-pass's edge transient (fewer than ``shortest_log`` samples at the
    identification's cutoff) was predicted with exit 0 (a 5-sample log 100 % off): refused in one line naming the
    log, the length needed and the way round it (dq and ddq logged, states as logged); at that length it predicts,
    and with its rates logged and ``smooth=False`` any length does."""
    from baseparams.ident.preprocess import shortest_log

    log, ddq, _ = exact
    rng = np.random.default_rng(seed)
    need = shortest_log(200.0, ident.options.cutoff)
    n = int(rng.integers(3, need))
    start = int(rng.integers(0, len(log.t) - need))
    short = replace(log, t=log.t[start:start + n], q=log.q[start:start + n], dq=None, ddq=None,
                    tau=log.tau[start:start + n], source="short.csv")
    with pytest.raises(BaseparamsError) as err:
        ident.predict(short)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("short.csv:") and f"{need / 200.0:.3g} s" in msg and "--raw-states" in msg
    enough = replace(log, t=log.t[start:start + need], q=log.q[start:start + need], dq=None, ddq=None,
                     tau=log.tau[start:start + need])
    assert ident.predict(enough).shape == (need, log.tau.shape[1])
    logged = replace(log, t=log.t[start:start + n], q=log.q[start:start + n], dq=log.dq[start:start + n],
                     ddq=ddq[start:start + n], tau=log.tau[start:start + n])
    assert np.abs(ident.predict(logged, smooth=False) - logged.tau).max() <= 1e-2 * np.abs(log.tau).max()
