"""A restricted evaluator for the Python expressions of xacro files (``${...}``, ``$(eval ...)``).

A model file is untrusted input. ROS's ``xacro`` evaluates ``${...}`` with Python's ``eval``
behind a filter of ``__`` names, which a file gets around (``python.vars``, then
``object.__getattribute__`` reached through string keys) to run any code; its ``$(eval ...)`` is a
plain ``eval``. Here an expression is parsed with :mod:`ast` and interpreted node by node: nothing
read from a file is compiled into code that runs.

What an expression may do: literals, names (the file's properties and the symbols handed in),
arithmetic, comparisons, ``and``/``or``/``not``, ``x if c else y``, subscripts and slices, list,
tuple, dict and set displays, comprehensions, f-strings; call only the callables handed to the
:class:`Evaluator` (by identity) and a few methods of strings, lists and dicts (``split``,
``strip``, ``keys``, ...); read attributes of namespaces only (``math.pi``, ``xacro.arg``); no name
or attribute starting with ``_``. A :class:`Budget` bounds the work (evaluation steps, seconds),
the characters and elements produced (strings, lists) and the size of integers, checked *before*
an operation that could allocate much (``'a' * 10**12``, ``9**9**9``, ``'%1000000000d' % 1``).
"""

from __future__ import annotations

import ast
import builtins
import operator
import re
import time
from collections.abc import Callable, Iterable

from ..display import counted
from ..files import MODEL_MAX_BYTES

#: evaluation steps (expression nodes, comprehension items, expanded elements) of one file
MAX_STEPS = 2_000_000
#: characters and container elements produced while expanding one file
MAX_CHARS = MODEL_MAX_BYTES
#: wall-clock seconds for expanding one file
MAX_SECONDS = 30.0
#: the largest integer, in bits
MAX_INT_BITS = 10_000
#: the longest ``range`` (elements)
MAX_RANGE = 10**6
#: what one element of a container counts against :data:`MAX_CHARS` (a pointer's bytes)
ITEM_CHARS = 8

_BINOPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
           ast.FloorDiv: operator.floordiv, ast.Mod: operator.mod, ast.Pow: operator.pow,
           ast.LShift: operator.lshift, ast.RShift: operator.rshift, ast.BitAnd: operator.and_,
           ast.BitOr: operator.or_, ast.BitXor: operator.xor}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos, ast.Not: operator.not_, ast.Invert: operator.invert}
_COMPARE = {ast.Eq: operator.eq, ast.NotEq: operator.ne, ast.Lt: operator.lt, ast.LtE: operator.le,
            ast.Gt: operator.gt, ast.GtE: operator.ge, ast.In: lambda a, b: a in b,
            ast.NotIn: lambda a, b: a not in b, ast.Is: operator.is_, ast.IsNot: operator.is_not}
#: the methods an expression may call, by the type of the object
_STR_METHODS = frozenset((
    "lower", "upper", "strip", "lstrip", "rstrip", "split", "rsplit", "splitlines", "startswith", "endswith",
    "find", "rfind", "index", "rindex", "count", "isdigit", "isalpha", "isalnum", "isspace", "isnumeric",
    "capitalize", "title", "swapcase", "casefold", "partition", "rpartition", "join", "replace",
    "removeprefix", "removesuffix"))
_SEQ_METHODS = frozenset(("index", "count"))
_DICT_METHODS = frozenset(("keys", "values", "items", "get"))
#: a ``%`` conversion of a format string: width and precision are checked
_PERCENT = re.compile(r"%(?:\([^)]*\))?[-#0 +]*(\*|\d+)?(?:\.(\*|\d*))?[hlL]?[a-zA-Z%]")
#: a format spec of an f-string: at most three digits of width and precision
_SPEC_OK = re.compile(r"^(?:.?[<>=^])?[-+ ]?#?0?\d{0,3}[,_]?(?:\.\d{1,3})?[a-zA-Z%]?$")


class ExpressionError(ValueError):
    """An expression that is invalid, does what a model file may not, or exceeds its budget."""


