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


@pytest.mark.slow
def test_the_default_leaves_the_physical_fit_out_of_a_large_model_and_says_so(tmp_path, monkeypatch):
    """Above PHYSICAL_AUTO_PARAMS the default does not solve the conic program once per block (minutes, gigabytes on a
    220-link chain): least squares with the file's prior, one line saying why; --method physical still fits it."""
    from baseparams.ident import fitting, physical

    puma_log = str(tmp_path / "long.csv")  # blocks long enough for cross-validation to weigh the physical fit
    bp.simulate("puma560", duration=20.0, rate=200.0, noise=0.05, seed=2, out=puma_log)

    calls = []
    real = physical.physical_fit
    monkeypatch.setattr(physical, "physical_fit", lambda *a, **k: calls.append(1) or real(*a, **k))
    before = bp.identify("puma560", puma_log)
    assert calls and not any("physically consistent fit not tried" in n for n in before.notes)
    calls.clear()
    monkeypatch.setattr(fitting, "PHYSICAL_AUTO_PARAMS", before.fit.model.n_params - 1)
    res = bp.identify("puma560", puma_log)
    assert not calls and res.fit.physical is None and res.fit.selection.estimator != "physical"
    line = [n for n in res.notes if "physically consistent fit not tried" in n]
    assert len(line) == 1 and f"{res.fit.model.n_params} parameters" in line[0] and "--method physical" in line[0]
    forced = bp.identify("puma560", puma_log, method="physical")
    assert calls and forced.fit.physical is not None


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
    assert main(["simulate", str(model), str(log), "--duration", "0.82", "--rate", "100"]) != 0
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line.lower()]
    assert len(err) == 1 and "drive parameters regroup" in err[0] and "--friction none" in err[0]
    assert not log.exists()
    assert main(["simulate", str(model), str(log), "--duration", "0.82", "--rate", "100", "--friction", "none"]) == 0
    capsys.readouterr()
    assert main(["identify", str(model), str(log), "--friction", "none"]) != 0
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line.lower()]
    assert len(err) == 1 and "floating-point operations" in err[0] and "--joints" in err[0]
    assert "drive terms" not in err[0]
    # 300 m tall in the world frame at q = 0: its paper values lose every digit; the other convention is named
    assert main(["simulate", str(model), str(log), "--duration", "0.82", "--rate", "100", "--friction", "none",
                 "--convention", "paper"]) != 0
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line.lower()]
    assert len(err) == 1 and "cannot be computed in double precision" in err[0] and "--convention khalil" in err[0]


def _whole_k(base) -> np.ndarray:
    """The whole ``K`` (``RecursiveForm.expand``), rounding zeroed relative to its row as the writer does."""
    from baseparams.base.regroup import ZERO_TOL

    k = base.recursive.expand()
    k = np.array(k.toarray() if hasattr(k, "toarray") else k, dtype=float)
    k[np.abs(k) <= ZERO_TOL * np.maximum(1.0, np.abs(k).max(axis=1, initial=0.0))[:, None]] = 0.0
    return k


