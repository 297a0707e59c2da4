"""Exact regrouping over the rational functions of the symbols: base parameters as SymPy formulas.

Given DRNG's columns on a symbolic geometry (:mod:`~baseparams.symbolic.columns`) in the parameters of a convention
(``A (10 n, c)``, polynomial entries), the regrouping ``beta = pi_I + K pi_D`` is
``K = -A_I A_D^-1`` on a basis of the columns (``A_D`` square). Which columns form a basis and
which parameters are dependent is decided at random rational values of the symbols (exact
arithmetic; a generic choice with probability 1, Schwartz-Zippel), in the numeric regrouping's
order (last body first; within a body the convention's order: M, MZ, MY, MX, ZZ, ...), so the
dependent parameters are Khalil's. ``K`` is then solved exactly, fraction-free, over the
polynomials in the symbols. It is valid wherever ``det A_D != 0``: its factors are the conditions
reported (:attr:`SymbolicAnalysis.conditions`), with the decisions the rules took.
"""

from __future__ import annotations

import random
import time
from dataclasses import dataclass, field

import sympy as sp
from sympy.polys.matrices import DomainMatrix
from sympy.polys.polyerrors import CoercionFailed, GeneratorsError

from ..display import clip, summary_repr
from ..enums import Source
from ..errors import BaseparamsError
from ..model.inertia import SPECS, check_convention
from . import ring
from .angles import angle_of, to_trig
from .columns import SymColumn, symbolic_columns
from .geometry import SymbolicRobot, at_point, inverse, to_fraction
from .rules import rule_columns


def body_parameters(robot: SymbolicRobot, i: int, n_world: sp.Matrix, convention: str,
                    cache: dict | None = None) -> list:
    """Body ``i``'s ten parameters (``convention``'s order) of a pseudo-inertia given in the world at q = 0.

    Computed fraction-free over ``ZZ[symbols]`` (:func:`.ring.body_parameters`), each parameter
    then cancelled once; geometry outside that ring (e.g. ``sqrt(2)`` of an angle ``pi/4``) falls
    back to expanded expressions.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    i : int
        The body.
    n_world : sympy.Matrix, shape ``(4, 4)``
        A symmetric pseudo-inertia (or change of one), world frame at q = 0.
    convention : str
        ``paper`` (the pseudo-inertia's entries in the world frame) or a link-frame convention
        (expressed in :attr:`SymbolicRobot.link_frames` ``[i]``, inertia about its origin).
    cache : dict, optional
        Reused across calls for one robot (the ring and each body's inverse frame).

    Returns
    -------
    list of sympy.Expr, length 10
        The parameters (polynomials expanded; rational functions as one cancelled fraction).
    """
    cache = {} if cache is None else cache
    rg = cache.setdefault("ring", ring.ring_of(robot))
    got = ring.body_parameters(robot, i, n_world, convention, rg, cache)
    if got is not None:
        vals, den = got
        if rg == sp.QQ:
            return [rg.to_sympy(v) for v in vals]
        field = rg.get_field()
        return [field.to_sympy(field.field.new(v, den)) for v in vals]
    if convention == "paper":
        nl = n_world
    else:
        fi = inverse(robot.link_frames[i])
        nl = fi * n_world * fi.T
    s, h, m = nl[:3, :3], nl[:3, 3], nl[3, 3]
    j = sp.eye(3) * s.trace() - s if convention != "paper" else s
    vals = {"m": m, "hx": h[0], "hy": h[1], "hz": h[2]}
    for a, b, key in ((0, 0, "xx"), (0, 1, "xy"), (0, 2, "xz"), (1, 1, "yy"), (1, 2, "yz"), (2, 2, "zz")):
        vals["i" + key] = vals["s" + key] = j[a, b]
    return [sp.expand(vals[f]) for f in SPECS[check_convention(convention)].fields]


