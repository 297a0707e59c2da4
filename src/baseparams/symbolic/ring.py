"""Fraction-free arithmetic for the regrouping: polynomial numerators and one denominator per matrix.

Symbolic angles enter the geometry through their half-angle tangents ``t`` (:mod:`.angles`), so
the frames have denominators (powers of ``1 + t^2``). Expanding SymPy expressions of such
fractions does not cancel them, and arithmetic in the field of rational functions cancels a
multivariate gcd at every addition: both grow quickly with the number of symbols and angles (a
7-DoF arm with six lengths, two offsets and a twist). Here a matrix is split once into
numerators over ``ZZ[symbols]`` and a common denominator (:func:`split`); products are then
polynomial (no gcd), and a column of DRNG's matrix is scaled to polynomial entries (a column's
scale does not change ``K = -A_I A_D^-1``). Geometry outside that ring (``sqrt(2)`` of an angle
``pi/4``) is reported as ``None`` and the caller uses expressions instead.
"""

from __future__ import annotations

import time

import sympy as sp
from sympy.polys.matrices import DomainMatrix
from sympy.polys.polyerrors import CoercionFailed, GeneratorsError

from ..model.inertia import SPECS, check_convention
from .geometry import SymbolicRobot, inverse, to_fraction


def ring_of(robot: SymbolicRobot):
    """``ZZ[symbols]`` of the robot (``QQ`` without symbols): integer coefficients, rational ones cleared.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot (its :attr:`~.geometry.SymbolicRobot.symbols`, angles as half-angle tangents).

    Returns
    -------
    sympy.polys.domains.Domain
        The polynomial ring (a SymPy domain).
    """
    return sp.ZZ[tuple(robot.symbols)] if robot.symbols else sp.QQ


def split(m: sp.Matrix, ring) -> tuple[DomainMatrix, object] | None:
    """``m = N / d``: polynomial numerators ``N`` over ``ring`` and one denominator ``d``.

    Parameters
    ----------
    m : sympy.Matrix
        Entries rational in the ring's symbols.
    ring : sympy.polys.domains.Domain
        ``ZZ[symbols]`` (:func:`ring_of`) or ``QQ``.

    Returns
    -------
    tuple or None
        ``(N, d)``: ``N`` a ``DomainMatrix`` over ``ring`` of ``m``'s shape and ``d`` a ring
        element (the lcm of the entries' denominators); None when an entry is not in the field
        of fractions of ``ring``.
    """
    if ring == sp.QQ:
        try:
            rows = [[ring.from_sympy(e) for e in m.row(r)] for r in range(m.rows)]
            return DomainMatrix(rows, m.shape, ring), ring.one
        except (CoercionFailed, GeneratorsError):
            return None
    try:
        entries = [[to_fraction(e, ring) for e in m.row(r)] for r in range(m.rows)]
    except (CoercionFailed, GeneratorsError):
        return None
    den = ring.one
    for row in entries:
        for _, d in row:
            den = den if d in (den, 1) else (d if den == 1 else den.lcm(d))
    nums = [[n * (den if d == 1 else den.exquo(d)) for n, d in row] for row in entries]
    return DomainMatrix(nums, m.shape, ring), den


