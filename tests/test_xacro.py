"""Issue 26 (xacro in): .xacro models read directly, expanded by ROS's xacro with expressions interpreted
by baseparams' restricted evaluator (io.safe_expr); files confined, work bounded.

Oracles: the hand-expanded URDF (tests/data/xacro/arm.urdf), stock xacro's own expansion of the same
benign file, and Pinocchio's regressor rank of the expanded URDF.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import baseparams as bp
from baseparams.cli import main
from baseparams.errors import BaseparamsError, ModelError
from baseparams.io import safe_expr, xacro_in
from baseparams.io.xacro_in import expand_xacro, find_package, parse_xacro_args

pytest.importorskip("xacro")

DATA = Path(__file__).resolve().parent / "data" / "xacro"
PKG = DATA / "arm_description"
ARM = PKG / "urdf" / "arm.urdf.xacro"
HAND = DATA / "arm.urdf"
NS = 'xmlns:xacro="http://www.ros.org/wiki/xacro"'


@pytest.fixture(autouse=True)
def _no_ros_env(monkeypatch):
    for var in ("BASEPARAMS_PACKAGE_PATH", "ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH"):
        monkeypatch.delenv(var, raising=False)


def _xacro(folder: Path, body: str, name: str = "r.urdf.xacro") -> Path:
    p = folder / name
    p.write_text(f'<?xml version="1.0"?>\n<robot name="r" {NS}>\n{body}\n</robot>\n')
    return p


def _link(name="b", mass="1.0"):
    return (f'<link name="{name}"><inertial><mass value="{mass}"/>'
            f'<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>')


ONE_JOINT = ('<link name="base"/>{link}<joint name="j" type="revolute"><parent link="base"/><child link="b"/>'
             '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')


# ---- the acceptance: the fixture analysed directly, as its hand expansion -------------------------------------
def test_xacro_loads_as_its_hand_expansion():
    a, h = bp.load(ARM), bp.load(HAND)
    assert (a.name, a.jtype, a.names) == (h.name, h.jtype, h.names) == \
        ("xarm", ("R",) * 4, ("link1", "link2", "link3", "link4"))
    assert np.allclose(a.parameters("paper"), h.parameters("paper"), rtol=1e-10, atol=1e-13)
    assert np.allclose(a.limits, h.limits)


def test_same_certified_nullity_and_analysis_as_hand_expansion():
    ra, rh = bp.analyze(bp.load(ARM)), bp.analyze(bp.load(HAND))
    assert ra.certificate.status == rh.certificate.status == "certified"
    assert ra.nullity == rh.nullity == 18
    ea, eh = ra.expressions(), rh.expressions()
    assert [e["name"] for e in ea] == [e["name"] for e in eh]
    assert [e["expression"] for e in ea] == [e["expression"] for e in eh]


def test_nullity_matches_pinocchio_rank_of_the_expanded_urdf(tmp_path):
    pin = pytest.importorskip("pinocchio")
    data, _ = expand_xacro(ARM)
    out = tmp_path / "expanded.urdf"
    out.write_bytes(data)
    robot = bp.load(ARM)
    nullity = bp.analyze(robot).nullity
    rng = np.random.default_rng(7)
    for urdf in (out, HAND):  # Pinocchio reads both files itself
        model = pin.buildModelFromUrdf(str(urdf))
        d = model.createData()
        assert model.nv == 4
        w = np.vstack([pin.computeJointTorqueRegressor(model, d, *rng.uniform(-1, 1, (3, model.nv)))
                       for _ in range(60)])
        s = np.linalg.svd(w, compute_uv=False)
        assert int(np.sum(s > 1e-9 * s[0])) == 10 * robot.n - nullity == 22


def test_our_expansion_equals_stock_xacro_on_a_benign_file(monkeypatch):
    import xacro
    import xacro.substitution_args as sa

    # stock xacro finds packages through ament; here the fixture's package is the only one
    monkeypatch.setattr(sa, "_eval_find", lambda pkg: str(PKG))
    stock = ET.fromstring(xacro.process(str(ARM)))
    ours = ET.fromstring(expand_xacro(ARM)[0])

    def items(root):
        return [(e.tag, sorted(e.attrib.items())) for e in root.iter()]

    assert items(ours) == items(stock)
    assert len(items(ours)) > 40


# ---- arguments, package path ----------------------------------------------------------------------------------
def test_xacro_args_change_the_robot():
    r = bp.load(ARM, xacro_args={"wrist": "false", "prefix": "l_"})
    assert r.jtype == ("R",) * 3 and r.names == ("l_link1", "l_link2", "l_link3")
    r2 = bp.load(ARM, xacro_args=["wrist:=0"])
    assert r2.n == 3


@pytest.mark.parametrize("bad", ["wrist=false", ":=1", "a b:=1"])
def test_bad_xacro_arg_is_one_line(bad):
    with pytest.raises(BaseparamsError, match=r"--xacro-arg .*expected NAME:=VALUE"):
        parse_xacro_args([bad])


def test_xacro_args_for_a_urdf_or_builtin_refused():
    with pytest.raises(BaseparamsError, match="apply to .xacro files"):
        bp.load(HAND, xacro_args=["a:=1"])
    with pytest.raises(BaseparamsError, match="apply to .xacro files"):
        bp.load("puma560", package_path=str(DATA))


def _outside(tmp_path, how="$(find arm_description)/urdf/inertials.xacro"):
    """A xacro file outside the fixture's package that uses it (so needs the package path)."""
    return _xacro(tmp_path, f'<xacro:include filename="{how}"/>\n<link name="base"/>\n'
                            '<link name="b"><xacro:cylinder_inertial radius="0.1" length="0.5"/></link>\n'
                            '<joint name="j" type="continuous"><parent link="base"/><child link="b"/>'
                            '<axis xyz="0 0 1"/></joint>')


