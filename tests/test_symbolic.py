"""Symbolic base parameters (issue 18): formulas in the robot's dimensions.

Oracles: the certified numerical analysis of the same robot at random values of the symbols
(computed here, independently of the symbolic checks), random DH tables, the textbook rules
(:mod:`khalil_rules`, written without the symbolic code).
"""

import json
import random
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import baseparams
from baseparams.cli import main
from baseparams.errors import BaseparamsError, ModelError
from baseparams.symbolic import (
    SymbolicBuilder,
    builtin_tables,
    from_dh,
    load_symbolic,
    probe,
    read_table,
    symbolic_analysis,
    trans,
    transform,
)
from baseparams.symbolic.report import codegen, symbolic_json

ACCEPTANCE = ["puma560-symbolic", "6r-wrist-symbolic", "stanford-symbolic", "scara-symbolic",
              "parallelogram-symbolic", "pkm-2rru-1rrs-symbolic"]


def _point(robot, seed):
    rng = random.Random(seed)
    return {s: sp.Rational(rng.randint(20, 180), 89) for s in robot.symbols}


def _numeric_k(sa, point):
    """The numerical analysis' regrouping at ``point``: (dependent sorted, K with columns sorted alike)."""
    num = baseparams.analyze(sa.robot.to_robot(point), convention=sa.convention)
    order = np.argsort(num.base.dependent)
    return num, np.asarray(num.base.dependent)[order], num.base.K[:, order]


@pytest.mark.parametrize("name", ACCEPTANCE)
def test_formulas_equal_the_certified_numerical_analysis_at_random_values(name):
    sa = symbolic_analysis(load_symbolic(name), check=False)
    for seed in (11, 12):
        point = _point(sa.robot, seed)
        num, dep, k = _numeric_k(sa, point)
        assert num.certified and num.n_base == sa.n_base
        assert list(dep) == sa.dependent
        ks = np.array(sa.K.subs(point).evalf(17).tolist(), dtype=float).reshape(k.shape)
        assert np.abs(ks - k).max() <= 1e-9 * max(1.0, np.abs(k).max())


def test_puma560_has_36_base_parameters_and_the_textbook_eliminations():
    sa = symbolic_analysis(load_symbolic("puma560-symbolic"))
    assert sa.n_base == 36 and len(sa.checks) == 2
    names = [p.name for p in sa.params]
    eliminated = {names[d] for d in sa.dependent}
    # Khalil: link 1 keeps ZZR1 only; every other link loses YY, MZ and M
    assert eliminated == {f"{p}1" for p in ("XX", "XY", "XZ", "YY", "YZ", "MX", "MY", "MZ", "M")} | {
        f"{p}{j}" for j in range(2, 7) for p in ("YY", "MZ", "M")}


def test_generic_count_changes_when_a_symbol_is_zero_and_the_tool_says_so():
    sa = symbolic_analysis(load_symbolic("scara-symbolic"))
    probe(sa)
    d2 = next(c for c in sa.conditions if [str(p) for p in c.polynomials] == ["D2"])
    robot = sa.robot.to_robot(d2.point)
    at_zero = baseparams.analyze(robot).n_base  # the independent, numerical count
    assert at_zero < sa.n_base
    assert f"{at_zero} base parameters there, not {sa.n_base}" in d2.effect
    # the same report on the command line and in JSON
    j = symbolic_json(sa)
    assert any(c["condition"] == "D2 = 0" and str(at_zero) in c["effect"] for c in j["conditions"])


def _random_table(rng: random.Random, n: int) -> list[dict]:
    rows = []
    for j in range(1, n + 1):
        sigma = 1 if rng.random() < 0.25 else 0
        length = [0, sp.Symbol(f"L{j}", real=True), sp.Rational(rng.randint(1, 9), 10)]
        rows.append({"j": j, "sigma": sigma, "alpha": rng.choice([0, sp.pi / 2, -sp.pi / 2, sp.pi]),
                     "d": rng.choice(length), "theta": rng.choice([0, sp.pi / 2]),
                     "r": rng.choice(length[:2] + [sp.Symbol(f"R{j}", real=True)])})
    return rows


