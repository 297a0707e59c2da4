"""Fleet identification on a local Dask cluster: equality with the serial path, per-file and
pooled estimates, and a worker killed mid-run."""

import os
import signal

import distributed  # a test dependency: never skipped
import numpy as np
import pytest

import baseparams
from baseparams.fleet import file_factors, identify_fleet, simulate_fleet
from baseparams.ident import fit
from baseparams.ident.chunks import combine
from baseparams.ident.model import ident_model


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    robot = baseparams.load("puma560")
    model = ident_model(baseparams.analyze(robot), rotor=False)  # simulate_fleet: friction, no rotor
    paths = simulate_fleet(robot, tmp_path_factory.mktemp("fleet"), robots=4, duration=20.0, rate=500.0, seed=2)
    return robot, model, paths


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    cl = distributed.Client(cluster)
    yield cl
    cl.close()
    cluster.close()


@pytest.mark.slow
def test_fleet_equals_serial_per_file_and_pooled(fleet, client):
    robot, model, paths = fleet
    res = identify_fleet(model, paths, per_file=True, pooled=True, method="wls", client=client)
    serial = [file_factors(str(p), model) for p in paths]
    for (acc, info), p in zip(serial, paths):
        ref = fit(model, acc, "wls").theta
        assert np.abs(res.per_file[str(p)].theta - ref).max() <= 1e-10 * np.abs(ref).max()
        assert info["used"] == next(f["used"] for f in res.files if f["path"] == str(p))
    pooled = fit(model, combine([a for a, _ in serial]), "wls").theta
    assert np.abs(res.pooled.theta - pooled).max() <= 1e-10 * np.abs(pooled).max()
    # each robot's truth is recovered within its estimate's standard deviations
    import json
    for p in paths:
        truth = json.loads(p.with_name(p.name + ".truth.json").read_text())["parameters"]
        truth = {t["name"]: t["value"] for t in truth}
        f = res.per_file[str(p)]
        z = (f.theta - np.array([truth[n] for n in model.names])) / f.estimate.std
        assert np.sqrt(np.mean(z**2)) < 5
    # the fleet's spread reflects the robots' differences (10 % mass and inertia spread)
    assert res.spread is not None and np.max(res.spread["std"] / np.abs(res.spread["mean"])) > 0.01


def _serial_meat(model, path, f):
    """One log's HAC meat at ``f``'s estimate, computed in this process (the single-log path's functions)."""
    from baseparams.ident import accumulate_prepared, log_columns
    from baseparams.ident.preprocess import prepare
    from baseparams.ident.uncertainty import hac_meat
    from baseparams.io.logs import read_log

    log = read_log(str(path), model.robot)
    prep = prepare(log)
    cols = log_columns(model, log)
    kept = []
    acc, _ = accumulate_prepared(model, prep, cols, 128.0, log, None, keep=kept)
    inv = np.linalg.inv(f.estimate.R11)
    return hac_meat(kept, inv @ inv.T, f.theta, f.estimate.weights, acc.samples), acc


@pytest.mark.slow
def test_pooled_standard_deviations_are_hac_over_the_logs(fleet, client):
    from baseparams.ident.uncertainty import apply_covariance, sandwich

    robot, model, paths = fleet
    # one log: the fleet's pooled HAC equals the single-log path's HAC
    one = identify_fleet(model, paths[:1], per_file=False, pooled=True, method="wls", client=client)
    meat, acc = _serial_meat(model, paths[0], one.pooled)
    ref = apply_covariance(fit(model, acc, "wls"), acc, lambda: [], "white")[0]  # white, for comparison
    hac = sandwich([meat], np.linalg.inv(one.pooled.estimate.R11) @ np.linalg.inv(one.pooled.estimate.R11).T,
                   acc.samples * acc.nrows)
    assert one.pooled.estimate.covariance.startswith("HAC")
    assert np.allclose(one.pooled.estimate.std, np.sqrt(np.diag(hac)), rtol=1e-8, atol=0)
    # the simulated noise is correlated: HAC's sigmas are not the white formula's
    assert np.median(one.pooled.estimate.std / ref.estimate.std) > 1.2
    # several logs: independent, so their meats add, each with its own bandwidth
    res = identify_fleet(model, paths, per_file=False, pooled=True, method="wls", client=client)
    h = np.linalg.inv(res.pooled.estimate.R11)
    pairs = [_serial_meat(model, p, res.pooled) for p in paths]
    cov = sandwich([m for m, _ in pairs], h @ h.T, sum(a.samples * a.nrows for _, a in pairs))
    assert np.allclose(res.pooled.estimate.std, np.sqrt(np.diag(cov)), rtol=1e-8, atol=0)
    white = identify_fleet(model, paths, per_file=False, pooled=True, method="wls", client=client,
                           covariance="white")
    assert white.pooled.estimate.covariance.startswith("white")
    assert res.to_json()["pooled"]["covariance"] == res.pooled.estimate.covariance