def test_find_needs_the_package_path(tmp_path, monkeypatch):
    p = _outside(tmp_path)
    with pytest.raises(ModelError) as e:
        bp.load(p)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"{p}:3: xacro: $(find arm_description)") and "--package-path" in msg
    mass = 2700 * np.pi * 0.1**2 * 0.5
    assert np.isclose(bp.load(p, package_path=str(DATA)).parameters("paper")[-1], mass)
    monkeypatch.setenv("BASEPARAMS_PACKAGE_PATH", os.pathsep.join([str(tmp_path), str(DATA)]))
    assert np.isclose(bp.load(p).parameters("paper")[-1], mass)
    monkeypatch.delenv("BASEPARAMS_PACKAGE_PATH")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(DATA))
    assert np.isclose(bp.load(p).parameters("paper")[-1], mass)


def test_package_url_include_and_nested_package_folders(tmp_path):
    ws = tmp_path / "ws" / "src" / "repo"
    ws.mkdir(parents=True)
    shutil.copytree(PKG, ws / "arm_description")
    p = _outside(tmp_path, "package://arm_description/urdf/inertials.xacro")
    assert bp.load(p, package_path=[str(tmp_path / "ws" / "src")]).n == 1  # found two levels down
    assert find_package("arm_description", [ws / "arm_description"]) == ws / "arm_description"
    assert find_package("../etc", [tmp_path]) is None
    with pytest.raises(BaseparamsError, match="--package-path .*: not a folder"):
        bp.load(p, package_path=str(tmp_path / "nope"))


