"""The symbolic pipeline at full size (issue 30): a 7-DoF arm with lengths, offsets and a twist.

Oracles: the certified numerical analysis of the same robot at random values of the symbols
(computed here), the expression-based column matrix (SymPy ``expand``, the previous path) for
the fraction-free one, ``sympy.cancel`` and the residual of the system for the ring helpers.
"""

import random

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import baseparams  # noqa: E402
from baseparams.errors import BaseparamsError  # noqa: E402
from baseparams.symbolic import (  # noqa: E402
    from_dh,
    load_symbolic,
    ring,  # noqa: E402
    symbolic_analysis,
)
from baseparams.symbolic.columns import symbolic_columns  # noqa: E402
from baseparams.symbolic.geometry import at_point, to_fraction  # noqa: E402
from baseparams.symbolic.rules import rule_columns  # noqa: E402
from baseparams.symbolic.solve import column_matrix, random_point  # noqa: E402


def _point(robot, seed):
    rng = random.Random(seed)
    return {s: sp.Rational(rng.randint(20, 180), 89) for s in robot.symbols}


def _against_numerics(sa, seed):
    """K at a random point against the certified numerical analysis there (same dependent set)."""
    point = _point(sa.robot, seed)
    num = baseparams.analyze(sa.robot.to_robot(point), convention=sa.convention)
    order = np.argsort(num.base.dependent)
    assert num.certified and num.n_base == sa.n_base
    assert list(np.asarray(num.base.dependent)[order]) == sa.dependent
    k = num.base.K[:, order]
    ks = np.array(sa.K_rational.xreplace(point).evalf(17).tolist(), dtype=float).reshape(k.shape)
    assert np.abs(ks - k).max() <= 1e-9 * max(1.0, np.abs(k).max())


def test_panda_six_lengths_gives_43_and_the_numerical_formulas():
    sa = symbolic_analysis(load_symbolic("panda-symbolic"), check=False)
    assert len(sa.robot.symbols) == 6 and sa.n_base == 43
    _against_numerics(sa, 5)


@pytest.mark.slow
def test_panda_with_offsets_and_a_twist_gives_43_and_the_numerical_formulas():
    """9 symbols (six lengths, theta of joints 2 and 4, alpha of joint 4): no answer in 300 s before."""
    sa = symbolic_analysis(load_symbolic("panda-offsets-symbolic"))  # with its own two checks
    assert len(sa.robot.symbols) == 9 and sa.n_base == 43
    assert all(c["n_base"] == 43 and c["status"] == "certified" for c in sa.checks)
    _against_numerics(sa, 7)


@pytest.mark.parametrize("name", ["panda-symbolic", "parallelogram-symbolic", "pkm-2rru-1rrs-symbolic"])
def test_fraction_free_columns_equal_the_expression_columns_up_to_scale(name):
    robot = load_symbolic(name)
    probe = random_point(robot, 1)
    cols, _ = symbolic_columns(robot, probe)
    cols += rule_columns(robot, probe)
    point = random_point(robot, 9)
    fast = ring.at_point(ring.column_matrix(robot, cols, "khalil"), point).to_Matrix()
    slow = at_point(column_matrix(robot, cols, "khalil"), point).to_Matrix()
    for k in range(fast.cols):  # each column scaled by a nonzero factor (its cleared denominator)
        assert sp.Matrix.hstack(fast[:, k], slow[:, k]).rank() == (1 if any(slow[:, k]) else 0)


def test_to_fraction_is_the_expression():
    a, b, t = sp.symbols("a b t", real=True)
    dom = sp.ZZ[a, b, t]
    c, s = (1 - t**2) / (1 + t**2), 2 * t / (1 + t**2)
    for e in (c * a + s * b, (c**2 + s**2) * a - sp.Rational(3, 7) * b, a / (1 + t**2) ** 2 - b * s * c, (a + b) ** 3):
        n, d = to_fraction(e, dom)
        assert sp.cancel(e - dom.to_sympy(n) / dom.to_sympy(d)) == 0


@pytest.mark.slow
def test_block_solve_solves_the_system_and_factors_the_determinant():
    x, y = sp.symbols("x y", real=True)
    dom = sp.ZZ[x, y]
    rng = random.Random(3)
    n = 7
    # block lower triangular in a shuffled order: blocks {0, 1}, {2}, {3, 4, 5}, {6}
    blocks = [[0, 1], [2], [3, 4, 5], [6]]
    m = sp.zeros(n, n)
    for bi, blk in enumerate(blocks):
        for r in blk:
            for c in [c for b in blocks[:bi + 1] for c in b]:
                if c in blk or rng.random() < 0.5:
                    m[r, c] = rng.randint(-3, 3) + rng.randint(0, 2) * x + rng.randint(0, 2) * y * x
            m[r, r] += 5 + x**2
    perm = list(range(n))
    rng.shuffle(perm)
    m = m.extract(perm, list(range(n)))
    rhs = sp.Matrix(n, 2, lambda i, j: rng.randint(-4, 4) + y * (i + j))
    dm = ring.split(m, dom)[0]
    got, dets = ring.block_solve(dm, ring.split(rhs, dom)[0])
    assert len(dets) == 4
    field = dom.get_field()
    y_mat = sp.Matrix([[field.to_sympy(e) for e in row] for row in got])
    assert (m * y_mat - rhs).applyfunc(sp.cancel).is_zero_matrix  # the solution solves the system
    full = dom.to_sympy(dm.det())  # SymPy's fraction-free determinant of the whole matrix
    assert sp.cancel(sp.Mul(*[field.to_sympy(d) for d in dets]) ** 2 - full**2) == 0  # det up to sign


def test_geometry_not_rational_in_the_symbols_is_refused_in_one_line():
    """A fixed angle pi/3 brings sqrt(3)/2: refused with what to do (it was a SymPy traceback)."""
    d2, r3 = sp.symbols("D2 R3", real=True)
    rows = [{"j": 1, "sigma": 0, "alpha": 0, "d": 0, "theta": 0, "r": 0},
            {"j": 2, "sigma": 0, "alpha": sp.pi / 3, "d": d2, "theta": 0, "r": 0},
            {"j": 3, "sigma": 0, "alpha": -sp.pi / 2, "d": 0, "theta": 0, "r": r3}]
    with pytest.raises(BaseparamsError, match=r"sqrt\(3\)/2, not rational in the symbols.*as a symbol"):
        symbolic_analysis(from_dh(rows, name="third-twist"))


def test_time_limit_gives_one_line_saying_what_would_help():
    with pytest.raises(BaseparamsError, match=r"did not finish in 0 s \(9 symbols, 3 of them angles.*fewer angles"):
        symbolic_analysis(load_symbolic("panda-offsets-symbolic"), max_seconds=0.0)
