"""A large model's fitted rows held in a temporary file (issue 51): the rows a few measured rows at a time are the
model's, the file's readers are the row factors', and an identification from spilled rows is the in-memory one."""

from __future__ import annotations

import tempfile

import numpy as np
import pytest

from baseparams import load
from baseparams.ident import identify, spilled
from baseparams.ident.estimate import RowAccumulator
from baseparams.ident.model import ident_model
from baseparams.ident.simulate import simulate_log
from baseparams.robots import random_robot


@pytest.mark.parametrize("seed", range(4))
def test_a_views_rows_are_the_models_rows(seed):
    """``RowsView.regressor`` is ``model.regressor(...)[:, rows]`` (rigid body, rotor and friction columns) and its
    broadband entries are the model's on those rows, for random trees and random row subsets."""
    import baseparams as bp

    rng = np.random.default_rng(seed)
    robot = random_robot(rng, int(rng.integers(3, 8)), joint_types="RP", branching=0.4)
    model = ident_model(bp.analyze(robot, verify=False), rotor=bool(seed % 2))
    q, dq, ddq = rng.normal(size=(3, 9, robot.dof))
    whole = model.regressor(q, dq, ddq)
    rows = np.sort(rng.choice(len(model.coords), size=int(rng.integers(1, len(model.coords) + 1)), replace=False))
    view = spilled.RowsView(model, rows)
    assert np.array_equal(view.regressor(q, dq, ddq), whole[:, rows])
    r, c, v = view.broadband_entries(q, dq, ddq)
    assert np.array_equal(v, whole[:, rows[r], c]) and len(r) == sum(
        int(x) in set(rows.tolist()) for x in model.broadband_entries(q, dq, ddq)[0])


def _spilled(blocks, m, p, edges, zero=None):
    """``SpilledRows`` of ``blocks`` written sample-major, with children at ``edges`` (``zero (m, p)``: entries zero
    in every sample, as a tree's rows have)."""
    a = np.concatenate([x for x, _ in blocks])
    tau = np.concatenate([t for _, t in blocks])
    if zero is not None:
        a[:, zero] = 0.0
    fh = tempfile.TemporaryFile()  # noqa: SIM115 - held by the accumulators it returns, as spill() holds it
    fh.write(np.concatenate([a, tau[:, :, None]], axis=2).tobytes())
    fh.flush()
    kids = [spilled.SpilledRows(fh, m, p, lo, hi) for lo, hi in zip(edges[:-1], edges[1:])]
    return spilled.SpilledRows(fh, m, p, 0, len(a), kids), a, tau


@pytest.mark.parametrize("seed", range(5))
def test_the_files_readers_are_the_row_factors(seed, monkeypatch):
    """Stacked factors of any weighting, residual sums of squares, column norms, row Gram matrices and the HAC
    pass's blocks read from the file (in blocks of any size, with folds, an empty one too) are those of a
    :class:`RowAccumulator` fed the same rows."""
    rng = np.random.default_rng(seed)
    m, p = int(rng.integers(1, 5)), int(rng.integers(2, 12))
    blocks = [(rng.normal(size=(k, m, p)), rng.normal(size=(k, m))) for k in rng.integers(1, 30, size=3)]
    monkeypatch.setattr(spilled, "BLOCK_BYTES", float(rng.integers(1, 5) * 8 * m * (p + 1)))
    count = sum(len(a) for a, _ in blocks)
    cut = sorted(rng.integers(0, count + 1, size=3))
    # a chain's pattern (row r uses the columns from some start on) or random zeros, or none
    starts = np.sort(rng.integers(0, p, size=m))
    zero = [None, np.arange(p)[None, :] < starts[:, None], rng.random((m, p)) < 0.4][seed % 3]
    whole, a, tau = _spilled(blocks, m, p, [0, cut[0], cut[0], *cut[1:], count], zero)
    ref = RowAccumulator(m, p).add(a, tau)
    w = rng.uniform(0.5, 2.0, m)
    for acc in (whole, whole.children[-1] if count - cut[-1] else whole):
        lo, hi = acc.lo, acc.hi
        part = RowAccumulator(m, p).add(a[lo:hi], tau[lo:hi])
        rs, rr = acc.stacked(w), part.stacked(w)
        assert np.allclose(rs.T @ rs, rr.T @ rr, atol=1e-9 * max(1.0, np.abs(rr.T @ rr).max()))
        assert np.allclose(np.tril(rs, -1), 0.0)  # triangular in the parameters' order
    theta = rng.normal(size=p)
    assert np.allclose(whole.row_sse(theta), ref.row_sse(theta))
    assert np.allclose(whole.column_norms2(), ref.column_norms2())
    cols = [0, p]
    assert np.allclose(whole.row_gram(m - 1, cols), ref.row_gram(m - 1, cols))
    got = list(whole.fitted_blocks())
    assert np.array_equal(np.concatenate([x for x, _ in got]), a)
    assert np.array_equal(np.concatenate([y for _, y in got]), tau)
    assert whole.samples == count and sum(c.samples for c in whole.children) == count


