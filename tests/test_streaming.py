"""StreamingQR: the triangular factor of a tall matrix fed in blocks of rows."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from baseparams.errors import BaseparamsError
from baseparams.numerics import StreamingQR, rank_decision


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), ncols=st.integers(1, 12), splits=st.lists(st.integers(0, 40), max_size=6),
       rank_deficit=st.integers(0, 3))
def test_streaming_factor_equals_the_whole_matrix(seed, ncols, splits, rank_deficit):
    """Any split into blocks: ``R^T R = W^T W``, same singular values, ``||W x|| = ||R x||``."""
    rng = np.random.default_rng(seed)
    rows = sum(splits) + 1
    w = rng.normal(size=(rows, ncols)) * 10.0 ** rng.uniform(-3, 3, ncols)
    if rank_deficit and ncols > rank_deficit:
        w[:, :rank_deficit] = w[:, rank_deficit:] @ rng.normal(size=(ncols - rank_deficit, rank_deficit))
    qr = StreamingQR(ncols)
    start = 0
    for k in splits + [1]:
        qr.add(w[start:start + k])
        start += k
    assert qr.rows == rows
    assert qr.r.shape == (min(rows, ncols), ncols)
    assert np.allclose(np.triu(qr.r), qr.r)
    scale = np.linalg.norm(w) ** 2
    assert np.abs(qr.r.T @ qr.r - w.T @ w).max() <= 1e-12 * scale
    x = rng.normal(size=ncols)
    assert np.isclose(np.linalg.norm(qr.r @ x), np.linalg.norm(w @ x), rtol=1e-9, atol=1e-12 * np.linalg.norm(w))
    sw, sr = np.linalg.svd(w, compute_uv=False), np.linalg.svd(qr.r, compute_uv=False)
    assert np.allclose(sr, sw[: len(sr)], rtol=1e-9, atol=1e-12 * sw[0])


def test_rank_decision_on_the_factor_matches_the_matrix(rng):
    """The certification's numerical nullspace is the same computed on R as on W."""
    w = rng.normal(size=(3000, 40)) @ np.diag(np.r_[np.ones(31), np.zeros(9)]) @ rng.normal(size=(40, 40))
    a, b = rank_decision(w), rank_decision(StreamingQR(40).add(w).r)
    assert a.rank == b.rank == 31
    proj = a.null_basis @ a.null_basis.T - b.null_basis @ b.null_basis.T
    assert np.abs(proj).max() < 1e-9


def test_bad_blocks_are_one_clear_error():
    qr = StreamingQR(3)
    with pytest.raises(BaseparamsError, match=r"shape \(k, 3\)"):
        qr.add(np.ones((4, 2)))
    with pytest.raises(BaseparamsError, match="NaN"):
        qr.add(np.array([[1.0, np.nan, 0.0]]))
    assert qr.rows == 0 and qr.r.shape == (0, 3)


def test_an_empty_block_changes_nothing(rng):
    a = rng.normal(size=(30, 4))
    f = StreamingQR(4).add(a[:20]).add(np.zeros((0, 4))).add(a[20:])
    g = StreamingQR(4).add(a)
    np.testing.assert_allclose(np.abs(f.r), np.abs(g.r), atol=1e-12)


def test_a_chunk_whose_samples_are_all_too_slow_is_skipped_not_a_traceback():
    """A rest in the middle of a log, chunked (small memory) with --min-speed: the rest chunk is empty."""
    import baseparams
    from baseparams.ident import identify
    from baseparams.ident.simulate import fourier_trajectory, simulate_log

    robot = baseparams.load("puma560")
    t, q, dq, ddq = fourier_trajectory(6, 30.0, 200.0, np.random.default_rng(1))
    rest = (t > 5) & (t < 25)
    q[rest], dq[rest], ddq[rest] = q[rest][0], 0.0, 0.0  # the robot stops for 20 s: whole chunks at rest
    log, _ = simulate_log(robot, trajectory=(t, q, dq, ddq), seed=1)
    res = identify(robot, log, method="ols", min_speed=0.01, memory_mb=0.5, cutoff=10.0)
    assert any("chunks" in n for n in res.notes)
    assert res.samples["removed"] and sum(res.samples["removed"].values()) > 0
    assert np.all(np.isfinite(res.fit.theta))


