"""Files baseparams reads back, checked against one declarative schema before any value is used.

Three kinds of file come back in: saved identifications (``identify --save``, read by
``Identification.load`` and ``baseparams predict``: :func:`result`, completed by the model terms'
own fields in :data:`baseparams.ident.saved.RESULT`), the true parameters of a
simulation (``simulate``'s ``OUT.truth.json``, read by ``identify --truth`` and
``compare_truth``: :data:`TRUTH`) and TOML column maps (``--columns``: :data:`COLUMNS`).

Reading (:func:`read_json`, :func:`read_toml`)
    Regular files only (a FIFO, a device, a folder or a symbolic link to ``/dev/zero`` is refused
    before it is opened), at most ``max_bytes`` read; nesting at most :data:`MAX_DEPTH` deep
    (measured on the bytes before parsing); no ``NaN``/``Infinity`` literals, no number beyond
    floating point (``1e400``), no integer of more than :data:`MAX_INT_DIGITS` digits, no key twice
    in one object. Every failure is one line naming the file.

Checking (:func:`check`)
    A schema is a tree of nodes: :class:`Num` (a finite number, never a boolean; bounds),
    :class:`Int`, :class:`Str`, :class:`Bool`, :class:`Enum`, :class:`Opt` (``null`` allowed),
    :class:`Arr` (an array: its items' node, a length or a size symbol, bounds), :class:`Map`
    (free keys, one node for every value), :class:`Obj` (named fields), :class:`Tagged` (one of
    several objects, by a field naming its kind) and :class:`Any` (any JSON value, kept as read).
    A size symbol (``Arr(Num(), "p")``) binds to the first array that names it and every later one
    must match; the caller may bind symbols first (the robot's body count). A names symbol
    (``Arr(Str(), names="joints")``) binds the strings of an array: a ``Map(..., keys="joints")``
    must have exactly those keys, a ``Str(among="joints")`` be one of them.
    A problem is one line ``FILE: WHERE: expected ..., got ...`` with ``WHERE`` the path into the
    document (``estimate.R11[3][5]``).

Unknown keys, and adding a field
    Each :class:`Obj` says what an unknown key means (``extra``): ``"refuse"`` where a value
    changes what the file predicts (the options the model is rebuilt from, the parameter values,
    the robot): a file written by a newer baseparams with a term this one does not know is refused
    naming the key, never used without it; ``"note"`` where nothing is computed from the section
    (the top level, the estimate's statistics): the key is ignored and named in one note;
    ``"keep"`` for free-form descriptive sections. To add a field, add it to the schema below with
    ``Field(node, required=False, default=...)``: files written before it lack it and read with the
    default (the format's version stays; a change of meaning of an existing field bumps it).
"""

from __future__ import annotations

import json
import math
import numbers
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from .display import counted
from .enums import Convention, values
from .errors import BaseparamsError
from .files import read_input_bytes

#: the deepest nesting of arrays and objects read (a saved identification nests 4 deep)
MAX_DEPTH = 32
#: the most digits of an integer read (counts and seeds: 2**64 has 20)
MAX_INT_DIGITS = 20
#: the longest string read from a document (names, notes, expressions), in characters
MAX_STR = 100_000
#: the most items of one array or object (a saved identification's largest has p <= a few thousand)
MAX_ITEMS = 1_000_000
#: size bounds of each file kind [bytes]: a saved identification, a truth file, a column map
RESULT_MAX_BYTES = 32 * 2**20
TRUTH_MAX_BYTES = 8 * 2**20
COLUMNS_MAX_BYTES = 2**20


class _Problem(Exception):
    """A value that does not fit its node: ``where`` (the path) and ``what`` (expected, got)."""

    def __init__(self, where: str, what: str):
        super().__init__(where, what)
        self.where, self.what = where, what


def _show(v) -> str:
    """A short description of a JSON value for a message."""
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (dict, Mapping)):
        return f"an object of {len(v)} key{'' if len(v) == 1 else 's'}"
    if isinstance(v, (list, tuple)):
        return f"an array of {len(v)} item{'' if len(v) == 1 else 's'}"
    if isinstance(v, str):
        return repr(v if len(v) <= 40 else v[:37] + "...")
    if isinstance(v, int) and abs(v) >= 10**12:
        return f"an integer of {len(str(abs(v)))} digits"
    text = " ".join(repr(v).split())  # one line (an array's repr spans lines)
    return text if len(text) <= 60 else text[:57] + "..."


