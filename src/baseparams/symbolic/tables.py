"""Denavit-Hartenberg tables with symbols: a small text format and the built-in examples.

The format (one table per file, ``.dh``)::

    # comments
    name puma560-symbolic
    description Puma560 arm in modified DH
    convention modified            # or: standard
    gravity 0 0 -9.81
    values D3=0.4318 RL3=0.15005   # optional default numbers
    j  ant  sigma  alpha   d   theta  r
    1  0    0      0       0   0      0
    2  1    0      -pi/2   0   0      0
    3  2    0      0       D3  0      RL3

``modified`` (Khalil & Dombre's table, Khalil-Kleinfinger): ``T(ant, j) = Rot(z, gamma) Trans(z, b)
Rot(x, alpha) Trans(x, d) Rot(z, theta) Trans(z, r)`` (``gamma``, ``b``: Khalil's optional
columns for trees, default 0); the parameters of link ``j`` are in frame ``j`` (the joint
frame). ``standard`` (Denavit-Hartenberg, Corke): columns ``j ant sigma theta d a alpha``,
joint ``j`` moves about (along) ``z_{j-1}`` and ``T(j-1, j) = Rot(z, theta) Trans(z, d) Trans(x, a)
Rot(x, alpha)``; the parameters of link ``j`` are in frame ``j`` (its distal frame). ``ant`` is
the antecedent (0: the base; optional, default ``j - 1``), ``sigma`` 0 revolute (``q``
adds to ``theta``), 1 prismatic (``q`` adds to ``r``, or ``d`` for standard DH). Lengths are
numbers or names (SymPy symbols, real); angles are exact numbers (``pi/2``, ``-pi/2``, ``0``,
``pi/3``...) or a name, possibly signed and plus a constant (``alpha2``, ``-a + pi/2``), handled
through its half-angle tangent (:mod:`.angles`). The symbolic analysis needs the geometry rational
in the symbols: a fixed angle with an irrational cosine (``pi/3``) is analysed in numbers only
(give it as a name to have formulas).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import sympy as sp

from ..display import counted
from ..errors import ModelError
from ..files import MODEL_MAX_BYTES, read_input_bytes
from .angles import cos_sin
from .expr import ExpressionError, parse
from .geometry import SymbolicBuilder, SymbolicRobot, exact, rot, trans

#: the columns of each convention (``ant`` optional)
COLUMNS = {"modified": ("j", "ant", "sigma", "gamma", "b", "alpha", "d", "theta", "r"),
           "standard": ("j", "ant", "sigma", "theta", "d", "a", "alpha")}
#: columns a table may leave out (``ant``: ``j - 1``; Khalil's tree columns ``gamma``, ``b``: 0)
OPTIONAL = ("ant", "gamma", "b")
_ANGLES = {"modified": ("alpha", "theta", "gamma"), "standard": ("alpha", "theta")}


def _entry(text: str, where: str, angle: bool) -> sp.Expr:
    try:
        e = parse(text)  # an allow-list grammar: nothing in a table is evaluated as Python
    except ExpressionError as exc:
        raise ModelError(f"{where}: cannot read {text[:60]!r}: {exc} (a number, a name or an expression like "
                         "pi/2)") from None
    if e.free_symbols:
        e = e.subs({s: sp.Symbol(s.name, real=True) for s in e.free_symbols})
        if angle:
            try:
                cos_sin(e)
            except ValueError:
                raise ModelError(f"{where}: a symbolic angle must be a name, possibly signed and plus a constant "
                                 f"(a, -a, a + pi/2), got {text!r}") from None
    return e


def mdh(alpha, d, theta, r) -> sp.Matrix:
    """Modified DH transform ``Rot(x, alpha) Trans(x, d) Rot(z, theta) Trans(z, r)`` ``(4, 4)``.

    Parameters
    ----------
    alpha, d, theta, r : sympy expression or number
        Khalil & Dombre's link parameters (angles exact).

    Returns
    -------
    sympy.Matrix, shape ``(4, 4)``
        Frame ``j`` in frame ``ant(j)``.
    """
    return rot("x", alpha) * trans("x", d) * rot("z", theta) * trans("z", r)


def sdh(theta, d, a, alpha) -> sp.Matrix:
    """Standard DH transform ``Rot(z, theta) Trans(z, d) Trans(x, a) Rot(x, alpha)`` ``(4, 4)``.

    Parameters
    ----------
    theta, d, a, alpha : sympy expression or number
        Denavit-Hartenberg link parameters (angles exact).

    Returns
    -------
    sympy.Matrix, shape ``(4, 4)``
        Frame ``j`` in frame ``j - 1``.
    """
    return rot("z", theta) * trans("z", d) * trans("x", a) * rot("x", alpha)


def from_dh(rows: list[dict], convention: str = "modified", name: str = "dh", gravity=(0, 0, -9.81),
            values: dict | None = None, description: str = "") -> SymbolicRobot:
    """A :class:`SymbolicRobot` from DH rows.

    Parameters
    ----------
    rows : list of dict
        One per link, keys as :data:`COLUMNS` (``ant`` optional: ``j - 1``; ``gamma``, ``b``
        optional: 0), SymPy entries or numbers.
    convention : {"modified", "standard"}
        The table's convention (module docstring).
    name : str
        The robot's name.
    gravity : array_like, shape ``(3,)``
        Gravity in frame 0 [m/s^2].
    values : dict, optional
        Default numbers for the symbols.
    description : str
        One line.

    Returns
    -------
    SymbolicRobot
        Body ``j`` named ``link{j}``, labelled ``j`` (parameters ``XX{j}``...); the parameter
        frame of link ``j`` is DH frame ``j``.
    """
    if convention not in COLUMNS:
        raise ModelError(f"robot {name!r}: unknown DH convention {convention!r} (modified or standard)")
    b = SymbolicBuilder(name, gravity=gravity, values=values, description=description)
    b.convention = f"{convention} DH"
    end = {0: sp.eye(4)}  # standard DH: each link's distal frame in its joint frame
    for row in rows:
        j, ant = int(row["j"]), int(row.get("ant", int(row["j"]) - 1))
        sigma = int(row["sigma"])
        joint = "R" if sigma == 0 else "P"
        parent = None if ant == 0 else f"link{ant}"
        if convention == "modified":
            origin = rot("z", row.get("gamma", 0)) * trans("z", row.get("b", 0))
            origin, frame = origin * mdh(row["alpha"], row["d"], row["theta"], row["r"]), None
        else:
            origin = end[ant]  # joint j sits in frame ant (= j - 1), moving about its z
            frame = rot("z", row["theta"]) * trans("z", row["d"]) * trans("x", row["a"]) * rot("x", row["alpha"])
            end[j] = frame
        if ant not in end and convention == "standard":
            raise ModelError(f"robot {name!r}, row j={j}: antecedent {ant} comes later in the table")
        b.add_link(f"link{j}", parent=parent, joint=joint, origin=origin, label=str(j), param_frame=frame)
    return b.build()


def _values(words: list[str], where: str) -> dict:
    out = {}
    for w in words:
        key, eq, val = w.partition("=")
        if not eq:
            raise ModelError(f"{where}: expected NAME=NUMBER, got {w!r}")
        try:
            out[key] = exact(float(val))
        except ValueError:
            raise ModelError(f"{where}: {val!r} is not a number") from None
    return out


def _read_text(path: Path) -> str:
    """A table file's text: a regular UTF-8 file of at most 64 MB (:func:`baseparams.files.read_input_bytes`)."""
    data = read_input_bytes(path, MODEL_MAX_BYTES, error=ModelError)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ModelError(f"{path}: not a UTF-8 text file (byte {e.start})") from None


