"""Memory and work on large trees (issue 51): simulation without a regressor, row factors of bounded size,
and an identification the machine cannot do refused at once in one line (memory, dense work, values that
double precision cannot carry) rather than run out of memory or never end."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap
from types import SimpleNamespace

import numpy as np
import pytest

import baseparams as bp
from baseparams import numerics
from baseparams.analysis import regressor
from baseparams.errors import BaseparamsError
from baseparams.ident import model as ident_model_module
from baseparams.ident.estimate import MOTION_FLOPS, RowAccumulator, motion_stride
from baseparams.ident.model import checked_values, fit_cost, ident_model, probe_cost
from baseparams.regressor.tp import generalized_forces
from baseparams.robots import random_robot
from test_long_chain import chain_urdf


def _one_line(err: BaseException) -> str:
    text = str(err)
    assert "\n" not in text and text
    return text


@pytest.fixture(scope="module")
def puma_log(tmp_path_factory):
    """A short simulated Puma560 log (CSV)."""
    path = tmp_path_factory.mktemp("puma") / "puma.csv"
    bp.simulate("puma560", duration=4.0, rate=200.0, noise=0.05, seed=1, out=str(path))
    return str(path)


@pytest.mark.parametrize("seed", range(6))
def test_inverse_dynamics_without_the_regressor_is_the_regressor_times_the_parameters(seed):
    """``generalized_forces`` (O(S n), no ``(S, dof, 10 n)`` regressor), numpy and compiled, on random trees
    of every joint kind, fixed and floating, is ``Y pi`` for random parameters, on all rows and on a subset."""
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, int(rng.integers(2, 8)), joint_types="RPUSC", floating=bool(seed % 2), branching=0.5)
    s = 7
    q, dq, ddq = rng.normal(size=(3, s, robot.dof))
    pi = rng.normal(size=10 * robot.n)
    want = np.einsum("sjk,k->sj", regressor(robot, q, dq, ddq), pi)
    rows = rng.permutation(robot.dof)[: max(1, robot.dof // 2)]
    scale = np.abs(want).max()
    for backend in ("numpy", "compiled"):
        got = generalized_forces(robot, q, dq, ddq, pi, backend=backend)
        assert got.shape == (s, robot.dof)
        assert np.abs(got - want).max() <= 1e-9 * scale
        sub = generalized_forces(robot, q, dq, ddq, pi, rows=rows, backend=backend, max_bytes=2e3)  # batched
        assert np.abs(sub - want[:, rows]).max() <= 1e-9 * scale


@pytest.mark.parametrize("seed", range(4))
def test_combined_accumulators_read_as_the_one_fed_every_sample(seed):
    """``RowAccumulator.combine`` (TSQR of the parts, no copied factors): the stacked factor, the rows' sums
    of squared residuals, the column norms and the row Gram matrices are the single accumulator's."""
    rng = np.random.default_rng(seed)
    m, p = int(rng.integers(1, 4)), int(rng.integers(2, 9))
    blocks = [(rng.normal(size=(k, m, p)), rng.normal(size=(k, m))) for k in rng.integers(1, 40, size=4)]
    whole = RowAccumulator(m, p)
    for a, tau in blocks:
        whole.add(a, tau)
    parts = [RowAccumulator(m, p).add(a, tau) for a, tau in blocks]
    both = RowAccumulator.combine([RowAccumulator.combine(parts[:2]), *parts[2:]])  # parts of parts are parts
    assert both.samples == whole.samples
    w = rng.uniform(0.5, 2.0, m)
    ra, rb = whole.stacked(w), both.stacked(w)
    assert np.allclose(ra.T @ ra, rb.T @ rb, atol=1e-9 * np.abs(ra.T @ ra).max())
    theta = rng.normal(size=p)
    a_all = np.concatenate([a for a, _ in blocks])
    t_all = np.concatenate([t for _, t in blocks])
    sse = ((np.einsum("smp,p->sm", a_all, theta) - t_all) ** 2).sum(axis=0)
    assert np.allclose(both.row_sse(theta), sse) and np.allclose(whole.row_sse(theta), sse)
    assert np.allclose(both.column_norms2(), whole.column_norms2())
    cols = [0, p]  # a parameter and the torques
    assert np.allclose(both.row_gram(m - 1, cols), whole.row_gram(m - 1, cols))