# ---- errors: one line naming the file and line ------------------------------------------------------------------
@pytest.mark.parametrize("body, line, pattern", [
    (ONE_JOINT.format(link=_link(mass="${undefined_mass}")), 3, r"name 'undefined_mass' is not defined"),
    ('<link name="base"/>\n<xacro:no_such_macro/>', 4, r"unknown macro name: xacro:no_such_macro"),
    ('<link name="base"/>\n<link name="$(arg missing)"/>', 4, r"undefined xacro argument 'missing'.*--xacro-arg"),
    ('<link name="base"/>\n<link name="${1/0}"/>', 4, r"division by zero"),
    ('<link name="base">\n<oops></link>', 4, r"malformed XML \(mismatched tag"),
    ('<link name="${lambda: 1}"/>', 3, r"lambda is not allowed"),
])
def test_expansion_errors_are_one_line_with_file_and_line(tmp_path, body, line, pattern):
    p = _xacro(tmp_path, body)
    with pytest.raises(ModelError, match=pattern) as e:
        bp.load(p)
    assert str(e.value).startswith(f"{p}:{line}: xacro: ") and "\n" not in str(e.value)


def test_error_in_an_included_file_names_it(tmp_path):
    (tmp_path / "inc.xacro").write_text(f'<robot {NS}>\n<link name="a"/>\n<link name="${{nope + 1}}"/>\n</robot>\n')
    p = _xacro(tmp_path, '<xacro:include filename="inc.xacro"/>')
    with pytest.raises(ModelError) as e:
        bp.load(p)
    assert str(e.value).startswith(f"{tmp_path / 'inc.xacro'}:3: xacro: name 'nope' is not defined")
    assert str(e.value).endswith(f"(included from {p})")


def test_urdf_level_errors_name_the_xacro_file(tmp_path):
    p = _xacro(tmp_path, ONE_JOINT.format(link=_link()).replace('type="revolute"', 'type="helical"'))
    with pytest.raises(ModelError, match=rf"^{p}: <joint name='j'>: .*helical"):
        bp.load(p)


def test_notes_name_the_xacro_file(tmp_path):
    p = _xacro(tmp_path, ONE_JOINT.format(link=_link(mass="-1")) + '\n<gazebo reference="$(optenv HOME fallback)"/>')
    with pytest.warns(bp.ModelWarning) as rec:
        bp.load(p)
    notes = [str(w.message) for w in rec]
    assert any(n.startswith(str(p)) and "'fallback'" in n for n in notes)
    assert all(str(p) in n or "link 'b'" in n for n in notes) and not any("/tmp/tmp" in n for n in notes)


# ---- the missing extra, the CLI ---------------------------------------------------------------------------------
def test_missing_extra_is_one_line(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "xacro", None)
    with pytest.raises(BaseparamsError, match=r"pip install 'baseparams\[xacro\]'"):
        bp.load(ARM)
    assert main(["analyze", str(ARM)]) != 0
    err = capsys.readouterr().err
    assert "baseparams[xacro]" in err and err.count("\n") == 1 and "Traceback" not in err


def test_cli_analyze_xacro_with_args_and_package_path(tmp_path, capsys):
    assert main(["analyze", str(ARM), "--json"]) == 0
    ours = json.loads(capsys.readouterr().out)
    assert main(["analyze", str(HAND), "--json"]) == 0
    hand = json.loads(capsys.readouterr().out)
    assert ours["nullity"] == hand["nullity"] == 18 and ours["n_base"] == hand["n_base"] == 22
    assert main(["analyze", str(ARM), "--json", "--xacro-arg", "wrist:=false", "--xacro-arg", "prefix:=r_"]) == 0
    assert json.loads(capsys.readouterr().out)["nullity"] == 15
    p = _outside(tmp_path)
    assert main(["analyze", str(p), "--json", "--package-path", str(DATA)]) == 0
    assert json.loads(capsys.readouterr().out)["n_base"] == 1
    code = main(["analyze", str(p)])
    err = capsys.readouterr().err
    assert code != 0 and err.count("\n") == 1 and str(p) in err and "--package-path" in err


def test_cli_simulate_identify_excite_accept_xacro(tmp_path, capsys):
    log = tmp_path / "log.csv"
    assert main(["simulate", str(ARM), str(log), "--duration", "2", "--xacro-arg", "wrist:=false"]) == 0
    assert main(["identify", str(ARM), str(log), "--xacro-arg", "wrist:=false", "--json"]) == 0
    out = capsys.readouterr().out
    result = json.loads(out[out.index("{"):])
    assert result["model"] == "xarm" and len(result["base_parameters"]) == 15
    assert main(["excite", str(ARM), "--starts", "1", "--grid", "40", "--harmonics", "2"]) == 0


