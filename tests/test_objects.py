"""Readable objects: one-line reprs, names / values / std arrays and tables, a clean namespace,
coefficients printed at the precision they have."""

import ast
import json
import math
import re
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import baseparams
from baseparams.display import MAX_REPR, counted, format_number, summary_repr, text_table
from baseparams.ident import identify
from baseparams.ident.simulate import simulate_log
from baseparams.robots import BUILTINS

from paths import STRICT

PKG = Path(baseparams.__file__).resolve().parent
NOISE = re.compile(r"9{6,}|0{6,}")
COEF = re.compile(r"(?:^|[+-] )([0-9][0-9.e+-]*)\*")


def _pandas():
    try:
        import pandas
    except ImportError:
        if STRICT:
            pytest.fail("BASEPARAMS_REQUIRE_ALL is set but pandas (in the test extra) is not installed")
        return None
    return pandas


@pytest.fixture(scope="module")
def puma():
    robot = baseparams.load("puma560")
    return robot, baseparams.analyze(robot)


@pytest.fixture(scope="module")
def ident(puma):
    robot, _ = puma
    log, _ = simulate_log(robot, duration=10, rate=200, noise=0.05, seed=1, rotor=True)
    return log, identify(robot, log, rotor=True, holdout=2.0)


def _short(obj):
    text = repr(obj)
    assert len(text) < MAX_REPR and "\n" not in text, (type(obj).__name__, len(text), text[:200])
    return text


