#!/usr/bin/env python3
"""Benchmarks for baseparams (standalone script; not collected by pytest).

Usage::

    PYTHONPATH=src python3 benchmarks/run.py            # human-readable table
    PYTHONPATH=src python3 benchmarks/run.py --json     # exactly one JSON object on stdout
    PYTHONPATH=src python3 benchmarks/run.py --quick    # smaller sizes, fewer repeats (< 60 s)
    PYTHONPATH=src python3 benchmarks/run.py --only drng_scaling
    PYTHONPATH=src python3 benchmarks/run.py --blas-threads 0   # leave BLAS threading alone

Figure groups (``--only SUBSTRING`` selects groups whose name contains SUBSTRING):

* ``regressor``     TP regressor vs a Python loop over ``pin.computeJointTorqueRegressor``
                    (Puma560, Go2, talos_full_v2; S = 1, 100, 10000 samples); at S = 10000 the
                    compiled kernel (fresh output, reused ``out=``, one thread) vs the floor,
                    one write pass over the output.
* ``base_streaming``  base regressor + streaming QR over 10^6 Puma560 samples.
* ``analyze_cli``   ``baseparams analyze`` end to end in fresh processes.
* ``vs_pinocchio``  ``baseparams analyze`` end to end (fresh process) against the bare Pinocchio
                    numerical rank (fresh process: import, URDF, 100 random states, stacked
                    ``computeJointTorqueRegressor``, SVD rank), talos_full_v2 (free flyer) and Puma560
                    (a URDF written from the built-in), with and without the package's bytecode caches.
* ``identify``      ``identify`` on 10^6 simulated Puma560 samples end to end; the physical solve
                    on the Panda and on a 32-body humanoid.
* ``stream``        ``baseparams identify puma560 LOG.csv`` on generated 10^6- and 10^7-row CSV logs, streamed
                    (``--stream on``) and read whole (10^6 rows): wall time and peak resident memory.
* ``fleet``         Dask: 10^8 synthetic Puma560 samples, throughput with 1 and 2 workers, peak memory.
* ``scale_logs``    ``baseparams identify puma560 LOG`` (default flags, fresh process) on 10^5, 10^6 and
                    10^7-row CSV, NPZ and Parquet logs: wall, peak memory (``ru_maxrss``), log sizes, the
                    exponent of time vs rows (``benchmarks/scale_logs.py``).
* ``excite``        excitation design time and condition number (Puma560, Panda, pkm-2rru-1rrs).
* ``drng_vs_numerical``  DRNG vs the numerical method (100 samples) and ``certify``.
* ``drng_scaling``  DRNG on random chains and trees of N = 10 .. 10000 bodies.
* ``size_sweep``    ``baseparams analyze FILE --floating --json`` on random floating trees (URDF) of
                    N = 10 .. 10000 links: wall time, peak memory, status, nullity.
* ``large_inputs``  issue 51: ``identify`` of a 220-link random chain (paper convention, 500 samples) and of a
                    10^6-sample 100 kHz Puma560 log, fresh processes: wall, peak memory, the log's arrays; and
                    ``analyze`` of 1 000-link prismatic and revolute chains (in process): seconds, their ratio.
* ``scale_trees``   issue 41: ``baseparams analyze --floating`` (certified, fresh processes) on chains, random deep
                    trees and wide random trees of N = 100, 1 000, 10 000 bodies: wall, peak RSS, nullity, and
                    the exponent of the curve between 1 000 and 10 000.
* ``loops``         DRNG on the two PKMs vs the paper's 5000-sample numerical validation.
* ``files``         every example-robot-data URDF, every ``../shared/models`` file and every MJCF model of
                    gymnasium and dm_control: certified, DRNG complete?; talos_full_v2 times.
* ``hands``         issue 46: CAD five-finger hands (URDF and MJCF, ``tests/hands.py``): design counts, UNDECIDED,
                    values snapped, default vs literal analysis time.
* ``cross_recording``  identify on one recording, the raw RMS on another (simulated recordings with the
                    defects real logs have, the Panda and TX40 logs split by time): default vs plain OLS,
                    WLS, physical (``benchmarks/cross_recording.py``).
* ``generalization``  issue 48: train on one motion, predict another (simulated recorder-filtered arms, the Panda
                    and TX40 logs, both directions), against an outsider's plain OLS on every sample.
* ``several_recordings``  issue 48: a simulated plant's first one, two and three recordings -> its fourth, with and
                    without the model terms (each recording one cross-validation fold of the estimate and the terms).
* ``currents``      issue 50: identification from motor currents with unknown gains: a simulated 7-DoF arm (held-out
                    joint-side torques against its sensors: one catalogue gain as the anchor, every catalogue gain, OLS
                    given the catalogue gains, a fit on the sensors) and the TX40's motor-side log
                    (``benchmarks/currents.py``).
* ``model_terms``   the Panda's held-out 5 Hz figure per model class: linear, + pre-sliding friction,
                    + tilt, + delay, + scale, and the terms cross-validation keeps.
* ``payload``       issue 49: a 3.2 kg payload off-axis and rotated on a MuJoCo-simulated Panda (armature,
                    damping, friction loss, a servo, 1.5 % AR(1) noise), full-arm and wrist-only motions, the
                    robot known from its URDF, an MJCF, or the project's identification of a payload-free log:
                    mass, centre-of-mass and inertia errors, 2-sigma coverage, time (``benchmarks/payload.py``).
* ``report``        the HTML analysis report (Puma560, talos_full_v2): generation time, size, and the
                    page's own render time in headless Chromium (``data-render-ms``).

Every timing is the median over ``repeats`` runs of ``time.perf_counter`` after one
untimed warm-up call; the number of repeats is reported next to every timing (the
``<figure>_repeats`` entries of the JSON). Progress goes to stderr.

BLAS runs single-threaded by default (``--blas-threads``, see benchmarks/README.md): with
OpenBLAS's default threads the numerical method's SVD was often 30-100x slower on this
noisy 2-vCPU machine, and no faster when the machine was quiet.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import signal
import statistics
import sys
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path

# Allow running from a checkout without installing (``python benchmarks/run.py``).
_SRC = Path(__file__).resolve().parent.parent / "src"
if _SRC.is_dir() and str(_SRC) not in sys.path:
    sys.path.insert(0, str(_SRC))
sys.path.insert(0, str(Path(__file__).resolve().parent))

np = None  # numpy, imported in main() after --blas-threads has set the environment

ROBOTS = ("puma560", "go2")
#: per-N wall-clock budget (s) for the DRNG scaling group (build + timing)
SCALING_BUDGET_S = 60.0


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# ----------------------------------------------------------------------------- helpers
class Timeout(Exception):
    pass


class time_limit:
    """Raise :class:`Timeout` after ``seconds`` (SIGALRM; a no-op where unavailable).

    Python code is interrupted between bytecodes; a single long C call finishes first."""

    def __init__(self, seconds: float):
        self.seconds = seconds
        self.ok = hasattr(signal, "SIGALRM") and hasattr(signal, "setitimer")

    def _raise(self, signum, frame):
        raise Timeout(f"exceeded {self.seconds:.0f} s")

    def __enter__(self):
        if self.ok:
            self.old = signal.signal(signal.SIGALRM, self._raise)
            signal.setitimer(signal.ITIMER_REAL, self.seconds)
        return self

    def __exit__(self, *exc):
        if self.ok:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, self.old)
        return False


def measure(fn: Callable[[], object], repeats: int, warmup: int = 1) -> tuple[float, int]:
    """Median seconds of ``fn()`` over ``repeats`` timed calls (after ``warmup`` calls)."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), repeats


def measure_pair(fa: Callable[[], object], fb: Callable[[], object], repeats: int) -> tuple[float, float, int]:
    """Median seconds of ``fa()`` and of ``fb()``, timed alternately (a, b, a, b, ...) so that a
    noisy machine affects both alike; for ratios of a variant against its baseline."""
    fa(), fb()
    ta, tb = [], []
    for _ in range(repeats):
        for fn, acc in ((fa, ta), (fb, tb)):
            t0 = time.perf_counter()
            fn()
            acc.append(time.perf_counter() - t0)
    return statistics.median(ta), statistics.median(tb), repeats


def peak_mb(fn: Callable[[], object]) -> float:
    """Peak traced memory (MB, 1e6 bytes) of one call of ``fn`` (tracemalloc; numpy
    registers its data buffers with tracemalloc)."""
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return peak / 1e6


def machine_info() -> dict:
    info = {
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "cpu_count": os.cpu_count(),
        "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS") or "default (all cores)",
    }
    try:
        import scipy
        info["scipy"] = scipy.__version__
    except ImportError:  # pragma: no cover
        pass
    try:
        import pinocchio
        info["pinocchio"] = pinocchio.__version__
    except ImportError:
        info["pinocchio"] = None
    try:  # which code was measured (the tree may have uncommitted edits)
        import subprocess
        root = Path(__file__).resolve().parent.parent
        info["git_commit"] = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True,
                                            text=True, timeout=10).stdout.strip() or None
        info["git_src_dirty"] = bool(subprocess.run(["git", "status", "--porcelain", "--", "src"], cwd=root,
                                                    capture_output=True, text=True, timeout=10).stdout.strip())
    except (OSError, subprocess.SubprocessError):
        pass
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    info["cpu_model"] = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return info


def _talos_path():
    """talos_full_v2.urdf of example-robot-data (a test dependency), or None."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    try:
        from erd import urdf_files
    except ImportError:
        return None
    found = [f for f in urdf_files() if f.name == "talos_full_v2.urdf"]
    return str(found[0]) if found else None


def _robot(name: str):
    import warnings

    from baseparams.robots import go2, puma560
    if name == "talos_full_v2":
        from baseparams.loading import load_model
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return load_model(_talos_path(), floating=True, strict_inertia=False)[0]
    return {"puma560": puma560, "go2": go2}[name]()


def _numba_threads(k: int | None) -> int:
    """Set numba's thread count (``None``: all cores); returns the count in effect."""
    import numba
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS if k is None else k)
    return numba.get_num_threads()