@pytest.mark.parametrize("seed", range(10))
def test_random_dh_chains_equal_the_numerical_analysis(seed):
    """Random serial R/P chains (exact twists, symbolic and numeric lengths, gravity along z, y or
    zero): DRNG's principles with R-A and R-B on the symbolic geometry span the whole nullspace
    (60 of 60 seeds when measured), and the formulas equal the numerics at a fresh point."""
    rng = random.Random(seed)
    robot = from_dh(_random_table(rng, rng.randint(2, 5)), name=f"random{seed}",
                    gravity=rng.choice([(0, 0, -9.81), (0, -9.81, 0), (0, 0, 0)]))
    sa = symbolic_analysis(robot, seed=seed)
    point = _point(robot, 1000 + seed)
    num, dep, k = _numeric_k(sa, point)
    assert num.n_base == sa.n_base and list(dep) == sa.dependent
    ks = np.array(sa.K.subs(point).evalf(17).tolist(), dtype=float).reshape(k.shape)
    assert np.abs(ks - k).max() <= 1e-9 * max(1.0, np.abs(k).max())


def _turret_parallelogram():
    """A parallelogram carried by a turret: R-L1 with a moving root, not available symbolically."""
    a, b, ell = sp.symbols("A B L", real=True)
    bl = SymbolicBuilder("turret-parallelogram", gravity=(0, 0, -9.81), values={"A": 0.3, "B": 0.5, "L": 1.0})
    bl.add_link("turret", joint="R", actuated=True)
    bl.add_link("crank", parent="turret", joint="R", axis=(0, 1, 0), actuated=True)
    bl.add_link("coupler", parent="crank", joint="R", axis=(0, 1, 0), origin=transform(translation=(a, 0, b)),
                actuated=False)
    bl.add_link("rocker", parent="turret", joint="R", axis=(0, 1, 0), origin=transform(translation=(ell, 0, 0)),
                actuated=False)
    bl.add_loop("closure", "R", "coupler", "rocker", origin=transform(translation=(ell, 0, 0)), axis=(0, 1, 0))
    bl.q_box = np.array([[-0.3, 0.3], [-0.3, 0.3]])
    return bl.build()


def test_a_nullspace_without_symbolic_rules_is_refused_with_the_missing_count():
    robot = _turret_parallelogram()
    num = baseparams.analyze(robot.to_robot())  # also: a zero R-L2 column no longer breaks certification
    # numerically DRNG is complete (R-L1's coupled-joint completion); the symbolic rules are not
    assert num.certified and num.status == "certified"
    with pytest.raises(BaseparamsError) as e:
        symbolic_analysis(robot)
    assert f"of the {num.nullity} nullspace directions" in str(e.value) and "no symbolic rule" in str(e.value)


def test_standard_dh_puma_agrees_with_the_builtin_numeric_puma():
    text = """name puma-sdh
convention standard
values A2=0.4318 A3=0.0203 D3=0.15005 D4=0.4318
j sigma theta d a alpha
1 0 0 0 0 pi/2
2 0 0 0 A2 0
3 0 0 D3 A3 -pi/2
4 0 0 D4 0 pi/2
5 0 0 0 0 -pi/2
6 0 0 0 0 0
"""
    sa = symbolic_analysis(read_table("puma-sdh.dh", text))
    assert sa.n_base == baseparams.analyze(baseparams.load("puma560")).n_base == 36
    # the built-in puma560 is this table at Corke's numbers: the same world geometry at q = 0
    ours = sa.robot.to_robot()
    np.testing.assert_allclose(ours.M0, baseparams.load("puma560").M0, atol=1e-12)


def test_builder_with_sympy_symbols_and_exact_angles():
    ell = sp.Symbol("L", positive=True)
    b = SymbolicBuilder("2R", gravity=(0, -9.81, 0), values={"L": 0.4})
    b.add_link("upper", joint="R").add_link("lower", parent="upper", joint="R", origin=trans("x", ell))
    sa = symbolic_analysis(b.build())
    z = {s.name: s for s in sa.params}
    assert sa.n_base == baseparams.analyze(sa.robot.to_robot()).n_base == 6
    # planar 2R, gravity in the plane (by hand: the lower link's mass seen from the upper axis)
    assert sp.expand(sa.base["ZZR_upper"] - (z["ZZ_upper"] + ell**2 * z["M_lower"])) == 0
    assert sp.expand(sa.base["MXR_upper"] - (z["MX_upper"] + ell * z["M_lower"])) == 0
    assert {"ZZ_lower", "MX_lower", "MY_lower", "MY_upper"} <= set(sa.base)