def read_table(path: str | Path, text: str | None = None) -> SymbolicRobot:
    """Read a DH table file (module docstring for the format).

    Parameters
    ----------
    path : str or Path
        The file (also used in messages when ``text`` is given).
    text : str, optional
        The file's content (default: read ``path``).

    Returns
    -------
    SymbolicRobot
        The robot (:func:`from_dh`).

    Raises
    ------
    ModelError
        One line naming the file, line and problem.
    """
    path = Path(path)
    if text is None:
        text = _read_text(path)
    meta = {"name": path.stem, "convention": "modified", "gravity": (0, 0, -9.81), "values": {}, "description": ""}
    header, rows = None, []
    for no, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        where = f"{path}, line {no}"
        if not line:
            continue
        key, _, rest = line.partition(" ")
        words = rest.split()
        if header is None and key in ("name", "description"):
            meta[key] = rest.strip()
        elif header is None and key == "convention":
            meta["convention"] = rest.strip().replace("-dh", "").replace(" dh", "")
            if meta["convention"] not in COLUMNS:
                raise ModelError(f"{where}: convention must be 'modified' or 'standard', got {rest.strip()!r}")
        elif header is None and key == "gravity":
            if len(words) != 3:
                raise ModelError(f"{where}: gravity needs 3 numbers")
            meta["gravity"] = tuple(_entry(w, where, False) for w in words)
        elif header is None and key == "values":
            meta["values"] = _values(words, where)
        elif header is None and key == "j":
            header = [key] + words
            need = [c for c in COLUMNS[meta["convention"]] if c not in OPTIONAL]
            missing = [c for c in need if c not in header]
            if missing or any(c not in COLUMNS[meta["convention"]] for c in header):
                raise ModelError(f"{where}: {meta['convention']} DH columns are {' '.join(COLUMNS[meta['convention']])}"
                                 f" ({', '.join(OPTIONAL)} optional); got {' '.join(header)}")
        elif header is None:
            raise ModelError(f"{where}: unknown line {key!r} (expected name, description, convention, gravity, "
                             f"values or the column header starting with j)")
        else:
            cells = line.split()
            if len(cells) != len(header):
                raise ModelError(f"{where}: {counted(len(cells), 'entry', 'entries')} for "
                                 f"{counted(len(header), 'column')}")
            row = {c: _entry(v, f"{where}, column {c}", c in _ANGLES[meta["convention"]])
                   for c, v in zip(header, cells)}
            for c in ("j", "ant", "sigma"):
                if c in row and (not row[c].is_Integer or row[c] < 0):
                    raise ModelError(f"{where}, column {c}: expected a non-negative integer, got {row[c]}")
            if row["sigma"] not in (0, 1):
                raise ModelError(f"{where}, column sigma: 0 (revolute) or 1 (prismatic), got {row['sigma']}")
            if int(row["j"]) != len(rows) + 1:
                raise ModelError(f"{where}: rows must be numbered 1, 2, ... in order (got j={row['j']})")
            if "ant" in row and int(row["ant"]) >= int(row["j"]):
                raise ModelError(f"{where}: antecedent {row['ant']} must be below j={row['j']}")
            rows.append(row)
    if not rows:
        raise ModelError(f"{path}: no table rows (a header line starting with 'j', then one row per link)")
    robot = from_dh(rows, meta["convention"], meta["name"], meta["gravity"], meta["values"], meta["description"])
    if path.is_file():
        object.__setattr__(robot, "source", str(path.resolve()))
    return robot


