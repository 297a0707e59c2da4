"""Long logs (issue 41): ``baseparams identify puma560 LOG`` on 10^5-10^7-row CSV, NPZ and Parquet logs.

Each log is one simulated Puma560 piece (``BLOCK`` rows at 500 Hz, noise 0.2 N m, the default
layout: ``t``, ``q_*``, ``dq_*``, ``tau_*``) repeated with shifted time, written block by block
(memory independent of the length; the NPZ members are streamed into the archive). Each
identification runs in a fresh process with the default flags, as an outsider runs it; its wall
time and peak resident memory come from ``os.wait4`` (the kernel's ``ru_maxrss``, what
``/usr/bin/time -v`` reports). Run as part of ``benchmarks/run.py --only scale_logs`` or alone::

    PYTHONPATH=src python3 benchmarks/scale_logs.py --rows 10000000 --out /tmp/logs   # only write the logs
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

#: rows of the simulated piece repeated (20 periods of the 10 s excitation at 500 Hz)
BLOCK = 10**5
RATE = 500.0
FORMATS = ("csv", "npz", "parquet")
_SRC = Path(__file__).resolve().parents[1] / "src"


def _piece() -> tuple[list[str], np.ndarray]:
    """The simulated piece: column names and ``(BLOCK, columns)`` values."""
    import baseparams
    from baseparams.ident.simulate import simulate_log
    from baseparams.io.logs import log_columns_of

    robot = baseparams.load("puma560")
    sim, _ = simulate_log(robot, duration=BLOCK / RATE, rate=RATE, noise=0.2, rotor=True, seed=0)
    cols = log_columns_of(sim)
    return list(cols), np.column_stack(list(cols.values()))


def _pieces(data: np.ndarray, rows: int):
    """The log's blocks: the piece repeated, time shifted, ``rows`` in all."""
    for k in range(0, rows, BLOCK):
        part = data[: min(BLOCK, rows - k)].copy()
        part[:, 0] += k / RATE
        yield part


def write_log(path: Path, rows: int, piece=None) -> Path:
    """Write a ``rows``-row log (suffix ``.csv``, ``.npz`` or ``.parquet``) block by block; its path.

    Parameters
    ----------
    path : Path
        The file (replaced).
    rows : int
        Samples.
    piece : tuple, optional
        :func:`_piece`'s result (computed when not given).

    Returns
    -------
    Path
        ``path``.
    """
    names, data = piece or _piece()
    path = Path(path)
    tmp = path.with_name(path.name + ".part")
    kind = path.suffix.lower()
    if kind == ".csv":
        import pyarrow as pa
        import pyarrow.csv as pcsv

        with open(tmp, "wb") as fh:
            fh.write((",".join(names) + "\n").encode())
            opts = pcsv.WriteOptions(include_header=False, quoting_style="none")
            with pcsv.CSVWriter(fh, pa.schema([(n, pa.float64()) for n in names]), write_options=opts) as w:
                for part in _pieces(data, rows):
                    w.write_table(pa.table({n: part[:, k] for k, n in enumerate(names)}))
    elif kind == ".parquet":
        import pyarrow as pa
        import pyarrow.parquet as pq

        with pq.ParquetWriter(str(tmp), pa.schema([(n, pa.float64()) for n in names])) as w:
            for part in _pieces(data, rows):
                w.write_table(pa.table({n: part[:, k] for k, n in enumerate(names)}), row_group_size=BLOCK)
    elif kind == ".npz":  # np.savez's layout (stored members), each member streamed column block by block
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_STORED, allowZip64=True) as z:
            for k, n in enumerate(names):
                with z.open(n + ".npy", "w", force_zip64=True) as fh:
                    np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False,
                                                              "shape": (rows,)})
                    for part in _pieces(data, rows):
                        fh.write(np.ascontiguousarray(part[:, k]).tobytes())
    else:
        raise ValueError(f"{path}: .csv, .npz or .parquet")
    os.replace(tmp, path)
    return path


def identify_run(robot: str, path: Path, extra=()) -> dict:
    """``baseparams identify ROBOT PATH`` in a fresh process: ``{"s", "peak_mb", "ok", "err"}``.

    Peak memory is the child's ``ru_maxrss`` (``os.wait4``) in MB (1e6 bytes).
    """
    env = dict(os.environ, PYTHONPATH=str(_SRC))
    with tempfile.TemporaryFile("w+") as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "baseparams", "identify", robot, str(path), *extra],
                                stdout=subprocess.DEVNULL, stderr=err, text=True, env=env)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        text = err.read()
    return {"s": wall, "peak_mb": usage.ru_maxrss * 1024 / 1e6, "ok": proc.returncode == 0, "err": text}


def bench_scale_logs(out: dict, quick: bool, log=print) -> None:
    """Wall time and peak memory of ``identify puma560 LOG`` (default flags, fresh process) on
    10^5, 10^6 and 10^7-row CSV, NPZ and Parquet logs (10^4-10^6 with --quick, one run each), the
    log sizes, and the exponent of time vs rows between the two largest logs (the smallest is read
    whole: below the 64 MB from which a log is streamed)."""
    sizes = (10**4, 10**5, 10**6) if quick else (10**5, 10**6, 10**7)
    piece = _piece()
    with tempfile.TemporaryDirectory() as d:
        for fmt in FORMATS:
            walls = []
            for rows in sizes:
                path = write_log(Path(d) / f"puma560_{rows}.{fmt}", rows, piece)
                key = f"scale_logs_{fmt}_1e{round(math.log10(rows))}"
                log(f"  identify puma560 {rows}-row {fmt.upper()} ({path.stat().st_size / 1e6:.0f} MB) ...")
                r = identify_run("puma560", path)
                out[f"{key}_mb_file"] = path.stat().st_size / 1e6
                path.unlink()
                if not r["ok"]:
                    log(f"    failed: {r['err'].strip()[-300:]}")
                    out[f"{key}_s"] = out[f"{key}_peak_mb"] = None
                    continue
                out[f"{key}_s"] = r["s"]
                out[f"{key}_s_repeats"] = 1
                out[f"{key}_peak_mb"] = r["peak_mb"]
                walls.append((rows, r["s"]))
            if len(walls) >= 2:  # between the two largest logs: the smallest is read whole (below 64 MB)
                (r0, s0), (r1, s1) = walls[-2:]
                out[f"scale_logs_{fmt}_time_exponent"] = float(np.log(s1 / s0) / np.log(r1 / r0))


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description="write long Puma560 logs (CSV, NPZ, Parquet) block by block")
    ap.add_argument("--rows", type=int, default=10**7)
    ap.add_argument("--out", type=Path, default=Path("/tmp"))
    ap.add_argument("--formats", default=",".join(FORMATS))
    a = ap.parse_args()
    pc = _piece()
    for f in a.formats.split(","):
        t = time.perf_counter()
        p = write_log(a.out / f"puma560_{a.rows}.{f}", a.rows, pc)
        print(f"{p}: {p.stat().st_size / 1e6:.0f} MB in {time.perf_counter() - t:.1f} s", file=sys.stderr)
