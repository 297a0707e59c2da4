"""Read a recorded joint log (CSV/TSV, NPZ, Parquet, ROS bag) into a :class:`~baseparams.jointlog.JointLog`.

:func:`read_log` picks the reader by the path: ``.csv``/``.tsv``/``.txt`` (text table, delimiter
sniffed, header row required), ``.npz`` (one 1-D array per column), ``.parquet``/``.pq``
(``pyarrow``, extra ``parquet``), and ROS bags (a rosbag2 folder holding ``metadata.yaml``, a
``.mcap`` or ``.db3`` file, or a ROS 1 ``.bag``; ``rosbags``, extra ``ros``).

Default layout (tables)
-----------------------
A time column ``t`` [s] and per coordinate of the model ``q_<joint>`` [rad or m], ``tau_<joint>``
[N m or N], and optionally ``dq_<joint>``, ``ddq_<joint>``, where ``<joint>`` is the coordinate's
name (``robot.coordinate_names()``): a 1-dof joint's name; for a joint of several coordinates one
name each, an MJCF body's own joints (``rootx``, ``rootz``, ``rooty`` of ``rootx+rootz+rooty``) or
the joint's name and the coordinate's place (``p.0``, ``p.1``, ``p.2`` of a URDF ``planar`` joint
``p``, in the order of its axes; a ball, a universal joint likewise). An arm without joint-torque
sensors logs its motor currents instead (or as well): ``cur_<joint>`` [A], the current of the
motor named after the joint, identified with unknown gains (:mod:`baseparams.ident.fromcurrents`);
a joint with a ``cur_`` column needs no ``tau_``. Example CSV header for a 2-joint arm::

    t,q_joint1,q_joint2,dq_joint1,dq_joint2,tau_joint1,tau_joint2

Every column named ``q_``/``dq_``/``ddq_``/``tau_``/``cur_`` + a name must name a coordinate of
the model; other columns are ignored, and a note lists them. Every coordinate of the model (the floating
base's excepted: below) must be in the log unless ``allow_subset=True``.

Floating base
-------------
A robot with a floating base (``Robot.floating``: a legged robot, ``--floating``) needs the
base's pose in the log, ``base_x, base_y, base_z`` [m] (the base frame's origin, world frame)
and ``base_qw, base_qx, base_qy, base_qz`` (its orientation, world <- base, unit quaternion,
scalar first), and takes its twist when the joints have ``dq``: ``base_vx, base_vy, base_vz``
[m/s] (the origin's velocity) and ``base_wx, base_wy, base_wz`` [rad/s], both in the **base**
frame (without them the twist is derived from the pose). Accelerations are derived. The base
becomes the log's first six coordinates :data:`~baseparams.kinematics.floating.BASE_COORDINATES`
(position and unwrapped Z-Y-X angles; tau zero, not measured): :mod:`baseparams.kinematics.floating`.
A pitch beyond 85 deg, or a quaternion far from unit norm, is refused naming the row. The twist is
checked against the pose (:func:`~baseparams.kinematics.floating.twist_mismatch`): one that follows
it expressed in the world frame, not the base frame, is refused with both figures; one that follows
neither gets a note. Every format reads the same columns (:func:`_layout_columns`); a ROS bag
carries them on a ``nav_msgs/msg/Odometry`` topic (:func:`_bag_base`).

ROS bags
--------
``sensor_msgs/msg/JointState`` messages on one topic (default: the first JointState topic; a
string ``columns`` or the mapping's ``topic`` names it), matched by ``name[]``: ``position[]`` is
q, ``velocity[]`` dq (when every message has it), ``effort[]`` tau. Time is the header stamp,
counted from the first message (the bag's record time when every header stamp is zero; a note
says so). Messages that lack one of the joints read are removed and counted. A floating base's pose
and twist come from a ``nav_msgs/msg/Odometry`` topic (the mapping's ``base_topic``, default the
first one): pose in the world frame, twist in the child (base) frame, as REP 105 has it; taken at
the JointState stamps (interpolated between two of its own: a note), JointState messages outside
its time span removed and counted.

Mapping (any other layout)
--------------------------
``columns`` may be a TOML file (read with :mod:`tomllib`) or a dict of the same structure::

    time = "stamp_ns"        # time column (default "t")
    time_scale = 1e-9        # seconds per time unit (default 1)
    topic = "/franka/joint_states"   # bags only
    base_topic = "/odom"     # bags only: a floating base's nav_msgs/msg/Odometry

    [joints.panda_joint1]    # a model joint; only the joints listed here are read
    q = "motor_pos_1"        # column names (defaults: q_<joint>, dq_<joint>, ...)
    dq = "motor_vel_1"       # optional
    tau = "current_1"
    sign = -1                # +1 or -1 (default 1)
    gear_ratio = 100         # motor side -> joint side: q = q_motor / ratio, tau = tau_motor * ratio
    torque_gain = 0.35       # tau column is a current [A]: tau_motor = gain * current [N m/A]
    cur = "motor_current_1"  # or: the current [A] itself, its gain unknown (identified; sign applied)
    offset = 1.5708          # joint-side zero shift [rad or m], added last (default 0)

    [joints.panda_joint2]
    name = "fr3_joint2"      # columns q_fr3_joint2, ... (bags: the name in JointState.name[])

Conversions, per joint: ``q = sign * q_col / gear_ratio + offset``, the same for ``dq`` and ``ddq``
without the offset, ``tau = sign * torque_gain * gear_ratio * tau_col``, ``cur = sign * cur_col``.
Coupled transmissions (one motor driving two joints) are not expressible here: convert such logs
before reading.

Checks
------
Bad input is one :class:`~baseparams.errors.DataError` line naming the file, the column and the
row: NaN/inf values, time not strictly increasing (repeated or going back), rows or arrays of
different lengths, unknown or missing joints, an empty file, and a revolute joint beyond
``max_angle`` (default 4 pi: "degrees given as radians?"; not a joint the model declares without
position limits, a continuous one) or a prismatic one beyond ``max_travel`` (10 m: millimetres?):
with ``allow_units`` these two are a warning note instead. A continuous joint logged modulo a turn
(in [-pi, pi) or [0, 2 pi), as drivers often report it) is unwrapped: a step of more than pi between
samples is a whole turn, counted in a note (streamed too, across blocks). Rows are named as the
file counts them: text files by file line (1-based) and data row (1-based, the first row after the
header is 1); NPZ and Parquet by 0-based index; bags by the 1-based message number on the topic.

Streamed logs
-------------
:class:`LogStream` reads CSV/TSV and Parquet logs block by block (the same layouts, conversions
and checks, row numbers counted over the whole file), for identification in memory independent of
the log's length (:mod:`baseparams.ident.stream`).
"""

from __future__ import annotations

import contextlib
import csv
import functools
import io
import itertools
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..display import counted
from ..errors import GO_ON, DataError, going_on
from ..files import check_input
from ..jointlog import JointLog
from ..kinematics.floating import BASE_COORDINATES, POSE_COLUMNS, TWIST_COLUMNS
from ..model.robot import Robot

#: suffixes of each kind of log
TEXT_SUFFIXES = (".csv", ".tsv", ".txt")
PARQUET_SUFFIXES = (".parquet", ".pq")
BAG_SUFFIXES = (".mcap", ".db3", ".bag")
#: the signals of a joint, in the default layout's column prefixes
KINDS = ("q", "dq", "ddq", "tau", "cur")
#: joint types whose coordinates are not a log's joint columns (a floating base: its pose columns)
UNLOGGED = ("F",)
#: the largest plausible ``|q|`` of a rotation [rad] and of a translation [m] (degrees? millimetres?)
MAX_ANGLE, MAX_TRAVEL = 4 * np.pi, 10.0

_BAG_FIELDS = {"q": "position", "dq": "velocity", "ddq": "acceleration", "tau": "effort"}
_COLUMN = re.compile(r"^(q|dq|ddq|tau|cur)_(.+)$")


@dataclass
class _Table:
    """Columns read from a file, before they are mapped to joints."""

    source: str
    columns: dict[str, np.ndarray]
    rows: np.ndarray  # the row number shown for each sample
    row_fmt: str  # "{0}" the shown number, "{1}" the 1-based sample
    labels: dict[str, str] = field(default_factory=dict)  # column -> how to name it in a message
    notes: list[str] = field(default_factory=list)
    removed: dict[str, int] = field(default_factory=dict)
    is_bag: bool = False
    booleans: set = field(default_factory=set)  # columns stored as true/false (refused when used)
    text: dict[str, str] = field(default_factory=dict)  # columns that are not numbers -> the error if one is read
    offset: int = 0  # samples before this table's first (a block of a streamed log: row numbers stay global)
    stamps: np.ndarray | None = None  # a bag's stamps [ns] of each sample (other topics are aligned to them)

    def row(self, i: int) -> str:
        return self.row_fmt.format(int(self.rows[i]), i + 1 + self.offset)

    def label(self, col: str) -> str:
        return self.labels.get(col, f"column {col!r}")


@dataclass
class _Joint:
    """How one model joint is read: its columns and the conversion to the joint side."""

    joint: str
    jtype: str
    cols: dict[str, str | None]
    sign: float = 1.0
    ratio: float = 1.0
    gain: float = 1.0
    offset: float = 0.0
    unbounded: bool = False  # a revolute joint the model declares without position limits (continuous)