# ----------------------------------------------------------------------------- groups
def bench_regressor(out: dict, quick: bool) -> None:
    """Regressor vs Pinocchio's loop; at S = 10000 the compiled kernel (fresh output, reused
    ``out=`` buffer, one thread) against one write pass over the output (the floor)."""
    from baseparams.regressor import regressor
    try:
        import pinocchio as pin

        from baseparams.io.pinocchio import state_to_pinocchio, to_pinocchio
    except ImportError:
        pin = None
        log("  pinocchio not installed: skipping the Pinocchio side")

    sizes = (1, 100, 10000)
    reps = {1: 51, 100: 21, 10000: 5} if not quick else {1: 21, 100: 7, 10000: 3}
    names = ROBOTS + (("talos_full_v2",) if _talos_path() else ())
    for name in names:
        robot = _robot(name)
        model = data = None
        if pin is not None:
            model = to_pinocchio(robot)
            data = model.createData()
        for s in sizes:
            rng = np.random.default_rng(s)
            q, dq, ddq = (rng.uniform(0.0, 1.0, (s, robot.dof)) for _ in range(3))
            key = f"{name}_S{s}"
            log(f"  regressor {key}: ours ...")
            t_ours, r_ours = measure(lambda: regressor(robot, q, dq, ddq, backend="numpy"), reps[s])
            out[f"regressor_ours_{key}_s"] = t_ours
            out[f"regressor_ours_{key}_s_repeats"] = r_ours
            if s < 10000:
                out[f"regressor_peak_mb_{key}"] = peak_mb(lambda: regressor(robot, q, dq, ddq, backend="numpy"))
            t_pin = None
            if pin is not None:
                states = [state_to_pinocchio(robot, q[k], dq[k], ddq[k]) for k in range(s)]  # not timed

                def pin_loop():
                    for qp, vp, ap in states:
                        pin.computeJointTorqueRegressor(model, data, qp, vp, ap)

                log(f"  regressor {key}: pinocchio ...")
                t_pin, r_pin = measure(pin_loop, reps[s])
                out[f"regressor_pin_{key}_s"] = t_pin
                out[f"regressor_pin_{key}_s_repeats"] = r_pin
                out[f"regressor_numpy_vs_pinocchio_{key}"] = t_pin / t_ours
            if s == 10000:
                _bench_compiled(out, robot, key, q, dq, ddq, t_pin, reps[s])


def _bench_compiled(out: dict, robot, key: str, q, dq, ddq, t_pin: float | None, reps: int) -> None:
    """The compiled kernel at one batch size: fresh output, reused buffer (all threads, one)."""
    from baseparams.regressor import regressor

    s = q.shape[0]
    buf = np.empty((s, robot.dof, 10 * robot.n))
    regressor(robot, q[:2], dq[:2], ddq[:2], backend="compiled")  # compile / load the cache (not timed)
    log(f"  regressor {key}: compiled ...")
    threads = _numba_threads(None)
    t_floor, _ = measure(lambda: buf.fill(1.0), reps)
    t_fresh, _ = measure(lambda: regressor(robot, q, dq, ddq, backend="compiled"), reps)
    t_reuse, n_reuse = measure(lambda: regressor(robot, q, dq, ddq, out=buf, backend="compiled"), reps)
    _numba_threads(1)
    t_one, _ = measure(lambda: regressor(robot, q, dq, ddq, out=buf, backend="compiled"), reps)
    _numba_threads(None)
    out["regressor_compiled_threads"] = threads
    out[f"regressor_floor_{key}_us"] = 1e6 * t_floor / s
    out[f"regressor_compiled_fresh_{key}_us"] = 1e6 * t_fresh / s
    out[f"regressor_compiled_{key}_us"] = 1e6 * t_reuse / s
    out[f"regressor_compiled_{key}_us_repeats"] = n_reuse
    out[f"regressor_compiled_1thread_{key}_us"] = 1e6 * t_one / s
    out[f"regressor_numpy_{key}_us"] = 1e6 * out[f"regressor_ours_{key}_s"] / s
    out[f"regressor_vs_floor_{key}"] = t_reuse / t_floor
    out[f"regressor_fresh_vs_floor_{key}"] = t_fresh / t_floor
    if t_pin is not None:
        out[f"regressor_pin_{key}_us"] = 1e6 * t_pin / s
        out[f"regressor_vs_pinocchio_{key}"] = t_pin / t_reuse
        out[f"regressor_fresh_vs_pinocchio_{key}"] = t_pin / t_fresh
        out[f"regressor_1thread_vs_pinocchio_{key}"] = t_pin / t_one


def bench_base_streaming(out: dict, quick: bool) -> None:
    """Base regressor + streaming QR least squares over 10^6 Puma560 samples in chunks of 10^4:
    time, tracemalloc peak (independent of S), error of the recovered base parameters."""
    import baseparams
    from baseparams.numerics import StreamingQR

    robot = baseparams.load("puma560")
    res = baseparams.analyze(robot)
    nb, chunk = res.n_base, 10000
    beta = res.to_base(robot.parameters(res.convention), res.convention)
    res.base_regressor(np.zeros((2, 6)), backend="compiled")  # compile / load the cache (not timed)
    buf = np.empty((chunk, robot.dof, nb))

    def run(total: int):
        rng = np.random.default_rng(0)
        qr = StreamingQR(nb + 1)
        for _ in range(0, total, chunk):
            q, dq, ddq = (rng.uniform(-2.0, 2.0, (chunk, 6)) for _ in range(3))
            yb = res.base_regressor(q, dq, ddq, out=buf, backend="compiled")
            qr.add(yb, yb @ beta)
        return qr

    total = 10**5 if quick else 10**6
    log(f"  base regressor + streaming QR, {total} samples ...")
    t, n = measure(lambda: run(total), 1 if not quick else 3, warmup=0)
    r = run(total).r
    est = np.linalg.solve(r[:nb, :nb], r[:nb, nb])
    out["base_streaming_samples"] = total
    out["base_streaming_s"] = t
    out["base_streaming_s_repeats"] = n
    out["base_streaming_per_1e6_s"] = t * 1e6 / total
    out["base_streaming_peak_mb_1e5"] = peak_mb(lambda: run(10**5))
    out["base_streaming_beta_rel_error"] = float(np.abs(est - beta).max() / np.abs(beta).max())


def bench_identify(out: dict, quick: bool) -> None:
    """Identification: ``identify`` end to end on 10^6 simulated Puma560 samples (read an NPZ log,
    filter, regressor, OLS), its tracemalloc peak; the physical solve alone on the Panda log's
    compressed system and on a 32-body humanoid (talos_reduced, fixed base) with a prior."""
    import tempfile
    import warnings

    import baseparams
    from baseparams.ident import accumulate, fit, identify
    from baseparams.ident.model import ident_model
    from baseparams.ident.physical import physical_fit
    from baseparams.ident.simulate import fourier_trajectory, simulate_log
    from baseparams.io.logs import read_log, write_log

    robot = baseparams.load("puma560")
    total = 10**5 if quick else 10**6
    sim, _ = simulate_log(robot, duration=total / 1000.0, rate=1000.0, noise=0.1, seed=0)
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "sim.npz"
        write_log(path, sim)
        del sim

        def run():
            return identify(robot, read_log(path, robot), method="ols")

        log(f"  identify puma560, {total} samples (read, filter, regressor, OLS) ...")
        t, n = measure(run, 1 if not quick else 2, warmup=1)
        out["identify_samples"] = total
        out["identify_puma560_s"] = t
        out["identify_puma560_s_repeats"] = n
        out["identify_puma560_peak_mb"] = peak_mb(run)
    # the physical solve alone: Panda (real log) and a 32-body humanoid (simulated states)
    panda = Path(__file__).resolve().parents[2] / "shared" / "ident" / "panda_gaz2019"
    cases = []
    if panda.is_dir():
        sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
        rp = baseparams.load(str(panda / "panda_mdh_gaz2019.urdf"))
        mp = ident_model(baseparams.analyze(rp))
        rng = np.random.default_rng(0)
        _, q, dq, ddq = fourier_trajectory(7, 20.0, 100.0, rng, amplitude=0.5)
        tau = np.asarray(mp.regressor(q, dq, ddq) @ mp.theta(rp.parameters("paper"), np.ones(mp.drives.n_params)))
        cases.append(("panda", mp, accumulate(mp, q, dq, ddq, tau + rng.normal(scale=0.05, size=tau.shape))))
    hum = _talos_path()
    if hum:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from baseparams.loading import load_model
            rh, _ = load_model(hum.replace("talos_full_v2", "talos_reduced"), strict_inertia=False)
        mh = ident_model(baseparams.analyze(rh), friction=("viscous",))
        rng = np.random.default_rng(1)
        _, q, dq, ddq = fourier_trajectory(rh.dof, 20.0, 50.0, rng, amplitude=0.3)
        tau = mh.regressor(q, dq, ddq) @ mh.theta(rh.parameters("paper"), np.ones(mh.drives.n_params))
        cases.append(("talos_reduced", mh, accumulate(mh, q, dq, ddq, tau + rng.normal(scale=0.05, size=tau.shape))))
    for name, model, acc in cases:
        est = fit(model, acc, "wls").estimate
        log(f"  physical solve {name} ({model.robot.n} bodies) ...")
        t, n = measure(lambda: physical_fit(est.R11, est.r12, model.full_map(), model.robot,
                                            model.drives.param_kinds), 3 if not quick else 1)
        out[f"physical_solve_{name}_s"] = t
        out[f"physical_solve_{name}_s_repeats"] = n
        out[f"physical_solve_{name}_bodies"] = model.robot.n


