"""The Khalil-rules oracle (``khalil_rules``) against the certified numerical analysis.

For each symbolic DH table (puma560, stanford, scara, 6r-wrist), a few small inline chains that
exercise the other particular rules (a prismatic joint oblique or perpendicular to the first
axis, coaxial revolute joints, gravity across the first axis), and two sets of lengths (the
``values`` and seeded random ones) the robot is built numerically with
:class:`baseparams.RobotBuilder` (body frame = DH frame ``j``, the frame of Khalil's
parameters) and analysed in the ``khalil`` convention. The oracle's symbolic base parameters,
evaluated at the lengths, must give the same number of base parameters, the same kept
(independent) parameters and the same rows of ``E`` (``beta = E pi``). Independently of the
numerical regrouping, the oracle must also be sufficient: parameters it cannot see (its
kernel) change no torque (the RNEA of ``oracles``), and its rows must be independent.

Both the textbook (eliminate ``YYj MZj Mj``, then the particular rules) and the numerical
regrouping (dependents chosen from the last body back, within a body in the order ``M MZ MY
MX ZZ YZ YY XZ XY XX``: ``inertia._BACK``) keep the parameters of the lower links and, within
a link, eliminate ``M``, ``MZ``, ``YY`` first, so the kept sets are compared as they are.
"""

from __future__ import annotations

import functools
import re
import zlib
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import baseparams
from khalil_rules import (
    PARAMS,
    DHTable,
    khalil_base_parameters,
    link_transform,
    parameter_symbols,
    read_dh,
    transfer_matrix,
)

from oracles import rnea

DATA = Path(__file__).resolve().parents[1] / "src" / "baseparams" / "robots" / "data" / "symbolic"
TABLES = ("puma560", "stanford", "scara", "6r-wrist")
_L1, _L2, _L3 = sp.symbols("L1 L2 L3")
_LENGTHS = {_L1: 0.4, _L2: 0.3, _L3: 0.25}
_PI = sp.pi
#: small chains for the particular rules the four tables do not reach (rows as in a .dh file)
EXTRA = {
    # P-4 with a_z = 0 (MY eliminated): a horizontal slide after a vertical one
    "cylindrical-RPP": DHTable("cylindrical-RPP", (0.0, 0.0, -9.81), _LENGTHS, [
        (0, 0, 0, 0, 0), (1, 0, _L1, 0, 0), (1, -_PI / 2, 0, 0, _L2)]),
    # P-4 with a_z != 0 (MZ eliminated): a slide at 45 degrees, then a non-parallel revolute joint
    "oblique-RPR": DHTable("oblique-RPR", (0.0, 0.0, -9.81), _LENGTHS, [
        (0, 0, 0, 0, 0), (1, _PI / 4, _L1, 0, 0), (0, -_PI / 4, _L2, 0, _L3)]),
    # P-2 beyond link 1: joint 2 coaxial with joint 1
    "coaxial-RRR": DHTable("coaxial-RRR", (0.0, 0.0, -9.81), _LENGTHS, [
        (0, 0, 0, 0, 0), (0, 0, 0, 0, _L1), (0, -_PI / 2, _L2, 0, 0)]),
    # gravity across the (parallel) axes: MXR1, MYR1 stay
    "planar-RRR-sideways-gravity": DHTable("planar-RRR-sideways-gravity", (0.0, -9.81, 0.0), _LENGTHS, [
        (0, 0, 0, 0, 0), (0, 0, _L1, 0, 0), (0, 0, _L2, 0, 0)]),
}
ROBOTS = (*TABLES, *EXTRA)
WHICH = ("file", "random")
CASES = [(r, w) for r in ROBOTS for w in WHICH]
_NAME = re.compile(rf"^({'|'.join(sorted(PARAMS, key=len, reverse=True))})(R?)(\d+)$")


@functools.cache
def table(robot: str) -> DHTable:
    """The robot's table.

    Parameters
    ----------
    robot : str
        One of :data:`ROBOTS`.

    Returns
    -------
    DHTable
        The parsed ``.dh`` file, or the inline chain of :data:`EXTRA`.
    """
    return EXTRA[robot] if robot in EXTRA else read_dh(DATA / f"{robot}.dh")


