"""Memory of long, high-rate logs (issue 51): windows bounded in time, a window's states prepared a few joints at a
time with :func:`~baseparams.ident.preprocess.prepare`'s arithmetic, and a ``memory_mb`` the windows cannot meet
said in one WARNING line with the memory they need."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from baseparams import load
from baseparams.ident import chunks, identify
from baseparams.ident.preprocess import prepare
from baseparams.ident.simulate import simulate_log
from baseparams.ident.stream import identify_stream
from baseparams.io.logs import LogStream, write_log


@pytest.fixture(scope="module")
def puma():
    return load("puma560")


@pytest.fixture(scope="module")
def short_log(puma, tmp_path_factory):
    """A simulated Puma560 log (20 s at 200 Hz) and its CSV file."""
    log, _ = simulate_log(puma, duration=20, rate=200, noise=0.1, seed=7)
    path = tmp_path_factory.mktemp("large_logs") / "puma.csv"
    write_log(path, log)
    return log, path


@pytest.mark.parametrize("seed", range(3))
def test_window_states_are_prepares_arrays_joint_by_joint(puma, seed, monkeypatch):
    """Preparing a window a few joints at a time gives :func:`prepare`'s full-rate arrays to rounding (with measured
    rates or without, any grouping of the columns, any order of the state columns)."""
    rng = np.random.default_rng(seed)
    log, _ = simulate_log(puma, duration=float(rng.uniform(3, 8)), rate=float(rng.uniform(150, 400)), noise=0.1,
                          seed=seed)
    if seed % 2:
        log = type(log)(log.t, log.joints, log.q, log.tau, source=log.source)  # no measured rates: derived
    cols = rng.permutation(len(log.joints))
    cutoff = float(rng.uniform(4, 12))
    whole = prepare(log, cutoff=cutoff, decimate=1).full
    monkeypatch.setattr(chunks, "FILTER_VALUES", int(rng.integers(1, 3)) * log.n_samples)  # 1 or 2 joints at once
    design, q, dq, ddq, tau = chunks.window_states(log, cutoff, cols)
    assert design.cutoff == cutoff
    for got, want in ((q, whole.q), (dq, whole.dq), (ddq, whole.ddq), (tau, whole.tau)):
        # to rounding: the end extension's polynomial is a matrix product whose last bits depend on how many
        # columns are filtered together (x the derivatives' gain: 1e-11 relative seen on derived accelerations)
        np.testing.assert_allclose(got, want[:, cols], rtol=1e-8, atol=1e-9 * np.abs(want).max())


@pytest.mark.parametrize("seed", range(5))
def test_the_floor_note_is_given_exactly_when_a_window_exceeds_the_budget(puma, seed):
    """``window_size`` never goes below its floor; ``floor_note`` speaks exactly when a window at that size needs
    more than ``memory_mb``, in one line naming the floor and the memory needed."""
    from baseparams.ident.model import model_for
    from baseparams.ident.options import options_of

    rng = np.random.default_rng(seed)
    model = model_for(puma, options_of(None, {}))
    margin, stride = int(rng.integers(10, 10**5)), int(rng.integers(1, 50))
    budget = float(10 ** rng.uniform(-2, 4))
    size = chunks.window_size(model, budget, margin, stride)
    assert size >= chunks.MIN_OWNED_MARGINS * margin
    need = (size + 2 * margin) * chunks.sample_bytes(model, stride) / 1e6
    note = chunks.floor_note(model, budget, margin, size, stride)
    assert (note is None) == (need <= budget)
    if note is not None:
        assert "\n" not in note and note.startswith("memory: WARNING") and f"{size + 2 * margin} samples" in note
        assert f"about {need:.0f} MB" in note


def test_a_memory_mb_the_windows_cannot_meet_is_said_streamed_and_in_memory(puma, short_log):
    """Issue 51: a tiny ``memory_mb`` went over silently once the window was at its floor; now one WARNING line,
    streamed and in memory, and the same estimate as with room to spare (it changes the windows, not the fit)."""
    log, path = short_log
    kw = dict(method="ols", covariance="white", cutoff=5.0)
    tight = identify_stream(puma, LogStream(path, puma, block_bytes=1 << 15), memory_mb=0.01, **kw)
    roomy = identify_stream(puma, LogStream(path, puma, block_bytes=1 << 15), memory_mb=1e4, **kw)
    said = [n for n in tight.notes if "memory: WARNING" in n]
    assert len(said) == 1 and "memory_mb 0.01 MB cannot be met" in said[0] and "samples" in said[0], tight.notes
    assert not [n for n in roomy.notes if "WARNING" in n]
    assert np.allclose(tight.values, roomy.values, rtol=5e-8, atol=1e-9 * np.abs(roomy.values).max())
    inmem = identify(puma, log, memory_mb=0.01, **kw)
    said = [n for n in inmem.notes if "memory: WARNING" in n]
    assert len(said) == 1 and "chunks" in said[0], inmem.notes
    assert np.allclose(inmem.values, roomy.values, rtol=5e-8, atol=1e-9 * np.abs(roomy.values).max())


_HIGH_WATER = """
for _line in open("/proc/self/status"):
    if _line.startswith("VmHWM:"):
        print("VmHWM", int(_line.split()[1]))
"""


@pytest.mark.slow
def test_a_100_khz_log_is_identified_within_a_few_times_its_own_size(tmp_path):
    """Issue 51: a 10^6-sample 100 kHz log (152 MB of arrays) peaked at 1.26 GB in ``identify`` (windows of
    1.2 million samples, 24 columns filtered together); now windows of 3 filter overlaps, states filtered a joint at
    a time: 0.56 GB measured; bounded here at 5x the log's arrays."""
    log = tmp_path / "fast.npz"
    done = subprocess.run([sys.executable, "-m", "baseparams", "simulate", "puma560", str(log), "--duration", "10",
                           "--rate", "100000", "--noise", "0.05"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-500:]
    with np.load(log) as z:
        size_mb = sum(z[k].nbytes for k in z.files) / 1e6
    code = textwrap.dedent(f"""
        from baseparams.cli import main
        assert main(["identify", "puma560", {str(log)!r}, "--json"]) == 0
    """)
    done = subprocess.run([sys.executable, "-c", code + _HIGH_WATER], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-500:]
    mb = [int(x.split()[1]) / 1024 for x in done.stdout.splitlines() if x.startswith("VmHWM ")][-1]
    assert mb < 5 * size_mb, (mb, size_mb)