def test_row_factors_hold_a_bounded_number_of_rows():
    """However many samples are fed, each row factor holds at most ``p + 1`` rows plus one step pending."""
    rng = np.random.default_rng(0)
    m, p = 3, 6
    acc = RowAccumulator(m, p)
    sizes = []
    for _ in range(30):
        acc.add(rng.normal(size=(500, m, p)), rng.normal(size=(500, m)))
        sizes.append(acc.nbytes())
    step = acc.factors[0].step
    assert max(sizes) <= m * 8 * (p + 1) * (p + 1 + step)
    assert acc.samples == 15000


@pytest.mark.parametrize("seed", range(5))
def test_fit_memory_does_not_grow_with_the_log(seed):
    """The fit's memory is of the row factors: it stops growing at ``m (p + 1)`` observations; its work grows."""
    rng = np.random.default_rng(seed)
    p, m = int(rng.integers(5, 3000)), int(rng.integers(1, 300))
    full = m * (p + 1)
    f1, b1 = fit_cost(p, m, full)
    f2, b2 = fit_cost(p, m, 100 * full)
    assert b1 == b2 and f1 == f2
    assert fit_cost(p, m, full // 2)[1] < b1
    assert probe_cost(2 * p, m)[0] > probe_cost(p, m)[0]


@pytest.mark.parametrize("seed", range(5))
def test_the_motion_factor_stays_within_its_budget(seed):
    """A long log of a large model: its motion factor is formed on every k-th sample, within the budget."""
    rng = np.random.default_rng(seed)
    p, m, samples = int(rng.integers(10, 5000)), int(rng.integers(1, 500)), int(rng.integers(100, 10**7))
    k = motion_stride(SimpleNamespace(coords=range(m), n_params=p), samples)
    per = 2.0 * m * p**2
    assert k >= 1
    if k > 1:
        assert math.ceil(samples / k) * per <= MOTION_FLOPS * (1 + 1e-9) + per
        assert samples * per > MOTION_FLOPS
    else:
        assert samples * per <= MOTION_FLOPS


def test_identification_beyond_the_memory_is_refused_in_one_line(puma_log, monkeypatch):
    """Less memory than the fit's factors need: refused before any of it runs, saying what would help."""
    monkeypatch.setattr(numerics, "available_bytes", lambda: 1e4)
    with pytest.raises(BaseparamsError) as err:
        bp.identify("puma560", puma_log)
    line = _one_line(err.value)
    assert "GB of memory" in line and "GB are available" in line and "--joints" in line


def test_identification_beyond_the_work_allowed_is_refused_in_one_line(puma_log, monkeypatch):
    """Dense work beyond the limit: refused at once; the drive terms named as a help only when there are some."""
    monkeypatch.setattr(ident_model_module, "MAX_FLOPS", 1e3)
    with pytest.raises(BaseparamsError) as err:
        bp.identify("puma560", puma_log)
    line = _one_line(err.value)
    assert "floating-point operations" in line and "--joints" in line and "drive terms" in line
    with pytest.raises(BaseparamsError) as err:
        bp.identify("puma560", puma_log, friction="none")
    line = _one_line(err.value)
    assert "floating-point operations" in line and "drive terms" not in line


def test_the_drive_probe_beyond_its_budget_is_refused_and_skipped_without_drive_terms(monkeypatch):
    """The drive-regrouping probe too large: one line naming ``--friction none``; without drive terms no probe."""
    analysis = bp.analyze(bp.load("puma560"), verify=False)
    monkeypatch.setattr(ident_model_module, "PROBE_FLOPS", 1.0)
    with pytest.raises(BaseparamsError) as err:
        ident_model(analysis, rotor=True)
    line = _one_line(err.value)
    assert "drive parameters regroup" in line and "--friction none" in line
    model = ident_model(analysis, rotor=False, friction=())
    assert model.n_params == len(analysis.base_names)


@pytest.mark.parametrize("seed", range(6))
def test_values_are_checked_against_the_torques(seed, monkeypatch):
    """A random tree's own parameters, regrouped, give its torques (no false refusal, either convention);
    a regrouping whose values miss them is refused in one line naming ``--convention paper``."""
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, int(rng.integers(2, 7)), joint_types="RP", floating=seed % 3 == 0)
    for convention in ("khalil", "paper"):
        model = ident_model(bp.analyze(robot, verify=False, convention=convention), rotor=False, friction=(),
                            log_base=robot.floating)
        assert checked_values(model, np.random.default_rng(seed)) is model
    exact = type(model).theta
    monkeypatch.setattr(type(model), "theta", lambda self, pi, delta=None: 1.01 * exact(self, pi, delta))
    with pytest.raises(BaseparamsError) as err:
        checked_values(model, np.random.default_rng(seed))
    line = _one_line(err.value)
    assert "cannot be computed in double precision" in line and "--convention khalil" in line  # the other one


