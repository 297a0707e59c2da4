"""Readable text of the package's objects: numbers without float-repr noise, one-line reprs, tables.

:func:`format_number` writes a float at the precision it has (``0.00041209``, not
``0.0004120899999999``); :func:`summary_repr` is the one-line ``repr`` of a result object that
has no better one (``<Estimate method='wls', theta=ndarray(54), ...>``, never its arrays);
:func:`text_table` and :func:`data_frame` lay out named columns (the latter through pandas, an
optional package imported only when asked).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .errors import BaseparamsError

#: every repr of the package's objects is shorter than this
MAX_REPR = 300
#: significant digits of a printed coefficient: a computed coefficient is not more precise
DIGITS = 12
#: magnitudes written positionally (``0.00041209``, ``12.5``); others in scientific notation
#: (``1.2e-07``): no long runs of zeros either way
POSITIONAL = (1e-4, 1e6)


def format_number(x: float, digits: int = DIGITS) -> str:
    """The shortest decimal that is ``x`` rounded to ``digits`` significant digits.

    Parameters
    ----------
    x : float
        A number.
    digits : int
        Significant digits kept (:data:`DIGITS`; 4 to 6 for summaries).

    Returns
    -------
    str
        ``0.00041209`` for ``0.0004120899999999``, ``2`` for ``2.0``, ``1.5e-07``; positional
        for magnitudes in :data:`POSITIONAL`, scientific otherwise; ``nan`` / ``inf`` as such.
        It reads back within ``0.5 * 10**(1 - digits)`` relative of ``x``.

    Examples
    --------
    >>> format_number(0.0004120899999999), format_number(-2.0), format_number(1.5e-7)
    ('0.00041209', '-2', '1.5e-07')
    """
    x = float(x)
    if not math.isfinite(x):
        return repr(x)
    if x == 0.0:
        return "0"
    text = f"{x:.{digits - 1}e}"
    r = float(text)  # rounded to ``digits`` significant digits
    if POSITIONAL[0] <= abs(r) < POSITIONAL[1]:
        # repr is the shortest round-trip decimal, positional in this range: the same digits as
        # np.format_float_positional(r, unique=True, trim="-") at a third of the cost
        s = repr(r)
        return s[:-2] if s.endswith(".0") else s
    if digits <= 15 and _SMALLEST_NORMAL <= abs(r) < math.inf:
        # a normal float holds every decimal of at most 15 digits apart: the rounded text without its
        # trailing zeros is r's only shortest round-trip decimal, what numpy's Dragon4 writes below
        # (a third of the cost: the expanded form of a long chain writes millions)
        mantissa, _, exponent = text.partition("e")
        return f"{mantissa.rstrip('0').rstrip('.')}e{exponent}"
    return np.format_float_scientific(r, unique=True, trim="-", exp_digits=2)


#: below this (subnormal), a float carries fewer than 15 significant digits
_SMALLEST_NORMAL = float(np.finfo(float).tiny)


def clip(text: str, limit: int = MAX_REPR - 1) -> str:
    """One line of at most ``limit`` characters.

    Parameters
    ----------
    text : str
        A repr, ending in ``>``.
    limit : int
        The longest result.

    Returns
    -------
    str
        ``text`` on one line, cut at the last ``", "`` that fits and ended by ``", ...>"``
        when too long.
    """
    text = " ".join(text.split())
    if len(text) <= limit:
        return text
    head = text[: limit - 5]
    cut = head.rfind(", ")
    return (head[:cut] if cut > 0 else head) + ", ...>"


def name_list(names, limit: int = 12) -> str:
    """Names joined by commas, at most ``limit`` of them and the count of the rest.

    Parameters
    ----------
    names : iterable of str
        The names, most important first.
    limit : int
        The most names shown.

    Returns
    -------
    str
        E.g. ``a, b, c`` or ``a, b, c and 397 more``: a message naming hundreds of parameters
        stays one readable line.
    """
    names = [str(n) for n in names]
    shown = ", ".join(names[:limit])
    return shown if len(names) <= limit else f"{shown} and {len(names) - limit} more"


def counted(n, noun: str, plural: str | None = None) -> str:
    """A count and its noun in the number the count takes: the one place messages write ``1 row``, ``2 rows``.

    Parameters
    ----------
    n : int
        The count.
    noun : str
        The noun in the singular (``row``).
    plural : str, optional
        Its plural when it is not ``noun + "s"`` (``bodies``, ``entries``).

    Returns
    -------
    str
        ``1 row``, ``0 rows``, ``2 rows``.
    """
    n = int(n)
    return f"{n} {noun if n == 1 else plural or noun + 's'}"


def brief(value, width: int = 60) -> str:
    """A field's value in a few characters: arrays by shape, numbers at 4 digits, long text cut.

    Parameters
    ----------
    value : object
        Any value.
    width : int
        The longest text of a string, a short sequence or a nested object's repr.

    Returns
    -------
    str
        E.g. ``ndarray(6x4x4)``, ``[0, 0, -9.81]``, ``'puma560'``, ``12 items``, ``{3 keys}``,
        ``<Robot puma560: ...>`` or ``<Robot>``.
    """
    if value is None or isinstance(value, bool | np.bool_):
        return str(value)
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return format_number(value, 4)
    if isinstance(value, str):
        return repr(value) if len(value) <= width else repr(value[: width - 3] + "...")
    if isinstance(value, np.ndarray):
        if value.ndim == 1 and value.size <= 4 and value.dtype.kind in "fiub":
            return "[" + ", ".join(brief(v) for v in value.tolist()) + "]"
        return f"ndarray({'x'.join(map(str, value.shape))})"
    if isinstance(value, list | tuple):
        if len(value) <= 6 and all(isinstance(v, str | int | float | tuple) for v in value):
            text = ", ".join(brief(v, 30) for v in value)
            if len(text) <= width:
                return f"[{text}]" if isinstance(value, list) else f"({text}{',' if len(value) == 1 else ''})"
        return f"{len(value)} items"
    if isinstance(value, dict):
        return f"{{{len(value)} keys}}"
    text = repr(value)
    return text if len(text) <= width and "\n" not in text else f"<{type(value).__name__}>"


def summary_repr(obj) -> str:
    """The one-line repr of a dataclass: each field :func:`brief`, clipped below :data:`MAX_REPR`.

    Parameters
    ----------
    obj : dataclass instance
        The object.

    Returns
    -------
    str
        ``<ClassName field=value, ...>``.
    """
    parts = [f"{f.name}={brief(getattr(obj, f.name))}" for f in dataclasses.fields(obj) if f.repr]
    return clip(f"<{type(obj).__name__} {', '.join(parts)}>")


def text_table(columns: dict[str, list], digits: dict[str, int] | None = None) -> str:
    """Named columns as aligned text: text left, numbers right at a few significant digits.

    Parameters
    ----------
    columns : dict of str to list
        Header -> cells, all of one length; cells are str, numbers or None.
    digits : dict of str to int, optional
        Significant digits per numeric column (default 6).

    Returns
    -------
    str
        A header line and one line per row, columns separated by two spaces.
    """
    digits = digits or {}
    cells, numeric = {}, {}
    for head, col in columns.items():
        numeric[head] = all(isinstance(c, int | float | np.number) or c is None for c in col)
        cells[head] = [("" if c is None else format_number(c, digits.get(head, 6)) if numeric[head] else str(c))
                       for c in col]
    widths = {h: max([len(h)] + [len(c) for c in cells[h]]) for h in columns}
    last = list(columns)[-1] if columns else None

    def line(row: dict[str, str]) -> str:
        out = [row[h].rjust(widths[h]) if numeric[h] else (row[h] if h == last else row[h].ljust(widths[h]))
               for h in columns]
        return "  ".join(out).rstrip()

    n = len(next(iter(columns.values()))) if columns else 0
    return "\n".join([line({h: h for h in columns})] + [line({h: cells[h][i] for h in columns}) for i in range(n)])


def data_frame(columns: dict[str, list]):
    """Named columns as a pandas DataFrame (pandas is optional: imported here only).

    Parameters
    ----------
    columns : dict of str to array_like
        Header -> column, all of one length.

    Returns
    -------
    pandas.DataFrame
        One column per entry, in order.

    Raises
    ------
    BaseparamsError
        pandas is not installed (the message says how to install it).
    """
    try:
        import pandas as pd
    except ImportError:
        raise BaseparamsError("to_frame() needs pandas, which baseparams does not install: pip install pandas; "
                              "table() gives the same as text") from None
    return pd.DataFrame(columns)