def read_log(path, robot: Robot, columns=None, *, allow_subset: bool = False,
             max_angle: float | None = MAX_ANGLE, max_travel: float | None = MAX_TRAVEL, require_tau: bool = True,
             require_time: bool = True, allow_units: bool = False) -> JointLog:
    """Read a joint log and map it to the model's joints.

    Parameters
    ----------
    path : str or Path
        The log: ``.csv``/``.tsv``/``.txt``, ``.npz``, ``.parquet``/``.pq``, a rosbag2 folder
        (with ``metadata.yaml``), ``.mcap``, ``.db3`` or ``.bag``. Formats: the module docstring.
    robot : Robot
        The model; its coordinates' names name the columns (:meth:`Robot.coordinate_names`), and
        each coordinate's kind (a rotation or a translation) says which plausibility check applies.
    columns : str, Path or dict, optional
        A mapping (TOML file or dict; see the module docstring) for any other layout, or, for
        a bag, the JointState topic to read. Default: the default layout, the first JointState
        topic.
    allow_subset : bool, optional
        Accept a log that covers only some of the model's coordinates (default: every one must
        be there, a floating base's excepted).
    max_angle : float or None, optional
        Largest plausible ``|q|`` of a revolute joint [rad] (default 4 pi, beyond which the
        values look like degrees); ``None`` disables the check. Not applied to a joint the model
        declares without position limits (a URDF ``continuous`` joint, an MJCF hinge without
        ``range``: its ``Robot.limits`` lower and upper NaN): any angle, any number of turns.
    max_travel : float or None, optional
        Largest plausible ``|q|`` of a prismatic joint [m] (default 10, beyond which the values
        look like millimetres); ``None`` disables the check.
    require_tau : bool, optional
        Every joint read must have a ``tau`` column (default). ``False``: states only (a
        trajectory to predict torques of, states for a regressor); ``tau`` is then ``None`` when
        no joint has one.
    require_time : bool, optional
        The time column must be there (default). ``False``: without one, ``t`` is the sample
        index ``0, 1, ...`` and a note says so.
    allow_units : bool, optional
        A position beyond ``max_angle`` or ``max_travel`` (degrees? millimetres?) is a warning
        note, not a refusal (``--allow-units``: go on anyway).

    Returns
    -------
    JointLog
        Time ``t (S,)`` [s], ``q, tau (S, m)`` on the joint side in the model's joint order,
        ``dq, ddq`` when the log has them, the notes of the reading.

    Raises
    ------
    DataError
        One line naming the file, the column and the row, for any problem listed in the module
        docstring (and a missing optional package: the extra to install).
    """
    from ..arguments import ArgumentTypeError, Range, check_flags, check_path, check_value

    if not isinstance(robot, Robot):
        raise ArgumentTypeError(f"read_log: robot must be a Robot (baseparams.load(...)), got {type(robot).__name__}")
    check_path(path, "read_log: path")
    check_flags("read_log", allow_subset=allow_subset, require_tau=require_tau, require_time=require_time,
                allow_units=allow_units)
    for name, bound in (("max_angle", max_angle), ("max_travel", max_travel)):
        if bound is not None:
            check_value(bound, name, r=Range(0, 1e12, lo_open=True))
    p = check_input(path, folder_ok=True, error=DataError)  # a file or a bag folder, never a device or FIFO
    spec = _mapping(columns)
    kind = _kind(p)
    if kind == "bag":
        table = _read_bag(p, spec, robot.floating)
    else:
        for key in ("topic", "base_topic"):
            if spec[key] is not None:
                raise DataError(f"{spec['label']}: {key!r} applies to ROS bags only, not to {p.name}")
        if kind == "text":
            table = _read_text(p)
        else:  # the header first (names, rows, declared sizes): only the columns read are loaded, bounded
            header = _npz_header(p) if kind == "npz" else _parquet_header(p)
            joints = _resolve(header.empty(), robot, spec, allow_subset, require_tau)
            used = _layout_columns(header.names, spec, joints, robot)
            header.check_size(used)
            table = header.read(used, spec["time"])
    joints = _resolve(table, robot, spec, allow_subset, require_tau)
    base = _base_columns(table, robot)
    log = _assemble(table, joints, spec, (max_angle, max_travel, allow_units), require_time, base)
    return _with_base(table, log, base) if base else log


def _layout_columns(names: list[str], spec: dict, joints: list[_Joint], robot: Robot) -> list[str]:
    """The columns of a file the layout reads, of those it has: time, the joints', a floating base's pose and twist.

    A fixed robot's log may hold a base pose too: read to check that it does not move
    (:func:`_check_still_base`).

    One list for every reader that loads columns by name (NPZ, Parquet, streamed), so that each
    format reads what a text file read whole offers (:func:`_base_columns` then checks them).
    """
    base = (*POSE_COLUMNS, *TWIST_COLUMNS) if robot.floating else POSE_COLUMNS  # fixed: checked to be still
    cols = [spec["time"], *(c for x in joints for c in x.cols.values() if c), *base]
    have = set(names)
    return [c for c in dict.fromkeys(cols) if c in have]


def _kind(p: Path) -> str:
    """The reader for a path: ``text``, ``npz``, ``parquet`` or ``bag``."""
    suffix = p.suffix.lower()
    if p.is_dir():
        if (p / "metadata.yaml").exists():
            return "bag"
        raise DataError(f"{p}: a folder without metadata.yaml (not a rosbag2 recording)")
    if suffix in TEXT_SUFFIXES:
        return "text"
    if suffix == ".npz":
        return "npz"
    if suffix in PARQUET_SUFFIXES:
        return "parquet"
    if suffix in BAG_SUFFIXES:
        return "bag"
    known = ", ".join(TEXT_SUFFIXES + (".npz",) + PARQUET_SUFFIXES + BAG_SUFFIXES)
    raise DataError(f"{p}: unknown log type {suffix!r}; expected {known} or a rosbag2 folder")


# ---------------------------------------------------------------- the mapping
def _mapping(columns) -> dict:
    """The mapping as a checked dict: ``time, time_scale, topic, joints, label``."""
    from .. import schema

    label = "columns="
    if columns is None:
        raw: dict = {}
    elif isinstance(columns, (str, Path)) and Path(columns).suffix.lower() == ".toml":
        label = str(columns)
        raw = schema.read_toml(columns, "a valid TOML mapping", schema.COLUMNS_MAX_BYTES, error=DataError)
    elif isinstance(columns, str):
        raw = {"topic": columns}
    elif isinstance(columns, Mapping):
        raw = dict(columns)
    else:
        raise DataError(f"columns=: expected a TOML file, a dict or a topic name, got {type(columns).__name__}")
    return _check_mapping(raw, label)


def _check_mapping(raw: dict, label: str) -> dict:
    """Check the keys and values of a mapping against :data:`baseparams.schema.COLUMNS` (one line, naming the key)."""
    from .. import schema

    spec = schema.check(raw, schema.COLUMNS, label, error=DataError)[0]
    joints = {j: {k: v for k, v in e.items() if v is not None and (k in raw["joints"][j])}
              for j, e in spec["joints"].items()}
    return {"time": spec["time"], "time_scale": spec["time_scale"], "topic": spec["topic"],
            "base_topic": spec["base_topic"], "joints": joints, "label": label,
            "explicit_time": "time" in raw or "time_scale" in raw}


# ---------------------------------------------------------------- text tables
def _read_text(path: Path) -> _Table:
    """A delimited text table with a header row (delimiter sniffed); blank and ``#`` lines skipped."""
    size = path.stat().st_size
    if size > TEXT_MAX_BYTES:
        raise DataError(_too_large(path, f"{size / 2**20:.0f} MB of text"))
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: not a UTF-8 text file (byte {exc.start})") from None
    except OSError as exc:
        raise DataError(f"{path}: cannot read ({exc.strerror or exc})") from None
    lines = text.splitlines()
    stripped = list(map(str.strip, lines))
    keep = np.fromiter(map(bool, stripped), bool, len(lines))
    keep &= ~np.fromiter(map(str.startswith, stripped, itertools.repeat("#")), bool, len(lines))
    numbers = np.flatnonzero(keep) + 1  # file line numbers, 1-based
    if len(numbers) == 0:
        raise DataError(f"{path}: empty file (expected a header row and data rows)")
    kept = list(itertools.compress(stripped, keep))
    delim = _sniff(kept[0], path.suffix.lower())
    if delim is None:  # runs of blanks: one space each
        blanks = re.compile(r"[ \t]+")
        kept = list(map(functools.partial(blanks.sub, " "), kept))
        delim = " "
    names = [n.strip() for n in next(csv.reader([kept[0]], delimiter=delim, skipinitialspace=True))]
    _check_header(path, names, numbers[0])
    data = kept[1:]
    if not data:
        raise DataError(f"{path}: no data rows after the header (line {numbers[0]})")
    counts = np.fromiter(map(str.count, data, itertools.repeat(delim)), int, len(data)) + 1
    if np.any(bad := counts != len(names)):
        i = int(np.argmax(bad))
        raise DataError(f"{path}: line {numbers[i + 1]} (data row {i + 1}): {counts[i]} fields, the header has "
                        f"{len(names)} (columns of different lengths; {counted(bad.sum(), 'such row')})")
    values, text_columns = _parse_numbers(path, data, delim, names, numbers[1:])
    table = _Table(str(path), {n: values[:, k] for k, n in enumerate(names)}, numbers[1:],
                   "line {0} (data row {1})", text=text_columns)
    skipped = len(lines) - len(numbers)
    table.notes.append(f"{path.name}: {counted(len(data), 'row')}, delimiter {_delim_name(delim)}"
                       + (f"; {counted(skipped, 'blank or comment line')} skipped" if skipped else ""))
    return table


def _sniff(header: str, suffix: str) -> str | None:
    """The delimiter, from the header row: tab for ``.tsv``, else the most frequent of ``, ; tab |``.

    ``None`` (runs of blanks) when the header has none of them. The header decides, not the data
    rows, so a malformed data row cannot change the reading of the others.
    """
    if suffix == ".tsv" and "\t" in header:
        return "\t"
    counts = {d: header.count(d) for d in (",", "\t", ";", "|")}
    best = max(counts, key=counts.__getitem__)
    return best if counts[best] else None


def _delim_name(delim: str) -> str:
    return {"\t": "tab", " ": "blanks"}.get(delim, repr(delim))


