"""Symbolic base parameters as text, JSON, a LaTeX table and generated Python code.

Formulas are written the textbook way: terms whose coefficients are equal are grouped,
``(D3**2 + RL3**2)*(M4 + M5 + M6)``, in the order of the standard parameters.
"""

from __future__ import annotations

import sympy as sp

from ..model.inertia import FRAMES
from .angles import to_trig
from .check import conversion
from .solve import SymbolicAnalysis


def _groups(expr: sp.Expr, params: list) -> list[tuple[sp.Expr, list]]:
    """``[(coefficient, [parameters])]``: ``expr`` (linear in ``params``) with equal coefficients together."""
    poly = sp.Poly(expr, *params) if expr != 0 else None
    coeffs = {}
    for p in params:
        c = poly.coeff_monomial(p) if poly is not None else 0
        if c != 0:
            coeffs.setdefault(sp.factor_terms(sp.expand(c)), []).append(p)
    return list(coeffs.items())


def _term(c: sp.Expr, ps: list, printer, first: bool) -> str:
    inner = " + ".join(printer(p) for p in ps)
    neg = c.could_extract_minus_sign()
    mag = -c if neg else c
    if mag == 1:
        body = inner if len(ps) == 1 or not neg else f"({inner})"
    else:
        cs = printer(mag)
        cs = f"({cs})" if isinstance(mag, sp.Add) else cs
        body = f"{cs}*{inner}" if len(ps) == 1 else f"{cs}*({inner})"
    if first:
        return f"-{body}" if neg else body
    return f" - {body}" if neg else f" + {body}"


def pretty(expr: sp.Expr, params: list, printer=sp.sstr) -> str:
    """A base parameter's formula with equal coefficients grouped, e.g. ``ZZ1 + YY2 + D3**2*(M3 + M4)``.

    Parameters
    ----------
    expr : sympy.Expr
        Linear in ``params`` (coefficients in the geometry's symbols).
    params : list of sympy.Symbol
        The standard parameters, in their order.
    printer : callable
        ``sympy.sstr`` (text) or ``sympy.latex``.

    Returns
    -------
    str
        The formula (``0`` for zero).
    """
    groups = _groups(sp.expand(expr), params)
    # unit coefficients first (the parameter itself and what adds to it), then by first parameter
    groups.sort(key=lambda g: (g[0] != 1, params.index(g[1][0])))
    out = "".join(_term(c, ps, printer, k == 0) for k, (c, ps) in enumerate(groups))
    if printer is sp.latex:
        out = out.replace("*", " ")
    return out or "0"


def format_symbolic(sa: SymbolicAnalysis) -> str:
    """The text report: counts, checks, formulas, unidentifiable parameters, conditions.

    Parameters
    ----------
    sa : SymbolicAnalysis
        The result.

    Returns
    -------
    str
        Lines for a terminal.
    """
    r = sa.robot
    syms = ", ".join(r.display(s).name for s in r.symbols) or "none"
    src = ", ".join(f"{k} {v}" for k, v in sa.by_source.items())
    frame = FRAMES[sa.convention] if sa.convention == "paper" else "the link frames of the geometry, inertia about " \
        "their origins" + (" (DH frame j)" if "DH" in r.convention else "")
    lines = [f"{r.name}: {r.description}" if r.description else r.name,
             f"geometry: {r.convention}, symbols {syms}; gravity {tuple(float(g) for g in r.gravity)}",
             f"{10 * r.n} standard parameters ({sa.convention}: {frame}), {sa.nullity} nullspace "
             f"directions (DRNG on the symbolic geometry: {src}), {sa.n_base} base parameters"]
    if sa.checks:
        errs = [c["K_error"] for c in sa.checks if c["K_error"] is not None]
        detail = f"K equal to {max(errs):.0e}" if errs else "same nullspace"
        lines.append(f"checked: the certified numerical analysis at {len(sa.checks)} random points of the symbols "
                     f"agrees ({detail})")
    lines += ["", f"base parameters ({sa.convention}):"]
    lines += [f"  {e['name']} = {e['expression']}" for e in expressions(sa)]
    un = sa.unidentifiable
    if un:
        lines += ["", f"unidentifiable (no effect on any measurement): {', '.join(p.name for p in un)}"]
    lines += ["", "these hold for generic values of the symbols; they change where:"]
    lines += [f"  {c}" for c in sa.conditions] or ["  (no condition found: every pivot is a constant and no symbol "
                                                   "or pair of symbols at zero changes the count)"]
    lines.append(f"({sa.seconds:.2f} s)")
    return "\n".join(lines)


def expressions(sa: SymbolicAnalysis, printer=sp.sstr) -> list[dict]:
    """``[{"name", "expression"}]`` with grouped coefficients (:func:`pretty`).

    Parameters
    ----------
    sa : SymbolicAnalysis
        The result.
    printer : callable
        ``sympy.sstr`` or ``sympy.latex``.

    Returns
    -------
    list of dict
        One per base parameter, in parameter order.
    """
    return [{"name": printer(sp.Symbol(k)) if printer is sp.latex else k, "expression": pretty(v, sa.params, printer)}
            for k, v in sa.base.items()]


