"""Every number the command line and the front door take, range-checked before any work.

One table (:data:`RANGES`) holds each numeric option's type and bounds, under the keyword the front
door uses (``base_frequency=``, the CLI's ``--base-frequency``), and :data:`CHOICES` the values of
the options that name one of a few: the Python functions check their keywords
(:func:`check_keywords`, :func:`check_choice`, naming ``base_frequency=``, in one line) and the
command line checks its parsed flags with the same functions under the same keywords, naming the
flags instead (:mod:`baseparams.cli.parser` maps each keyword to its flag). The bounds are not a
robot's limits: they refuse what no run means (``--starts 1000000``, ``--base-frequency 1e-12``: a
7 PiB allocation, ``--acceleration nan``: no limit at all, ``--gravity 0 0 1e308``) before it
allocates or runs for hours. :func:`check_samples` bounds what a run holds at once (samples x
columns), for the outputs whose size follows from two options (``duration x rate``).

A value of the wrong type is a :class:`ArgumentTypeError` (a ``TypeError``), one out of range an
:class:`ArgumentError` (a ``ValueError``); both are :class:`~baseparams.errors.BaseparamsError`
(the CLI prints them as ``baseparams: error: ...``, exit 2).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from .enums import Convention, MocapWelds, values
from .errors import ArgumentError, ArgumentTypeError, BaseparamsError

__all__ = ["CHOICES", "IDENTIFY", "OPTIONAL", "PAYLOAD", "PAYLOAD_CHOICES", "RANGES", "ArgumentError",
           "ArgumentTypeError", "Range", "brief", "check_array", "check_choice", "check_flags", "check_keywords",
           "check_path", "check_progress", "check_samples", "check_total", "check_value", "need", "options_from"]


@dataclass(frozen=True)
class Range:
    """A numeric argument's type and bounds.

    Parameters
    ----------
    lo, hi : float
        Bounds (inclusive unless ``lo_open``/``hi_open``).
    integer : bool
        An integer (a float with an integer value is accepted from Python, not a fraction).
    lo_open, hi_open : bool
        Exclusive bounds.
    unit : str
        The unit, for messages.
    count : int or None
        A fixed number of values (``gravity``: 3); None: one value.
    """

    lo: float
    hi: float
    integer: bool = False
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""
    count: int | None = None

    def __repr__(self) -> str:
        return f"<Range: {self.text()}>"

    def text(self) -> str:
        """The range as ``[lo, hi]`` with its unit and kind.

        Returns
        -------
        str
            E.g. ``an integer in [1, 1000]`` or ``a number in (0, 3600] s``.
        """
        kind = "an integer" if self.integer else "a number"
        left, right = "(" if self.lo_open else "[", ")" if self.hi_open else "]"
        lo, hi = (f"{int(self.lo)}", f"{int(self.hi)}") if self.integer else (f"{self.lo:g}", f"{self.hi:g}")
        return f"{kind} in {left}{lo}, {hi}{right}{' ' + self.unit if self.unit else ''}"


#: every numeric keyword of the front door and flag of the CLI (``-`` for ``_``)
RANGES = {
    "samples": Range(1, 100_000, integer=True),  # analysis samples (analyze --samples, --analysis-samples)
    "analysis_samples": Range(1, 100_000, integer=True),
    "seed": Range(0, 2**63 - 1, integer=True),
    "workers": Range(1, 1024, integer=True),
    "harmonics": Range(1, 100, integer=True),
    "period": Range(1e-3, 86_400, unit="s"),
    "base_frequency": Range(1 / 86_400, 1e3, unit="Hz"),
    "rate": Range(1, 1e6, unit="Hz"),
    "margin": Range(0, 0.5, hi_open=True),
    "starts": Range(1, 1000, integer=True),
    "grid": Range(3, 100_000, integer=True),
    "max_iter": Range(1, 100_000, integer=True),
    "duration": Range(0, 1e6, lo_open=True, unit="s"),
    "amplitude": Range(0, 1e3, lo_open=True, unit="rad or m"),
    "noise": Range(0, 1e9, unit="N m"),
    "robots": Range(1, 10_000, integer=True),
    "holdout": Range(0, 1e9, lo_open=True, unit="s"),
    "coulomb_width": Range(0, 1e3, lo_open=True, unit="rad/s"),
    "cutoff": Range(1e-3, 1e6, unit="Hz"),
    "decimate": Range(1, 1_000_000, integer=True),
    "min_speed": Range(0, 1e3, unit="rad/s"),
    "prior_weight": Range(0, 1e12),
    "score_cutoff": Range(1e-3, 1e6, unit="Hz"),
    "memory_mb": Range(0, 1e6, lo_open=True, unit="MB"),
    "gravity": Range(-1e3, 1e3, unit="m/s^2", count=3),
    "acceleration": Range(0, 1e7, lo_open=True, unit="rad/s^2"),
    # payload (issue 49): a joint's logged range below which it does not move; the default min_speed as a fraction
    # of each joint's peak speed; the torque noise of a payload design's predicted sigmas
    "still": Range(0, 10, lo_open=True, unit="rad or m"),
    "slow_fraction": Range(0, 1, hi_open=True),
    "payload_noise": Range(0, 1e6, lo_open=True, unit="N m"),
}

#: the identification's options and their defaults, each written once: :class:`baseparams.ident.options.IdentOptions`
#: (which checks them), the front door's ``identify`` keywords and the CLI's ``identify`` flags read them here,
#: where neither ``import baseparams`` nor another command loads the identification
IDENTIFY = MappingProxyType({
    "method": "auto", "rotor": "auto", "friction": ("viscous", "coulomb", "offset"), "coulomb_width": None,
    "couplings": (), "holdout": None, "cutoff": None, "decimate": None, "min_speed": None, "prior_weight": None,
    "convention": "khalil", "covariance": "hac", "score_cutoff": None, "allow_units": False, "literal": False,
    "terms": "auto", "analysis_samples": None, "seed": 0, "memory_mb": 128.0,
    "effort": "auto", "gain_anchor": None,
})
#: a payload identification's options and their defaults, each written once:
#: :class:`baseparams.ident.payload.PayloadOptions` (which checks them), the front door's ``identify_payload``
#: keywords and the CLI's ``payload`` flags read them here
PAYLOAD = MappingProxyType({
    "method": "auto", "friction": ("viscous", "coulomb", "offset"), "rotor": "auto", "offsets": "auto",
    "coulomb_width": None, "min_speed": None, "slow_fraction": 0.1, "still": 0.02, "cutoff": None, "decimate": None,
    "covariance": "hac", "prior": None, "analysis_samples": 200, "seed": 0, "memory_mb": 512.0,
})
#: the choices of ``identify_payload``'s options (``baseparams payload``), where they are not :data:`CHOICES`'
PAYLOAD_CHOICES = MappingProxyType({
    "method": ("auto", "physical", "ls"), "rotor": ("auto", "file", "fit"), "offsets": ("auto", "fit"),
    "covariance": ("hac", "white"),
})
#: the values of the options that name one of a few choices (the first: the default, but ``method``'s)
CHOICES = MappingProxyType({
    "method": ("auto", "ols", "wls", "physical"), "covariance": ("hac", "white"), "stream": ("auto", "on", "off"),
    "criterion": ("cond", "logdet"), "form": ("auto", "expanded", "recursive"),
    "convention": tuple(values(Convention)), "mocap_welds": tuple(values(MocapWelds)),
    "effort": ("auto", "torque", "current"),
})

#: the most samples a run holds at once (a simulated log, a designed trajectory) and samples x columns
MAX_SAMPLES = 2_000_000
MAX_CELLS = 20_000_000
#: the most samples a run makes in all (a simulated fleet: robots x samples per log)
MAX_TOTAL_SAMPLES = 100_000_000


#: keywords whose ``None`` means "the default" (the others must be given as numbers)
OPTIONAL = frozenset({"samples", "analysis_samples", "period", "base_frequency", "amplitude", "acceleration", "holdout",
                      "coulomb_width", "cutoff", "decimate", "min_speed", "prior_weight", "score_cutoff", "gravity",
                      "workers", "robots"})


def brief(value, most: int = 60) -> str:
    """A value's repr on one line, at most ``most`` characters (an array's repr spans lines).

    Parameters
    ----------
    value : object
        The value.
    most : int
        The most characters.

    Returns
    -------
    str
        ``repr(value)`` with its white space collapsed, clipped with ``...``.
    """
    text = " ".join(repr(value).split())
    return text if len(text) <= most else text[:most - 3] + "..."


def _one(value, name: str, r: Range):
    """One value checked against its range: an int or a float."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ArgumentTypeError(f"{name} must be {r.text()}, got {type(value).__name__} {brief(value)}")
    try:
        x = float(value)
    except OverflowError:
        raise ArgumentError(f"{name} must be {r.text()}, got an integer of {len(str(value))} digits") from None
    if not math.isfinite(x):
        raise ArgumentError(f"{name} must be {r.text()}, got {x}")
    if r.integer and x != int(x):
        raise ArgumentTypeError(f"{name} must be {r.text()}, got {value!r}")
    if x < r.lo or x > r.hi or (r.lo_open and x == r.lo) or (r.hi_open and x == r.hi):
        raise ArgumentError(f"{name} must be {r.text()}, got {value:g}" if not r.integer
                            else f"{name} must be {r.text()}, got {int(x)}")
    return int(x) if r.integer else x