def _repeated_csv(path: Path, rows: int, block: int = 10**5, rate: float = 500.0) -> None:
    """A simulated Puma560 log of ``rows`` rows (CSV, default layout, noise 0.2 N m): one simulated
    ``block``-row piece (a whole number of the 10 s excitation periods) repeated with shifted time."""
    import baseparams
    from baseparams.ident.simulate import simulate_log
    from baseparams.io.logs import log_columns_of

    robot = baseparams.load("puma560")
    sim, _ = simulate_log(robot, duration=block / rate, rate=rate, noise=0.2, rotor=True, seed=0)
    cols = log_columns_of(sim)
    data = np.column_stack(list(cols.values()))
    with open(path, "w") as fh:
        fh.write(",".join(cols) + "\n")
        for k in range(0, rows, block):
            part = data[: min(block, rows - k)].copy()
            part[:, 0] += k / rate
            np.savetxt(fh, part, delimiter=",", fmt="%.17g")


def bench_stream(out: dict, quick: bool) -> None:
    """``baseparams identify puma560 LOG.csv`` in a fresh process on generated CSV logs (issue 24):
    10^6 and 10^7 rows (10^5 and 10^6 with --quick) streamed block by block (``--stream on``), and
    10^6 rows (10^5) read whole (``--stream off``): wall time and peak resident memory (sampled every
    0.1 s, imports included). The files are written to a temporary folder, not kept."""
    import subprocess
    import tempfile

    sizes = (10**5, 10**6) if quick else (10**6, 10**7)
    env = dict(os.environ, PYTHONPATH=str(_SRC))
    with tempfile.TemporaryDirectory() as d:
        for rows, mode in ((sizes[0], "off"), (sizes[0], "on"), (sizes[1], "on")):
            path = Path(d) / f"puma560_{rows}.csv"
            if not path.exists():
                log(f"  writing a {rows}-row CSV log ...")
                _repeated_csv(path, rows)
            log(f"  identify puma560 {rows}-row CSV, --stream {mode} ...")
            t0 = time.perf_counter()
            proc = subprocess.Popen([sys.executable, "-m", "baseparams", "identify", "puma560", str(path), "--stream",
                                     mode], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
            with _RssPeak([proc.pid], period=0.1) as rss:
                err = proc.communicate()[1]
            wall = time.perf_counter() - t0
            key = f"identify_csv_{rows:.0e}".replace("+0", "").replace("+", "") + ("_streamed" if mode == "on" else
                                                                                   "_whole")
            if proc.returncode:
                log(f"    failed: {err.strip()[-300:]}")
                out[f"{key}_s"] = out[f"{key}_peak_mb"] = None
                continue
            out[f"{key}_s"] = wall
            out[f"{key}_s_repeats"] = 1
            out[f"{key}_peak_mb"] = rss.largest_mb * 2**20 / 1e6  # sampled every 0.1 s (psutil)
            out[f"{key}_mb_file"] = path.stat().st_size / 1e6


def bench_fleet(out: dict, quick: bool) -> None:
    """Fleet scale on a local Dask cluster: 10^8 synthetic Puma560 samples (10^6 with --quick)
    generated inside the tasks in chunks of 10^5 and reduced by TSQR; throughput with 1 and 2
    workers, peak memory (workers' max RSS + the driver's), chunked vs in-memory estimate."""
    import distributed

    import baseparams
    from baseparams.fleet import synthetic_factors, synthetic_fleet_factors
    from baseparams.ident import fit
    from baseparams.ident.model import ident_model

    robot = baseparams.load("puma560")
    model = ident_model(baseparams.analyze(robot), rotor=False)
    theta = model.theta(robot.parameters("paper"), np.ones(model.drives.n_params))
    chunk = 10**5
    whole = None  # in memory: one accumulator over 10^6 samples, on the 1-worker cluster (not in this process)
    for workers in (1, 2):
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                           dashboard_address=None, env={"NUMBA_NUM_THREADS": "1"})
        client = distributed.Client(cluster)
        try:
            client.run(lambda: None)
            synthetic_fleet_factors(model, theta, 2 * workers, chunk, client)  # warm the workers (numba cache)
            if whole is None:
                whole = fit(model, client.submit(synthetic_factors, model, theta, 0, 10 * chunk).result(), "ols").theta
            if workers == 2:
                acc = synthetic_fleet_factors(model, theta, 10, chunk, client)
                out["fleet_chunked_vs_inmemory_relerr"] = float(np.abs(fit(model, acc, "ols").theta - whole).max()
                                                                / np.abs(whole).max())
            total = (10**6 if quick else (10**7 if workers == 1 else 10**8))
            if workers == 1:
                t0 = time.perf_counter()
                synthetic_fleet_factors(model, theta, 1, chunk, client)
                out["fleet_chunk_seconds"] = time.perf_counter() - t0
            log(f"  fleet: {total} samples on {workers} worker(s) ...")
            pids = list(client.run(os.getpid).values())
            with _RssPeak(pids + [os.getpid()]) as peak:
                t0 = time.perf_counter()
                acc = synthetic_fleet_factors(model, theta, total // chunk, chunk, client)
                dt = time.perf_counter() - t0
            est = fit(model, acc, "ols").theta
            out[f"fleet_samples_per_s_{workers}worker{'s' if workers > 1 else ''}"] = total / dt
            if workers == 2:
                out["fleet_peak_mb"] = peak.total_mb  # workers + driver, sampled every 0.2 s during the run
                out["fleet_worker_peak_mb"] = peak.largest_mb
                out["fleet_samples"] = total
                out["fleet_seconds"] = dt
                out["fleet_theta_rel_error"] = float(np.abs(est - theta).max() / np.abs(theta).max())
        finally:
            client.close()
            cluster.close()


class _RssPeak:
    """The peak of the summed resident memory of some processes, sampled in a thread (psutil)."""

    def __init__(self, pids: list[int], period: float = 0.2):
        import threading

        import psutil

        self.procs = [psutil.Process(p) for p in pids]
        self.period, self.total_mb, self.largest_mb = period, 0.0, 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            rss = []
            for p in self.procs:
                with contextlib.suppress(Exception):  # a worker restarted: not counted
                    rss.append(p.memory_info().rss / 2**20)
            self.total_mb = max(self.total_mb, sum(rss))
            self.largest_mb = max(self.largest_mb, max(rss, default=0.0))
            self._stop.wait(self.period)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        return False


def bench_excite(out: dict, quick: bool) -> None:
    """Excitation design (5 harmonics, 4 starts, cond criterion): time and achieved condition
    number for Puma560 (+-1 rad), the Panda (its limits, 0.075 Hz) and pkm-2rru-1rrs; the Panda's
    recorded trajectory's condition number by the same code."""
    import baseparams
    from baseparams.excitation import design_excitation, random_excitation

    panda = Path(__file__).resolve().parents[2] / "shared" / "ident" / "panda_gaz2019" / "panda_mdh_gaz2019.urdf"
    cases = [("puma560", "puma560", 0.1), ("pkm_2rru_1rrs", "pkm-2rru-1rrs", 0.1)]
    if panda.is_file():
        cases.insert(1, ("panda", str(panda), 0.075))
    starts = 1 if quick else 4
    for key, model, f in cases:
        robot = baseparams.load(model)
        log(f"  excite {key} ({starts} starts) ...")
        t0 = time.perf_counter()
        ex = design_excitation(robot, base_frequency=f, starts=starts, seed=0)
        out[f"excite_{key}_s"] = time.perf_counter() - t0
        out[f"excite_{key}_cond"] = ex.condition_number
        out[f"excite_{key}_random_cond"] = random_excitation(robot, base_frequency=f, seed=0).condition_number


def bench_analyze_cli(out: dict, quick: bool) -> None:
    """``baseparams analyze`` end to end in a fresh process (``python -m baseparams``; imports,
    loading, DRNG, certification, regrouping, report), median of fresh runs."""
    import subprocess

    cases = [("puma560", ["puma560"]), ("pkm-2rru-1rrs", ["pkm-2rru-1rrs"])]
    if _talos_path():
        cases.append(("talos_full_v2", [_talos_path(), "--floating"]))
    reps = 3 if quick else 5
    for name, argv in cases:
        cmd = [sys.executable, "-m", "baseparams", "analyze", *argv, "--json"]
        log(f"  analyze {name} (fresh processes) ...")

        def once():
            done = subprocess.run(cmd, capture_output=True, text=True, check=False)
            if done.returncode != 0:
                raise RuntimeError(f"{' '.join(cmd)}: exit {done.returncode}: {done.stderr[-300:]}")
            return done.stdout

        t, n = measure(once, reps)
        status = json.loads(once())["status"]
        out[f"analyze_cli_{name}_s"] = t
        out[f"analyze_cli_{name}_s_repeats"] = n
        out[f"analyze_cli_{name}_status"] = status


#: the bare Pinocchio numerical rank (issue 25's yardstick), run as a script in a fresh process
PIN_RANK = """\
import sys
import numpy as np
import pinocchio as pin
path, floating = sys.argv[1], sys.argv[2] == "1"
model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if floating else pin.buildModelFromUrdf(path)
data = model.createData()
rng = np.random.default_rng(0)
rows = []
for _ in range(100):
    q = pin.integrate(model, pin.neutral(model), rng.uniform(-1, 1, model.nv))
    v, a = rng.uniform(-1, 1, model.nv), rng.uniform(-1, 1, model.nv)
    rows.append(pin.computeJointTorqueRegressor(model, data, q, v, a).copy())
s = np.linalg.svd(np.concatenate(rows), compute_uv=False)
print(int(np.sum(s > 1e-9 * s[0])))
"""


def puma560_urdf() -> str:
    """The built-in Puma560 (standard DH, Corke's inertias) as URDF text, for Pinocchio."""
    from scipy.spatial.transform import Rotation

    from baseparams.robots.puma560 import DH, LINKS, dh_offset

    def xyz_rpy(t):
        return (" ".join(f"{v:.17g}" for v in t[:3, 3]),
                " ".join(f"{v:.17g}" for v in Rotation.from_matrix(t[:3, :3]).as_euler("xyz")))

    out = ['<?xml version="1.0"?>', '<robot name="puma560">', '  <link name="base"/>']
    parent, origin = "base", np.eye(4)
    for i, ((a, alpha, d), (m, r, inertia)) in enumerate(zip(DH, LINKS), start=1):
        off = dh_offset(a, alpha, d)
        com = off.copy()
        com[:3, 3] = off[:3, :3] @ np.asarray(r) + off[:3, 3]
        (x, rpy), (cx, crpy) = xyz_rpy(origin), xyz_rpy(com)
        out += [f'  <joint name="joint{i}" type="revolute"><parent link="{parent}"/><child link="link{i}"/>',
                f'    <origin xyz="{x}" rpy="{rpy}"/><axis xyz="0 0 1"/>'
                f'<limit lower="-3.2" upper="3.2" effort="100" velocity="10"/></joint>',
                f'  <link name="link{i}"><inertial><origin xyz="{cx}" rpy="{crpy}"/><mass value="{m}"/>',
                f'    <inertia ixx="{inertia[0]}" ixy="0" ixz="0" iyy="{inertia[1]}" iyz="0" izz="{inertia[2]}"/>'
                f'</inertial></link>']
        parent, origin = f"link{i}", off
    return "\n".join(out + ["</robot>"]) + "\n"


def bench_vs_pinocchio(out: dict, quick: bool) -> None:
    """``baseparams analyze`` end to end vs the bare Pinocchio numerical rank, fresh processes.

    Interleaved runs (the two commands alternate), medians of the wall time and of the process's
    CPU time (user + system: less sensitive to other jobs on a shared machine); BLAS threads as set
    for the whole run (one by default) for both. Two bytecode settings: ``pyc``, the package's ``__pycache__`` written
    by a warm-up run (what an installed package has), and ``nopyc``, ``PYTHONDONTWRITEBYTECODE=1``
    on a copy of the package without caches (every baseparams module compiled at each start;
    third-party packages keep their installed caches either way).
    """
    import shutil
    import subprocess
    import tempfile

    import baseparams

    talos = _talos_path()
    reps = 3 if quick else 9
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "pin_rank.py").write_text(PIN_RANK)
        (tmp / "puma560.urdf").write_text(puma560_urdf())
        pkg = Path(baseparams.__file__).resolve().parent
        shutil.copytree(pkg, tmp / "src" / "baseparams", ignore=shutil.ignore_patterns("__pycache__"))
        cases = [("puma560", ["puma560"], str(tmp / "puma560.urdf"), "0")]
        if talos:
            cases.append(("talos_full_v2", [talos, "--floating"], talos, "1"))
        base_env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONDONTWRITEBYTECODE")}
        envs = {"pyc": dict(base_env, PYTHONPATH=str(tmp / "src")),
                "nopyc": dict(base_env, PYTHONPATH=str(tmp / "src"), PYTHONDONTWRITEBYTECODE="1")}

        def run(cmd, env):
            """``(wall s, CPU s of the process: user + system, stdout)``."""
            with tempfile.TemporaryFile() as fo, tempfile.TemporaryFile() as fe:
                t0 = time.perf_counter()
                proc = subprocess.Popen(cmd, env=env, stdout=fo, stderr=fe)
                _, status, usage = os.wait4(proc.pid, 0)
                wall = time.perf_counter() - t0
                fo.seek(0)
                fe.seek(0)
                if os.waitstatus_to_exitcode(status) != 0:
                    raise RuntimeError(f"{' '.join(cmd)}: exit {status}: {fe.read().decode()[-300:]}")
                return wall, usage.ru_utime + usage.ru_stime, fo.read().decode()

        for name, argv, urdf, floating in cases:
            ours = [sys.executable, "-m", "baseparams", "analyze", *argv, "--json"]
            pin_cmd = [sys.executable, str(tmp / "pin_rank.py"), urdf, floating]
            text = run(ours, envs["pyc"])[2]  # warm-up: writes the copy's caches for "pyc"
            res = json.loads(text)
            rank = run(pin_cmd, base_env)[2]
            out[f"vs_pinocchio_{name}_status"] = res["status"]
            out[f"vs_pinocchio_{name}_n_base"] = res["n_base"]
            out[f"vs_pinocchio_{name}_pinocchio_rank"] = int(rank)
            for mode, env in envs.items():
                log(f"  {name}, {mode}: analyze vs Pinocchio rank, {reps} interleaved fresh runs ...")
                ours_runs, pin_runs = [], []
                for _ in range(reps):
                    if mode == "nopyc":  # the pyc runs write them; nothing is written with the flag set
                        for d in (tmp / "src").rglob("__pycache__"):
                            shutil.rmtree(d)
                    ours_runs.append(run(ours, env)[:2])
                    pin_runs.append(run(pin_cmd, base_env if mode == "pyc" else dict(base_env,
                                                                                      PYTHONDONTWRITEBYTECODE="1"))[:2])
                key = f"vs_pinocchio_{name}_{mode}"
                for k, what in ((0, "s"), (1, "cpu_s")):
                    a = statistics.median(r[k] for r in ours_runs)
                    p = statistics.median(r[k] for r in pin_runs)
                    out[f"{key}_analyze_{what}"], out[f"{key}_analyze_{what}_repeats"] = a, reps
                    out[f"{key}_pinocchio_{what}"], out[f"{key}_pinocchio_{what}_repeats"] = p, reps
                    out[f"{key}_{'ratio' if what == 's' else 'cpu_ratio'}"] = a / p
            out["vs_pinocchio_load_average"] = os.getloadavg()[0]


