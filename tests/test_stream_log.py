"""A log identified block by block from its file (issue 24): the whole log's answer, bounded memory.

The oracle is the in-memory path (:func:`baseparams.ident.identify` on
:func:`baseparams.io.logs.read_log`), independent of the streamed one in everything but the shared
preprocessing functions: the streamed run must give its estimate, standard deviations (HAC over
the streamed rows) and validation RMS, with windows and blocks far smaller than the log.
"""

from __future__ import annotations

import subprocess
import sys
import tracemalloc

import numpy as np
import pytest

from baseparams import load
from baseparams.errors import DataError
from baseparams.ident import identify
from baseparams.ident.simulate import simulate_log
from baseparams.ident.stream import NotStreamable, fold_edges, identify_stream, scan
from baseparams.io.logs import LogStream, read_log, write_log
from baseparams.jointlog import JointLog
from baseparams.tables import column_writer


@pytest.fixture(scope="module")
def puma():
    return load("puma560")


@pytest.fixture(scope="module")
def sim(puma, tmp_path_factory):
    """A simulated Puma560 log (40 s at 200 Hz, torque noise), as CSV and Parquet."""
    log, _ = simulate_log(puma, duration=40, rate=200, noise=0.2, rotor=True, seed=3)
    folder = tmp_path_factory.mktemp("stream")
    csv = folder / "sim.csv"
    write_log(csv, log)
    pq = pytest.importorskip("pyarrow.parquet")
    import pyarrow as pa

    table = pa.table({k: np.asarray(v) for k, v in
                      zip(["t", *[f"{kind}_{j}" for kind in ("q", "dq", "tau") for j in log.joints]],
                          [log.t, *log.q.T, *log.dq.T, *log.tau.T])})
    pq.write_table(table, folder / "sim.parquet", row_group_size=1000)
    return csv, folder / "sim.parquet"


def _compare(a, b, what):
    rel = np.abs(a.values - b.values) / np.maximum(np.abs(a.values), 1e-6 * np.abs(a.values).max())
    # rounding only: the in-memory filter may run compiled, the streamed one through scipy (1.6e-8 seen with the
    # curvature-keeping end extension of issue 48); a wrong window or sample moves the estimate by > 1e-4
    assert rel.max() <= 5e-8, f"{what}: estimate differs by {rel.max():.3g} relative"
    assert np.allclose(a.std, b.std, rtol=1e-8, atol=0), what
    assert a.samples == b.samples, what
    # the streamed log's training figure is on the fitted rows (labelled so); the in-memory one has both
    assert np.isclose(a.train.get("fit_rms_total", a.train["rms_total"]), b.train["rms_total"], rtol=1e-10)
    assert "fit's own rows" in b.train["measure"]
    if a.validation is not None:
        for key in ("rms_total", "rms_lowpassed_total"):
            if key in a.validation:
                assert np.isclose(a.validation[key], b.validation[key], rtol=1e-10), (what, key)
        assert a.validation["samples"] == b.validation["samples"]
    assert a.fit.estimate.covariance == b.fit.estimate.covariance


@pytest.mark.parametrize("method", ["auto", "ols"])
def test_streamed_equals_in_memory_on_a_small_log(puma, sim, method):
    """Windows of ~1800 samples, blocks of 64 kB and the HAC pass streamed: the whole log's answer."""
    csv, _ = sim
    kw = dict(method=method, rotor=True, holdout=8, score_cutoff=5.0)
    whole = identify(puma, read_log(csv, puma), **kw)
    got = []
    streamed = identify_stream(puma, LogStream(csv, puma, block_bytes=1 << 16), memory_mb=1.0,
                               predictions=lambda t, tau: got.append(np.column_stack([t, tau])), **kw)
    assert "windows" in " ".join(streamed.notes)
    _compare(whole, streamed, method)
    log = read_log(csv, puma)
    held = log.t >= log.t[-1] - 8
    pred = np.concatenate(got)
    assert np.array_equal(pred[:, 0], log.t[held])
    assert np.abs(pred[:, 1:] - whole.predict(log)[held]).max() <= 1e-9


def test_parquet_is_streamed_by_batches_with_the_same_answer(puma, sim):
    csv, pq = sim
    whole = identify(puma, read_log(csv, puma), method="wls", rotor=True, covariance="white")
    streamed = identify_stream(puma, LogStream(pq, puma), method="wls", rotor=True, covariance="white",
                               memory_mb=1.0)
    _compare(whole, streamed, "parquet")