def body_parameters(robot: SymbolicRobot, i: int, n_world: sp.Matrix, convention: str, ring,
                    cache: dict) -> tuple[list, object] | None:
    """Body ``i``'s ten parameters of a world pseudo-inertia change as ``(numerators, denominator)``.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    i : int
        The body.
    n_world : sympy.Matrix, shape ``(4, 4)``
        A symmetric pseudo-inertia change, world frame at q = 0.
    convention : str
        ``paper`` or a link-frame convention (:func:`.solve.body_parameters`).
    ring : sympy.polys.domains.Domain
        :func:`ring_of` the robot.
    cache : dict
        Reused across calls (each body's inverse link frame, split).

    Returns
    -------
    tuple or None
        ``([10 ring elements in the convention's order], denominator)``; None outside the ring.
    """
    n = split(n_world, ring)
    if n is None:
        return None
    nn, dn = n
    if convention != "paper":
        if ("frame", i) not in cache:
            cache[("frame", i)] = split(inverse(robot.link_frames[i]), ring)
        f = cache[("frame", i)]
        if f is None:
            return None
        ff, df = f
        nn, dn = ff * nn * ff.transpose(), df * df * dn
    e = nn.to_list()
    s = [row[:3] for row in e[:3]]
    tr = s[0][0] + s[1][1] + s[2][2]
    vals = {"m": e[3][3], "hx": e[0][3], "hy": e[1][3], "hz": e[2][3]}
    for a, b, key in ((0, 0, "xx"), (0, 1, "xy"), (0, 2, "xz"), (1, 1, "yy"), (1, 2, "yz"), (2, 2, "zz")):
        j = s[a][b] if convention == "paper" else (tr - s[a][b] if a == b else -s[a][b])
        vals["i" + key] = vals["s" + key] = j
    return [vals[f] for f in SPECS[check_convention(convention)].fields], dn


class TimeLimit(Exception):
    """The exact computation passed its deadline (:func:`check_deadline`)."""


def check_deadline(deadline: float | None) -> None:
    """Raise :class:`TimeLimit` once ``time.perf_counter()`` is past ``deadline`` (None: never).

    Parameters
    ----------
    deadline : float or None
        A ``time.perf_counter()`` value.

    Raises
    ------
    TimeLimit
        Past the deadline.
    """
    if deadline is not None and time.perf_counter() > deadline:
        raise TimeLimit


def column_matrix(robot: SymbolicRobot, cols: list, convention: str,
                  deadline: float | None = None) -> DomainMatrix | None:
    """DRNG's columns ``A (10 n, c)`` in ``convention``'s parameters, each scaled to polynomial entries.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    cols : list of SymColumn
        The columns (pseudo-inertia changes per body, world frame at q = 0).
    convention : str
        The parameter convention.
    deadline : float, optional
        ``time.perf_counter()`` after which :class:`TimeLimit` is raised (checked per column).

    Returns
    -------
    DomainMatrix or None
        Over ``ZZ[symbols]`` (:func:`ring_of`); column ``k`` is the column times the lcm of its
        bodies' denominators (products of ``1 + t^2``: nowhere zero). None when the geometry is
        not rational in the symbols (the caller falls back to expressions).
    """
    ring = ring_of(robot)
    cache: dict = {}
    out = [[ring.zero] * len(cols) for _ in range(10 * robot.n)]
    for k, c in enumerate(cols):
        check_deadline(deadline)
        parts = {}
        for i, blk in c.blocks.items():
            p = body_parameters(robot, i, blk, convention, ring, cache)
            if p is None:
                return None
            parts[i] = p
        den = ring.one
        for _, d in parts.values():
            den = den if d == 1 else (d if den == 1 else den.lcm(d))
        for i, (vals, d) in parts.items():
            scale = den if d == 1 else den.exquo(d)
            for f, v in enumerate(vals):
                out[10 * i + f][k] = v * scale
    return DomainMatrix(out, (10 * robot.n, len(cols)), ring)


def at_point(a: DomainMatrix, point: dict) -> DomainMatrix:
    """``a`` (over :func:`ring_of`) at rational values of the symbols: a ``DomainMatrix`` over ``QQ``.

    Parameters
    ----------
    a : DomainMatrix
        Polynomial entries.
    point : dict
        ``{symbol: Rational}`` for every generator of the ring.

    Returns
    -------
    DomainMatrix
        Over ``QQ``.
    """
    if a.domain == sp.QQ:
        return a
    a = a.convert_to(sp.QQ[tuple(a.domain.symbols)])
    vals = [(g, sp.QQ.from_sympy(point[s])) for g, s in zip(a.domain.ring.gens, a.domain.symbols)]
    rows = [[e.evaluate(vals) if e else sp.QQ.zero for e in row] for row in a.to_list()]
    return DomainMatrix(rows, a.shape, sp.QQ)


