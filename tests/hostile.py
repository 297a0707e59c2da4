"""Helpers of the attack tests: one line within a deadline, a subprocess within memory and time."""

from __future__ import annotations

import contextlib
import os
import resource
import signal
import subprocess
import sys
import time

#: the memory a subprocess attack may use (address space): a normal run takes well under 1 GB
MEMORY_BYTES = 3 * 2**30 // 2


@contextlib.contextmanager
def deadline(seconds: int):
    """Fail (instead of hanging the suite) when the block runs longer than ``seconds``."""
    def _late(*_):
        raise TimeoutError(f"took more than {seconds} s")
    old = signal.signal(signal.SIGALRM, _late)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def one_line_error(argv, capsys, seconds: int = 30, code: int = 2) -> str:
    """Run the CLI in-process: exit ``code`` and exactly one stderr line ``baseparams: error: ...``."""
    from baseparams.cli import main

    capsys.readouterr()
    t0 = time.perf_counter()
    with deadline(seconds):
        try:
            got = main([str(a) for a in argv])
        except SystemExit as exc:  # argparse: a flag it cannot parse
            got = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert got == code and len(err) == 1 and err[0].startswith("baseparams: error:"), (got, err)
    assert "Traceback" not in err[0] and time.perf_counter() - t0 < seconds
    return err[0]


def api_error(call, *args, match: str | None = None, **kwargs) -> str:
    """Call a Python API: it raises a BaseparamsError, TypeError or ValueError of one line; the line."""
    from baseparams.errors import BaseparamsError

    try:
        call(*args, **kwargs)
    except (BaseparamsError, TypeError, ValueError) as exc:
        msg = str(exc)
    else:
        raise AssertionError(f"{getattr(call, '__name__', call)}{args}{kwargs}: no error")
    assert msg and "\n" not in msg, msg
    if match is not None:
        assert match in msg, (match, msg)
    return msg


def run_cli(argv, seconds: int = 60, memory: int = MEMORY_BYTES, cwd=None) -> subprocess.CompletedProcess:
    """``python -m baseparams ARGV`` in a subprocess limited to ``memory`` bytes of address space.

    A run that allocates beyond it fails (MemoryError: a traceback), one that takes longer than
    ``seconds`` raises ``subprocess.TimeoutExpired``.
    """
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))

    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "baseparams", *map(str, argv)], capture_output=True, text=True,
                          timeout=seconds, preexec_fn=limit, env=env, cwd=cwd)


def refused_in_a_subprocess(argv, seconds: int = 60, memory: int = MEMORY_BYTES, cwd=None) -> str:
    """The CLI in a bounded subprocess: exit 2, one stderr line, no traceback; the line."""
    import re

    r = run_cli(argv, seconds, memory, cwd)
    progress = re.compile(r"baseparams: (?!error:).* \[\d+\.\d s\]$")  # a slow machine shows progress after 2 s
    err = [line for line in r.stderr.strip().splitlines() if not progress.match(line)]
    assert r.returncode == 2 and len(err) == 1 and err[0].startswith("baseparams: error:"), (r.returncode, err[-5:])
    return err[0]


def hostile_path(kind: str, path):
    """``path`` made a FIFO, a link to ``/dev/zero``, a folder or a sparse 1 GB file; returned."""
    import pathlib

    p = pathlib.Path(path)
    if kind == "fifo":
        os.mkfifo(p)
    elif kind == "dev_zero":
        p.symlink_to("/dev/zero")
    elif kind == "folder":
        p.mkdir()
    elif kind == "sparse_1gb":
        with open(p, "wb") as fh:
            fh.truncate(2**30)
    else:
        raise ValueError(kind)
    return p
