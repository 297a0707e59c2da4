"""The rigid-body regressor evaluated at a stride (issue 41): the fitted rows and the estimate are the full rate's.

:func:`baseparams.ident.chunks.prepared_rows` evaluates the model's smooth columns at every
``prep.stride``-th sample and filters them at that rate; Coulomb friction's columns (not smooth)
at the full rate. Oracle: ``prep.apply(model.regressor(...))`` at every sample (the definition of
parallel filtering), on seeded random arms with simulated noisy logs.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from baseparams.analysis import analyze
from baseparams.ident import chunks, identify, log_columns
from baseparams.ident import preprocess as pp
from baseparams.ident.model import ident_model
from baseparams.ident.simulate import simulate_log
from baseparams.robots.random import random_robot


def _case(seed: int):
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, n=int(rng.integers(2, 6)), joint_types="RP")
    log, _ = simulate_log(robot, duration=12.0, rate=1000.0, noise=0.05, seed=seed, rotor=True)
    model = ident_model(analyze(robot), True, ("viscous", "coulomb", "offset"), None)
    return robot, log, model


@pytest.mark.parametrize("seed", range(4))
def test_strided_rows_equal_the_full_rate_rows(seed):
    robot, log, model = _case(seed)
    prep = pp.prepare(log, decimate=24)
    assert prep.stride > 1 and 1000.0 / prep.stride >= pp.STRIDE_MARGIN * prep.design.cutoff
    cols = log_columns(model, log)
    f = prep.full
    oracle = prep.apply(model.regressor(f.q[:, cols], f.dq[:, cols], f.ddq[:, cols]))
    rows = chunks.prepared_rows(model, prep, cols)
    assert rows.shape == oracle.shape
    scale = np.abs(oracle).max(axis=0)  # per entry (row, column) over the samples
    err = np.abs(rows - oracle).max(axis=0)
    rr, cc, _ = model.broadband_entries(f.q[:1, cols], f.dq[:1, cols], f.ddq[:1, cols])
    assert len(rr) == len(model.coords)  # one Coulomb column per joint
    np.testing.assert_allclose(rows[:, rr, cc], oracle[:, rr, cc], rtol=0, atol=1e-12 * scale[rr, cc].max())
    smooth = scale > 0
    smooth[rr, cc] = False
    assert np.max(err[smooth] / scale[smooth]) < 1e-4
    # stride 1 is the full rate's definition, to rounding (the end extension's polynomial is a matrix product whose
    # last bits depend on how many columns are filtered together)
    one = chunks.prepared_rows(model, replace(prep, stride=1), cols)
    np.testing.assert_allclose(one, oracle, rtol=1e-12, atol=1e-13 * np.abs(oracle).max())


@pytest.mark.parametrize("seed", range(3))
def test_strided_estimate_within_a_small_fraction_of_its_sigma(seed, monkeypatch):
    robot, log, _ = _case(seed)
    runs = {}
    for margin in (pp.STRIDE_MARGIN, np.inf):
        monkeypatch.setattr(pp, "STRIDE_MARGIN", margin)
        runs[margin] = identify(robot, log, decimate=24, terms="none", method="ols")
    fast, full = runs[10.0], runs[np.inf]
    assert any(n.startswith("regressor: evaluated at 1 sample in") for n in fast.notes)
    assert any(n.startswith("regressor: evaluated and parallel-filtered at every sample") for n in full.notes)
    z = np.abs(fast.fit.theta - full.fit.theta) / full.fit.estimate.std
    assert z.max() < 0.01
