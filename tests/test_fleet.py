"""Fleet identification on a local Dask cluster: equality with the serial path, per-file and
pooled estimates, and a worker killed mid-run."""

import os
import signal

import distributed  # a test dependency: never skipped
import numpy as np
import pytest

import baseparams
from baseparams.fleet import file_factors, identify_fleet, simulate_fleet
from baseparams.ident.chunks import combine
from baseparams.ident.model import ident_model
from baseparams.ident.pipeline import fit


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