def _blocks(pattern) -> list[tuple[list, list]] | None:
    """Block-triangular order of a square sparsity pattern ``[(rows, cols)]``, or None.

    Each block's unknowns depend only on earlier blocks (a perfect matching of rows to unknowns,
    then the strongly connected components in dependency order); None when the pattern is
    structurally singular.
    """
    import numpy as np
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components, maximum_bipartite_matching

    pat = csr_matrix(np.asarray(pattern, dtype=float))
    match = maximum_bipartite_matching(pat, perm_type="column")  # row r solves for unknown match[r]
    if (match < 0).any():
        return None
    row_of = np.empty_like(match)
    row_of[match] = np.arange(len(match))
    n = len(match)
    dep = np.zeros((n, n))  # unknown c needs unknown c2: c2 appears in c's equation
    for c in range(n):
        dep[c, pat[row_of[c]].indices] = 1.0
    _, label = connected_components(csr_matrix(dep), directed=True, connection="strong")
    order, seen = [], set()

    def visit(b):  # depth first: a block after the blocks it needs
        seen.add(b)
        for c in np.flatnonzero(label == b):
            for c2 in np.flatnonzero(dep[c]):
                if label[c2] not in seen:
                    visit(label[c2])
        order.append(b)

    for b in range(label.max() + 1):
        if b not in seen:
            visit(b)
    return [([int(row_of[c]) for c in np.flatnonzero(label == b)], [int(c) for c in np.flatnonzero(label == b)])
            for b in order]


def block_solve(s: DomainMatrix, b: DomainMatrix, deadline: float | None = None) -> tuple[list, list] | None:
    """``Y = S^-1 B`` over the field of fractions, block by block (block-triangular ``S``).

    DRNG's columns touch one body or a child and its parent, so ``A_D`` is block triangular in
    the bodies' order: each block is a small system, and the entries never grow to the size of
    ``det A_D`` (as one fraction-free elimination of the whole matrix does).

    Parameters
    ----------
    s : DomainMatrix, shape ``(n, n)``
        Over ``ZZ[symbols]`` (or ``QQ``), generically nonsingular.
    b : DomainMatrix, shape ``(n, k)``
        Same domain.
    deadline : float, optional
        ``time.perf_counter()`` after which :class:`TimeLimit` is raised (checked per block).

    Returns
    -------
    tuple or None
        ``(Y, dets)``: ``Y`` as lists ``(n, k)`` of field elements and the diagonal blocks'
        determinants (their product is ``det S`` up to sign); None when ``S`` is structurally
        singular.
    """
    ring = s.domain
    field = ring.get_field() if ring != sp.QQ else sp.QQ
    sl = [[field.convert_from(e, ring) for e in row] for row in s.to_list()]
    bl = [[field.convert_from(e, ring) for e in row] for row in b.to_list()]
    order = _blocks([[e != 0 for e in row] for row in sl])
    if order is None:
        return None
    n, k = len(sl), b.shape[1]
    y: list = [None] * n
    done: list = []
    dets = []
    for rows, cols in order:
        check_deadline(deadline)
        rhs = []
        for r in rows:
            acc = list(bl[r])
            for c in done:
                if sl[r][c]:
                    acc = [a - sl[r][c] * yc for a, yc in zip(acc, y[c])]
            rhs.append(acc)
        blk = DomainMatrix([[sl[r][c] for c in cols] for r in rows], (len(rows), len(cols)), field)
        dets.append(blk.det())
        sol = blk.lu_solve(DomainMatrix(rhs, (len(rows), k), field)).to_list()
        for c, row in zip(cols, sol):
            y[c] = row
        done += cols
    return y, dets