@pytest.mark.slow
def test_pooled_default_cross_validates_over_the_logs(fleet, client):
    """``auto`` pooled: the prior's weight by cross-validation whose blocks are whole logs (= the serial fit)."""
    robot, model, paths = fleet
    res = identify_fleet(model, paths, per_file=False, pooled=True, method="auto", client=client)
    accs = [file_factors(str(p), model)[0] for p in paths]
    ref = fit(model, combine(accs), "auto", blocks=accs)
    assert ref.selection is not None and res.pooled.selection is not None
    assert res.pooled.selection.weighting == ref.selection.weighting and res.pooled.selection.lam == ref.selection.lam
    assert np.abs(res.pooled.theta - ref.theta).max() <= 1e-10 * np.abs(ref.theta).max()
    note = res.to_json()["pooled"]["estimate"]
    assert note.startswith("default estimate: ") and "over the logs" in note
    if ref.selection.lam > 0:  # the covariance is mapped through the prior
        assert "prior" in res.pooled.estimate.covariance


@pytest.mark.slow  # 9-25 s: a Dask worker started and killed
def test_a_worker_killed_mid_run_loses_nothing(fleet):
    """Kill one of two worker processes while the fleet runs: Dask reruns its tasks elsewhere."""
    robot, model, paths = fleet
    many = [str(p) for p in paths] * 3
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    cl = distributed.Client(cluster)
    try:
        pids = list(cl.run(os.getpid).values())
        killed = []

        def kill_on_first_result(line):  # the first log done: the others are queued or running
            if not killed:
                os.kill(pids[0], signal.SIGKILL)
                killed.append(line)

        res = identify_fleet(model, many, per_file=False, pooled=True, method="ols", client=cl,
                             progress=kill_on_first_result)
        assert killed and pids[0] not in cl.run(os.getpid).values()  # that worker process is gone
    finally:
        cl.close()
        cluster.close()
    ref = fit(model, combine([file_factors(p, model)[0] for p in many]), "ols").theta
    assert np.abs(res.pooled.theta - ref).max() <= 1e-10 * np.abs(ref).max()
    assert sum(f["used"] for f in res.files) > 0 and len(res.files) == len(many)


@pytest.mark.slow
def test_a_million_samples_chunked_on_dask_equal_in_memory(client):
    """10^6 synthetic Puma560 samples: 10 Dask chunks reduced by TSQR on the workers give the same
    estimate as one accumulator over all samples in memory (to 1e-10 relative)."""
    from baseparams.fleet import synthetic_fleet_factors

    robot = baseparams.load("puma560")
    model = ident_model(baseparams.analyze(robot), rotor=False)
    theta = model.theta(robot.parameters("paper"), np.ones(model.drives.n_params))
    chunked = fit(model, synthetic_fleet_factors(model, theta, 10, 10**5, client, seed=5), "ols").theta
    from baseparams.fleet import synthetic_factors

    whole = fit(model, synthetic_factors(model, theta, 0, 10**6, seed=5), "ols").theta
    assert np.abs(chunked - whole).max() <= 1e-10 * np.abs(whole).max()
    assert np.abs(whole - theta).max() <= 1e-2 * np.abs(theta).max()  # and it is the truth, to the noise


# ---------------------------------------------------------------- bad logs in a fleet (issue 24)
@pytest.fixture(scope="module")
def mixed_fleet(tmp_path_factory):
    """Two good logs and three bad ones (binary in a CSV, no rows, a pickle in an .npz)."""
    folder = tmp_path_factory.mktemp("mixed")
    good = simulate_fleet(baseparams.load("puma560"), folder, robots=2, duration=3.0, rate=500.0, seed=1)
    (folder / "bad-binary.csv").write_bytes(good[0].read_bytes())
    (folder / "bad-empty.csv").write_text("t,q_joint1\n")
    (folder / "bad-archive.npz").write_bytes(b"garbage")
    return folder


def _fleet_cli(folder, capsys, *extra):
    from baseparams.cli import main

    code = main(["identify", "puma560", str(folder / "*.[cn][sp][vz]"), "--per-file", "--workers", "1", *extra])
    out = capsys.readouterr()
    return code, out.out, [ln for ln in out.err.splitlines() if "error" in ln or "skipped" in ln]


@pytest.mark.slow
def test_one_bad_log_does_not_stop_the_fleet(mixed_fleet, capsys):
    code, out, err = _fleet_cli(mixed_fleet, capsys, "--json")
    import json

    res = json.loads(out)
    assert code == 0 and res["logs"] == {"given": 5, "used": 2, "skipped": 3}
    assert sorted(s["path"].rsplit("/", 1)[1] for s in res["skipped"]) == ["bad-archive.npz", "bad-binary.csv",
                                                                          "bad-empty.csv"]
    assert len(res["per_file"]) == 2 and "Traceback" not in "".join(err)
    assert len([ln for ln in err if "skipped" in ln]) == 3  # one stderr line per bad log, naming it
    code, out, _ = _fleet_cli(mixed_fleet, capsys)
    assert code == 0 and "5 logs, 2 used, 3 skipped" in out and out.count("skipped: ") == 3


