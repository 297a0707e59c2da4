"""The extended rules R-A (fixed vectors) and R-B (sliding points) on a symbolic geometry.

As :mod:`baseparams.nullspace.rules` and :mod:`baseparams.nullspace.subspaces`, exactly: body
``i``'s motion span ``M_i = span{(g_i(q) - I)[:3, :]}`` is built base-first by the Krylov
recursion ``M <- span{M, M S, M S^2} + span{S, S^2}`` over the world screws ``S`` of its path;
a vector is *fixed* when ``X v = 0`` for every ``X`` in ``M_i``, *level* in ``d`` when
``d^T X v = 0``, *sliding* along ``d`` when ``X v`` is parallel to ``d``. Spans are kept as
generically independent SymPy matrices (chosen at a random rational point); kernels are
computed exactly over the rational functions of the symbols and cleared of denominators. Loop
robots use the open tree's spans (a superset of the closed motion: safe, maybe incomplete).
"""

from __future__ import annotations

import sympy as sp
from sympy.polys.matrices import DomainMatrix

from ..enums import Source
from .columns import UNIT, SymColumn, sym
from .geometry import SymbolicRobot, at_point, matmul, normal


def _skew(w: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def screw(robot: SymbolicRobot, i: int, k: int) -> sp.Matrix:
    """World screw ``(4, 4)`` of body ``i``'s ``k``-th joint axis at q = 0 (``dg = S g dq``).

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    i : int
        The body.
    k : int
        The axis (``0`` for R and P; ``0, 1`` for U; S joints: the three world axes).

    Returns
    -------
    sympy.Matrix, shape ``(4, 4)``
        ``[[w^, -w^ O], [0, 0]]`` for a rotation about the axis through ``O``, ``[[0, z], [0, 0]]``
        for a translation along ``z``.
    """
    o = robot.M0[i][:3, 3]
    s = sp.zeros(4, 4)
    if robot.jtype[i] == "P":
        s[:3, 3] = robot.world_axes(i)[0]
        return s
    w = robot.world_axes(i)[k] if robot.jtype[i] != "S" else sp.Matrix([1 if j == k else 0 for j in range(3)])
    s[:3, :3] = _skew(w)
    s[:3, 3] = matmul(-_skew(w), o)
    return s


def _n_axes(robot: SymbolicRobot, i: int) -> int:
    return {"R": 1, "P": 1, "U": 2, "S": 3}[robot.jtype[i]]


def _select(mats: list, point: dict, limit: int = 12) -> list:
    """A generically independent subset of ``mats`` (earlier ones preferred), decided at ``point``."""
    if not mats:
        return []
    flat = sp.Matrix.hstack(*[m.reshape(len(m), 1) for m in mats])
    return [mats[p] for p in at_point(flat, point).rref()[1][:limit]]


def motion_spans(robot: SymbolicRobot, point: dict) -> list:
    """Every body's motion span: a list of ``(3, 4)`` SymPy matrices, ``None`` when all 12 dimensions.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    point : dict
        Random rational values of the symbols (generic rank decisions).

    Returns
    -------
    list
        Per body: generically independent spanning matrices, or ``None`` (saturated).
    """
    spans: list = []
    for i in range(robot.n):
        p = robot.parent[i]
        cur = [] if p < 0 else spans[p]
        if cur is None:
            spans.append(None)
            continue
        for k in range(_n_axes(robot, i)):
            s = screw(robot, i, k)
            s2 = matmul(s, s)
            cand = [_mul(x, s) for x in cur] + [_mul(x, s2) for x in cur] + [s[:3, :], s2[:3, :]]
            cur = _select(cur + cand, point)
        spans.append(None if len(cur) >= 12 else cur)
    return spans


def _mul(x: sp.Matrix, s: sp.Matrix) -> sp.Matrix:
    """``x (3, 4) @ s (4, 4)``, entries in :func:`~.geometry.normal` form."""
    return matmul(x, s)


def kernel(rows: sp.Matrix) -> list:
    """Exact right kernel of ``rows`` over the rational functions of its symbols, denominators cleared.

    Parameters
    ----------
    rows : sympy.Matrix, shape ``(m, c)``
        Polynomial entries.

    Returns
    -------
    list of sympy.Matrix, shape ``(c, 1)``
        A basis of the kernel (polynomial entries).
    """
    syms = sorted(rows.free_symbols, key=lambda s: s.name)
    if rows.rows == 0:
        return [sp.Matrix([1 if k == j else 0 for k in range(rows.cols)]) for j in range(rows.cols)]
    dom = sp.QQ.frac_field(*syms) if syms else sp.QQ
    ns = DomainMatrix.from_Matrix(rows).convert_to(dom).nullspace().to_Matrix()
    out = []
    for r in range(ns.rows):
        v = ns.row(r).T.applyfunc(sp.cancel)
        den = sp.lcm([sp.fraction(e)[1] for e in v]) if len(v) else 1
        out.append((v * den).applyfunc(sp.cancel))
    return out


def _stack(span: list, left: sp.Matrix | None = None) -> sp.Matrix:
    """Rows ``[left @ X for X in span]`` stacked (``left`` default identity)."""
    mats = [x if left is None else matmul(left, x) for x in span]
    return sp.Matrix.vstack(*mats) if mats else sp.zeros(0, 4)


def _gravity_filtered(robot: SymbolicRobot, span: list, blocks: list) -> list:
    """Combinations of ``blocks`` whose ``dN e4`` is level in gravity (the potential never changes)."""
    g = robot.gravity
    if not blocks or all(e == 0 for e in g) or not span:
        return blocks
    rows = normal(sp.Matrix([[(g.T * x * b[:, 3])[0] for b in blocks] for x in span]))
    coefs = kernel(rows)
    return [normal(sum((c[m] * blocks[m] for m in range(len(blocks))), sp.zeros(4, 4))) for c in coefs]


def _slide_direction(robot: SymbolicRobot, i: int) -> sp.Matrix | None:
    """The one line a point of body ``i`` can slide along: the common P direction of its path, else None."""
    d = None
    b = i
    while b >= 0:
        if robot.jtype[b] == "P":
            z = robot.world_axes(b)[0]
            if d is None:
                d = z
            elif any(sp.cancel(e) != 0 for e in d.cross(z)):
                return None
        b = robot.parent[b]
    return d


def rule_columns(robot: SymbolicRobot, point: dict) -> list[SymColumn]:
    """R-A (``sym(f, v)``, ``f`` fixed) and R-B (``sym(a, b)``, ``a`` sliding, ``b`` level), gravity filtered.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    point : dict
        Random rational values of the symbols (generic rank decisions).

    Returns
    -------
    list of SymColumn
        Single-body columns (sources R-A fixed vectors and R-B sliding points), world frame at
        q = 0.
    """
    out = []
    for i, span in enumerate(motion_spans(robot, point)):
        if span is None:
            continue
        fixed = kernel(_stack(span))
        if fixed:
            blocks = [sym(f, e) for f in fixed for e in UNIT]
            out += [SymColumn({i: h}, Source.R_A, i, "sym(f, v), f fixed")
                    for h in _gravity_filtered(robot, span, blocks)]
        d = _slide_direction(robot, i)
        if d is None:
            continue
        proj = normal(d.dot(d) * sp.eye(3) - d * d.T)
        sliding = kernel(_stack(span, proj))
        if len(sliding) <= len(fixed):
            continue
        level = kernel(_stack(span, d.T))
        blocks = [sym(a, b) for a in sliding for b in level]
        out += [SymColumn({i: h}, Source.R_B, i, "sym(a, b), a sliding, b level")
                for h in _gravity_filtered(robot, span, blocks)]
    return out
