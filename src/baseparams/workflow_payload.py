"""The payload's front door: :func:`identify_payload`, ``baseparams payload`` (``excite --payload``: ``bp.excite``).

A module of its own beside :mod:`baseparams.workflow` (the loop's front door, whose helpers it uses:
a half floor above it, below the CLI): the files are read and checked here (the model, the log, a saved
identification), every output is checked before the fit and written atomically, never onto an
input; the work is :mod:`baseparams.ident.payload`'s (``bp.excite(..., payload=LINK)``:
:mod:`baseparams.excitation.payload`'s).
"""

from __future__ import annotations

import os
from pathlib import Path

#: the suffixes of the outputs, by keyword
SUFFIXES = {"save": (".json",), "urdf": (".urdf",), "mjcf": (".xml",), "predictions": (".csv", ".tsv")}


def identify_payload(model, log, *, link: str, result=None, validate=None, columns=None, save=None, urdf=None,
                     mjcf=None, predictions=None, source=None, options=None, progress=None, **keywords):
    """Identify what a robot carries on a link from a log: ``baseparams payload MODEL LOG --link LINK``.

    The robot is known: from its model file (its rigid body and armature; the moving joints'
    friction is fitted with the payload), or from a saved identification of it without the payload
    (``result``: its prediction; the payload comes out of the regrouping of the link's columns).
    :mod:`baseparams.ident.payload` describes the method.

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
        A saved identification of the robot without the payload (``identify --save``).
    validate : JointLog, str or path, optional
        Another log with the payload: every sample predicted, RMS per joint (``.validation``).
    columns : str, path or dict, optional
        A layout mapping for the log files (README "Log layout").
    save : str or path, optional
        Write the result's JSON (``{"payload": {...}}``) there.
    urdf, mjcf : str or path, optional
        Write the model file with the payload as a fixed body on ``link`` (a URDF model for
        ``urdf``; an MJCF or URDF model for ``mjcf``), checked by MuJoCo's inverse dynamics
        (:mod:`baseparams.ident.payload.export`).
    predictions : str or path, optional
        With ``validate``: the torques predicted with the payload at every sample of that log
        (``t, tau_<joint>``; ``.csv`` or ``.tsv``).
    source : str or path, optional
        The model file, when ``model`` is a loaded Robot and an export needs the file.
    options : PayloadOptions, optional
        How (:class:`~baseparams.ident.payload.PayloadOptions`); its fields may also be given as
        keywords (``method="ls"``, ``prior={...}``, ``still=0.05``).
    progress : callable, optional
        Called with one line of text per step.
    **keywords
        :class:`~baseparams.ident.payload.PayloadOptions` fields.

    Returns
    -------
    Payload
        ``.mass``, ``.com``, ``.inertia_com`` (LINK's frame), ``.sigma()``, ``.identified()``,
        ``.to_json()``, ``.summary()``, ``.predict(log)``; its ``notes`` list what was written.

    Raises
    ------
    BaseparamsError
        Bad options, files or outputs (checked before the fit), an unknown link, a robot that is
        not a fixed-base tree, a result of another robot, a log in which nothing carrying the link
        moves, an export of a payload the motion does not identify.
    """
    from dataclasses import replace

    from .arguments import options_from
    from .ident.payload import PayloadOptions
    from .ident.payload import identify_payload as core
    from .workflow import input_files, robot_of

    opts = options_from(PayloadOptions, options, keywords)
    file = model if source is None else source
    if predictions is not None and validate is None:
        from .errors import BaseparamsError

        raise BaseparamsError("payload: predictions= are the torques of the validation log: give validate= (nothing "
                              "was fitted)")
    _check_outputs(file, save=save, urdf=urdf, mjcf=mjcf, predictions=predictions)
    robot = robot_of(model, "payload")
    inputs = input_files(file, log, result, validate, columns)
    _no_output_on_input(inputs, save=save, urdf=urdf, mjcf=mjcf, predictions=predictions)
    read = _log(log, robot, columns, "log")
    val = None if validate is None else _log(validate, robot, columns, "validate")
    res = _result(result, robot)
    out = core(robot, read, link, opts, result=res, validation=val, progress=progress)
    notes = _write(out, file, inputs, save=save, urdf=urdf, mjcf=mjcf)
    if predictions is not None:
        from .tables import write_columns

        tau = out.predict(val)
        write_columns(predictions, {"t": val.t, **{f"tau_{j}": tau[:, k] for k, j in
                                                   enumerate(robot.coordinate_names())}}, inputs, "predictions=")
        notes.append(f"predictions of {val.n_samples} validation samples written to {predictions}")
    return replace(out, notes=out.notes + tuple(notes)) if notes else out