@pytest.mark.parametrize("seed", range(3))
def test_expanded_form_written_in_blocks_is_the_whole_one(seed, monkeypatch):
    """Issue 51: the expanded form of a large tree is written a few rows at a time from the recursive form:
    any block gives the whole ``K``'s rows, any block size the same text, and the streamed JSON and report
    are the whole ``json.dumps`` and report, in both forms."""
    import json

    from baseparams.analysis import format_report, json_chunks, report_lines
    from baseparams.base import recursive, regroup

    rng = np.random.default_rng(seed)
    robot = random_robot(rng, int(rng.integers(60, 90)), joint_types="RP", branching=0.3 * seed)
    a = bp.analyze(robot, form="expanded", convention=("khalil", "paper")[seed % 2])
    assert a.form == "expanded" and a.base.recursive is not None  # a large tree: regrouped in recursive form
    for b in (a.base, a.base_paper):  # the rows block by block are the whole K's (to its rounding)
        whole = _whole_k(b)
        got = np.zeros_like(whole)
        for start, stop, indptr, indices, data in b.recursive.expand_rows(float(rng.integers(1, 5e4))):
            got[start + np.repeat(np.arange(stop - start), np.diff(indptr)), indices] = data
        scale = np.maximum(1.0, np.abs(whole).max(axis=1, keepdims=True))
        assert np.abs(got - whole).max(initial=0.0) <= 1e-10 * scale.max()
        assert np.all(np.abs(got - whole) <= 1e-10 * scale)
    want = [list(b.iter_expressions("expanded")) for b in (a.base, a.base_paper)]
    whole_json, whole_report = json.dumps(a.to_json(), indent=2), format_report(a)
    monkeypatch.setattr(recursive, "EXPAND_BLOCK_BYTES", float(rng.integers(1, 5e4)))
    monkeypatch.setattr(regroup, "EXPRESSION_CHUNK_TERMS", int(rng.integers(1, 500)))
    assert [list(b.iter_expressions("expanded")) for b in (a.base, a.base_paper)] == want  # any block size
    assert "".join(json_chunks(a)) == whole_json and "\n".join(report_lines(a)) == whole_report
    assert json.loads(whole_json)["base_parameters"] == want[0]
    assert [e["name"] for e in want[0]] == a.base_names and len(want[0]) == a.n_base
    r = bp.analyze(robot, form="recursive", convention=a.base.convention)
    assert "".join(json_chunks(r)) == json.dumps(r.to_json(), indent=2)
    assert np.array_equal(r.base.unidentifiable, a.base.unidentifiable)


def test_expanded_form_keeps_what_the_regressor_sees():
    """A random chain whose expanded coefficients reach 1e10 and more: every parameter the expanded form calls
    unidentifiable has a zero regressor column (before, terms below 1e-9 of a row's largest were dropped from
    ``K`` and parameters the torques do see were listed as unidentifiable)."""
    robot = random_robot(np.random.default_rng(60), 60, "R", branching=0.0)
    a = bp.analyze(robot, form="expanded")
    assert a.base.expanded_size()[1] > 1e9
    rng = np.random.default_rng(0)
    q, dq, ddq = rng.normal(size=(3, 4, robot.dof))
    t = a.base.T.toarray() if hasattr(a.base.T, "toarray") else a.base.T
    y = regressor(robot, q, dq, ddq).reshape(-1, 10 * robot.n) @ t  # columns in the analysis' convention
    scale = np.abs(y).max()
    seen = np.abs(y).max(axis=0) > 1e-9 * scale
    assert not seen[a.base.unidentifiable].any()
    listed = set(a.base.unidentifiable.tolist())
    assert all(i in listed for i in np.flatnonzero(~seen))  # and what it does not see is listed


def _write_peak(a, path, monkeypatch) -> tuple[int, int]:
    """Peak traced memory [bytes] while ``analyze --json --output`` writes ``a``, and the file's size."""
    import tracemalloc

    from baseparams.analysis import json_chunks
    from baseparams.cli.common import emit

    args = SimpleNamespace(output=str(path), json=True, model="m.urdf")
    monkeypatch.setattr("baseparams.cli.common.input_files", lambda args: [])
    tracemalloc.start()
    try:
        emit(args, json_chunks(a))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return peak, path.stat().st_size