@pytest.mark.parametrize("method", ["ols", "auto"])
def test_an_identification_from_spilled_rows_is_the_in_memory_one(method, monkeypatch):
    """The spilled path forced on a Puma log: the same values, standard deviations (HAC from the file's blocks)
    and fit RMS as the rows held in memory, and a note saying where the rows were held."""
    puma = load("puma560")
    log, _ = simulate_log(puma, duration=20, rate=200, noise=0.1, rotor=True, seed=3)
    held = identify(puma, log, method=method, rotor=True)
    monkeypatch.setattr(spilled, "SPILL_MIN_MB", 0.0)
    got = identify(puma, log, method=method, rotor=True, memory_mb=0.05)
    assert any("held in a temporary file" in n for n in got.notes)
    assert not any("held in a temporary file" in n for n in held.notes)
    rel = np.abs(got.values - held.values) / np.maximum(np.abs(held.values), 1e-6 * np.abs(held.values).max())
    assert rel.max() <= 1e-8, rel.max()
    assert np.allclose(got.std, held.std, rtol=1e-8, atol=0)
    assert got.fit.estimate.covariance == held.fit.estimate.covariance
    assert np.isclose(got.train["fit_rms_total"], held.train["fit_rms_total"], rtol=1e-10)
    assert got.samples == held.samples


@pytest.mark.parametrize("seed", range(5))
def test_only_trees_whose_row_factors_exceed_the_budget_spill(seed):
    """Spilled exactly when a tree's row factors ``m min(S, p + 1) (p + 1)`` exceed ``max(memory_mb, SPILL_MIN_MB)``;
    an arm's are a fraction of a megabyte, never; a robot with loops or a logged floating base never."""
    from types import SimpleNamespace

    import baseparams as bp

    assert not spilled.spills(ident_model(bp.analyze(load("puma560"), verify=False)), 10**7, 0.01)
    rng = np.random.default_rng(seed)
    m, p, s = int(rng.integers(1, 2000)), int(rng.integers(1, 20000)), int(rng.integers(1, 10**6))
    budget = float(10 ** rng.uniform(-1, 4))
    robot = SimpleNamespace(has_loops=False, floating=bool(seed % 2))
    model = SimpleNamespace(robot=robot, coords=np.arange(m), n_params=p, log_base=False)
    mb = m * min(s, p + 1) * (p + 1) * 8 / 1e6
    assert spilled.spills(model, s, budget) == (mb > max(budget, spilled.SPILL_MIN_MB))
    assert not spilled.spills(SimpleNamespace(**{**vars(model), "robot": SimpleNamespace(has_loops=True,
                                                                                         floating=False)}), s, 0.0)
    assert not spilled.spills(SimpleNamespace(**{**vars(model), "log_base": True,
                                                 "robot": SimpleNamespace(has_loops=False, floating=True)}), s, 0.0)


@pytest.mark.parametrize("seed", range(6))
def test_a_staircase_order_puts_every_rows_columns_after_its_start(seed):
    """``staircase_order``: a permutation; each row's nonzero columns at or after its start; a chain's rows (row ``r``
    the columns of bodies ``r ..``), shuffled, start where their bodies' columns do; an empty row starts at the end."""
    rng = np.random.default_rng(seed)
    m, per = int(rng.integers(1, 9)), int(rng.integers(1, 4))
    body = np.repeat(np.arange(m), per)  # the body of each column
    chain = (body[None, :] >= np.arange(m)[:, None]) & (rng.random((m, m * per)) < 0.8)
    chain |= body[None, :] == np.arange(m)[:, None]  # each row has its own body's columns
    shuffle = rng.permutation(m * per)
    support = chain[:, shuffle]
    if seed % 2:
        support = np.vstack([support, np.zeros((1, m * per), dtype=bool)])
    perm, starts = spilled.staircase_order(support)
    assert np.array_equal(np.sort(perm), np.arange(m * per))
    placed = support[:, perm]
    for r in range(len(support)):
        assert not placed[r, :starts[r]].any()
    assert np.array_equal(starts[:m], np.arange(m) * per)
    if seed % 2:
        assert starts[-1] == m * per


@pytest.mark.parametrize("seed", range(3))
def test_released_factors_are_made_again_the_same(seed):
    """``release()`` drops every cached factor (the whole's and its pieces', spilled or in memory) and nothing else:
    the next read is the same factor."""
    rng = np.random.default_rng(seed)
    m, p = int(rng.integers(1, 4)), int(rng.integers(2, 9))
    blocks = [(rng.normal(size=(k, m, p)), rng.normal(size=(k, m))) for k in rng.integers(5, 30, size=3)]
    count = sum(len(a) for a, _ in blocks)
    whole, a, tau = _spilled(blocks, m, p, [0, count // 2, count])
    memory = RowAccumulator.combine([RowAccumulator(m, p).add(a[:9], tau[:9]),
                                     RowAccumulator(m, p).add(a[9:], tau[9:])])
    w = rng.uniform(0.5, 2.0, m)
    for acc, pieces in ((whole, whole.children), (memory, memory._parts)):
        first = np.array(acc.stacked(w))
        assert acc.nbytes() > 0 if acc is whole else acc._stacked
        acc.release()
        assert not acc._stacked and all(not x._stacked for x in pieces)
        if acc is whole:
            assert acc.nbytes() == sum(c._norms.nbytes for c in [whole, *whole.children] if c._norms is not None)
        again = acc.stacked(w)
        assert np.allclose(again.T @ again, first.T @ first, rtol=1e-12, atol=1e-12 * np.abs(first).max() ** 2)