def gravity_vertical(robot: str) -> bool:
    """Whether the table's gravity is along ``z0``.

    Parameters
    ----------
    robot : str
        One of :data:`ROBOTS`.

    Returns
    -------
    bool
        ``gx == gy == 0 != gz``.
    """
    g = table(robot).gravity
    return g[0] == 0 and g[1] == 0 and g[2] != 0


@functools.cache
def oracle(robot: str) -> dict:
    """The oracle's base parameters.

    Parameters
    ----------
    robot : str
        One of :data:`ROBOTS`.

    Returns
    -------
    dict of str to sympy.Expr
        :func:`khalil_base_parameters` of the table, symbolic in its lengths.
    """
    t = table(robot)
    return khalil_base_parameters(t.rows, gravity_vertical=gravity_vertical(robot))


def lengths(robot: str, which: str) -> dict:
    """A set of lengths for the table's symbols.

    Parameters
    ----------
    robot : str
        One of :data:`ROBOTS`.
    which : {"file", "random"}
        The table's ``values``, or random ones of either sign (seeded by the robot's name).

    Returns
    -------
    dict of sympy.Symbol to float
        A number per length symbol.
    """
    values = table(robot).values
    if which == "file":
        return dict(values)
    rng = np.random.default_rng(zlib.crc32(robot.encode()))
    return {s: float(rng.choice([-1, 1]) * rng.uniform(0.1, 0.9)) for s in values}


def split_name(name: str) -> tuple[str, bool, int]:
    """Split an oracle name.

    Parameters
    ----------
    name : str
        E.g. ``"XXR3"`` or ``"XY2"``.

    Returns
    -------
    tuple of (str, bool, int)
        The parameter, whether it is grouped (``R``) and the link: ``("XX", True, 3)``.
    """
    m = _NAME.match(name)
    assert m, name
    return m.group(1), m.group(2) == "R", int(m.group(3))


def numeric_name(param: str, j: int) -> str:
    """The numerical analysis' name of a standard parameter.

    Parameters
    ----------
    param : str
        One of :data:`PARAMS`.
    j : int
        The link, from 1 (the builder's link ``link{j}``).

    Returns
    -------
    str
        E.g. ``"link3.XX"``.
    """
    return f"link{j}.{param}"


def random_inertia(rng: np.random.Generator) -> baseparams.Inertia:
    """A physically consistent random inertia: a rotated box off the origin.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source.

    Returns
    -------
    baseparams.Inertia
        Mass 1 to 5 kg, centre of mass within 0.2 m of the origin.
    """
    mass = rng.uniform(1.0, 5.0)
    a, b, c = rng.uniform(0.05, 0.4, 3)
    rot, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    box = mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    return baseparams.Inertia(mass, com=tuple(rng.uniform(-0.2, 0.2, 3)), inertia=rot @ box @ rot.T)


def origin(row: tuple, values: dict) -> np.ndarray:
    """Pose of frame ``j`` in frame ``j-1`` at ``q = 0``, in numbers.

    Parameters
    ----------
    row : tuple
        ``(sigma, alpha, d, theta, r)`` of joint ``j``.
    values : dict of sympy.Symbol to float
        The lengths.

    Returns
    -------
    ndarray, shape ``(4, 4)``
        ``T(j-1, j)`` at ``q_j = 0``.
    """
    rot, pos = link_transform(row)
    t = np.eye(4)
    t[:3, :3] = np.array(rot.subs(values), dtype=float)
    t[:3, 3] = np.array(pos.subs(values), dtype=float).ravel()
    return t


def build(robot: str, values: dict, seed: int = 0) -> baseparams.Robot:
    """The numerical robot of a table, with random inertias.

    Parameters
    ----------
    robot : str
        One of :data:`ROBOTS`.
    values : dict of sympy.Symbol to float
        The lengths.
    seed : int
        Seed of the inertias.

    Returns
    -------
    baseparams.Robot
        Links ``link1 .. linkn``, each body frame the DH frame ``j``.
    """
    t = table(robot)
    rng = np.random.default_rng(seed)
    b = baseparams.RobotBuilder(f"{robot}-khalil", gravity=t.gravity)
    for j, row in enumerate(t.rows, start=1):
        b.add_link(f"link{j}", parent=f"link{j - 1}" if j > 1 else None, joint="R" if row[0] == 0 else "P",
                   origin=origin(row, values), axis=(0, 0, 1), inertia=random_inertia(rng))
    return b.build()