def _check_header(path: Path, names: list[str], line: int) -> None:
    """Header names: none empty, none repeated, not numbers (a header row is required), not too many."""
    if len(names) > MAX_COLUMNS:
        raise DataError(f"{path}: line {line} (header): {len(names)} columns, more than a joint log has (at most "
                        f"{MAX_COLUMNS})")
    for k, n in enumerate(names):
        if not n:
            raise DataError(f"{path}: line {line} (header): column {k + 1} has no name")
        if re.fullmatch(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|nan|inf", n, re.IGNORECASE):
            raise DataError(f"{path}: line {line}: the first row is numbers ({n!r}), expected a header row of "
                            "column names")
    seen: dict[str, int] = {}
    for k, n in enumerate(names):
        if n in seen:
            raise DataError(f"{path}: line {line} (header): column {n!r} appears twice (columns {seen[n] + 1} "
                            f"and {k + 1})")
        seen[n] = k


def _parse_numbers(path: Path, data: list[str], delim: str, names: list[str], numbers: np.ndarray,
                   first_row: int = 1) -> tuple[np.ndarray, dict[str, str]]:
    """``(S, columns)`` floats and ``{column: message}`` for columns that are not all numbers.

    Such a column (a ``comment`` column) is NaN here; its message (naming the first cell that is
    not a number) is the error only if the layout reads the column. ``first_row``: the data row
    number of ``data[0]`` (a block of a streamed file).
    """
    try:
        return np.loadtxt(data, delimiter=delim, dtype=float, comments=None, ndmin=2, encoding=None), {}
    except ValueError:
        pass
    cells = np.loadtxt(data, delimiter=delim, dtype=str, comments=None, ndmin=2, encoding=None)
    values = np.full(cells.shape, np.nan)
    text: dict[str, str] = {}
    for k, n in enumerate(names):  # a loop over columns; bisection over rows
        col = np.char.strip(cells[:, k])
        if _floats_ok(col):
            values[:, k] = col.astype(float)
            continue
        lo, hi = 0, len(col)
        while hi - lo > 1:
            mid = (lo + hi) // 2
            lo, hi = (mid, hi) if _floats_ok(col[lo:mid]) else (lo, mid)
        value = str(col[lo])
        hint = " (decimal comma?)" if "," in value and delim != "," else ""
        what = "an empty field" if not value else f"{value!r} is not a number{hint}"
        text[n] = f"{path}: column {n!r}, line {numbers[lo]} (data row {lo + first_row}): {what}"
    return values, text


def _floats_ok(col: np.ndarray) -> bool:
    try:
        col.astype(float)
    except ValueError:
        return False
    return True


# ---------------------------------------------------------------- NPZ and Parquet
def _table_of_arrays(path: Path, columns: dict[str, np.ndarray], row_fmt: str, what: str) -> _Table:
    """A table from named columns: at least one, all of one nonzero length."""
    if not columns:
        raise DataError(f"{path}: empty file (no {what}s)")
    first, n = next((k, len(v)) for k, v in columns.items())
    for k, v in columns.items():
        if len(v) != n:
            raise DataError(f"{path}: {what} {k!r} has {counted(len(v), 'row')}, {what} {first!r} has {n} (columns of "
                            "different lengths)")
    if n == 0:
        raise DataError(f"{path}: no data rows (every {what} is empty)")
    table = _Table(str(path), columns, np.arange(n), row_fmt,
                   labels={k: f"{what} {k!r}" for k in columns})
    table.notes.append(f"{path.name}: {counted(n, 'row')}, {counted(len(columns), what)}")
    return table


#: the most columns a log may have (a robot's joints times four, and other signals)
MAX_COLUMNS = 10_000
#: the most rows a log may have, streamed or not (5e7: 14 hours at 1 kHz)
MAX_ROWS = 50_000_000
#: the largest log read whole [bytes]: the columns read, as float64 (larger: stream it)
WHOLE_MAX_BYTES = 256 * 2**20
#: the largest text log read whole [bytes of file] (reading text takes about 3 times its size; the CLI streams
#: text logs above 64 MB)
TEXT_MAX_BYTES = 2**30


def _too_large(path: Path, what: str) -> str:
    return (f"{path}: {what}, more than is read whole ({WHOLE_MAX_BYTES / 2**20:.0f} MB of numbers); stream it: "
            f"CSV/TSV, NPZ or Parquet with 'identify --stream on' (baseparams.ident.stream.identify_stream in Python)")


@dataclass
class _Header:
    """A columnar log's header (NPZ members, Parquet schema): names, rows, how to read some columns."""

    path: Path
    names: list[str]
    rows: int
    what: str  # "array" or "column"
    reader: object  # (names, time column) -> (columns, booleans, notes)
    row_fmt: str

    def __post_init__(self):
        if not self.names:
            raise DataError(f"{self.path}: empty file (no {self.what}s)")

    def empty(self) -> _Table:
        return _Table(str(self.path), {n: np.empty(0) for n in self.names}, np.empty(0, int), self.row_fmt,
                      labels={n: f"{self.what} {n!r}" for n in self.names})

    def check_size(self, used: list[str]) -> None:
        need = self.rows * max(len(used), 1) * 8
        if need > WHOLE_MAX_BYTES:
            raise DataError(_too_large(self.path, f"{self.rows} rows x {len(used)} {self.what}s read "
                                                  f"({need / 2**20:.0f} MB)"))

    def read(self, used: list[str], time: str) -> _Table:
        columns, booleans, notes = self.reader(used, time)
        table = _table_of_arrays(self.path, columns, self.row_fmt, self.what) if columns else self.empty()
        table.booleans, table.notes = set(booleans), table.notes + notes
        unused = [n for n in self.names if n not in columns]
        if unused:
            more = f" and {len(unused) - 12} more" if len(unused) > 12 else ""
            table.notes.append(f"{self.path.name}: {self.what}s not loaded (not read by the layout): "
                               f"{', '.join(unused[:12])}{more}")
        return table


def _check_counts(path: Path, columns: int, rows: int, what: str) -> None:
    if columns > MAX_COLUMNS:
        raise DataError(f"{path}: {columns} {what}s, more than a joint log has (at most {MAX_COLUMNS})")
    if rows > MAX_ROWS:
        raise DataError(f"{path}: {rows} rows, more than a log may have (at most {MAX_ROWS}: "
                        f"{MAX_ROWS / 3.6e6:.3g} hours at 1 kHz); split it")


def _integer_time(name: str, values: np.ndarray, notes: list[str], path: Path, first=None) -> np.ndarray:
    """Integer time stamps beyond float's exact range (epoch nanoseconds): counted from the first, exactly.

    ``first``: the stamp counted from (default the first of ``values``). Other stamps: as floats.
    """
    if values.dtype.kind in "iu" and len(values) and max(abs(int(values.min())), abs(int(values.max()))) > 2**53:
        first = int(values[0]) if first is None else int(first)
        if values.dtype.kind == "u":  # uint64 beyond int64: exact differences in Python integers, then floats
            out = np.array([int(v) - first for v in values.tolist()], dtype=float)
        else:
            out = (values.astype(np.int64) - np.int64(first)).astype(float)
        notes.append(f"{path.name}: {name!r} holds integer stamps up to {int(values.max())}: counted from the first "
                     f"one ({first}), exactly")
        return out
    return values.astype(float)


def _npz_header(path: Path) -> _Header:
    """An .npz log's members from the zip directory and each .npy header, checked before any array is read."""
    import zipfile

    members, rows = _npz_members(path)

    def read(used, time):
        columns, booleans, notes = {}, [], []
        with zipfile.ZipFile(path) as zz:
            for col in used:
                info, offset, dtype, n = members[col]
                with zz.open(info) as fh:
                    fh.read(offset)
                    raw = fh.read(n * dtype.itemsize)
                a = np.frombuffer(raw, dtype=dtype, count=n)
                if dtype.kind == "b":
                    booleans.append(col)
                columns[col] = _integer_time(col, a, notes, path) if col == time else a.astype(float)
        return columns, booleans, notes

    return _Header(path, list(members), int(rows or 0), "array", read, "index {0} (0-based)")


def _npz_members(path: Path) -> tuple[dict, int | None]:
    """An .npz log's checked members ``{column: (ZipInfo, data offset, dtype, length)}`` and its row count."""
    import zipfile

    try:
        z = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, ValueError, EOFError) as exc:
        raise DataError(f"{path}: not a readable .npz archive ({_first_line(exc)})") from None
    with z:
        infos = z.infolist()
        _check_counts(path, len(infos), 0, "array")
        members, rows = {}, None
        for info in infos:
            name = info.filename
            if not name.endswith(".npy") or info.is_dir():
                raise DataError(f"{path}: member {name!r} is not a NumPy array (.npy); an .npz log holds one array "
                                "per column")
            col = name[:-4]
            try:
                with z.open(info) as fh:
                    version = np.lib.format.read_magic(fh)
                    if version not in ((1, 0), (2, 0)):
                        raise ValueError(f"format version {version} (1.0 and 2.0 are read)")
                    read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else \
                        np.lib.format.read_array_header_2_0
                    shape, fortran, dtype = read_header(fh, max_header_size=10_000)
                    offset = fh.tell()
            except Exception as exc:  # noqa: BLE001 - zipfile, numpy: one line whatever they raise
                raise DataError(f"{path}: member {name!r} is not a NumPy array ({_first_line(exc)})") from None
            if dtype.hasobject:
                raise DataError(f"{path}: array {col!r} holds Python objects (not read)")
            if dtype.kind not in "biuf":
                raise DataError(f"{path}: array {col!r} holds {dtype} values, expected numbers")
            if len(shape) != 1:
                raise DataError(f"{path}: array {col!r} has shape {shape}; expected one value per sample (S,)")
            size = shape[0] * dtype.itemsize
            if size != info.file_size - offset:
                raise DataError(f"{path}: array {col!r}: its header claims {shape[0]} values ({size} bytes), the "
                                f"member holds {info.file_size - offset} bytes")
            _check_counts(path, len(infos), shape[0], "array")
            members[col] = (info, offset, dtype, shape[0])
            rows = shape[0] if rows is None else rows
    return members, rows


def _parquet_header(path: Path) -> _Header:
    """A Parquet log's schema and row count from its footer, checked before any column is read."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise DataError(f"{path}: reading Parquet needs pyarrow: pip install 'baseparams[parquet]'") from None
    try:
        meta = pq.read_metadata(path)
        _check_counts(path, meta.num_columns, meta.num_rows, "column")
        schema = meta.schema.to_arrow_schema()
    except DataError:
        raise
    except Exception as exc:  # pyarrow's errors: one line
        raise DataError(f"{path}: not a readable Parquet file ({_first_line(exc)})") from None
    names = list(schema.names)

    def read(used, time):
        try:
            table = pq.read_table(path, columns=used)
        except Exception as exc:  # pyarrow's errors: one line
            raise DataError(f"{path}: not a readable Parquet file ({_first_line(exc)})") from None
        batch = pa.RecordBatch.from_arrays([c.combine_chunks() for c in table.columns], names=table.column_names) \
            if table.num_columns else None
        if batch is None:
            return {}, [], []
        columns, booleans, notes = _arrow_columns(path, batch, 0, time)
        return columns, booleans, notes

    return _Header(path, names, int(meta.num_rows), "column", read, "row {0} (0-based)")


def _names(names: list[str], most: int = 12) -> str:
    """Names joined by commas, the first ``most`` of them."""
    more = f" and {len(names) - most} more" if len(names) > most else ""
    return ", ".join(names[:most]) + more


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip() or type(exc).__name__
    return text.splitlines()[0].strip()


# ---------------------------------------------------------------- ROS bags
def _read_bag(path: Path, spec: dict, floating: bool = False) -> _Table:
    """JointState messages of one topic: per message name, stamps, position, velocity, effort.

    With ``floating``, a floating base's pose and twist from a ``nav_msgs/msg/Odometry`` topic too
    (:func:`_bag_base`).
    """
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise DataError(f"{path}: reading ROS bags needs rosbags: pip install 'baseparams[ros]'") from None
    if spec["explicit_time"]:
        raise DataError(f"{spec['label']}: time and time_scale do not apply to bags (time is the header stamp)")
    notes: list[str] = []
    odom = None
    try:
        with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
            con = _joint_state_topic(path, reader.connections, spec["topic"], notes)
            msgs = [(stamp, reader.deserialize(raw, c.msgtype))
                    for c, stamp, raw in reader.messages(connections=[con])]
            ocon = _odometry_topic(path, reader.connections, spec["base_topic"]) if floating else None
            if ocon is not None:
                odom = (ocon.topic, [(stamp, reader.deserialize(raw, c.msgtype))
                                     for c, stamp, raw in reader.messages(connections=[ocon])])
    except DataError:
        raise
    except Exception as exc:  # rosbags' reader and deserialiser errors: one line
        raise DataError(f"{path}: cannot read the bag ({_first_line(exc)})") from None
    if not msgs:
        raise DataError(f"{path}: topic {con.topic!r} has no messages")
    wanted = [e.get("name", j) for j, e in spec["joints"].items()] or None
    table = _bag_table(path, con.topic, msgs, wanted)
    table.notes[:0] = notes
    return _bag_base(path, table, *odom) if odom is not None else table


#: the message a bag carries a floating base in: pose in ``header.frame_id`` (the world), twist in
#: ``child_frame_id`` (the base), as REP 105 and the module docstring's base columns
ODOMETRY = "nav_msgs/msg/Odometry"


def _odometry_topic(path: Path, connections, topic: str | None):
    """The base's odometry connection: the named topic, else the first Odometry topic, else None."""
    if topic is not None:
        named = [c for c in connections if c.topic == topic]
        if not named:
            raise DataError(f"{path}: no topic {topic!r} (base_topic); topics: "
                            f"{', '.join(sorted({c.topic for c in connections}))}")
        if named[0].msgtype != ODOMETRY:
            raise DataError(f"{path}: topic {topic!r} (base_topic) carries {named[0].msgtype}, not {ODOMETRY}")
        return named[0]
    return next((c for c in connections if c.msgtype == ODOMETRY), None)