@pytest.mark.parametrize("text,needle", [
    ("j ant sigma alpha d theta r\n1 0 0 2*a 0 0 0\n", "a symbolic angle must be a name"),
    ("j ant sigma alpha d theta r\n1 0 2 0 0 0 0\n", "column sigma"),
    ("j ant sigma alpha d theta\n1 0 0 0 0 0\n", "columns are"),
    ("j ant sigma alpha d theta r\n2 0 0 0 0 0 0\n", "numbered 1, 2"),
    ("j ant sigma alpha d theta r\n1 0 0 0 0 0\n", "6 entries for 7 columns"),
    ("j ant sigma alpha d theta r\n1 0 0 0 0 0 (\n", "cannot read"),
    ("frobnicate 3\n", "unknown line"),
    ("values D3=x\n", "not a number"),
    ("name x\n", "no table rows"),
])
def test_bad_tables_are_one_line_naming_file_and_line(text, needle):
    with pytest.raises(ModelError) as e:
        read_table("bad.dh", text)
    msg = str(e.value)
    assert needle in msg and msg.startswith("bad.dh") and "\n" not in msg


def test_missing_values_are_named():
    r = read_table("t.dh", "j sigma alpha d theta r\n1 0 0 0 0 0\n2 0 pi/2 A 0 B\n")
    with pytest.raises(ModelError, match="no value for A, B"):
        r.to_robot()


