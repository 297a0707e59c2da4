"""The compiled TP regressor (numba) against the numpy one, Newton-Euler and Pinocchio.

numba is a test dependency: CI runs these on the compiled path (never skipped).
"""

import numpy as np
import pinocchio as pin
import pytest

from baseparams.errors import BaseparamsError
from baseparams.io.pinocchio import forces_from_pinocchio, state_to_pinocchio, to_pinocchio
from baseparams.kinematics.loops import close_loops
from baseparams.regressor import closed_regressor, compiled, projected_regressor, regressor
from baseparams.robots import get, go2, puma560, random_robot

from oracles import rnea

CASES = [(seed, jt, fl) for seed in range(3) for jt, fl in
         [("R", False), ("P", False), ("RPUS", False), ("RPUS", True), ("RPUSC", False), ("RC", True)]]


def _states(rng, robot, s, scale=2.0):
    return rng.uniform(-scale, scale, (3, s, robot.dof))


def test_numba_is_installed_for_the_tests():
    assert compiled.available()


@pytest.mark.parametrize("seed, types, floating", CASES)
def test_compiled_matches_numpy_and_newton_euler(seed, types, floating):
    """Random trees of every joint type (compound C, floating F root), random gravity."""
    rng = np.random.default_rng(100 + seed)
    robot = random_robot(rng, int(rng.integers(2, 9)), joint_types=types, floating=floating,
                         branching=0.5, gravity=rng.normal(scale=5, size=3))
    q, dq, ddq = _states(rng, robot, 70)
    y_c = regressor(robot, q, dq, ddq, backend="compiled")
    y_n = regressor(robot, q, dq, ddq, backend="numpy")
    assert y_c.shape == y_n.shape == (70, robot.dof, 10 * robot.n)
    assert np.abs(y_c - y_n).max() <= 1e-12 * np.abs(y_n).max()
    pi = robot.parameters("paper")
    ref = np.array([rnea(robot, q[k], dq[k], ddq[k]) for k in range(5)])
    assert np.abs(y_c[:5] @ pi - ref).max() <= 1e-10 * np.abs(ref).max()


@pytest.mark.parametrize("make", [puma560, go2])
def test_compiled_torques_match_pinocchio(make, rng):
    robot = make()
    model = to_pinocchio(robot)
    data = model.createData()
    q, dq, ddq = _states(rng, robot, 6, 1.0)
    tau = regressor(robot, q, dq, ddq, backend="compiled") @ robot.parameters("paper")
    for k in range(6):
        qp, vp, ap = state_to_pinocchio(robot, q[k], dq[k], ddq[k])
        ref = forces_from_pinocchio(robot, q[k], pin.rnea(model, data, qp, vp, ap))
        assert np.allclose(tau[k], ref, rtol=1e-10, atol=1e-9)


def test_out_buffer_reused_and_any_content_overwritten(rng):
    """A reused buffer is returned; whatever it held (NaN, stale rows) never leaks through."""
    robot = go2()
    q, dq, ddq = _states(rng, robot, 40, 1.0)
    ref = regressor(robot, q, dq, ddq, backend="numpy")
    structural_zero = ~np.repeat(robot.support, 10, axis=1)  # (dof, 10 n): j does not move i
    for fill in (np.nan, 1.0, 0.0):
        buf = np.full(ref.shape, fill)
        y = regressor(robot, q, dq, ddq, out=buf, backend="compiled")
        assert y is buf
        assert np.all(y[:, structural_zero] == 0.0)
        assert np.abs(y - ref).max() <= 1e-12 * np.abs(ref).max()
    q2 = q[::-1].copy()
    y = regressor(robot, q2, dq, ddq, out=buf, backend="compiled")  # stale content of the last call
    assert np.abs(y - regressor(robot, q2, dq, ddq, backend="numpy")).max() <= 1e-12 * np.abs(ref).max()
    assert regressor(robot, q, dq, ddq, out=np.empty(ref.shape), backend="numpy") is not None


@pytest.mark.parametrize("bad", [np.zeros((3, 2)), np.zeros((40, 18, 130), dtype=np.float32),
                                 np.zeros((40, 130, 18)).transpose(0, 2, 1)])
@pytest.mark.parametrize("backend", ["compiled", "numpy"])
def test_bad_out_buffer_is_one_clear_error(bad, backend, rng):
    robot = go2()
    q = rng.uniform(-1, 1, (40, robot.dof))
    with pytest.raises(BaseparamsError, match="out must be"):
        regressor(robot, q, out=bad, backend=backend)