def parameter_symbols(robot: SymbolicRobot, convention: str) -> tuple[list, list]:
    """Standard parameters as SymPy symbols, and the names of their base parameters when regrouped.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    convention : str
        The parameter convention (its SYMORO-style names: ``XX`` ... ``M``; the ``paper``
        convention's ``XX`` is the world-frame second moment ``MXX``).

    Returns
    -------
    symbols : list of sympy.Symbol, length ``10 n``
        ``XX3`` for a body labelled ``3``, ``XX_crank`` for one labelled ``crank``.
    regrouped : list of str, length ``10 n``
        ``XXR3`` / ``XXR_crank``: the name of the base parameter a standard one becomes when
        others are grouped into it.
    """
    spec = SPECS[check_convention(convention)]
    names = list(spec.names)
    syms, regrouped = [], []
    for lab in robot.labels:
        sep = "" if lab.isdigit() else "_"
        for n in names:
            syms.append(sp.Symbol(f"{n}{sep}{lab}", real=True))
            regrouped.append(f"{n}R{sep}{lab}")
    return syms, regrouped


def column_matrix(robot: SymbolicRobot, cols: list[SymColumn], convention: str) -> sp.Matrix:
    """``A (10 n, c)``: the columns in ``convention``'s parameters (polynomial entries).

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    cols : list of SymColumn
        The columns.
    convention : str
        The parameter convention.

    Returns
    -------
    sympy.Matrix, shape ``(10 n, c)``
        One column per :class:`SymColumn`.
    """
    a = sp.zeros(10 * robot.n, len(cols))
    cache: dict = {}
    for k, c in enumerate(cols):
        for i, blk in c.blocks.items():
            a[10 * i:10 * i + 10, k] = sp.Matrix(body_parameters(robot, i, blk, convention, cache))
    return a


def random_point(robot: SymbolicRobot, seed: int) -> dict:
    """Random rational values of the symbols (integers over 97, in ``(0.1, 2)`` m).

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    seed : int
        Seed.

    Returns
    -------
    dict
        ``{symbol: Rational}``.
    """
    rng = random.Random(seed)
    return {s: sp.Rational(rng.randint(10, 190), 97) for s in robot.symbols}


