"""A safe reader of the expressions in robot files: an allow-list grammar, never ``eval``.

A DH table is untrusted input. SymPy's ``parse_expr`` and ``sympify`` of a string evaluate
Python, so a table entry such as ``__import__('os').system(...)`` would run. :func:`parse` reads
the text with Python's own parser (:func:`ast.parse`, which builds a tree and runs nothing) and
accepts only:

* numbers (integers and decimals, made exact rationals: ``0.15 -> 3/20``);
* names (identifiers without leading underscores) as real symbols, and ``pi``;
* ``+ - * / **`` and parentheses; unary ``+`` and ``-``;
* ``sin``, ``cos``, ``sqrt`` of one argument.

Anything else — attributes, subscripts, calls of other names, keywords, strings, comparisons,
lambdas — is refused with one line naming it. Size is bounded: at most :data:`MAX_CHARS`
characters, :data:`MAX_DEPTH` levels of nesting, exponents of at most :data:`MAX_EXPONENT` in
absolute value.
"""

from __future__ import annotations

import ast

import sympy as sp

#: longest entry accepted
MAX_CHARS = 200
#: deepest nesting of operations accepted
MAX_DEPTH = 24
#: largest ``|exponent|`` of ``**`` accepted (a number)
MAX_EXPONENT = 16

_FUNCS = {"sin": sp.sin, "cos": sp.cos, "sqrt": sp.sqrt}
_BINOPS = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
           ast.Div: lambda a, b: a / b, ast.Pow: lambda a, b: a ** b}


class ExpressionError(ValueError):
    """An entry outside the grammar (the message says what was found)."""


def parse(text: str) -> sp.Expr:
    """An exact SymPy expression from an entry of a robot file.

    Parameters
    ----------
    text : str
        The entry, e.g. ``0.4318``, ``-pi/2``, ``a3 + d4``, ``sqrt(2)*L``.

    Returns
    -------
    sympy.Expr
        Rational numbers, real symbols, ``pi``, ``sin``/``cos``/``sqrt``.

    Raises
    ------
    ExpressionError
        Anything outside the grammar (the module docstring), too long or too deep.
    """
    if not isinstance(text, str):
        raise ExpressionError(f"expected text, got {type(text).__name__}")
    if len(text) > MAX_CHARS:
        raise ExpressionError(f"longer than {MAX_CHARS} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        raise ExpressionError("not an expression (numbers, names, + - * / **, parentheses, sin/cos/sqrt, pi)") from None
    return _build(tree.body, 0)


def _number(node: ast.Constant) -> sp.Expr:
    v = node.value
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ExpressionError(f"{v!r} is not a number")
    if isinstance(v, float) and not (v == v and abs(v) != float("inf")):
        raise ExpressionError(f"{v!r} is not a finite number")
    return sp.Integer(v) if isinstance(v, int) else sp.Rational(repr(v))


def _build(node: ast.AST, depth: int) -> sp.Expr:
    if depth > MAX_DEPTH:
        raise ExpressionError(f"nested deeper than {MAX_DEPTH} levels")
    if isinstance(node, ast.Constant):
        return _number(node)
    if isinstance(node, ast.Name):
        if node.id.startswith("_"):
            raise ExpressionError(f"name {node.id!r}: names may not start with '_'")
        if node.id in _FUNCS:
            raise ExpressionError(f"{node.id!r} is a function: write {node.id}(x)")
        return sp.pi if node.id == "pi" else sp.Symbol(node.id, real=True)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
        inner = _build(node.operand, depth + 1)
        return -inner if isinstance(node.op, ast.USub) else inner
    if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
        left, right = _build(node.left, depth + 1), _build(node.right, depth + 1)
        if isinstance(node.op, ast.Pow) and (not right.is_number or abs(float(right)) > MAX_EXPONENT):
            raise ExpressionError(f"exponent {right} (a number of at most {MAX_EXPONENT} in absolute value)")
        if isinstance(node.op, ast.Div) and right == 0:
            raise ExpressionError("division by zero")
        return _BINOPS[type(node.op)](left, right)
    if isinstance(node, ast.Call):
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name not in _FUNCS or node.keywords or len(node.args) != 1:
            raise ExpressionError(f"call of {ast.unparse(node.func)!r}: only sin(x), cos(x), sqrt(x)")
        return _FUNCS[name](_build(node.args[0], depth + 1))
    raise ExpressionError(f"{type(node).__name__.lower()} {ast.unparse(node)!r} is not allowed")
