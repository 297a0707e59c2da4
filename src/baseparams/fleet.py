"""Fleet scale: identification over many logs on Dask, with memory bounded by the chunk.

Every log (file) is read, preprocessed and reduced to its row factors by a Dask task
(:func:`file_factors`: the same code as :func:`baseparams.ident.identify`, chunked with
overlapping filter edges past ``memory_mb``); factors combine exactly in a tree (TSQR,
:func:`baseparams.ident.chunks.combine`), and the estimators — OLS, WLS, the physical fit — run
on the combined factors, whose size does not depend on the data. ``per_file`` gives one estimate
per log (one robot each) and the spread across the fleet; ``pooled`` one estimate from all.

The cluster: ``client`` if given, else ``scheduler`` (an address, or Dask's own
``DASK_SCHEDULER_ADDRESS``), else a local cluster sized to the machine (one single-threaded worker
process per core), started and stopped here. A scheduler that does not answer within
:data:`SCHEDULER_TIMEOUT_S` seconds (no listener, an unresolvable host) or a malformed address is
one line naming the address. A worker that dies mid-run loses nothing: the
scheduler runs its tasks again elsewhere. A bad log (unreadable, a wrong layout, too little
motion to identify alone) does not stop the fleet: it is listed in :attr:`FleetResult.skipped`
with its one-line reason and the others go on; only a fleet with no usable log is an error.

Synthetic fleets for tests and benchmarks: :func:`simulate_fleet` writes one log per robot (a
known parameter vector each), file by file, never holding the fleet; :func:`synthetic_factors` is
the same data generated inside the task (no disk), for throughput measurements.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .display import clip, counted
from .errors import BaseparamsError, DataError
from .ident import Fit, fit, pulled_covariance
from .ident.drives import FRICTION_TERMS
from .ident.model import IdentModel
from .ident.options import IdentOptions

#: seconds to wait for a scheduler given by address (``--scheduler``, ``DASK_SCHEDULER_ADDRESS``)
SCHEDULER_TIMEOUT_S = 5.0


def file_factors(path: str, model: IdentModel, options: IdentOptions | None = None):
    """One log reduced to its row factors (the task a Dask worker runs).

    Parameters
    ----------
    path : str
        A log file (:func:`baseparams.io.logs.read_log`).
    model : IdentModel
        The identification model.
    options : IdentOptions, optional
        Its ``memory_mb`` (largest regressor formed at once), ``cutoff`` [Hz] (default from the
        log's excitation) and ``min_speed`` (slow-sample threshold); default the defaults.

    Returns
    -------
    acc : RowAccumulator
        The log's row factors.
    info : dict
        ``{"path", "read", "used", "removed", "warnings"}``: ``warnings`` the reader's WARNING notes
        (positions beyond the plausible bounds, gone on with ``options.allow_units``).
    """
    from .ident.preprocess import prepare
    from .ident.rows import accumulate_prepared, log_columns
    from .io.logs import read_log
    from .numerics import blas_threads

    o = options or IdentOptions()
    with blas_threads():
        log = read_log(path, model.robot, allow_units=o.allow_units)
        if log.tau is None:  # a log of motor currents alone
            raise DataError(f"{path}: no joint torques (tau_<joint>): a log of motor currents is identified on its "
                            f"own, not in a fleet")
        prep = prepare(log, cutoff=o.cutoff, min_speed=o.min_speed)
        acc, _ = accumulate_prepared(model, prep, log_columns(model, log), o.memory_mb, log, o.min_speed)
    return acc, {"path": str(path), "read": int(log.n_samples), "used": int(acc.samples),
                 "removed": dict(prep.removed), "warnings": [n for n in log.notes if "WARNING" in n]}


def combine_pair(a, b):
    """Two accumulators combined (a tree-reduction step).

    Parameters
    ----------
    a, b : RowAccumulator
        Factors of the same model.

    Returns
    -------
    RowAccumulator
        Their TSQR combination.
    """
    from .ident.chunks import combine

    return combine([a, b])


@dataclass(frozen=True, eq=False)
class FleetResult:
    """Estimates over a fleet of logs.

    Parameters
    ----------
    model : IdentModel
        The model identified.
    per_file : dict of str to Fit
        One estimate per log (empty unless asked).
    pooled : Fit, optional
        One estimate from all logs (``None`` unless asked).
    files : list of dict
        Per log used: ``{"path", "read", "used", "removed", "warnings"}`` (:func:`file_factors`).
    spread : dict, optional
        Across the per-file estimates: ``{"mean", "std"}`` per model parameter, ``(p,)`` each.
    skipped : list of dict
        Per log skipped: ``{"path", "error", "stage"}``: ``stage`` ``"read"`` (the log is not used at
        all) or ``"fit"`` (read, but not identifiable alone: not in ``per_file``; its rows are in
        the pooled estimate when one is asked for).
    notes : tuple of str
        What the options asked for and the fleet did not do, one line each (``rotor="auto"`` and
        ``terms="auto"``: not tried in a fleet, :func:`fleet_notes`).
    """

    model: IdentModel
    per_file: dict[str, Fit]
    pooled: Fit | None
    files: list[dict]
    spread: dict | None
    skipped: list[dict] = field(default_factory=list)
    notes: tuple = ()

    def __repr__(self) -> str:
        what = [counted(len(self.per_file), "per-file fit")] if self.per_file else []
        what += ["pooled " + self.pooled.method] if self.pooled is not None else []
        return clip(f"<FleetResult {self.model.robot.name}: {counted(len(self.files), 'log')}, "
                    f"{counted(self.model.n_params, 'term')}, "
                    f"{', '.join(what) or 'no fits'}>")

    def pooled_note(self) -> str | None:
        """What the pooled default estimate chose (``auto``: cross-validated over the logs), or ``None``.

        Returns
        -------
        str or None
            The :class:`~baseparams.ident.select.Selection`'s line, blocks being groups of logs.
        """
        if self.pooled is None:
            return None
        sel = self.pooled.selection
        if sel is None:
            if self.pooled.method != "auto":
                return None
            return ("default estimate: weighted least squares; one log, nothing to cross-validate over the logs: "
                    "identify it alone for the model file's prior")
        return replace(sel, scope="cross-validation over the logs (each block whole logs)").note()

    def to_json(self) -> dict:
        """One JSON-able object.

        Returns
        -------
        dict
            ``model, names, logs{given, used, skipped}, files, skipped, per_file{path: values},
            pooled{values, std, covariance, estimate} | null, spread{mean, std} | null, notes``
            (``estimate``: :meth:`pooled_note`; ``notes``: :attr:`notes`).
        """
        names = self.model.names
        given = len(self.files) + sum(s["stage"] == "read" for s in self.skipped)
        return {"model": self.model.robot.name, "names": names,
                "logs": {"given": given, "used": len(self.files), "skipped": len(self.skipped)},
                "files": self.files, "skipped": self.skipped,
                "per_file": {k: f.theta.tolist() for k, f in self.per_file.items()},
                "pooled": None if self.pooled is None else {"values": self.pooled.theta.tolist(),
                                                             "std": self.pooled.estimate.std.tolist(),
                                                             "covariance": self.pooled.estimate.covariance,
                                                             "estimate": self.pooled_note()},
                "spread": None if self.spread is None else {k: v.tolist() for k, v in self.spread.items()},
                "notes": list(self.notes)}


#: the estimator of a fleet when the options are not given (the fleet's own default: per-joint weights)
FLEET_METHOD = "wls"


def fleet_notes(model: IdentModel, options: IdentOptions) -> tuple[str, ...]:
    """What the options leave to the data that a fleet does not try, one line each; forced model terms refused.

    A fleet fits one model to every log (the per-file estimates, their spread and the pooled estimate
    have the same parameters) from each log's row factors: ``rotor="auto"`` (identify's default) and
    ``terms="auto"`` choose per log from its rows, so a fleet fits neither and says so.

    Parameters
    ----------
    model : IdentModel
        The model the fleet fits (with rotor inertia columns or without).
    options : IdentOptions
        The fleet's options.

    Returns
    -------
    tuple of str
        The notes (none for rotor inertia when ``rotor`` is True or False or the model has its
        columns; none for the terms with ``terms="none"``).

    Raises
    ------
    BaseparamsError
        Model terms forced by name (``terms="dahl"``): a fleet cannot fit them.
    """
    from .ident.notes import rotor_not_tried
    from .ident.terms.fit import parse_terms

    candidates, forced = parse_terms(options.terms)
    if forced:
        raise BaseparamsError(f"identify: terms={options.terms} applies to one log or several recordings in one "
                              f"identification, not to a fleet of logs (per-file or pooled estimates: the linear "
                              f"model alone)")
    rotor = any(k in ("Ia", "Iam") for k in model.drives.param_kinds)
    notes = [rotor_not_tried("fleet")] if isinstance(options.rotor, str) and not rotor else []
    if candidates:
        notes.append(f"model terms (terms={options.terms}): not tried for a fleet of logs (each log is reduced to "
                     f"its row factors; the terms' choice needs its rows), so the linear model alone; identify a log "
                     f"alone, or several recordings in one identification, for them; --terms none leaves them out "
                     f"without this note")
    return tuple(notes)


def identify_fleet(model: IdentModel, paths, options: IdentOptions | None = None, /, *, per_file: bool = True,
                   pooled: bool = False, client=None, scheduler: str | None = None, workers: int | None = None,
                   progress=None, **keywords) -> FleetResult:
    """Identify over many logs on Dask.

    Parameters
    ----------
    model : IdentModel
        The model (:func:`baseparams.ident.model.model_for` builds it from the options).
    paths : iterable of str
        Log files, one robot each for ``per_file``.
    options : IdentOptions, optional
        How (:class:`~baseparams.ident.options.IdentOptions`): the estimator ``method`` (default
        here :data:`FLEET_METHOD`), ``prior_weight``, ``memory_mb`` (the largest regressor a task
        forms at once: memory per worker is bounded by it and by one log's signals, not by the
        fleet), ``cutoff``, ``min_speed``, and ``covariance`` (the pooled estimate's standard
        deviations: ``hac``, a second pass over the logs at the pooled estimate, each log's
        Newey-West meat summed; or the white-noise formula).
    per_file : bool
        One estimate per log, and the spread across them.
    pooled : bool
        One estimate from all logs.
    client : distributed.Client, optional
        An existing client.
    scheduler : str, optional
        A scheduler address (default ``DASK_SCHEDULER_ADDRESS``, else a local cluster).
    workers : int, optional
        Local cluster size (default: one worker per core).
    progress : callable, optional
        Called with one line per finished log.
    **keywords
        Options as keywords, instead of or over ``options`` (``method="ols"``).

    Returns
    -------
    FleetResult
        The estimates.

    Raises
    ------
    BaseparamsError
        No file, no usable log (every one skipped), neither ``per_file`` nor ``pooled``, dask
        missing (names the extra), or a floating base.
    """
    from .ident.options import options_of

    opts = options_of(options, keywords if options is not None else {"method": FLEET_METHOD, **keywords})
    if model.robot.floating:
        raise BaseparamsError(f"robot {model.robot.name!r}: fleets of a floating base are not supported yet; identify "
                              "each log on its own (baseparams identify MODEL LOG)")
    paths = [str(p) for p in paths]
    if not paths:
        raise BaseparamsError("no log file to identify")
    if not (per_file or pooled):
        raise BaseparamsError("ask for per_file and/or pooled estimates")
    notes = fleet_notes(model, opts)
    # workers of an existing cluster run elsewhere: they get absolute paths, reports the ones given
    given = {os.path.abspath(p): p for p in paths}
    with dask_client(client, scheduler, workers) as cl:
        futures = cl.map(_file_task, [os.path.abspath(p) for p in paths], model=model, options=opts, pure=False)
        results = _gather(cl, futures, progress, given)
        skipped = [i for a, i in results if a is None]
        results = [(a, i) for a, i in results if a is not None]
        if not results:
            raise BaseparamsError(f"no usable log: all {len(paths)} skipped (first: {skipped[0]['error']})")
        accs = [a for a, _ in results]
        files = [i for _, i in results]
        fits = _per_file_fits(model, accs, files, opts, skipped, progress) if per_file else {}
        spread = None
        if len(fits) > 1:
            thetas = np.array([f.theta for f in fits.values()])
            spread = {"mean": thetas.mean(axis=0), "std": thetas.std(axis=0, ddof=1)}
        pooled_fit = None
        if pooled:
            acc = _tree(accs)
            # auto: the prior's weight by cross-validation over the logs (each block a group of whole logs)
            pooled_fit = fit(model, acc, opts.method, opts.prior_weight, blocks=accs if len(accs) > 1 else None,
                             rule="recordings" if len(accs) > 1 else "blocks")
            pooled_fit = pulled_covariance(_pooled_covariance(cl, pooled_fit, acc, files, opts, progress))
    return FleetResult(model, fits, pooled_fit, files, spread, skipped, notes)


def _pooled_covariance(cl, f, acc, files: list[dict], opts: IdentOptions, progress):
    """The pooled fit with its covariance: HAC from a second pass over the logs used, or white."""
    from dataclasses import replace

    from .ident.uncertainty import apply_covariance, describe, sandwich, with_covariance

    if opts.covariance == "white":
        return apply_covariance(f, acc, (), "white")[0]
    est = f.estimate
    inv = np.linalg.inv(est.R11)
    h_inv = inv @ inv.T
    paths = [os.path.abspath(i["path"]) for i in files]
    if progress is not None:
        progress(f"covariance (HAC): a second pass over {len(paths)} logs at the pooled estimate")
    futures = cl.map(_meat_task, paths, model=f.model, theta=f.theta, h_inv=h_inv, weights=est.weights, options=opts,
                     pure=False)
    meats = cl.gather(futures)
    cov = sandwich([(m, q) for m, q, _ in meats], h_inv, acc.samples * acc.nrows)
    widths = sorted({b for _, _, b in meats})
    label = describe("hac", widths[-1]) + (f" (per log, {widths[0]} to {widths[-1]})" if len(widths) > 1 else "")
    return replace(f, estimate=with_covariance(est, f.theta, cov, label))


def _meat_task(path: str, model: IdentModel, theta, h_inv, weights, options: IdentOptions):
    """One log's HAC meat at the pooled estimate (the covariance's second pass, on a worker).

    Returns ``(S (p, p), Q (p, p), bandwidth)`` of :class:`~baseparams.ident.uncertainty.HacMeat`.
    """
    from .ident.preprocess import prepare
    from .ident.rows import accumulate_prepared, log_columns
    from .ident.uncertainty import hac_meat
    from .io.logs import read_log
    from .numerics import blas_threads

    o = options
    with blas_threads():
        log = read_log(path, model.robot, allow_units=o.allow_units)
        if log.tau is None:  # a log of motor currents alone
            raise DataError(f"{path}: no joint torques (tau_<joint>): a log of motor currents is identified on its "
                            f"own, not in a fleet")
        prep = prepare(log, cutoff=o.cutoff, min_speed=o.min_speed)
        cols = log_columns(model, log)
        kept: list = []
        acc, _ = accumulate_prepared(model, prep, cols, o.memory_mb, log, o.min_speed, keep=kept)
        if not kept:
            from .ident.uncertainty import fitted_rows

            kept = fitted_rows(model, prep, cols, o.memory_mb, log, o.min_speed)
        meat = hac_meat(kept, h_inv, theta, weights, acc.samples)
    return meat.meat(), meat.bias(), meat.b


def _as_given(info: dict, given: dict[str, str]) -> dict:
    """A task's report with the path as the user gave it (tasks see absolute paths)."""
    if not isinstance(info, dict) or info.get("path") not in given:
        return info
    shown, absolute = given[info["path"]], info["path"]
    return {k: (v.replace(absolute, shown) if isinstance(v, str) else v) for k, v in info.items()}


