"""Preprocessing: resampling, the zero-phase low-pass, derivatives, decimation, parallel filtering, a real log."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import signal

from baseparams.errors import DataError
from baseparams.ident.preprocess import (
    MIN_FITTED,
    decimate,
    derivatives,
    excitation_bandwidth,
    lowpass_design,
    prepare,
    remove_slow,
    resample,
    zero_phase,
)
from baseparams.jointlog import JointLog

from paths import SHARED

PANDA = SHARED.parent / "ident" / "panda_gaz2019"


def seeded(n: int):
    """Hypothesis settings: derandomized (a fixed seed), ``n`` examples, fixtures allowed."""
    return settings(max_examples=n, derandomize=True, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


def sine_log(fs=500.0, seconds=6.0, freqs=(0.4, 0.7, 1.1), jitter=0.0, rng=None, noise=0.0) -> JointLog:
    """Joint i follows sin(2 pi f_i t + i); tau is a fixed linear map of (q, ddq) (a regressor-like model)."""
    n = int(seconds * fs)
    t = np.arange(n) / fs
    if jitter:
        t = t + rng.uniform(-jitter, jitter, n) / fs
    w = 2 * np.pi * np.asarray(freqs)
    q = np.sin(w * t[:, None] + np.arange(len(freqs)))
    if noise:
        q = q + rng.normal(scale=noise, size=q.shape)
    tau = 3.0 * q - 0.5 * (-(w**2) * q)  # 3 q - 0.5 ddq
    return JointLog(t=t, joints=tuple(f"j{k}" for k in range(len(freqs))), q=q, tau=tau, source="sines")


# ---------------------------------------------------------------- resampling
@seeded(30)
@given(st.integers(2, 400), st.floats(10, 5000), st.floats(-100, 100), st.booleans())
def test_resampling_a_uniform_log_is_the_identity(n, fs, t0, rates):
    rng = np.random.default_rng(n)
    t = t0 + np.arange(n) / fs
    q, tau = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    log = JointLog(t=t, joints=("a", "b", "c"), q=q, tau=tau, dq=q * 2 if rates else None)
    for rate in (None, fs):
        out = resample(log, rate)
        for kind in ("t", "q", "tau", "dq"):
            a, b = getattr(out, kind), getattr(log, kind)
            assert a is b or np.array_equal(a, b)
        assert out.removed == {} and "not resampled" in out.notes[-1]


@seeded(20)
@given(st.integers(0, 2**32 - 1), st.floats(0.05, 0.45))
def test_resampling_is_exact_on_linear_signals_and_reports_the_spread(seed, jitter):
    rng = np.random.default_rng(seed)
    n = 300
    t = np.arange(n) * 1e-3 + rng.uniform(-jitter, jitter, n) * 1e-3
    a, b = rng.normal(size=(2, 4))
    log = JointLog(t=t, joints=tuple("abcd"), q=a + b * t[:, None], tau=b - a * t[:, None])
    out = resample(log)
    dt = np.diff(out.t)
    np.testing.assert_allclose(dt, np.median(np.diff(t)), rtol=1e-9)
    assert out.t[0] == t[0] and out.t[-1] <= t[-1] + 1e-12
    np.testing.assert_allclose(out.q, a + b * out.t[:, None], atol=1e-12)
    np.testing.assert_allclose(out.tau, b - a * out.t[:, None], atol=1e-12)
    assert "resampled 300 non-uniform samples" in out.notes[-1] and "median rate" in out.notes[-1]
    assert f"{np.diff(t).max() * 1e3:.4g} ms" in out.notes[-1]
    down = resample(log, rate=200.0)
    assert down.removed["resampling to fewer samples"] == n - down.n_samples > 0


# ---------------------------------------------------------------- the low-pass
@seeded(30)
@given(st.floats(100, 5000), st.floats(0.05, 0.5))
def test_zero_phase_has_no_lag_below_the_cutoff_and_attenuates_above(fs, ratio):
    design = lowpass_design(fs)
    t = np.arange(int(40 * fs / design.cutoff)) / fs
    f = ratio * design.cutoff
    x = np.sin(2 * np.pi * f * t)
    y = zero_phase(x, design)
    p = design.pad
    gain = 1 / (1 + (f / design.cutoff) ** 8)  # |H|^2 of the 4th-order Butterworth
    np.testing.assert_allclose(y[p:-p], gain * x[p:-p], atol=2e-3)  # no phase lag: peaks where x has them
    peaks_x = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:]))[1:-1] + 1
    peaks_y = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:]))[1:-1] + 1
    assert np.all(np.abs(peaks_y - peaks_x[: len(peaks_y)]) <= 1)
    above = zero_phase(np.sin(2 * np.pi * 4 * design.cutoff * t), design)
    assert np.abs(above[2 * p:-2 * p]).max() < 1e-4  # 4x the cutoff: |H|^2 = 1 / (1 + 4^8)
    assert np.abs(above[p:-p]).max() < 1e-2  # what is left of the edge transient after the trimmed edges


def test_default_cutoff_and_notes():
    assert lowpass_design(1000.0).cutoff == 20.0
    assert lowpass_design(100.0).cutoff == 5.0
    d = lowpass_design(1000.0, cutoff=10.0, order=2)
    assert d.cutoff == 10.0 and d.order == 2 and d.pad == 200 and d.sos.shape == (1, 6)
    assert "default min(fs/20, 20 Hz)" in lowpass_design(1000.0).note and "(given)" in d.note
    for bad in (dict(fs=100.0, cutoff=60.0), dict(fs=-1.0), dict(fs=100.0, order=0)):
        with pytest.raises(DataError):
            lowpass_design(**bad)


# ---------------------------------------------------------------- derivatives
@seeded(30)
@given(st.integers(0, 2**32 - 1), st.floats(1e-4, 1e-1))
def test_derivatives_of_quadratics_are_exact(seed, h):
    rng = np.random.default_rng(seed)
    c = rng.normal(size=(3, 2))
    t = np.arange(50) * h
    q = c[0] + c[1] * t[:, None] + c[2] * t[:, None] ** 2
    dq, ddq = derivatives(q, 1 / h)
    scale = 1 + np.abs(c).max() * (1 + t[-1]) ** 2
    np.testing.assert_allclose(dq, c[1] + 2 * c[2] * t[:, None], atol=1e-8 * scale / h)
    np.testing.assert_allclose(ddq, np.broadcast_to(2 * c[2], ddq.shape), atol=1e-7 * scale / h**2)


@seeded(20)
@given(st.sampled_from([100.0, 1000.0, 5000.0]), st.floats(0.05, 0.3))
def test_derivatives_of_filtered_sinusoids_are_accurate_away_from_the_edges(fs, ratio):
    design = lowpass_design(fs)
    f = ratio * design.cutoff
    w = 2 * np.pi * f
    t = np.arange(int(20 * fs / design.cutoff)) / fs
    q = np.sin(w * t)[:, None] * [1.0, -2.0]
    dq, ddq = derivatives(q, fs, design)
    gain = 1 / (1 + (f / design.cutoff) ** 8)
    p = design.pad
    np.testing.assert_allclose(dq[p:-p], gain * w * np.cos(w * t)[p:-p, None] * [1.0, -2.0], atol=0.01 * 2 * w)
    np.testing.assert_allclose(ddq[p:-p], -gain * w**2 * q[p:-p], atol=0.01 * 2 * w**2)


# ---------------------------------------------------------------- decimation, parallel filtering
@seeded(20)
@given(st.integers(0, 2**32 - 1), st.integers(1, 8), st.integers(1, 5))
def test_filtering_a_regressor_equals_filtering_each_column(seed, factor, p):
    rng = np.random.default_rng(seed)
    fs = 1000.0
    design = lowpass_design(fs, cutoff=fs / (2 * factor) * 0.8)
    w = rng.normal(size=(400, 3, p))  # (S, m, p): a regressor block per sample
    both = decimate(w, factor, design)
    for i in range(3):
        for k in range(p):
            np.testing.assert_allclose(both[:, i, k], decimate(w[:, i, k], factor, design), rtol=1e-12, atol=1e-12)
    assert both.shape == (len(range(0, 400, factor)), 3, p)


def test_parallel_filtering_keeps_the_linear_model(rng):
    """tau = W beta at the full rate stays tau' = apply(W) beta after filtering and decimation."""
    log = sine_log(rng=rng)
    prep = prepare(log, decimate=5)
    full = prep.full
    w = np.stack([full.q, full.ddq, np.ones_like(full.q)], axis=2)  # (S, m, 3), from the filtered signals
    beta = np.array([3.0, 0.5, 0.2])
    wf = prep.apply(w)
    assert wf.shape == (prep.n_samples, 3, 3)
    np.testing.assert_allclose(prep.apply(log.tau), prep.tau, rtol=0, atol=1e-12)  # tau went through apply's path
    np.testing.assert_allclose(prep.apply(w @ beta), wf @ beta, atol=1e-10)  # linear, column by column
    np.testing.assert_allclose(wf[:, :, 2], 1.0, atol=1e-9)  # DC gain 1
    # the model holds on the prepared samples up to the filter's effect on derived ddq: every sample is kept, and
    # within a cutoff period of the ends (the edge extension keeps the curvature) it holds to 2 %
    err = np.abs(wf[:, :, :2] @ [3.0, -0.5] - prep.tau).max(axis=1)
    assert prep.n_samples == len(range(0, full.n_samples, 5))
    near = int(np.ceil(prep.design.fs / prep.design.cutoff / 5))
    assert err[near:-near].max() < 5e-3 * np.abs(prep.tau).max()
    assert err.max() < 2e-2 * np.abs(prep.tau).max()
    with pytest.raises(DataError, match="one row per full-rate sample"):
        prep.apply(w[:-1])