def test_rank_decision_survives_an_svd_that_does_not_converge(monkeypatch):
    """LAPACK's divide-and-conquer SVD fails on rare inputs (a 60x60 R factor of a mimic hand):
    the decision falls back to the QR-iteration driver and decides the same rank."""
    import baseparams.numerics as nm

    rng = np.random.default_rng(0)
    w = rng.normal(size=(200, 8)) @ np.diag([1, 1, 1, 1, 1, 1, 0, 0]) @ rng.normal(size=(8, 8))
    ref = nm.rank_decision(w)
    real = np.linalg.svd

    def failing(*a, **k):
        raise np.linalg.LinAlgError("SVD did not converge")

    monkeypatch.setattr(nm.np.linalg, "svd", failing)
    got = nm.rank_decision(w)
    monkeypatch.setattr(nm.np.linalg, "svd", real)
    assert got.rank == ref.rank == 6 and got.nullity == 2
    np.testing.assert_allclose(got.singular_values, ref.singular_values, rtol=1e-10, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), ncols=st.integers(1, 70), k=st.integers(0, 90), untouched=st.integers(0, 5))
def test_a_triangular_update_is_the_qr_of_the_stacked_rows(seed, ncols, k, untouched):
    """``triangular_update(R, rows)``: upper triangular, ``R'^T R' = R^T R + rows^T rows`` and the same singular values
    as a dense QR of ``[R; rows]``, also when ``R`` has zero diagonal entries (columns no row touched yet) and the rows
    are fewer than the columns."""
    from baseparams.numerics import triangular_update

    rng = np.random.default_rng(seed)
    r = np.triu(rng.normal(size=(ncols, ncols)))
    r[:min(untouched, ncols)] = 0.0
    rows = rng.normal(size=(k, ncols)) * 10.0 ** rng.uniform(-3, 3, ncols)
    want = r.T @ r + rows.T @ rows
    got = triangular_update(r.copy(), rows.copy())
    assert got.shape == (ncols, ncols) and np.array_equal(np.tril(got, -1), np.zeros_like(got))
    assert np.abs(got.T @ got - want).max() <= 1e-12 * max(np.abs(want).max(), 1.0)
    dense = np.linalg.qr(np.vstack([r, rows]), mode="r")
    other = np.triu(rng.normal(size=(ncols, ncols)))  # a TSQR's merge of two triangles
    both = triangular_update(r.copy(), np.array(other, order="F"), triangular=True)
    assert np.array_equal(np.tril(both, -1), np.zeros_like(both))
    assert np.abs(both.T @ both - r.T @ r - other.T @ other).max() <= 1e-12 * max(np.abs(want).max(), 1.0,
                                                                                   np.abs(other).max() ** 2)
    assert np.allclose(np.linalg.svd(got, compute_uv=False), np.linalg.svd(dense, compute_uv=False),
                       rtol=1e-9, atol=1e-12 * max(np.linalg.norm(want) ** 0.5, 1.0))


@pytest.mark.parametrize("seed", range(4))
def test_a_wide_factor_fed_past_its_step_is_the_whole_matrix(seed, monkeypatch):
    """Steps folded into a full triangle (the triangular update) give the dense factor: ``R^T R = W^T W``."""
    rng = np.random.default_rng(seed)
    monkeypatch.setattr(StreamingQR, "STEP", int(rng.integers(1, 30)))
    monkeypatch.setattr(StreamingQR, "STEP_BYTES", 8.0)
    monkeypatch.setattr(StreamingQR, "WIDE", int(rng.integers(1, 10)))
    ncols = int(rng.integers(1, 25))
    w = rng.normal(size=(int(rng.integers(ncols, 300)), ncols))
    qr = StreamingQR(ncols)
    held = []
    for part in np.array_split(w, int(rng.integers(1, 20))):
        qr.add(part)
        held.append((qr.r, qr.r.copy()))  # a factor read mid-way stays what it was when more rows come
    assert all(np.array_equal(r, copy) for r, copy in held)
    assert np.allclose(np.tril(qr.r, -1), 0.0)
    assert np.abs(qr.r.T @ qr.r - w.T @ w).max() <= 1e-12 * np.linalg.norm(w) ** 2