def check_value(value, keyword: str, r: Range | None = None):
    """One argument checked against :data:`RANGES`.

    Parameters
    ----------
    value : object
        The value (a number, or for ``gravity`` three numbers, for ``acceleration`` one or a
        sequence); ``None`` passes for the keywords of :data:`OPTIONAL`.
    keyword : str
        Its keyword (``base_frequency``; named ``base_frequency=`` in messages).
    r : Range, optional
        The range (default ``RANGES[keyword]``).

    Returns
    -------
    object
        The value as a Python int, float, or a float array (sequences).

    Raises
    ------
    ArgumentTypeError
        Not a number (a string, a boolean, a fraction for an integer), not the right count.
    ArgumentError
        Not finite, out of range.
    """
    r = r or RANGES[keyword]
    name = f"{keyword}="
    if value is None:
        if keyword in OPTIONAL:
            return None
        raise ArgumentTypeError(f"{name} must be {r.text()}, got None")
    if r.count is not None or keyword == "acceleration" and not isinstance(value, numbers.Real):
        try:
            a = np.asarray(value, dtype=object).ravel()
        except Exception:  # noqa: BLE001 - whatever the object: one line
            a = None
        if a is None or isinstance(value, (str, bytes, dict)) or (r.count is not None and len(a) != r.count) \
                or len(a) == 0:
            want = f"{r.count} numbers" if r.count is not None else "a number or a sequence of numbers"
            raise ArgumentTypeError(f"{name} must be {want} ({r.text()} each), got {brief(value, 80)}")
        return np.array([_one(v, f"{name} (item {k})", r) for k, v in enumerate(a)], dtype=float)
    return _one(value, name, r)