@functools.cache
def analysis(robot: str, which: str) -> tuple[baseparams.Robot, baseparams.Analysis]:
    """The numerical robot and its analysis.

    Parameters
    ----------
    robot : str
        One of :data:`ROBOTS`.
    which : {"file", "random"}
        The lengths (:func:`lengths`).

    Returns
    -------
    tuple of (baseparams.Robot, baseparams.Analysis)
        The robot and ``analyze(robot, convention="khalil")``.
    """
    r = build(robot, lengths(robot, which), seed=zlib.crc32(which.encode()))
    return r, baseparams.analyze(r, convention="khalil")


def coefficient_row(expr: sp.Expr, n: int, values: dict) -> np.ndarray:
    """A linear form over the standard parameters as a row of numbers.

    Parameters
    ----------
    expr : sympy.Expr
        Linear in the parameters of links ``1..n``.
    n : int
        Number of links.
    values : dict of sympy.Symbol to float
        The lengths.

    Returns
    -------
    ndarray, shape ``(10 n,)``
        The coefficient of each standard parameter, links in order, :data:`PARAMS` order.
    """
    params = [s for j in range(1, n + 1) for s in parameter_symbols(j)]
    poly = sp.Poly(expr, *params)
    assert poly.total_degree() <= 1, expr
    return np.array([float(sp.diff(expr, s).subs(values)) for s in params])


def oracle_matrix(robot: str, which: str) -> np.ndarray:
    """The oracle's ``E`` (``beta = E pi``) in numbers.

    Parameters
    ----------
    robot : str
        One of :data:`ROBOTS`.
    which : {"file", "random"}
        The lengths (:func:`lengths`).

    Returns
    -------
    ndarray, shape ``(nb, 10 n)``
        One row per oracle base parameter, in the oracle's order.
    """
    n = len(table(robot).rows)
    values = lengths(robot, which)
    return np.array([coefficient_row(e, n, values) for e in oracle(robot).values()])


@pytest.mark.parametrize(("robot", "which"), CASES)
def test_count(robot, which):
    """As many base parameters as the certified numerical analysis."""
    _, a = analysis(robot, which)
    assert a.status == "certified"
    assert len(oracle(robot)) == a.n_base


@pytest.mark.parametrize(("robot", "which"), CASES)
def test_kept_parameters(robot, which):
    """The same kept parameters, and the same ``R`` (grouped) marks."""
    _, a = analysis(robot, which)
    ours = {numeric_name(p, j) + ("R" if grouped else "") for p, grouped, j in map(split_name, oracle(robot))}
    theirs = {a.base.names[i] for i in a.base.independent}
    assert {s.removesuffix("R") for s in ours} == theirs
    assert ours == set(a.base_names)


@pytest.mark.parametrize(("robot", "which"), CASES)
def test_expressions(robot, which):
    """Each oracle expression, at the lengths, is the numerical ``E`` row of its parameter."""
    _, a = analysis(robot, which)
    rows = {a.base.names[i]: a.base.E[r] for r, i in enumerate(a.base.independent)}
    ours = oracle_matrix(robot, which)
    for name, row in zip(oracle(robot), ours):
        p, _, j = split_name(name)
        theirs = rows[numeric_name(p, j)]
        np.testing.assert_allclose(row, theirs, rtol=1e-9, atol=1e-9 * np.abs(theirs).max(), err_msg=name)


