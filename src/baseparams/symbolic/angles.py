"""Symbolic angles as rational functions: ``cos a``, ``sin a`` through the half-angle tangent.

With ``t = tan(a / 2)``, ``cos a = (1 - t^2) / (1 + t^2)`` and ``sin a = 2 t / (1 + t^2)``: the
geometry stays a rational function of its symbols (no relation ``cos^2 + sin^2 = 1`` to carry),
so every exact step of the analysis (ranks, kernels, elimination) is unchanged, and random rational
``t`` are points of the circle. Results are written back in ``cos a`` and ``sin a``
(:func:`to_trig`): each coefficient, per monomial of the other symbols, is fitted exactly by the
lowest-degree trigonometric form (``C^2``, ``C S``, ``S^2`` before mixed forms).
"""

from __future__ import annotations

import sympy as sp

#: half-angle tangent symbol -> its angle symbol (``t_a = tan(a / 2)``)
_ANGLE_OF: dict = {}


def half_tangent(angle: sp.Symbol) -> sp.Symbol:
    """The symbol ``tan(angle / 2)`` stands for (one per angle name).

    Parameters
    ----------
    angle : sympy.Symbol
        An angle symbol.

    Returns
    -------
    sympy.Symbol
        ``tan_<name>_2`` (real), registered so that :func:`angle_of` finds the angle again.
    """
    t = sp.Symbol(f"tan_{angle.name}_2", real=True)
    _ANGLE_OF[t] = angle
    return t


def angle_of(t: sp.Symbol) -> sp.Symbol | None:
    """The angle a half-angle tangent stands for, or ``None`` for any other symbol.

    Parameters
    ----------
    t : sympy.Symbol
        A symbol of the geometry.

    Returns
    -------
    sympy.Symbol or None
        The angle.
    """
    return _ANGLE_OF.get(t)


def cos_sin(angle) -> tuple[sp.Expr, sp.Expr]:
    """``(cos angle, sin angle)``: exact numbers, or rational functions of a half-angle tangent.

    Parameters
    ----------
    angle : sympy expression
        A number, or ``+-a + c`` for one angle symbol ``a`` and an exact constant ``c``.

    Returns
    -------
    tuple of sympy.Expr
        Cosine and sine.

    Raises
    ------
    ValueError
        Another form (several symbols, a multiple of a symbol).
    """
    angle = sp.sympify(angle)
    syms = angle.free_symbols
    if not syms:
        return sp.cos(angle), sp.sin(angle)
    (a,) = syms if len(syms) == 1 else (None,)
    if a is None or sp.expand(angle).coeff(a) not in (1, -1) or sp.diff(angle, a, 2) != 0:
        raise ValueError(f"symbolic angle {angle}: only +-a + constant (one symbol) is supported")
    t = half_tangent(a)
    ca, sa = (1 - t**2) / (1 + t**2), 2 * t / (1 + t**2)
    c, s = sp.expand_trig(sp.cos(angle)), sp.expand_trig(sp.sin(angle))
    return (sp.cancel(c.subs({sp.cos(a): ca, sp.sin(a): sa})), sp.cancel(s.subs({sp.cos(a): ca, sp.sin(a): sa})))


def _fit(g: sp.Expr, t: sp.Symbol, c: sp.Symbol, s: sp.Symbol) -> sp.Expr | None:
    """``g(t)`` (no other symbol) as a polynomial in ``c = cos``, ``s = sin``: homogeneous forms first."""
    den = sp.fraction(sp.cancel(g))[1]
    k = sp.degree(den, t) // 2 if den.has(t) else 0
    ct, st = (1 - t**2) / (1 + t**2), 2 * t / (1 + t**2)
    shapes = [[(i, d - i) for i in range(d, -1, -1)] for d in range(k + 1)]  # homogeneous degree d
    shapes.append([(i, j) for j in (0, 1) for i in range(k + 1 - j)])  # mixed, lowest degree
    for monos in shapes:
        coefs = sp.symbols(f"_k0:{len(monos)}")
        trial = sum((q * ct**i * st**j for q, (i, j) in zip(coefs, monos)), sp.S.Zero)
        eqs = sp.Poly(sp.fraction(sp.cancel(trial - g))[0], t).all_coeffs()
        sol = sp.solve(eqs, coefs, dict=True)
        if sol:
            return sum((sol[0].get(q, 0) * c**i * s**j for q, (i, j) in zip(coefs, monos)), sp.S.Zero)
    return None


def to_trig(expr: sp.Expr) -> sp.Expr:
    """A rational function of half-angle tangents written in ``cos`` and ``sin`` of the angles.

    Parameters
    ----------
    expr : sympy.Expr
        Polynomial in the other symbols; each coefficient a rational function of the
        half-angle tangents that comes from ``cos`` and ``sin`` (as the geometry's).

    Returns
    -------
    sympy.Expr
        The same function with ``cos(a)``, ``sin(a)``; ``expr`` unchanged when it has no
        half-angle tangent, or when a coefficient cannot be fitted (then in ``tan(a/2)``).
    """
    ts = [t for t in sorted(expr.free_symbols, key=lambda x: x.name) if angle_of(t) is not None]
    if not ts:
        return expr
    t = ts[0]
    a = angle_of(t)
    others = sorted(expr.free_symbols - {t}, key=lambda x: x.name)
    num, den = sp.fraction(sp.cancel(expr))
    out = sp.S.Zero
    pn = sp.Poly(num, *others) if others else None
    terms = pn.terms() if pn is not None else [((), num)]
    for mono, coef in terms:
        fitted = _fit(coef / den, t, sp.cos(a), sp.sin(a)) if not (den.free_symbols - {t}) else None
        if fitted is None:
            return expr.subs(t, sp.tan(a / 2))
        out += sp.Mul(*(x**e for x, e in zip(others, mono))) * fitted
    return to_trig(out) if any(angle_of(x) is not None for x in out.free_symbols) else out


def circle_probes(t: sp.Symbol) -> list[tuple[sp.Expr, str]]:
    """Special values of an angle to probe: ``(value of t, label)`` for 0 and pi/2.

    Parameters
    ----------
    t : sympy.Symbol
        A half-angle tangent.

    Returns
    -------
    list of tuple
        ``[(0, "a = 0"), (1, "a = pi/2")]``.
    """
    a = angle_of(t)
    return [(sp.S.Zero, f"{a} = 0"), (sp.S.One, f"{a} = pi/2")]