def test_decimation_that_aliases_is_an_error():
    design = lowpass_design(1000.0, cutoff=60.0)
    with pytest.raises(DataError, match="aliasing"):
        decimate(np.zeros(100), 10, design)
    log = sine_log()
    msg = str(pytest.raises(DataError, prepare, log, cutoff=60.0, decimate=10).value)
    assert "decimating by 10" in msg and "aliasing" in msg and "\n" not in msg


def test_remove_slow_counts_what_it_removes():
    dq = np.array([[1.0, 1.0], [0.01, 1.0], [1.0, -0.02], [-0.5, 0.5]])
    keep, removed = remove_slow(dq, 0.1)
    assert keep.tolist() == [True, False, False, True] and removed == {"slow (|dq| < min_speed on a joint)": 2}
    keep, removed = remove_slow(dq, [0.001, 0.6])
    assert keep.tolist() == [True, True, False, False] and sum(removed.values()) == 2
    assert remove_slow(dq, 0.0)[1] == {}
    with pytest.raises(DataError):
        remove_slow(dq, [0.1, 0.2, 0.3])
    with pytest.raises(DataError, match="no dq"):
        remove_slow(JointLog(t=np.arange(2.0), joints=("a",), q=np.zeros((2, 1)), tau=np.zeros((2, 1))), 0.1)