@dataclass
class _Context:
    """The state of one check: the source (for messages), the size symbols, the notes."""

    source: str
    sizes: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    bound_at: dict = field(default_factory=dict)
    names: dict = field(default_factory=dict)

    def among(self, symbol: str, where: str) -> list:
        # the names bound to ``symbol`` (an array with ``names=symbol`` checked before)
        if symbol not in self.names:
            raise _Problem(where, f"cannot be checked: {symbol} not given before it")
        return self.names[symbol]

    def size(self, symbol: str, n: int, where: str, what: str = "items") -> None:
        # bind ``symbol`` to ``n``, or check ``n`` against its binding
        bound = self.sizes.get(symbol)
        if bound is None:
            self.sizes[symbol] = n
            self.bound_at[symbol] = where
        elif bound != n:
            at = self.bound_at.get(symbol)
            raise _Problem(where, f"expected {bound}{' ' + what if what else ''} (as {at or 'given'}), got {n}")


def _listed(names, most: int = 8) -> str:
    """Names for a message: the first ``most``, then how many more."""
    shown = ", ".join(map(str, names[:most]))
    return shown + (f" and {len(names) - most} more" if len(names) > most else "")


def _node_repr(node) -> str:
    return f"<{type(node).__name__}: {node._describe()}>"


class Node:
    """A node of a schema: :meth:`check` returns the value (numbers as floats) or raises."""

    def _check(self, v, where: str, ctx: _Context):  # pragma: no cover - abstract
        raise NotImplementedError

    def _describe(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError


def _number(v, where: str, expected: str = "a finite number") -> float:
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
        raise _Problem(where, f"expected {expected}, got {_show(v)}")
    try:
        x = float(v)
    except OverflowError:
        raise _Problem(where, f"expected {expected} (within floating point), got {_show(v)}") from None
    if not math.isfinite(x):
        raise _Problem(where, f"expected {expected}, got {x}")
    return x


@dataclass(frozen=True)
class Num(Node):
    """A finite number (JSON integer or float, never a boolean) within ``[lo, hi]``.

    Parameters
    ----------
    lo, hi : float
        Bounds (default: none).
    lo_open : bool
        Strictly above ``lo``.
    nonzero : bool
        Not 0.
    null : bool
        ``null`` is allowed too, read as NaN (a statistic that was not finite when written).
    """

    __repr__ = _node_repr

    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    nonzero: bool = False
    null: bool = False

    def _describe(self) -> str:
        if self.lo > -math.inf and self.hi < math.inf:
            bounds = f" in {'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}]"
        elif self.lo > -math.inf:
            bounds = f" {'>' if self.lo_open else '>='} {self.lo:g}"
        else:
            bounds = f" <= {self.hi:g}" if self.hi < math.inf else ""
        return f"a finite {'nonzero ' if self.nonzero else ''}number{bounds}" + (" or null" if self.null else "")

    def _check(self, v, where: str, ctx: _Context) -> float:
        if v is None and self.null:
            return math.nan
        x = _number(v, where, self._describe())
        if x < self.lo or (self.lo_open and x == self.lo) or x > self.hi or (self.nonzero and x == 0):
            raise _Problem(where, f"expected {self._describe()}, got {_show(v)}")
        return x


@dataclass(frozen=True)
class Int(Node):
    """An integer (not a boolean, not a float) within ``[lo, hi]``.

    Parameters
    ----------
    lo, hi : int
        Bounds.
    bind : str, optional
        A size symbol it equals (binds it when unbound).
    """

    __repr__ = _node_repr

    lo: int = -(2**63)
    hi: int = 2**63 - 1
    bind: str | None = None

    def _describe(self) -> str:
        return f"an integer in [{self.lo}, {self.hi}]"

    def _check(self, v, where: str, ctx: _Context) -> int:
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Integral):
            raise _Problem(where, f"expected an integer, got {_show(v)}")
        if not self.lo <= v <= self.hi:
            raise _Problem(where, f"expected {self._describe()}, got {_show(v)}")
        if self.bind is not None:
            ctx.size(self.bind, v, where, "")
        return int(v)


@dataclass(frozen=True)
class Str(Node):
    """A string of at most ``max_len`` characters.

    Parameters
    ----------
    max_len : int
        The most characters.
    pattern : str, optional
        A regular expression it matches whole.
    nonempty : bool
        Not ``""``.
    text : str, optional
        How messages name what is expected (``a column name``).
    among : str, optional
        A names symbol (:class:`Arr` ``names=``): the string must be one of those names.
    """

    __repr__ = _node_repr

    max_len: int = MAX_STR
    pattern: str | None = None
    nonempty: bool = False
    text: str | None = None
    among: str | None = None

    def _describe(self) -> str:
        return self.text or ("a non-empty string" if self.nonempty else "a string")

    def _check(self, v, where: str, ctx: _Context) -> str:
        if not isinstance(v, str):
            raise _Problem(where, f"expected {self._describe()}, got {_show(v)}")
        if len(v) > self.max_len:
            raise _Problem(where, f"expected a string of at most {self.max_len} characters, got {len(v)}")
        if self.nonempty and not v:
            raise _Problem(where, f"expected {self._describe()}, got ''")
        if self.pattern is not None and not re.fullmatch(self.pattern, v):
            raise _Problem(where, f"expected a string of the form {self.pattern}, got {_show(v)}")
        if self.among is not None and v not in (names := ctx.among(self.among, where)):
            raise _Problem(where, f"expected one of {_listed(names)} ({ctx.bound_at.get(self.among)}), got {_show(v)}")
        return v


