"""DRNG's nullspace columns on a symbolic geometry (the paper's principles, E1-E5 fixed, and R-L1).

The same columns as :func:`baseparams.nullspace.principles.drng_columns` and
:func:`baseparams.nullspace.rules.parallelogram_columns` (fixed-root parallelograms), built from
the SymPy points and directions of the spatial assignment (world frame at q = 0): each column is
a symmetric ``4 x 4`` pseudo-inertia change per body, polynomial in the symbols. Where the
numeric code compares with a tolerance (parallel axes, gravity along an axis, a zero planar
direction) the decision here is exact; a decision that holds only generically (a polynomial that
is not identically zero) is recorded as a condition under which the result may change.
Perpendicular pairs ``x, y`` of an axis ``z`` are not normalised (``x = z x e_k``,
``y = z x x``): the spans are the same. The rules R-A and R-B are in :mod:`~baseparams.symbolic.rules`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from ..display import summary_repr
from ..enums import Source
from .geometry import SymbolicRobot, normal

#: the homogeneous unit 4-vectors ``e1 e2 e3`` (directions) and ``e4`` (the origin)
UNIT = [sp.Matrix([1 if k == i else 0 for k in range(4)]) for i in range(4)]


@dataclass
class SymColumn:
    """One nullspace column: a pseudo-inertia change per body.

    Parameters
    ----------
    blocks : dict of int to sympy.Matrix
        Body -> symmetric ``(4, 4)`` change of its pseudo-inertia (world frame at q = 0).
    source : Source
        Provenance (principle or rule).
    joint : int
        The joint it comes from (``n + l`` for loop joint ``l``).
    label : str
        Which points or vectors.
    """

    blocks: dict
    source: Source
    joint: int
    label: str

    __repr__ = summary_repr


@dataclass
class Decisions:
    """Generic decisions taken on the way: polynomials assumed nonzero.

    Parameters
    ----------
    conditions : list of tuple
        ``(polynomials, reason)``: the result may change where all the polynomials vanish.
    """

    conditions: list = field(default_factory=list)

    __repr__ = summary_repr

    def is_zero(self, v: sp.Matrix, reason: str) -> bool:
        """Whether every entry of ``v`` is identically zero; if not, and it can vanish, record it.

        Parameters
        ----------
        v : sympy.Matrix
            The entries.
        reason : str
            What vanishing would mean (for the report).

        Returns
        -------
        bool
            True when identically zero.
        """
        entries = [sp.cancel(e) for e in v]  # rational functions (symbolic angles)
        nonzero = [sp.fraction(e)[0] for e in entries if e != 0]
        if not nonzero:
            return True
        if all(e.free_symbols for e in nonzero):
            self.conditions.append((nonzero, reason))
        return False


def outer(a: sp.Matrix) -> sp.Matrix:
    """``a a^T`` of a homogeneous 4-vector.

    Parameters
    ----------
    a : sympy.Matrix, shape ``(4, 1)``
        A point (``w = 1``) or direction (``w = 0``).

    Returns
    -------
    sympy.Matrix, shape ``(4, 4)``
        The symmetric product.
    """
    return a * a.T


def sym(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    """``a b^T + b a^T`` of homogeneous 4-vectors (the paper's ``sym``).

    Parameters
    ----------
    a, b : sympy.Matrix, shape ``(4, 1)``
        Points (``w = 1``) or directions (``w = 0``).

    Returns
    -------
    sympy.Matrix, shape ``(4, 4)``
        The symmetrised product.
    """
    return a * b.T + b * a.T


def _pt(v: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([v[0], v[1], v[2], 1])


def _dir(v: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([v[0], v[1], v[2], 0])


def perp_pair(z: sp.Matrix, probe: dict) -> tuple[sp.Matrix, sp.Matrix]:
    """Directions ``x = z x e_k`` and ``y = z x x`` perpendicular to ``z`` (``(3, 1)``), ``|x| = |y|`` for unit ``z``.

    Parameters
    ----------
    z : sympy.Matrix, shape ``(3, 1)``
        The axis.
    probe : dict
        Numbers for the symbols, to pick ``e_k`` farthest from ``z``.

    Returns
    -------
    x, y : sympy.Matrix, shape ``(3, 1)``
        Not normalised.
    """
    k = min(range(3), key=lambda i: abs(float(z[i].subs(probe))))
    e = sp.Matrix([1 if i == k else 0 for i in range(3)])
    x = normal(z.cross(e))
    return x, normal(z.cross(x))


def _pairs(vectors: list, names: list) -> list[tuple[sp.Matrix, str]]:
    out = []
    for a in range(len(vectors)):
        for b in range(a, len(vectors)):
            h = outer(vectors[a]) if a == b else sym(vectors[a], vectors[b])
            out.append((h, f"{names[a]} {names[b]}"))
    return out


def _two(h: sp.Matrix, child: int, parent: int) -> dict:
    return {child: h} if parent < 0 else {child: h, parent: -h}


def shared_points(robot: SymbolicRobot) -> list[SymColumn]:
    """Principle 1: R ``{O, z}``, P ``{x, y, z}``, U/S ``{O}``, ``+`` on the child, ``-`` on the parent (E1).

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.

    Returns
    -------
    list of SymColumn
        The columns (source: shared points).
    """
    out = []
    for i in range(robot.n):
        o = _pt(robot.M0[i][:3, 3])
        t = robot.jtype[i]
        if t == "R":
            vs, names = [o, _dir(robot.world_axes(i)[0])], ["O", "z"]
        elif t == "P":
            vs, names = UNIT[:3], ["x", "y", "z"]
        else:
            vs, names = [o], ["O"]
        out += [SymColumn(_two(h, i, robot.parent[i]), Source.SHARED_POINTS, i, lab) for h, lab in _pairs(vs, names)]
    return out


def fixed_points(robot: SymbolicRobot, dec: Decisions, probe: dict) -> list[SymColumn]:
    """Principle 2 for joints on the fixed base (E2 fixed), single-body columns.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    dec : Decisions
        Records generic decisions.
    probe : dict
        Numbers for the symbols (choice of perpendicular directions only).

    Returns
    -------
    list of SymColumn
        The columns (source: fixed points).
    """
    out = []
    g = robot.gravity
    g_zero = all(e == 0 for e in g)
    for i in range(robot.n):
        if robot.parent[i] >= 0:
            continue
        o = _pt(robot.M0[i][:3, 3])
        t = robot.jtype[i]
        if t == "P" or (t in ("U", "S") and g_zero):
            out += [SymColumn({i: sym(o, UNIT[k])}, Source.FIXED_POINTS, i, f"O {'xyz'[k]}") for k in range(3)]
        elif t == "R":
            z = robot.world_axes(i)[0]
            x, y = perp_pair(z, probe)
            xy = ((x, "x"), (y, "y"))
            out += [SymColumn({i: sym(_dir(z), _dir(v))}, Source.FIXED_POINTS, i, f"z {n}") for v, n in xy]
            if g_zero or dec.is_zero(z.cross(g), f"joint {robot.labels[i]}'s axis along gravity"):
                out += [SymColumn({i: sym(o, _dir(v))}, Source.FIXED_POINTS, i, f"O {n}") for v, n in xy]
    return out


def _planar(robot: SymbolicRobot, dec: Decisions) -> tuple[list, list]:
    """PRI (E5 fixed): ``is_pr`` and ``d_pr`` per body, exact decisions."""
    is_pr, d_pr = [False] * robot.n, [sp.zeros(3, 1)] * robot.n
    for i in range(robot.n):
        t = robot.jtype[i]
        if t not in ("R", "P"):
            continue
        ld = robot.world_axes(i)[0] if t == "R" else sp.zeros(3, 1)
        p = robot.parent[i]
        if p < 0:
            is_pr[i], d_pr[i] = True, ld
        elif is_pr[p] and dec.is_zero(ld.cross(d_pr[p]), f"joint {robot.labels[i]} parallel to the planar "
                                                       f"direction of {robot.names[p]}"):
            is_pr[i] = True
            d_pr[i] = d_pr[p] if any(e != 0 for e in d_pr[p]) else ld
    return is_pr, d_pr


def planar_rotations(robot: SymbolicRobot, dec: Decisions, probe: dict) -> list[SymColumn]:
    """Principle 3 (E5 fixed): planar rotations and the sliding transfers of P joints.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    dec : Decisions
        Records generic decisions.
    probe : dict
        Numbers for the symbols (choice of perpendicular directions only).

    Returns
    -------
    list of SymColumn
        The columns (source: planar rotations).
    """
    out = []
    is_pr, d_pr = _planar(robot, dec)
    src = Source.PLANAR_ROTATIONS
    for i in range(robot.n):
        if not is_pr[i] or all(e == 0 for e in d_pr[i]):
            continue
        z = d_pr[i]
        x, y = perp_pair(z, probe)
        base = robot.parent[i] < 0
        if robot.jtype[i] == "R":
            out += [SymColumn({i: outer(_dir(x)) - outer(_dir(y))}, src, i, "x x - y y"),
                    SymColumn({i: sym(_dir(x), _dir(y))}, src, i, "x y")]
            if not base:
                out += [SymColumn({i: sym(_dir(z), _dir(v))}, src, i, f"z {n}") for v, n in ((x, "x"), (y, "y"))]
        elif not base:
            o = _pt(robot.M0[i][:3, 3])
            out.append(SymColumn({i: sym(_dir(z), o)}, src, i, "d_pr O"))
            if dec.is_zero(robot.world_axes(i)[0].cross(z), f"joint {robot.labels[i]} sliding along d_pr"):
                out += [SymColumn(_two(sym(o, _dir(v)), i, robot.parent[i]), src, i, f"O {n} (transfer)")
                        for v, n in ((x, "x"), (y, "y"))]
    return out


def loop_columns(robot: SymbolicRobot) -> list[SymColumn]:
    """Principle 1 across loop joints (E4): R ``{O, z}``, P ``{x, y, z}``, U/S ``{O}``, fixed ``{O, x, y, z}``.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.

    Returns
    -------
    list of SymColumn
        The columns (source: shared points; joint ``n + l``).
    """
    out = []
    for k, lp in enumerate(robot.loops):
        o = _pt(lp.frame[:3, 3])
        if lp.type == "R":
            vs, names = [o, _dir(lp.frame[:3, :3] * lp.axes[0])], ["O", "z"]
        elif lp.type == "P":
            vs, names = UNIT[:3], ["x", "y", "z"]
        elif lp.type in ("U", "S"):
            vs, names = [o], ["O"]
        else:
            vs, names = [o] + UNIT[:3], ["O", "x", "y", "z"]
        out += [SymColumn(_two(h, lp.child, lp.parent), Source.SHARED_POINTS, robot.n + k, f"{lab} (loop)")
                for h, lab in _pairs(vs, names)]
    return out


def _path_up(robot: SymbolicRobot, b: int, stop: int) -> list[int]:
    out = []
    while b != stop:
        out.append(b)
        b = robot.parent[b]
    return out


def parallelogram_columns(robot: SymbolicRobot, dec: Decisions) -> list[SymColumn]:
    """R-L1 for parallelograms on the fixed base (the numeric rule's fixed-root case).

    A loop R joint closing a cycle base - L1 - L2 - L3 - base of R joints with parallel axes whose
    joint points form a parallelogram for every value of the symbols: the coupler ``L2`` only
    translates (``sym(f, v)`` for every direction ``f``), and every parameter of the rocker
    ``L3`` transfers to the crank ``L1`` (translated by ``P3 - P0``).

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    dec : Decisions
        Records generic decisions.

    Returns
    -------
    list of SymColumn
        The columns (source: R-L1 parallelograms).
    """
    out = []
    for lp in robot.loops:
        if lp.type != "R":
            continue
        down, up = _path_up(robot, lp.child, -1)[::-1], _path_up(robot, lp.parent, -1)
        down, up = (down, up) if len(down) == 1 else (up[::-1], down[::-1])
        if len(down) != 1 or len(up) != 2 or any(robot.jtype[b] != "R" for b in down + up):
            continue
        l1, l2 = up[::-1]
        l3 = down[0]
        pts = [robot.M0[l1][:3, 3], robot.M0[l2][:3, 3], lp.frame[:3, 3], robot.M0[l3][:3, 3]]
        axes = [robot.world_axes(b)[0] for b in (l1, l2, l3)] + [lp.frame[:3, :3] * lp.axes[0]]
        if any(not dec.is_zero(axes[0].cross(a), "parallel axes of a four-bar") for a in axes[1:]):
            continue
        if not dec.is_zero((pts[1] - pts[0]) - (pts[2] - pts[3]), f"loop {lp.name!r} a parallelogram"):
            continue
        label = f"parallelogram (loop {lp.name!r})"
        out += [SymColumn({l2: sym(UNIT[a], UNIT[b])}, Source.R_L1, l2, f"{label}: coupler translates")
                for a in range(3) for b in range(a, 4)]
        t = sp.eye(4)
        t[:3, 3] = pts[3] - pts[0]
        ti = t.inv()
        for a in range(4):
            for b in range(a, 4):
                dn = outer(UNIT[a]) if a == b else sym(UNIT[a], UNIT[b])
                out.append(SymColumn({l3: dn, l1: -(ti * dn * ti.T)}, Source.R_L1, l3,
                                     f"{label}: rocker to crank"))
    return out


def symbolic_columns(robot: SymbolicRobot, probe: dict) -> tuple[list[SymColumn], Decisions]:
    """Every DRNG column on the symbolic geometry: principles 1-3, loop joints, R-L1.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot (``n`` bodies).
    probe : dict
        Numbers for the symbols, used only to pick perpendicular directions.

    Returns
    -------
    columns : list of SymColumn
        Spanning (possibly redundant) nullspace columns, world frame at q = 0.
    decisions : Decisions
        The generic decisions taken.
    """
    dec = Decisions()
    cols = (shared_points(robot) + fixed_points(robot, dec, probe) + planar_rotations(robot, dec, probe)
            + loop_columns(robot) + parallelogram_columns(robot, dec))
    return cols, dec