def test_cli_xacro_arg_with_a_urdf_refused(capsys):
    assert main(["analyze", str(HAND), "--xacro-arg", "a:=1"]) != 0
    assert "apply to .xacro files" in capsys.readouterr().err


# ---- hostile files: no code, no other files, bounded work ----------------------------------------------------
ESCAPE = ("python.vars(python.type(0).mro()[1])['_'+'_getattribute__'](xacro.abs_filename, '_'+'_globals__')"
          "['os'].system('touch {marker}')")


@pytest.mark.parametrize("expr, pattern", [
    ("${" + ESCAPE + "}", "vars: a callable that a model file may not use"),
    ("$(eval __builtins__)", "names starting with '_'"),
    ("$(eval [c for c in python.vars])", "name 'python' is not defined"),
    ("${''.__class__.__mro__[1].__subclasses__()}", "names starting with '_'"),
    ("${'%s'.format(1)}", "attribute 'format' of a str is not allowed"),
    ("${python.type(1)}", "a callable that a model file may not use"),
    ("${math.factorial(10**5)}", "a callable that a model file may not use"),
    ("${[x for x in python.vars(math)]}", "a callable that a model file may not use"),
    ("${(lambda: 1)()}", "lambda is not allowed"),
    ("${open('/etc/passwd').read()}", "name 'open' is not defined"),
    ("${xacro.load_yaml('/etc/passwd')}", "outside the model's folder"),
    ("$(env HOME)", "may not read the environment"),
    ("$(cwd)", "may not read the environment or the working folder"),
])
def test_hostile_expressions_refused(tmp_path, expr, pattern):
    marker = tmp_path / "pwned"
    p = _xacro(tmp_path, f'<link name="{expr.replace("{marker}", str(marker))}"/>')
    with pytest.raises(ModelError, match=pattern) as e:
        expand_xacro(p)
    assert "\n" not in str(e.value) and str(e.value).startswith(str(p))
    assert not marker.exists()


def test_stock_xacro_would_run_the_escape(tmp_path):
    """Why the evaluator exists: ROS's own xacro runs this file's code (the test proves the attack is real)."""
    import xacro

    marker = tmp_path / "pwned"
    p = _xacro(tmp_path, '<link name="${' + ESCAPE.replace("{marker}", str(marker)) + '}"/>')
    xacro.process(str(p))
    assert marker.exists()
    marker.unlink()
    with pytest.raises(ModelError):
        expand_xacro(p)
    assert not marker.exists()


def test_files_outside_the_model_folder_refused(tmp_path):
    d = tmp_path / "model"
    d.mkdir()
    (tmp_path / "secret.xacro").write_text(f"<robot {NS}><link name='secret'/></robot>")
    (d / "link.xacro").symlink_to(tmp_path / "secret.xacro")
    (d / "folder.xacro").mkdir()
    for inc, pattern in [("/etc/passwd", "passwd: outside the model's folder"),
                         ("../secret.xacro", "secret.xacro: outside the model's folder"),
                         ("link.xacro", "link.xacro: outside the model's folder"),  # a symlink out
                         ("folder.xacro", "not a regular file"),
                         ("missing.xacro", "missing.xacro: no such file")]:
        p = _xacro(d, f'<link name="a"/>\n<xacro:include filename="{inc}"/>')
        with pytest.raises(ModelError, match=pattern) as e:
            expand_xacro(p)
        assert str(e.value).startswith(f"{p}:4: xacro: ")
    p = _xacro(d, '<link name="a"/>\n<xacro:include filename="missing.xacro" optional="true"/>')
    assert b"<link name=\"a\"/>" in expand_xacro(p)[0]