@dataclass(frozen=True)
class Bool(Node):
    """``true`` or ``false`` (not 0 or 1)."""

    __repr__ = _node_repr

    def _describe(self) -> str:
        return "true or false"

    def _check(self, v, where: str, ctx: _Context) -> bool:
        if not isinstance(v, bool):
            raise _Problem(where, f"expected true or false, got {_show(v)}")
        return v


@dataclass(frozen=True)
class Enum(Node):
    """One of ``choices`` (of the same type: ``true`` is not 1).

    Parameters
    ----------
    choices : tuple
        The values allowed.
    text : str, optional
        How messages name them (``+1 or -1``).
    """

    __repr__ = _node_repr

    choices: tuple
    text: str | None = None

    def _describe(self) -> str:
        return self.text or "one of " + ", ".join(map(_show, self.choices))

    def _check(self, v, where: str, ctx: _Context):
        for c in self.choices:
            if type(c) is type(v) and c == v:
                return v
        raise _Problem(where, f"expected {self._describe()}, got {_show(v)}")


@dataclass(frozen=True)
class Opt(Node):
    """``null`` (read as ``None``) or the wrapped node.

    Parameters
    ----------
    node : Node
        What a value that is not ``null`` must be.
    """

    __repr__ = _node_repr

    node: Node

    def _describe(self) -> str:
        return f"{self.node._describe()} or null"

    def _check(self, v, where: str, ctx: _Context):
        return None if v is None else self.node._check(v, where, ctx)


@dataclass(frozen=True)
class Any(Node):
    """Any JSON value, kept as read (its size and depth are bounded by the reader)."""

    __repr__ = _node_repr

    def _describe(self) -> str:
        return "any value"

    def _check(self, v, where: str, ctx: _Context):
        return v


#: Python types of a JSON number
_NUMBER_TYPES = (int, float)


@dataclass(frozen=True)
class Arr(Node):
    """An array.

    Parameters
    ----------
    item : Node
        Every item's node.
    length : int, str or None
        The number of items, a size symbol (bound by the first array naming it), or free.
    min_len, max_len : int
        Bounds on the number of items.
    unique : str, optional
        A key of the items (objects) whose values must not repeat (parameter names, term names).
    names : str, optional
        A names symbol this array of strings binds (the robot's measured joints): a :class:`Map`
        with ``keys=`` the symbol, or a :class:`Str` with ``among=`` it, checked later against it.
    """

    __repr__ = _node_repr

    item: Node
    length: int | str | None = None
    min_len: int = 0
    max_len: int = MAX_ITEMS
    unique: str | None = None
    names: str | None = None

    def _describe(self) -> str:
        return f"an array (each item {self.item._describe()})"

    def _check(self, v, where: str, ctx: _Context) -> list:
        if not isinstance(v, list):
            raise _Problem(where, f"expected {self._describe()}, got {_show(v)}")
        n = len(v)
        if isinstance(self.length, int) and n != self.length:
            raise _Problem(where, f"expected {self.length} items, got {n}")
        if isinstance(self.length, str):
            ctx.size(self.length, n, where)
        if n < self.min_len or n > self.max_len:
            raise _Problem(where, f"expected {self.min_len} to {self.max_len} items, got {n}")
        fast = self._numbers(v, where)
        if fast is not None:
            return fast
        out = [self.item._check(x, f"{where}[{k}]", ctx) for k, x in enumerate(v)]
        if self.names is not None:
            ctx.names[self.names] = list(out)
            ctx.bound_at[self.names] = where
        if self.unique is not None:
            seen: dict = {}
            for k, x in enumerate(out):
                key = x.get(self.unique) if isinstance(x, dict) else None
                if key in seen:
                    raise _Problem(f"{where}[{k}].{self.unique}", f"{_show(key)} appears twice (items {seen[key]} "
                                                                  f"and {k})")
                seen[key] = k
        return out

    def _numbers(self, v: list, where: str):
        """An array of plain numbers checked at once (a 300 x 300 factor), else None (item by item)."""
        node = self.item
        if type(node) is not Num or not v:
            return None
        nullable = node.null
        if not all(type(x) in _NUMBER_TYPES or (nullable and x is None) for x in v):
            return None
        try:
            a = np.array([np.nan if x is None else x for x in v], dtype=float)
        except OverflowError:
            return None
        bad = ~np.isfinite(a)
        if nullable:
            bad &= ~np.array([x is None for x in v])
        lo_bad = (a <= node.lo) if node.lo_open else (a < node.lo)
        bad |= lo_bad | (a > node.hi) | ((a == 0) if node.nonzero else False)
        if bad.any():
            return None  # item by item: names the first one
        return a.tolist()


