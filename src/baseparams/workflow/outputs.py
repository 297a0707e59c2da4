"""Every rule about the files a run writes, and the writers of identify's: one home for both doors.

:data:`SUFFIXES` says which formats each kind of output is written in (the format comes from the
suffix) and :data:`OUTPUTS` which kind each command's output keyword is; :func:`check_outputs`
checks a run's outputs before any work (a known suffix, a folder that exists, no input
overwritten, no two outputs onto one file). The front door's functions call it with their
keywords, the command line's preflight with its flags' keywords (:mod:`baseparams.cli.preflight`):
one rule, one message, naming the keyword (the command line names the flag). Every write is
atomic (:func:`baseparams.files.atomic_path`), never onto an input.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, fields
from pathlib import Path
from types import MappingProxyType

from ..errors import BaseparamsError
from ..tables import LOG_SUFFIXES, PREDICTION_SUFFIXES, TABLE_SUFFIXES, TRAJECTORY_SUFFIXES

#: the figure formats matplotlib writes by suffix (with its required Pillow; ``.pgf`` needs LaTeX: not one)
PLOT_SUFFIXES = (".png", ".svg", ".svgz", ".pdf", ".eps", ".ps", ".jpg", ".jpeg", ".tif", ".tiff", ".webp")

#: the formats of each kind of output, by suffix (None: any suffix, the content is the command's)
SUFFIXES = MappingProxyType({
    "plot": PLOT_SUFFIXES,
    "html": None,  # any name: the page is the same (a stream, /dev/stdout, included)
    "urdf": (".urdf",),
    "mjcf": (".xml",),
    "predictions": PREDICTION_SUFFIXES,
    "trajectory": TRAJECTORY_SUFFIXES,
    "log": LOG_SUFFIXES,
    "regressor": TABLE_SUFFIXES,
    "result": None,
    "text": None,
})

#: each command's output keywords and the kind of each (its flag on the command line: ``--plot``, ``OUT``)
OUTPUTS = MappingProxyType({
    "analyze": {"output": "text", "html": "html", "plot": "plot", "codegen": "text"},
    "regressor": {"out": "regressor"},
    "identify": {"output": "text", "save": "result", "predictions": "predictions", "urdf": "urdf", "mjcf": "mjcf",
                 "html": "html", "plot": "plot"},
    "predict": {"out": "predictions"},
    "simulate": {"out": "log"},
    "excite": {"out": "trajectory", "plot": "plot", "output": "text"},
    "payload": {"output": "text", "save": "result", "predictions": "predictions", "urdf": "urdf", "mjcf": "mjcf"},
})


def check_suffix(where: str, name: str, path, kind: str) -> None:
    """One output's suffix among its kind's :data:`SUFFIXES` (the format comes from it).

    Parameters
    ----------
    where : str
        The command or function, for messages.
    name : str
        The output's keyword.
    path : str or path
        The output.
    kind : str
        Its kind (a key of :data:`SUFFIXES`).

    Raises
    ------
    ArgumentError
        Another suffix: one line naming the keyword, the formats and the suffix given.
    """
    from ..arguments import ArgumentError

    allowed = SUFFIXES[kind]
    suffix = Path(os.fspath(path)).suffix
    if allowed is not None and suffix.lower() not in allowed:
        raise ArgumentError(f"{where}: {name}= {os.fspath(path)}: the format comes from the suffix: "
                            f"{', '.join(allowed)}, not {suffix or 'none'}")


def check_outputs(where: str, inputs, **paths) -> None:
    """A run's outputs checked before any work (:data:`OUTPUTS` of ``where``; None: not written).

    Parameters
    ----------
    where : str
        The command (a key of :data:`OUTPUTS`), for the outputs' kinds and messages.
    inputs : iterable of str
        The run's input files (no output may overwrite one).
    **paths
        The outputs by keyword (``plot="fig.png"``).

    Raises
    ------
    BaseparamsError
        A path that is not a str or path, a suffix of no format the output is written in, a
        missing folder, a target that is not a regular file, an input, two outputs onto one file,
        a Parquet output without pyarrow: one line naming the keyword.
    """
    from ..arguments import check_path
    from ..files import check_output
    from ..tables import check_parquet

    kinds = OUTPUTS.get(where, {})
    seen: dict[Path, str] = {}
    for name, path in paths.items():
        if path is None:
            continue
        check_path(path, f"{where}: {name}=")
        kind = kinds.get(name, "text")
        check_suffix(where, name, path, kind)
        if kind in ("predictions", "regressor"):
            check_parquet(os.fspath(path), f"{where}: {name}=")
        check_output(path, inputs, f"{name}=")
        key = Path(os.fspath(path)).resolve()
        if key in seen:
            raise BaseparamsError(f"{where}: {name}= and {seen[key]}= name the same file {os.fspath(path)}")
        seen[key] = name


def check_exports(where: str, source, method: str, urdf=None, mjcf=None, joints=None) -> None:
    """Refuse, before any fit, an export that cannot be honoured (``urdf``, ``mjcf``).

    Parameters
    ----------
    where : str
        The command or function, for messages.
    source : object
        The model file (a path), or the model as given.
    method : str
        The identification method (exports need ``physical``).
    urdf, mjcf : str or path, optional
        The files to write.
    joints : object, optional
        The sub-chain asked for (exports need every joint).

    Raises
    ------
    BaseparamsError
        One line saying what would help (nothing was fitted).
    """
    if (urdf is not None or mjcf is not None) and joints is not None:
        raise BaseparamsError(f"{where}: {'urdf' if urdf is not None else 'mjcf'}= with joints=: writing a sub-chain's "
                              f"values into the whole robot's file is not supported; identify every moving joint to "
                              f"export")
    if urdf is not None:
        if method != "physical":
            raise BaseparamsError(f"{where}: urdf= needs method=physical: least squares gives base parameters, not "
                                  f"bodies (nothing was fitted)")
        path = Path(os.fspath(source)) if isinstance(source, (str, os.PathLike)) else None
        if path is None or path.suffix.lower() != ".urdf" or not path.is_file():
            raise BaseparamsError(f"{where}: urdf= writes the model file with the identified inertias: it needs a URDF "
                                  f"model file, got {source if path is not None else type(source).__name__} (nothing "
                                  f"was fitted)")
    if mjcf is not None:
        from ..io.mjcf_write import check_mjcf_request

        check_mjcf_request(source, method, mjcf, f"{where}: mjcf=")


@dataclass(frozen=True)
class Outputs:
    """The files :func:`baseparams.identify` writes (checked before the fit, written atomically, never onto an input).

    Parameters
    ----------
    save : str or path, optional
        The result (``Identification.save``: versioned JSON).
    predictions : str or path, optional
        The predicted torques at every validation sample (``t, tau_<joint>``; CSV, TSV or Parquet
        by the suffix).
    urdf, mjcf : str or path, optional
        The identified bodies and drive terms written into a copy of the model file (URDF; MJCF
        through MuJoCo, checked by its inverse dynamics): need ``method="physical"`` and the
        model file.
    html, plot : str or path, optional
        A self-contained HTML report; a static figure of the torques (matplotlib).
    """

    save: object = None
    predictions: object = None
    urdf: object = None
    mjcf: object = None
    html: object = None
    plot: object = None

    def __repr__(self) -> str:
        return f"Outputs({', '.join(f'{k}={os.fspath(v)!r}' for k, v in self.given().items())})"

    def given(self) -> dict:
        """The outputs asked for.

        Returns
        -------
        dict
            ``{name: path}`` of the outputs that are not None, in field order.
        """
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}


def write_predictions(result, logs: tuple, holdout, path, inputs, note) -> None:
    """Predicted torques at every validation sample, written to ``path`` (``t, tau_<joint>``).

    A result identified from motor currents: ``tau_<joint>`` the joint-side torques, and
    ``cur_<joint>`` the predicted currents [A] of the motor named after each joint.

    Parameters
    ----------
    result : Identification
        The identification.
    logs : tuple
        ``(log, validation log or None)``: the validation log, else the log's held-out end.
    holdout : float or None
        The hold-out [s] (with no validation log).
    path : str or path
        The file (CSV, TSV or Parquet by the suffix).
    inputs : list of str
        The run's input files.
    note : callable
        Takes the line saying what was written.
    """
    from ..tables import write_columns

    log, val = logs
    whole = val if val is not None else log
    tau = result.predict(whole)
    keep = (whole.t >= -float("inf")) if val is not None else whole.t >= whole.t[-1] - holdout
    cols = {"t": whole.t[keep], **{f"tau_{j}": tau[keep, k] for k, j in enumerate(result.joints)}}
    if result.currents is not None:  # from currents: the joint-side torques and the motors' currents
        cur = result.predict_currents(whole)
        cols.update({f"cur_{m}": cur[keep, k] for k, m in enumerate(result.currents.motors)})
    write_columns(path, cols, inputs, "predictions=")
    note(f"predictions of {int(keep.sum())} validation samples written to {path}")


def write_results(result, log, source, outputs: Outputs, inputs, reporter) -> None:
    """``save``, ``urdf``, ``mjcf``, ``html``, ``plot`` of an identification (each checked before the fit).

    Parameters
    ----------
    result : Identification
        The identification.
    log : JointLog or None
        The log read whole (the MJCF export checks the model on its states), None when streamed.
    source : str, path or None
        The model file (the exports write a copy of it).
    outputs : Outputs
        What to write.
    inputs : list of str
        The run's input files.
    reporter : Reporter
        Progress lines and notes (:class:`baseparams.workflow.identify.Reporter`).
    """
    say, note = reporter.say, reporter.note
    if outputs.save is not None:
        result.save(outputs.save, inputs, "save=")
        say(f"result saved to {outputs.save}")
    if outputs.urdf is not None:
        _write_urdf(result, source, outputs.urdf, inputs, note)
    if outputs.mjcf is not None:
        from ..ident.export import identified_mjcf

        for n in identified_mjcf(result, os.fspath(source), outputs.mjcf, log, inputs=inputs):
            note(n)
        note(f"MJCF written to {outputs.mjcf}")
    if outputs.plot is not None:
        from ..report.plots import torque_plot

        torque_plot(result, outputs.plot, inputs, "plot=")
        say(f"plot written to {outputs.plot}")
    if outputs.html is not None:
        from ..files import write_text
        from ..report.html import identification_html

        write_text(outputs.html, identification_html(result), inputs, "html=")
        say(f"HTML report written to {outputs.html}")


def _write_urdf(result, source, path, inputs, note) -> None:
    """The model's URDF file with the identified inertias and drive terms (``urdf=``)."""
    from ..ident.export import identified_drives
    from ..io.urdf import write_urdf

    drives, couplings = identified_drives(result)
    tilt = next((t for t in result.fit.terms if t.name == "tilt"), None)
    rotation = None if tilt is None else tilt.base_rotation()
    for n in write_urdf(os.fspath(source), path, result.model.robot, result.fit.physical.pi, "paper", drives=drives,
                        couplings=couplings, inputs=inputs, base_rotation=rotation):
        note(n)
    for n in (x for t in result.fit.terms for x in t.export().get("not", [])):
        note(f"urdf=: not written: {n}")
    note(f"URDF written to {path}")