def check_keywords(where: str, **values) -> dict:
    """Check keyword arguments that have a range in :data:`RANGES`; the others are returned as given.

    Parameters
    ----------
    where : str
        The function (for messages: ``excite: base_frequency= must be ...``), or ''.
    **values
        The arguments.

    Returns
    -------
    dict
        The checked values (numbers as int or float).

    Raises
    ------
    ArgumentTypeError, ArgumentError
        One line naming the first bad argument.
    """
    out = {}
    for k, v in values.items():
        if k in RANGES:
            try:
                out[k] = check_value(v, k)
            except BaseparamsError as exc:
                raise type(exc)(f"{where}: {exc}" if where else str(exc)) from None
        else:
            out[k] = v
    return out


def check_samples(samples: float, columns: int, what: str) -> None:
    """Refuse a run that would hold more than :data:`MAX_SAMPLES` samples or :data:`MAX_CELLS` numbers.

    Parameters
    ----------
    samples : float
        The samples the run makes (``duration x rate``, ``period x rate``).
    columns : int
        Numbers per sample held at once (joints x signals).
    what : str
        The options that make them, for the message (``--duration x --rate``).

    Raises
    ------
    ArgumentError
        One line naming the options, the samples and the bound.
    """
    if not samples <= MAX_SAMPLES or not samples * max(columns, 1) <= MAX_CELLS:
        raise ArgumentError(f"{what} makes {samples:.4g} samples of {columns} numbers; at most {MAX_SAMPLES:g} "
                            f"samples and {MAX_CELLS:g} numbers are held at once (split the run)")