def _check_outputs(model, **paths) -> None:
    """Each output's type and suffix, and what an export needs of the model, before any work."""
    from .arguments import check_path
    from .errors import BaseparamsError

    for name, value in paths.items():
        if value is None:
            continue
        check_path(value, f"payload: {name}=", optional=True)
        if Path(os.fspath(value)).suffix.lower() not in SUFFIXES[name]:
            raise BaseparamsError(f"payload: {name}= {os.fspath(value)}: expected a {' or '.join(SUFFIXES[name])} "
                                  f"file")
    src = Path(os.fspath(model)) if isinstance(model, (str, os.PathLike)) else None
    for name, kinds in (("urdf", (".urdf",)), ("mjcf", (".urdf", ".xml"))):
        if paths.get(name) is not None and (src is None or src.suffix.lower() not in kinds or not src.is_file()):
            raise BaseparamsError(f"payload: {name}= writes the model file with the payload: it needs a "
                                  f"{' or '.join(kinds)} model file, got {model if src else type(model).__name__} "
                                  f"(nothing was fitted)")


def _no_output_on_input(inputs: list, **paths) -> None:
    """No output onto an input, two outputs onto one file, an output in a missing folder (before any work)."""
    from .errors import BaseparamsError
    from .files import check_output

    seen = {}
    for name, path in paths.items():
        if path is None:
            continue
        key = Path(os.fspath(path)).resolve()
        if key in seen:
            raise BaseparamsError(f"payload: {name}= and {seen[key]}= name the same file {path}")
        seen[key] = name
        check_output(path, inputs, f"{name}=")


def _log(log, robot, columns, name: str):
    """A log as a JointLog: a JointLog (checked) or a log file read for the robot."""
    from .arguments import ArgumentTypeError
    from .jointlog import JointLog

    if isinstance(log, (str, os.PathLike)):
        from .io.logs import read_log

        return read_log(log, robot, columns=columns)
    if not isinstance(log, JointLog):
        raise ArgumentTypeError(f"payload: {name}= must be a JointLog or a log file's path, got {type(log).__name__}")
    return log.checked()


def _result(result, robot):
    """A saved identification: an Identification as given, or read from its file for the robot."""
    if result is None or not isinstance(result, (str, os.PathLike)):
        return result
    from .ident import Identification

    return Identification.load(result, robot)


def _write(payload, model, inputs: list, save=None, urdf=None, mjcf=None) -> list[str]:
    """The outputs asked for, each written atomically; a note per file."""
    notes = []
    if save is not None:
        import json

        from .files import write_text

        write_text(save, json.dumps(payload_document(payload), indent=1, allow_nan=False) + "\n", inputs, "save=")
        notes.append(f"result saved to {save}")
    if urdf is not None:
        from .ident.payload.export import payload_urdf

        notes += payload_urdf(payload, model, urdf, inputs)
    if mjcf is not None:
        from .ident.payload.export import payload_mjcf

        notes += payload_mjcf(payload, model, mjcf, inputs)
    return notes


def payload_document(payload) -> dict:
    """The JSON a saved payload holds: format, version, the robot's name and fingerprint, the options, the payload.

    Parameters
    ----------
    payload : Payload
        The result.

    Returns
    -------
    dict
        ``{"format": "baseparams-payload", "version": 1, "baseparams", "robot": {"name",
        "fingerprint"}, "options", "payload": {...}}`` (:meth:`Payload.to_json`'s ``payload``);
        non-finite numbers as None.
    """
    from .ident.saved import robot_fingerprint
    from .version import version

    robot = payload.model.robot
    doc = {"format": "baseparams-payload", "version": 1, "baseparams": version(),
           "robot": {"name": robot.name, "fingerprint": robot_fingerprint(robot)},
           "options": payload.options.to_json(), **payload.to_json()}
    return _plain(doc)


def _plain(x):
    """Numpy scalars and tuples as JSON types; non-finite floats as None."""
    import math

    import numpy as np

    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_plain(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x