@dataclass(frozen=True)
class Map(Node):
    """An object with free keys (joint names, reasons), every value of one node.

    Parameters
    ----------
    value : Node
        Every value's node.
    key : Node
        Every key's node.
    max_len : int
        The most keys.
    keys : str, optional
        A names symbol (:class:`Arr` ``names=``): the keys must be exactly those names (one value
        per measured joint: a key the robot lacks, or a joint left out, is refused).
    """

    __repr__ = _node_repr

    value: Node
    key: Node = Str(max_len=1000)
    max_len: int = MAX_ITEMS
    keys: str | None = None

    def _describe(self) -> str:
        return f"an object of {self.value._describe()}s"

    def _check(self, v, where: str, ctx: _Context) -> dict:
        if not isinstance(v, dict):
            raise _Problem(where, f"expected {self._describe()}, got {_show(v)}")
        if len(v) > self.max_len:
            raise _Problem(where, f"expected at most {self.max_len} keys, got {len(v)}")
        if self.keys is not None:
            names = ctx.among(self.keys, where)
            at = ctx.bound_at.get(self.keys)
            if stray := [k for k in v if k not in names]:
                raise _Problem(where, f"key {_show(stray[0])} is not one of {at} ({_listed(names)})")
            if missing := [k for k in names if k not in v]:
                raise _Problem(where, f"missing {_show(missing[0])}: expected one value for each of {at} "
                                      f"({_listed(names)})")
        return {self.key._check(k, f"{where}", ctx): self.value._check(x, f"{where}.{k}", ctx) for k, x in v.items()}


@dataclass(frozen=True)
class Tagged(Node):
    """An object whose ``tag`` field says which of several schemas it follows (a model term by name).

    Parameters
    ----------
    tag : str
        The field naming the kind (``name``).
    kinds : mapping of str to Obj
        Each kind's schema (it checks ``tag`` too).
    """

    __repr__ = _node_repr

    tag: str
    kinds: Mapping[str, Node]

    def _describe(self) -> str:
        return f"an object with {self.tag} one of {', '.join(self.kinds)}"

    def _check(self, v, where: str, ctx: _Context) -> dict:
        if not isinstance(v, dict):
            raise _Problem(where, f"expected an object ({{...}}), got {_show(v)}")
        kind = v.get(self.tag)
        here = f"{where}.{self.tag}" if where else self.tag
        if self.tag not in v:
            raise _Problem(here, "missing")
        if not isinstance(kind, str) or kind not in self.kinds:
            raise _Problem(here, f"expected one of {', '.join(map(repr, self.kinds))}, got {_show(kind)}")
        return self.kinds[kind]._check(v, where, ctx)


#: a field's default when absent: "required" (refused when missing)
REQUIRED = object()
#: a field's default meaning "left out when absent": the reader gives its own default
#: (a saved identification's options: :class:`baseparams.ident.options.IdentOptions`' defaults)
ABSENT = object()


@dataclass(frozen=True)
class Field:
    """A named field of an :class:`Obj`.

    Parameters
    ----------
    node : Node
        Its value's node.
    default : object
        Its value when absent (:data:`REQUIRED`: refused when absent).
    """

    __repr__ = _node_repr

    node: Node
    default: object = REQUIRED

    def _describe(self) -> str:
        shown = self.default is REQUIRED or self.default is ABSENT
        return self.node._describe() + ("" if shown else f" (default {self.default!r:.40})")


@dataclass(frozen=True)
class Obj(Node):
    """An object with named fields.

    Parameters
    ----------
    fields : mapping of str to Field or Node
        The fields (a bare node: required).
    extra : {"refuse", "note", "keep"}
        What an unknown key means (module doc).
    rule : callable, optional
        A check across fields, ``checked object -> message or None``.
    hint : str
        Added to the message refusing an unknown key.
    """

    __repr__ = _node_repr

    fields: Mapping[str, Field | Node]
    extra: str = "refuse"
    rule: Callable | None = None
    hint: str = ""

    def _describe(self) -> str:
        return "an object"

    def _check(self, v, where: str, ctx: _Context) -> dict:
        if not isinstance(v, dict):
            raise _Problem(where, f"expected an object ({{...}}), got {_show(v)}")
        out = {}
        for name, spec in self.fields.items():
            f = spec if isinstance(spec, Field) else Field(spec)
            here = f"{where}.{name}" if where else name
            if name not in v:
                if f.default is REQUIRED:
                    raise _Problem(here, "missing")
                if f.default is not ABSENT:
                    out[name] = f.default
                continue
            out[name] = f.node._check(v[name], here, ctx)
        unknown = [k for k in v if k not in self.fields]
        if unknown:
            names = ", ".join(f"{where}.{k}" if where else str(k) for k in unknown[:6])
            if self.extra == "refuse":
                raise _Problem(where, f"unknown key {unknown[0]!r}; expected one of {', '.join(self.fields)}"
                                      + self.hint)
            if self.extra == "note":
                ctx.notes.append(f"{ctx.source}: keys not read: {names}"
                                 + (f" and {len(unknown) - 6} more" if len(unknown) > 6 else "")
                                 + " (written by a newer baseparams?)")
            for k in unknown:
                out[k] = v[k]
        if self.rule is not None and (msg := self.rule(out)):
            raise _Problem(where, msg)
        return out


