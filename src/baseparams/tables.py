"""The one table writer: named columns to CSV/TSV, Parquet or NPZ, atomically (logs, trajectories, predictions).

The format is chosen by the suffix: ``.csv`` / ``.tsv`` (a header row, every value as its
shortest exact decimal, ``%.17g``), ``.parquet`` / ``.pq`` (pyarrow, the extra ``parquet``;
float64 columns, string columns kept as strings), ``.npz`` (one array per name, any shape).
Every write goes through :func:`baseparams.files.atomic_path` once. :func:`write_columns` takes any
of these (an output option's file: ``--out``, ``--predictions``); :func:`write_table` the formats
of a joint log or a trajectory (:func:`baseparams.io.logs.write_log`,
:meth:`baseparams.excitation.result.Excitation.save`); :func:`column_writer` appends block by block.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

import numpy as np

from .errors import BaseparamsError, DataError
from .files import atomic_path, check_output

#: suffixes :func:`write_columns` writes
TABLE_SUFFIXES = (".csv", ".tsv", ".parquet", ".pq", ".npz")
#: the suffixes of each table the library writes: a joint log, a trajectory, predicted torques
#: (:data:`baseparams.workflow.outputs.SUFFIXES`, the rule both doors ask, is made of these)
LOG_SUFFIXES = (".csv", ".tsv", ".npz")
TRAJECTORY_SUFFIXES = (".csv", ".tsv")
PREDICTION_SUFFIXES = (".csv", ".tsv", ".parquet", ".pq")


def check_table_path(path, inputs=(), what: str = "--out") -> None:
    """Refuse an output that cannot be written, before any work is done.

    Parameters
    ----------
    path : str or path or None
        The output (None: nothing to check).
    inputs : iterable of str or path
        The run's input files (the output must not overwrite one).
    what : str
        The option, for messages.

    Raises
    ------
    BaseparamsError
        An unknown suffix, a Parquet output without pyarrow, a missing folder, a non-regular
        target, an output onto an input.
    """
    if path is None:
        return
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in TABLE_SUFFIXES:
        raise BaseparamsError(f"{what} {p}: write .csv, .tsv, .parquet or .npz, not {p.suffix or 'no suffix'}")
    check_parquet(p, what)
    check_output_path(p, inputs, what)


def check_parquet(path, what: str = "--out") -> None:
    """A Parquet output (``.parquet``, ``.pq``) needs pyarrow (the extra ``parquet``): said before any work.

    Parameters
    ----------
    path : str or path
        The output.
    what : str
        The option, for messages.

    Raises
    ------
    BaseparamsError
        pyarrow missing for a Parquet output.
    """
    if Path(path).suffix.lower() in (".parquet", ".pq"):
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise BaseparamsError(f"{what} {path}: writing Parquet needs pyarrow: pip install "
                                  f"'baseparams[parquet]'") from None


def check_output_path(path, inputs=(), what: str = "output") -> None:
    """Refuse an output path whose folder is missing, that is not a regular file, or an input.

    Parameters
    ----------
    path : str or path or None
        The output (None: nothing to check).
    inputs : iterable of str or path
        The run's input files.
    what : str
        The option, for messages.

    Raises
    ------
    BaseparamsError
        One line naming the option and the problem.
    """
    if path is None:
        return
    check_output(path, inputs, what)


def write_columns(path, cols: dict, inputs=(), what: str = "--out") -> Path:
    """Write columns by the path's suffix (module docstring).

    Parameters
    ----------
    path : str or path
        The file.
    cols : dict of str to ndarray
        For CSV/TSV/Parquet: 1-D columns of one length ``S`` (numbers, or strings); for NPZ:
        arrays of any shape.
    inputs : iterable of str or path
        The run's input files.
    what : str
        The option, for messages.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    BaseparamsError
        As :func:`check_table_path`, or a failed write.
    """
    check_table_path(path, inputs, what)
    with atomic_path(path, inputs, what) as tmp:
        _write(tmp, cols, Path(path).suffix.lower())
    return Path(path)


def write_table(path, cols: dict, formats: str = "a table as .csv or .tsv", suffixes=(".csv", ".tsv"),
                inputs=(), what: str = "table") -> Path:
    """Columns of one length in one of a few formats, a bad suffix or a failed write a :class:`DataError`.

    Parameters
    ----------
    path : str or Path
        ``.csv`` (comma-separated) or ``.tsv`` (tab-separated), or another of ``suffixes``.
    cols : dict of str to ndarray, each shape ``(S,)``
        The columns, in order.
    formats : str
        How a wrong suffix is named in the error (``"a log as .csv, .tsv or .npz"``).
    suffixes : tuple of str
        The suffixes taken (of :data:`TABLE_SUFFIXES`).
    inputs : iterable of str or path
        The run's input files (the output must not overwrite one).
    what : str
        The output's role, for messages (``--out``).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    DataError
        Another suffix, or a file that cannot be written.
    BaseparamsError
        An output onto an input, a missing folder, a non-regular target.
    """
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise DataError(f"{p}: write {formats}, not {p.suffix or 'no suffix'}")
    try:
        with atomic_path(p, inputs, what) as tmp:  # never a partial file under the final name
            _write(tmp, cols, p.suffix.lower())
    except OSError as exc:
        raise DataError(f"{p}: cannot write ({exc.strerror or exc})") from None
    return p


def _write(tmp: Path, cols: dict, suffix: str) -> None:
    """Columns written to ``tmp`` in the format of ``suffix`` (module docstring)."""
    if suffix == ".npz":
        with open(tmp, "wb") as fh:
            np.savez(fh, **cols)
    elif suffix in (".parquet", ".pq"):
        import pyarrow as pa
        import pyarrow.parquet as pq

        pq.write_table(pa.table({k: pa.array(np.asarray(v)) for k, v in cols.items()}), tmp)
    else:
        delim = "\t" if suffix == ".tsv" else ","
        text_cols = [np.asarray(v) for v in cols.values()]
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(delim.join(cols) + "\n")
            if all(c.dtype.kind in "fiub" for c in text_cols):
                np.savetxt(fh, np.column_stack(text_cols).astype(float), delimiter=delim, fmt="%.17g")
            else:
                for row in zip(*text_cols):
                    fh.write(delim.join(str(x) if isinstance(x, str) else f"{float(x):.17g}" for x in row) + "\n")


@contextlib.contextmanager
def column_writer(path, names: list[str], inputs=(), what: str = "--out"):
    """Write columns block by block (a streamed run's predictions), atomically.

    CSV/TSV rows are appended as they come (``%.17g``, the header first), Parquet by row groups
    (``pyarrow.parquet.ParquetWriter``, float64); NPZ cannot be appended to: its blocks are held
    and written at the end. The file appears under ``path`` only when the block ends without
    error (:func:`baseparams.files.atomic_path`).

    Parameters
    ----------
    path : str or path
        The file (suffix as for :func:`write_columns`).
    names : list of str
        The column names, in order.
    inputs : iterable of str or path
        The run's input files.
    what : str
        The option, for messages.

    Yields
    ------
    callable
        ``write(block)``: ``block`` an ``(k, len(names))`` array of numbers, the next ``k`` rows.

    Raises
    ------
    BaseparamsError
        As :func:`check_table_path`.
    """
    check_table_path(path, inputs, what)
    suffix = Path(path).suffix.lower()
    with atomic_path(path, inputs, what) as tmp:
        held: list = []
        if suffix in (".parquet", ".pq"):
            import pyarrow as pa
            import pyarrow.parquet as pq

            schema = pa.schema([(n, pa.float64()) for n in names])
            with pq.ParquetWriter(tmp, schema) as pw:
                yield lambda block: pw.write_table(pa.table({n: np.asarray(block, float)[:, k]
                                                             for k, n in enumerate(names)}, schema=schema))
        elif suffix == ".npz":
            yield lambda block: held.append(np.asarray(block, float))
            cat = np.concatenate(held) if held else np.empty((0, len(names)))
            with open(tmp, "wb") as fh:
                np.savez(fh, **{n: cat[:, k] for k, n in enumerate(names)})
        else:
            delim = "\t" if suffix == ".tsv" else ","
            with open(tmp, "w", encoding="utf-8", newline="") as fh:
                fh.write(delim.join(names) + "\n")
                yield lambda block: np.savetxt(fh, np.asarray(block, float), delimiter=delim, fmt="%.17g")
