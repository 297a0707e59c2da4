"""A joint log read block by block, in memory independent of its length (CSV/TSV, Parquet).

:class:`LogStream` reads the same files and layouts as :func:`baseparams.io.logs.read_log`
(default layout or a ``columns`` mapping, the same conversions and checks) but never holds the
whole log: :meth:`LogStream.blocks` yields consecutive blocks of samples as
:class:`~baseparams.ident.data.JointLog` objects, each checked as ``read_log`` checks a whole log
(finite values, time strictly increasing, also across blocks, plausible angles), with bad input
reported in one line naming the file, the column and the row **as the whole file counts it**
(text files: file line and data row; Parquet: 0-based row).

Text files are cut into blocks of about ``block_bytes`` at line ends; blank and ``#`` lines are
skipped as ``read_log`` skips them (the delimiter is sniffed from the header row). Each block is
parsed by ``pyarrow.csv`` when it is installed and every field is a plain number, else by
NumPy's ``loadtxt`` (which also names a cell that is not a number): pyarrow is optional, only
faster. Parquet files (pyarrow required, extra ``parquet``) are read by record batches.
NPZ archives and ROS bags are not streamed (:func:`streamable`).
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ..errors import DataError
from ..files import check_input
from ..ident.data import JointLog
from ..model.robot import Robot
from . import logs as L

#: suffixes :class:`LogStream` reads
STREAM_SUFFIXES = L.TEXT_SUFFIXES + L.PARQUET_SUFFIXES
#: bytes of a text file parsed at once (a block ends at a line end)
BLOCK_BYTES = 1 << 22
#: rows of a Parquet record batch
BATCH_ROWS = 1 << 16


def streamable(path) -> bool:
    """Whether :class:`LogStream` reads this path (a regular CSV/TSV/TXT or Parquet file).

    Parameters
    ----------
    path : str or Path
        The log.

    Returns
    -------
    bool
        True for an existing regular file with a text or Parquet suffix.
    """
    p = Path(path)
    return p.suffix.lower() in STREAM_SUFFIXES and p.is_file()


class LogStream:
    """A joint log read block by block (:meth:`blocks`), checked as :func:`~baseparams.io.logs.read_log` checks it.

    Parameters
    ----------
    path : str or Path
        A ``.csv``/``.tsv``/``.txt`` or ``.parquet``/``.pq`` file.
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

    Attributes
    ----------
    source : str
        The path, for messages.
    joints : tuple of str, shape ``(m,)``
        The model's joints read, in the model's order (the columns of every block).
    has_dq, has_ddq : bool
        Whether the blocks carry logged velocities and accelerations.

    Raises
    ------
    DataError
        Not a regular file, another suffix, a bad mapping or header, joints missing (as ``read_log``).
    """

    def __init__(self, path, robot: Robot, columns=None, *, allow_subset: bool = False,
                 max_angle: float | None = 4 * np.pi, max_travel: float | None = 10.0, require_tau: bool = True,
                 block_bytes: int = BLOCK_BYTES):
        p = check_input(path, error=DataError)
        if p.suffix.lower() not in STREAM_SUFFIXES:
            raise DataError(f"{p}: not streamed (expected {', '.join(STREAM_SUFFIXES)}); read it with read_log")
        self.path, self.source = p, str(p)
        self.kind = "parquet" if p.suffix.lower() in L.PARQUET_SUFFIXES else "text"
        self.spec = L._mapping(columns)
        if self.spec["topic"] is not None:
            raise DataError(f"{self.spec['label']}: 'topic' applies to ROS bags only, not to {p.name}")
        self.bounds = (max_angle, max_travel)
        self.block_bytes = max(int(block_bytes), 1)
        self.names = self._text_header()[0] if self.kind == "text" else self._parquet_names()
        empty = L._Table(self.source, {n: np.empty(0) for n in self.names}, np.empty(0, int), "")
        if self.kind == "parquet":
            empty.labels = {n: f"column {n!r}" for n in self.names}
        self._joints = L._resolve(empty, robot, self.spec, allow_subset, require_tau)
        if self.spec["time"] not in self.names:
            raise DataError(f"{self.source}: no time column {self.spec['time']!r} (columns: "
                            f"{', '.join(self.names[:12])})")
        self.joints = tuple(x.joint for x in self._joints)
        self.has_dq = self._joints[0].cols["dq"] is not None
        self.has_ddq = self._joints[0].cols["ddq"] is not None

    def __repr__(self) -> str:
        return f"<LogStream {self.source}: {len(self.joints)} joints, {self.kind}>"

    # ------------------------------------------------------------ the blocks
    def blocks(self) -> Iterator[JointLog]:
        """The log's samples, block after block, each checked and converted to the joint side.

        Yields
        ------
        JointLog
            Consecutive samples (``t (k,)``, ``q, tau (k, m)``, ``dq``/``ddq`` when logged);
            ``notes`` of the first block say how the file was read.

        Raises
        ------
        DataError
            The first bad value in file order (non-finite, a text cell, time not strictly
            increasing, an implausible angle), naming the file, the column and the global row;
            an empty file.
        """
        tables = self._text_tables() if self.kind == "text" else self._parquet_tables()
        last_t, count = None, 0
        for table in tables:
            log = L._assemble(table, self._joints, self.spec, *self.bounds)
            if last_t is not None and not log.t[0] > last_t:
                what = "repeats" if log.t[0] == last_t else "is before"
                raise DataError(f"{self.source}: {table.label(self.spec['time'])}, {table.row(0)}: time "
                                f"{log.t[0]:.9g} s {what} the one before ({last_t:.9g} s); time must be strictly "
                                f"increasing")
            if count:
                log = JointLog(log.t, log.joints, log.q, log.tau, log.dq, log.ddq, log.source)
            last_t, count = float(log.t[-1]), count + log.n_samples
            yield log
        if not count:
            raise DataError(f"{self.source}: no data rows")

    # ------------------------------------------------------------ text
    def _chunks(self) -> Iterator[tuple[int, bytes, str]]:
        """``(first line number, bytes, text)`` per block of about ``block_bytes``, cut at line ends."""
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
                try:
                    text = body.decode("utf-8-sig" if offset == 0 else "utf-8")
                except UnicodeDecodeError as exc:
                    raise DataError(f"{self.path}: not a UTF-8 text file (byte {offset + exc.start})") from None
                offset += len(body)
                if body:
                    yield first, body, text
                first += len(text.splitlines()) if _odd_breaks(body) else body.count(b"\n") + (
                    not body.endswith(b"\n"))
                if not chunk:
                    return

    def _lines(self) -> Iterator[tuple[int, list[str]]]:
        """``(first line number, lines)`` per block (``str.splitlines``: the line numbers ``read_log`` gives)."""
        for first, _, text in self._chunks():
            yield first, text.splitlines()

    def _text_header(self) -> tuple[list[str], str, int]:
        """The header row: ``(names, delimiter, line number)`` (delimiter ``" "``: runs of blanks)."""
        for first, lines in self._lines():
            for k, line in enumerate(lines):
                s = line.strip()
                if s and not s.startswith("#"):
                    delim = L._sniff(s, self.path.suffix.lower())
                    if delim is None:
                        s, delim = re.sub(r"[ \t]+", " ", s), " "
                    names = [n.strip() for n in next(csv.reader([s], delimiter=delim, skipinitialspace=True))]
                    L._check_header(self.path, names, first + k)
                    self._delim, self._header_line = delim, first + k
                    return names, delim, first + k
        raise DataError(f"{self.path}: empty file (expected a header row and data rows)")

    def _text_tables(self) -> Iterator[L._Table]:
        """One checked table per block of data lines (global line numbers and data rows)."""
        names, delim, header = self.names, self._delim, self._header_line
        rows_before = 0
        for first, body, text in self._chunks():
            values = _fast_block(body, delim, names) if first > header and not _odd_breaks(body) else None
            if values is not None:
                numbers, text_cols = np.arange(first, first + len(values)), {}
            else:
                numbers, values, text_cols = self._slow_block(first, text, rows_before)
                if numbers is None:
                    continue
            table = L._Table(self.source, {n: values[:, k] for k, n in enumerate(names)}, numbers,
                             "line {0} (data row {1})", text=text_cols, offset=rows_before)
            if rows_before == 0:
                table.notes.append(f"{self.path.name}: read in blocks of {self.block_bytes} bytes, delimiter "
                                   f"{L._delim_name(delim)}")
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

    # ------------------------------------------------------------ Parquet
    def _parquet_file(self):
        try:
            import pyarrow.parquet as pq
        except ImportError:
            raise DataError(f"{self.path}: reading Parquet needs pyarrow: pip install 'baseparams[parquet]'") from None
        try:
            return pq.ParquetFile(self.path)
        except Exception as exc:  # pyarrow's errors: one line
            raise DataError(f"{self.path}: not a readable Parquet file ({L._first_line(exc)})") from None

    def _parquet_names(self) -> list[str]:
        return list(self._parquet_file().schema_arrow.names)

    def _parquet_tables(self) -> Iterator[L._Table]:
        """One checked table per record batch (0-based global rows)."""
        f = self._parquet_file()
        start = 0
        try:
            batches = f.iter_batches(batch_size=BATCH_ROWS)
            for batch in batches:
                columns, booleans, notes = _arrow_columns(self.path, batch, start)
                table = L._Table(self.source, columns, np.arange(start, start + batch.num_rows), "row {0} (0-based)",
                                 labels={k: f"column {k!r}" for k in columns}, booleans=booleans,
                                 notes=notes if start == 0 else [], offset=start)
                start += batch.num_rows
                if batch.num_rows:
                    yield table
        except DataError:
            raise
        except Exception as exc:  # a damaged file found mid-way: one line
            raise DataError(f"{self.path}: not a readable Parquet file ({L._first_line(exc)})") from None
        finally:
            f.close()


#: bytes that may start a line break ``str.splitlines`` counts besides ``\n`` (and ``\r\n``); the
#: last two lead U+0085, U+2028 and U+2029 (and other non-ASCII text, read line by line too)
_ODD_BYTES = (b"\r", b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e", b"\xc2", b"\xe2")


def _odd_breaks(body: bytes) -> bool:
    """Whether a block may have line breaks other than newlines (``str.splitlines`` counts them too)."""
    return any(b in body for b in _ODD_BYTES)


def _fast_block(body: bytes, delim: str, names: list[str]) -> np.ndarray | None:
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
                              read_options=pcsv.ReadOptions(column_names=names, use_threads=False),
                              parse_options=pcsv.ParseOptions(delimiter=delim, quote_char=False,
                                                              ignore_empty_lines=False),
                              convert_options=pcsv.ConvertOptions(column_types={n: pa.float64() for n in names},
                                                                  null_values=[], strings_can_be_null=False))
    except (pa.ArrowInvalid, pa.ArrowTypeError, ValueError):
        return None
    if table.num_rows != body.count(b"\n") + (not body.endswith(b"\n")):
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
        return L._parse_numbers(path, kept, delim, names, numbers, first_row)
    try:
        table = pcsv.read_csv(io.BytesIO("\n".join(kept).encode("utf-8")),
                              read_options=pcsv.ReadOptions(column_names=names, use_threads=False),
                              parse_options=pcsv.ParseOptions(delimiter=delim, quote_char=False),
                              convert_options=pcsv.ConvertOptions(column_types={n: pa.float64() for n in names},
                                                                  null_values=[], strings_can_be_null=False))
    except (pa.ArrowInvalid, pa.ArrowTypeError, ValueError):
        return L._parse_numbers(path, kept, delim, names, numbers, first_row)
    if table.num_rows != len(kept):
        return L._parse_numbers(path, kept, delim, names, numbers, first_row)
    return _numbers(table, names), {}


def _arrow_columns(path: Path, batch, start: int):
    """A Parquet record batch as float columns (``read_log``'s rules), nulls naming the global row."""
    import pyarrow as pa
    import pyarrow.compute as pc

    columns, booleans, notes = {}, set(), []
    for name, col in zip(batch.schema.names, batch.columns):
        if col.null_count:
            i = int(np.argmax(pc.is_null(col).to_numpy(zero_copy_only=False)))
            raise DataError(f"{path}: column {name!r}, row {start + i} (0-based): null value")
        if pa.types.is_timestamp(col.type) or pa.types.is_duration(col.type):
            scale = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}[col.type.unit]
            columns[name] = col.cast(pa.int64()).to_numpy().astype(float) * scale
            notes.append(f"{path.name}: column {name!r} is a {col.type}: converted to seconds")
        elif pa.types.is_integer(col.type) or pa.types.is_floating(col.type) or pa.types.is_boolean(col.type):
            columns[name] = col.to_numpy(zero_copy_only=False).astype(float)
            if pa.types.is_boolean(col.type):
                booleans.add(name)
        else:
            raise DataError(f"{path}: column {name!r} holds {col.type} values, expected numbers")
    return columns, booleans, notes