@dataclass
class Condition:
    """Where the generic result may change.

    Parameters
    ----------
    polynomials : list of sympy.Expr
        The result may change where all of these vanish.
    reason : str
        Where it comes from (a pivot of the elimination, a rule's decision, a symbol at zero).
    effect : str
        What the numerical, certified analysis finds there (filled by :func:`.check.probe`).
    point : dict, optional
        The values of the symbols it was probed at.
    text : str
        How to write it, when not as its polynomials (e.g. ``alpha2 = pi/2``).
    """

    polynomials: list
    reason: str
    effect: str = ""
    point: dict | None = None
    text: str = ""

    __repr__ = summary_repr

    def equation(self) -> str:
        """The condition as text, angles through ``tan(a/2)``.

        Returns
        -------
        str
            E.g. ``D2 = 0`` or ``3*L1b + 5*RBb - 5*RPb = 0``.
        """
        if self.text:
            return self.text

        def show(p):
            ts = [t for t in p.free_symbols if angle_of(t) is not None]
            for t in ts:  # p(t) / (1 + t^2)^k is a trigonometric polynomial: write it so
                trig = to_trig(sp.cancel(p / (1 + t**2) ** ((sp.degree(p, t) + 1) // 2)))
                if not trig.has(sp.tan):
                    p = trig
            back = {t: sp.tan(angle_of(t) / 2) for t in p.free_symbols if angle_of(t) is not None}
            p = sp.factor(p).subs(back)
            return sp.sstr(-p if p.could_extract_minus_sign() else p)

        return " and ".join(f"{show(p)} = 0" for p in self.polynomials)

    def __str__(self) -> str:
        eq = self.equation()
        return f"{eq}  ({self.reason}{': ' + self.effect if self.effect else ''})"


@dataclass
class SymbolicAnalysis:
    """Base parameters of a symbolic robot as formulas, as returned by :func:`symbolic_analysis`.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    convention : str
        Parameter convention of :attr:`params` and the formulas.
    params : list of sympy.Symbol
        The ``10 n`` standard parameters (``XX1`` ... ``M6``).
    independent, dependent : list of int
        Indices into :attr:`params`: kept and eliminated parameters.
    K : sympy.Matrix, shape ``(len(independent), len(dependent))``
        ``beta = pi_I + K pi_D``, rational functions of the symbols (symbolic angles through
        their ``cos`` and ``sin``).
    base_names : list of str
        One per base parameter (suffix ``R`` when others are grouped into it).
    columns : list of SymColumn
        DRNG's columns on the symbolic geometry (a spanning set).
    basis : list of int
        The columns used as a nullspace basis.
    conditions : list of Condition
        Where the result may change (pivots and decisions).
    seconds : float
        Wall time [s].
    by_source : dict
        Nullspace directions per principle or rule.
    checks : list of dict
        Comparisons with the numerical analysis (:func:`.check.check`).
    K_rational : sympy.Matrix, optional
        ``K`` as rational functions of :attr:`SymbolicRobot.symbols` (symbolic angles through
        their half-angle tangents, :mod:`.angles`): what numbers are substituted into. Default
        ``K``.
    """

    robot: SymbolicRobot
    convention: str
    params: list
    independent: list
    dependent: list
    K: sp.Matrix
    base_names: list
    columns: list
    basis: list
    conditions: list
    seconds: float
    by_source: dict
    checks: list = field(default_factory=list)
    K_rational: sp.Matrix | None = None

    def __post_init__(self) -> None:
        if self.K_rational is None:
            self.K_rational = self.K

    def __repr__(self) -> str:
        name = getattr(self.robot, "name", "robot")
        return clip(f"<SymbolicAnalysis {name}: nullity {self.nullity}, {self.n_base} base parameters "
                    f"({self.convention}), {len(self.conditions)} conditions>")

    @property
    def nullity(self) -> int:
        """Number of nullspace directions (generic)."""
        return len(self.dependent)

    @property
    def n_base(self) -> int:
        """Number of base parameters (generic)."""
        return len(self.independent)

    @property
    def base(self) -> dict:
        """``{name: sympy expression}`` of every base parameter, in parameter order."""
        out = {}
        for r, i in enumerate(self.independent):
            out[self.base_names[r]] = self.params[i] + sum(
                (self.K[r, c] * self.params[d] for c, d in enumerate(self.dependent) if self.K[r, c] != 0), sp.S.Zero)
        return out

    @property
    def unidentifiable(self) -> list:
        """Parameters that enter no base parameter (their effect on every measurement is zero)."""
        return [self.params[d] for c, d in enumerate(self.dependent)
                if all(self.K[r, c] == 0 for r in range(self.K.rows))]

    def expressions(self) -> list[dict]:
        """Every base parameter as strings: ``[{"name", "expression"}]``.

        Returns
        -------
        list of dict
            E.g. ``{"name": "ZZR1", "expression": "ZZ1 + YY2 + ..."}``.
        """
        return [{"name": k, "expression": sp.sstr(v, order="none")} for k, v in self.base.items()]

    def substitute(self, values: dict) -> sp.Matrix:
        """``K`` at numbers for the symbols (exact where they are).

        Parameters
        ----------
        values : dict
            ``{symbol or name: number}``; missing symbols take the table's values.

        Returns
        -------
        sympy.Matrix
            ``K`` evaluated.
        """
        return self.K_rational.subs(self.robot.complete_values(values))


def _choose(a, robot: SymbolicRobot, convention: str, seed: int) -> tuple[list, list]:
    """A basis of the columns and the dependent parameters, decided at a random rational point.

    ``a``: a ``sympy.Matrix`` or a ``DomainMatrix`` over :func:`.ring.ring_of` the robot.
    """
    point = random_point(robot, seed)
    num = at_point(a, point) if isinstance(a, sp.Matrix) else ring.at_point(a, point)
    basis = list(num.rref()[1])
    within = SPECS[check_convention(convention)].regroup_order
    order = [10 * i + w for i in reversed(range(robot.n)) for w in within]
    sub = num.extract(order, basis).transpose()  # rows: basis columns; columns: parameters in order
    dep = [order[p] for p in sub.rref()[1]]
    return basis, dep


def _solve(a: sp.Matrix, basis: list, dep: list, ind: list) -> tuple[sp.Matrix, sp.Expr]:
    """``K = -A_I A_D^-1`` exactly, and ``det A_D`` (columns first cleared of denominators: same ``K``)."""
    syms = sorted(a.free_symbols, key=lambda s: s.name)
    a = a.extract(list(range(a.rows)), basis).applyfunc(sp.cancel)
    for j in range(a.cols):  # symbolic angles: rational entries; a column's scale does not change K
        den = sp.lcm([sp.fraction(e)[1] for e in a.col(j)])
        if den != 1:
            a[:, j] = (a.col(j) * den).applyfunc(sp.cancel)
    basis = list(range(a.cols))
    ad, ai = a.extract(dep, basis), a.extract(ind, basis)
    dom = sp.QQ[tuple(syms)] if syms else sp.QQ
    adt = DomainMatrix.from_Matrix(ad.T).convert_to(dom)
    ait = DomainMatrix.from_Matrix(ai.T).convert_to(dom)
    if not len(dep):
        return sp.zeros(len(ind), 0), sp.S.One
    x, den = adt.solve_den(ait)  # A_D^T X = A_I^T den
    k = (-x.to_Matrix().T / dom.to_sympy(den)).applyfunc(sp.cancel)
    return k, sp.factor(dom.to_sympy(adt.det()))


def _solve_ring(a: DomainMatrix, basis: list, dep: list, ind: list,
                deadline: float | None = None) -> tuple[sp.Matrix, sp.Expr]:
    """:func:`_solve` on polynomial columns over ``ZZ[symbols]`` (:func:`.ring.column_matrix`).

    ``A_D^T X = den A_I^T`` by fraction-free elimination, then each ``K`` entry cancelled once in
    the field of fractions.
    """
    if not len(dep):
        return sp.zeros(len(ind), 0), sp.S.One
    dom = a.domain
    field = dom.get_field() if dom != sp.QQ else sp.QQ
    adt, ait = a.extract(dep, basis).transpose(), a.extract(ind, basis).transpose()
    blocks = ring.block_solve(adt, ait, deadline)  # A_D^T X = A_I^T, body by body
    if blocks is None:
        x, den = adt.solve_den(ait)  # A_D^T X = A_I^T den
        d = field.convert_from(den, dom)
        x = [[field.convert_from(e, dom) / d for e in row] for row in x.to_list()]
        dets = [field.convert_from(adt.det(), dom)]
    else:
        x, dets = blocks
    k = sp.Matrix([[field.to_sympy(-e) for e in row] for row in x]).T
    return k, sp.Mul(*[sp.factor(field.to_sympy(d)) for d in dets])


def regroup(robot: SymbolicRobot, convention: str = "khalil", seed: int = 0, progress=None,
            max_seconds: float | None = None) -> SymbolicAnalysis:
    """The regrouping of ``robot`` as formulas in its symbols, unchecked (:func:`.analyze.symbolic_analysis` checks).

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    convention : str, default "khalil"
        Parameter convention of the formulas: ``khalil`` (link frames, Khalil & Dombre) or
        ``paper`` (spatial pseudo-inertia entries at q = 0), or any of
        :data:`~baseparams.model.inertia.CONVENTIONS`.
    seed : int
        Seed of the random rational point that decides the column basis and the dependent
        parameters.
    progress : callable, optional
        Called with one line per step (``progress(str)``), e.g. the CLI's progress lines.
    max_seconds : float, optional
        Give up after this long (checked per column and per eliminated block); default no limit.

    Returns
    -------
    SymbolicAnalysis
        The formulas and the conditions under which they hold (no checks yet).

    Raises
    ------
    BaseparamsError
        Geometry not rational in the symbols, or ``max_seconds`` passed (saying where and what
        would help).
    """
    try:
        return _regroup(robot, convention, seed, progress,
                        None if max_seconds is None else time.perf_counter() + max_seconds)
    except ring.TimeLimit:
        n_ang = sum(1 for s in robot.symbols if angle_of(s) is not None)
        raise BaseparamsError(
            f"{robot.name}: the exact regrouping did not finish in {max_seconds:g} s ({len(robot.symbols)} symbols, "
            f"{n_ang} of them angles; the formulas grow with every symbolic angle): give fewer angles as symbols "
            f"(numbers in the table), or analyse at numbers ('baseparams analyze TABLE --values ...' without "
            f"--symbolic)") from None


def _regroup(robot: SymbolicRobot, convention: str, seed: int, progress, deadline: float | None) -> SymbolicAnalysis:
    """:func:`regroup` with a deadline (a ``time.perf_counter()`` value or None)."""
    t0 = time.perf_counter()
    say = progress or (lambda msg: None)
    convention = str(check_convention(convention))
    _check_rational(robot)
    probe = random_point(robot, seed + 1)
    say(f"DRNG's columns on the symbolic geometry ({len(robot.symbols)} symbols)")
    cols, dec = symbolic_columns(robot, probe)
    cols = cols + rule_columns(robot, probe)
    say(f"{len(cols)} columns in the {convention} parameters (fraction-free, per body)")
    a = ring.column_matrix(robot, cols, convention, deadline)  # fraction-free; None: not rational
    if a is None:
        a = column_matrix(robot, cols, convention)
    basis, dep = _choose(a, robot, convention, seed)
    ind = [i for i in range(10 * robot.n) if i not in set(dep)]
    say(f"eliminating {len(dep)} dependent parameters (block by block)")
    k, det = _solve(a, basis, dep, ind) if isinstance(a, sp.Matrix) else _solve_ring(a, basis, dep, ind, deadline)
    params, regrouped = parameter_symbols(robot, convention)
    names = [regrouped[i] if any(e != 0 for e in k.row(r)) else params[i].name for r, i in enumerate(ind)]
    conditions = [Condition(p, r) for p, r in dec.conditions]
    for f, _ in sp.factor_list(det)[1] if det.free_symbols else []:
        if not any(sp.expand(f - (t**2 + 1)) == 0 for t in f.free_symbols if angle_of(t) is not None):
            conditions.append(Condition([f], "a pivot of the elimination vanishes: the regrouping changes"))
    by_source: dict = {}
    chosen = [cols[b] for b in basis]
    for s in Source:
        if s.label not in by_source and any(c.source == s for c in chosen):
            by_source[s.label] = sum(1 for c in chosen if c.source == s)
    k = _reorder(k, dep)
    shown = k.applyfunc(to_trig) if any(angle_of(x) is not None for x in robot.symbols) else k
    out = SymbolicAnalysis(robot, convention, params, ind, sorted(dep), shown, names, cols, basis,
                           conditions, 0.0, by_source, K_rational=k)
    out.seconds = time.perf_counter() - t0
    return out


def _check_rational(robot: SymbolicRobot) -> None:
    """Refuse geometry that is not rational in the symbols (a fixed angle ``pi/3``: ``sqrt(3)/2``)."""
    rg = ring.ring_of(robot)
    if rg == sp.QQ:
        rg = sp.ZZ[sp.Dummy("x")]
    mats = (*robot.origins, *robot.param_frames, *(lp.frame for lp in robot.loops))
    for m in mats:
        for e in m:
            try:
                to_fraction(e, rg)
            except (CoercionFailed, GeneratorsError):
                raise BaseparamsError(
                    f"{robot.name}: the geometry has {sp.sstr(e)}, not rational in the symbols: a fixed angle must "
                    f"have a rational cosine and sine (0, pi/2, pi, -pi/2); give any other angle as a symbol "
                    f"(its number in 'values'), or analyse the robot in numbers") from None


def _reorder(k: sp.Matrix, dep: list) -> sp.Matrix:
    order = sorted(range(len(dep)), key=lambda c: dep[c])
    return k.extract(list(range(k.rows)), order) if len(dep) else k


def no_rule_error(robot: SymbolicRobot, found: int, nullity: int) -> BaseparamsError:
    """The error for a nullspace the symbolic rules do not span.

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    found : int
        Directions the rules give (generic rank).
    nullity : int
        Directions the certified numerical analysis finds.

    Returns
    -------
    BaseparamsError
        One line saying what is missing and what would help.
    """
    return BaseparamsError(
        f"{robot.name}: the rules give {found} of the {nullity} nullspace directions the certified numerical "
        f"analysis finds at random values of the symbols; the other {nullity - found} have no symbolic rule, so "
        f"no formula is given (analyse it in numbers instead: 'baseparams analyze TABLE --values ...' without "
        f"--symbolic, or SymbolicRobot.to_robot(values) and baseparams.analyze)")
