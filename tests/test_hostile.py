"""Hostile and careless input: nothing in a file runs code, no output lands on an input, one line.

Each case is a class of problem closed at its source: the allow-list grammar of the symbolic
tables (``baseparams.symbolic.expr``), the one atomic writer (``baseparams.files``).
"""

import os
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

sp = pytest.importorskip("sympy")

from baseparams.symbolic.expr import ExpressionError, parse  # noqa: E402

TABLE = """name evil
convention modified
j  ant  sigma  alpha   d   theta  r
1  0    0      0       0   0      0
2  1    0      -pi/2   {entry}  0      0
"""

ATTACKS = [
    "__import__('pathlib').Path('{marker}').touch()",
    "(lambda: __import__('os').system('touch {marker}'))()",
    "open('{marker}','w')",
    "D2.__class__",
    "getattr(D2,'x')",
    "[x for x in ().__class__.__bases__]",
    "exec('1')",
    "D2 if 1 else 0",
    "'text'",
    "9**9**9**9",
    "(" * 500 + "1" + ")" * 500,
    "D2 " * 100,
    "Symbol('x')",
    "sin(x, y)",
    "cos(x=1)",
    "nan",
    "1e999",
]


@pytest.mark.parametrize("attack", ATTACKS)
def test_a_dh_table_never_runs_code(attack, tmp_path, capsys):
    from baseparams.cli import main

    marker = tmp_path / "pwned"
    f = tmp_path / "evil.dh"
    f.write_text(TABLE.format(entry=attack.format(marker=marker)))
    code = main(["analyze", str(f), "--symbolic"])
    err = capsys.readouterr().err.strip().splitlines()
    assert not marker.exists()
    if attack == "nan":  # a plain name: a symbol called nan, read as such
        return
    assert code == 2 and len(err) == 1 and str(f) in err[0], err


def test_the_same_attack_in_a_subprocess_leaves_no_file(tmp_path):
    marker = tmp_path / "pwned"
    f = tmp_path / "evil.dh"
    f.write_text(TABLE.format(entry=f"__import__('os').system('touch {marker}')"))
    r = subprocess.run([sys.executable, "-m", "baseparams", "analyze", str(f), "--symbolic"], capture_output=True,
                       text=True, timeout=120, env={**os.environ})
    assert r.returncode == 2 and "Traceback" not in r.stderr and not marker.exists()


_names = st.sampled_from(["a", "b", "D3", "RL4", "pi"])
_numbers = st.one_of(st.integers(-50, 50), st.floats(-10, 10, allow_nan=False).map(lambda x: round(x, 4)))


def _exprs():
    leaf = st.one_of(_names, _numbers.map(lambda x: f"({x})"))
    return st.recursive(leaf, lambda e: st.one_of(
        st.tuples(e, st.sampled_from(["+", "-", "*"]), e).map(lambda t: f"({t[0]} {t[1]} {t[2]})"),
        st.tuples(e, st.integers(0, 3)).map(lambda t: f"({t[0]})**{t[1]}"),
        e.map(lambda x: f"sin({x})"), e.map(lambda x: f"sqrt(({x})**2)"), e.map(lambda x: f"-{x}")), max_leaves=8)


@settings(max_examples=150, deadline=None)
@given(_exprs())
def test_allowed_expressions_read_as_sympy_reads_them(text):
    ns = {n: sp.Symbol(n, real=True) for n in ("a", "b", "D3", "RL4")}
    expected = sp.sympify(text, locals={**ns, "pi": sp.pi}, rational=True)  # the oracle: trusted text only
    assert sp.simplify(parse(text) - expected) == 0


@pytest.mark.parametrize("text, words", [("__x", "may not start"), ("a.b", "attribute"), ("a[0]", "subscript"),
                                        ("f(1)", "only sin"), ("2**a", "exponent"), ("1/0", "division by zero"),
                                        ("x" * 300, "longer than")])
def test_refusals_say_what_was_found(text, words):
    with pytest.raises(ExpressionError, match=words):
        parse(text)