def test_validation_on_another_streamed_log(puma, sim, tmp_path):
    csv, _ = sim
    other_log, _ = simulate_log(puma, duration=10, rate=200, noise=0.2, rotor=True, seed=4)
    other = tmp_path / "other.csv"
    write_log(other, other_log)
    whole = identify(puma, read_log(csv, puma), method="ols", rotor=True, validation=read_log(other, puma))
    streamed = identify_stream(puma, LogStream(csv, puma), method="ols", rotor=True,
                               validation=LogStream(other, puma, block_bytes=1 << 15), memory_mb=2.0)
    _compare(whole, streamed, "--validate")
    assert streamed.validation["source"] == str(other)


def _bad_copy(src, dest, line: int, old_new):
    lines = src.read_text().splitlines(keepends=True)
    lines[line - 1] = old_new(lines[line - 1])
    dest.write_text("".join(lines))


def test_a_bad_value_names_its_global_line_and_row_as_read_log_does(puma, sim, tmp_path):
    """A NaN, a word and a time going back, far past the first block: the whole file's line numbers."""
    csv, _ = sim
    bad = tmp_path / "bad.csv"
    cases = [(6001, lambda s: s[:s.index(",") + 1] + "nan" + s[s.index(",", s.index(",") + 1):]),
             (5003, lambda s: s[:s.rindex(",") + 1] + "oops\n"),
             (7000, lambda s: "0.5" + s[s.index(","):])]
    for line, edit in cases:
        _bad_copy(csv, bad, line, edit)
        with pytest.raises(DataError) as whole:
            read_log(bad, puma)
        with pytest.raises(DataError) as streamed:
            scan(LogStream(bad, puma, block_bytes=1 << 14))
        expect = str(whole.value).split(" (not finite")[0].split("; time must")[0]
        assert str(streamed.value).startswith(expect), (str(whole.value), str(streamed.value))
        assert f"line {line} (data row {line - 1})" in str(streamed.value)


def test_a_later_blocks_units_warning_reaches_the_streamed_notes(puma, sim, tmp_path):
    """Issue 51: a streamed run kept the notes of the first block only: with allow_units, an angle beyond
    4 pi far into the file went on without the WARNING the whole-log reader gives."""
    csv, _ = sim
    odd = tmp_path / "odd.csv"
    _bad_copy(csv, odd, 6001, lambda s: s[:s.index(",") + 1] + "20.0" + s[s.index(",", s.index(",") + 1):])
    whole = [n for n in read_log(odd, puma, allow_units=True).notes if "WARNING" in n]
    with pytest.raises(DataError, match="allow-units"):
        scan(LogStream(odd, puma, block_bytes=1 << 14))
    streamed = [n for n in scan(LogStream(odd, puma, block_bytes=1 << 14, allow_units=True)).notes if "WARNING" in n]
    assert len(whole) == 1 and len(streamed) == 1 and "units: WARNING" in streamed[0], (whole, streamed)
    assert "20" in streamed[0] and "line 6001" in streamed[0], streamed


def test_blank_and_comment_lines_keep_line_numbers_global(puma, sim, tmp_path):
    csv, _ = sim
    text = csv.read_text().splitlines(keepends=True)
    text[2000:2000] = ["\n", "# a comment\n", "   \n"]
    text[5000] = "nan" + text[5000][text[5000].index(","):]
    f = tmp_path / "commented.csv"
    f.write_text("".join(text))
    with pytest.raises(DataError) as whole:
        read_log(f, puma)
    with pytest.raises(DataError) as streamed:
        scan(LogStream(f, puma, block_bytes=1 << 13))
    assert str(streamed.value).split(" (not finite")[0] == str(whole.value).split(" (not finite")[0]
    assert "line 5001 (data row 4997)" in str(streamed.value)


def _jittered(puma, csv, path):
    log = read_log(csv, puma)
    t = log.t + np.random.default_rng(0).uniform(-0.3, 0.3, len(log.t)) / 200  # stamps off by up to 30 %
    write_log(path, JointLog(t, log.joints, log.q, log.tau, log.dq))
    return path


def test_non_uniform_time_is_resampled_block_by_block(puma, sim, tmp_path):
    """Jittered stamps: the grid, the interpolation and the estimate of the in-memory resampling."""
    odd = _jittered(puma, sim[0], tmp_path / "odd.csv")
    whole = identify(puma, read_log(odd, puma), method="wls", rotor=True)
    streamed = identify_stream(puma, LogStream(odd, puma, block_bytes=1 << 15), method="wls", rotor=True,
                               memory_mb=1.0)
    _compare(whole, streamed, "resampled")
    assert any(n.startswith("time: resampled 8000 non-uniform samples") and "block by block" in n
               for n in streamed.notes)
    with pytest.raises(NotStreamable, match="non-uniform"):  # a hold-out's states need the whole log's grid
        identify_stream(puma, LogStream(odd, puma), method="ols", holdout=5)