@pytest.mark.slow
def test_strict_fleet_and_a_fleet_of_only_bad_logs_exit_2(mixed_fleet, capsys, tmp_path):
    code, _, err = _fleet_cli(mixed_fleet, capsys, "--strict")
    assert code == 2 and [ln for ln in err if "error" in ln] == [
        ln for ln in err if ln.startswith("baseparams: error: --strict: 3 of 5 logs skipped")]
    for p in mixed_fleet.glob("bad-*"):
        (tmp_path / p.name).write_bytes(p.read_bytes())
    code, _, err = _fleet_cli(tmp_path, capsys)
    errors = [ln for ln in err if "error:" in ln]
    assert code == 2 and len(errors) == 1 and "no usable log: all 3 skipped" in errors[0]


@pytest.mark.slow
def test_a_fleet_log_in_degrees_is_refused_unless_allow_units_and_then_said(tmp_path):
    """Issue 51: the fleet read its logs without ``allow_units``: a log the single-log path accepts with
    --allow-units was skipped by the fleet whatever the flag. Now the flag reaches the reader and its
    WARNING comes back in the file's info."""
    from baseparams.errors import DataError
    from baseparams.ident.options import IdentOptions

    robot = baseparams.load("puma560")
    model = ident_model(baseparams.analyze(robot), rotor=False)
    path = simulate_fleet(robot, tmp_path, robots=1, duration=4.0, rate=500.0, seed=5)[0]
    with np.load(path) as z:
        table = {k: (np.degrees(z[k]) + 30.0 if k.startswith("q_") else z[k]) for k in z.files}  # beyond 4 pi
    degrees = tmp_path / "degrees.npz"
    np.savez(degrees, **table)
    with pytest.raises(DataError, match="allow-units"):
        file_factors(str(degrees), model)
    acc, info = file_factors(str(degrees), model, IdentOptions(allow_units=True))
    assert acc.samples > 0 and info["read"] == len(table["t"])
    assert len(info["warnings"]) == 1 and "units: WARNING" in info["warnings"][0]
    _, plain = file_factors(str(path), model)
    assert plain["warnings"] == []


@pytest.mark.slow
def test_a_fleet_says_rotor_inertia_and_terms_are_not_tried_and_rotor_forces_it(client, tmp_path, capsys):
    """A fleet fits one model to every log from its row factors: ``rotor="auto"`` and ``terms="auto"`` (identify's
    defaults) are not tried, each said in one note of the text and the JSON; ``--rotor`` fits rotor inertia on every
    log (no note), a model given with its rotor columns needs no note, and a forced term is refused in one line."""
    import json

    from baseparams.cli import main
    from baseparams.cli.parser import flag_message
    from baseparams.errors import BaseparamsError
    from baseparams.ident.model import model_for
    from baseparams.ident.options import IdentOptions

    robot = baseparams.load("puma560")
    paths = simulate_fleet(robot, tmp_path, robots=2, duration=4.0, rate=200.0, seed=6)
    argv = ["identify", "puma560", str(tmp_path / "*.npz"), "--per-file", "--pooled", "--scheduler",
            client.scheduler.address]
    assert main(argv) == 0
    text = capsys.readouterr().out.splitlines()
    rotor = [ln for ln in text if ln.startswith("note: rotor inertia (neither --rotor nor --no-rotor): not tried for "
                                                "a fleet of logs")]
    terms = [ln for ln in text if ln.startswith("note: model terms (--terms auto): not tried for a fleet of logs")]
    assert len(rotor) == 1 and "so the model has none; --rotor fits it" in rotor[0] and len(terms) == 1, text
    assert main([*argv, "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert [f"note: {flag_message(n, 'identify')}" for n in j["notes"]] == rotor + terms  # JSON: the keywords
    assert not any(n.startswith("Ia") for n in j["names"])
    assert main([*argv, "--rotor", "--terms", "none", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["notes"] == [] and sum(n.startswith("Ia") for n in j["names"]) == 4  # joints 1-2 regroup
    with_rotor = identify_fleet(model_for(robot, IdentOptions(rotor=True)), paths, client=client)  # options: defaults
    assert len(with_rotor.notes) == 1 and with_rotor.notes[0].startswith("model terms (terms=auto)")
    with pytest.raises(BaseparamsError, match="terms=dahl applies to one log or several recordings"):
        identify_fleet(with_rotor.model, paths, client=client, terms="dahl")
    assert main([*argv, "--terms", "dahl"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("baseparams: error: --terms dahl applies to one log"), err