def bench_drng_vs_numerical(out: dict, quick: bool) -> None:
    from baseparams.nullspace import drng
    from baseparams.nullspace.certify import certify
    from baseparams.numerics import numerical_nullspace

    r_fast, r_slow = (51, 11) if not quick else (11, 3)
    for name in ROBOTS:
        robot = _robot(name)
        log(f"  drng {name} ...")
        t_d, t_e, n_d = measure_pair(lambda: drng(robot, extended=False), lambda: drng(robot), r_fast)
        log(f"  numerical {name} (100 samples) ...")
        t_n, n_n = measure(lambda: numerical_nullspace(robot, samples=100, seed=0), r_slow)
        log(f"  certify {name} ...")
        t_c, n_c = measure(lambda: certify(robot), r_slow)
        out[f"drng_{name}_ms"] = 1e3 * t_d
        out[f"drng_{name}_ms_repeats"] = n_d
        out[f"drng_extended_{name}_ms"] = 1e3 * t_e
        out[f"numerical_{name}_ms"] = 1e3 * t_n
        out[f"numerical_{name}_ms_repeats"] = n_n
        out[f"drng_speedup_{name}"] = t_n / t_d
        out[f"certify_{name}_ms"] = 1e3 * t_c
        out[f"certify_{name}_ms_repeats"] = n_c


def bench_drng_scaling(out: dict, quick: bool) -> None:
    from baseparams.nullspace import drng
    from baseparams.robots import random_robot

    sizes = (10, 100, 1000) if quick else (10, 100, 1000, 10000)
    reps = {10: 21, 100: 11, 1000: 5, 10000: 5} if not quick else {10: 7, 100: 5, 1000: 5}
    for kind, branching in (("chain", 0.0), ("tree", 0.5)):
        last_total, prev_n = None, 1  # seconds (build + timing) of the previous N, to extrapolate
        for n in sizes:
            key = f"drng_{kind}_N{n}"
            # hopeless by linear extrapolation from the previous N: skip without trying
            if last_total is not None and last_total * (n / prev_n) > 2 * SCALING_BUDGET_S:
                log(f"  {key}: SKIPPED (extrapolated {last_total * n / prev_n:.0f} s from N={prev_n} "
                    f"exceeds twice the {SCALING_BUDGET_S:.0f} s budget per N)")
                out[f"{key}_ms"] = out[f"{key}_us_per_body"] = None
                continue
            log(f"  {key}: building ...")
            t0 = time.perf_counter()
            try:
                with time_limit(SCALING_BUDGET_S):
                    robot = random_robot(np.random.default_rng(n), n, joint_types="RP", branching=branching)
                    t_build = time.perf_counter() - t0
                    log(f"  {key}: built in {t_build:.2f} s; timing drng ...")
                    t, te, r = measure_pair(lambda: drng(robot, extended=False), lambda: drng(robot), reps[n])
            except Timeout as e:
                log(f"  {key}: SKIPPED (build + timing {e}; budget {SCALING_BUDGET_S:.0f} s per N)")
                out[f"{key}_ms"] = out[f"{key}_us_per_body"] = None
                last_total, prev_n = time.perf_counter() - t0, n
                continue
            last_total, prev_n = time.perf_counter() - t0, n
            out[f"{key}_ms"] = 1e3 * t
            out[f"{key}_ms_repeats"] = r
            out[f"{key}_us_per_body"] = 1e6 * t / n
            out[f"{key}_extended_ms"] = 1e3 * te
            out[f"{key}_extended_ratio"] = te / t
    done = [n for n in sizes if out.get(f"drng_chain_N{n}_us_per_body") is not None]
    if 100 in done and max(done) > 100:
        out["drng_chain_linearity"] = out[f"drng_chain_N{max(done)}_us_per_body"] / out["drng_chain_N100_us_per_body"]
        out["drng_chain_linearity_N"] = max(done)
    else:
        out["drng_chain_linearity"] = None