def _bag_base(path: Path, table: _Table, topic: str, msgs: list) -> _Table:
    """A floating base's columns (module docstring) from Odometry messages, at the JointState stamps.

    A JointState stamp that is an odometry stamp takes its values exactly; one between two is
    interpolated (position and twist linearly, the quaternion normalised); JointState messages
    outside the odometry's span are removed and counted.
    """
    if not msgs:
        raise DataError(f"{path}: topic {topic!r} ({ODOMETRY}, the floating base) has no messages")
    notes: list[str] = []
    ns = _bag_stamps(path, msgs, np.arange(len(msgs)), notes)
    bad = np.diff(ns) <= 0
    if bad.any():
        i = int(np.argmax(bad)) + 1
        raise DataError(f"{path}: header stamp on {topic}, message {i + 1}: {'repeats' if ns[i] == ns[i - 1] else 'is'}"
                        f"{'' if ns[i] == ns[i - 1] else ' before'} the one before; time must be strictly increasing")
    pose = [m.pose.pose for _, m in msgs]
    twist = [m.twist.twist for _, m in msgs]
    values = np.array([[p.position.x, p.position.y, p.position.z, p.orientation.w, p.orientation.x,
                        p.orientation.y, p.orientation.z, v.linear.x, v.linear.y, v.linear.z, v.angular.x,
                        v.angular.y, v.angular.z] for p, v in zip(pose, twist)], dtype=float)
    at = table.stamps
    inside = (at >= ns[0]) & (at <= ns[-1])
    if not inside.any():
        raise DataError(f"{path}: the base odometry on {topic} and the JointState messages do not overlap in time")
    if (out := int((~inside).sum())):
        table.removed[f"JointState messages outside the base odometry's time span ({topic})"] = out
        table.notes.append(f"{path.name}: {out} JointState messages outside the time span of {topic}: removed")
        table.columns = {k: v[inside] for k, v in table.columns.items()}
        table.rows, at = table.rows[inside], at[inside]
    hi = np.searchsorted(ns, at)
    exact = ns[np.minimum(hi, len(ns) - 1)] == at
    lo = np.maximum(hi - 1, 0)
    w = np.where(exact, 0.0, (at - ns[lo]) / np.maximum(ns[hi.clip(max=len(ns) - 1)] - ns[lo], 1))[:, None]
    a, b = values[lo], values[np.minimum(hi, len(ns) - 1)]
    b[:, 3:7] *= np.where(np.sum(a[:, 3:7] * b[:, 3:7], axis=1) < 0, -1.0, 1.0)[:, None]  # the nearer sign
    mixed = (1 - w) * a + w * b
    mixed[:, 3:7] /= np.linalg.norm(mixed[:, 3:7], axis=1, keepdims=True)
    mixed[exact] = values[hi[exact]]
    names = list(POSE_COLUMNS) + (list(TWIST_COLUMNS) if np.any(values[:, 7:]) else [])
    fields = ["pose.pose.position." + c for c in "xyz"] + ["pose.pose.orientation." + c for c in "wxyz"] + \
        ["twist.twist.linear." + c for c in "xyz"] + ["twist.twist.angular." + c for c in "xyz"]
    for k, n in enumerate(names):
        table.columns[n] = mixed[:, k]
        table.labels[n] = f"{fields[k]} on {topic}"
    table.notes += notes + [f"{path.name}: floating base from {topic} ({ODOMETRY}: pose in the world frame, twist in "
                            "the base frame)" + ("" if exact.all() else f"; interpolated at {int((~exact).sum())} "
                                                 "JointState stamps between two of its own")
                            + ("" if len(names) > len(POSE_COLUMNS) else "; its twist is zero: not read")]
    return table


def _joint_state_topic(path: Path, connections, topic: str | None, notes: list[str]):
    """The connection to read: the named topic, else the first JointState topic."""
    states = [c for c in connections if c.msgtype == "sensor_msgs/msg/JointState"]
    if topic is not None:
        named = [c for c in connections if c.topic == topic]
        if not named:
            raise DataError(f"{path}: no topic {topic!r}; topics: {', '.join(sorted({c.topic for c in connections}))}")
        if named[0].msgtype != "sensor_msgs/msg/JointState":
            raise DataError(f"{path}: topic {topic!r} carries {named[0].msgtype}, not sensor_msgs/msg/JointState")
        return named[0]
    if not states:
        found = ", ".join(f"{c.topic} ({c.msgtype})" for c in connections) or "none"
        raise DataError(f"{path}: no sensor_msgs/msg/JointState topic; topics: {found}")
    others = sorted({c.topic for c in states} - {states[0].topic})
    notes.append(f"{path.name}: JointState topic {states[0].topic} (default: the first)"
                 + (f"; also on {', '.join(others)} (columns= picks one)" if others else ""))
    return states[0]


def _bag_table(path: Path, topic: str, msgs: list, wanted: list[str] | None) -> _Table:
    """Columns ``t, q_<name>, dq_<name>, tau_<name>`` from JointState messages.

    Messages are grouped by their ``name[]`` list; messages lacking a wanted name are removed
    (counted). ``wanted`` defaults to every name on the topic.
    """
    keys = [tuple(m.name) for _, m in msgs]
    groups = list(dict.fromkeys(keys))
    code = {g: i for i, g in enumerate(groups)}
    gid = np.fromiter(map(code.__getitem__, keys), int, len(keys))
    names = wanted or list(dict.fromkeys(n for g in groups for n in g))
    full = [i for i, g in enumerate(groups) if set(names) <= set(g)]
    if not full:
        sets = "; ".join(f"[{', '.join(g)}] x{int((gid == i).sum())}" for i, g in enumerate(groups[:4]))
        raise DataError(f"{path}: topic {topic!r}: no message has all of the joints {', '.join(names)} (messages "
                        f"carry: {sets}); name the joints to read with columns=")
    keep = np.isin(gid, full)
    sel = np.flatnonzero(keep)
    table = _Table(str(path), {}, sel + 1, "message {0}", is_bag=True)
    if (dropped := int((~keep).sum())):
        table.removed["JointState messages without every joint read"] = dropped
        table.notes.append(f"{path.name}: {dropped} messages on {topic} lack some of the joints read: removed")
    table.columns["t"], table.stamps = _bag_time(path, msgs, sel, table.notes)
    for kind, fld in (("q", "position"), ("dq", "velocity"), ("tau", "effort")):
        block = _bag_field(path, topic, msgs, fld, groups, gid, sel, names, table.notes)
        for k, n in enumerate(names):
            table.labels[f"{kind}_{n}"] = f"{fld}[{n!r}] on {topic}"
            if block is not None:
                table.columns[f"{kind}_{n}"] = block[:, k]
    table.labels["t"] = f"header stamp on {topic}"
    table.notes.append(f"{path.name}: {len(sel)} JointState messages on {topic}")
    return table


def _bag_field(path, topic, msgs, fld, groups, gid, sel, names, notes) -> np.ndarray | None:
    """``(K, len(names))`` values of one JointState field, or None when some message lacks it."""
    arrays = [np.asarray(getattr(msgs[i][1], fld), dtype=float) for i in sel]
    lengths = np.fromiter(map(len, arrays), int, len(arrays))
    expect = np.array([len(groups[g]) for g in gid[sel]])
    wrong = (lengths != expect) & (lengths != 0)
    if wrong.any():
        i = int(np.argmax(wrong))
        raise DataError(f"{path}: topic {topic!r}, message {sel[i] + 1}: {lengths[i]} {fld} values for "
                        f"{expect[i]} names")
    if np.all(lengths == 0):
        return None
    if np.any(lengths == 0):
        notes.append(f"{path.name}: {int((lengths == 0).sum())} messages on {topic} have no {fld}: {fld} not read")
        return None
    out = np.empty((len(sel), len(names)))
    for g in np.unique(gid[sel]):  # a loop over the distinct name lists, not over messages
        rows = np.flatnonzero(gid[sel] == g)
        order = [groups[g].index(n) for n in names]
        out[rows] = np.stack([arrays[r] for r in rows])[:, order]
    return out


def _bag_stamps(path: Path, msgs: list, sel: np.ndarray, notes: list[str]) -> np.ndarray:
    """Header stamps [ns] of the selected messages; the record time when every stamp is zero."""
    sec = np.array([msgs[i][1].header.stamp.sec for i in sel], dtype=np.int64)
    nsec = np.array([msgs[i][1].header.stamp.nanosec for i in sel], dtype=np.int64)
    ns = sec * 1_000_000_000 + nsec
    if not ns.any():
        ns = np.array([msgs[i][0] for i in sel], dtype=np.int64)
        notes.append(f"{path.name}: every header stamp is zero: time is the bag's record time")
    return ns