def symbolic_json(sa: SymbolicAnalysis) -> dict:
    """The result as JSON-ready data (formulas as SymPy strings).

    Parameters
    ----------
    sa : SymbolicAnalysis
        The result.

    Returns
    -------
    dict
        ``model``, ``convention``, ``symbols``, ``n_params``, ``nullity``, ``n_base``,
        ``by_source``, ``base_parameters`` (``name``, ``expression``, ``latex``),
        ``unidentifiable``, ``conditions`` (``condition``, ``reason``, ``effect``), ``checks``,
        ``seconds``.
    """
    tex = expressions(sa, sp.latex)
    return {
        "model": sa.robot.name, "geometry": sa.robot.convention, "convention": sa.convention,
        "symbols": [sa.robot.display(s).name for s in sa.robot.symbols], "n_params": 10 * sa.robot.n,
        "nullity": sa.nullity,
        "n_base": sa.n_base, "by_source": sa.by_source,
        "base_parameters": [{**e, "latex": t["expression"]} for e, t in zip(expressions(sa), tex)],
        "unidentifiable": [p.name for p in sa.unidentifiable],
        "conditions": [{"condition": c.equation(),
                        "reason": c.reason, "effect": c.effect} for c in sa.conditions],
        "checks": sa.checks, "seconds": sa.seconds,
    }


def symbolic_latex(sa: SymbolicAnalysis) -> str:
    r"""A LaTeX ``longtable`` of the base parameters, for a paper.

    Parameters
    ----------
    sa : SymbolicAnalysis
        The result.

    Returns
    -------
    str
        ``\\begin{longtable}{ll} ... \\end{longtable}`` (needs the ``longtable`` package).
    """
    rows = [f"${e['name']}$ & ${e['expression']}$ \\\\" for e in expressions(sa, sp.latex)]
    names = ", ".join(f"${sp.latex(sa.robot.display(s))}$" for s in sa.robot.symbols)
    cap = (f"Base inertial parameters of {sa.robot.name} ({sa.convention} convention; {sa.n_base} of "
           f"{10 * sa.robot.n}), generic values of {names}.")
    return "\n".join([r"\begin{longtable}{ll}", rf"\caption{{{cap}}}\\", r"\hline", r"Base parameter & Expression \\",
                      r"\hline", r"\endhead", *rows, r"\hline", r"\end{longtable}"])


def _matrix_function(name: str, m: sp.Matrix, args: str, doc: str) -> list[str]:
    from sympy.printing.numpy import NumPyPrinter

    pr = NumPyPrinter({"fully_qualified_modules": False})
    body = [f"    m[{r}, {c}] = {pr.doprint(m[r, c])}" for r in range(m.rows) for c in range(m.cols) if m[r, c] != 0]
    return [f"def {name}({args}):", f'    """{doc}"""', f"    m = np.zeros(({m.rows}, {m.cols}))", *body,
            "    return m", "", ""]


def codegen(sa: SymbolicAnalysis) -> str:
    """Python source of the family: ``regrouping(**dims) -> K``, ``base_parameters``, ``base_regressor``.

    ``regrouping`` and ``base_parameters`` (``beta = pi_I + K pi_D`` for a standard parameter
    vector in the result's convention) are generated NumPy code (no SymPy, no baseparams).
    ``base_regressor(q, dq, ddq, **dims)`` (``W_b``, ``tau = W_b @ beta``) evaluates the TP
    regressor with baseparams for the robot at those dimensions; it is written when the robot
    can be loaded again by name or file (``SymbolicRobot.source``).

    Parameters
    ----------
    sa : SymbolicAnalysis
        The result.

    Returns
    -------
    str
        The module's source.
    """
    syms = ", ".join(sa.robot.display(s).name for s in sa.robot.symbols)
    n10 = 10 * sa.robot.n
    lines = [
        f'"""Base parameters of {sa.robot.name} as functions of its dimensions (generated by baseparams).',
        "",
        f"Convention {sa.convention!r}: beta = theta[INDEPENDENT] + K @ theta[DEPENDENT], theta the {n10}",
        "standard parameters in PARAMETERS order. Valid for generic dimensions (see the analysis' conditions).",
        '"""', "", "import numpy as np", "from numpy import sqrt  # noqa: F401", "",
        f"PARAMETERS = {[p.name for p in sa.params]!r}",
        f"BASE_PARAMETERS = {list(sa.base)!r}",
        f"INDEPENDENT = {list(sa.independent)!r}", f"DEPENDENT = {list(sa.dependent)!r}",
        f"SOURCE = {sa.robot.source!r}", "", "",
        *_matrix_function("regrouping", sa.K, syms, f"K ({sa.K.rows}, {sa.K.cols}) at these dimensions."),
        f"def base_parameters(theta, {syms}):",
        f'    """beta ({sa.n_base},) of standard parameters theta ({n10},)."""',
        "    theta = np.asarray(theta, dtype=float)",
        f"    return theta[INDEPENDENT] + regrouping({syms}) @ theta[DEPENDENT]", "", ""]
    if sa.robot.source:
        lines += [
            *_matrix_function("conversion", conversion(sa).applyfunc(to_trig), syms,
                              f"C ({n10}, {n10}): {sa.convention} parameters = C @ paper parameters."),
            f"def base_regressor(q, dq, ddq, {syms}):",
            f'    """W_b (S, m, {sa.n_base}) with tau = W_b @ beta (needs baseparams[symbolic])."""',
            "    from baseparams import regressor",
            "    from baseparams.symbolic import load_symbolic",
            "",
            f"    dims = dict({', '.join(f'{s}={s}' for s in syms.split(', '))})",
            "    y = regressor(load_symbolic(SOURCE).to_robot(dims), q, dq, ddq)",
            f"    return (y @ np.linalg.inv(conversion({syms})))[..., INDEPENDENT]", ""]
    return "\n".join(lines)