def check(doc, schema: Node, source: str, sizes: dict | None = None, error=BaseparamsError) -> tuple[object, list]:
    """A document checked against a schema: ``(the checked document, notes)``.

    Parameters
    ----------
    doc : object
        The parsed document (or a dict given in Python).
    schema : Node
        Its schema (:func:`result`, :data:`TRUTH`, :data:`COLUMNS`).
    source : str
        The file (or the argument's name), for messages.
    sizes : dict, optional
        Size symbols bound before the check (``{"n": robot.n}``); bound ones are added.
    error : type
        The exception class raised.

    Returns
    -------
    checked : object
        The document, numbers as Python floats, absent optional fields at their defaults, unknown
        keys of ``keep``/``note`` objects as read.
    notes : list of str
        One line per object with keys not read (``extra="note"``).

    Raises
    ------
    BaseparamsError
        ``SOURCE: WHERE: expected ..., got ...``, one line.
    """
    ctx = _Context(source, sizes if sizes is not None else {})
    try:
        out = schema._check(doc, "", ctx)
    except _Problem as p:
        raise error(f"{source}: {p.where}: {p.what}" if p.where else f"{source}: {p.what}") from None
    except RecursionError:
        raise error(f"{source}: nested deeper than {MAX_DEPTH} levels") from None
    return out, ctx.notes


# ---------------------------------------------------------------- reading, bounded
_JSON_STRINGS = re.compile(rb'"(?:[^"\\]|\\.)*"')
_TOML_STRINGS = re.compile(rb'"""[\s\S]*?"""|\'\'\'[\s\S]*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*')


def nesting_depth(data: bytes, strings: re.Pattern = _JSON_STRINGS) -> int:
    """The deepest nesting of ``[``/``{`` in a document, strings (and comments) left out.

    Parameters
    ----------
    data : bytes
        The document.
    strings : re.Pattern
        What to blank out first (JSON strings; TOML strings and comments).

    Returns
    -------
    int
        The largest number of open brackets at any point (0 for a scalar).
    """
    bare = strings.sub(b"''", data)
    a = np.frombuffer(bare, dtype=np.uint8)
    idx = np.flatnonzero((a == 91) | (a == 123) | (a == 93) | (a == 125))
    if not len(idx):
        return 0
    step = np.where((a[idx] == 91) | (a[idx] == 123), 1, -1).astype(np.int32)
    return int(np.cumsum(step, dtype=np.int32).max())


def _decode(data: bytes, source: str, what: str, error) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(f"{source}: not {what} (not UTF-8 text: byte {exc.start})") from None


class _Refused(ValueError):
    """A literal the JSON reader refuses (NaN, Infinity, 1e400, a 5 000-digit integer)."""


def _json_float(s: str) -> float:
    x = float(s)
    if not math.isfinite(x):
        raise _Refused(f"the number {s[:40]} is beyond floating point")
    return x


def _json_int(s: str) -> int:
    if len(s.lstrip("-")) > MAX_INT_DIGITS:
        raise _Refused(f"an integer of {len(s.lstrip('-'))} digits (at most {MAX_INT_DIGITS})")
    return int(s)


def _json_constant(s: str):
    raise _Refused(f"{s} is not a number JSON allows (write null)")


def _json_object(pairs: list) -> dict:
    # an object whose keys are unique: JSON readers disagree on which of two values counts
    out = dict(pairs)
    if len(out) < len(pairs):
        seen: set = set()
        twice = next(k for k, _ in pairs if k in seen or seen.add(k))
        raise _Refused(f"the key {_show(twice)} appears twice in one object (which value counts is not defined)")
    return out


def parse_json(data: bytes, source: str, what: str, error=BaseparamsError):
    """A JSON document from bytes, bounded (module doc): no NaN/Infinity, no overflow, no huge integers.

    Parameters
    ----------
    data : bytes
        The document.
    source : str
        The file, for messages.
    what : str
        What the file should be (``a saved identification``), for messages.
    error : type
        The exception class raised.

    Returns
    -------
    object
        The parsed document.

    Raises
    ------
    BaseparamsError
        One line: not UTF-8, not JSON, nested too deep, a refused literal.
    """
    depth = nesting_depth(data)
    if depth > MAX_DEPTH:
        raise error(f"{source}: not {what}: nested {depth} levels deep (at most {MAX_DEPTH})")
    text = _decode(data, source, what, error)
    try:
        return json.loads(text, parse_float=_json_float, parse_int=_json_int, parse_constant=_json_constant,
                          object_pairs_hook=_json_object)
    except _Refused as exc:
        raise error(f"{source}: not {what}: {exc}") from None
    except (json.JSONDecodeError, RecursionError, ValueError) as exc:
        raise error(f"{source}: not {what} (cannot read JSON: {str(exc).splitlines()[0][:200]})") from None