@pytest.mark.slow
def test_writing_the_expanded_form_holds_a_block_not_the_report(tmp_path, monkeypatch):
    """Issue 51 (2.5 GB for a 1 000-link chain's expanded form): the text is made and written a block at a
    time. Doubling the chain quadruples the text; the memory while writing stays a block's, not the text's."""
    from baseparams.base import recursive, regroup

    monkeypatch.setattr(recursive, "EXPAND_BLOCK_BYTES", 2e5)
    monkeypatch.setattr(regroup, "EXPRESSION_CHUNK_TERMS", 5000)
    peaks, sizes = [], []
    for n in (100, 100, 200):  # the first run warms up (imports, caches)
        a = bp.analyze(random_robot(np.random.default_rng(n), n, "R", branching=0.0), form="expanded")
        peak, size = _write_peak(a, tmp_path / f"c{n}.json", monkeypatch)
        peaks.append(peak)
        sizes.append(size)
    peaks, sizes = peaks[1:], sizes[1:]
    assert sizes[1] > 3 * sizes[0]  # quadratic text (about 12 MB at 200 links)
    assert peaks[1] < 1.5 * peaks[0] and peaks[1] < sizes[1] / 4  # not: held whole it would be the text's


_ANALYZE_CHAIN = """
import numpy as np
from baseparams.cli import common, main
from baseparams.robots import random_robot
robot = random_robot(np.random.default_rng({n}), {n}, "R", branching=0.0)
common.load_robot = lambda args: robot  # the command as run on the chain's file, without writing the file
assert main(["analyze", "chain.urdf", "--form", {form!r}, "--output", {out!r}]) == 0
"""


@pytest.mark.slow
def test_analyze_expanded_needs_the_analysis_memory_not_the_texts(tmp_path):
    """Issue 51: ``analyze --form expanded`` of a 1 000-link chain peaked at 2.5 GB (``K`` regrouped and
    held whole, its 278 MB of text made from it). The command now needs what the analysis itself needs (the
    same command with ``--form recursive``, O(n) text) plus a block of rows and of terms' text: on a 600-link
    chain, 117 MB of text, less than an eighth of it more (7 MB measured; 38 MB with 200 000 terms' text made
    at once, 912 MB, growing with the square of the links, with ``K`` held)."""
    peaks, sizes = {}, {}
    for form in ("recursive", "expanded"):
        out = tmp_path / f"{form}.txt"
        peaks[form], done = _peak_mb(_ANALYZE_CHAIN.format(n=600, form=form, out=str(out)))
        assert done.returncode == 0, done.stderr[-500:]
        sizes[form] = out.stat().st_size / 2**20
    assert sizes["expanded"] > 50 * sizes["recursive"] > 50  # the text quadratic in the links (about 117 MB)
    assert peaks["expanded"] - peaks["recursive"] < sizes["expanded"] / 8, (peaks, sizes)


def test_huge_expanded_form_and_coefficients_noted_in_one_line(tmp_path, monkeypatch, capsys):
    """``analyze --form expanded``: past the thresholds, one line each on stderr (and in the report) before the
    writing: the number of terms with ``--form recursive`` named, the largest coefficient against 1/eps."""
    from baseparams import analysis
    from baseparams.cli import main

    model = tmp_path / "chain.urdf"
    model.write_text(chain_urdf(80))
    out = tmp_path / "r.txt"
    assert main(["analyze", str(model), "--form", "expanded", "--output", str(out)]) == 0
    assert "note:" not in capsys.readouterr().err  # 80 links of 0.3 m: neither
    monkeypatch.setattr(analysis, "EXPANDED_NOTE_TERMS", 1000)
    monkeypatch.setattr(analysis, "COEFFICIENT_NOTE", 0.5)
    assert main(["analyze", str(model), "--form", "expanded", "--output", str(out)]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if "note:" in line]
    assert len(notes) == 2
    assert "million terms" in notes[0] and "--form recursive" in notes[0]
    assert "coefficients up to" in notes[1] and "double precision" in notes[1]
    text = out.read_text()
    assert all(line.removeprefix("baseparams: ") in text for line in notes)
    assert main(["analyze", str(model), "--output", str(out)]) == 0  # auto: recursive (80 < 200: expanded)
    capsys.readouterr()
    assert main(["analyze", str(model), "--form", "recursive", "--output", str(out)]) == 0
    assert "note:" not in capsys.readouterr().err
