"""A design sweep: many robot files analysed on Dask (``baseparams analyze 'variants/*.urdf'``).

Each file is one task (:func:`analyze_file`: load, analyse, its JSON or its one-line error); the
cluster is :class:`baseparams.fleet.dask_client`'s (a client, a scheduler's address, or a local
cluster started and stopped here).
"""

from __future__ import annotations

import os
from pathlib import Path

from .errors import BaseparamsError
from .fleet import dask_client


def analyze_file(path: str, floating: bool = False, convention: str = "khalil", rows: str = "all") -> dict:
    """One model file analysed (the task of a design sweep).

    Parameters
    ----------
    path : str
        A robot file (URDF / URDF+ / MJCF) or a built-in name.
    floating : bool
        Attach the root link by a free joint.
    convention : str
        Convention of the regrouped expressions.
    rows : {"all", "joints", "base"}
        Measured rows.

    Returns
    -------
    dict
        :meth:`baseparams.analysis.Analysis.to_json` plus ``"path"``; a file that cannot be
        analysed gives ``{"path", "error"}`` (one line) instead of failing the sweep.
    """
    import warnings

    from .analysis import analyze
    from .loading import load_model

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            robot, _ = load_model(path, floating=floating, strict_inertia=False)
        return {"path": str(path), **analyze(robot, convention=convention, rows=rows).to_json()}
    except BaseparamsError as exc:
        return {"path": str(path), "error": str(exc)}


def analyze_fleet(paths, *, client=None, scheduler: str | None = None, workers: int | None = None,
                  floating: bool = False, convention: str = "khalil", rows: str = "all", progress=None) -> list[dict]:
    """Many model files analysed on Dask (a design sweep over geometric variants).

    Parameters
    ----------
    paths : iterable of str
        Robot files.
    client, scheduler, workers
        The cluster, as for :func:`baseparams.fleet.identify_fleet`.
    floating : bool
        Attach each root link by a free joint.
    convention : str
        Convention of the regrouped expressions.
    rows : {"all", "joints", "base"}
        Measured rows.
    progress : callable, optional
        Called with one line per finished file.

    Returns
    -------
    list of dict
        One :func:`analyze_file` result per path, in order.
    """
    from distributed import as_completed

    paths = [str(p) if "://" in str(p) or not Path(p).exists() else os.path.abspath(p) for p in paths]
    with dask_client(client, scheduler, workers) as cl:
        futures = cl.map(analyze_file, paths, floating=floating, convention=convention, rows=rows, pure=False)
        done = {}
        for k, fut in enumerate(as_completed(futures)):
            res = fut.result()
            done[fut.key] = res
            if progress is not None:
                what = res.get("error") or f"{res['status']}, {res['n_base']} base parameters"
                progress(f"[{k + 1}/{len(futures)}] {res['path']}: {what}")
    return [done[f.key] for f in futures]