def read_json(path, what: str, max_bytes: int, error=BaseparamsError):
    """A JSON file: a regular file of at most ``max_bytes``, parsed by :func:`parse_json`.

    Parameters
    ----------
    path : str or path
        The file.
    what : str
        What it should be, for messages.
    max_bytes : int
        The largest size read.
    error : type
        The exception class raised.

    Returns
    -------
    object
        The parsed document (check it with :func:`check`).

    Raises
    ------
    BaseparamsError
        Not a regular file, too large, unreadable, not JSON (one line naming the file).
    """
    data = read_input_bytes(path, max_bytes, error=error)
    return parse_json(data, str(path), what, error)


def read_toml(path, what: str, max_bytes: int = COLUMNS_MAX_BYTES, error=BaseparamsError) -> dict:
    """A TOML file: a regular file of at most ``max_bytes``, nesting and integers bounded.

    Parameters
    ----------
    path : str or path
        The file.
    what : str
        What it should be (``a valid TOML mapping``), for messages.
    max_bytes : int
        The largest size read.
    error : type
        The exception class raised.

    Returns
    -------
    dict
        The parsed document.

    Raises
    ------
    BaseparamsError
        Not a regular file, too large, not UTF-8, nested too deep, not TOML.
    """
    import tomllib

    data = read_input_bytes(path, max_bytes, error=error)
    depth = nesting_depth(data, _TOML_STRINGS)
    if depth > MAX_DEPTH:
        raise error(f"{path}: not {what}: nested {depth} levels deep (at most {MAX_DEPTH})")
    text = _decode(data, str(path), what, error)
    try:
        return tomllib.loads(text, parse_float=_json_float)
    except (tomllib.TOMLDecodeError, _Refused, RecursionError, ValueError) as exc:
        raise error(f"{path}: not {what} ({str(exc).splitlines()[0][:200]})") from None


# ---------------------------------------------------------------- the schemas
_FINITE = Num()
#: the largest model parameter value read (a robot file's bounds: 1e9 kg x (1e6 m)^2 = 1e21)
MAX_VALUE = 1e24
_VALUE = Num(lo=-MAX_VALUE, hi=MAX_VALUE)
#: why a saved identification's unknown key is refused where values are computed from
_NEWER = " (written by a newer baseparams, or edited? it would predict without it)"
#: a root mean square as the reports keep it (null where it was not finite)
_RMS = Opt(Num(lo=0.0))


def _matrix(symbol: str, item: Node = _FINITE) -> Arr:
    return Arr(Arr(item, symbol), symbol)


def _coupling_rule(c: dict) -> str | None:
    if len(c["joints"]) != len(c["weights"]):
        return f"{counted(len(c['joints']), 'joint')} but {counted(len(c['weights']), 'weight')} (one weight per joint)"
    return None


#: the options a saved identification's model is rebuilt from, and its data were prepared with
#: (:meth:`baseparams.ident.options.IdentOptions.to_json`, plus the measured ``rows``); an option an older file
#: does not hold is left out (:data:`ABSENT`), and takes its default when read
OPTIONS = Obj({
    "method": Enum(("auto", "ols", "wls", "physical")),
    "convention": Enum(tuple(values(Convention))),
    "rows": Str(max_len=100_000, nonempty=True),
    "rotor": Bool(),
    "friction": Arr(Enum(("viscous", "coulomb", "offset")), max_len=3),
    "coulomb_width": Opt(Num(lo=0.0, lo_open=True)),
    "couplings": Arr(Obj({"name": Str(max_len=200, nonempty=True),
                          "joints": Arr(Str(max_len=1000, nonempty=True), min_len=1, max_len=1000),
                          "weights": Arr(Num(nonzero=True), min_len=1, max_len=1000)}, rule=_coupling_rule),
                     max_len=1000),
    "cutoff": Num(lo=1e-3, hi=1e6),
    "decimate": Int(lo=1, hi=10**9),
    "min_speed": Any(),  # a number, one per joint, or null: checked by IdentOptions
    "literal": Field(Bool(), ABSENT),
    "terms": Field(Str(max_len=200), ABSENT),
    "holdout": Field(Opt(Num(lo=0.0, lo_open=True)), ABSENT),
    "prior_weight": Field(Opt(Num(lo=0.0)), ABSENT),
    "covariance": Field(Enum(("hac", "white")), ABSENT),
    "score_cutoff": Field(Opt(Num(lo=0.0, lo_open=True)), ABSENT),
    "allow_units": Field(Bool(), ABSENT),
    "analysis_samples": Field(Opt(Int(lo=1)), ABSENT),
    "seed": Field(Int(lo=0), ABSENT),
    "memory_mb": Field(Num(lo=0.0, lo_open=True), ABSENT),
    "effort": Field(Enum(("auto", "torque", "current")), ABSENT),
    "gain_anchor": Field(Opt(Str(max_len=1000)), ABSENT),
}, extra="refuse", hint=_NEWER)