# ---------------------------------------------------------------- prepare
def test_prepare_counts_every_removed_sample_and_notes_every_choice(rng):
    log = sine_log(jitter=0.3, rng=rng, noise=1e-4, seconds=40.0)
    prep = prepare(log, min_speed=0.05)
    n_full = prep.full.n_samples
    assert sum(v for k, v in prep.removed.items() if k != "resampling to fewer samples") + prep.n_samples == n_full
    assert "filter edges" not in prep.removed and prep.index[0] == 0  # every sample, the ends too
    # default cutoff: 10 x the excitation bandwidth (the sines' 1.1 Hz), within [1, 20] Hz
    band = excitation_bandwidth(prep.full.q, 500.0)
    assert 1.0 <= band <= 1.5  # the 40 s window: frequency bins of 1/40 Hz
    assert prep.design.cutoff == pytest.approx(10 * band, rel=0.05)  # (band of the filtered q here)
    k = min(int(500.0 // (5 * prep.design.cutoff)), n_full // MIN_FITTED)  # at least MIN_FITTED samples kept
    assert k > 1
    k -= k > 3 and all(k % d for d in range(2, k))  # a prime above 3 lowered by one (a stride divides it)
    assert prep.factor == k and prep.fs == pytest.approx(500.0 / k, rel=1e-3)
    # the rigid-body regressor's stride: the largest divisor of k whose rate is >= 10 x the cutoff
    r = max(d for d in range(1, k + 1) if k % d == 0 and (d == 1 or 500.0 / d >= 10 * prep.design.cutoff))
    assert prep.stride == r > 1 and np.all(prep.index % r == 0)
    assert prep.removed["slow (|dq| < min_speed on a joint)"] > 0
    text = "\n".join(prep.notes)
    for word in ("resampled", "low-pass", "x the excitation bandwidth", "dq: derived", "ddq: derived",
                 f"decimation: 1 sample in {k} kept (default", "slow samples:"):
        assert word in text
    assert prep.q.shape == prep.dq.shape == prep.ddq.shape == prep.tau.shape == (prep.n_samples, 3)
    assert np.all(np.abs(prep.dq) >= 0.05)
    np.testing.assert_array_equal(prep.t, prep.full.t[prep.index])


def test_prepare_keeps_measured_rates_filtered(rng):
    base = sine_log(fs=200.0, seconds=8.0)
    w = 2 * np.pi * np.array([0.4, 0.7, 1.1])
    dq = w * np.cos(w * base.t[:, None] + np.arange(3))
    log = JointLog(t=base.t, joints=base.joints, q=base.q, tau=base.tau, dq=dq + rng.normal(scale=0.01, size=dq.shape))
    prep = prepare(log, decimate=1)
    assert any(n.startswith("dq: measured, low-passed") for n in prep.notes)
    near = int(np.ceil(prep.design.fs / prep.design.cutoff))  # the ends: an end sample's noise is not averaged
    np.testing.assert_allclose(prep.dq[near:-near], dq[prep.index][near:-near], atol=0.01)
    np.testing.assert_allclose(prep.dq, dq[prep.index], atol=0.05)
    assert prep.factor == 1 and "decimation by 1" not in prep.removed and prep.n_samples == len(log.t)


@pytest.mark.parametrize("make, expect", [
    (lambda lg: JointLog(t=lg.t, joints=lg.joints, q=np.where(np.arange(len(lg.t))[:, None] == 7, np.nan, lg.q),
                         tau=lg.tau, source="x.csv"), "x.csv: q, joint 'j0', sample 7 (0-based): nan"),
    (lambda lg: JointLog(t=lg.t[:90], joints=lg.joints, q=lg.q[:90], tau=lg.tau[:90], source="short"),
     "short: 90 samples at 500 Hz; the filter edges alone take 2 x 50"),
    (lambda lg: JointLog(t=lg.t, joints=lg.joints, q=lg.q[:, :2], tau=lg.tau, source="s"), "q has shape"),
    (lambda lg: JointLog(t=lg.t[::-1], joints=lg.joints, q=lg.q, tau=lg.tau, source="r"), "sample 1 (0-based)"),
])
def test_prepare_rejects_bad_logs_in_one_line(make, expect):
    with pytest.raises(DataError) as info:
        prepare(make(sine_log()))
    assert expect in str(info.value) and "\n" not in str(info.value)


# ---------------------------------------------------------------- a real log
@pytest.mark.shared
def test_real_panda_log(tmp_path):
    """Gaz et al. 2019 Panda log: sample-major single-column files, converted here to the default CSV layout."""
    import baseparams
    from baseparams.io.logs import read_log

    robot = baseparams.load(PANDA / "panda_mdh_gaz2019.urdf")
    signals = {kind: np.loadtxt(PANDA / f"exciting_traj_{name}.txt").reshape(-1, 7)
               for kind, name in (("q", "positions"), ("dq", "velocity"), ("tau", "torques"))}
    t = np.loadtxt(PANDA / "exciting_traj_time.txt")
    names = robot.joint_names
    header = ["t"] + [f"{kind}_{j}" for kind in signals for j in names]
    path = tmp_path / "panda.csv"
    np.savetxt(path, np.column_stack([t, *signals.values()]), delimiter=",", header=",".join(header), comments="",
               fmt="%.17g")
    log = read_log(path, robot)
    assert log.n_samples == 20544 and log.joints == names and log.dq is not None
    prep = prepare(log)
    assert any(n.startswith("time: resampled 20544 non-uniform samples (dt 0.7-8.81 ms") for n in prep.notes)
    # the excitation: 5 harmonics of 0.075 Hz -> bandwidth ~0.4-0.5 Hz, cutoff 10x that
    assert 3.5 <= prep.design.cutoff <= 5.0
    assert prep.full.n_samples == 21000 and prep.fs >= 5 * prep.design.cutoff
    for a in (prep.q, prep.dq, prep.ddq, prep.tau):
        assert np.all(np.isfinite(a))
    # the robot's dq agrees with d/dt of the filtered q to a few % of its RMS
    rms = np.sqrt(np.mean((prep.dq - np.gradient(prep.full.q, 1e-3, axis=0)[prep.index]) ** 2, axis=0))
    assert np.all(rms < 0.05 * np.sqrt(np.mean(prep.dq**2, axis=0)))


# ---------------------------------------------------------------- the ends: every sample fitted
@seeded(25)
@given(st.integers(0, 2**32 - 1), st.floats(100.0, 2000.0), st.floats(8.0, 20.0))
def test_the_ends_keep_a_smooth_motion_s_acceleration(seed, fs, ratio):
    """At either end of a smooth motion (cutoff ``ratio`` x its top frequency) the derived ddq stays within a few %
    of the truth, where scipy's odd extension pulls it towards zero (the edges used to be trimmed for that)."""
    from baseparams.regressor.compiled import edge_extended

    rng = np.random.default_rng(seed)
    top = 0.5
    design = lowpass_design(fs, cutoff=min(ratio * top, fs / 5))
    t = np.arange(int(12.0 * fs)) / fs
    w = 2 * np.pi * rng.uniform(0.1, top, (1, 3))
    a = rng.normal(size=(1, 3))
    q = a * np.sin(w * t[:, None] + rng.uniform(0, 6, (1, 3)))
    true = -w**2 * q
    scale = np.abs(true).max()
    for curved, bound in ((True, 0.03), (False, None)):
        pad = min(2 * design.pad, len(t) - 1)
        ext = edge_extended(q, pad, curved)
        f = signal.sosfiltfilt(design.sos, ext, axis=0, padtype=None)[pad:pad + len(t)]
        _, ddq = derivatives(f, fs)
        err = np.abs(ddq - true * (1 / (1 + (w / (2 * np.pi * design.cutoff)) ** 8))).max() / scale
        if curved:
            assert err < bound
            _, ddq_here = derivatives(q, fs, design)  # zero_phase: this extension
            np.testing.assert_allclose(ddq_here, ddq, atol=1e-9 * scale)
        else:
            assert err > 0.2  # scipy's odd extension: the acceleration at the ends is far off


@seeded(10)
@given(st.floats(100.0, 1000.0), st.floats(40.0, 100.0))
def test_the_ends_average_their_noise_instead_of_doubling_one_sample(fs, ratio):
    """White noise through :func:`zero_phase`: at the very ends its variance stays within a few times the interior's
    (9-14x here; the odd extension about the end sample itself doubled that one sample into every extended one:
    ~fs / (2 cutoff) times the interior's, 22-56x here). The filter is one linear map: each output's gain is the
    squared norm of its row."""
    from baseparams.regressor.compiled import edge_extended

    design = lowpass_design(fs, cutoff=fs / ratio)
    n = 8 * design.pad + 1
    pad = min(2 * design.pad, n - 1)
    rows = np.r_[0, 1, n - 2, n - 1, n // 2]  # both ends, and the middle

    def gain(curved):
        h = signal.sosfiltfilt(design.sos, edge_extended(np.eye(n), pad, curved), axis=0, padtype=None)[pad:pad + n]
        return np.sum(h[rows] ** 2, axis=1)

    ours, odd = gain(True), gain(False)
    assert np.all(ours[:4] < 16 * ours[4]), ours[:4] / ours[4]
    assert np.all(odd[[0, 3]] > 1.5 * ours[[0, 3]]), odd[:4] / ours[:4]  # odd: the end is the raw sample itself


def test_every_sample_is_fitted_and_the_linear_model_holds_at_the_ends(rng):
    """tau = W beta at the full rate holds on the prepared rows at the very ends too (one linear filter for both)."""
    log = sine_log(rng=rng)
    prep = prepare(log, decimate=1)
    full = prep.full
    w = np.stack([full.q, full.ddq], axis=2)
    assert prep.n_samples == full.n_samples and "filter edges" not in prep.removed
    assert any(n.startswith("edges: every sample fitted") for n in prep.notes)
    # exactness of the parallel filter at the ends: filtering W beta and W then beta agree to rounding
    beta = np.array([3.0, -0.5])
    np.testing.assert_allclose(prep.apply(w @ beta), prep.apply(w) @ beta, atol=1e-9)
