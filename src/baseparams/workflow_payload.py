"""The payload's front door: :func:`identify_payload` (``payload``) and :func:`excite_payload` (``excite --payload``).

A module of its own beside :mod:`baseparams.workflow` (the loop's front door, whose helpers it uses:
a half floor above it, below the CLI): the files are read and checked here (the model, the log, a saved
identification), every output is checked before the fit and written atomically, never onto an
input; the work is :mod:`baseparams.ident.payload`'s and :mod:`baseparams.excitation.payload`'s.
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


def excite_payload(model, link: str, *, period: float = 5.0, harmonics: int = 5, rate: float = 1000.0,
                   criterion: str = "logdet", position=None, velocity=None, acceleration=None, keepout=None,
                   margin: float = 0.0, starts: int = 4, grid: int = 200, seed: int = 0, max_iter: int = 150,
                   friction=("viscous", "coulomb", "offset"), rotor: str = "auto", payload_noise: float = 0.1,
                   nominal=None, repeats: int = 1, out=None, progress=None):
    """A short excitation that identifies a payload on ``link`` best: ``baseparams excite MODEL --payload LINK``.

    Only the joints that carry the link are designed (the others welded at q = 0); the criterion is
    taken on the payload's ten columns with the drive terms fitted with it as nuisance parameters
    (:mod:`baseparams.excitation.payload`), within the position, velocity and acceleration limits and
    the keep-outs (as :func:`baseparams.excite`). The design's notes carry the standard deviations it
    predicts.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot without the payload.
    link : str
        The payload's link.
    period : float
        The period [s] (default 5: a short motion).
    harmonics, rate, criterion, margin, starts, grid, seed, max_iter
        As :func:`baseparams.excite` (``criterion`` default ``logdet``: D_s-optimal on the
        payload's columns; ``cond``: the condition number of their information).
    position, velocity, acceleration, keepout : optional
        Limits and keep-outs, as :func:`baseparams.excite` (by joint name, or one per designed joint).
    friction : str or iterable of str
        The drive terms fitted with the payload (their columns are nuisance parameters).
    rotor : {"auto", "file", "fit"}
        Rotor inertia columns: ``fit``, or ``auto`` when the model file states no armature.
    payload_noise : float
        Torque noise [N m per sample] of the predicted standard deviations (``--payload-noise``).
    nominal : dict, optional
        The nominal payload of the predicted sigmas (``{"mass", "com", "inertia_com"}``).
    repeats : int
        Periods recorded, for the predicted sigmas.
    out : str or path, optional
        Also write the trajectory there (``.csv``/``.tsv``: ``t, q_, dq_, ddq_`` of the designed joints).
    progress : callable, optional
        Called with one line of text per start.

    Returns
    -------
    Excitation
        The trajectory of the joints that carry the link; ``notes`` end with the predicted
        standard deviations.

    Raises
    ------
    BaseparamsError
        Bad options, an unknown link, limits that leave no room, a design that does not excite the
        payload's columns.
    """
    from dataclasses import replace

    from .arguments import check_choice, check_keywords, check_path
    from .excitation import design_excitation
    from .excitation.limits import given_limits
    from .excitation.payload import design_model, payload_robot, predicted_sigmas, sigma_note
    from .ident.drives import friction_terms
    from .workflow import input_files, robot_of

    check_keywords("excite", period=period, harmonics=harmonics, rate=rate, margin=margin, starts=starts, grid=grid,
                   seed=seed, max_iter=max_iter, payload_noise=payload_noise)
    check_choice("excite", "criterion", criterion, ("cond", "logdet"))
    check_choice("excite", "rotor", rotor, ("auto", "file", "fit"))
    check_keywords("excite", robots=repeats)
    check_path(out, "excite: out=", optional=True)
    robot = robot_of(model, "excite")
    inputs = input_files(model)
    if out is not None:
        from .files import check_output

        check_output(out, inputs, "out=")
    small, body, notes = payload_robot(robot, link)
    dm = design_model(small, body, friction_terms(friction), rotor)
    lim = given_limits(small, None, position, velocity, None)
    result = design_excitation(dm, harmonics=harmonics, base_frequency=1.0 / period, rate=rate, criterion=criterion,
                               limits=lim, acceleration=acceleration, keepout=keepout, margin=margin, starts=starts,
                               seed=seed, grid=grid, max_iter=max_iter, progress=progress)
    s = predicted_sigmas(dm, result.q, result.dq, result.ddq, payload_noise, nominal, int(repeats))
    result = replace(result, notes=result.notes + tuple(notes) + (sigma_note(s, result.period, int(repeats)),))
    if out is not None:
        result.save(out, inputs, "out")
    return result