def test_yaml_is_safe_and_confined(tmp_path):
    (tmp_path / "ok.yaml").write_text("arm: {length: !degrees 90, mass: 2}\n")
    (tmp_path / "evil.yaml").write_text("x: !!python/object/apply:os.system ['touch pwned']\n")
    p = _xacro(tmp_path, '<xacro:property name="c" value="${xacro.load_yaml(\'ok.yaml\')}"/>\n'
                         '<link name="l${c.arm.mass}_${int(round(c[\'arm\'][\'length\'] * 1000))}"/>')
    assert b'<link name="l2_1571"/>' in expand_xacro(p)[0]
    p = _xacro(tmp_path, '<link name="${xacro.load_yaml(\'evil.yaml\')}"/>')
    with pytest.raises(ModelError, match="invalid YAML"):
        expand_xacro(p)
    assert not (tmp_path / "pwned").exists()


def test_yaml_aliases_bounded(tmp_path):
    (tmp_path / "loop.yaml").write_text("a: &x [1, *x]\n")
    laughs = "l0: &l0 [" + ", ".join(["lol"] * 10) + "]\n"
    laughs += "".join(f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 10) + "]\n" for i in range(1, 9))
    (tmp_path / "laughs.yaml").write_text(laughs)
    for f, pattern in (("loop.yaml", "nested too deeply"), ("laughs.yaml", "more than .* (steps|characters)")):
        p = _xacro(tmp_path, f'<link name="${{xacro.load_yaml(\'{f}\')}}"/>')
        t0 = time.perf_counter()
        with pytest.raises(ModelError, match=pattern):
            expand_xacro(p)
        assert time.perf_counter() - t0 < 15


@pytest.mark.parametrize("expr, pattern", [
    ("${'a' * 10**12}", "a repetition would produce more than"),
    ("${[0] * 10**12}", "a repetition would produce more than"),
    ("${9**9**9}", "a power of more than"),
    ("${1 &lt;&lt; 10**9}", "a shift to more than"),
    ("${'%1000000000d' % 1}", "width or precision of more than 3 digits"),
    ("${python.range(10**12)}", "a range of"),
    ("${[1 for a in python.range(10**6) for b in python.range(10**6)]}", "more than .* (steps|characters)"),
    ("${'x'.join(['y' * 10**7] * 10)}", "a join would produce"),
    ("${('a' * 10**7).replace('a', 'bbbbbbbbbb')}", "a replace would produce"),
    ("${str([['a' * 10**6] * 10**4] * 10)}", "str\\(\\) would produce"),
    ("${python.sorted([[['a' * 10**6] * 10**3] * 10**3] * 3, key=str)}", "str\\(\\) would produce"),
])
def test_memory_and_time_bombs_refused_fast(tmp_path, expr, pattern):
    p = _xacro(tmp_path, f'<link name="{expr}"/>')
    t0 = time.perf_counter()
    with pytest.raises(ModelError, match=pattern):
        expand_xacro(p)
    assert time.perf_counter() - t0 < 10


def _doubling(n):
    return ('<xacro:property name="p0" value="' + "a" * 64 + '"/>\n'
            + "".join(f'<xacro:property name="p{i}" value="${{p{i - 1}}}${{p{i - 1}}}"/>\n' for i in range(1, n + 1))
            + f'<link name="${{p{n}}}"/>')


def _exponential_macros(n):
    body = '<xacro:macro name="m0"><link name="a"/></xacro:macro>\n'
    body += "".join(f'<xacro:macro name="m{i}"><xacro:m{i - 1}/><xacro:m{i - 1}/></xacro:macro>\n'
                    for i in range(1, n + 1))
    return body + f"<xacro:m{n}/>"