def random_tree_urdf(n: int, seed: int = 0, branching: float = 0.3) -> str:
    """A random tree of ``n`` links as URDF text: generic revolute joints (random origin, rotation
    and axis), random inertias; each link hangs from the previous one, or with probability
    ``branching`` from a random earlier one. Loaded with ``--floating``: nullity 3 (N - 1)."""
    rng = np.random.default_rng(seed)
    out = ['<?xml version="1.0"?>', f'<robot name="tree{n}">']
    for i in range(n):
        m, c, d = rng.uniform(0.5, 2.0), rng.uniform(-0.1, 0.1, 3), rng.uniform(0.01, 0.05, 3)
        out.append(f'<link name="b{i}"><inertial><origin xyz="{c[0]:.6f} {c[1]:.6f} {c[2]:.6f}"/>'
                   f'<mass value="{m:.6f}"/><inertia ixx="{d[1] + d[2]:.6f}" ixy="0.001" ixz="-0.002" '
                   f'iyy="{d[0] + d[2]:.6f}" iyz="0.0015" izz="{d[0] + d[1]:.6f}"/></inertial></link>')
        if i:
            p = int(rng.integers(0, i)) if rng.random() < branching else i - 1
            xyz, rpy, ax = rng.uniform(-0.3, 0.3, 3), rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3)
            ax /= np.linalg.norm(ax)
            out.append(f'<joint name="j{i}" type="continuous"><parent link="b{p}"/><child link="b{i}"/>'
                       f'<origin xyz="{xyz[0]:.6f} {xyz[1]:.6f} {xyz[2]:.6f}" '
                       f'rpy="{rpy[0]:.6f} {rpy[1]:.6f} {rpy[2]:.6f}"/>'
                       f'<axis xyz="{ax[0]:.6f} {ax[1]:.6f} {ax[2]:.6f}"/></joint>')
    out.append("</robot>")
    return "\n".join(out)


def deep_tree_urdf(n: int, seed: int = 0, branching: float = 0.3, reach: int = 10) -> str:
    """A random *deep* tree of ``n`` links (URDF text, as :func:`random_tree_urdf`): each link hangs
    from the previous one, or with probability ``branching`` from one of the ``reach`` links before
    that (fingers and snakes: the mean depth grows like ``n / (0.7 + 0.15 reach)``, about 0.45 n);
    ``branching=0`` is a chain. Loaded with ``--floating``: nullity 3 (N - 1)."""
    rng = np.random.default_rng(seed)
    parents = [-1] + [(i - 1 if rng.random() >= branching else int(rng.integers(max(0, i - reach), i)))
                      for i in range(1, n)]
    lines = random_tree_urdf(n, seed, branching=0.0).split("\n")  # one line per link, then its joint
    for k, line in enumerate(lines):
        if line.startswith('<joint name="j'):
            i = int(line[len('<joint name="j'):line.index('"', len('<joint name="j'))])
            lines[k] = line.replace(f'<parent link="b{i - 1}"/>', f'<parent link="b{parents[i]}"/>', 1)
    return "\n".join(lines)


def run_measured(cmd: list[str]) -> tuple[float, float, int, str]:
    """``(wall s, peak RSS MB, exit code, stdout)`` of one subprocess (``os.wait4``: its own
    ``ru_maxrss``, not the maximum over every child so far)."""
    import subprocess
    import tempfile

    with tempfile.TemporaryFile() as fo, tempfile.TemporaryFile() as fe:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=fo, stderr=fe)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        fo.seek(0)
        return wall, usage.ru_maxrss / 1024, proc.returncode, fo.read().decode()


def bench_size_sweep(out: dict, quick: bool) -> None:
    """``baseparams analyze FILE --floating --json`` in fresh processes on random floating-base trees
    (:func:`random_tree_urdf`) of N = 10 ... 10 000 links: median wall time (3 runs up to N = 1 000,
    2 above), the largest peak memory, status, nullity."""
    import tempfile

    from baseparams.files import write_text

    sizes = (10, 100, 1000) if quick else (10, 100, 1000, 3000, 10000)
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            path = Path(tmp) / f"tree{n}.urdf"
            write_text(path, random_tree_urdf(n, seed=n))
            reps = 1 if quick else {10: 3, 100: 3, 1000: 3}.get(n, 2)
            log(f"  analyze tree{n} (--floating, {reps} fresh processes) ...")
            cmd = [sys.executable, "-m", "baseparams", "analyze", str(path), "--floating", "--json"]
            runs = [run_measured(cmd) for _ in range(reps)]
            wall, mb = statistics.median(r[0] for r in runs), max(r[1] for r in runs)
            code, text = runs[-1][2], runs[-1][3]
            key = f"sweep_N{n}"
            out[f"{key}_s"], out[f"{key}_peak_mb"], out[f"{key}_exit"] = wall, mb, code
            out[f"{key}_s_repeats"], out[f"{key}_s_all"] = reps, [r[0] for r in runs]
            res = json.loads(text) if code in (0, 1) and text.strip() else {}
            out[f"{key}_status"] = res.get("status")
            out[f"{key}_nullity"] = res.get("nullity")
            out[f"{key}_nullity_expected"] = 3 * (n - 1)
            log(f"  tree{n}: {wall:.2f} s, {mb:.0f} MB, exit {code}, {res.get('status')}, nullity "
                f"{res.get('nullity')} (expected {3 * (n - 1)})")


def bench_scale_trees(out: dict, quick: bool) -> None:
    """Issue 41: ``baseparams analyze FILE --floating --json`` (certified, ``--form auto``: recursive
    from 200 bodies) in fresh processes, as an outsider runs it, on chains and random deep trees
    (:func:`deep_tree_urdf`, mean depth about 0.45 N) and the wide random trees of the size sweep
    (:func:`random_tree_urdf`), N = 100, 1 000, 10 000 (quick: up to 1 000): wall time, peak RSS,
    nullity (expected 3 (N - 1)), and the exponent of wall and memory between the two largest N
    (1 linear, 2 quadratic). One run per point above N = 1 000 (median of 3 below)."""
    import math
    import tempfile

    from baseparams.files import write_text

    sizes = (100, 1000) if quick else (100, 1000, 10000)
    kinds = {"chain": lambda n: deep_tree_urdf(n, seed=n, branching=0.0),
             "deep": lambda n: deep_tree_urdf(n, seed=n),
             "wide": lambda n: random_tree_urdf(n, seed=n)}
    with tempfile.TemporaryDirectory() as tmp:
        for kind, make in kinds.items():
            for n in sizes:
                path = Path(tmp) / f"{kind}{n}.urdf"
                write_text(path, make(n))
                reps = 1 if quick or n > 1000 else 3
                cmd = [sys.executable, "-m", "baseparams", "analyze", str(path), "--floating", "--json"]
                runs = [run_measured(cmd) for _ in range(reps)]
                wall, mb = statistics.median(r[0] for r in runs), max(r[1] for r in runs)
                code, text = runs[-1][2], runs[-1][3]
                res = json.loads(text) if code in (0, 1) and text.strip() else {}
                key = f"trees_{kind}_N{n}"
                out[f"{key}_s"], out[f"{key}_peak_mb"], out[f"{key}_exit"] = wall, mb, code
                out[f"{key}_status"], out[f"{key}_nullity"] = res.get("status"), res.get("nullity")
                out[f"{key}_nullity_ok"] = res.get("nullity") == 3 * (n - 1)
                out[f"{key}_form"] = res.get("form")
                log(f"  {kind}{n}: {wall:.2f} s, {mb:.0f} MB, exit {code}, {res.get('status')}, nullity "
                    f"{res.get('nullity')} (expected {3 * (n - 1)}), form {res.get('form')}")
            a, b = sizes[-2], sizes[-1]
            for what in ("s", "peak_mb"):
                lo, hi = out[f"trees_{kind}_N{a}_{what}"], out[f"trees_{kind}_N{b}_{what}"]
                out[f"trees_{kind}_{what}_exponent"] = math.log(hi / lo) / math.log(b / a)


LOOP_BUILTINS = ("four-bar", "parallelogram", "pkm-2rru-1rrs", "pkm-2prs-1psr", "pkm-2prs-1psr-symmetric")