def check_total(samples: float, what: str) -> None:
    """Refuse a run that makes more than :data:`MAX_TOTAL_SAMPLES` samples in all (hours of work).

    Parameters
    ----------
    samples : float
        The samples made in all (``robots x duration x rate``).
    what : str
        The options that make them, for the message.

    Raises
    ------
    ArgumentError
        One line naming the options.
    """
    if not samples <= MAX_TOTAL_SAMPLES:
        raise ArgumentError(f"{what} makes {samples:.4g} samples in all; at most {MAX_TOTAL_SAMPLES:g} in one run "
                            f"(split it)")


def check_array(value, name: str, ndim: int | tuple = (1, 2), finite: bool = True) -> np.ndarray:
    """A float array argument: numbers (not strings, objects or booleans), its dimensions, finite.

    Parameters
    ----------
    value : array_like
        The argument.
    name : str
        Its name, for messages.
    ndim : int or tuple of int
        The dimensions accepted.
    finite : bool
        Refuse NaN and inf.

    Returns
    -------
    ndarray
        ``value`` as float64.

    Raises
    ------
    ArgumentTypeError
        Not numbers, or another number of dimensions.
    ArgumentError
        Not finite.
    """
    if isinstance(value, (str, bytes, dict)) or value is None:
        raise ArgumentTypeError(f"{name} must be an array of numbers, got {type(value).__name__}")
    try:
        a = np.asarray(value)
    except Exception as exc:  # noqa: BLE001 - ragged lists and the like
        raise ArgumentTypeError(f"{name} must be an array of numbers ({str(exc).splitlines()[0][:80]})") from None
    if a.dtype.kind not in "iuf":
        raise ArgumentTypeError(f"{name} must be an array of numbers, got {a.dtype} values")
    dims = (ndim,) if isinstance(ndim, int) else tuple(ndim)
    if a.ndim not in dims:
        raise ArgumentTypeError(f"{name} must have {' or '.join(map(str, dims))} dimensions, got shape {a.shape}")
    a = a.astype(float, copy=False)  # a log of 10^7 rows is not copied
    if finite and not np.all(np.isfinite(a)):
        raise ArgumentError(f"{name} must be finite, got {int(np.sum(~np.isfinite(a)))} values that are not")
    return a


def check_path(value, name: str, optional: bool = False):
    """A path argument: a str or an ``os.PathLike`` (``None`` with ``optional``).

    Parameters
    ----------
    value : object
        The argument.
    name : str
        Its name, for messages (``out=``).
    optional : bool
        ``None`` is accepted (returned as is).

    Returns
    -------
    str, os.PathLike or None
        ``value``.

    Raises
    ------
    ArgumentTypeError
        Anything else (bytes, numbers, lists...).
    """
    import os

    if value is None and optional:
        return None
    if isinstance(value, str) or (isinstance(value, os.PathLike) and isinstance(os.fspath(value), str)):
        return value
    raise ArgumentTypeError(f"{name} must be a file path (str or pathlib.Path), got {type(value).__name__} "
                            f"{brief(value)}")