@pytest.mark.parametrize("body, pattern", [
    (_doubling(45), r"more than \d+ characters"),  # 64 * 2^45 characters
    (_exponential_macros(40), r"more than \d+ elements expanded"),  # 2^40 links
    ('<xacro:macro name="m"><xacro:m/></xacro:macro><xacro:m/>', "nested too deeply"),
    ('<xacro:property name="a" value="${b}"/><xacro:property name="b" value="${a}"/><link name="${a}"/>',
     "circular variable definition"),
])
def test_exponential_and_recursive_expansions_refused(tmp_path, body, pattern):
    p = _xacro(tmp_path, body)
    t0 = time.perf_counter()
    with pytest.raises(ModelError, match=pattern) as e:
        expand_xacro(p)
    assert time.perf_counter() - t0 < 15 and "\n" not in str(e.value)


def test_self_include_and_include_count_bounded(tmp_path):
    p = _xacro(tmp_path, '<xacro:include filename="r.urdf.xacro"/>')
    with pytest.raises(ModelError, match="nested too deeply|more than 1000 files"):
        expand_xacro(p)


def test_entity_expansion_refused(tmp_path):
    lol = "".join(f'<!ENTITY l{i} "&l{i - 1};&l{i - 1};&l{i - 1};&l{i - 1};&l{i - 1};">' for i in range(1, 12))
    p = tmp_path / "lol.urdf.xacro"
    p.write_text(f'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY l0 "lol">{lol}]><robot name="&l11;"/>')
    t0 = time.perf_counter()
    with pytest.raises(ModelError, match=rf"^{p}:1: xacro: malformed XML"):
        expand_xacro(p)
    assert time.perf_counter() - t0 < 5


def test_budget_bounds_time(tmp_path, monkeypatch):
    monkeypatch.setattr(safe_expr, "MAX_SECONDS", 0.0)
    p = _xacro(tmp_path, '<link name="${1 + 1}"/>')
    with pytest.raises(ModelError, match="takes more than 0 s"):
        expand_xacro(p)
    monkeypatch.setattr(safe_expr, "MAX_SECONDS", 30.0)
    monkeypatch.setattr(xacro_in, "MAX_INCLUDES", 0)
    with pytest.raises(ModelError, match="more than 0 files read"):
        expand_xacro(p)


def test_xacro_module_restored_after_expansion(tmp_path):
    import xacro

    before = {k: getattr(xacro, k) for k in ("safe_eval", "eval_extension", "parse", "eval_text", "eval_all")}
    with pytest.raises(ModelError):
        expand_xacro(_xacro(tmp_path, '<link name="${nope}"/>'))
    expand_xacro(ARM)
    assert before == {k: getattr(xacro, k) for k in before}
    assert xacro.substitution_args_context["arg"] == {} and not xacro.all_includes


def test_external_entities_not_read(tmp_path):
    (tmp_path / "secret.txt").write_text("SECRET")
    p = tmp_path / "xxe.urdf.xacro"
    p.write_text(f'<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY x SYSTEM "file://{tmp_path}/secret.txt">]>'
                 f'<robot name="r" {NS}><link name="a&x;"/></robot>')
    try:
        data = expand_xacro(p)[0]
    except ModelError:
        return  # refused: fine too
    assert b"SECRET" not in data


def test_wildcard_includes_confined(tmp_path):
    d = tmp_path / "model"
    (d / "parts").mkdir(parents=True)
    for k in range(3):
        (d / "parts" / f"p{k}.xacro").write_text(f'<robot {NS}><link name="p{k}"/></robot>')
    p = _xacro(d, '<link name="a"/>\n<xacro:include filename="parts/*.xacro"/>')
    assert expand_xacro(p)[0].count(b"<link") == 4
    for spec in ("/etc/*", "parts/*/../../../*"):
        p = _xacro(d, f'<link name="a"/>\n<xacro:include filename="{spec}"/>')
        with pytest.raises(ModelError, match="wildcard include outside"):
            expand_xacro(p)


# ---- the evaluator itself: Python's semantics where allowed ----------------------------------------------------
def _evaluator():
    import math

    allowed = [(f, f) for f in (math.sin, math.sqrt, math.radians, float, int, abs, min, max, round, len, str)]
    allowed.append((range, safe_expr.bounded_range))
    return safe_expr.Evaluator(allowed, budget=safe_expr.Budget())