# ---------------------------------------------------------------- reprs
@pytest.mark.parametrize("name", BUILTINS)
def test_robot_repr_is_one_short_line(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", baseparams.ModelWarning)
        robot = baseparams.load(name)
    text = _short(robot)
    assert text.startswith(f"<Robot {name}: {robot.n} bodies, {robot.dof} dofs")
    for part in (*robot.loops, *robot.couplings):
        _short(part)


def test_analysis_reprs(puma):
    robot, a = puma
    assert _short(a) == "<Analysis puma560: nullity 24, 36 base parameters (khalil), certified>"
    assert _short(a.base).startswith("<BaseParameters khalil: 36 base of 60")
    for obj in (a.base_paper, a.certificate, a.certificate.numerical, a.certificate.drng):
        _short(obj)


def test_identification_reprs(ident):
    log, res = ident
    text = _short(res)
    m = res.model
    nb, nd = m.n_base, m.n_drive
    assert nb + nd == len(res.names) and nb == 36
    assert re.fullmatch(rf"<Identification puma560: auto, {nb} base \+ {nd} drive terms, held-out RMS [0-9.e-]+ N m>",
                        text), text
    # the default is least squares or the physical fit, as cross-validation chose (said)
    assert re.match(rf"<Fit puma560: auto(: physical \(feasible\))?, {nb} base \+ {nd} drive terms, residual RMS",
                    _short(res.fit))
    assert _short(m).startswith(f"<IdentModel puma560: {nb} base + {nd} drive terms (Ia Fv Fc Fo on 6 joints")
    assert _short(log).startswith("<JointLog simulated puma560: 2000 samples of 6 joints over 9.995 s (200 Hz)")
    for obj in (res.fit.estimate, m.drives, m.regrouping):
        _short(obj)


@given(n=st.integers(-3, 10**6), noun=st.sampled_from(["row", "log", "per-file fit", "element"]),
       plural=st.sampled_from([None, "bodies"]))
def test_a_count_takes_its_noun_in_its_number(n, noun, plural):
    """Property: the one plural rule of the messages (issue 51: "1 elements and attributes", "1 logs")."""
    text = counted(n, noun, plural)
    assert text.startswith(f"{n} ") and text.removeprefix(f"{n} ") == (noun if n == 1 else plural or noun + "s")
    assert counted(np.int64(1), "row") == "1 row" and counted(np.float64(2.0), "row") == "2 rows"


def test_excitation_and_fleet_reprs(ident):
    from baseparams.excitation import random_excitation
    from baseparams.fleet import FleetResult

    exc = random_excitation(baseparams.load("puma560"), rate=50.0)
    assert _short(exc).startswith("<Excitation puma560: 6 joints, 5 harmonics of 0.1 Hz, condition number")
    _, res = ident
    fleet = FleetResult(res.model, {"a.csv": res.fit}, res.fit, [{"path": "a.csv"}], None)
    assert _short(fleet) == "<FleetResult puma560: 1 log, 58 terms, 1 per-file fit, pooled auto>".replace(
        "58", str(res.model.n_params))


def test_every_public_dataclass_has_its_own_repr():
    """A generated dataclass repr prints every array: each public dataclass defines a short one."""
    missing = []
    for path in sorted(PKG.rglob("*.py")):
        for node in ast.parse(path.read_text()).body:
            if not (isinstance(node, ast.ClassDef) and not node.name.startswith("_")
                    and any("dataclass" in ast.unparse(d) for d in node.decorator_list)):
                continue
            own = any((isinstance(b, ast.FunctionDef) and b.name == "__repr__")
                      or (isinstance(b, ast.Assign) and any(getattr(t, "id", "") == "__repr__" for t in b.targets))
                      for b in node.body)
            if not own:
                missing.append(f"{path.relative_to(PKG)}: {node.name}")
    assert not missing


def test_summary_repr_clips_to_one_short_line():
    from dataclasses import dataclass

    @dataclass(frozen=True)
    class Many:
        a: np.ndarray
        b: str
        c: tuple
        d: dict

        __repr__ = summary_repr

    obj = Many(np.zeros((7, 3)), "x" * 500, tuple(range(100)), {"k": 1})
    text = repr(obj)
    assert len(text) < MAX_REPR and text.startswith("<Many a=ndarray(7x3), b='xxx") and text.endswith(">")
    assert "100 items" in repr(Many(np.zeros(2), "", tuple(range(100)), {}))


# ---------------------------------------------------------------- names, values, std, tables
def test_identification_arrays_match_the_json(ident):
    _, res = ident
    names, values, std = res.names, res.values, res.std
    assert names.shape == values.shape == std.shape == (res.model.n_params,)
    assert values.dtype == std.dtype == float and list(names) == res.model.names
    pos = {n: k for k, n in enumerate(names)}
    j = json.loads(json.dumps(res.to_json()))
    seen = set()
    for b in j["base_parameters"]:
        k = pos[b["name"]]
        assert values[k] == b["value"] and std[k] == b["std"]
        seen.add(b["name"])
    for d in j["drives"]:
        for kind in ("Ia", "Fv", "Fc", "Fo"):
            if isinstance(d[kind], float):
                assert values[pos[f"{kind}_{d['joint']}"]] == d[kind]
                seen.add(f"{kind}_{d['joint']}")
    assert seen == set(names)  # base parameters then drive terms, every one in the JSON
    nb = res.model.n_base
    assert all(n in {b["name"] for b in j["base_parameters"]} for n in names[:nb])
    lines = res.table().splitlines()
    assert lines[0].split() == ["name", "kind", "value", "std", "pct_sigma", "expression"]
    assert [ln.split()[0] for ln in lines[1:]] == list(names)
    assert [ln.split()[1] for ln in lines[1:]] == ["base"] * nb + ["drive"] * (len(names) - nb)


def test_identification_to_frame(ident):
    _, res = ident
    pd = _pandas()
    if pd is None:
        with pytest.raises(baseparams.BaseparamsError, match="pip install pandas"):
            res.to_frame()
        return
    df = res.to_frame()
    assert list(df.columns) == ["name", "kind", "value", "std", "pct_sigma", "expression"]
    assert list(df["name"]) == list(res.names)
    assert np.array_equal(df["value"].to_numpy(), res.values) and np.array_equal(df["std"].to_numpy(), res.std)


def test_analysis_table_and_frame(puma):
    robot, a = puma
    vals = a.base_values
    assert vals.shape == (a.n_base,)
    assert np.allclose(vals, a.to_base(robot.parameters("khalil"), "khalil"))
    lines = a.table().splitlines()
    assert lines[0].split() == ["name", "value", "expression"] and len(lines) == a.n_base + 1
    assert [ln.split()[0] for ln in lines[1:]] == a.base_names
    pd = _pandas()
    if pd is None:
        with pytest.raises(baseparams.BaseparamsError, match="pip install pandas"):
            a.to_frame()
        return
    df = a.to_frame()
    assert list(df.columns) == ["name", "expression", "value"]
    assert list(df["expression"]) == [e["expression"] for e in a.expressions()]
    assert np.array_equal(df["value"].to_numpy(), vals)


def test_to_frame_without_pandas_is_one_clear_error(puma, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas -> ImportError
    with pytest.raises(baseparams.BaseparamsError, match=r"to_frame\(\) needs pandas.*pip install pandas"):
        puma[1].to_frame()


def test_text_table_aligns():
    out = text_table({"name": ["a", "bbb"], "value": [1.0, -0.000123456789], "note": ["x", None]})
    assert out.splitlines() == ["name         value  note", "a                1  x", "bbb   -0.000123457"]


# ---------------------------------------------------------------- namespace
def test_dir_shows_public_names_and_documented_subpackages_only():
    import baseparams.display  # noqa: F401  (a helper module: bound on the package, not listed)

    names = [n for n in dir(baseparams) if not n.startswith("__")]
    assert set(names) == set(baseparams.__all__) - {"__version__"} | set(baseparams._SUBMODULES)
    assert not {"os", "warnings", "importlib", "annotations", "display", "loading"} & set(names)
    modules = {n for n in names if type(getattr(baseparams, n)).__name__ == "module"}
    assert modules == set(baseparams._SUBMODULES)
    for sub in baseparams._SUBMODULES:
        assert f"baseparams.{sub}" in baseparams.__doc__ or sub in {"analysis", "cli", "enums", "errors"}


# ---------------------------------------------------------------- coefficients
def _check_printed(x: float) -> str:
    s = format_number(x)
    assert abs(float(s) - x) <= 1e-10 * abs(x), (x, s)
    return s


@settings(max_examples=300, deadline=None)
@given(m=st.integers(1, 99999), e=st.integers(-12, 5), ulps=st.integers(-64, 64), neg=st.booleans())
def test_printed_coefficient_is_the_decimal_without_noise(m, e, ulps, neg):
    """A short decimal off by rounding (``0.0004120899999999``) prints as the decimal."""
    exact = float(f"{'-' if neg else ''}{m}e{e}")
    x = exact * (1 + ulps * np.finfo(float).eps)
    s = _check_printed(x)
    assert not NOISE.search(s), (x, s)
    assert float(s) == exact


@settings(max_examples=300, deadline=None)
@given(x=st.floats(allow_nan=False, allow_infinity=False, min_value=-1e300, max_value=1e300).filter(
    lambda v: abs(v) > 1e-300))
def test_printed_coefficient_reads_back(x):
    _check_printed(x)


@settings(max_examples=500, deadline=None)
@given(x=st.floats(allow_nan=False, allow_infinity=False).filter(lambda v: v != 0), digits=st.integers(1, 17),
       near=st.sampled_from([None, 1e-4, 1e6, 1e16, float(np.finfo(float).tiny), float(np.finfo(float).max)]))
def test_scientific_text_is_numpys_shortest_decimal(x, digits, near):
    """Past the positional range, ``format_number`` writes the rounded value's text without trailing zeros
    (a faster path): the shortest decimal that reads back as the rounded float, the one numpy's Dragon4
    writes, for every float (next to the range's ends, subnormal, near overflow) and 1 to 17 digits."""
    if near is not None:  # a few ulps from a boundary, either side
        x = math.copysign(near, x) * (1 + (abs(x) % 64 - 32) * float(np.finfo(float).eps))  # inf past max
    r = float(f"{x:.{digits - 1}e}")
    if 1e-4 <= abs(r) < 1e6 or not np.isfinite(r):
        return
    assert format_number(x, digits) == np.format_float_scientific(r, unique=True, trim="-", exp_digits=2)


def test_puma560_expressions_have_no_float_noise(puma, capsys):
    _, a = puma
    for base in (a.base, a.base_paper):
        order = np.argsort(base.dependent, kind="stable")
        for r, e in enumerate(base.expressions()):
            printed = [float(c) for c in COEF.findall(e["expression"])]
            coefs = [abs(c) for c in base.K[r, order] if c != 0 and abs(c) != 1]
            assert len(printed) == len(coefs)
            assert all(abs(p - c) <= 1e-10 * c for p, c in zip(printed, coefs))
            assert not NOISE.search(e["expression"]), e
    assert "0.00041209*link4.M" in a.expressions()[8]["expression"]
    assert baseparams.cli.main(["analyze", "puma560"]) == 0
    text = capsys.readouterr().out
    expr_lines = [ln for ln in text.splitlines() if re.match(r"  link\d\.\w+ = ", ln)]
    assert len(expr_lines) == 2 * a.n_base and not any(NOISE.search(ln) for ln in expr_lines)
    # only the strings changed: the JSON's numbers are the arrays' own
    j = a.to_json()
    assert j["base_parameters"] == a.expressions() and j["nullity"] == 24