@pytest.mark.parametrize("suffix", [".urdf", ".xml", ".xacro"])
def test_a_robot_file_is_not_read_as_a_dh_table(suffix, tmp_path, capsys):
    """``analyze robot.urdf --symbolic``: one line saying what --symbolic takes, not a DH-table parse error."""
    f = tmp_path / f"robot{suffix}"
    f.write_text("<?xml version='1.0'?>\n<robot name='r'><link name='a'/></robot>\n")
    assert main(["analyze", str(f), "--symbolic"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a robot file has numbers, not symbols" in err[0]
    assert "DH table (.dh" in err[0] and "puma560-symbolic" in err[0] and "without --symbolic" in err[0]
    with pytest.raises(ModelError, match="a robot file has numbers, not symbols"):
        baseparams.analyze_symbolic(f)


@pytest.mark.slow
def test_cli_symbolic_json_latex_and_codegen(tmp_path, capsys):
    assert main(["analyze", "puma560-symbolic", "--symbolic", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    sa = symbolic_analysis(load_symbolic("puma560-symbolic"), check=False)
    assert j["n_base"] == 36 and j["symbols"] == ["D3", "D4", "RL3", "RL4"]
    params = {p.name: p for p in sa.params} | {s.name: s for s in sa.robot.symbols}
    for e in j["base_parameters"]:  # the printed strings parse back to the SymPy formulas
        assert sp.expand(sp.sympify(e["expression"], locals=params) - sa.base[e["name"]]) == 0
    assert main(["analyze", "puma560-symbolic", "--symbolic", "--latex", "--no-verify"]) == 0
    tex = capsys.readouterr().out
    assert tex.count(r"\\") >= 36 + 2 and r"\begin{longtable}" in tex and "ZZR_{1}" in tex
    gen = tmp_path / "puma_regrouping.py"
    assert main(["analyze", "puma560-symbolic", "--symbolic", "--no-verify", "--codegen", str(gen)]) == 0
    ns = {}
    exec(compile(gen.read_text(), str(gen), "exec"), ns)  # pure NumPy: no SymPy, no baseparams needed
    vals = {"D3": 0.41, "D4": -0.03, "RL3": 0.12, "RL4": 0.44}
    np.testing.assert_allclose(ns["regrouping"](**vals), np.array(sa.substitute(vals).evalf().tolist(), dtype=float),
                               rtol=1e-12, atol=1e-14)
    theta = np.random.default_rng(0).normal(size=60)
    beta = ns["base_parameters"](theta, **vals)
    assert beta.shape == (36,)


def test_cli_text_report_and_numeric_analysis_of_a_table(capsys):
    assert main(["analyze", "scara-symbolic", "--symbolic"]) == 0
    out = capsys.readouterr().out
    assert "8 base parameters" in out and "ZZR1 = ZZ1 + D2**2*M2" in out and "D2 = 0" in out
    assert main(["analyze", "scara-symbolic", "--values", "D2=0", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["n_base"] == 6
    assert main(["analyze", "scara-symbolic", "--values", "D2"]) == 2
    assert "NAME=NUMBER" in capsys.readouterr().err


def test_builtin_tables_are_listed_and_load():
    names = builtin_tables()
    assert set(ACCEPTANCE) <= set(names)
    for n in names:
        r = load_symbolic(n)
        assert r.symbols and r.complete_values(None)


def _by_name(e):
    return sp.expand(e).subs({s: sp.Symbol(s.name) for s in e.free_symbols})


@pytest.mark.parametrize("table", ["puma560", "6r-wrist", "stanford", "scara"])
def test_formulas_match_the_textbook_rules(table):
    """Khalil & Dombre's regrouping, derived independently in tests/khalil_rules.py from the same table."""
    from khalil_rules import khalil_base_parameters, read_dh

    path = Path(baseparams.__file__).parent / "robots" / "data" / "symbolic" / f"{table}.dh"
    textbook = khalil_base_parameters(read_dh(path).rows)
    sa = symbolic_analysis(read_table(path), check=False)
    assert list(sa.base) == list(textbook)  # the same base parameters, names and order
    for name, expr in sa.base.items():
        assert sp.expand(_by_name(expr) - _by_name(textbook[name])) == 0, name
    if table in ("puma560", "6r-wrist"):
        assert sa.n_base == 36


@pytest.mark.parametrize("argv,needle", [
    (["analyze", "puma560-symbolic", "--symbolic", "--html", "x.html"], "--html draws the numerical analysis"),
    (["analyze", "puma560-symbolic", "--latex"], "need --symbolic"),
    (["analyze", "*.urdf", "--symbolic"], "--symbolic applies to one model"),
    (["analyze", "puma560-symbolic", "--symbolic", "--gravity", "0", "0", "-1"], "gravity is in its table"),
])
def test_cli_refuses_option_combinations_it_would_ignore(argv, needle, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1


@pytest.mark.parametrize("name", ["puma560-symbolic", "stanford-symbolic", "pkm-2rru-1rrs-symbolic"])
def test_base_regressor_of_the_family_reproduces_the_torques(name):
    """tau = W_b(q, dq, ddq; dims) @ beta(theta; dims) at dimensions other than the table's, for random theta."""
    from baseparams.symbolic import base_regressor
    from baseparams.symbolic.check import conversion, floats

    sa = symbolic_analysis(load_symbolic(name), check=False)
    rng = np.random.default_rng(3)
    dims = {s.name: float(v) * rng.uniform(0.8, 1.2) for s, v in sa.robot.complete_values(None).items()}
    robot = sa.robot.to_robot(dims)
    m = len(robot.actuated) if robot.loops else robot.dof
    q, dq, ddq = 0.2 * rng.uniform(-1, 1, size=(3, 4, m))
    if robot.loops:  # states that close the loops (actuated coordinates)
        from baseparams.numerics import closed_samples

        cs = closed_samples(robot, 300, rng)  # ~10 % of the box closes (as the built-in PKM)
        q, dq, ddq = (x[:4, robot.actuated] for x in (cs.q, cs.dq, cs.ddq))
    theta = rng.normal(size=10 * robot.n)  # standard parameters, khalil convention
    vals = sa.robot.complete_values(dims)
    c = floats(conversion(sa).subs(vals))
    tau = baseparams.regressor(robot, q, dq, ddq) @ np.linalg.solve(c, theta)
    k = floats(sa.K.subs(vals))
    beta = theta[sa.independent] + k @ theta[sa.dependent]
    wb = base_regressor(sa, q, dq, ddq, dims)
    assert wb.shape == (4, m, sa.n_base)
    np.testing.assert_allclose(wb @ beta, tau, atol=1e-9 * max(1.0, np.abs(tau).max()))
    gen = {}
    exec(codegen(sa), gen)  # the generated module: the same regressor and regrouping
    np.testing.assert_allclose(gen["base_regressor"](q, dq, ddq, **dims), wb, atol=1e-12)
    np.testing.assert_allclose(gen["base_parameters"](theta, **dims), beta, atol=1e-12)


def test_khalil_tree_columns_gamma_and_b():
    """Khalil's gamma, b columns: a tree (two arms on link 1) equals the same tree built with poses."""
    text = """name tree
j ant sigma gamma b alpha d theta r
1 0 0 0 0 0 0 0 0
2 1 0 0 0 pi/2 A 0 0
3 1 0 pi/2 B pi/2 C 0 0
"""
    sa = symbolic_analysis(read_table("tree.dh", text))
    a, b, c = sp.symbols("A B C", real=True)
    m3 = sa.robot.M0[2]
    # frame 3 = Rot(z, pi/2) Trans(z, B) Rot(x, pi/2) Trans(x, C) from frame 1 (at the origin)
    assert list(m3[:3, 3]) == [0, c, b] and list(m3[:3, 2]) == [1, 0, 0]
    assert sa.n_base == baseparams.analyze(sa.robot.to_robot({"A": 0.3, "B": 0.2, "C": 0.4})).n_base


def _table_with(table: str, row: str, new: str, values: str) -> str:
    path = Path(baseparams.__file__).parent / "robots" / "data" / "symbolic" / f"{table}.dh"
    text = path.read_text()
    assert row in text
    return text.replace(row, new).replace("\nvalues ", f"\nvalues {values} ")


@pytest.mark.slow
def test_symbolic_twist_angle_matches_the_textbook_rules(tmp_path):
    """Puma560 with a symbolic twist alpha3 (axes 2 and 3 no longer parallel): cos/sin formulas."""
    from khalil_rules import khalil_base_parameters, read_dh

    f = tmp_path / "puma_alpha3.dh"
    f.write_text(_table_with("puma560", "3  2    0      0       D3  0      RL3", "3 2 0 alpha3 D3 0 RL3", "alpha3=0.2"))
    sa = symbolic_analysis(read_table(f))
    textbook = khalil_base_parameters(read_dh(f).rows)
    assert list(sa.base) == list(textbook) and sa.n_base == 36
    for name, expr in sa.base.items():
        assert sp.simplify(_by_name(expr) - _by_name(textbook[name])) == 0, name
    assert sa.base["ZZR2"].has(sp.sin(sp.Symbol("alpha3", real=True)))


def test_symbolic_twist_angle_condition_and_count(tmp_path):
    """SCARA with a symbolic twist alpha2: generic spatial count, and alpha2 = 0 (planar) reported."""
    f = tmp_path / "scara_alpha2.dh"
    f.write_text(_table_with("scara", "2  1    0      0      D2  0      0", "2 1 0 alpha2 D2 0 0", "alpha2=0.3"))
    sa = symbolic_analysis(read_table(f))
    probe(sa)
    generic = baseparams.analyze(sa.robot.to_robot({"alpha2": 0.7, "D2": 0.3, "D3": 0.2})).n_base
    planar = baseparams.analyze(sa.robot.to_robot({"alpha2": 0.0, "D2": 0.3, "D3": 0.2})).n_base
    assert sa.n_base == generic > planar
    cond = [c for c in sa.conditions if "alpha2" in c.equation()]
    assert cond and f"{planar} base parameters there" in cond[0].effect, [str(c) for c in sa.conditions]
    assert cond[0].equation() == "sin(alpha2) = 0"


def test_symbols_vanishing_together_are_probed():
    """SCARA with D2 = D3 = 0 has 4 base parameters: not implied by D2 = 0 (6) nor D3 = 0 alone."""
    import baseparams
    from baseparams.symbolic import load_symbolic, symbolic_analysis
    from baseparams.symbolic.check import probe

    sa = symbolic_analysis(load_symbolic("scara-symbolic"))
    conds = {c.equation(): c for c in probe(sa)}
    assert "D2 = D3 = 0" in conds and conds["D2 = D3 = 0"].effect.startswith("4 base parameters there, not 8")
    point = conds["D2 = D3 = 0"].point
    assert baseparams.analyze(sa.robot.to_robot(point)).n_base == 4  # the certified numerical analysis agrees