@pytest.mark.parametrize("expr", [
    "1 + 2 * 3 - 4 / 5", "2 ** 10 // 3 % 7", "-(3.5) ** 2", "1 < 2 <= 2 != 3", "not (1 and 0) or 5",
    "'a' if 1 > 2 else 'b'", "'abc'[1:] + 'x' * 3", "[i * i for i in range(5) if i % 2]",
    "{k: v for k, v in [(1, 2), (3, 4)]}", "sqrt(2) * sin(radians(30))", "max([3, 1, 2], key=abs)",
    "'a,b;c'.split(',')", "round(3.14159, 2)", "len({1, 2, 2})", "' x '.strip().upper()", "(1, 2) + (3,)",
    "str(12) + 'mm'", "min(abs(-3), int('7'), float('2.5'))", "[x for x in 'ab' for y in range(2)]",
    "'%s=%.3f' % ('m', 1 / 3)", "5 & 3 | 8 ^ 1", "1 << 8 >> 2", "{'a': [1, 2]}['a'][-1]", "1 in [1, 2]",
])
def test_evaluator_agrees_with_python(expr):
    import math

    names = {"sqrt": math.sqrt, "sin": math.sin, "radians": math.radians, "float": float, "int": int,
             "abs": abs, "min": min, "max": max, "round": round, "len": len, "str": str, "range": range}
    assert _evaluator().evaluate(expr, names.__getitem__) == eval(expr, {"__builtins__": {}, **names})  # noqa: S307


def test_evaluator_random_arithmetic_agrees_with_python():
    rng = np.random.default_rng(11)
    ops = ["+", "-", "*", "/", "**", "%", "//"]
    for _ in range(300):
        expr = str(round(float(rng.uniform(0.5, 3)), 3))
        for _ in range(int(rng.integers(1, 6))):
            op = ops[int(rng.integers(len(ops)))]
            right = str(round(float(rng.uniform(0.5, 3)), 3))
            expr = f"({expr} {op} {right})" if rng.random() < 0.5 else f"({right} {op} {expr})"
        try:
            want = eval(expr, {"__builtins__": {}})  # noqa: S307  (our own generated text)
        except (ZeroDivisionError, OverflowError) as exc:
            with pytest.raises(type(exc)):
                _evaluator().evaluate(expr, {}.__getitem__)
            continue
        got = _evaluator().evaluate(expr, {}.__getitem__)
        assert got == want or (isinstance(want, complex) and np.isclose(got, want))


@pytest.mark.parametrize("expr, pattern", [
    ("f'{1:>1000000000}'", "at most 3 digits"),
    ("(lambda: 1)()", "lambda"),
    ("b'%1000000000d' % 1", "width or precision of more than 3 digits"),
    ("'%*d' % (10**9, 1)", "width or precision of more than 3 digits"),
    ("(x := 1)", "':='"),
    ("[*range(3)]", "unpacking"),
    ("abs(*[1])", "'\\*' and '\\*\\*' arguments"),
    ("range.__mro__", "names starting with '_'"),
    ("str.upper('a')", "attribute 'upper' of a type is not allowed"),
    ("'a'.zfill(10**9)", "attribute 'zfill' of a str"),
    ("undefined_name", "name 'undefined_name' is not defined"),
    ("1 +", "invalid expression"),
    ("(" * 500 + "1" + ")" * 500, "nested too deeply|invalid expression"),
])
def test_evaluator_refusals(expr, pattern):
    with pytest.raises(safe_expr.ExpressionError, match=pattern):
        _evaluator().evaluate(expr, {"range": range, "str": str, "abs": abs}.__getitem__)