#: the least-squares estimate's statistics (the triangular factor, the covariance)
ESTIMATE = Obj({
    "method": Str(max_len=100),
    "theta": Arr(Num(null=True), "p"),
    "std": Arr(Num(lo=0.0, null=True), "p"),
    "weights": Arr(Num(null=True), "m"),
    "rms": Arr(Num(lo=0.0, null=True), "m"),
    "rms_total": Num(lo=0.0, null=True),
    "condition_number": Num(lo=0.0, null=True),
    "samples": Int(lo=0),
    "R11": _matrix("p"),
    "r12": Arr(_FINITE, "p"),
    "cov": Opt(_matrix("p", Num(null=True))),
    "covariance": Opt(Str()),
}, extra="note")

#: the physically consistent fit (``method physical``)
PHYSICAL = Obj({
    "pi": Arr(_FINITE, "npar"), "delta": Arr(_FINITE), "theta": Arr(_FINITE, "p"),
    "min_eigenvalues": Arr(Num(null=True), "n"), "relative_min_eigenvalues": Arr(Num(null=True), "n"),
    "feasible": Bool(), "masses": Arr(Num(null=True), "n"), "objective": Num(null=True),
    "fit_residual": Num(null=True), "fit_scale": Num(null=True), "prior_divergence": Arr(Num(null=True), "n"),
    "solver_status": Str(max_len=1000),
    "seconds": Num(lo=0.0, null=True), "notes": Field(Arr(Str()), []),
}, extra="refuse", hint=_NEWER)

#: held-out scores (:func:`baseparams.ident.validation_scores`)
VALIDATION = Obj({
    "rms": Map(_RMS), "rms_total": _RMS, "samples": Int(lo=0),
    "t_start": Opt(Num()), "t_end": Opt(Num()), "source": Str(), "measure": Str(),
    "score_cutoff": Field(Opt(Num(lo=0.0)), None), "rms_lowpassed": Field(Opt(Map(_RMS)), None),
    "rms_lowpassed_total": Field(_RMS, None),
}, extra="keep")


def _counts_rule(s: dict) -> str | None:
    if s["used"] > s["read"] * 1000:  # decimation and filtering only remove samples (a fleet pools logs)
        return f"used {s['used']} samples of {s['read']} read"
    return None


def _motors_rule(c: dict) -> str | None:
    m = c["motors"]
    if len(c["matrix"]) != len(m) or any(len(row) != len(m) for row in c["matrix"]):
        return f"matrix must be {len(m)} x {len(m)} (one row per joint, one column per motor)"
    missing = [k for k in ("gains", "std") if set(c[k]) != set(m)]
    return f"{', '.join(missing)} must name every motor {m}" if missing else None


#: a result identified from motor currents (:class:`baseparams.ident.fromcurrents.CurrentGains`)
CURRENTS = Obj({
    "motors": Arr(Str(max_len=1000, nonempty=True), "motors", min_len=1, max_len=100_000),
    "matrix": _matrix("motors"),
    "gains": Map(Num(lo=-1e12, hi=1e12, nonzero=True, null=True)),
    "std": Map(Num(lo=0.0, null=True)),
    "anchor": Str(max_len=2000),
    "scale_std": Num(lo=0.0, null=True),
    "sigma": Field(Opt(Map(Num(lo=0.0, null=True))), None),
    "undetermined": Field(Arr(Str(max_len=1000)), []),
    "groups": Field(Arr(Any()), []),
    "rotor_split": Field(Map(_VALUE), {}),
    "scale_note": Field(Str(), ""),
}, extra="refuse", hint=_NEWER, rule=_motors_rule)