def _bundled_tables() -> list[SymbolicRobot]:
    """The package's ``robots/data/symbolic/*.dh`` tables, read, by file name."""
    folder = resources.files("baseparams") / "robots" / "data" / "symbolic"
    return [read_table(Path(f.name), f.read_text()) for f in sorted(folder.iterdir(), key=lambda p: p.name)
            if f.name.endswith(".dh")]


def builtin_tables() -> dict[str, str]:
    """The built-in symbolic robots: ``{name: description}`` (``baseparams robots`` lists them).

    Returns
    -------
    dict
        Table robots read from the package's ``robots/data/symbolic/*.dh`` and the Python-built
        closed chains (:mod:`.examples`).
    """
    from .examples import EXAMPLES

    out = {r.name: r.description for r in _bundled_tables()}
    out.update({k: d for k, (_, d) in EXAMPLES.items()})
    return out


#: robot files (numbers, not symbols): refused by :func:`load_symbolic` instead of read as a table
ROBOT_FILE_SUFFIXES = (".urdf", ".xml", ".mjcf", ".xacro", ".sdf")


def load_symbolic(model: str) -> SymbolicRobot:
    """A symbolic robot by built-in name (``puma560-symbolic``...) or ``.dh`` file path.

    Parameters
    ----------
    model : str
        A built-in name (:func:`builtin_tables`) or a table file.

    Returns
    -------
    SymbolicRobot
        The robot.

    Raises
    ------
    ModelError
        Neither a file nor a built-in symbolic robot; a robot file (URDF, MJCF, xacro), which has
        numbers, not symbols.
    """
    from .examples import EXAMPLES

    p = Path(model)
    if p.suffix.lower() in ROBOT_FILE_SUFFIXES:
        raise ModelError(f"{model}: a robot file has numbers, not symbols: the symbolic analysis takes a DH table "
                         f"(.dh, lengths as names) or a built-in symbolic robot ({', '.join(builtin_tables())}); "
                         "analyze this file without --symbolic")
    if p.exists() or model.lower().endswith(".dh"):  # read_table refuses a folder, a device, a FIFO
        return read_table(p)
    key = model.lower()
    if key in EXAMPLES:
        r = EXAMPLES[key][0]()
        object.__setattr__(r, "source", key)
        return r
    for r in _bundled_tables():
        if r.name == key:
            object.__setattr__(r, "source", key)
            return r
    raise ModelError(f"{model}: no such table file, and not a built-in symbolic robot "
                     f"({', '.join(builtin_tables())})")