def bench_loops(out: dict, quick: bool) -> None:
    """Closed loops: DRNG on both PKMs (the paper's principles, as the paper times it, and with the
    extended rules) vs the paper's 5000-sample numerical validation; completeness on every
    built-in loop robot."""
    from baseparams.nullspace import drng
    from baseparams.numerics import numerical_nullspace
    from baseparams.robots import get

    samples = 1000 if quick else 5000
    for name in ("pkm-2rru-1rrs", "pkm-2prs-1psr"):
        robot = get(name)
        key = name.replace("-", "_")
        log(f"  drng {name} ...")
        t_d, t_e, n_d = measure_pair(lambda: drng(robot, extended=False), lambda: drng(robot), 51 if not quick else 11)
        log(f"  validation {name} ({samples} actuated samples) ...")
        info: dict = {}
        t_v, n_v = measure(lambda: numerical_nullspace(robot, samples=samples, seed=0, info=info),
                           5 if not quick else 2)
        res = numerical_nullspace(robot, samples=samples, seed=0)
        out[f"drng_{key}_ms"] = 1e3 * t_d
        out[f"drng_{key}_ms_repeats"] = n_d
        out[f"validation_{key}_s"] = t_v
        out[f"validation_{key}_s_repeats"] = n_v
        out[f"validation_{key}_kept"] = info.get("kept")
        out[f"validation_{key}_nullity"] = res.nullity
        out[f"validation_{key}_sv_gap"] = res.gap
        out[f"validation_vs_drng_{key}"] = t_v / t_d
        out[f"drng_extended_{key}_ms"] = 1e3 * t_e
        out[f"validation_vs_drng_extended_{key}"] = t_v / t_e
    from baseparams.numerics import closed_samples

    for name in ("four-bar", "parallelogram"):  # a 1-dof loop: its whole motion traced vs the paper's box
        robot = get(name)
        key = name.replace("-", "_")
        log(f"  whole-motion sampling {name} ...")
        t_box, n_box = measure(lambda: closed_samples(robot, samples, np.random.default_rng(0)), 5 if not quick else 2)
        t_tr, n_tr = measure(lambda: closed_samples(robot, samples, np.random.default_rng(0), whole_motion=True),
                             5 if not quick else 2)
        out[f"sampling_box_{key}_s"], out[f"sampling_box_{key}_s_repeats"] = t_box, n_box
        out[f"sampling_traced_{key}_s"], out[f"sampling_traced_{key}_s_repeats"] = t_tr, n_tr
        out[f"sampling_traced_vs_box_{key}"] = t_tr / t_box
    from baseparams.nullspace.certify import certify

    for name in LOOP_BUILTINS:  # completeness of the geometric span on every built-in loop robot
        robot = get(name)
        key = name.replace("-", "_")
        log(f"  completeness {name} ...")
        c = certify(robot, samples=3000, seed=1)
        out[f"loops_{key}_paper_rank"] = drng(robot, extended=False).rank
        out[f"loops_{key}_extended_rank"] = c.drng_rank
        out[f"loops_{key}_by_rule"] = {k: v for k, v in c.drng.by_principle().items() if v}
        out[f"loops_{key}_nullity"] = c.nullity
        out[f"loops_{key}_completed"] = c.completed
        out[f"loops_{key}_status"] = c.status


def _simulator_files(out: dict, quick: bool) -> None:
    """Every MJCF model shipped with gymnasium and dm_control (test dependencies): DRNG-complete count."""
    import importlib.util
    import warnings

    from baseparams.errors import NoMovingBodiesError
    from baseparams.loading import load_model
    from baseparams.nullspace.certify import certify

    roots = []
    for pkg, sub in (("gymnasium", ("envs", "mujoco", "assets")), ("dm_control", ("suite",))):
        spec = importlib.util.find_spec(pkg)
        if spec is not None and spec.origin is not None:
            roots.append(Path(spec.origin).parent.joinpath(*sub))
    files = [f for r in roots for f in sorted(r.glob("*.xml"))]
    if quick:
        files = [f for f in files if f.name not in ("dog.xml", "humanoid_CMU.xml", "stacker.xml")]
    done, left, total = 0, [], 0
    for f in files:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                robot, _ = load_model(str(f), strict_inertia=False)
        except NoMovingBodiesError:  # lqr.xml: a template without bodies
            continue
        c = certify(robot, seed=0)
        total += 1
        done += bool(c.certified and c.completed == 0)
        if not (c.certified and c.completed == 0):
            left.append(f"{f.parent.name}/{f.name} ({c.status}, +{c.completed})")
    out["simulator_models_analysed"] = total
    out["simulator_models_drng_complete"] = done
    out["simulator_models_drng_incomplete"] = ", ".join(left)


def bench_files(out: dict, quick: bool) -> None:
    """Real files: every example-robot-data URDF (test dependency): how often DRNG alone is
    complete, and loading / DRNG / certification times on talos_full_v2 (45 joints)."""
    import warnings

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from baseparams.loading import load_model
    from baseparams.nullspace import drng
    from baseparams.nullspace.certify import certify

    from erd import is_floating, urdf_files  # the same file list and root joints as the tests

    files = urdf_files()
    if quick:
        files = files[::4]
    complete = certified = total = 0
    incomplete = []
    for f in files:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                robot, _ = load_model(str(f), floating=is_floating(f), strict_inertia=False)
        except Exception as exc:  # noqa: BLE001 - counted, reported
            log(f"  {f.name}: not loaded ({str(exc)[-80:]})")
            continue
        c = certify(robot, seed=1)
        total += 1
        certified += c.certified
        if c.certified and c.completed == 0:
            complete += 1
        else:
            incomplete.append(f"{f.name} (+{c.completed})")
    out["files_analysed"] = total
    out["files_certified"] = certified
    out["files_drng_complete"] = complete
    out["files_drng_incomplete"] = ", ".join(incomplete)
    shared = Path(__file__).resolve().parent.parent.parent / "shared" / "models"
    if shared.is_dir():  # the shared corpus: URDF+ linkages and MJCF (loops: Cassie, a leg linkage)
        done, left = 0, []
        models = sorted(shared.glob("urdfplus/*.urdf")) + sorted(shared.glob("mjcf/*/*.xml"))
        for f in models:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                robot, _ = load_model(str(f), strict_inertia=False)
            c = certify(robot, seed=0)
            done += bool(c.certified and c.completed == 0)
            if not (c.certified and c.completed == 0):
                left.append(f"{f.name} ({c.status}, +{c.completed})")
        out["shared_models_analysed"] = len(models)
        out["shared_models_drng_complete"] = done
        out["shared_models_drng_incomplete"] = ", ".join(left)
    _simulator_files(out, quick)
    talos = [f for f in urdf_files() if f.name == "talos_full_v2.urdf"]
    if talos:
        path = str(talos[0])
        t_load, n_load = measure(lambda: load_model(path, floating=True, strict_inertia=False), 5)
        robot, _ = load_model(path, floating=True, strict_inertia=False)
        t_d, n_d = measure(lambda: drng(robot), 21)
        t_c, n_c = measure(lambda: certify(robot, seed=1), 3)
        from baseparams.numerics import numerical_nullspace
        t_num, _ = measure(lambda: numerical_nullspace(robot, seed=1), 3)
        out["talos_full_v2_numerical_ms"] = 1e3 * t_num
        out["talos_full_v2_drng_vs_numerical"] = t_num / t_d
        out["talos_full_v2_bodies"] = robot.n
        out["talos_full_v2_load_ms"] = 1e3 * t_load
        out["talos_full_v2_drng_ms"] = 1e3 * t_d
        out["talos_full_v2_certify_ms"] = 1e3 * t_c
        out["talos_full_v2_drng_ms_repeats"] = n_d


def bench_hands(out: dict, quick: bool) -> None:
    """Issue 46: CAD five-finger hands (tests/hands.py: mimic couplings, angles to 6 digits, mates off), URDF
    and MJCF: how often the default count is the design's, how often it is UNDECIDED, values snapped, and the
    default analysis' time against the literal one (median, same hands, timed alternately)."""
    import tempfile
    import warnings

    import baseparams

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from hands import five_finger_hand, five_finger_hand_mjcf

    seeds = range(4 if quick else 12)
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for kind, gen, suffix in (("urdf", five_finger_hand, ".urdf"), ("mjcf", five_finger_hand_mjcf, ".xml")):
            design = undecided = snapped = 0
            t_def, t_lit = [], []
            for seed in seeds:
                hand = gen(seed)
                f, g = Path(tmp) / f"h{suffix}", Path(tmp) / f"d{suffix}"
                f.write_text(hand.text)
                g.write_text(hand.design)
                robot, want = baseparams.load(str(f)), baseparams.analyze(baseparams.load(str(g)), literal=True)
                a = baseparams.analyze(robot)
                design += a.n_base == want.n_base
                undecided += a.status == "undecided"
                snapped += 0 if a.practical is None else len(a.practical.snaps)
                td, tl, _ = measure_pair(lambda: baseparams.analyze(robot),
                                         lambda: baseparams.analyze(robot, literal=True), 1)
                t_def.append(td)
                t_lit.append(tl)
            log(f"  hands {kind}: {design}/{len(seeds)} design counts")
            out[f"hands_{kind}_count"] = len(seeds)
            out[f"hands_{kind}_design_count"] = design
            out[f"hands_{kind}_undecided"] = undecided
            out[f"hands_{kind}_values_snapped"] = snapped
            out[f"hands_{kind}_default_s"] = statistics.median(t_def)
            out[f"hands_{kind}_literal_s"] = statistics.median(t_lit)
            out[f"hands_{kind}_default_vs_literal"] = statistics.median(a / b for a, b in zip(t_def, t_lit))


def bench_special(out: dict, quick: bool) -> None:
    """Extended principles on random special-geometry robots: completeness and emitted-column
    residuals (the same generator as tests/test_special.py, more seeds)."""
    from baseparams.nullspace.survey import summarize, survey_case
    from baseparams.robots import special_robot

    count = 100 if quick else 1000
    log(f"  surveying {count} special robots ...")
    t0 = time.perf_counter()
    cases = [survey_case(special_robot(np.random.default_rng(seed))) for seed in range(count)]
    s = summarize(cases)
    out["special_seconds"] = time.perf_counter() - t0
    for k, v in s.items():
        out[f"special_{k}"] = v
    rules: dict[str, int] = {}
    for c in cases:
        for k, v in c.by_rule.items():
            if v and k.startswith("R-"):
                rules[k] = rules.get(k, 0) + 1
    out["special_robots_using_rule"] = rules