def test_auto_backend_threshold(monkeypatch, rng):
    """auto: numpy for small batches in a process without the kernels, compiled for large ones
    or once they are loaded."""
    robot = puma560()
    calls = []
    real = compiled.tree_regressor
    monkeypatch.setattr(compiled, "tree_regressor", lambda *a, **k: calls.append(1) or real(*a, **k))
    monkeypatch.setattr(compiled, "MIN_WORK", 50 * 6 * 6)
    monkeypatch.setattr(compiled, "loaded", lambda: False)
    regressor(robot, rng.uniform(-1, 1, (49, 6)))
    assert calls == []
    regressor(robot, rng.uniform(-1, 1, (50, 6)))
    assert calls == [1]
    regressor(robot, rng.uniform(-1, 1, (500, 6)), backend="numpy")
    assert calls == [1]
    monkeypatch.setattr(compiled, "loaded", lambda: True)
    regressor(robot, rng.uniform(-1, 1, (2, 6)))
    assert calls == [1, 1]


def test_compiled_without_numba_says_what_to_install(monkeypatch, rng):
    monkeypatch.setattr(compiled, "available", lambda: False)
    robot = puma560()
    q = rng.uniform(-1, 1, (5000, 6))
    with pytest.raises(BaseparamsError, match=r"baseparams\[fast\]"):
        regressor(robot, q, backend="compiled")
    assert regressor(robot, q).shape == (5000, 6, 60)  # auto falls back to numpy
    with pytest.raises(BaseparamsError, match="unknown regressor backend"):
        regressor(robot, q, backend="jax")


@pytest.mark.parametrize("name", ["four-bar", "pkm-2rru-1rrs", "pkm-2prs-1psr"])
def test_compiled_closed_regressor_matches_numpy(name, rng):
    robot = get(name)
    na = len(robot.actuated)
    cs = close_loops(robot, rng.uniform(-0.2, 0.2, (30, na)), rng.uniform(-1, 1, (30, na)),
                     rng.uniform(-1, 1, (30, na)))
    y_n = closed_regressor(robot, cs, backend="numpy")
    y_c = closed_regressor(robot, cs, backend="compiled")
    assert y_c.shape == y_n.shape == (cs.q.shape[0], na, 10 * robot.n)
    assert np.abs(y_c - y_n).max() <= 1e-12 * np.abs(y_n).max()
    buf = np.full(y_n.shape, np.nan)
    assert closed_regressor(robot, cs, out=buf, backend="compiled") is buf
    assert np.abs(buf - y_n).max() <= 1e-12 * np.abs(y_n).max()


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("backend", ["compiled", "numpy"])
def test_projected_regressor_is_the_regressor_times_the_map(seed, backend):
    """Any map P (dense, mixing bodies) and any row subset: ``Y[:, rows] @ P``."""
    rng = np.random.default_rng(200 + seed)
    robot = random_robot(rng, int(rng.integers(2, 8)), joint_types="RPUSC", floating=bool(seed % 2), branching=0.5)
    q, dq, ddq = _states(rng, robot, 33)
    P = rng.normal(size=(10 * robot.n, int(rng.integers(1, 12))))
    P[:, 0] = 0.0  # a column no body contributes to
    rows = rng.permutation(robot.dof)[: int(rng.integers(1, robot.dof + 1))]
    ref = regressor(robot, q, dq, ddq, backend="numpy")[:, rows] @ P
    y = projected_regressor(robot, q, dq, ddq, P=P, rows=rows, backend=backend)
    assert y.shape == ref.shape
    assert np.abs(y - ref).max() <= 1e-12 * np.abs(ref).max()
    buf = np.full(ref.shape, np.nan)
    assert projected_regressor(robot, q, dq, ddq, P=P, rows=rows, out=buf, backend=backend) is buf
    assert np.abs(buf - ref).max() <= 1e-12 * np.abs(ref).max()


def test_projected_regressor_bad_input(rng):
    robot = puma560()
    q = rng.uniform(-1, 1, (4, 6))
    with pytest.raises(BaseparamsError, match="P must have shape"):
        projected_regressor(robot, q, P=np.ones((59, 3)))
    with pytest.raises(BaseparamsError, match="rows must be"):
        projected_regressor(robot, q, P=np.ones((60, 3)), rows=[0, 6])


@pytest.mark.parametrize("name, rows", [("go2", "all"), ("go2", "joints"), ("go2", "base"), ("puma560", "all"),
                                        ("pkm-2rru-1rrs", "all"), ("four-bar", "all")])
