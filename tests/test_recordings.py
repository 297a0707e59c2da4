"""Several recordings of one robot in one identification (issue 48): one system of rows, each recording a block."""

from __future__ import annotations

import numpy as np
import pytest

import baseparams
from baseparams.errors import BaseparamsError
from baseparams.ident import IdentOptions, accumulate_prepared, identify, log_columns
from baseparams.ident.model import model_for
from baseparams.ident.preprocess import prepare
from baseparams.ident.simulate import simulate_log
from baseparams.robots import random_robot


def _logs(robot, seeds, seconds=6.0, rate=200.0):
    return [simulate_log(robot, duration=seconds, rate=rate, noise=0.05, seed=s)[0] for s in seeds]


@pytest.mark.parametrize("seed", [0, 1])
def test_several_recordings_are_one_least_squares_system(seed):
    """Plain OLS of two recordings = the least-squares solution of both recordings' rows stacked (computed apart)."""
    robot = random_robot(np.random.default_rng(seed), 3, "R", False, branching=0.0)
    a, b = _logs(robot, [10 + seed, 20 + seed])
    opts = IdentOptions(method="ols", terms="none", cutoff=8.0)
    res = identify(robot, [a, b], opts)
    model = model_for(robot, opts)
    rows, taus = [], []
    for x in (a, b):
        prep = prepare(x, cutoff=8.0)
        cols = log_columns(model, x)
        kept: list = []
        accumulate_prepared(model, prep, cols, 128.0, x, keep=kept)
        rows.append(np.concatenate([k[0] for k in kept]))
        taus.append(np.concatenate([k[1] for k in kept]))
    w = np.concatenate(rows).reshape(-1, model.n_params)
    theta = np.linalg.lstsq(w, np.concatenate(taus).reshape(-1), rcond=None)[0]
    np.testing.assert_allclose(res.fit.theta, theta, rtol=1e-6, atol=1e-8 * np.abs(theta).max())
    assert res.samples["read"] == a.n_samples + b.n_samples
    assert res.train["samples"] == a.n_samples + b.n_samples and len(res.train["recordings"]) == 2


def test_the_default_cross_validates_with_each_recording_one_block():
    robot = baseparams.load("puma560")
    a, b, c = _logs(robot, [1, 2, 3], seconds=5.0)
    res = identify(robot, [a, b, c])
    sel = res.to_json()["selection"]
    assert sel["rule"] == "recordings" and sel["folds"] == 3
    assert any("each recording one block" in n for n in res.notes)
    assert any(n.startswith("several recordings: 3") for n in res.notes)
    # one recording alone: its blocks are pieces of one motion (5 s, too short: the structure rule)
    one = identify(robot, a).to_json()["selection"]
    assert one["rule"] == "structure" and one["estimator"] in ("physical", "least squares")


def test_several_recordings_refuse_a_holdout_and_an_empty_list():
    robot = baseparams.load("puma560")
    a, b = _logs(robot, [1, 2], seconds=3.0)
    with pytest.raises(BaseparamsError, match="holdout with several recordings"):
        identify(robot, [a, b], holdout=1.0)
    with pytest.raises(BaseparamsError, match="no log given"):
        identify(robot, [])