class Budget:
    """The work one file's expansion may do: steps, seconds, characters and elements produced.

    Parameters
    ----------
    max_steps : int, optional
        Evaluation steps (default :data:`MAX_STEPS`, read when the budget is made).
    max_chars : int, optional
        Characters of strings and elements of containers produced (default :data:`MAX_CHARS`).
    seconds : float, optional
        Wall-clock seconds from now (default :data:`MAX_SECONDS`).
    """

    def __init__(self, max_steps: int | None = None, max_chars: int | None = None, seconds: float | None = None):
        self.max_steps = MAX_STEPS if max_steps is None else max_steps
        self.max_chars = MAX_CHARS if max_chars is None else max_chars
        self.seconds = MAX_SECONDS if seconds is None else seconds
        self.steps = self.chars = 0
        self.deadline = time.monotonic() + self.seconds

    def step(self, n: int = 1) -> None:
        """Count ``n`` steps; past the step budget or the deadline, raise.

        Parameters
        ----------
        n : int, optional
            Steps taken.

        Raises
        ------
        ExpressionError
            More than ``max_steps`` steps, or past the deadline.
        """
        self.steps += n
        if self.steps > self.max_steps:
            raise ExpressionError(f"the expansion takes more than {self.max_steps} steps (a model file's limit)")
        if time.monotonic() > self.deadline:
            raise ExpressionError(f"the expansion takes more than {self.seconds:g} s (a model file's limit)")

    def room(self, n: int, what: str = "an expression") -> None:
        """Refuse before producing ``n`` more characters or elements beyond the budget.

        Parameters
        ----------
        n : int
            Characters (strings) or elements (containers) about to be produced.
        what : str, optional
            What produces them, for the message.

        Raises
        ------
        ExpressionError
            ``n`` does not fit in what is left of ``max_chars``.
        """
        if self.chars + n > self.max_chars:
            raise ExpressionError(f"{what} would produce more than {self.max_chars} characters or elements "
                                  f"in all (a model file's limit)")

    def charge(self, value):
        """Count what ``value`` holds (a string's characters, a container's elements); check an integer's size.

        Parameters
        ----------
        value : object
            A value just produced.

        Returns
        -------
        object
            ``value``.

        Raises
        ------
        ExpressionError
            Beyond the budget of characters (an integer beyond 64 bits counts its bytes), or an integer of
            more than :data:`MAX_INT_BITS` bits.
        """
        if isinstance(value, int) and not isinstance(value, bool):
            bits = value.bit_length()
            if bits > MAX_INT_BITS:
                raise ExpressionError(f"an integer of more than {MAX_INT_BITS} bits")
            if bits > 64:  # a large integer's bytes count as characters (a million of them: 1.3 GB)
                self.room(bits // 8, "large integers")
                self.chars += bits // 8
        elif isinstance(value, str | bytes | list | tuple | dict | set | frozenset):
            n = len(value) * (1 if isinstance(value, str | bytes) else ITEM_CHARS)
            self.room(n)
            self.chars += n
        return value


class _Method:
    """A method of a string, list or dict named in an expression (called through :meth:`Evaluator._method`)."""

    __slots__ = ("obj", "name")

    def __init__(self, obj, name: str):
        self.obj, self.name = obj, name


def text_size(value, budget: Budget) -> int:
    """An upper bound of ``len(str(value))``, counted without building the text.

    Parameters
    ----------
    value : object
        A value produced by an expression.
    budget : Budget
        Charged one step per element visited.

    Returns
    -------
    int
        The bound, in characters.
    """
    budget.step()
    if isinstance(value, str | bytes):
        return 4 * len(value) + 3  # repr escapes a character in at most 4
    if isinstance(value, int) and not isinstance(value, bool):
        return value.bit_length() // 3 + 3
    if isinstance(value, dict):
        return 2 + sum(text_size(k, budget) + text_size(v, budget) + 4 for k, v in value.items())
    if isinstance(value, list | tuple | set | frozenset):
        return 2 + sum(text_size(v, budget) + 2 for v in value)
    return 64


class Evaluator:
    """Interpret expressions over a lookup of names, calling only the callables it was handed.

    Parameters
    ----------
    callables : iterable of (object, callable)
        Pairs ``(found, called)``: a value ``found`` among the symbols may be called, and a call
        of it calls ``called`` (the same object, or a bounded or confined replacement).
    namespaces : tuple of type, optional
        Types whose attributes are items (``ns.name`` is ``ns['name']``), e.g. xacro's namespaces.
    budget : Budget, optional
        The bounds (a new :class:`Budget` by default).
    """

    def __init__(self, callables: Iterable[tuple[object, Callable]], namespaces: tuple[type, ...] = (),
                 budget: Budget | None = None):
        pairs = list(callables)
        self._keep = pairs  # the ids below stay valid while these objects live
        self._safe = {id(found): called for found, called in pairs}
        self._safe.update({id(called): called for _, called in pairs})
        self.namespaces = namespaces
        self.budget = budget or Budget()

    def evaluate(self, expr: str, lookup: Callable[[str], object]):
        """The value of ``expr``; ``lookup(name)`` gives a name's value (``KeyError`` if undefined).

        Parameters
        ----------
        expr : str
            A Python expression (the text of a ``${...}``).
        lookup : callable
            ``lookup(name) -> value``; raises ``KeyError`` for an undefined name.

        Returns
        -------
        object
            The value (its text, ``str(value)``, is known to fit in the budget).

        Raises
        ------
        ExpressionError
            Invalid syntax, a construct or call a model file may not use, an undefined name, or a
            budget exceeded. Errors of the operations themselves (``ZeroDivisionError``,
            ``TypeError``) propagate.
        """
        try:
            tree = ast.parse(expr.strip(), mode="eval")
        except SyntaxError as exc:
            raise ExpressionError(f"invalid expression {expr.strip()!r} ({exc.msg})") from None
        except (RecursionError, MemoryError):
            raise ExpressionError("expression nested too deeply") from None
        try:
            value = self._eval(tree.body, _Scope(lookup))
            if not isinstance(value, str | int | float | bool) and value is not None:
                self.budget.room(text_size(value, self.budget), "the text of a value")
        except RecursionError:
            raise ExpressionError("expression or value nested too deeply") from None
        return value

    # ---- dispatch -------------------------------------------------------------------------------
    def _eval(self, node: ast.AST, scope: _Scope):
        self.budget.step()
        handler = _HANDLERS.get(type(node))
        if handler is None:
            raise ExpressionError(f"{_what(node)} is not allowed in a model file's expression")
        return handler(self, node, scope)

    def _allowed(self, value, what: str):
        """``value`` itself, or the callable to call for it; refuse any other callable."""
        if callable(value) and not isinstance(value, _Method):
            called = self._safe.get(id(value))
            if called is None:
                raise ExpressionError(f"{what}: a callable that a model file may not use")
            return called
        return value

    def _name(self, node: ast.Name, scope: _Scope):
        if node.id.startswith("_"):
            raise ExpressionError(f"name {node.id!r}: names starting with '_' are not allowed")
        return self._allowed(scope.get(node.id), node.id)

    def _constant(self, node: ast.Constant, scope: _Scope):
        return node.value

    def _attribute(self, node: ast.Attribute, scope: _Scope):
        attr = node.attr
        if attr.startswith("_"):
            raise ExpressionError(f"attribute {attr!r}: names starting with '_' are not allowed")
        obj = self._eval(node.value, scope)
        if isinstance(obj, self.namespaces):
            try:
                return self._allowed(obj[attr], attr)
            except (KeyError, AttributeError, NameError):
                if isinstance(obj, dict) and attr in _DICT_METHODS:
                    return _Method(obj, attr)
                raise ExpressionError(f"no attribute or item {attr!r}") from None
        allowed = (_STR_METHODS if isinstance(obj, str) else _DICT_METHODS if isinstance(obj, dict)
                   else _SEQ_METHODS if isinstance(obj, list | tuple) else frozenset())
        if attr not in allowed:
            raise ExpressionError(f"attribute {attr!r} of a {type(obj).__name__} is not allowed in a model file")
        return _Method(obj, attr)

    def _subscript(self, node: ast.Subscript, scope: _Scope):
        obj = self._eval(node.value, scope)
        key = self._eval(node.slice, scope)
        if not isinstance(obj, str | bytes | list | tuple | dict | range):
            raise ExpressionError(f"subscript of a {type(obj).__name__} is not allowed in a model file")
        try:
            value = obj[key]
        except (KeyError, AttributeError, NameError):
            raise ExpressionError(f"no item {key!r}") from None
        return self.budget.charge(self._allowed(value, repr(key)))

    def _slice(self, node: ast.Slice, scope: _Scope):
        parts = [None if p is None else self._eval(p, scope) for p in (node.lower, node.upper, node.step)]
        return slice(*parts)

    # ---- operators ------------------------------------------------------------------------------
    def _binop(self, node: ast.BinOp, scope: _Scope):
        op = _BINOPS.get(type(node.op))
        if op is None:
            raise ExpressionError(f"operator {type(node.op).__name__} is not allowed in a model file")
        a, b = self._eval(node.left, scope), self._eval(node.right, scope)
        self._check_binop(type(node.op), a, b)
        return self.budget.charge(op(a, b))

    def _check_binop(self, op: type, a, b) -> None:
        """Refuse an operation whose result would be too large, before computing it."""
        seq = str | bytes | list | tuple

        def ints(*v):
            return all(isinstance(x, int) for x in v)

        if op is ast.Mult and (isinstance(a, seq) and ints(b) or isinstance(b, seq) and ints(a)):
            s, n = (a, b) if isinstance(a, seq) else (b, a)
            self.budget.room(len(s) * max(n, 0) * (1 if isinstance(s, str | bytes) else ITEM_CHARS), "a repetition")
        elif op is ast.Add and isinstance(a, seq) and isinstance(b, seq):
            self.budget.room((len(a) + len(b)) * (1 if isinstance(a, str | bytes) else ITEM_CHARS), "a concatenation")
        elif op is ast.Mult and ints(a, b) and a.bit_length() + b.bit_length() > MAX_INT_BITS:
            raise ExpressionError(f"a product of more than {MAX_INT_BITS} bits")
        elif op is ast.Pow and ints(a, b) and abs(a) > 1 and b > 0 and a.bit_length() * b > MAX_INT_BITS + b:
            raise ExpressionError(f"a power of more than {MAX_INT_BITS} bits")
        elif op is ast.LShift and ints(a, b) and a and b > 0 and a.bit_length() + b > MAX_INT_BITS:
            raise ExpressionError(f"a shift to more than {MAX_INT_BITS} bits")
        elif op is ast.Mod and isinstance(a, str | bytes):
            for width, prec in _PERCENT.findall(a if isinstance(a, str) else a.decode("latin-1")):
                if "*" in (width, prec) or len(width) > 3 or len(prec) > 3:
                    raise ExpressionError("a '%' format with a width or precision of more than 3 digits")
            self.budget.room(len(a) + text_size(b, self.budget), "a '%' format")

    def _unaryop(self, node: ast.UnaryOp, scope: _Scope):
        return _UNARY[type(node.op)](self._eval(node.operand, scope))

    def _boolop(self, node: ast.BoolOp, scope: _Scope):
        value = None
        for v in node.values:
            value = self._eval(v, scope)
            if (not value) if isinstance(node.op, ast.And) else value:
                return value
        return value

    def _compare(self, node: ast.Compare, scope: _Scope):
        left = self._eval(node.left, scope)
        for op, right_node in zip(node.ops, node.comparators):
            right = self._eval(right_node, scope)
            if not _COMPARE[type(op)](left, right):
                return False
            left = right
        return True

    def _ifexp(self, node: ast.IfExp, scope: _Scope):
        return self._eval(node.body if self._eval(node.test, scope) else node.orelse, scope)

    # ---- calls ----------------------------------------------------------------------------------
    def _call(self, node: ast.Call, scope: _Scope):
        f = self._eval(node.func, scope)
        if any(isinstance(a, ast.Starred) for a in node.args) or any(k.arg is None for k in node.keywords):
            raise ExpressionError("'*' and '**' arguments are not allowed in a model file")
        args = [self._guard(self._eval(a, scope)) for a in node.args]
        kwargs = {k.arg: self._guard(self._eval(k.value, scope)) for k in node.keywords}
        if isinstance(f, _Method):
            return self._contents_allowed(self.budget.charge(self._method(f, args, kwargs)))  # ns.get('vars')
        return self._invoke(f, args, kwargs)

    def _invoke(self, f, args, kwargs):
        """Call an allowed callable: its text (``str``, ``repr``) is bounded first, its result charged."""
        called = self._safe.get(id(f))
        if called is None:
            raise ExpressionError(f"calling a {type(f).__name__} is not allowed in a model file")
        self.budget.step()
        if called in (str, repr, ascii) and args:
            self.budget.room(text_size(args[0], self.budget), f"{called.__name__}()")
        return self._contents_allowed(self.budget.charge(called(*args, **kwargs)))

    def _contents_allowed(self, value):
        """A call's result with its elements checked: ``dict(ns)`` or ``ns.values()`` must not hand out a callable.

        Containers built by expressions were checked element by element when built; a call can copy
        a namespace's values (xacro's ``python`` namespace holds ``vars`` and ``type``).
        """
        value = self._allowed(value, "a call's result")
        if isinstance(value, dict):
            items = list(value.values())
        elif isinstance(value, list | tuple | set | frozenset | type({}.values()) | type({}.items())):
            items = list(value)
        else:
            return value
        self.budget.step(len(items))
        for v in items:
            for x in (v if isinstance(v, tuple) else (v,)):
                self._allowed(x, "an element of a call's result")
        return value

    def _guard(self, value):
        """A callable passed as an argument (``sorted(v, key=float)``) is called through :meth:`_invoke`."""
        if callable(value) and not isinstance(value, _Method):
            return lambda *a, **k: self._invoke(value, a, k)
        return value

    def _method(self, m: _Method, args: list, kwargs: dict):
        """Call an allowed method, refusing first what would produce too much (``join``, ``replace``)."""
        obj = m.obj
        if isinstance(obj, str) and m.name == "join" and args:
            items = list(args[0])
            self.budget.step(len(items))
            self.budget.room(sum(len(x) if isinstance(x, str) else 0 for x in items) + len(obj) * len(items),
                             "a join")
            args = [items, *args[1:]]
        elif isinstance(obj, str) and m.name == "replace" and len(args) >= 2:
            old, new = args[0], args[1]
            if isinstance(old, str) and isinstance(new, str):
                n = obj.count(old) if old else len(obj) + 1
                self.budget.room(len(obj) + n * len(new), "a replace")
        if isinstance(obj, self.namespaces) and m.name in _DICT_METHODS:
            return getattr(dict, m.name)(obj, *args, **kwargs)
        return getattr(obj, m.name)(*args, **kwargs)

    # ---- displays and comprehensions ------------------------------------------------------------
    def _elements(self, nodes: list[ast.expr], scope: _Scope) -> list:
        if any(isinstance(n, ast.Starred) for n in nodes):
            raise ExpressionError("'*' unpacking is not allowed in a model file")
        return [self._eval(n, scope) for n in nodes]

    def _list(self, node: ast.List, scope: _Scope):
        return self.budget.charge(self._elements(node.elts, scope))

    def _tuple(self, node: ast.Tuple, scope: _Scope):
        return self.budget.charge(tuple(self._elements(node.elts, scope)))

    def _set(self, node: ast.Set, scope: _Scope):
        return self.budget.charge(set(self._elements(node.elts, scope)))

    def _dict(self, node: ast.Dict, scope: _Scope):
        if any(k is None for k in node.keys):
            raise ExpressionError("'**' unpacking is not allowed in a model file")
        return self.budget.charge({self._eval(k, scope): self._eval(v, scope) for k, v in zip(node.keys, node.values)})

    def _scopes(self, generators: list[ast.comprehension], scope: _Scope):
        """Yield the scope of each item of a comprehension (nested generators, filters applied)."""
        gen, rest = generators[0], generators[1:]
        if gen.is_async:
            raise ExpressionError("async comprehensions are not allowed in a model file")
        for item in self._eval(gen.iter, scope):
            self.budget.step()
            inner = scope.child()
            _bind(gen.target, item, inner)
            if all(self._eval(cond, inner) for cond in gen.ifs):
                if rest:
                    yield from self._scopes(rest, inner)
                else:
                    yield inner

    def _comprehension(self, node, scope: _Scope):
        out = []
        for inner in self._scopes(node.generators, scope):
            if isinstance(node, ast.DictComp):
                out.append((self._eval(node.key, inner), self._eval(node.value, inner)))
            else:
                out.append(self._eval(node.elt, inner))
            self.budget.room(ITEM_CHARS, "a comprehension")
            self.budget.chars += ITEM_CHARS
        if isinstance(node, ast.DictComp):
            return dict(out)
        return set(out) if isinstance(node, ast.SetComp) else out

    def _joinedstr(self, node: ast.JoinedStr, scope: _Scope):
        parts = []
        for v in node.values:
            if isinstance(v, ast.Constant):
                parts.append(str(v.value))
                continue
            value = self._eval(v.value, scope)
            spec = "" if v.format_spec is None else self._joinedstr(v.format_spec, scope)
            if not _SPEC_OK.match(spec):
                raise ExpressionError(f"format spec {spec!r}: at most 3 digits of width and precision in a model file")
            self.budget.room(text_size(value, self.budget), "an f-string")
            conv = {-1: None, 115: str, 114: repr, 97: ascii}[v.conversion]
            parts.append(format(conv(value) if conv else value, spec))
        return self.budget.charge("".join(parts))


class _Scope:
    """Names of a comprehension's variables, then the lookup's."""

    __slots__ = ("lookup", "local")

    def __init__(self, lookup: Callable[[str], object], local: dict | None = None):
        self.lookup, self.local = lookup, local or {}

    def get(self, name: str):
        if name in self.local:
            return self.local[name]
        try:
            return self.lookup(name)
        except KeyError:
            raise ExpressionError(f"name {name!r} is not defined") from None

    def child(self) -> _Scope:
        return _Scope(self.lookup, dict(self.local))


def _bind(target: ast.expr, value, scope: _Scope) -> None:
    """Assign a comprehension's item to its target (a name or a tuple of names)."""
    if isinstance(target, ast.Name):
        if target.id.startswith("_"):
            raise ExpressionError(f"name {target.id!r}: names starting with '_' are not allowed")
        scope.local[target.id] = value
    elif isinstance(target, ast.Tuple | ast.List):
        values = list(value)
        if len(values) != len(target.elts):
            raise ExpressionError(f"cannot unpack {counted(len(values), 'value')} into "
                                  f"{counted(len(target.elts), 'name')}")
        for t, v in zip(target.elts, values):
            _bind(t, v, scope)
    else:
        raise ExpressionError(f"{_what(target)} as a comprehension variable is not allowed")


def _what(node: ast.AST) -> str:
    return {"Lambda": "lambda", "NamedExpr": "':='", "Await": "await", "Yield": "yield"}.get(
        type(node).__name__, type(node).__name__)


_HANDLERS = {
    ast.Name: Evaluator._name, ast.Constant: Evaluator._constant, ast.Attribute: Evaluator._attribute,
    ast.Subscript: Evaluator._subscript, ast.Slice: Evaluator._slice, ast.BinOp: Evaluator._binop,
    ast.UnaryOp: Evaluator._unaryop, ast.BoolOp: Evaluator._boolop, ast.Compare: Evaluator._compare,
    ast.IfExp: Evaluator._ifexp, ast.Call: Evaluator._call, ast.List: Evaluator._list, ast.Tuple: Evaluator._tuple,
    ast.Set: Evaluator._set, ast.Dict: Evaluator._dict, ast.ListComp: Evaluator._comprehension,
    ast.SetComp: Evaluator._comprehension, ast.GeneratorExp: Evaluator._comprehension,
    ast.DictComp: Evaluator._comprehension, ast.JoinedStr: Evaluator._joinedstr,
}


def bounded_range(*args) -> range:
    """``range(...)`` of at most :data:`MAX_RANGE` elements.

    Parameters
    ----------
    *args : int
        As for :class:`range`.

    Returns
    -------
    range
        The range.

    Raises
    ------
    ExpressionError
        More than :data:`MAX_RANGE` elements.
    """
    r = range(*args)
    if len(r) > MAX_RANGE:
        raise ExpressionError(f"a range of {len(r)} elements (at most {MAX_RANGE} in a model file)")
    return r


def numeric_sum(iterable, start=0):
    """``sum`` of numbers only (a sum of lists or strings is quadratic).

    Parameters
    ----------
    iterable : iterable of numbers
        The terms.
    start : int or float, optional
        The first term.

    Returns
    -------
    int or float
        The sum.

    Raises
    ------
    ExpressionError
        A ``start`` that is not a number.
    """
    if not isinstance(start, int | float):
        raise ExpressionError("sum() of non-numbers is not allowed in a model file")
    return builtins.sum(iterable, start)