def _peak_mb(puma, path) -> float:
    tracemalloc.start()
    identify_stream(puma, LogStream(path, puma, block_bytes=1 << 15), method="ols", covariance="hac",
                    memory_mb=0.5, holdout=5, cutoff=5.0)
    peak = tracemalloc.get_traced_memory()[1] / 1e6
    tracemalloc.stop()
    return peak


@pytest.mark.slow
def test_memory_does_not_grow_with_the_log(puma, tmp_path, monkeypatch):
    """4x the samples, the same peak of Python/NumPy allocations once past the bounded subsamples.

    The bounds (head for the unit checks, cutoff subsample, report series, validation series, the
    HAC bandwidth's pilot) are lowered so that a short log exceeds them all; then nothing else may
    grow with the log.

    The cutoff is given, the same for both logs: the window (and so the peak, in pass 3) is sized by
    the filter's overlap, 12 cutoff periods, and a cutoff chosen from each log's excitation would
    differ between them (their training parts' bandwidths are 0.543 and 0.510 Hz, the in-memory
    choice too: cutoffs 5.43 and 5.10 Hz, windows of 1768 + 2 x 442 and 1884 + 2 x 471 samples), a
    window 7 % larger that has nothing to do with the length. The bounded subsample is still taken
    (pass 2) and used (the rate check, the spectrum). What grows in pass 3 is bounded: the folds'
    factors (5 x 6 of 55 x 55), filled as the pass reaches each fold (0.4 MB more at the longer
    log's peak, none after).
    """
    import baseparams.ident.stream as st
    import baseparams.ident.uncertainty as unc

    for name, value in (("HEAD_ROWS", 1024), ("SUBSAMPLE_MAX", 2048), ("SERIES_MAX", 256),
                        ("HELD_SERIES_MAX", 256), ("VALIDATION_ROWS", 512)):
        monkeypatch.setattr(st, name, value)
    monkeypatch.setattr(unc, "PILOT", 256)  # the HAC bandwidth's pilot samples
    files = []
    for duration in (40, 160):
        log, _ = simulate_log(puma, duration=duration, rate=200, noise=0.1, seed=5)
        files.append(tmp_path / f"log{duration}.csv")
        write_log(files[-1], log)
        del log
    _peak_mb(puma, files[0])  # one-time allocations (imports, caches) out of the way
    peaks = [_peak_mb(puma, f) for f in files]
    assert peaks[1] <= 1.05 * peaks[0] + 0.5, peaks


def test_fold_edges_are_the_in_memory_folds_without_an_array():
    rng = np.random.default_rng(4)
    for count in [*range(12), *rng.integers(12, 10**6, 20)]:
        for folds in (1, 2, 3, 5, 7):
            split = np.array_split(np.arange(count), folds)
            assert fold_edges(int(count), folds).tolist() == np.cumsum([0] + [len(x) for x in split]).tolist()


def test_column_writer_is_atomic_and_appends(tmp_path):
    out = tmp_path / "pred.csv"
    with column_writer(out, ["t", "tau_a"]) as write:
        write(np.array([[0.0, 1.0], [0.1, 2.0]]))
        write(np.array([[0.2, 3.0]]))
        assert not out.exists()
    assert out.read_text().splitlines() == ["t,tau_a", "0,1", "0.10000000000000001,2", "0.20000000000000001,3"]
    with pytest.raises(RuntimeError), column_writer(tmp_path / "gone.csv", ["t"]) as write:
        write(np.zeros((1, 1)))
        raise RuntimeError("interrupted")
    assert not (tmp_path / "gone.csv").exists()
    pq = pytest.importorskip("pyarrow.parquet")
    with column_writer(tmp_path / "pred.parquet", ["t", "x"]) as write:
        write(np.ones((3, 2)))
        write(np.zeros((2, 2)))
    assert pq.read_table(tmp_path / "pred.parquet").num_rows == 5


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "baseparams", *map(str, args)], capture_output=True, text=True)