@pytest.mark.parametrize(("robot", "which"), CASES)
def test_to_base(robot, which):
    """The oracle's base parameters of a random-inertia robot equal ``Analysis.to_base``."""
    r, a = analysis(robot, which)
    pi = r.parameters("khalil")
    np.testing.assert_allclose(oracle_matrix(robot, which) @ pi, a.to_base(pi, "khalil"), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(("robot", "which"), CASES)
def test_oracle_is_sufficient_and_minimal(robot, which):
    """What the oracle does not see moves no torque (RNEA); its rows are independent.

    This checks the oracle against the dynamics, not against the numerical regrouping: with
    ``len(oracle) == n_base`` (:func:`test_count`) its parameters are a base.
    """
    r, _ = analysis(robot, which)
    e = oracle_matrix(robot, which)
    assert np.linalg.matrix_rank(e) == len(e)
    _, _, vt = np.linalg.svd(e)
    kernel = vt[len(e):].T
    rng = np.random.default_rng(7)
    pi = r.parameters("khalil")
    moved = r.with_parameters(pi + kernel @ rng.normal(size=kernel.shape[1]), "khalil")
    for _ in range(5):
        q, dq, ddq = rng.uniform(-np.pi, np.pi, (3, r.dof))
        tau = rnea(r, q, dq, ddq)
        np.testing.assert_allclose(rnea(moved, q, dq, ddq), tau, rtol=0, atol=1e-9 * max(1.0, np.abs(tau).max()))


@pytest.mark.slow
def test_general_revolute_rule_is_the_textbook_one():
    """The derived grouping of ``(YYj, MZj, Mj)`` into link ``j-1`` is Khalil & Dombre's.

    Symbolic ``alpha``, ``d``, ``r``: ``XXR(j-1) = XX(j-1) + YYj + 2 rj MZj + rj^2 Mj`` and so on
    (the general grouping relations, ``S = sin(alpha_j)``, ``C = cos(alpha_j)``).
    """
    al, d, r, th, q = sp.symbols("alpha d r theta q", real=True)
    yy, mz, m = sp.symbols("YY MZ M")
    rot, pos = link_transform((0, al, d, th, r), q)
    lam = transfer_matrix(rot, pos)
    got = (lam[:, 0] + lam[:, 3]) * yy + lam[:, 8] * mz + lam[:, 9] * m
    s, c = sp.sin(al), sp.cos(al)
    textbook = [yy + 2 * r * mz + r**2 * m,                          # XXR(j-1)
                d * s * mz + d * r * s * m,                          # XYR(j-1)
                -d * c * mz - d * r * c * m,                         # XZR(j-1)
                c**2 * yy + 2 * r * c**2 * mz + (d**2 + r**2 * c**2) * m,  # YYR(j-1)
                c * s * yy + 2 * r * c * s * mz + r**2 * c * s * m,  # YZR(j-1)
                s**2 * yy + 2 * r * s**2 * mz + (d**2 + r**2 * s**2) * m,  # ZZR(j-1)
                d * m,                                               # MXR(j-1)
                -s * mz - r * s * m,                                 # MYR(j-1)
                c * mz + r * c * m,                                  # MZR(j-1)
                m]                                                   # MR(j-1)
    for name, a, b in zip(PARAMS, got, textbook):
        assert sp.simplify(a - b) == 0, (name, sp.simplify(a), b)


@pytest.mark.slow
def test_prismatic_rule_rotates_the_tensor():
    """The general prismatic rule carries ``J_j`` as ``R J_j R^T`` (no translation term)."""
    al, d, r, th = sp.symbols("alpha d r theta", real=True)
    p = parameter_symbols(2)
    rot, pos = link_transform((1, al, d, th, r))
    lam = transfer_matrix(rot, pos)
    got = lam[:, :6] * sp.Matrix(p[:6])
    j = sp.Matrix([[p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]])
    want = rot * j * rot.T
    expected = [want[0, 0], want[0, 1], want[0, 2], want[1, 1], want[1, 2], want[2, 2], 0, 0, 0, 0]
    assert all(sp.simplify(a - b) == 0 for a, b in zip(got, expected))


@pytest.mark.parametrize("rows", [
    [(1, 0, 0, 0, 0), (0, 0, 0, 0, 0)],                          # prismatic before the first revolute
    [(1, 0, 0, 0, 0), (1, -sp.pi / 2, 0, 0, 0)],                 # no revolute joint at all
], ids=["prismatic-first", "cartesian"])
def test_not_implemented(rows):
    """Geometries outside the implemented rules raise instead of guessing."""
    with pytest.raises(NotImplementedError):
        khalil_base_parameters(rows)


def test_read_dh_rejects_a_tree(tmp_path):
    """The parser reads serial chains only (``ant = j - 1``)."""
    serial = (DATA / "scara.dh").read_text()
    text = serial.replace("4  3    0      0      0   0      0", "4  2    0      0      0   0      0")
    assert text != serial
    (tmp_path / "tree.dh").write_text(text)
    with pytest.raises(ValueError, match="joint 4"):
        read_dh(tmp_path / "tree.dh")