def _bag_time(path: Path, msgs: list, sel: np.ndarray, notes: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Time [s] from the first stamp (:func:`_bag_stamps`), and the stamps [ns]."""
    ns = _bag_stamps(path, msgs, sel, notes)
    notes.append(f"{path.name}: t = 0 at the first stamp ({ns[0] // 1_000_000_000}.{ns[0] % 1_000_000_000:09d} s)")
    return (ns - ns[0]) * 1e-9, ns


# ---------------------------------------------------------------- joints and conversion
def coordinate_kinds(robot: Robot) -> dict[str, str]:
    """Each coordinate a log holds, by its column name (:meth:`Robot.coordinate_names`), and its kind.

    Parameters
    ----------
    robot : Robot
        The model.

    Returns
    -------
    dict of str to str
        ``{name: "R" or "P"}`` in the model's order: a rotation (rad) or a translation (m); a
        floating base's coordinates are left out (its pose columns, module docstring).

    """
    names = robot.coordinate_names(np.arange(robot.dof))
    slide = np.linalg.norm(robot.local_screws[:, :3], axis=1) == 0.0
    types = np.asarray(robot.jtype)[robot.dof_body]
    return {n: ("P" if s else "R") for n, s, t in zip(names, slide, types) if t not in UNLOGGED}


def _resolve(table: _Table, robot: Robot, spec: dict, allow_subset: bool, require_tau: bool = True) -> list[_Joint]:
    """The coordinates of the log in the model's order, with their columns, checked against the model."""
    jtypes = coordinate_kinds(robot)
    loggable = list(jtypes)
    entries = spec["joints"] or _detect(table, robot, jtypes, loggable)
    for j in entries:
        if j not in jtypes:
            raise DataError(f"{spec['label']}: joints.{j}: robot {robot.name!r} has no joint {j!r} (joints: "
                            f"{_names(loggable)})")
    required = loggable
    if robot.has_loops or robot.couplings:  # the measured joints are the independent (actuated) ones
        ind = robot.independent if robot.independent is not None else range(robot.dof)
        actuated = set(robot.coordinate_names(np.asarray(ind, dtype=int)))
        required = [j for j in loggable if j in actuated]
    missing = [j for j in required if j not in entries]
    if missing and not allow_subset:
        where = (f"not in the mapping {spec['label']}" if spec["joints"] else
                 "no columns (expected q_<joint> and tau_<joint> each)")
        raise DataError(f"{table.source}: joints {_names(missing)} of robot {robot.name!r}: {where}; "
                        "to identify a sub-chain: --joints A,B,... on the command line (allow_subset=True in Python)")
    out = []
    unbounded = unbounded_joints(robot)
    for j in [j for j in loggable if j in entries]:
        e = entries[j]
        base = e.get("name", j)
        cols = {k: e.get(k, f"{k}_{base}") for k in KINDS}
        for k in KINDS:  # a joint that logs its motor's current needs no torque
            required = k == "q" or (k == "tau" and require_tau and cols["cur"] not in table.columns)
            if cols[k] not in table.columns and (required or k in e):
                need = "required" if required else "named in the mapping"
                raise DataError(f"{table.source}: no {table.label(cols[k])} for joint {j!r} ({k} is {need})")
            if cols[k] not in table.columns:
                cols[k] = None
        out.append(_Joint(j, jtypes[j], cols, float(e.get("sign", 1)), float(e.get("gear_ratio", 1.0)),
                          float(e.get("torque_gain", 1.0)), float(e.get("offset", 0.0)), j in unbounded))
    if not out:
        raise DataError(f"{table.source}: no joint of robot {robot.name!r} in the log")
    for k in ("dq", "ddq", "tau", "cur"):  # tau too: a joint logging currents need not have it, but then none
        have = [x.joint for x in out if x.cols[k] is not None]
        if have and len(have) < len(out):
            lack = [x.joint for x in out if x.cols[k] is None]
            raise DataError(f"{table.source}: {k} given for joints {', '.join(have)} but not for "
                            f"{', '.join(lack)} (give it for every joint read, or for none)")
    return out


def unbounded_joints(robot: Robot) -> set[str]:
    """Revolute joints the model declares without position limits (``Robot.limits`` lower and upper NaN).

    A URDF ``continuous`` joint, an MJCF hinge without ``range``: any angle and any number of
    turns is theirs (a wheel, a turntable). A model that says nothing of limits (``limits`` None)
    declares none.

    Parameters
    ----------
    robot : Robot
        The model.

    Returns
    -------
    set of str
        The joints' names.
    """
    if robot.limits is None:
        return set()
    lim = np.asarray(robot.limits, dtype=float)
    body = robot.dof_body
    return {robot.joint_names[body[k]] for k in range(robot.dof)
            if robot.jtype[body[k]] == "R" and np.isnan(lim[k, 0]) and np.isnan(lim[k, 1])}


def _detect(table: _Table, robot: Robot, jtypes: dict, loggable: list[str]) -> dict[str, dict]:
    """Coordinates named by default-layout columns (``q_<joint>`` ...); an unknown one is an error."""
    found: dict[str, dict] = {}
    for col in table.columns:
        m = _COLUMN.match(col)
        if not m:
            continue
        j = m.group(2)
        if j not in jtypes:
            raise DataError(f"{table.source}: {table.label(col)}: {_unknown(robot, j)} (joints: {_names(loggable)})")
        found[j] = {}
    return found


def _unknown(robot: Robot, name: str) -> str:
    """Why a column's joint is not one of the log's: not the robot's, a floating base, or several coordinates."""
    if name not in robot.joint_names:
        return f"robot {robot.name!r} has no joint {name!r}"
    i = robot.joint_names.index(name)
    if robot.jtype[i] in UNLOGGED:
        return f"joint {name!r} is the floating base, logged as its pose columns ({', '.join(POSE_COLUMNS)})"
    coords = robot.coordinate_names(np.flatnonzero(robot.dof_body == i))
    return f"joint {name!r} has {len(coords)} coordinates, logged one column each ({_names(coords)})"


def _assemble(table: _Table, joints: list[_Joint], spec: dict, bounds: tuple,
              require_time: bool = True, base: list[str] = (), turns: dict | None = None) -> JointLog:
    """Check the values (finite, time increasing, plausible) and convert to the joint side.

    ``bounds``: ``(max_angle, max_travel, allow_units)`` (:func:`read_log`); ``turns``: the
    unwrapping of continuous joints carried from the block before (:func:`_unwrap_turns`).
    """
    tcol = spec["time"] if not table.is_bag else "t"
    untimed = tcol not in table.columns and not require_time
    if tcol not in table.columns and not untimed:
        raise DataError(f"{table.source}: no time column {tcol!r} (columns: {', '.join(list(table.columns)[:12])})")
    used = ([] if untimed else [tcol]) + [c for x in joints for c in x.cols.values() if c is not None] + list(base)
    for c in used:
        if c in table.text:
            raise DataError(table.text[c])
    _check_finite(table, used)
    if untimed:
        t = np.arange(len(table.columns[joints[0].cols["q"]]), dtype=float)
        table.notes.append(f"no time column {tcol!r}: samples numbered 0, 1, ...")
    else:
        t = table.columns[tcol] * spec["time_scale"]
        _check_time(table, tcol, t)
    arrays = {}
    for k in KINDS:
        if joints[0].cols[k] is None:
            arrays[k] = None
            continue
        raw = np.stack([table.columns[x.cols[k]] for x in joints], axis=1)
        if k == "q":
            raw = _unwrap_turns(table, joints, raw, {} if turns is None else turns)
        sign = np.array([x.sign for x in joints])
        ratio = np.array([x.ratio for x in joints])
        if k == "tau":
            arrays[k] = raw * (sign * ratio * np.array([x.gain for x in joints]))
        elif k == "cur":  # a current: its gain is what identification finds
            arrays[k] = raw * sign
        else:
            arrays[k] = raw * (sign / ratio) + (np.array([x.offset for x in joints]) if k == "q" else 0.0)
    implausible = _check_plausible(table, joints, arrays["q"], *bounds[:2])
    if implausible and not bounds[2]:
        raise DataError(implausible + GO_ON)
    unused = [c + (" (text)" if c in table.text else "") for c in table.columns if c not in used]
    notes = list(table.notes) + _conversion_notes(joints, spec)
    if implausible:
        notes.append(going_on("units", implausible))
    if unused:
        notes.append(f"{Path(table.source).name}: columns not read: {', '.join(unused[:12])}"
                     + (f" and {len(unused) - 12} more" if len(unused) > 12 else ""))
    return JointLog(t=t, joints=tuple(x.joint for x in joints), q=arrays["q"], tau=arrays["tau"], dq=arrays["dq"],
                    ddq=arrays["ddq"], source=table.source, removed=dict(table.removed), notes=tuple(notes),
                    cur=arrays["cur"])


def _unwrap_turns(table: _Table, joints: list[_Joint], raw: np.ndarray, turns: dict) -> np.ndarray:
    """Positions of continuous joints logged modulo a turn, unwrapped (``raw (S, m)``, a note counting the wraps).

    Every step of more than pi between samples is taken as a wrap of 2 pi (``np.unwrap``). Only joints
    the model declares without position limits (:func:`unbounded_joints`: a URDF ``continuous`` joint,
    an MJCF hinge without ``range``), whose angle is the same modulo a turn (a true step of pi or
    more would be half a turn in one sample: aliased anyway). ``turns``: per joint column, ``(last raw
    value, its shift)`` of the block before, updated (a streamed log unwraps across its blocks).
    """
    out = raw
    for k, x in enumerate(joints):
        if not x.unbounded:
            continue
        col = raw[:, k]
        last, shift = turns.get(k, (col[0], 0.0))
        seq = np.concatenate([[last], col])
        wraps = int(np.count_nonzero(np.abs(np.diff(seq)) > np.pi))
        if wraps or shift:
            if out is raw:
                out = raw.copy()
            out[:, k] = np.unwrap(seq)[1:] + shift
        if wraps:
            table.notes.append(f"{table.label(x.cols['q'])}: continuous joint {x.joint!r} logged modulo a turn: "
                               f"unwrapped ({counted(wraps, 'step')} of more than pi between samples taken as whole "
                               f"turns, {table.row(0)} to {table.row(len(col) - 1)})")
        turns[k] = (col[-1], out[-1, k] - col[-1])
    return out


def _base_columns(table: _Table, robot: Robot) -> list[str]:
    """A floating base's pose columns and, when all six are there, its twist columns (else ``[]``)."""
    if not robot.floating:
        _check_still_base(table, robot)
        return []
    clash = [j for j in robot.joint_names if j in BASE_COORDINATES]
    if clash:
        raise DataError(f"{table.source}: robot {robot.name!r} has a joint named {clash[0]!r}, the name of a floating "
                        f"base coordinate in a log; rename the joint")
    missing = [c for c in POSE_COLUMNS if c not in table.columns]
    if missing and table.is_bag:
        raise DataError(f"{table.source}: robot {robot.name!r} has a floating base: the bag needs its pose and twist "
                        f"on a {ODOMETRY} topic (pose in the world frame, twist in the base frame; base_topic= "
                        "names it)")
    if missing:
        raise DataError(f"{table.source}: robot {robot.name!r} has a floating base: the log needs its pose, columns "
                        f"{', '.join(POSE_COLUMNS)} (position [m] and unit quaternion, world frame); missing "
                        f"{', '.join(missing)}")
    twist = [c for c in TWIST_COLUMNS if c in table.columns]
    if twist and len(twist) < len(TWIST_COLUMNS):
        raise DataError(f"{table.source}: base twist columns {', '.join(twist)} without "
                        f"{', '.join(c for c in TWIST_COLUMNS if c not in twist)} (give all six, or none)")
    return list(POSE_COLUMNS) + twist


#: a fixed robot's log whose base pose moves more than this [m, degree] is refused (mocap noise on a bolted base:
#: about a millimetre and a tenth of a degree)
STILL_BASE = (0.01, 1.0)


def _check_still_base(table: _Table, robot: Robot, first: np.ndarray | None = None) -> np.ndarray | None:
    """Refuse a fixed robot's log whose floating-base pose columns move (``--floating`` forgotten).

    The joints alone would be identified as if the base stood still: a wrong model with nothing
    to show it. ``first``: the pose ``(7,)`` the motion is measured from (a streamed log's first
    sample), else this table's first; returned (None: no pose columns).
    """
    if not all(c in table.columns for c in POSE_COLUMNS):
        return None
    pose = np.stack([table.columns[c] for c in POSE_COLUMNS], axis=1)
    if not np.isfinite(pose).all() or not len(pose):
        return first  # the joints' checks name bad values; these columns are not read
    ref = pose[0] if first is None else first
    moved = float(np.max(np.linalg.norm(pose[:, :3] - ref[:3], axis=1)))
    quat = pose[:, 3:] / np.maximum(np.linalg.norm(pose[:, 3:], axis=1, keepdims=True), 1e-300)
    q0 = quat[0] if first is None else ref[3:] / max(float(np.linalg.norm(ref[3:])), 1e-300)
    turned = float(np.degrees(2 * np.arccos(np.clip(np.abs(quat @ q0), 0.0, 1.0))).max())
    if moved > STILL_BASE[0] or turned > STILL_BASE[1]:
        raise DataError(f"{table.source}: columns {', '.join(POSE_COLUMNS)}: a floating base's pose that moves "
                        f"({moved:.3g} m, {turned:.3g} degree from the first sample), but robot {robot.name!r} has a "
                        "fixed root: --floating (floating=True) attaches it by a free joint; or leave the columns out "
                        "if the base is fixed")
    return ref


def _with_base(table: _Table, log: JointLog, base: list[str]) -> JointLog:
    """The floating base's six coordinates (and rates) put before the joints (:mod:`baseparams.kinematics.floating`)."""
    from ..kinematics.floating import MAX_PITCH, chart_rates, quaternion_matrix, zyx_of_rotation

    pose = np.stack([table.columns[c] for c in POSE_COLUMNS], axis=1)
    norm = np.linalg.norm(pose[:, 3:], axis=1)
    bad = np.abs(norm - 1.0) > 1e-2
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(f"{table.source}: columns base_qw..base_qz, {table.row(i)}: quaternion norm {norm[i]:.4g}, "
                        "not a unit quaternion (w, x, y, z of the base's orientation)")
    chart = np.concatenate([pose[:, :3], zyx_of_rotation(quaternion_matrix(pose[:, 3:]))], axis=1)
    steep = np.abs(chart[:, 4]) > MAX_PITCH
    if steep.any():
        i = int(np.argmax(steep))
        raise DataError(f"{table.source}: columns base_qw..base_qz, {table.row(i)}: the base pitches "
                        f"{np.rad2deg(chart[i, 4]):.1f} deg; beyond +-{np.rad2deg(MAX_PITCH):.0f} deg the Euler "
                        "angles the base pose is filtered in are singular")
    notes = list(log.notes)
    rates = None
    if log.dq is not None and len(base) > len(POSE_COLUMNS):
        twist = np.stack([table.columns[c] for c in TWIST_COLUMNS], axis=1)
        notes += _check_twist_frame(table, log.t, chart, twist, pose[:, 3:])
        rates = chart_rates(chart, twist)
    elif log.dq is not None:
        rates = np.gradient(chart, log.t, axis=0)
        notes.append("base twist: no columns base_vx..base_wz; derived from the base pose (central differences)")
    elif len(base) > len(POSE_COLUMNS):
        notes.append("base twist: columns base_vx..base_wz not used (the joints have no dq: every rate is derived)")
    zeros = np.zeros((log.n_samples, 6))

    def cat(base_part, joint_part):
        return None if joint_part is None else np.concatenate([base_part, joint_part], axis=1)

    ddq = None if log.ddq is None else np.gradient(np.gradient(chart, log.t, axis=0) if rates is None else rates,
                                                    log.t, axis=0)
    if ddq is not None:
        notes.append("base acceleration: derived from the base twist (central differences)")
    return JointLog(log.t, BASE_COORDINATES + log.joints, cat(chart, log.q), cat(zeros, log.tau), cat(rates, log.dq),
                    cat(ddq, log.ddq), log.source, dict(log.removed), tuple(notes), cat(zeros, log.cur))


#: a logged base twist is refused as given in the world frame when, integrated in the world frame, it follows
#: the pose this many times better than in the base frame, and in the base frame it misses by more than
#: TWIST_FRAME_MISS (:func:`~baseparams.kinematics.floating.twist_mismatch`)
TWIST_FRAME_RATIO, TWIST_FRAME_MISS = 0.5, 0.05
#: a logged base twist that follows the pose worse than this in both frames gets a note
TWIST_POOR = 0.25


def _check_twist_frame(table: _Table, t: np.ndarray, chart: np.ndarray, twist: np.ndarray,
                       quat: np.ndarray) -> list[str]:
    """Refuse a base twist given in the world frame, or a scalar-last quaternion; note a twist that fits neither.

    The pose's derivative says which frame the twist is in; read scalar-last (``quat (S, 4)`` as
    logged), the pose the twist follows says the quaternion's order (:func:`_check_quaternion_order`).
    """
    from ..kinematics.floating import TWIST_WINDOW, twist_mismatch

    miss = twist_mismatch(t, chart, twist)
    if np.nan_to_num(miss[0], nan=0.0).max() > TWIST_FRAME_MISS:
        _check_quaternion_order(table, t, chart, twist, quat, miss[0])
    notes = []
    for k, (what, cols) in enumerate((("linear velocity", TWIST_COLUMNS[:3]), ("angular velocity", TWIST_COLUMNS[3:]))):
        body, world = miss[:, k]
        names = ", ".join(table.label(c) for c in cols)
        if world < TWIST_FRAME_RATIO * body and body > TWIST_FRAME_MISS:
            raise DataError(f"{table.source}: {names}: the base's {what} looks expressed in the world frame: "
                            f"integrated as world-frame it misses the logged pose by {world:.1%}, as base-frame "
                            f"(the layout's frame) by {body:.1%}; rotate it into the base frame (R^T times the "
                            "world vector), or leave the twist columns out (then derived from the pose)")
        if min(body, world) > TWIST_POOR:
            notes.append(f"base twist: the {what} ({names}) misses the logged pose by {body:.0%} (integrated over "
                         f"{TWIST_WINDOW:g} s windows; by {world:.0%} read as world-frame): check its units, frame "
                         "and time stamps")
    return notes


def _check_quaternion_order(table: _Table, t: np.ndarray, chart: np.ndarray, twist: np.ndarray, quat: np.ndarray,
                            miss: np.ndarray) -> None:
    """Refuse a base quaternion logged scalar-last (x, y, z, w) in the columns of one scalar-first (w, x, y, z).

    Only with a logged twist, which says which reading the pose's motion follows: the twist
    misses the pose read as logged (``miss (2,)``, linear and angular:
    :func:`~baseparams.kinematics.floating.twist_mismatch`) and follows it within ``TWIST_FRAME_MISS``
    read scalar-last. Without a twist nothing tells them
    apart (both are unit quaternions).
    """
    from ..kinematics.floating import quaternion_matrix, twist_mismatch, zyx_of_rotation

    swapped = np.concatenate([chart[:, :3], zyx_of_rotation(quaternion_matrix(quat[:, [3, 0, 1, 2]]))], axis=1)
    alt = np.nan_to_num(twist_mismatch(t, swapped, twist)[0], nan=0.0)
    if alt.max() < TWIST_FRAME_MISS:
        raise DataError(f"{table.source}: columns base_qw, base_qx, base_qy, base_qz: the base's quaternion looks "
                        f"scalar-last (x, y, z, w): read so, the logged twist follows the pose (misses it by "
                        f"{alt.max():.1%}), read as the layout's scalar-first w, x, y, z it misses by "
                        f"{np.nan_to_num(miss, nan=0.0).max():.1%}; write w in base_qw (SciPy's as_quat and ROS "
                        "give x, y, z, w)")


def _conversion_notes(joints: list[_Joint], spec: dict) -> list[str]:
    notes = []
    if spec["time_scale"] != 1.0:
        notes.append(f"time: column {spec['time']!r} x {spec['time_scale']:g} s")
    for x in joints:
        parts = [f"sign {x.sign:+g}" if x.sign != 1 else "", f"gear ratio {x.ratio:g}" if x.ratio != 1 else "",
                 f"torque gain {x.gain:g}" if x.gain != 1 else "", f"offset {x.offset:g}" if x.offset else ""]
        if any(parts):
            notes.append(f"joint {x.joint}: " + ", ".join(p for p in parts if p))
    return notes


def _check_numeric(table: _Table, used: list[str]) -> None:
    """A used column stored as booleans (e.g. a Parquet ``bool``) is no measurement: refused."""
    for c in used:
        if c in table.booleans:
            raise DataError(f"{table.source}: {table.label(c)} holds booleans (true/false), not numbers: "
                            f"not used as a measurement")


def _check_finite(table: _Table, used: list[str]) -> None:
    """The first NaN or inf of the used columns, in file order."""
    _check_numeric(table, used)
    if all(np.isfinite(table.columns[c]).all() for c in used):  # the usual case: no copy of the block
        return
    block = np.stack([table.columns[c] for c in used], axis=1)
    bad = ~np.isfinite(block)
    if bad.any():
        i, k = np.unravel_index(int(np.argmax(bad)), bad.shape)
        raise DataError(f"{table.source}: {table.label(used[k])}, {table.row(i)}: {block[i, k]} (not finite; "
                        f"{counted(bad.sum(), 'such value')} in the columns read)")


def _check_time(table: _Table, tcol: str, t: np.ndarray) -> None:
    """Time strictly increasing: a repeated or earlier stamp names its row."""
    dt = np.diff(t)
    bad = dt <= 0
    if bad.any():
        i = int(np.argmax(bad)) + 1
        what = "repeats" if dt[i - 1] == 0 else "is before"
        rows = counted(bad.sum(), "such row")
        raise DataError(f"{table.source}: {table.label(tcol)}, {table.row(i)}: time {t[i]:.9g} s {what} the one "
                        f"before ({t[i - 1]:.9g} s); time must be strictly increasing ({rows})")


def _check_plausible(table: _Table, joints: list[_Joint], q: np.ndarray, max_angle, max_travel) -> str | None:
    """A revolute joint beyond ``max_angle`` (degrees?) or a prismatic one beyond ``max_travel`` (mm?): the line.

    A joint the model declares without position limits (:func:`unbounded_joints`) may turn any number of times.
    """
    limit = np.array([(np.inf if x.unbounded else max_angle) if x.jtype == "R" else max_travel for x in joints],
                     dtype=float)
    limit = np.where(np.isnan(limit), np.inf, limit)
    bad = np.abs(q) > limit
    if not bad.any():
        return None
    k = int(np.argmax(bad.any(axis=0)))
    i = int(np.argmax(bad[:, k]))
    x = joints[k]
    if x.jtype == "R":
        why = (f"|q| = {abs(q[i, k]):.4g} rad > {limit[k]:.4g} for revolute joint {x.joint!r}: degrees given as "
               "radians? (or a motor-side angle without gear_ratio)")
    else:
        why = (f"|q| = {abs(q[i, k]):.4g} m > {limit[k]:.4g} for prismatic joint {x.joint!r}: millimetres given as "
               "metres?")
    return f"{table.source}: {table.label(x.cols['q'])}, {table.row(i)}: {why}"


def log_columns_of(log: JointLog) -> dict[str, np.ndarray]:
    """A log in the default layout, one 1-D array per column.

    Parameters
    ----------
    log : JointLog
        The log.

    Returns
    -------
    dict of str to ndarray, each shape ``(S,)``
        ``t``, then ``q_<joint>`` for every joint, ``dq_``/``ddq_`` when the log has them, ``tau_``;
        a floating base's coordinates (:data:`~baseparams.kinematics.floating.BASE_COORDINATES`
        first) as its pose columns and, with ``dq``, its twist columns (module docstring).
    """
    cols = {"t": log.t}
    first = 0
    if log.floating:  # a floating base: its pose and twist columns
        from ..kinematics.floating import chart_twist, zyx_quaternion

        first = 6
        cols.update(zip(POSE_COLUMNS, np.concatenate([log.q[:, :3], zyx_quaternion(log.q[:, 3:6])], axis=1).T))
        if log.dq is not None:
            cols.update(zip(TWIST_COLUMNS, chart_twist(log.q[:, :6], log.dq[:, :6]).T))
    for kind in KINDS:
        arr = getattr(log, kind)
        if arr is not None:
            cols.update({f"{kind}_{j}": arr[:, k] for k, j in enumerate(log.joints) if k >= first})
    return cols


def write_log(path, log: JointLog, inputs=(), what: str = "log") -> Path:
    """Write a log in the default layout, read back exactly by :func:`read_log` (atomically).

    Parameters
    ----------
    path : str or Path
        ``.csv`` / ``.tsv`` (text, every value as its shortest exact decimal) or ``.npz``.
    log : JointLog
        The log.
    inputs : iterable of str or Path
        The run's input files, which the log must not overwrite.
    what : str
        The output's role, for messages (``out``).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    DataError
        Another suffix, or a file that cannot be written.
    """
    from ..arguments import ArgumentTypeError, check_path

    check_path(path, "write_log: path")
    if not isinstance(log, JointLog):
        raise ArgumentTypeError(f"write_log: log must be a JointLog, got {type(log).__name__}")
    from ..tables import LOG_SUFFIXES, write_table

    return write_table(path, log_columns_of(log), "a log as .csv, .tsv or .npz", LOG_SUFFIXES, inputs, what)


# ---------------------------------------------------------------- streamed logs
# A joint log read block by block, in memory independent of its length (CSV/TSV, Parquet).
#
# :class:`LogStream` reads the same files and layouts as :func:`read_log` (default layout or a
# ``columns`` mapping, the same conversions and checks) but never holds the whole log:
# :meth:`LogStream.blocks` yields consecutive blocks of samples, each checked as ``read_log`` checks
# a whole log (finite values, time strictly increasing, also across blocks, plausible angles), with
# bad input reported in one line naming the file, the column and the row as the whole file counts it.
# Text files are cut into blocks of about ``block_bytes`` at line ends; a block of plain numbers is
# parsed by ``pyarrow.csv`` straight from its bytes (pyarrow is optional: only faster), any other
# block line by line with ``read_log``'s rules. Parquet files are read by record batches.

#: suffixes :class:`LogStream` reads
STREAM_SUFFIXES = TEXT_SUFFIXES + PARQUET_SUFFIXES + (".npz",)
#: bytes of a text file parsed at once (a block ends at a line end)
BLOCK_BYTES = 1 << 22
#: rows of a Parquet record batch
BATCH_ROWS = 1 << 16


def decoded_mb(path) -> float:
    """The size of a log's numbers [MB]: Parquet rows x columns x 8 bytes (it may be compressed), else the file's.

    Parameters
    ----------
    path : str or Path
        The log.

    Returns
    -------
    float
        Megabytes (1e6 bytes); the file's size when the Parquet footer cannot be read.
    """
    p = Path(path)
    size = p.stat().st_size
    if p.suffix.lower() in PARQUET_SUFFIXES:
        try:
            import pyarrow.parquet as pq

            meta = pq.read_metadata(p)
            size = max(size, meta.num_rows * meta.num_columns * 8)
        except Exception:  # noqa: BLE001 - the reader says what is wrong with the file
            pass
    return size / 1e6


def streamable(path) -> bool:
    """Whether :class:`LogStream` reads this path (a regular CSV/TSV/TXT, Parquet or NPZ file).

    Parameters
    ----------
    path : str or Path
        The log.

    Returns
    -------
    bool
        True for an existing regular file with a text, Parquet or ``.npz`` suffix.
    """
    p = Path(path)
    return p.suffix.lower() in STREAM_SUFFIXES and p.is_file()


class LogStream:
    """A joint log read block by block (:meth:`blocks`), checked as :func:`~baseparams.io.logs.read_log` checks it.

    Parameters
    ----------
    path : str or Path
        A ``.csv``/``.tsv``/``.txt``, ``.parquet``/``.pq`` or ``.npz`` file (an NPZ's members are
        read block by block from the archive, stored or compressed: never a whole array).
    robot : Robot
        The model (names the columns, as for ``read_log``).
    columns : str, Path or dict, optional
        A mapping for another layout (``read_log``'s ``columns``; no ``topic``).
    allow_subset : bool
        Accept a log of only some of the model's 1-dof joints.
    max_angle, max_travel : float or None
        Plausibility bounds of ``|q|`` (``read_log``'s).
    require_tau : bool
        Every joint read must have a ``tau`` column.
    block_bytes : int
        Bytes of a text file per block (at least one line).
    allow_units : bool
        A position beyond the bounds is a warning note of its block, not a refusal (``read_log``'s).

    Attributes
    ----------
    source : str
        The path, for messages.
    joints : tuple of str, shape ``(m,)``
        The model's joints read, in the model's order (the columns of every block).
    has_dq, has_ddq : bool
        Whether the blocks carry logged velocities and accelerations.
    has_tau, has_currents : bool
        Whether the blocks carry joint torques, motor currents (``cur_<joint>`` [A]).

    Raises
    ------
    DataError
        Not a regular file, another suffix, a bad mapping or header, joints missing (as ``read_log``).
    """

    def __init__(self, path, robot: Robot, columns=None, *, allow_subset: bool = False,
                 max_angle: float | None = MAX_ANGLE, max_travel: float | None = MAX_TRAVEL, require_tau: bool = True,
                 block_bytes: int = BLOCK_BYTES, allow_units: bool = False):
        p = check_input(path, error=DataError)
        if p.suffix.lower() not in STREAM_SUFFIXES:
            raise DataError(f"{p}: not streamed (expected {', '.join(STREAM_SUFFIXES)}); read it with read_log")
        self.path, self.source = p, str(p)
        self.kind = ("parquet" if p.suffix.lower() in PARQUET_SUFFIXES else "npz" if p.suffix.lower() == ".npz"
                     else "text")
        self.spec = _mapping(columns)
        for key in ("topic", "base_topic"):
            if self.spec[key] is not None:
                raise DataError(f"{self.spec['label']}: {key!r} applies to ROS bags only, not to {p.name}")
        if robot.floating:
            raise DataError(f"{p}: robot {robot.name!r} has a floating base: its log is read whole (read_log: its "
                            "pose is unwrapped over the whole log), not streamed")
        self.bounds = (max_angle, max_travel, bool(allow_units))
        self.block_bytes = max(int(block_bytes), 1)
        self.names = self._names()
        empty = _Table(self.source, {n: np.empty(0) for n in self.names}, np.empty(0, int), "")
        if self.kind != "text":
            what = "array" if self.kind == "npz" else "column"
            empty.labels = {n: f"{what} {n!r}" for n in self.names}
        self._joints = _resolve(empty, robot, self.spec, allow_subset, require_tau)
        self._robot = robot
        if self.spec["time"] not in self.names:
            raise DataError(f"{self.source}: no time column {self.spec['time']!r} (columns: "
                            f"{', '.join(self.names[:12])})")
        self.joints = tuple(x.joint for x in self._joints)
        self.has_dq = self._joints[0].cols["dq"] is not None
        self.has_ddq = self._joints[0].cols["ddq"] is not None
        self.has_tau = self._joints[0].cols["tau"] is not None
        self.has_currents = self._joints[0].cols["cur"] is not None  # every joint read has them, or none

    def __repr__(self) -> str:
        return f"<LogStream {self.source}: {counted(len(self.joints), 'joint')}, {self.kind}>"

    def _names(self) -> list[str]:
        """The file's column names (an NPZ's members are indexed on the way)."""
        if self.kind == "npz":
            self._members, _ = _npz_members(self.path)
            return list(self._members)
        return self._text_header()[0] if self.kind == "text" else self._parquet_names()

    @functools.cached_property
    def decoded_mb(self) -> float:
        """The size of the log's numbers [MB] (:func:`decoded_mb`: a compressed Parquet file's by its rows)."""
        return decoded_mb(self.path)

    # ------------------------------------------------------------ the blocks
    def blocks(self) -> Iterator[JointLog]:
        """The log's samples, block after block, each checked and converted to the joint side.

        Yields
        ------
        JointLog
            Consecutive samples (``t (k,)``, ``q, tau (k, m)``, ``dq``/``ddq`` when logged);
            ``notes`` of the first block say how the file was read; a later block's notes are
            its WARNING lines only (``allow_units``: positions beyond the plausible bounds).

        Raises
        ------
        DataError
            The first bad value in file order (non-finite, a text cell, time not strictly
            increasing, an implausible angle), naming the file, the column and the global row;
            an empty file.
        """
        tables = {"text": self._text_tables, "parquet": self._parquet_tables, "npz": self._npz_tables}[self.kind]()
        last_t, count, turns, still = None, 0, {}, None
        for table in tables:
            log = _assemble(table, self._joints, self.spec, self.bounds, turns=turns)
            still = _check_still_base(table, self._robot, still)
            if last_t is not None and not log.t[0] > last_t:
                what = "repeats" if log.t[0] == last_t else "is before"
                raise DataError(f"{self.source}: {table.label(self.spec['time'])}, {table.row(0)}: time "
                                f"{log.t[0]:.9g} s {what} the one before ({last_t:.9g} s); time must be strictly "
                                f"increasing")
            if count:  # how the file was read is the first block's to say; a later block's warnings are its own
                log = JointLog(log.t, log.joints, log.q, log.tau, log.dq, log.ddq, log.source,
                               notes=tuple(n for n in log.notes if "WARNING" in n), cur=log.cur)
            last_t, count = float(log.t[-1]), count + log.n_samples
            yield log
        if not count:
            raise DataError(f"{self.source}: no data rows")

    # ------------------------------------------------------------ text
    def _chunks(self) -> Iterator[tuple[int, bytes, str | None, bool, int]]:
        """``(first line number, bytes, text, odd, lines)`` per block of about ``block_bytes``, cut at line ends.

        ``text`` is None for a plain ASCII block (``body.decode("ascii")`` when needed); ``odd``:
        the block may have line breaks other than newlines (:func:`_odd_breaks`); ``lines``: the
        lines ``str.splitlines`` counts in it.
        """
        first, rest, offset = 1, b"", 0
        with open(self.path, "rb") as fh:
            while True:
                chunk = fh.read(self.block_bytes)
                data = rest + chunk
                cut = data.rfind(b"\n") + 1 if chunk else len(data)
                if not cut and chunk:
                    rest = data
                    continue
                body, rest = data[:cut], data[cut:]
                odd, text = _odd_breaks(body), None
                if odd or not body.isascii():
                    try:
                        text = body.decode("utf-8-sig" if offset == 0 else "utf-8")
                    except UnicodeDecodeError as exc:
                        raise DataError(f"{self.path}: not a UTF-8 text file (byte {offset + exc.start})") from None
                offset += len(body)
                lines = len(text.splitlines()) if odd else body.count(b"\n") + (not body.endswith(b"\n"))
                if body:
                    yield first, body, text, odd, lines
                first += lines
                if not chunk:
                    return

    def _lines(self) -> Iterator[tuple[int, list[str]]]:
        """``(first line number, lines)`` per block (``str.splitlines``: the line numbers ``read_log`` gives)."""
        for first, body, text, _, _ in self._chunks():
            yield first, (body.decode("ascii") if text is None else text).splitlines()

    def _text_header(self) -> tuple[list[str], str, int]:
        """The header row: ``(names, delimiter, line number)`` (delimiter ``" "``: runs of blanks)."""
        for first, lines in self._lines():
            for k, line in enumerate(lines):
                s = line.strip()
                if s and not s.startswith("#"):
                    delim = _sniff(s, self.path.suffix.lower())
                    if delim is None:
                        s, delim = re.sub(r"[ \t]+", " ", s), " "
                    names = [n.strip() for n in next(csv.reader([s], delimiter=delim, skipinitialspace=True))]
                    _check_header(self.path, names, first + k)
                    self._delim, self._header_line = delim, first + k
                    return names, delim, first + k
        raise DataError(f"{self.path}: empty file (expected a header row and data rows)")

    def _text_tables(self) -> Iterator[_Table]:
        """One checked table per block of data lines (global line numbers and data rows)."""
        names, delim, header = self.names, self._delim, self._header_line
        rows_before = 0
        for first, body, text, odd, lines in self._chunks():
            values = _fast_block(body, delim, names, lines) if first > header and not odd else None
            if values is not None:
                numbers, text_cols = np.arange(first, first + len(values)), {}
            else:
                numbers, values, text_cols = self._slow_block(first, body.decode("ascii") if text is None else text,
                                                              rows_before)
                if numbers is None:
                    continue
            table = _Table(self.source, {n: values[:, k] for k, n in enumerate(names)}, numbers,
                             "line {0} (data row {1})", text=text_cols, offset=rows_before)
            if rows_before == 0:
                table.notes.append(f"{self.path.name}: read in blocks of {self.block_bytes} bytes, delimiter "
                                   f"{_delim_name(delim)}")
            rows_before += len(values)
            yield table

    def _slow_block(self, first: int, text: str, rows_before: int):
        """``read_log``'s line rules on one block: blank and ``#`` lines skipped, field counts checked.

        Returns ``(line numbers, values, text columns)``, or ``(None, None, None)`` for a block
        without data lines.
        """
        names, delim, header = self.names, self._delim, self._header_line
        stripped = [s.strip() for s in text.splitlines()]
        numbers = np.array([first + k for k, s in enumerate(stripped)
                            if s and not s.startswith("#") and first + k > header], dtype=np.int64)
        kept = [stripped[n - first] for n in numbers]
        if not kept:
            return None, None, None
        if delim == " ":
            blanks = re.compile(r"[ \t]+")
            kept = [blanks.sub(" ", s) for s in kept]
        counts = np.fromiter(map(str.count, kept, [delim] * len(kept)), int, len(kept)) + 1
        if np.any(bad := counts != len(names)):
            i = int(np.argmax(bad))
            raise DataError(f"{self.path}: line {numbers[i]} (data row {rows_before + i + 1}): {counts[i]} fields, "
                            f"the header has {len(names)} (columns of different lengths)")
        values, text_cols = _parse_block(self.path, kept, delim, names, numbers, rows_before + 1)
        return numbers, values, text_cols

    # ------------------------------------------------------------ NPZ
    def _npz_tables(self) -> Iterator[_Table]:
        """One checked table per :data:`BATCH_ROWS` samples of the used arrays (0-based global indices).

        Every used member is open at once and read sequentially (a compressed member is
        decompressed as it is read), so memory is a block's, whatever the length.
        """
        import zipfile

        used = self._used()
        lengths = {c: self._members[c][3] for c in used}
        first_col, n = next(iter(lengths.items()))
        for c, k in lengths.items():
            if k != n:
                raise DataError(f"{self.source}: array {c!r} has {counted(k, 'row')}, array {first_col!r} has {n} "
                                "(columns of different lengths)")
        tcol, first = self.spec["time"], None
        with contextlib.ExitStack() as stack:
            try:
                z = stack.enter_context(zipfile.ZipFile(self.path))
                handles = {}
                for c in used:
                    info, offset, dtype, _ = self._members[c]
                    fh = stack.enter_context(z.open(info))
                    fh.read(offset)
                    handles[c] = (fh, dtype)
            except (zipfile.BadZipFile, OSError, ValueError, EOFError) as exc:
                raise DataError(f"{self.path}: not a readable .npz archive ({_first_line(exc)})") from None
            for start in range(0, n, BATCH_ROWS):
                k = min(BATCH_ROWS, n - start)
                columns, booleans, notes = {}, set(), []
                for c, (fh, dtype) in handles.items():
                    try:
                        raw = fh.read(k * dtype.itemsize)
                    except (zipfile.BadZipFile, OSError, ValueError, EOFError) as exc:
                        raise DataError(f"{self.path}: array {c!r}: not readable ({_first_line(exc)})") from None
                    if len(raw) != k * dtype.itemsize:
                        raise DataError(f"{self.path}: array {c!r} ends at index {start + len(raw) // dtype.itemsize}"
                                        f" (0-based); its header claims {n} values")
                    a = np.frombuffer(raw, dtype=dtype, count=k)
                    if dtype.kind == "b":
                        booleans.add(c)
                    if c == tcol:
                        if first is None:
                            first = a[0] if dtype.kind in "iu" else None
                        columns[c] = _integer_time(c, a, notes, self.path, first)
                    else:
                        columns[c] = a.astype(float)
                notes = [*notes, f"{self.path.name}: read in blocks of {BATCH_ROWS} samples"] if not start else []
                yield _Table(self.source, columns, np.arange(start, start + k), "index {0} (0-based)",
                             labels={c: f"array {c!r}" for c in columns}, booleans=booleans, notes=notes,
                             offset=start)

    # ------------------------------------------------------------ Parquet
    def _parquet_file(self):
        try:
            import pyarrow.parquet as pq
        except ImportError:
            raise DataError(f"{self.path}: reading Parquet needs pyarrow: pip install 'baseparams[parquet]'") from None
        try:
            # buffered reads, no pre-buffering: iter_batches otherwise keeps every column chunk it read
            # (memory growing with the file: 2.3 GB on a 10^7-row log)
            return pq.ParquetFile(self.path, pre_buffer=False, buffer_size=1 << 16)
        except Exception as exc:  # pyarrow's errors: one line
            raise DataError(f"{self.path}: not a readable Parquet file ({_first_line(exc)})") from None

    def _parquet_names(self) -> list[str]:
        f = self._parquet_file()
        meta = f.metadata
        _check_counts(self.path, meta.num_columns, meta.num_rows, "column")
        return list(f.schema_arrow.names)

    def _used(self) -> list[str]:
        """The columns the layout reads (:func:`_layout_columns`)."""
        return _layout_columns(self.names, self.spec, self._joints, self._robot)

    def _parquet_tables(self) -> Iterator[_Table]:
        """One checked table per record batch (0-based global rows)."""
        f = self._parquet_file()
        start, first = 0, None
        try:
            used = self._used()  # never the other columns; one iterator per row group (freed after it)
            batches = (b for g in range(f.num_row_groups)
                       for b in f.iter_batches(batch_size=BATCH_ROWS, row_groups=[g], columns=used,
                                               use_threads=False))  # threads: ~50 MB more, no faster
            for batch in batches:
                tcol = self.spec["time"]
                if first is None and tcol in batch.schema.names and batch.num_rows:
                    first = batch.column(tcol)[0].as_py()
                    first = getattr(first, "value", first) if not isinstance(first, int) else first
                columns, booleans, notes = _arrow_columns(self.path, batch, start, tcol,
                                                          first if isinstance(first, int) else None)
                table = _Table(self.source, columns, np.arange(start, start + batch.num_rows), "row {0} (0-based)",
                                 labels={k: f"column {k!r}" for k in columns}, booleans=booleans,
                                 notes=notes if start == 0 else [], offset=start)
                start += batch.num_rows
                if batch.num_rows:
                    yield table
        except DataError:
            raise
        except Exception as exc:  # a damaged file found mid-way: one line
            raise DataError(f"{self.path}: not a readable Parquet file ({_first_line(exc)})") from None
        finally:
            f.close()
            import pyarrow as pa

            pa.default_memory_pool().release_unused()  # the pass's buffers back to the system before the next


#: bytes that may start a line break ``str.splitlines`` counts besides ``\n`` (and ``\r\n``); the
#: last two lead U+0085, U+2028 and U+2029 (and other non-ASCII text, read line by line too)
_ODD_BYTES = (b"\r", b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e", b"\xc2", b"\xe2")


def _odd_breaks(body: bytes) -> bool:
    """Whether a block may have line breaks other than newlines (``str.splitlines`` counts them too)."""
    return any(b in body for b in (_ODD_BYTES[:6] if body.isascii() else _ODD_BYTES))  # memchr each


def _fast_block(body: bytes, delim: str, names: list[str], lines: int) -> np.ndarray | None:
    """``(k, columns)`` floats of a block in which every line is a row of plain numbers, or None.

    pyarrow parses the bytes as they are; a blank, comment or malformed line, a text cell, or
    pyarrow missing gives None (the block is then read line by line).
    """
    if delim == " ":
        return None
    try:
        import pyarrow as pa
        import pyarrow.csv as pcsv
    except ImportError:
        return None
    try:
        table = pcsv.read_csv(io.BytesIO(body),
                              read_options=pcsv.ReadOptions(column_names=names, use_threads=True,
                                                            block_size=1 << 20),
                              parse_options=pcsv.ParseOptions(delimiter=delim, quote_char=False,
                                                              ignore_empty_lines=False),
                              convert_options=pcsv.ConvertOptions(column_types={n: pa.float64() for n in names},
                                                                  null_values=[], strings_can_be_null=False))
    except (pa.ArrowInvalid, pa.ArrowTypeError, ValueError):
        return None
    if table.num_rows != lines:
        return None
    return _numbers(table, names)


def _numbers(table, names: list[str]) -> np.ndarray:
    """``(k, columns)`` floats of a pyarrow table of float64 columns (without pandas)."""
    out = np.empty((table.num_rows, len(names)))
    for k, n in enumerate(names):
        start = 0
        for chunk in table.column(n).chunks:
            out[start:start + len(chunk), k] = chunk.to_numpy(zero_copy_only=False)
            start += len(chunk)
    return out


def _parse_block(path: Path, kept: list[str], delim: str, names: list[str], numbers: np.ndarray, first_row: int):
    """``(k, columns)`` floats of a block of data lines and ``{column: message}`` for text cells.

    pyarrow parses the block when every field is a plain number; else NumPy (``read_log``'s
    parser), which names the first cell that is not a number.
    """
    try:
        import pyarrow as pa
        import pyarrow.csv as pcsv
    except ImportError:
        return _parse_numbers(path, kept, delim, names, numbers, first_row)
    try:
        table = pcsv.read_csv(io.BytesIO("\n".join(kept).encode("utf-8")),
                              read_options=pcsv.ReadOptions(column_names=names, use_threads=False),
                              parse_options=pcsv.ParseOptions(delimiter=delim, quote_char=False),
                              convert_options=pcsv.ConvertOptions(column_types={n: pa.float64() for n in names},
                                                                  null_values=[], strings_can_be_null=False))
    except (pa.ArrowInvalid, pa.ArrowTypeError, ValueError):
        return _parse_numbers(path, kept, delim, names, numbers, first_row)
    if table.num_rows != len(kept):
        return _parse_numbers(path, kept, delim, names, numbers, first_row)
    return _numbers(table, names), {}


def _arrow_columns(path: Path, batch, start: int, time: str | None = None, first=None):
    """A Parquet record batch as float columns (``read_log``'s rules), nulls naming the global row.

    ``time``: the time column, whose integer stamps beyond float's exact range are counted from
    ``first`` (default: the batch's first stamp; a streamed log passes its first block's).
    """
    import pyarrow as pa
    import pyarrow.compute as pc

    columns, booleans, notes = {}, set(), []
    for name, col in zip(batch.schema.names, batch.columns):
        if col.null_count:
            i = int(np.argmax(pc.is_null(col).to_numpy(zero_copy_only=False)))
            raise DataError(f"{path}: column {name!r}, row {start + i} (0-based): null value")
        if pa.types.is_timestamp(col.type) or pa.types.is_duration(col.type):
            scale = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}[col.type.unit]
            raw = col.cast(pa.int64()).to_numpy()
            if name == time:
                raw = _integer_time(name, raw, notes, path, first)
            columns[name] = raw.astype(float) * scale
            notes.append(f"{path.name}: column {name!r} is a {col.type}: converted to seconds")
        elif name == time and pa.types.is_integer(col.type):
            columns[name] = _integer_time(name, col.to_numpy(zero_copy_only=False), notes, path, first)
        elif pa.types.is_integer(col.type) or pa.types.is_floating(col.type) or pa.types.is_boolean(col.type):
            columns[name] = col.to_numpy(zero_copy_only=False).astype(float)
            if pa.types.is_boolean(col.type):
                booleans.add(name)
        else:
            raise DataError(f"{path}: column {name!r} holds {col.type} values, expected numbers")
    return columns, booleans, notes