def check_flags(where: str, **flags) -> None:
    """Flags must be booleans (``rotor="no"`` would be true): one line naming the first that is not.

    Parameters
    ----------
    where : str
        The function, for messages ('' for none).
    **flags
        The flags.

    Raises
    ------
    ArgumentTypeError
        A flag that is not True or False.
    """
    head = f"{where}: " if where else ""
    for name, value in flags.items():
        if not isinstance(value, (bool, np.bool_)):
            raise ArgumentTypeError(f"{head}{name}= must be True or False, got {type(value).__name__} "
                                    f"{brief(value, 40)}")


def check_choice(where: str, name: str, value, choices) -> None:
    """A keyword that names one of ``choices``: one line naming it when it does not.

    Parameters
    ----------
    where : str
        The function, for messages.
    name : str
        The keyword.
    value : object
        Its value.
    choices : tuple of str
        The values it may take.

    Raises
    ------
    ArgumentTypeError
        Not a string.
    ArgumentError
        Not one of ``choices``.
    """
    head = f"{where}: " if where else ""
    if not isinstance(value, str):
        raise ArgumentTypeError(f"{head}{name}= must be one of {', '.join(choices)}, got {type(value).__name__}")
    if value not in choices:
        raise ArgumentError(f"{head}{name}= must be one of {', '.join(choices)}, got {brief(value)}")


def check_progress(value, where: str, stream: bool = False):
    """A ``progress`` argument: None, a callable taking one line (or with ``stream`` a text stream).

    Parameters
    ----------
    value : object
        The argument.
    where : str
        The function, for messages.
    stream : bool
        A text stream (an object with ``write``) is expected instead of a callable.

    Returns
    -------
    object
        ``value``.

    Raises
    ------
    ArgumentTypeError
        Anything else.
    """
    ok = value is None or (callable(getattr(value, "write", None)) if stream else callable(value))
    if not ok:
        want = "a text stream (sys.stderr)" if stream else "a callable taking one line of text"
        raise ArgumentTypeError(f"{where}: progress= must be {want} or None, got {type(value).__name__}")
    return value


def options_from(kind, options=None, keywords: dict | None = None):
    """An options object given as the object, as keywords, or both (the keywords over the object's).

    Parameters
    ----------
    kind : type
        The options' frozen dataclass (:class:`baseparams.ident.options.IdentOptions`, ...), which
        checks its values when made.
    options : kind, optional
        The options (default: the defaults).
    keywords : dict, optional
        Options by name (``kind``'s fields).

    Returns
    -------
    kind
        The options, checked.

    Raises
    ------
    ArgumentTypeError
        ``options`` not a ``kind``, or a keyword that is not one of its fields.
    """
    from dataclasses import fields, replace

    if options is not None and not isinstance(options, kind):
        raise ArgumentTypeError(f"options must be {kind.__name__}, got {type(options).__name__}")
    names = [f.name for f in fields(kind)]
    unknown = sorted(set(keywords or ()) - set(names))
    if unknown:
        raise ArgumentTypeError(f"unknown option(s) {unknown}; the options are {kind.__name__}'s fields: "
                                f"{', '.join(names)}")
    if options is None:
        return kind(**(keywords or {}))
    return replace(options, **keywords) if keywords else options


#: the optional modules a run may need, and the extra that installs each
EXTRAS = MappingProxyType({"matplotlib": "plot", "cvxpy": "ident", "clarabel": "ident", "pyarrow": "parquet",
                           "rosbags": "ros", "dask": "fleet", "distributed": "fleet", "sympy": "symbolic",
                           "xacro": "xacro"})


def need(module: str, why: str) -> None:
    """Refuse in one line, before any work, a run that needs an optional module that is missing.

    Parameters
    ----------
    module : str
        The module (a key of :data:`EXTRAS`), checked by importing it.
    why : str
        What needs it, for the message (``plot=``, ``reading Parquet``).

    Raises
    ------
    BaseparamsError
        ``WHY needs MODULE: pip install 'baseparams[EXTRA]'``.
    """
    import importlib

    try:
        importlib.import_module(module)
    except ImportError:
        raise BaseparamsError(f"{why} needs {module}: pip install 'baseparams[{EXTRAS[module]}]'") from None
