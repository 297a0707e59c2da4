"""``baseparams.identify_payload``: what a robot carries on a link (and the ``payload`` command's one implementation).

:func:`identify_payload` takes one keyword per flag of ``baseparams payload``; :func:`check_payload`
holds every rule of them that needs no model (the options as one
:class:`~baseparams.ident.payload.PayloadOptions`, a prior file, the exports' model file, every
output), which the command line's preflight calls too. The files are read here (the model, the
logs, a saved identification), every output is written atomically, never onto an input; the work
is :mod:`baseparams.ident.payload`'s (``excite(payload=LINK)``: :mod:`baseparams.workflow.excite`).
Messages name options by their keywords; the command line names them by their flags.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

from ..arguments import PAYLOAD
from ..errors import BaseparamsError
from .inputs import input_files, log_of, robot_of
from .outputs import check_outputs

#: the keywords that are :class:`~baseparams.ident.payload.PayloadOptions`' fields
OPTIONS = tuple(PAYLOAD)


def identify_payload(model, log, *, link: str, result=None, validate=None, columns=None,
                     method: str = PAYLOAD["method"], friction=PAYLOAD["friction"], rotor: str = PAYLOAD["rotor"],
                     offsets: str = PAYLOAD["offsets"], coulomb_width: float | None = PAYLOAD["coulomb_width"],
                     min_speed: float | None = PAYLOAD["min_speed"], slow_fraction: float = PAYLOAD["slow_fraction"],
                     still: float = PAYLOAD["still"], cutoff: float | None = PAYLOAD["cutoff"],
                     decimate: int | None = PAYLOAD["decimate"], covariance: str = PAYLOAD["covariance"],
                     memory_mb: float = PAYLOAD["memory_mb"], prior=PAYLOAD["prior"],
                     analysis_samples: int | None = None, seed: int = PAYLOAD["seed"], save=None, urdf=None,
                     mjcf=None, predictions=None, progress=None, _source=None):
    """Identify what a robot carries on a link from a log: ``baseparams payload MODEL LOG --link LINK``.

    One keyword per flag of the command (the command calls this function). The robot is known:
    from its model file (its rigid body and armature; the moving joints' friction is fitted with
    the payload), or from a saved identification of it without the payload (``result``: its
    prediction; the payload comes out of the regrouping of the link's columns).
    :mod:`baseparams.ident.payload` describes the method. Every keyword is checked before the model
    loads (:func:`check_payload`).

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot without the payload (a built-in name or a robot file is loaded).
    log : JointLog, str or path
        The log with the payload: positions and torques of every joint (a log file is read for
        ``model``: README "Log layout").
    link : str
        The link the payload is fixed to (its name, or its joint's).
    result : Identification, str or path, optional
        A saved identification of the robot without the payload (``identify --save``). Identify it
        with ``rotor=True`` when the drives have rotor inertia: a result without it mispredicts
        every acceleration of the payload's log (a WARNING note says so when the log shows it).
    validate : JointLog, str or path, optional
        Another log with the payload: every sample predicted, RMS per joint (``.validation``).
    columns : str, path or dict, optional
        A layout mapping for the log files (README "Log layout").
    method, friction, rotor, offsets, coulomb_width, min_speed, slow_fraction, still, cutoff, decimate, \
covariance, memory_mb, seed
        The identification's options (:class:`~baseparams.ident.payload.PayloadOptions`: the
        estimator, the moving joints' drive terms (their offsets kept by cross-validation), the slow
        and still samples, the filter, the standard deviations, the largest regressor [MB], the
        structural analysis' seed).
    prior : dict, Inertia, str or path, optional
        Hold what the motion does not identify at this payload: ``{"mass", "com", "inertia_com"}``
        (LINK's frame), an Inertia, or a JSON file of that object or a saved payload's (``save``).
    analysis_samples : int, optional
        Random states of the structural analysis (default 200).
    save : str or path, optional
        Write the result's JSON (``{"format": "baseparams-payload", ..., "payload": {...}}``;
        :meth:`baseparams.ident.payload.saved.SavedPayload.load` reads it back).
    urdf, mjcf : str or path, optional
        Write the model file with the payload as a fixed body on ``link`` (a URDF model for
        ``urdf``; an MJCF or URDF model for ``mjcf``), checked by MuJoCo's inverse dynamics
        (:mod:`baseparams.ident.payload.export`).
    predictions : str or path, optional
        With ``validate``: the torques predicted with the payload at every sample of that log
        (``t, tau_<joint>``; CSV, TSV or Parquet by the suffix).
    progress : callable, optional
        Called with one line of text per step.
    _source : str or path, optional
        The model file a given Robot was loaded from (the command line's), for the exports.

    Returns
    -------
    Payload
        ``.mass``, ``.com``, ``.inertia_com`` (LINK's frame), ``.sigma()``, ``.identified()``,
        ``.to_json()``, ``.summary()``, ``.predict(log)``; its ``notes`` list what was written.

    Raises
    ------
    BaseparamsError
        Bad options, files or outputs (checked before the model loads), an unknown link, a robot
        that is not a fixed-base tree, a result of another robot, a log in which nothing carrying
        the link moves, an export of a payload the motion does not identify.
    """
    kw = {"link": link, "result": result, "validate": validate, "columns": columns, "method": method,
          "friction": friction, "rotor": rotor, "offsets": offsets, "coulomb_width": coulomb_width,
          "min_speed": min_speed, "slow_fraction": slow_fraction, "still": still, "cutoff": cutoff,
          "decimate": decimate, "covariance": covariance, "memory_mb": memory_mb, "prior": prior,
          "analysis_samples": analysis_samples, "seed": seed, "save": save, "urdf": urdf, "mjcf": mjcf,
          "predictions": predictions, "progress": progress}
    file = model if _source is None else _source
    opts, inputs = check_payload(file, log, kw)
    robot = robot_of(model, "payload")
    from ..ident.payload.model import body_of

    body_of(robot, link)
    return _run(robot, log, opts, inputs, file, kw)


def check_payload(model, log, keywords: dict):
    """Every rule of :func:`identify_payload`'s keywords that needs no model: the options, the prior, the outputs.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The model as given (the exports need a model file; a file's inputs are never overwritten).
    log : JointLog, str or path
        The log as given (an input: never overwritten).
    keywords : dict
        :func:`identify_payload`'s keywords; those missing take their defaults.

    Returns
    -------
    tuple
        ``(PayloadOptions, inputs)``: the options, checked, and the run's input files.

    Raises
    ------
    BaseparamsError
        The first keyword refused, in one line naming it (its type, its range, a choice, a prior
        that is no physical body, ``predictions`` without ``validate``, an output's suffix, folder
        or clash with an input, an export without a model file of its kind).
    """
    from ..arguments import RANGES, check_keywords, check_progress
    from ..ident.payload import PayloadOptions

    k = {"link": None, "result": None, "validate": None, "columns": None, **keywords}
    check_keywords("payload", **{n: k[n] for n in OPTIONS if n in RANGES and k.get(n) is not None})
    values = {n: k[n] for n in OPTIONS if n in k and not (n == "analysis_samples" and k[n] is None)}
    values["prior"] = _prior(values.get("prior"))
    opts = PayloadOptions(**values)
    check_progress(k.get("progress"), "payload")
    outputs = {n: k.get(n) for n in ("save", "urdf", "mjcf", "predictions")}
    if outputs["predictions"] is not None and k["validate"] is None:
        raise BaseparamsError("payload: predictions= are the torques of the validation log: give validate= (nothing "
                              "was fitted)")
    inputs = input_files(model, log, k["result"], k["validate"], k["columns"], k.get("prior"))
    check_outputs("payload", inputs, **outputs)
    _check_exports(model, outputs["urdf"], outputs["mjcf"])
    return opts, inputs


def _check_exports(model, urdf, mjcf) -> None:
    """An export needs the model file of its kind (checked before any work)."""
    src = Path(os.fspath(model)) if isinstance(model, (str, os.PathLike)) else None
    for name, value, kinds in (("urdf", urdf, (".urdf",)), ("mjcf", mjcf, (".urdf", ".xml"))):
        if value is not None and (src is None or src.suffix.lower() not in kinds or not src.is_file()):
            raise BaseparamsError(f"payload: {name}= writes the model file with the payload: it needs a "
                                  f"{' or '.join(kinds)} model file, got {model if src else type(model).__name__} "
                                  f"(nothing was fitted)")


def _prior(prior):
    """``prior=`` as :class:`~baseparams.ident.payload.PayloadOptions` takes it: a JSON file read, else as given."""
    if not isinstance(prior, (str, os.PathLike)):
        return prior
    import json

    from ..files import read_input_bytes

    path = os.fspath(prior)
    try:
        doc = json.loads(read_input_bytes(path, 1 << 20))
    except (ValueError, UnicodeDecodeError) as exc:
        raise BaseparamsError(f"payload: prior= {path}: not JSON ({exc})") from None
    doc = doc.get("payload", doc) if isinstance(doc, dict) else doc
    if not isinstance(doc, dict) or any(doc.get(k) is None for k in ("mass", "com", "inertia_com")):
        raise BaseparamsError(f"payload: prior= {path}: expected an object with mass, com and inertia_com (numbers)")
    return {k: doc[k] for k in ("mass", "com", "inertia_com")}


def _run(robot, log, opts, inputs: list[str], file, kw: dict):
    """Read the logs and the saved identification, identify, write the outputs."""
    from ..ident.payload import identify_payload as core

    columns = kw["columns"]
    read = log_of(log, robot, columns, name="log")
    val = None if kw["validate"] is None else log_of(kw["validate"], robot, columns, name="validate")
    res = _result(kw["result"], robot)
    out = core(robot, read, kw["link"], opts, result=res, validation=val, progress=kw["progress"])
    notes = _write(out, file, inputs, save=kw["save"], urdf=kw["urdf"], mjcf=kw["mjcf"])
    if kw["predictions"] is not None:
        from ..tables import write_columns

        tau = out.predict(val)
        write_columns(kw["predictions"], {"t": val.t, **{f"tau_{j}": tau[:, k] for k, j in
                                                         enumerate(robot.coordinate_names())}}, inputs, "predictions=")
        notes.append(f"predictions of {val.n_samples} validation samples written to {kw['predictions']}")
    return replace(out, notes=out.notes + tuple(notes)) if notes else out


def _result(result, robot):
    """A saved identification: an Identification as given, or read from its file for the robot."""
    if result is None or not isinstance(result, (str, os.PathLike)):
        return result
    from ..ident import Identification

    return Identification.load(result, robot)


def _write(payload, model, inputs: list, save=None, urdf=None, mjcf=None) -> list[str]:
    """The outputs asked for, each written atomically; a note per file."""
    notes = []
    if save is not None:
        payload.save(save, inputs)
        notes.append(f"result saved to {save}")
    if urdf is not None:
        from ..ident.payload.export import payload_urdf

        notes += payload_urdf(payload, model, urdf, inputs)
    if mjcf is not None:
        from ..ident.payload.export import payload_mjcf

        notes += payload_mjcf(payload, model, mjcf, inputs)
    return notes
