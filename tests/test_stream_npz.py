"""An NPZ log streamed from its archive (issue 41): block by block, stored or compressed, as read whole.

Oracles: :func:`baseparams.io.logs.read_log` (the whole arrays) for the blocks, and the same log
streamed from CSV for the identification (the same numbers, so the same estimate bit for bit).
"""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

from baseparams import load
from baseparams.errors import DataError
from baseparams.ident.simulate import simulate_log
from baseparams.ident.stream import concat, identify_stream
from baseparams.io import logs
from baseparams.io.logs import LogStream, log_columns_of, read_log, streamable, write_log


@pytest.fixture(scope="module")
def puma():
    return load("puma560")


@pytest.fixture(scope="module")
def sim(puma, tmp_path_factory):
    """A simulated Puma560 log (30 s at 200 Hz, seeded) as CSV, stored NPZ and compressed NPZ."""
    log, _ = simulate_log(puma, duration=30, rate=200, noise=0.2, rotor=True, seed=5)
    folder = tmp_path_factory.mktemp("npz")
    write_log(folder / "sim.csv", log)
    write_log(folder / "sim.npz", log)
    np.savez_compressed(folder / "packed.npz", **log_columns_of(log))
    return folder


@pytest.mark.parametrize("name", ["sim.npz", "packed.npz"])
@pytest.mark.parametrize("batch", [1000, 4096, 1 << 16])
def test_npz_blocks_are_the_whole_arrays(sim, puma, monkeypatch, name, batch):
    monkeypatch.setattr(logs, "BATCH_ROWS", batch)
    whole = read_log(sim / name, puma)
    s = LogStream(sim / name, puma)
    blocks = list(s.blocks())
    assert len(blocks) == -(-whole.n_samples // batch)
    assert all(b.n_samples <= batch for b in blocks)
    got = concat(blocks)
    for k in ("t", "q", "dq", "tau"):
        assert np.array_equal(getattr(got, k), getattr(whole, k)), k
    assert s.has_dq and not s.has_ddq and streamable(sim / name)


def test_npz_streamed_identification_is_the_csvs(sim, puma, monkeypatch):
    monkeypatch.setattr(logs, "BATCH_ROWS", 777)  # blocks unrelated to the windows
    a = identify_stream(puma, LogStream(sim / "sim.csv", puma, block_bytes=50_000), rotor=True, holdout=5.0,
                        memory_mb=4)
    b = identify_stream(puma, LogStream(sim / "packed.npz", puma), rotor=True, holdout=5.0, memory_mb=4)
    assert np.array_equal(a.values, b.values) and np.array_equal(a.std, b.std)
    assert a.validation["rms_total"] == b.validation["rms_total"]


def test_npz_bad_members_one_line(sim, puma, tmp_path):
    cols = log_columns_of(read_log(sim / "sim.npz", puma))
    short = dict(cols, tau_joint3=cols["tau_joint3"][:-5])
    np.savez(tmp_path / "short.npz", **short)
    with pytest.raises(DataError, match=r"array 'tau_joint3' has \d+ rows, array 't' has") as e:
        list(LogStream(tmp_path / "short.npz", puma).blocks())
    assert "\n" not in str(e.value)
    bad = dict(cols)
    bad["q_joint2"] = bad["q_joint2"].copy()
    bad["q_joint2"][3000] = np.nan
    np.savez(tmp_path / "nan.npz", **bad)
    with pytest.raises(DataError, match=r"q_joint2.*index 3000"):
        list(LogStream(tmp_path / "nan.npz", puma).blocks())
    with zipfile.ZipFile(tmp_path / "junk.npz", "w") as z:
        z.writestr("t.txt", "not an array")
    with pytest.raises(DataError, match="not a NumPy array"):
        LogStream(tmp_path / "junk.npz", puma)


def test_spilled_rows_give_the_recomputed_covariance(sim, puma, monkeypatch):
    """HAC over the fitted rows read back from the temporary file = over rows recomputed from the log."""
    from baseparams.ident import stream as st

    calls = []
    real = st.fitted
    monkeypatch.setattr(st, "fitted", lambda *a: calls.append(1) or real(*a))
    s = LogStream(sim / "sim.npz", puma)
    spilled = identify_stream(puma, s, rotor=True, memory_mb=0.5)  # rows above 0.5 MB: spilled
    assert len(calls) == 1  # pass 3 only: pass 4 read the file
    monkeypatch.setattr(st.Spilled, "open", classmethod(lambda cls, mb: None))  # no room: recomputed
    again = identify_stream(puma, s, rotor=True, memory_mb=0.5)
    assert len(calls) == 3
    assert np.array_equal(spilled.values, again.values) and np.array_equal(spilled.std, again.std)
    assert np.array_equal(spilled.series["train"]["tau_hat"], again.series["train"]["tau_hat"])