def test_evaluator_refuses_handing_out_callables():
    import math

    ns = {"vars": vars, "type": type, "sqrt": math.sqrt}
    ev = safe_expr.Evaluator([(math.sqrt, math.sqrt), (dict, dict), (list, list)])
    lookup = {"ns": ns, "dict": dict, "list": list, "sqrt": math.sqrt}.__getitem__
    assert ev.evaluate("sqrt(4)", lookup) == 2
    for expr in ("ns['vars']", "list(ns.values())", "dict(ns)", "ns.get('type')", "[v for v in ns.values()]"):
        with pytest.raises(safe_expr.ExpressionError, match="may not use"):
            ev.evaluate(expr, lookup)


FEATURES = """
<xacro:arg name="side" default="left"/>
<xacro:arg name="n" default="3"/>
<xacro:property name="cfg" value="${xacro.load_yaml('cfg.yaml')}"/>
<xacro:property name="sizes" value="${[0.1 * (i + 1) for i in python.range(int(xacro.arg('n')))]}"/>
<xacro:property name="table" value="${dict(a=1, b=2)}"/>
<xacro:include filename="parts.xacro" ns="parts"/>
<xacro:macro name="box" params="name *origin **extra size:=${sizes[0]} mass:=^|1.5">
  <link name="${name}">
    <inertial><xacro:insert_block name="origin"/><mass value="${mass}"/>
      <inertia ixx="${mass * size**2 / 6}" ixy="0" ixz="0" iyy="${mass * size**2 / 6}" iyz="0"
               izz="${mass * size**2 / 6}"/>
    </inertial>
    <xacro:insert_block name="extra"/>
  </link>
  <xacro:property name="last" value="${name}" scope="parent"/>
</xacro:macro>
<link name="base"/>
<xacro:property name="mass" value="2.5"/>
<xacro:box name="$(arg side)_a"><origin xyz="0 0 ${cfg.offset}"/>
  <visual><geometry><box size="1 1 1"/></geometry></visual></xacro:box>
<xacro:box name="b_${last}" size="${max(sizes)}"><origin xyz="${' '.join(str(v) for v in cfg['xyz'])}"/><x/></xacro:box>
<xacro:parts.hinge name="j1" parent="base" child="$(arg side)_a"/>
<xacro:parts.hinge name="j2" parent="$(arg side)_a" child="b_$(arg side)_a"/>
<xacro:if value="$(eval side == 'left' and n > 2)"><xacro:element xacro:name="gazebo" reference="${last}"/></xacro:if>
<xacro:unless value="${table['a'] == 1}"><link name="never"/></xacro:unless>
<joint name="extra" type="fixed"><xacro:attribute name="note" value="${'%.3f' % radians(cfg.angle)}"/>
  <parent link="base"/><child link="tool${len(sizes)}"/></joint>
<link name="tool${len(sizes)}"/>
"""


def test_feature_rich_file_expands_as_stock_xacro(tmp_path, monkeypatch):
    import xacro

    (tmp_path / "cfg.yaml").write_text("offset: 0.25\nxyz: [0.1, 0, -0.2]\nangle: !degrees 30\n")
    (tmp_path / "parts.xacro").write_text(
        f'<robot {NS}><xacro:macro name="hinge" params="name parent child">'
        '<joint name="${name}" type="revolute"><parent link="${parent}"/><child link="${child}"/>'
        '<axis xyz="0 1 0"/><limit lower="${-pi/2}" upper="${pi/2}" effort="1" velocity="1"/></joint>'
        "</xacro:macro></robot>")
    p = _xacro(tmp_path, FEATURES)
    for args in ({}, {"side": "right", "n": "4"}):
        monkeypatch.chdir(tmp_path)
        stock = ET.fromstring(xacro.process(str(p), mappings=dict(args)))
        ours = ET.fromstring(expand_xacro(p, args)[0])
        assert [(e.tag, sorted(e.attrib.items())) for e in ours.iter()] == \
               [(e.tag, sorted(e.attrib.items())) for e in stock.iter()]
        assert len(list(ours.iter())) > 20
    robot = bp.load(p, xacro_args={"n": "4"})
    assert robot.names == ("left_a", "b_left_a") and robot.dof == 2