@pytest.mark.slow
def test_cli_streams_on_request_and_says_so(sim, tmp_path):
    csv, _ = sim
    pred = tmp_path / "pred.csv"
    r = _cli("identify", "puma560", csv, "--rotor", "--holdout", "8", "--stream", "on", "-v", "--method", "ols",
             "--predictions", pred)
    assert r.returncode == 0, r.stderr
    assert "streaming" in r.stderr and "block by block" in r.stderr
    assert len(pred.read_text().splitlines()) == 1 + 1601
    folder = tmp_path / "bag"  # a ROS bag folder is read whole: --stream on refuses it in one line
    folder.mkdir()
    r = _cli("identify", "puma560", folder, "--stream", "on")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "--stream on" in r.stderr


def test_cli_streams_automatically_above_the_size_and_falls_back_on_odd_time(sim, tmp_path, monkeypatch, capsys):
    """Above STREAM_MIN_MB the log is streamed (said with -v); non-uniform time with a hold-out is read whole."""
    import baseparams.cli as cli

    csv, _ = sim
    # the 1.5 MB test log counts as large
    monkeypatch.setattr(sys.modules["baseparams.workflow.identify"], "STREAM_MIN_MB", 0.5)
    assert cli.main(["identify", "puma560", str(csv), "--method", "ols", "--rotor", "-v", "--json"]) == 0
    out = capsys.readouterr()
    assert "streaming" in out.err and "MB > 0.5 MB" in out.err
    assert "the log streamed from its file" in out.out
    odd = _jittered(load("puma560"), csv, tmp_path / "odd.csv")
    assert cli.main(["identify", "puma560", str(odd), "--method", "ols", "--rotor", "-v", "--json", "--holdout",
                     "5"]) == 0
    out = capsys.readouterr()
    assert "non-uniform time stamps" in out.err and "resampled in memory" in out.err
    assert "the log streamed from its file" not in out.out


def test_parquet_null_names_its_global_row(puma, sim, tmp_path, monkeypatch):
    import baseparams.io.logs as logs

    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    _, good = sim
    table = pq.read_table(good)
    col = table.column("tau_joint3").to_pylist()
    col[4321] = None
    bad = tmp_path / "null.parquet"
    pq.write_table(table.set_column(table.schema.get_field_index("tau_joint3"), "tau_joint3", pa.array(col)), bad)
    monkeypatch.setattr(logs, "BATCH_ROWS", 1000)
    with pytest.raises(DataError) as streamed:
        scan(LogStream(bad, puma))
    with pytest.raises(DataError) as whole:
        read_log(bad, puma)
    assert str(streamed.value) == str(whole.value)
    assert "row 4321 (0-based)" in str(streamed.value)


def _arrays(blocks):
    return [np.concatenate([getattr(b, k) for b in blocks]) for k in ("t", "q", "tau", "dq")]


@pytest.mark.parametrize("which", [0, 1])
def test_a_text_or_parquet_log_is_parsed_once_and_replayed_bit_for_bit(puma, sim, which, monkeypatch):
    from baseparams.ident import stream as st

    raw = LogStream(sim[which], puma, block_bytes=1 << 14) if which == 0 else LogStream(sim[which], puma)
    reads = []
    original = raw.blocks

    def counted():
        reads.append(1)
        yield from original()

    monkeypatch.setattr(raw, "blocks", counted)
    rep = st.Replay(raw, 10.0)
    first = list(rep.blocks())
    assert len(first) > 3 and rep.ready
    again, third = list(rep.blocks()), list(rep.blocks())
    assert len(reads) == 1  # the file was read once
    for a, b in zip(_arrays(first), _arrays(again)):
        np.testing.assert_array_equal(a, b)
    assert [b.n_samples for b in third] == [b.n_samples for b in first]
    assert again[0].notes == first[0].notes  # the reader's notes kept with the first block
    rep.close()
    assert not rep.ready


def test_replay_falls_back_to_reading_again(puma, sim, monkeypatch):
    from baseparams.ident import stream as st

    raw = LogStream(sim[0], puma, block_bytes=1 << 14)
    # a pass stopped early keeps nothing
    rep = st.Replay(raw, 10.0)
    gen = rep.blocks()
    next(gen)
    gen.close()
    assert not rep.ready
    # no room in the temporary folder: every pass reads the file
    import shutil

    monkeypatch.setattr(shutil, "disk_usage", lambda p: shutil._ntuple_diskusage(10**12, 10**12, 1000))
    rep = st.Replay(raw, 10.0)
    n = sum(b.n_samples for b in rep.blocks())
    assert not rep.ready and sum(b.n_samples for b in rep.blocks()) == n