def test_base_regressor_predicts_the_torques(name, rows, rng):
    """``Yb @ to_base(pi) = tau`` on the measured rows, compiled and numpy alike."""
    from baseparams import analyze, load
    from baseparams.numerics import closed_samples, row_mask

    robot = load(name)
    result = analyze(robot, rows=rows)
    if robot.has_loops:
        cs = closed_samples(robot, 200, rng)
        q, dq, ddq = (x[:, robot.actuated] for x in (cs.q, cs.dq, cs.ddq))
        mask = np.ones(len(robot.actuated), dtype=bool)
    else:
        q, dq, ddq = _states(rng, robot, 50, 1.0)
        mask = row_mask(robot, rows)
    tau = (regressor(robot, q, dq, ddq, backend="numpy") @ robot.parameters("paper"))[:, mask] \
        if not robot.has_loops else closed_regressor(robot, cs) @ robot.parameters("paper")
    beta = result.to_base(robot.parameters(result.convention), result.convention)
    for backend in ("compiled", "numpy"):
        yb = result.base_regressor(q, dq, ddq, backend=backend)
        assert yb.shape == (q.shape[0], int(mask.sum()), result.n_base)
        assert np.abs(yb @ beta - tau).max() <= 1e-9 * np.abs(tau).max()


def test_will_compile_reads_numbas_disk_cache(tmp_path):
    """A fresh cached kernel will compile; once compiled (in memory, or on disk for a new process) it will not."""
    import os
    import subprocess
    import sys

    (tmp_path / "tiny_kernel.py").write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n"
                                             "    return x + 1\n")
    script = (f"import sys; sys.path.insert(0, {str(tmp_path)!r}); import tiny_kernel as t\n"
              "from baseparams.regressor.compiled import will_compile\n"
              "before = will_compile(t.f); t.f(1.0); print(before, will_compile(t.f))\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    first = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True)
    again = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True)
    assert first.stdout.split() == ["True", "False"]  # nothing cached; then compiled in memory
    assert again.stdout.split() == ["False", "False"]  # the disk cache holds it now


def test_a_kernel_that_will_compile_is_announced_once(monkeypatch, capsys):
    """The first-run compile (~20 s) is said in one line on stderr, once per kernel and process."""
    calls = []
    monkeypatch.setattr(compiled, "_kernels", lambda: type("K", (), {"tree": staticmethod(calls.append)}))
    monkeypatch.setattr(compiled, "_announced", set())
    monkeypatch.setattr(compiled, "will_compile", lambda fn: True)
    compiled._kernel("tree")(1)
    compiled._kernel("tree")(2)
    err = capsys.readouterr().err
    assert err.count("compiling the regressor kernel tree once (about 20 s)") == 1 and calls == [1, 2]
    monkeypatch.setattr(compiled, "_announced", set())
    monkeypatch.setattr(compiled, "will_compile", lambda fn: False)
    compiled._kernel("tree")(3)
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("seed", range(3))
def test_compiled_zero_phase_filter_is_scipys(seed):
    """The compiled sosfiltfilt (long streamed logs) gives scipy's numbers: random orders, cutoffs, pads, shapes."""
    from scipy import signal

    rng = np.random.default_rng(seed)
    order = int(rng.integers(1, 9))
    sos = signal.butter(order, float(rng.uniform(0.01, 0.4)), output="sos")
    s = int(rng.integers(50, 3000))
    x = rng.normal(size=(s, int(rng.integers(1, 5)), int(rng.integers(1, 70)))) * 10.0 ** rng.uniform(-3, 3)
    x = x[:, :, ::2] if seed == 1 else x  # a strided view
    for pad in (0, 1, int(rng.integers(2, s))):
        want = signal.sosfiltfilt(sos, x, axis=0, padtype="odd", padlen=pad)
        got = compiled.sosfiltfilt(sos, x, pad, curved=False)
        assert got.shape == x.shape
        assert np.allclose(got, want, rtol=1e-13, atol=1e-13 * np.abs(want).max()), (order, pad)
        # with the curvature kept at the ends (what identification uses): scipy's filter on that extension
        flat = x.reshape(s, -1)
        ext = compiled.edge_extended(flat, pad)
        want = signal.sosfiltfilt(sos, ext, axis=0, padtype=None)[pad:pad + s].reshape(x.shape)
        got = compiled.sosfiltfilt(sos, x, pad)
        assert np.allclose(got, want, rtol=1e-13, atol=1e-12 * np.abs(want).max()), (order, pad)
