"""The recursive form of the regrouped expressions (issue 41): linear size, and the expanded form rebuilt from it."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import baseparams as bp
from baseparams.analysis import RECURSIVE_MIN_BODIES, format_report
from baseparams.errors import BaseparamsError
from baseparams.model.snap import diameter
from baseparams.robots.random import random_robot


def _dense(a):
    return np.asarray(a.toarray() if hasattr(a, "toarray") else a)


def _same_regrouping(rec, exp, rtol=1e-8):
    """Same dependent set, names, unidentifiable parameters and K (relative to each row's largest)."""
    assert np.array_equal(rec.base.dependent, exp.base.dependent)
    assert rec.base_names == exp.base_names
    assert np.array_equal(rec.base.unidentifiable, exp.base.unidentifiable)
    ka, ke = _dense(rec.base.K), _dense(exp.base.K)
    row = np.maximum(np.abs(ke).max(axis=1, keepdims=True), 1.0) if ke.shape[1] else 1.0
    assert np.all(np.abs(ka - ke) <= rtol * row)


def _tree(seed: int, n: int, deep: bool) -> bp.Robot:
    return random_robot(np.random.default_rng(seed), n, "RP", floating=bool(seed % 2), branching=0.1 if deep else 0.4)


@pytest.mark.parametrize("name", ["puma560", "go2"])
def test_recursive_expands_to_todays_expanded_form(name):
    robot = bp.load(name)
    rec, exp = bp.analyze(robot, form="recursive"), bp.analyze(robot)
    assert exp.form == "expanded" and rec.form == "recursive"
    _same_regrouping(rec, exp)
    assert rec.expanded_expressions() == exp.expressions()
    pi = robot.parameters("khalil")  # the O(n) map (t = (I - S)^-1 pi_D) gives the expanded one's values
    assert np.allclose(rec.to_base(pi, "khalil"), exp.to_base(pi, "khalil"), rtol=1e-10, atol=1e-12)


def test_puma560_reads_as_khalil_writes_it():
    a = bp.analyze(bp.load("puma560"), form="recursive")
    rec = {e["name"]: e["expression"] for e in a.expressions()}
    defs = {e["name"]: e["expression"] for e in a.regrouped()}
    assert rec["link1.ZZR"] == "link1.ZZ + link2.YYR"
    assert defs["link2.MR"] == "link2.M + link3.MR"  # MR_j = M_j + MR_{j+1}
    assert defs["link5.MR"] == "link5.M + link6.M"  # a leaf's mass absorbs nothing: written as itself


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("deep", [False, True])
def test_recursive_equals_expanded_on_random_trees(seed, deep):
    robot = _tree(seed, 60 + 20 * seed, deep)
    rec, exp = bp.analyze(robot, form="recursive"), bp.analyze(robot, form="expanded")
    assert rec.nullity == exp.nullity and rec.certified
    _same_regrouping(rec, exp)
    pi = robot.parameters("khalil") * np.random.default_rng(seed).uniform(0.5, 2.0, 10 * robot.n)
    b = exp.to_base(pi, "khalil")
    assert np.allclose(rec.to_base(pi, "khalil"), b, rtol=1e-9, atol=1e-9 * np.abs(b).max())
    # the paper convention too
    _same_regrouping(type(rec)(**{**rec.__dict__, "base": rec.base_paper}),
                     type(exp)(**{**exp.__dict__, "base": exp.base_paper}))


def _evaluate(exprs: list[dict], values: dict[str, float]) -> dict[str, float]:
    """Evaluate ``name = a + c*b - ...`` lines in order (each term a known name)."""
    out = dict(values)
    term = re.compile(r"([+-]) (?:([0-9.e+-]+)\*)?(\S+)")
    for e in exprs:
        head, _, rest = e["expression"].partition(" ")
        total = out[head]
        for sign, coef, name in term.findall(" " + rest if rest else ""):
            total += (-1 if sign == "-" else 1) * float(coef or 1) * out[name]
        out[e["name"]] = total
    return out


def test_printed_recursive_form_gives_the_base_values():
    """The text a person reads: definitions (root side first, so evaluated leaves first) then base parameters."""
    robot = _tree(3, 50, deep=True)
    a = bp.analyze(robot, form="recursive")
    pi = robot.parameters("khalil")
    vals = _evaluate(a.regrouped()[::-1], dict(zip(a.names, pi.tolist())))
    vals = _evaluate(a.expressions(), vals)
    want = a.base_values
    got = np.array([vals[n] for n in a.base_names])
    assert np.allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


def _terms(exprs):
    return sum(e["expression"].count(" + ") + e["expression"].count(" - ") + 1 for e in exprs)


def test_recursive_size_is_linear_on_a_chain():
    """A chain's expanded expressions grow with the square of its length, the recursive ones linearly."""
    sizes = {}
    for n in (40, 80):
        robot = random_robot(np.random.default_rng(n), n, "R", floating=True, branching=0.0)
        a = bp.analyze(robot, form="recursive")
        sizes[n] = (_terms(a.expressions()) + _terms(a.regrouped()), _terms(a.expanded_expressions()))
    rec_ratio, exp_ratio = sizes[80][0] / sizes[40][0], sizes[80][1] / sizes[40][1]
    assert rec_ratio < 2.2 < 3.0 < exp_ratio
    # and each base parameter has a bounded number of terms
    a = bp.analyze(random_robot(np.random.default_rng(1), 80, "R", floating=True, branching=0.0), form="recursive")
    assert max(_terms([e]) for e in a.expressions() + a.regrouped()) <= 12


def test_form_in_json_and_text():
    robot = bp.load("puma560")
    rec, exp = bp.analyze(robot, form="recursive"), bp.analyze(robot)
    j = json.loads(json.dumps(rec.to_json()))
    assert j["form"] == "recursive" and j["regrouped_parameters"] and j["regrouped_parameters_paper"]
    assert exp.to_json()["form"] == "expanded" and exp.to_json()["regrouped_parameters"] == []
    text = format_report(rec)
    assert "recursive form" in text and "link2.MR = link2.M + link3.MR" in text
    assert "recursive form" not in format_report(exp) and "regrouped dependent" not in format_report(exp)


def test_auto_is_recursive_for_large_trees_only():
    small = bp.analyze(bp.load("puma560"))
    assert small.form == "expanded"
    big = random_robot(np.random.default_rng(0), RECURSIVE_MIN_BODIES, "R", floating=True)
    a = bp.analyze(big, verify=False)
    assert a.form == "recursive" and a.base.__dict__.get("_K") is None  # K not expanded for the report
    a.to_json()
    assert a.base.__dict__.get("_K") is None


def test_recursive_refused_in_one_line_without_compact_columns():
    with pytest.raises(BaseparamsError, match="form='recursive' needs a tree"):
        bp.analyze(bp.load("four-bar"), form="recursive")
    with pytest.raises(BaseparamsError, match="form= must be one of auto, expanded, recursive"):
        bp.analyze(bp.load("puma560"), form="short")


def test_cli_form_flag(tmp_path, capsys):
    from baseparams.cli import main

    assert main(["analyze", "puma560", "--form", "recursive", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["form"] == "recursive" and any(e["name"] == "link2.MR" for e in j["regrouped_parameters"])


@pytest.mark.parametrize("m", [1, 2, 7, 300])
def test_diameter_is_the_largest_pairwise_distance(m):
    rng = np.random.default_rng(m)
    for _ in range(20):
        p = rng.normal(size=(m, 3)) * rng.uniform(0.01, 10, 3)
        if m > 2 and rng.random() < 0.3:
            p[:, 2] = 0.0  # planar
        want = np.max(np.linalg.norm(p[:, None] - p[None], axis=2))
        assert diameter(p, block=5) == pytest.approx(want, rel=1e-12, abs=1e-300)


def test_html_says_which_form():
    from baseparams.report.html import analysis_html

    robot = bp.load("puma560")
    rec = analysis_html(bp.analyze(robot, form="recursive"))
    assert "Recursive form" in rec and "id='regrouped'" in rec and "link2.MR" in rec
    exp = analysis_html(bp.analyze(robot))
    assert "Expanded form" in exp and "id='regrouped'" not in exp


@pytest.mark.parametrize("seed", range(10))
def test_path_dofs_and_subtree_end_are_the_support_matrix(seed):
    """The O(depth) / O(n) replacements of the (dof, n) support matrix agree with it."""
    robot = random_robot(np.random.default_rng(seed), 15, "RPUSC", floating=bool(seed % 2), branching=0.5)
    sup, end = robot.support, robot.subtree_end
    for b in range(robot.n):
        assert np.array_equal(robot.path_dofs(b), np.flatnonzero(sup[:, b]))
        moved = np.flatnonzero(sup[robot.q_index[b]]) if robot.ndofs[b] else np.array([b])
        contiguous = moved[-1] - moved[0] + 1 == len(moved)
        assert (end[b] >= 0) == contiguous
        if contiguous:
            assert moved[0] == b and end[b] == moved[-1] + 1


@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_base_regressor_of_a_large_tree_uses_a_sparse_map(backend):
    """A tree with more than 1000 parameters: the base map stays sparse; the base regressor is
    the full regressor times the dense map, and it predicts the torques of the model's own
    base parameters."""
    pytest.importorskip("numba") if backend == "compiled" else None
    robot = random_robot(np.random.default_rng(5), 120, "R", floating=True)
    a = bp.analyze(robot, verify=False, form="recursive")
    assert hasattr(a.base.T, "tocsr")
    rng = np.random.default_rng(0)
    q, dq, ddq = rng.uniform(-1, 1, (3, 4, robot.dof))
    yb = a.base_regressor(q, dq, ddq, backend=backend)
    full = bp.regressor(robot, q, dq, ddq)
    assert np.allclose(yb, full @ a.base_map, rtol=1e-9, atol=1e-9 * np.abs(full).max())
    tau = full @ robot.parameters("paper")
    # (the recursive form's values come from small local coefficients: torques to ~1e-9 relative,
    # where the expanded form's coefficients of up to 1e7 leave ~1e-4 on this tree)
    assert np.allclose(yb @ a.base_values, tau, rtol=1e-7, atol=1e-7 * np.abs(tau).max())


def test_html_grid_of_the_recursive_form_names_where_each_parameter_is_written():
    from baseparams.report.html import parameter_classes, regrouped_into

    a = bp.analyze(bp.load("puma560"), form="recursive")
    into, cls = regrouped_into(a), parameter_classes(a)
    assert a.base.__dict__.get("_K") is None  # not expanded
    exprs = {e["name"]: e["expression"] for e in a.expressions() + a.regrouped()}
    for name, where in into.items():
        if cls[name] == "unidentifiable":
            assert where == []
        for w in where:  # each target's expression mentions the parameter (or its regrouped name)
            assert re.search(rf"(^| |\*){re.escape(name)}R?( |$)", exprs[w]), (name, w)
    assert into["link3.M"] == ["link3.MR"] and into["link2.M"] == [] and "link1.ZZR" in into["link1.ZZ"]