def bench_symbolic(out: dict, quick: bool) -> None:
    """Symbolic base parameters (issue 18): the formulas of each built-in symbolic robot in process
    (DRNG on the symbolic geometry, exact regrouping, two numerical checks), and Puma560's
    ``analyze --symbolic`` end to end in a fresh process (SymPy import, probing the conditions)."""
    import subprocess

    from baseparams.symbolic import load_symbolic, symbolic_analysis

    names = ["puma560-symbolic"] if quick else ["puma560-symbolic", "6r-wrist-symbolic", "stanford-symbolic",
                                                 "scara-symbolic", "parallelogram-symbolic", "pkm-2rru-1rrs-symbolic",
                                                 "panda-symbolic", "panda-offsets-symbolic"]
    for name in names:
        robot = load_symbolic(name)
        log(f"  symbolic {name} ...")
        t, n = measure(lambda: symbolic_analysis(load_symbolic(name)), 1 if quick else 3, warmup=0)
        sa = symbolic_analysis(robot)
        key = name.replace("-symbolic", "").replace("-", "_")
        out[f"symbolic_{key}_s"] = t
        out[f"symbolic_{key}_s_repeats"] = n
        out[f"symbolic_{key}_n_base"] = sa.n_base
    cmd = [sys.executable, "-m", "baseparams", "analyze", "puma560-symbolic", "--symbolic", "--json"]
    log("  analyze puma560-symbolic --symbolic (fresh processes) ...")
    t, n = measure(lambda: subprocess.run(cmd, capture_output=True, check=True), 1 if quick else 3, warmup=0)
    out["symbolic_cli_puma560_s"] = t
    out["symbolic_cli_puma560_s_repeats"] = n
    for name in ([] if quick else ["panda-symbolic", "panda-offsets-symbolic"]):  # issue 30: 6 and 9 symbols
        cmd = [sys.executable, "-m", "baseparams", "analyze", name, "--symbolic", "--json"]
        log(f"  analyze {name} --symbolic (fresh process) ...")
        t, n = measure(lambda: subprocess.run(cmd, capture_output=True, check=True), 1, warmup=0)
        key = name.replace("-symbolic", "").replace("-", "_")
        out[f"symbolic_cli_{key}_s"] = t
    _bench_near_singular(out, quick)


def _bench_near_singular(out: dict, quick: bool) -> None:
    """Issue 30: the parallelogram near its flat configuration, certified count and loop sampling."""
    import baseparams
    from baseparams.symbolic import load_symbolic

    for by in ([0.01] if quick else [0.05, 0.01, 1e-3, 1e-4, 1e-6]):
        log(f"  parallelogram BY={by:g} ...")
        robot = load_symbolic("parallelogram-symbolic").to_robot({"BY": by})
        t, _ = measure(lambda: baseparams.analyze(robot), 1, warmup=0)
        a = baseparams.analyze(robot)
        key = f"near_singular_{by:g}".replace("-", "m").replace(".", "p")
        out[f"{key}_status"] = str(a.status)
        out[f"{key}_n_base"] = a.n_base
        out[f"{key}_s"] = t
        out[f"{key}_kept"] = a.certificate.sampling["kept"]
        out[f"{key}_cond_max"] = a.certificate.sampling["cond_max"]

def _render_ms(page: str) -> float | None:
    """The page's own render time in headless Chromium: its ``data-render-ms`` (navigation start to
    the end of its scripts), or None without Chromium."""
    import re
    import shutil
    import subprocess
    import tempfile

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        return None
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "report.html"
        path.write_text(page)
        dom = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--dump-dom", path.as_uri()],
                             capture_output=True, text=True, timeout=120).stdout
    m = re.search(r'data-render-ms="([0-9.]+)"', dom)
    return float(m.group(1)) if m else None


def bench_report(out: dict, quick: bool) -> None:
    """The HTML analysis report: ``analysis_html`` time (DRNG re-run for the provenance included),
    page size, and the render time the page itself measures in headless Chromium (median of fresh
    browser runs), for Puma560 and talos_full_v2 (45 bodies, floating)."""
    import baseparams
    from baseparams.report.html import analysis_html

    cases = ["puma560"] + (["talos_full_v2"] if _talos_path() else [])
    reps, browser_reps = (3, 1) if quick else (11, 5)
    for key in cases:
        result = baseparams.analyze(_robot(key))
        log(f"  report {key} ...")
        t, n = measure(lambda: analysis_html(result), reps)
        page = analysis_html(result)
        out[f"report_{key}_html_ms"] = 1e3 * t
        out[f"report_{key}_html_ms_repeats"] = n
        out[f"report_{key}_kb"] = len(page.encode()) / 1e3
        ms = [_render_ms(page) for _ in range(browser_reps)]
        out[f"report_{key}_render_ms"] = None if None in ms else statistics.median(ms)
        out[f"report_{key}_render_ms_repeats"] = browser_reps


def _key(label: str) -> str:
    """A label as a figure's name: lower case, runs of other characters one ``_``."""
    key = "".join(ch if ch.isalnum() else "_" for ch in label).strip("_").lower()
    while "__" in key:
        key = key.replace("__", "_")
    return key


def bench_cross_recording(out: dict, quick: bool) -> None:
    """Cross-recording suite (``benchmarks/cross_recording.py``): identify on one recording, the raw RMS
    on another, per estimator; the worst ratio of the default to the better of plain OLS and physical."""
    import cross_recording as cr

    results = [cr.run_case(c) for c in cr.cases(quick)]
    log("\n" + cr.table(results))
    for r in results:
        key = "cross_" + "".join(ch if ch.isalnum() else "_" for ch in r["name"].split(":")[0].split("(")[0]).strip("_")
        out[f"{key}_name"] = r["name"]
        for label in cr.ESTIMATORS:
            out[f"{key}_rms_{_key(label)}"] = r["rms"][label]
        out[f"{key}_terms"] = ", ".join(r["terms"]["default"]) or "-"
        out[f"{key}_default_vs_best"] = r["default_vs_best"]
    out["cross_recording_worst_default_vs_best"] = max(r["default_vs_best"] for r in results)
    out["cross_recording_cases"] = len(results)


def bench_several_recordings(out: dict, quick: bool) -> None:
    """Issue 48 item 3: a plant's first one, two and three recordings -> its fourth, with and without the model terms
    (each recording one cross-validation fold of the estimate and of the terms)."""
    import cross_recording as cr

    results = [cr.run_several(c) for c in cr.several_recordings_cases()[:1 if quick else None]]
    log("\n" + cr.several_table(results))
    for i, r in enumerate(results):
        key = f"several_{i}"
        out[f"{key}_name"] = r["name"]
        for (n, label), v in r["rms"].items():
            out[f"{key}_{n}_rms_{_key(label)}"] = v
        for n in (1, 2, 3):
            out[f"{key}_{n}_terms"] = ", ".join(r["terms"][(n, "default")]) or "-"
        out[f"{key}_2_vs_1_default"] = r["rms"][(2, "default")] / r["rms"][(1, "default")]


def bench_generalization(out: dict, quick: bool) -> None:
    """Issue 48: splits that train on one motion and predict another (both directions), scored as an outsider
    would (5 Hz low-passed torques, 1 s trimmed at each end), against an outsider's plain Pinocchio OLS on every
    sample; the rule that chose each default estimate."""
    import cross_recording as cr

    results = [cr.run_generalization(c) for c in cr.generalization_cases()]
    log("\n" + cr.generalization_table(results))
    for i, r in enumerate(results):
        key = f"gen_{i:02d}"
        out[f"{key}_name"] = r["name"]
        for label, v in r["score"].items():
            out[f"{key}_score_{_key(label)}"] = v
        out[f"{key}_default_vs_outsider"] = r["default_vs_outsider"]
        out[f"{key}_rule"] = r["rule"]["default"]
    out["generalization_worst_default_vs_outsider"] = max(r["default_vs_outsider"] for r in results)
    out["generalization_cases"] = len(results)


def bench_model_terms(out: dict, quick: bool) -> None:
    """The Panda (real log, last 6 s held out): the 5 Hz held-out figure per model class, terms added one by
    one, then as cross-validation keeps them (default and physical)."""
    import cross_recording as cr

    rows = cr.panda_terms_table()
    if not rows:
        log("  model_terms: no ../shared/ident (skipped)")
        return
    log("\n" + cr.panda_table(rows))
    for r in rows:
        key = _key(r["label"])
        out[f"panda_lp5_{key}"] = r["lp5"]
        out[f"panda_label_{key}"] = r["label"]
        out[f"panda_raw_{key}"] = r["raw"]
        out[f"panda_terms_{key}"] = ", ".join(r["terms"]) or "-"
        out[f"panda_seconds_{key}"] = r["seconds"]
    out["panda_default_seconds"] = next(r["seconds"] for r in rows if r["label"].startswith("default (terms"))


