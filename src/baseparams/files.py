"""Safe file output: every write atomic, never onto an input, never through a non-regular path.

Every writer of the library and the CLI goes through :func:`atomic_path` (or the shortcuts
:func:`write_text` and :func:`write_bytes`): the content is written to a temporary file beside
the target and renamed over it only when complete, so an interrupted run (SIGINT, SIGTERM, a
full disk, an exception) never leaves a partial file under the final name, and concurrent
writers of one file leave one writer's complete content. :func:`refuse_inputs` refuses an
output path that names one of the run's input files.

Every reader of a user path goes through :func:`check_input` (or :func:`read_input_bytes`): a
path that is not a regular file (a folder, ``/dev/zero``, a FIFO, a socket) is refused at once,
in one line, and a robot file larger than :data:`MODEL_MAX_BYTES` is refused before it is read.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from .errors import ArgumentTypeError, BaseparamsError

#: the largest robot file (URDF, MJCF, DH table) read, in bytes: 64 MB; the largest robot
#: descriptions in use are a few MB, so a larger file is refused before it is read
MODEL_MAX_BYTES = 64 * 2**20
#: the largest small side file (a ``--columns`` TOML mapping) read, in bytes: 1 MB
SMALL_MAX_BYTES = 2**20


def _mb(n: int) -> str:
    return f"{n / 2**20:.3g} MB"


def check_input(path, max_bytes: int | None = None, folder_ok: bool = False, error=BaseparamsError) -> Path:
    """Refuse an input path that is missing, not a regular file, or larger than ``max_bytes``.

    The check is a ``stat`` (symbolic links followed): nothing is opened, so a FIFO or a device
    never blocks and is refused at once.

    Parameters
    ----------
    path : str or path
        The input.
    max_bytes : int, optional
        The largest size accepted (default: no bound), e.g. :data:`MODEL_MAX_BYTES`.
    folder_ok : bool
        A folder is accepted too (a ROS 2 bag is a folder).
    error : type
        The exception class raised (a :class:`~baseparams.errors.BaseparamsError`).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    BaseparamsError
        ``PATH: no such file``, ``PATH: not a regular file`` or ``PATH: N MB, larger than ...``.
    """
    p = Path(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise error(f"{p}: no such file") from None
    except OSError as exc:
        raise error(f"{p}: cannot read ({exc.strerror or exc})") from None
    if folder_ok and stat.S_ISDIR(st.st_mode):
        return p
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{p}: not a regular file")
    if max_bytes is not None and st.st_size > max_bytes:
        raise error(f"{p}: {_mb(st.st_size)}, larger than the {_mb(max_bytes)} such a file may have")
    return p


def read_input_bytes(path, max_bytes: int | None = MODEL_MAX_BYTES, error=BaseparamsError) -> bytes:
    """The content of a regular file of at most ``max_bytes``, checked on the open file.

    The file is opened without blocking and checked with ``fstat`` (so a path swapped for a FIFO
    or a device after a check is still refused), then read up to ``max_bytes``.

    Parameters
    ----------
    path : str or path
        The input.
    max_bytes : int or None
        The largest size accepted (default :data:`MODEL_MAX_BYTES`; None: no bound).
    error : type
        The exception class raised.

    Returns
    -------
    bytes
        The content.

    Raises
    ------
    BaseparamsError
        As :func:`check_input`.
    """
    p = check_input(path, max_bytes, error=error)
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise error(f"{p}: cannot read ({exc.strerror or exc})") from None
    with os.fdopen(fd, "rb") as fh:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise error(f"{p}: not a regular file")
        try:
            data = fh.read(max_bytes + 1) if max_bytes is not None else fh.read()
        except OSError as exc:
            raise error(f"{p}: cannot read ({exc.strerror or exc})") from None
    if max_bytes is not None and len(data) > max_bytes:
        raise error(f"{p}: larger than the {_mb(max_bytes)} such a file may have")
    return data


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
    if isinstance(inputs, (str, bytes, os.PathLike)) or not hasattr(inputs, "__iter__"):
        raise ArgumentTypeError(f"inputs must be a sequence of the run's input files, got {type(inputs).__name__}")
    for inp in inputs:
        if inp is None:
            continue
        if not isinstance(inp, (str, os.PathLike)):
            raise ArgumentTypeError(f"inputs must be file paths, got {type(inp).__name__}")
        p = Path(inp)
        if p.exists() and out.exists() and _same_file(out, p) or out.resolve() == p.resolve():
            raise BaseparamsError(f"{what} {output} would overwrite the input {inp}; choose another file name")


#: paths that name the process's own standard streams: written to the stream, never replaced
STANDARD_STREAMS = {"/dev/stdout": 1, "/dev/stderr": 2, "/dev/fd/1": 1, "/dev/fd/2": 2, "/proc/self/fd/1": 1,
                    "/proc/self/fd/2": 2}
#: folders where no output file is ever created or replaced (devices, kernel interfaces)
SYSTEM_FOLDERS = ("/dev", "/proc", "/sys")


def _in_system_folder(p: str) -> bool:
    return any(p == d or p.startswith(d + "/") for d in SYSTEM_FOLDERS)


def output_target(path, what: str = "output") -> tuple[str, object]:
    """How an output path is written: a regular file replaced atomically, or a stream written once.

    * ``/dev/stdout``, ``/dev/stderr`` (and ``/dev/fd/1``, ``/proc/self/fd/2``, ...): the process's
      own stream, written when the content is complete (nothing is renamed in ``/dev``);
    * an existing character device (``/dev/null``, a terminal) or FIFO (a pipe, ``>(cmd)``): written
      once the content is complete, as a stream (a FIFO no process reads is refused, not waited for);
    * a symbolic link to a regular file (or to a file yet to be created): the file it points to is
      replaced, the link kept;
    * anything else that exists and is not a regular file (a folder, a block device, a socket), and
      any new file inside ``/dev``, ``/proc`` or ``/sys``: refused.

    Parameters
    ----------
    path : str or path
        The output.
    what : str
        The output's role, for messages.

    Returns
    -------
    kind : {"file", "stream", "std"}
        How it is written.
    target : pathlib.Path or int
        The regular file to replace (links resolved), the stream's path, or the file descriptor
        (1 or 2) of a standard stream.

    Raises
    ------
    BaseparamsError
        A target that is not written (above), one line.
    """
    if not isinstance(path, (str, os.PathLike)) or not isinstance(os.fspath(path), str):
        raise ArgumentTypeError(f"{what} must be a file path (str or pathlib.Path), got {type(path).__name__}")
    p = Path(path)
    a = os.path.abspath(p)
    if a in STANDARD_STREAMS:
        return "std", STANDARD_STREAMS[a]
    if a in ("/dev/stdin", "/dev/fd/0", "/proc/self/fd/0"):
        raise BaseparamsError(f"{what} {p}: the standard input is not an output")
    try:
        st = os.stat(p)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise BaseparamsError(f"{what} {p}: cannot write ({exc.strerror or exc})") from None
    if st is not None and (stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode)):
        return "stream", p
    if st is not None and not stat.S_ISREG(st.st_mode):
        kind = "a folder" if stat.S_ISDIR(st.st_mode) else "a block device" if stat.S_ISBLK(st.st_mode) else \
            "a socket" if stat.S_ISSOCK(st.st_mode) else "something else"
        raise BaseparamsError(f"{what} {p}: exists and is {kind}, not a regular file; not written")
    real = Path(os.path.realpath(p))
    if _in_system_folder(str(real)) or (st is None and _in_system_folder(a)):
        if st is not None:  # /dev/fd/N or /proc/PID/fd/N of a regular file: written through the descriptor
            return "stream", p
        raise BaseparamsError(f"{what} {p}: no new file is created in {', '.join(SYSTEM_FOLDERS)}; choose another "
                              "file name (or /dev/stdout)")
    return "file", real


def check_output(path, inputs: Iterable = (), what: str = "output") -> Path:
    """Refuse an output that cannot be written, before any work: returns its folder.

    Parameters
    ----------
    path : str or path
        The output file.
    inputs : iterable of str or path
        Input files the output must not overwrite (:func:`refuse_inputs`).
    what : str
        The output's role, for messages.

    Returns
    -------
    pathlib.Path
        The folder the file will be written in (a stream's: its own folder).

    Raises
    ------
    BaseparamsError
        An output onto an input, a target that is not written (:func:`output_target`), a missing
        folder.
    """
    kind, target = output_target(path, what)
    final = Path(path)
    if kind != "file":
        return final.parent
    refuse_inputs(final, inputs, what)
    refuse_inputs(target, inputs, what)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise BaseparamsError(f"{what} {final}: the folder {folder} does not exist")
    return folder


def _replace_message(what: str, final: Path, exc: OSError) -> str:
    hint = " (immutable or append-only? lsattr shows it)" if exc.errno in (1, 13) and final.exists() else ""
    return f"{what} {final}: cannot write ({exc.strerror or exc}){hint}; nothing was written"


@contextlib.contextmanager
def atomic_path(path, inputs: Iterable = (), what: str = "output") -> Iterator[Path]:
    """A temporary path beside ``path``, renamed to ``path`` when the block ends without error.

    Parameters
    ----------
    path : str or path
        The final file. Its folder must exist; an existing non-regular file (a folder, a block
        device, a socket) is refused; a symbolic link's target is replaced (the link kept); a
        standard stream, character device or FIFO is written as a stream once the content is
        complete (:func:`output_target`).
    inputs : iterable of str or path
        Input files the output must not overwrite (:func:`refuse_inputs`).
    what : str
        The output's role, for messages.

    Yields
    ------
    pathlib.Path
        Where to write (same suffix as ``path``, so that writers choosing a format by suffix
        choose the same one). On an exception it is removed and ``path`` is left as it was.

    Raises
    ------
    BaseparamsError
        An output onto an input, a missing folder, a non-regular target, a target that cannot be
        replaced or written (permissions, an immutable file, a full disk): one line, the old file
        left as it was.
    """
    kind, target = output_target(path, what)  # a path of the right type first
    final = Path(path)
    if kind != "file":
        with _stream_path(final, kind, target, what) as tmp:
            yield tmp
        return
    folder = check_output(final, inputs, what)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".tmp{final.suffix}", dir=folder)
    except OSError as e:
        raise BaseparamsError(f"{what} {final}: cannot write in {folder} ({e.strerror})") from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        try:
            yield tmp_path
            if target.exists():
                with contextlib.suppress(OSError):
                    os.chmod(tmp_path, target.stat().st_mode & 0o777)
            else:
                with contextlib.suppress(OSError):
                    umask = os.umask(0)
                    os.umask(umask)
                    os.chmod(tmp_path, 0o666 & ~umask)
            os.replace(tmp_path, target)
        except OSError as exc:
            raise BaseparamsError(_replace_message(what, final, exc)) from None
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


@contextlib.contextmanager
def _stream_path(final: Path, kind: str, target, what: str) -> Iterator[Path]:
    """A temporary file in a private folder, copied to a stream when the block ends without error."""
    import shutil
    import sys

    folder = tempfile.mkdtemp(prefix="baseparams-")
    tmp = Path(folder) / f"output{final.suffix}"
    try:
        yield tmp
        data = tmp.read_bytes() if tmp.exists() else b""
        if kind == "std":
            stream = sys.stdout if target == 1 else sys.stderr
            stream.flush()
            buffer = getattr(stream, "buffer", None)
            if buffer is not None:
                buffer.write(data)
                buffer.flush()
            else:
                stream.write(data.decode("utf-8", "replace"))
                stream.flush()
            return
        _write_stream(final, data, what)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _write_stream(path: Path, data: bytes, what: str) -> None:
    """Write ``data`` to a character device or FIFO; a FIFO no process reads is refused, not waited for."""
    import errno
    import fcntl

    try:
        fd = os.open(path, os.O_WRONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except OSError as exc:
        why = "no process reads it" if exc.errno == errno.ENXIO else (exc.strerror or str(exc))
        raise BaseparamsError(f"{what} {path}: cannot write ({why})") from None
    try:
        fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
        view = memoryview(data)
        while view:
            n = os.write(fd, view)
            view = view[n:]
    except OSError as exc:
        raise BaseparamsError(f"{what} {path}: cannot write ({exc.strerror or exc})") from None
    finally:
        os.close(fd)


def write_text(path, text: str, inputs: Iterable = (), what: str = "output") -> Path:
    """Write to ``path`` atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or path
        The final file.
    text : str
        The content (written as UTF-8).
    inputs : iterable of str or path
        Input files the output must not overwrite.
    what : str
        The output's role, for messages.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with atomic_path(path, inputs, what) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_pieces(path, pieces: Iterable[str], inputs: Iterable = (), what: str = "output") -> Path:
    """Write consecutive pieces of text to ``path`` atomically (:func:`atomic_path`), each as it comes.

    Parameters
    ----------
    path : str or path
        The final file.
    pieces : iterable of str
        The content in order (UTF-8), e.g. a report made line by line: never held whole.
    inputs : iterable of str or path
        Input files the output must not overwrite.
    what : str
        The output's role, for messages.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with atomic_path(path, inputs, what) as tmp, open(tmp, "w", encoding="utf-8") as f:
        for piece in pieces:
            f.write(piece)
    return Path(path)


def write_bytes(path, data: bytes, inputs: Iterable = (), what: str = "output") -> Path:
    """Write to ``path`` atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or path
        The final file.
    data : bytes
        The content.
    inputs : iterable of str or path
        Input files the output must not overwrite.
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
