"""Safe file output: every write atomic, never onto an input, never through a non-regular path.

Every writer of the library and the CLI goes through :func:`atomic_path` (or the shortcuts
:func:`write_text` and :func:`write_bytes`): the content is written to a temporary file beside
the target and renamed over it only when complete, so an interrupted run (SIGINT, SIGTERM, a
full disk, an exception) never leaves a partial file under the final name, and concurrent
writers of one file leave one writer's complete content. :func:`refuse_inputs` refuses an
output path that names one of the run's input files.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from .errors import BaseparamsError


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return a.resolve() == b.resolve()


def refuse_inputs(output, inputs: Iterable, what: str = "output") -> None:
    """Refuse an output path that is one of the run's inputs (the same file, by any name).

    Parameters
    ----------
    output : str or path or None
        The output path (None: nothing to check).
    inputs : iterable of str or path or None
        The run's input files (model, logs, trajectory, ...); None entries and built-in names
        that are not files are skipped.
    what : str
        The output's role, for the message (``--output``, ``--urdf``, ...).

    Raises
    ------
    BaseparamsError
        ``OUTPUT would overwrite the input INPUT``.
    """
    if output is None:
        return
    out = Path(output)
    for inp in inputs:
        if inp is None:
            continue
        p = Path(inp)
        if p.exists() and out.exists() and _same_file(out, p) or out.resolve() == p.resolve():
            raise BaseparamsError(f"{what} {output} would overwrite the input {inp}; choose another file name")


@contextlib.contextmanager
def atomic_path(path, inputs: Iterable = (), what: str = "output") -> Iterator[Path]:
    """A temporary path beside ``path``, renamed to ``path`` when the block ends without error.

    Parameters
    ----------
    path : str or path
        The final file. Its folder must exist; an existing non-regular file (a folder, a
        device, a FIFO) is refused.
    inputs : iterable of str or path
        Input files the output must not overwrite (:func:`refuse_inputs`).
    what : str
        The output's role, for messages.

    Yields
    ------
    pathlib.Path
        Where to write (same folder and suffix as ``path``, so that writers choosing a format
        by suffix choose the same one). On an exception it is removed and ``path`` is left
        as it was.

    Raises
    ------
    BaseparamsError
        An output onto an input, a missing folder, a non-regular target.
    """
    final = Path(path)
    refuse_inputs(final, inputs, what)
    if final.exists() and not final.is_file():
        raise BaseparamsError(f"{what} {final}: exists and is not a regular file")
    folder = final.parent if str(final.parent) else Path(".")
    if not folder.is_dir():
        raise BaseparamsError(f"{what} {final}: the folder {folder} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{final.name}.", suffix=f".tmp{final.suffix}", dir=folder)
    except OSError as e:
        raise BaseparamsError(f"{what} {final}: cannot write in {folder} ({e.strerror})") from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        if final.exists():
            with contextlib.suppress(OSError):
                os.chmod(tmp_path, final.stat().st_mode & 0o777)
        else:
            with contextlib.suppress(OSError):
                umask = os.umask(0)
                os.umask(umask)
                os.chmod(tmp_path, 0o666 & ~umask)
        os.replace(tmp_path, final)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


def write_text(path, text: str, inputs: Iterable = (), what: str = "output") -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or path
        The file written.
    text : str
        Its content.
    inputs : iterable of str or path
        Input files ``path`` must not be (:func:`refuse_inputs`).
    what : str
        The output's role, for messages (``--urdf``, ...).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with atomic_path(path, inputs, what) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_bytes(path, data: bytes, inputs: Iterable = (), what: str = "output") -> Path:
    """Write ``data`` to ``path`` atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or path
        The file written.
    data : bytes
        Its content.
    inputs : iterable of str or path
        Input files ``path`` must not be (:func:`refuse_inputs`).
    what : str
        The output's role, for messages.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with atomic_path(path, inputs, what) as tmp:
        tmp.write_bytes(data)
    return Path(path)