def bench_currents(out: dict, quick: bool) -> None:
    """Issue 50 (``benchmarks/currents.py``): identification from motor currents with unknown gains, the acceptance's
    simulated analogue (a 7-DoF arm, held-out joint-side torques against its sensors) and the TX40's motor-side log."""
    import currents as cu

    result = cu.run(quick)
    if not result:
        log("  currents: no ../shared (skipped)")
        return
    log("\n" + cu.table(result))
    arm = result["arm"]
    for r in arm:
        for k in ("one_shoulder", "one_median", "one_best", "one_worst", "every", "exact", "ols_catalogue",
                  "sensor_fit", "ratio_error", "naive_smallest", "seconds"):
            out[f"currents_arm_seed{r['seed']}_{k}"] = r[k]
        out[f"currents_arm_seed{r['seed']}_undetermined"] = ", ".join(r["undetermined"]) or "-"
    for k in ("one_shoulder", "one_median", "every", "exact", "ols_catalogue", "sensor_fit", "seconds"):
        out[f"currents_arm_median_{k}"] = statistics.median(r[k] for r in arm)
    z = np.concatenate([r["z"] for r in arm])
    out["currents_arm_z_rms"] = float(np.sqrt(np.mean(z**2)))
    out["currents_arm_z_within_2"] = float(np.mean(np.abs(z) < 2))
    out["currents_arm_z_count"] = int(len(z))
    out["currents_arm_shoulder_beats_ols"] = sum(r["one_shoulder"] <= r["ols_catalogue"] for r in arm)
    out["currents_arm_every_beats_ols"] = sum(r["every"] <= r["ols_catalogue"] for r in arm)
    out["currents_arm_seeds"] = len(arm)
    tx = result.get("tx40")
    if tx is not None:
        for j in range(6):
            out[f"currents_tx40_ratio_j{j + 1}"] = tx["ratio"][j]
            out[f"currents_tx40_rel_std_j{j + 1}"] = tx["rel_std"][j]
            out[f"currents_tx40_current_rms_j{j + 1}"] = tx["current_rms"][j]
            out[f"currents_tx40_torque_fit_current_rms_j{j + 1}"] = tx["torque_fit_current_rms"][j]
        out["currents_tx40_undetermined"] = ", ".join(sorted(tx["undetermined"])) or "-"
        out["currents_tx40_seconds"] = tx["seconds"]


def bench_scale_logs(out: dict, quick: bool) -> None:
    """Long logs (issue 41): ``benchmarks/scale_logs.py``'s figures."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from scale_logs import bench_scale_logs as run

    run(out, quick, log)


def bench_payload(out: dict, quick: bool) -> None:
    """Payload identification (issue 49): the acceptance scenario simulated by MuJoCo (``benchmarks/payload.py``)."""
    import payload

    out.update(payload.run(quick, log))


_CHAIN = """
import sys, numpy as np, baseparams as bp
from baseparams.robots import random_robot
n, log, what = int(sys.argv[1]), sys.argv[2], sys.argv[3]
robot = random_robot(np.random.default_rng(n), n, "R", branching=0.0)
if what == "simulate":
    bp.simulate(robot, duration=5.0, rate=100.0, noise=0.1, convention="paper", out=log)
else:
    res = bp.identify(robot, log, convention="paper")
    print(res.fit.estimate.covariance.split(",")[0], res.model.n_params)
"""


def bench_large_inputs(out: dict, quick: bool) -> None:
    """Issue 51: ``identify`` of a random chain (``robots.random_robot``, paper convention, 500 samples at 100 Hz;
    220 links, quick 60) and of a 10^6-sample 100 kHz Puma560 log (quick 10^5 at 10 kHz), each in a fresh process:
    wall time, peak resident memory and, for the log, its arrays' size."""
    import subprocess
    import tempfile

    n = 60 if quick else 220
    rate, duration = (10000, 10) if quick else (100000, 10)
    with tempfile.TemporaryDirectory() as tmp:
        chain = str(Path(tmp) / f"chain{n}.csv")
        subprocess.run([sys.executable, "-c", _CHAIN, str(n), chain, "simulate"], check=True, capture_output=True)
        log(f"  identify chain{n} (paper convention, 500 samples) ...")
        wall, mb, code, text = run_measured([sys.executable, "-c", _CHAIN, str(n), chain, "identify"])
        key = f"large_chain{n}"
        out[f"{key}_identify_s"], out[f"{key}_identify_peak_mb"], out[f"{key}_identify_exit"] = wall, mb, code
        log(f"  chain{n}: {wall:.1f} s, {mb:.0f} MB, exit {code}, {text.strip()}")
        fast = str(Path(tmp) / "fast.npz")
        subprocess.run([sys.executable, "-m", "baseparams", "simulate", "puma560", fast, "--duration", str(duration),
                        "--rate", str(rate), "--noise", "0.05"], check=True, capture_output=True)
        with np.load(fast) as z:
            size = sum(z[k].nbytes for k in z.files) / 1e6
        wall, mb, code, _ = run_measured([sys.executable, "-m", "baseparams", "identify", "puma560", fast, "--json"])
        key = f"large_log_{rate // 1000}khz"
        out[f"{key}_s"], out[f"{key}_peak_mb"], out[f"{key}_exit"], out[f"{key}_arrays_mb"] = wall, mb, code, size
        out[f"{key}_peak_over_arrays"] = mb / size
        log(f"  {rate // 1000} kHz log ({size:.0f} MB of arrays): {wall:.1f} s, {mb:.0f} MB, exit {code}")
    _analyze_slide_chain(out, quick)


def _analyze_slide_chain(out: dict, quick: bool) -> None:
    """Issue 51: ``analyze`` of an all-prismatic random chain against the revolute one of the same length
    (1 000 links, quick 300; in process, one run each): seconds and their ratio (the prismatic chain's
    first moments climb to the root in the certificate's column check; was ~40x the revolute chain)."""
    from baseparams import analyze
    from baseparams.robots import random_robot

    n = 300 if quick else 1000
    for kind in ("P", "R"):
        robot = random_robot(np.random.default_rng(n), n, kind, branching=0.0)
        t0 = time.perf_counter()
        status = analyze(robot).status
        out[f"large_chain{n}_{kind}_analyze_s"] = time.perf_counter() - t0
        log(f"  analyze {kind} chain{n}: {out[f'large_chain{n}_{kind}_analyze_s']:.1f} s, {status}")
    out[f"large_chain{n}_P_over_R"] = out[f"large_chain{n}_P_analyze_s"] / out[f"large_chain{n}_R_analyze_s"]


GROUPS: dict[str, Callable[[dict, bool], None]] = {
    "large_inputs": bench_large_inputs,
    "payload": bench_payload,
    "cross_recording": bench_cross_recording,
    "generalization": bench_generalization,
    "several_recordings": bench_several_recordings,
    "currents": bench_currents,
    "model_terms": bench_model_terms,
    "files": bench_files,
    "hands": bench_hands,
    "special": bench_special,
    "regressor": bench_regressor,
    "base_streaming": bench_base_streaming,
    "analyze_cli": bench_analyze_cli,
    "vs_pinocchio": bench_vs_pinocchio,
    "identify": bench_identify,
    "stream": bench_stream,
    "fleet": bench_fleet,
    "scale_logs": bench_scale_logs,
    "excite": bench_excite,
    "drng_vs_numerical": bench_drng_vs_numerical,
    "drng_scaling": bench_drng_scaling,
    "size_sweep": bench_size_sweep,
    "scale_trees": bench_scale_trees,
    "loops": bench_loops,
    "symbolic": bench_symbolic,
    "report": bench_report,
}


# ----------------------------------------------------------------------------- output
def _fmt(v) -> str:
    if v is None:
        return "skipped"
    if isinstance(v, (int, str)):
        return str(v)
    if isinstance(v, (dict, list, tuple)):  # e.g. the loops group's per-robot sampling counts
        return str(v)
    if v == 0 or 1e-3 <= abs(v) < 1e5:
        return f"{v:.4g}"
    return f"{v:.3e}"


def print_table(out: dict) -> None:
    m = out["machine"]
    print(f"machine: {m['platform']}, {m.get('cpu_model', m['processor'])}, {m['cpu_count']} CPUs, "
          f"Python {m['python']}, numpy {m['numpy']}, pinocchio {m.get('pinocchio')}")
    print("(medians over the given number of repeats; noisy on a small shared machine)\n")
    names = [k for k in out if k != "machine" and not k.endswith("_repeats") and k != "total_seconds"]
    width = max(len(k) for k in names) if names else 10
    print(f"{'figure':<{width}}  {'value':>12}  repeats")
    print("-" * (width + 24))
    for k in names:
        r = out.get(f"{k}_repeats", "")
        print(f"{k:<{width}}  {_fmt(out[k]):>12}  {r}")
    print(f"\ntotal benchmark time: {out['total_seconds']:.1f} s")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", action="store_true", help="print exactly one JSON object to stdout")
    ap.add_argument("--quick", action="store_true", help="smaller sizes and fewer repeats (< 60 s)")
    ap.add_argument("--only", metavar="SUBSTRING", default=None,
                    help=f"run only the groups whose name contains SUBSTRING ({', '.join(GROUPS)})")
    ap.add_argument("--blas-threads", type=int, metavar="N", default=None,
                    help="BLAS threads, set (OPENBLAS/OMP/MKL_NUM_THREADS) before numpy is imported. "
                         "Default: 1, unless OPENBLAS_NUM_THREADS is already set in the environment; "
                         "0: leave the environment alone (OpenBLAS then uses all cores)")
    args = ap.parse_args(argv)
    blas = args.blas_threads
    if blas is None and "OPENBLAS_NUM_THREADS" not in os.environ:
        # Multi-threaded OpenBLAS on this 2-vCPU shared VM sometimes runs the numerical method's
        # SVD 30-100x slower (0.7-2.4 s instead of 5-25 ms); one thread is as fast when quiet.
        blas = 1
    if blas:
        if "numpy" in sys.modules:
            log("warning: numpy already imported; --blas-threads may have no effect")
        for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ[var] = str(blas)
    global np
    import numpy
    np = numpy

    groups = [g for g in GROUPS if args.only is None or args.only in g]
    if not groups:
        ap.error(f"--only {args.only!r} matches no group; groups: {', '.join(GROUPS)}")
    out: dict = {"machine": machine_info()}
    t_all = time.perf_counter()
    for g in groups:
        log(f"[{g}]")
        t0 = time.perf_counter()
        GROUPS[g](out, args.quick)
        log(f"[{g}] done in {time.perf_counter() - t0:.1f} s")
    out["total_seconds"] = time.perf_counter() - t_all
    out["quick"] = args.quick
    if args.json:
        json.dump(out, sys.stdout, indent=1)
        sys.stdout.write("\n")
    else:
        out.pop("quick")
        print_table(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