def result(term: Node) -> Obj:
    """The schema of a saved identification (:meth:`baseparams.ident.Identification.save`, version 1).

    Size symbols: ``p`` model parameters, ``m`` measured joints, ``n`` bodies, ``npar`` = 10 n;
    names symbol ``joints``: the measured joints (``robot.joints``), which every joint-keyed value
    of a model term must name exactly.

    Parameters
    ----------
    term : Node
        One kept model term's node: each term declares its own fields
        (:func:`baseparams.ident.terms.registry.term_schema`; this floor does not know the terms).

    Returns
    -------
    Obj
        The schema; ``terms`` is an array of ``term`` nodes, each term at most once.
    """
    return Obj({
        "format": Str(max_len=200),
        "version": Int(lo=0, hi=10**6),
        "baseparams": Field(Str(max_len=200), None),
        "robot": Obj({"name": Str(max_len=10_000), "fingerprint": Str(pattern=r"sha256:[0-9a-f]{64}"),
                      "bodies": Int(lo=0, bind="n"), "dof": Int(lo=0, bind="dof"),
                      "parameters": Int(lo=0, bind="npar"),
                      "joints": Arr(Str(max_len=1000), "m", names="joints")},
                     extra="refuse", hint=_NEWER),
        "options": OPTIONS,
        "parameters": Obj({"names": Arr(Str(max_len=1000, nonempty=True), "p", min_len=1),
                           "values": Arr(_VALUE, "p"), "std": Arr(Num(lo=0.0, null=True), "p")},
                          extra="refuse", hint=_NEWER),
        "base_parameters": Field(Arr(Any()), []), "drives": Field(Arr(Any()), []),
        "couplings": Field(Arr(Any()), []),
        "estimate": ESTIMATE,
        "physical": Opt(PHYSICAL),
        "samples": Obj({"read": Int(lo=0), "used": Int(lo=0), "removed": Field(Map(Int(lo=0)), {})},
                       extra="keep", rule=_counts_rule),
        "train": Obj({"rms": Map(_RMS), "rms_total": _RMS}, extra="keep"),
        "validation": Opt(VALIDATION),
        "notes": Field(Arr(Str()), []),
        "terms": Field(Arr(term, max_len=16, unique="name"), []),
        "term_choices": Field(Arr(Obj({"name": Str(max_len=100), "kept": Bool(), "why": Str(max_len=10_000),
                                       "cv_rms": Opt(Num(lo=0.0))}, extra="keep"), max_len=16,
                                   unique="name"), []),
        "motion": Field(Opt(Any()), None),
        "currents": Field(Opt(CURRENTS), None),
    }, extra="note")


#: the true parameters of a simulation (``simulate``'s ``OUT.truth.json``)
TRUTH = Obj({
    "parameters": Arr(Obj({"name": Str(max_len=1000, nonempty=True), "value": _VALUE}, extra="keep"),
                      min_len=1, unique="name"),
    "model": Field(Opt(Str(max_len=10_000)), None), "convention": Field(Opt(Str(max_len=100)), None),
    "noise": Field(Opt(Num(lo=0.0)), None), "amplitude": Field(Opt(Num()), None), "drives": Field(Any(), None),
}, extra="keep")


#: one ``[joints.<name>]`` table of a column map (:mod:`baseparams.io.logs`)
COLUMN_JOINT = Obj({
    **{k: Field(Str(max_len=10_000, nonempty=True, text="a column name"), None) for k in ("name", "q", "dq", "ddq",
                                                                                           "tau", "cur")},
    "sign": Field(Enum((1, -1, 1.0, -1.0), text="+1 or -1"), 1),
    "gear_ratio": Field(Num(lo=-1e6, hi=1e6, nonzero=True), 1.0),
    "torque_gain": Field(Num(lo=-1e6, hi=1e6, nonzero=True), 1.0),
    "offset": Field(Num(lo=-1e6, hi=1e6), 0.0),
}, extra="refuse")

#: a TOML column map (``--columns``; a dict in Python): time, time_scale, topic, base_topic, joints
COLUMNS = Obj({
    "time": Field(Str(max_len=10_000, nonempty=True, text="a column name"), "t"),
    "time_scale": Field(Num(lo=1e-12, hi=1e6), 1.0),
    "topic": Field(Opt(Str(max_len=10_000)), None),
    "base_topic": Field(Opt(Str(max_len=10_000)), None),
    "joints": Field(Map(COLUMN_JOINT, max_len=100_000), {}),
}, extra="refuse")


def array(x) -> np.ndarray:
    """A saved JSON array back to a float array: nested lists of numbers, ``None`` as NaN.

    Parameters
    ----------
    x : list
        Nested lists of numbers or ``None``.

    Returns
    -------
    ndarray
        The array.
    """
    return np.array(x, dtype=float) if x is not None else np.array(np.nan)


def read_truth(path, source: str | None = None) -> dict:
    """A truth file (``simulate``'s ``OUT.truth.json``), bounded and checked against :data:`TRUTH`.

    Parameters
    ----------
    path : str or path
        The file.
    source : str, optional
        How messages name it (default: the path).

    Returns
    -------
    dict
        The checked truth (``parameters``: ``[{"name", "value"}]``, names unique, values finite).

    Raises
    ------
    BaseparamsError
        One line: not a regular file, larger than :data:`TRUTH_MAX_BYTES`, not JSON, or not a truth
        (what is wrong and where; write one with ``baseparams simulate``).
    """
    doc = read_json(path, "a truth file (write one with 'baseparams simulate': OUT.truth.json)", TRUTH_MAX_BYTES)
    return check(doc, TRUTH, source or str(path))[0]