def test_available_memory_reads_the_cgroup(monkeypatch):
    """A cgroup's limit minus its usage bounds what is available; ``max`` (no limit) does not."""
    values = {"/sys/fs/cgroup/memory.max": 3e9, "/sys/fs/cgroup/memory.current": 1e9}
    monkeypatch.setattr(numerics, "_read_number", lambda path: values.get(path))
    assert numerics._cgroup_room() == 2e9
    assert numerics.available_bytes() <= 2e9
    values["/sys/fs/cgroup/memory.max"] = None  # "max"
    assert numerics._cgroup_room() is None


def test_available_memory_reads_the_address_space_limit():
    """``ulimit -v``: a process with 3 GB of address space has less than 3 GB available."""
    code = textwrap.dedent("""
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (3 * 2**30, resource.RLIM_INFINITY))
        from baseparams.numerics import available_bytes
        print(available_bytes())
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env=dict(os.environ))
    have = float(out.stdout.strip())
    assert 0 < have < 3 * 2**30


_HIGH_WATER = """
for _line in open("/proc/self/status"):
    if _line.startswith("VmHWM:"):
        print("VmHWM", int(_line.split()[1]))
"""


def _peak_mb(code: str) -> tuple[float, subprocess.CompletedProcess]:
    """Run ``code`` in a fresh interpreter: its peak resident memory [MB] and the completed process.

    The peak is the interpreter's own (``VmHWM``, reset by ``exec``), not ``ru_maxrss``, which keeps the
    high-water mark of the forked test process across ``exec`` (3.7 GB in a long CI run)."""
    done = subprocess.run([sys.executable, "-c", code + _HIGH_WATER], capture_output=True, text=True)
    marks = [int(line.split()[1]) for line in done.stdout.splitlines() if line.startswith("VmHWM ")]
    return (marks[-1] / 1024 if marks else float("inf")), done


@pytest.mark.slow
def test_simulating_a_long_chain_stays_small(tmp_path):
    """Issue 51: a 60-link chain's 4 000 samples peaked at 2.3 GB (the regressor of every sample); now the
    inverse dynamics is O(S n): well under 1 GB, and the log is written."""
    out = tmp_path / "c60.csv"
    code = textwrap.dedent(f"""
        import numpy as np, baseparams as bp
        from baseparams.robots import random_robot
        robot = random_robot(np.random.default_rng(60), 60, "R", branching=0.0)
        bp.simulate(robot, duration=40.0, rate=100.0, noise=0.1, convention="paper", out={str(out)!r})
    """)
    mb, done = _peak_mb(code)
    assert done.returncode == 0, done.stderr[-500:]
    assert out.stat().st_size > 0
    assert mb < 1000


@pytest.mark.slow
def test_a_thousand_link_chain_is_refused_at_once_in_one_line(tmp_path, capsys):
    """Issue 51: ``simulate`` and ``identify`` of a 1 000-link chain (4.2 GB and killed before): the drive
    probe and the fit refused before they run, one line each, within a few hundred MB."""
    from baseparams.cli import main

    model = tmp_path / "chain1000.urdf"
    model.write_text(chain_urdf(1000))
    log = tmp_path / "c.csv"
    assert main(["simulate", str(model), str(log), "--duration", "0.2", "--rate", "100"]) != 0
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line.lower()]
    assert len(err) == 1 and "drive parameters regroup" in err[0] and "--friction none" in err[0]
    assert not log.exists()
    assert main(["simulate", str(model), str(log), "--duration", "0.2", "--rate", "100", "--friction", "none"]) == 0
    capsys.readouterr()
    assert main(["identify", str(model), str(log), "--friction", "none"]) != 0
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line.lower()]
    assert len(err) == 1 and "floating-point operations" in err[0] and "--joints" in err[0]
    assert "drive terms" not in err[0]
    # 300 m tall in the world frame at q = 0: its paper values lose every digit; the other convention is named
    assert main(["simulate", str(model), str(log), "--duration", "0.2", "--rate", "100", "--friction", "none",
                 "--convention", "paper"]) != 0
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line.lower()]
    assert len(err) == 1 and "cannot be computed in double precision" in err[0] and "--convention khalil" in err[0]
