"""The symbolic result against the certified numerical analysis, and where it stops holding.

:func:`check` substitutes random values for the symbols and compares with
:func:`baseparams.analysis.analyze` of the same robot in numbers: the same count, ``K`` equal
(to 1e-9 relative) where both chose the same dependent parameters, and in every case every
regrouped combination orthogonal to the numerical nullspace. :func:`probe` visits the
conditions (and each symbol at zero) and says what the numerical analysis finds there.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..analysis import analyze
from ..errors import BaseparamsError
from ..model.inertia import HAT_INDEX
from .angles import angle_of, circle_probes
from .solve import Condition, SymbolicAnalysis, body_parameters, no_rule_error, random_point

#: relative agreement required between the formulas at numbers and the numerical analysis
RTOL = 1e-9


def conversion(sa: SymbolicAnalysis) -> sp.Matrix:
    """``C (10 n, 10 n)``: convention parameters = ``C @`` paper parameters (block diagonal, symbolic).

    Parameters
    ----------
    sa : SymbolicAnalysis
        The result (its robot's link frames and convention).

    Returns
    -------
    sympy.Matrix, shape ``(10 n, 10 n)``
        Polynomial in the symbols; the identity for the ``paper`` convention.
    """
    n = sa.robot.n
    c = sp.zeros(10 * n, 10 * n)
    units = []
    for a, b in HAT_INDEX:  # paper unit parameter k as a symmetric 4x4 (hat order)
        m = sp.zeros(4, 4)
        m[a, b] = m[b, a] = 1
        units.append(m)
    cache: dict = {}
    for i in range(n):
        for k, m in enumerate(units):
            c[10 * i:10 * i + 10, 10 * i + k] = sp.Matrix(body_parameters(sa.robot, i, m, sa.convention, cache))
    return c


def _p_matrix(sa: SymbolicAnalysis, kmat: np.ndarray) -> np.ndarray:
    p = np.zeros((sa.n_base, 10 * sa.robot.n))
    p[np.arange(sa.n_base), sa.independent] = 1.0
    p[:, sa.dependent] = kmat
    return p


def floats(m: sp.Matrix) -> np.ndarray:
    """A SymPy matrix of numbers as a float array (17 digits).

    Parameters
    ----------
    m : sympy.Matrix
        Entries without free symbols.

    Returns
    -------
    ndarray
        Same shape.
    """
    return np.array(m.evalf(17).tolist(), dtype=float).reshape(m.shape)


def check(sa: SymbolicAnalysis, seeds=(101, 202)) -> list[dict]:
    """Compare with the certified numerical analysis at random values; record in ``sa.checks``.

    Parameters
    ----------
    sa : SymbolicAnalysis
        The symbolic result (changed in place: ``checks``, and the conditions' effects).
    seeds : sequence of int
        One random rational point per seed.

    Returns
    -------
    list of dict
        Per point: ``values``, numeric ``n_base``, ``status``, ``same_dependent``, ``K_error``
        (relative, where the dependent sets agree) and ``residual`` (``|P N| / |P| |N|``).

    Raises
    ------
    BaseparamsError
        The counts differ (the rules miss directions, or the model is degenerate at that point)
        or the formulas are not orthogonal to the numerical nullspace.
    """
    conv = conversion(sa)
    for seed in seeds:
        point = random_point(sa.robot, seed)
        robot = sa.robot.to_robot(point)
        # the numeric link-frame conventions use the body (joint) frames: comparable when the
        # symbolic parameter frames are those (modified DH, the builder's default)
        same_frames = sa.convention == "paper" or all(f == sp.eye(4) for f in sa.robot.param_frames)
        num = analyze(robot, convention=sa.convention if same_frames else "paper")
        if num.nullity > sa.nullity:
            raise no_rule_error(sa.robot, sa.nullity, num.nullity)
        if num.nullity < sa.nullity or not num.certified:
            raise BaseparamsError(f"{sa.robot.name}: the symbolic rules give {sa.nullity} nullspace directions, the "
                                  f"numerical analysis {num.nullity} ({num.status}) at {point}")
        kmat = floats(sa.K_rational.xreplace(point))  # xreplace: exact numbers in, no pattern matching
        p = _p_matrix(sa, kmat)
        n_conv = floats(conv.xreplace(point)) @ num.basis
        residual = float(np.linalg.norm(p @ n_conv) / (np.linalg.norm(p) * np.linalg.norm(n_conv)))
        same = sorted(num.base.dependent) == list(sa.dependent) and num.convention == sa.convention
        k_num = num.base.K[:, np.argsort(num.base.dependent)] if same else None
        k_err = float(np.abs(k_num - kmat).max() / max(1.0, np.abs(kmat).max())) if same else None
        if residual > RTOL or (k_err is not None and k_err > 1e-8):
            raise BaseparamsError(f"{sa.robot.name}: the formulas disagree with the numerical analysis at {point} "
                                  f"(residual {residual:.1e}, K error {k_err})")
        sa.checks.append({"values": {s.name: str(v) for s, v in point.items()}, "n_base": num.n_base,
                          "status": str(num.status), "same_dependent": same, "K_error": k_err,
                          "residual": residual})
    return sa.checks


def _on_condition(sa: SymbolicAnalysis, polys: list, seed: int) -> dict | None:
    """A random point where all ``polys`` vanish (solving the first for a symbol it has at degree 1)."""
    point = random_point(sa.robot, seed)
    if len(polys) > 1 and all(isinstance(p, sp.Symbol) for p in polys):  # symbols at zero together
        return {**point, **{p: sp.Integer(0) for p in polys}}
    first = sp.expand(polys[0])
    for s in sorted(first.free_symbols, key=lambda x: x.name):
        if sp.degree(first, s) == 1:
            rest = {k: v for k, v in point.items() if k != s}
            sol = sp.solve(first.subs(rest), s)
            if sol:
                point[s] = sol[0]
                if all(sp.simplify(p.subs(point)) == 0 for p in polys):
                    return point
    return None


def _shown_value(s, v) -> float:
    """A point's value as users write it (an angle, not its half-angle tangent)."""
    return 2 * float(sp.atan(v)) if angle_of(s) is not None else float(v)


def probe(sa: SymbolicAnalysis, seed: int = 7) -> list:
    """What the certified numerical analysis finds on each condition, and with each symbol at zero.

    Parameters
    ----------
    sa : SymbolicAnalysis
        The symbolic result; symbols at zero not already among its conditions are added as
        conditions when they change the count.
    seed : int
        Seed of the random points on the conditions.

    Returns
    -------
    list of Condition
        ``sa.conditions``, each with ``effect`` filled (e.g. ``"34 base parameters, not 36"``).
    """
    have = {str(c.polynomials) for c in sa.conditions}
    extra = [Condition([s], "the symbol at zero") for s in sa.robot.symbols
             if str([s]) not in have and angle_of(s) is None]
    for t in (s for s in sa.robot.symbols if angle_of(s) is not None):  # an angle at 0 and at pi/2
        extra += [Condition([t - v], "the angle at a special value", text=label) for v, label in circle_probes(t)]
    known = [c.polynomials[0] for c in sa.conditions if len(c.polynomials) == 1]
    extra = [c for c in extra if not any(sp.cancel(c.polynomials[0] / p).is_number for p in known)]
    for c in sa.conditions + extra:
        point = _on_condition(sa, c.polynomials, seed)
        if point is None:
            c.effect = "not probed (no rational point found on it)"
            continue
        c.point = point
        try:
            num = analyze(sa.robot.to_robot(point))
        except BaseparamsError as e:
            c.effect = f"the numerical analysis refuses that geometry ({e})"
            continue
        if not num.certified:  # a count that is not certified is not claimed
            c.effect = (f"not decided there: the numerical analysis is {num.status} "
                        f"({num.certificate.message if num.certificate else 'not verified'})")
        elif num.n_base != sa.n_base:
            at = ", ".join(f"{sa.robot.display(k)}={_shown_value(k, v):.4g}" for k, v in point.items())
            c.effect = f"{num.n_base} base parameters there, not {sa.n_base} (certified numerically at {at})"
        else:
            c.effect = f"same count ({num.n_base})" + (", other formulas" if "pivot" in c.reason else "")
    sa.conditions += [c for c in extra if "base parameters there" in c.effect]
    sa.conditions += _pairs(sa, seed)
    return sa.conditions


#: most symbols whose pairs are probed (n (n - 1) / 2 numerical analyses)
MAX_PAIR_SYMBOLS = 10


def _count(effect: str, generic: int) -> int:
    """The base-parameter count a probe found (``generic`` when it found the same)."""
    head = effect.split(" base parameters there")[0]
    return int(head) if head.isdigit() else generic


def _pairs(sa: SymbolicAnalysis, seed: int) -> list:
    """Pairs of length symbols at zero together, kept where the count differs from each alone.

    A condition such as ``D2 = D3 = 0`` (a SCARA with both links of zero length) is not implied by
    ``D2 = 0`` or ``D3 = 0`` alone: each pair is probed with the certified numerical analysis and
    reported when its count differs from the generic one and from both symbols' own.
    """
    lengths = [s for s in sa.robot.symbols if angle_of(s) is None]
    if len(lengths) > MAX_PAIR_SYMBOLS:
        return []
    alone = {c.polynomials[0]: _count(c.effect, sa.n_base) for c in sa.conditions
             if len(c.polynomials) == 1 and isinstance(c.polynomials[0], sp.Symbol)}
    found = []
    for i, a in enumerate(lengths):
        for b in lengths[i + 1:]:
            c = Condition([a, b], "the symbols at zero together",
                          text=f"{sa.robot.display(a)} = {sa.robot.display(b)} = 0")
            point = _on_condition(sa, c.polynomials, seed)
            try:
                num = analyze(sa.robot.to_robot(point))
            except BaseparamsError:
                continue
            if not num.certified or num.n_base in (sa.n_base, alone.get(a, sa.n_base), alone.get(b, sa.n_base)):
                continue
            c.point = point
            at = ", ".join(f"{sa.robot.display(k)}={_shown_value(k, v):.4g}" for k, v in point.items())
            c.effect = f"{num.n_base} base parameters there, not {sa.n_base} (certified numerically at {at})"
            found.append(c)
    return found