def _file_task(path: str, model: IdentModel, options: IdentOptions):
    """:func:`file_factors`, or ``(None, {"path", "error"})`` for a bad log (one line, the fleet goes on)."""
    try:
        return file_factors(path, model, options)
    except (BaseparamsError, np.linalg.LinAlgError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return None, {"path": str(path), "error": msg if str(path) in msg else f"{path}: {msg}", "stage": "read"}


def _per_file_fits(model, accs, files, opts: IdentOptions, skipped, progress) -> dict:
    """One fit per log; a log that cannot be identified alone is skipped (its rows stay in the pool)."""
    fits = {}
    for a, i in zip(accs, files):
        try:
            fits[i["path"]] = fit(model, a, opts.method, opts.prior_weight)
        except (BaseparamsError, np.linalg.LinAlgError) as exc:
            skipped.append({"path": i["path"], "error": f"{i['path']}: not identifiable alone: {exc}", "stage": "fit"})
            if progress is not None:
                progress(f"skipped {skipped[-1]['error']}")
    return fits


def _gather(cl, futures, progress, given=None):
    """Results in submission order, reporting each as it finishes (a skipped log: one line saying why)."""
    from distributed import as_completed

    done = {}
    for k, fut in enumerate(as_completed(futures)):
        acc, info = fut.result()
        info = _as_given(info, given or {})
        done[fut.key] = (acc, info)
        if progress is None:
            continue
        if acc is None:
            progress(f"[{k + 1}/{len(futures)}] skipped {info['error']}")
        else:
            progress(f"[{k + 1}/{len(futures)}] {info['path']}: {info['used']} samples used of {info['read']}")
    return [done[f.key] for f in futures]


def _tree(accs):
    """Pairwise (TSQR) reduction of accumulators."""
    level = list(accs)
    while len(level) > 1:
        level = [combine_pair(level[k], level[k + 1]) if k + 1 < len(level) else level[k]
                 for k in range(0, len(level), 2)]
    return level[0]


def _connect(client_class, address: str, source: str):
    """A client of the scheduler at ``address``, or one line naming it (fails within the timeout)."""
    try:
        return client_class(address, timeout=SCHEDULER_TIMEOUT_S)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise BaseparamsError(f"{source} {address}: cannot connect to a Dask scheduler ({reason})") from None


#: the most local-cluster workers per core (each is a process)
MAX_WORKERS_PER_CORE = 4


class dask_client:
    """Context manager: the given client, a scheduler's, or a local cluster started and stopped here.

    Parameters
    ----------
    client : distributed.Client or None
        An existing client (used as it is, not closed).
    scheduler : str or None
        A scheduler address (default ``DASK_SCHEDULER_ADDRESS``, else a local cluster).
    workers : int or None
        Local cluster size (default: one worker per core).
    """

    def __init__(self, client, scheduler, workers):
        self.client, self.scheduler, self.workers = client, scheduler, workers
        self.own = []

    def __enter__(self):
        if self.client is not None:
            return self.client
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise BaseparamsError("fleet identification needs Dask: pip install 'baseparams[fleet]'") from None
        address = self.scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
        if address:
            cl = _connect(Client, address, "--scheduler" if self.scheduler else "DASK_SCHEDULER_ADDRESS")
        else:
            cores = os.cpu_count() or 1
            n = self.workers or cores
            if n > MAX_WORKERS_PER_CORE * cores:  # each a process: 1024 on 2 cores take minutes to start
                raise BaseparamsError(f"--workers {n}: a local cluster of at most {MAX_WORKERS_PER_CORE * cores} "
                                      f"worker processes on this machine's {cores} cores (a scheduler, --scheduler, "
                                      f"for more)")
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
            self.own.append(cluster)
            cl = Client(cluster)
        self.own.insert(0, cl)
        return cl

    def __exit__(self, *exc):
        for thing in self.own:
            thing.close()
        return False


def simulate_fleet(robot, outdir, robots: int, duration: float = 60.0, rate: float = 1000.0, noise: float = 0.05,
                   spread: float = 0.1, seed: int = 0, friction=FRICTION_TERMS,
                   suffix: str = ".npz", **simulate) -> list[Path]:
    """Write one synthetic log per robot of a fleet, each with its own known parameters.

    Robot ``k``'s bodies have their masses and inertias scaled by ``1 + spread u`` (``u``
    uniform in [-1, 1], per body; a scaled body stays physically consistent), its drive
    parameters drawn; each log is simulated and written before the next (the fleet is never
    held whole). ``<name>.truth.json`` beside each log holds its true model parameters.

    Parameters
    ----------
    robot : Robot
        The model (fixed base).
    outdir : str or Path
        Output folder (created).
    robots : int
        Number of robots.
    duration, rate, noise : float
        Per log: length [s], sampling rate [Hz], torque noise [N m].
    spread : float
        Relative spread of the bodies' inertial parameters across the fleet.
    seed : int
        Seed of the fleet.
    friction : iterable of str
        Friction terms simulated.
    suffix : str
        ``.npz`` or ``.csv``.
    **simulate
        Passed to :func:`~baseparams.ident.simulate.simulate_log` for every robot (``amplitude``,
        ``rotor``, ``convention``, ``trajectory``, ``samples``).

    Returns
    -------
    list of Path
        The logs written.
    """
    import json
    from dataclasses import replace

    from .files import write_text
    from .ident.simulate import simulate_log
    from .io.logs import write_log

    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    paths = []
    for k in range(robots):
        scale = 1.0 + spread * rng.uniform(-1.0, 1.0, robot.n)
        variant = replace(robot, N_body=robot.N_body * scale[:, None, None])  # a positive scale keeps N_i PSD
        log, truth = simulate_log(variant, duration=duration, rate=rate, noise=noise, seed=seed * 100003 + k,
                                  friction=friction, **simulate)
        path = out / f"robot{k:04d}{suffix}"
        write_log(path, log)
        write_text(path.with_name(path.name + ".truth.json"), json.dumps(truth), what="truth")
        paths.append(path)
        print(f"{path}: {log.n_samples} samples", file=sys.stderr)
    return paths


def synthetic_factors(model: IdentModel, theta: np.ndarray, chunk: int, samples: int, seed: int = 0,
                      noise: float = 0.05, rate: float = 1000.0, harmonics: int = 5, base_frequency: float = 0.1,
                      amplitude: float = 0.5):
    """Row factors of chunk ``chunk`` of a synthetic log generated inside the task (no disk).

    One long periodic Fourier trajectory (coefficients from ``seed``) is evaluated at the
    chunk's samples, exact states, torques ``A theta`` plus noise that is a function of the global
    sample index (so any chunking gives the same data): the throughput of the regressor and the
    factorisation alone, for benchmarks (a real log adds reading and filtering).

    Parameters
    ----------
    model : IdentModel
        The model (a tree).
    theta : ndarray, shape ``(p,)``
        True model parameters.
    chunk : int
        Chunk index.
    samples : int
        Samples per chunk.
    seed : int
        Seed of the trajectory (shared by all chunks) and of the chunk's noise.
    noise : float
        Torque noise standard deviation [N m] (uniform, deterministic per sample).
    rate : float
        Sampling rate [Hz].
    harmonics : int
        Fourier harmonics.
    base_frequency : float
        Fundamental [Hz].
    amplitude : float
        Approximate joint excursion [rad].

    Returns
    -------
    RowAccumulator
        The chunk's factors.
    """
    from .ident.estimate import RowAccumulator
    from .numerics import blas_threads

    m = model.state_columns
    coef = np.random.default_rng(seed).normal(size=(2, harmonics, m))
    w = 2 * np.pi * base_frequency * np.arange(1, harmonics + 1)
    t = (chunk * samples + np.arange(samples)) / rate
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
    k = amplitude / np.sqrt(harmonics)
    a, b = coef[0] * k, coef[1] * k
    q = s @ (a / w[:, None]) - c @ (b / w[:, None])
    dq, ddq = c @ a + s @ b, -s @ (a * w[:, None]) + c @ (b * w[:, None])
    with blas_threads():
        reg = model.regressor(q, dq, ddq)
        tau = reg @ theta + noise * _sample_noise(chunk * samples + np.arange(samples), reg.shape[1], seed)
        return RowAccumulator(len(model.coords), model.n_params).add(reg, tau)


def _sample_noise(index: np.ndarray, m: int, seed: int) -> np.ndarray:
    """Unit-variance pseudo-random noise ``(S, m)``, a function of the global sample index only."""
    x = np.sin(index[:, None] * 12.9898 + np.arange(m) * 78.233 + seed * 3.1) * 43758.5453
    return np.sqrt(12.0) * (x - np.floor(x) - 0.5)


def synthetic_fleet_factors(model: IdentModel, theta: np.ndarray, chunks: int, samples: int, client, seed: int = 0):
    """All chunks of a synthetic log on Dask, reduced in a tree (TSQR) on the workers.

    Parameters
    ----------
    model : IdentModel
        The model.
    theta : ndarray, shape ``(p,)``
        True model parameters.
    chunks : int
        Number of chunks.
    samples : int
        Samples per chunk.
    client : distributed.Client
        The cluster.
    seed : int
        Seed (see :func:`synthetic_factors`).

    Returns
    -------
    RowAccumulator
        The combined factors of ``chunks * samples`` samples.
    """
    mfut = client.scatter(model, broadcast=True, hash=False)  # a fresh key: a previous run may still release its own
    level = client.map(synthetic_factors, [mfut] * chunks, [theta] * chunks, range(chunks), [samples] * chunks,
                       seed=seed, pure=False)
    while len(level) > 1:  # combine on the workers as results arrive, pairwise
        level = [client.submit(combine_pair, level[k], level[k + 1], pure=False) if k + 1 < len(level) else level[k]
                 for k in range(0, len(level), 2)]
    return level[0].result()
