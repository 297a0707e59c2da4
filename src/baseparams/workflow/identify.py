"""``baseparams.identify`` and ``baseparams.predict``: one implementation each, also the commands'.

:func:`identify` takes one keyword per flag of ``baseparams identify``; :func:`plan_identify`
checks every one of them before the model loads (the options as one
:class:`~baseparams.ident.options.IdentOptions`, the inputs, every output), which the command
line's preflight calls too. The run then streams a large log from its file (:func:`stream_reason`)
or reads it whole, fits, and writes the outputs (:mod:`baseparams.workflow.outputs`). Messages
name options by their keywords; the command line names them by their flags.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, fields, replace

from ..arguments import IDENTIFY
from ..display import counted
from ..errors import BaseparamsError, ModelWarning
from ..model import Robot
from .inputs import input_files, log_of, robot_of
from .outputs import Outputs, check_exports, check_outputs, write_predictions, write_results

#: logs larger than this [MB] are streamed from their file by default (``stream="auto"``)
STREAM_MIN_MB = 64.0


def _warn(note: str) -> None:
    warnings.warn(note, ModelWarning, stacklevel=4)


@dataclass(frozen=True)
class Inputs:
    """What :func:`identify` reads besides the model, the log and the options (one field per flag).

    Parameters
    ----------
    validate : JointLog, str or path, optional
        Another log to validate on (exclusive with ``holdout``).
    columns : str, path or dict, optional
        A layout mapping for log files (TOML; docs/guides/log-layout.md).
    joints : str or sequence of str, optional
        Identify these joints only (``"A,B"``); every other joint is welded
        (:func:`baseparams.ident.subchain.subchain`).
    weld : dict or sequence of str, optional
        With ``joints``: where to weld others (``{"joint": value}`` or ``["JOINT=VALUE"]``, rad or m).
    stream : {"auto", "on", "off"}
        Stream a CSV/TSV/Parquet log from its file (``auto``: above :data:`STREAM_MIN_MB`).
    truth : dict, str or path, optional
        True parameters of a simulation (``simulate``'s ``OUT.truth.json``): compared per term
        (``result.truth``, the report's last section).
    """

    validate: object = None
    columns: object = None
    joints: object = None
    weld: object = None
    stream: str = "auto"
    truth: object = None

    def __repr__(self) -> str:
        given = [f"{f.name}={getattr(self, f.name)!r:.60}" for f in fields(self)
                 if getattr(self, f.name) is not None and getattr(self, f.name) != f.default]
        return f"Inputs({', '.join(given)})"


@dataclass(frozen=True)
class Reporter:
    """How a run was called and talks: progress lines, notes, and the model file a given Robot came from.

    Parameters
    ----------
    progress : callable, optional
        Called with one line of text per step.
    notes : callable, optional
        Called with each note about the data and the outputs (default: :class:`ModelWarning` warnings).
    source : str or path, optional
        The model file, when the model is a Robot loaded from it (the command line loads it with its
        flags) and an export writes a copy of the file.
    """

    progress: object = None
    notes: object = None
    source: object = None

    def __repr__(self) -> str:
        return f"<Reporter{' progress' if self.progress else ''}{' notes' if self.notes else ''}>"

    def say(self, line: str) -> None:
        """A progress line (nothing without ``progress``).

        Parameters
        ----------
        line : str
            The line.
        """
        if self.progress is not None:
            self.progress(line)

    def note(self, line: str) -> None:
        """A note (``notes``, else a :class:`ModelWarning`).

        Parameters
        ----------
        line : str
            The note.
        """
        (self.notes or _warn)(line)


def identify(model, log, *, validate=None, holdout: float | None = IDENTIFY["holdout"],
             method: str = IDENTIFY["method"], friction=IDENTIFY["friction"], rotor: bool | str = IDENTIFY["rotor"],
             coulomb_width: float | None = IDENTIFY["coulomb_width"], couplings=IDENTIFY["couplings"],
             cutoff: float | None = IDENTIFY["cutoff"], decimate: int | None = IDENTIFY["decimate"],
             min_speed: float | None = IDENTIFY["min_speed"], prior_weight: float | None = IDENTIFY["prior_weight"],
             convention: str = IDENTIFY["convention"], covariance: str = IDENTIFY["covariance"],
             score_cutoff: float | None = IDENTIFY["score_cutoff"], allow_units: bool = IDENTIFY["allow_units"],
             columns=None, joints=None, weld=None, analysis_samples: int | None = IDENTIFY["analysis_samples"],
             literal: bool = IDENTIFY["literal"], terms=IDENTIFY["terms"], stream: str = Inputs.stream, save=None,
             predictions=None, urdf=None, mjcf=None, html=None, plot=None, truth=None, seed: int = IDENTIFY["seed"],
             effort: str = IDENTIFY["effort"], gain_anchor: str | None = IDENTIFY["gain_anchor"], progress=None,
             _reporter: Reporter | None = None):
    """Identify base-parameter and drive values from a joint log: ``baseparams identify``.

    One keyword per flag of the command (the command calls this function). The identification's
    options become one :class:`~baseparams.ident.options.IdentOptions` (checked at once; their
    defaults are :data:`baseparams.arguments.IDENTIFY`'s); every keyword is checked before the
    model loads (:func:`plan_identify`); a large log is streamed from its file; every output is
    written atomically, never onto an input.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot the log was recorded on (a floating base's pose in the log; loops closed by the
        actuated joints; a file for ``urdf``/``mjcf``).
    log : JointLog, str or path, or a list of them
        The log (:func:`simulate`, or a file: CSV/TSV, NPZ, Parquet, a ROS 2 bag; docs/guides/log-layout.md);
        a list: several recordings of the robot in one identification, each read whole and one
        cross-validation block (validated on ``validate``; ``holdout`` refused).
    holdout, method, friction, rotor, coulomb_width, couplings, cutoff, decimate, min_speed, prior_weight, \
convention, covariance, score_cutoff, allow_units, analysis_samples, literal, terms, seed, effort, gain_anchor
        The identification's options (:class:`~baseparams.ident.options.IdentOptions`: the
        hold-out [s], the estimator, the drive model, the filter, the second validation score's
        cutoff [Hz], the analysis' random states and seed, the model terms; torques or motor
        currents with unknown gains, the gains' anchor ``JOINT=K``).
    validate, columns, joints, weld, stream, truth
        What is read besides the log (:class:`Inputs`).
    save, predictions, urdf, mjcf, html, plot
        What is written (:class:`~baseparams.workflow.outputs.Outputs`).
    progress : callable, optional
        Called with one line of text per step.
    _reporter : Reporter, optional
        The command line's notes and model file (private).

    Returns
    -------
    Identification
        Values, standard deviations, validation (``.predict(log)``, ``.save(path)``,
        ``.compare_truth(truth)``, ``.to_json()``), and ``truth`` when given.

    Raises
    ------
    BaseparamsError
        Bad data (a floating base without its pose), options or outputs, data that do not excite
        the model.
    """
    keywords = {"validate": validate, "holdout": holdout, "method": method, "friction": friction, "rotor": rotor,
                "coulomb_width": coulomb_width, "couplings": couplings, "cutoff": cutoff, "decimate": decimate,
                "min_speed": min_speed, "prior_weight": prior_weight, "convention": convention,
                "covariance": covariance, "score_cutoff": score_cutoff, "allow_units": allow_units,
                "columns": columns, "joints": joints, "weld": weld, "analysis_samples": analysis_samples,
                "literal": literal, "terms": terms, "stream": stream, "save": save, "predictions": predictions,
                "urdf": urdf, "mjcf": mjcf, "html": html, "plot": plot, "truth": truth, "seed": seed,
                "effort": effort, "gain_anchor": gain_anchor}
    reporter = _reporter or Reporter()
    run = plan_identify(model, log, keywords, reporter if progress is None else replace(reporter, progress=progress))
    robot = robot_of(model, "identify")
    if run.outputs.mjcf is not None:  # what the writer refuses, refused before the fit (the robot says it)
        from ..io.mjcf_write import check_mjcf_robot

        check_mjcf_robot(robot, run.source)
    result, read = _run_identification(robot, log, run)
    write_results(result, read, run.source, run.outputs, run.files, run.reporter)
    if run.truth is not None:
        truth = run.inputs.truth
        result = replace(result, truth=result.compare_truth(run.truth, "truth" if isinstance(truth, dict) else
                                                            os.fspath(truth)))
    return result


@dataclass(frozen=True)
class Run:
    """One identify run, checked (:func:`plan_identify`).

    Parameters
    ----------
    options : IdentOptions
        How to identify.
    inputs : Inputs
        What else is read.
    outputs : Outputs
        What is written.
    files : list of str
        The run's input files (no output may overwrite one).
    source : str, path or None
        The model file (the exports write a copy of it).
    truth : dict or None
        The true parameters read (``truth=``).
    reporter : Reporter
        Progress lines and notes.
    """

    options: object
    inputs: Inputs
    outputs: Outputs
    files: list
    source: object
    truth: object
    reporter: Reporter

    def __repr__(self) -> str:
        return f"<Run {self.options!r} {self.inputs!r} {self.outputs!r}, {len(self.files)} input files>"


def plan_identify(model, log, keywords: dict, reporter: Reporter | None = None) -> Run:
    """Every rule of :func:`identify`'s keywords checked before the model loads (both doors call it).

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The model as given.
    log : JointLog, str or path, or a list of them
        The log as given (a list: several recordings).
    keywords : dict
        :func:`identify`'s keywords (those missing take their defaults).
    reporter : Reporter, optional
        Progress, notes, the model file (default: silent, warnings).

    Returns
    -------
    Run
        The options, inputs and outputs, checked; the input files; the truth read.

    Raises
    ------
    BaseparamsError
        The first keyword refused, in one line naming it: an option
        (:class:`~baseparams.ident.options.IdentOptions`), an input of the wrong type, an output
        (suffix, folder, an input, two outputs onto one file), an export that cannot be honoured,
        validation outputs without validation data.
    """
    from ..arguments import ArgumentTypeError, check_choice, check_keywords, check_progress
    from ..ident.options import IdentOptions

    names = {f.name: cls for cls in (IdentOptions, Inputs, Outputs) for f in fields(cls)}
    unknown = sorted(set(keywords) - set(names))
    if unknown:
        raise ArgumentTypeError(f"identify: unknown keyword(s) {unknown}")
    check_keywords("identify", min_speed=keywords.get("min_speed"))  # one speed, as the flag
    options, inputs, outputs = (cls(**{k: v for k, v in keywords.items() if names[k] is cls})
                                for cls in (IdentOptions, Inputs, Outputs))
    reporter = reporter or Reporter()
    check_progress(reporter.progress, "identify")
    check_choice("identify", "stream", inputs.stream, ("auto", "on", "off"))
    if inputs.columns is not None and not isinstance(inputs.columns, (str, os.PathLike, dict)):
        raise ArgumentTypeError(f"identify: columns= must be a TOML file, a dict or a topic, got "
                                f"{type(inputs.columns).__name__}")
    _check_subchain(inputs)
    source = reporter.source if reporter.source is not None else \
        (model if isinstance(model, (str, os.PathLike)) else None)
    logs = _recordings(log, options.holdout, inputs.stream)
    files = input_files(source if source is not None else model, *logs, inputs.validate, inputs.columns, inputs.truth)
    check_outputs("identify", files, **outputs.given())
    if options.holdout is not None and inputs.validate is not None:
        raise BaseparamsError("identify: give holdout= SECONDS or validate= LOG, not both")
    if (outputs.predictions is not None or options.score_cutoff is not None) and options.holdout is None \
            and inputs.validate is None:
        raise BaseparamsError("identify: predictions= and score_cutoff= are about validation data: give holdout= "
                              "SECONDS or validate= FILE (nothing was fitted)")
    check_exports("identify", source, options.method, outputs.urdf, outputs.mjcf, inputs.joints)
    truth = inputs.truth
    if truth is not None and not isinstance(truth, dict):
        from ..schema import read_truth

        truth = read_truth(truth, f"truth= {truth}")
    return Run(options, inputs, outputs, files, source, truth, reporter)


def _recordings(log, holdout, stream: str) -> list:
    """``log`` as a list of recordings (one, or several); several refuse a hold-out, streaming, none given."""
    if not isinstance(log, (list, tuple)):
        return [log]
    if not log:
        raise BaseparamsError("identify: no log given (one log, or a list of recordings)")
    if len(log) > 1 and holdout is not None:
        raise BaseparamsError("identify: holdout= with several recordings: whose end would it be? Validate on "
                              "another recording (validate=), or fit them all (each is a cross-validation block)")
    if len(log) > 1 and stream == "on":
        raise BaseparamsError("identify: stream=on with several recordings: they are read whole (stream=auto)")
    return list(log)


def _check_subchain(inputs: Inputs) -> None:
    """``joints`` and ``weld``: their types, joint names given, ``weld`` only with ``joints``."""
    from ..arguments import ArgumentTypeError, brief

    joints, weld = inputs.joints, inputs.weld
    weld_ok = weld is None or isinstance(weld, dict) or (isinstance(weld, (list, tuple))
                                                          and all(isinstance(w, str) for w in weld))
    if not weld_ok:
        raise ArgumentTypeError(f"identify: weld= must be {{'JOINT': value}} or ['JOINT=VALUE', ...], got "
                                f"{brief(weld)}")
    names_ok = isinstance(joints, (list, tuple)) and all(isinstance(j, str) for j in joints)
    if joints is not None and not isinstance(joints, str) and not names_ok:
        raise ArgumentTypeError(f"identify: joints= must be 'A,B' or a sequence of joint names, got {brief(joints)}")
    if joints is not None and not joint_names(joints):
        raise BaseparamsError("identify: joints= needs joint names: 'A,B,...' (the joints to identify)")
    if weld and joints is None:
        raise BaseparamsError("identify: weld= applies with joints= (the joints to identify; the others are welded)")
    welds(weld)


def welds(weld) -> dict[str, float]:
    """``weld=`` as ``{joint: value}``: ``{"joint": value}`` or ``["JOINT=VALUE", ...]``, each a finite number.

    Parameters
    ----------
    weld : dict, sequence of str or None
        The welds.

    Returns
    -------
    dict of str to float
        Joint name -> value [rad or m].

    Raises
    ------
    BaseparamsError
        An item that is not ``NAME=VALUE``, a value that is not a number within 1e6.
    """
    from ..ident.subchain import parse_welds

    if not isinstance(weld, dict):
        return parse_welds(list(weld or ()))
    return parse_welds([f"{k}={v}" if isinstance(v, (int, float)) and not isinstance(v, bool) else f"{k}=?"
                        for k, v in weld.items()])


def joint_names(joints) -> list[str]:
    """``joints=`` as a list of names (``"A,B"`` or a sequence).

    Parameters
    ----------
    joints : str or sequence of str
        The joints.

    Returns
    -------
    list of str
        The names, blanks left out.
    """
    return [j.strip() for j in joints.split(",") if j.strip()] if isinstance(joints, str) else list(joints)


def _identification_logs(robot: Robot, log, inputs: Inputs, note, allow_units: bool = False):
    """``(log, validation log or None, robot)``: the logs read, restricted to a sub-chain's ``joints``."""
    validate, columns, joints, weld = inputs.validate, inputs.columns, inputs.joints, inputs.weld
    val = None if validate is None else log_of(validate, robot, columns, subset=joints is not None, name="validate",
                                               allow_units=allow_units)
    log = log_of(log, robot, columns, subset=joints is not None, allow_units=allow_units)
    if joints is None:
        return log, val, robot
    from ..ident.subchain import subchain

    small, log, notes = subchain(robot, log, joint_names(joints), welds(weld))
    if val is not None:
        val = subchain(robot, val, joint_names(joints), welds(weld))[1]
    for n in notes:
        note(n)
    return log, val, small


def stream_reason(log, inputs: Inputs, mjcf) -> str | None:
    """Why the log is streamed from its file (a progress line), or None: read it whole.

    Parameters
    ----------
    log : JointLog, str or path
        The log as given (only a file is streamed).
    inputs : Inputs
        ``stream``, ``validate`` and ``joints``.
    mjcf : object
        The MJCF output, if any (it checks the model on the log's states: read whole).

    Returns
    -------
    str or None
        The reason, or None.

    Raises
    ------
    BaseparamsError
        ``stream="on"`` for a log that cannot be streamed.
    """
    from ..io.logs import STREAM_SUFFIXES, streamable

    validate, joints, stream = inputs.validate, inputs.joints, inputs.stream
    if stream == "off" or not isinstance(log, (str, os.PathLike)):
        return None
    log = os.fspath(log)
    ok = streamable(log) and (validate is None or (isinstance(validate, (str, os.PathLike)) and streamable(validate)))
    if stream == "on":
        if not ok:
            raise BaseparamsError(f"identify: stream=on: only {', '.join(STREAM_SUFFIXES)} logs are streamed, not "
                                  f"{log}" + (f" / {validate}" if validate is not None else ""))
        if joints is not None or mjcf is not None:
            raise BaseparamsError(f"identify: stream=on with {'joints' if joints is not None else 'mjcf'}=: the log is "
                                  f"read whole for it (stream=auto)")
        return "stream=on"
    if not ok or joints is not None or mjcf is not None:  # mjcf checks the model on the log's states
        return None
    from ..io.logs import decoded_mb

    size = decoded_mb(log)  # a compressed Parquet file by the numbers it holds
    return f"{size:.0f} MB > {STREAM_MIN_MB:g} MB" if size > STREAM_MIN_MB else None


def _run_identification(robot: Robot, log, run: Run):
    """The fit: streamed from the log's file, or read whole; predictions written. ``(result, log read or None)``."""
    rep, options, inputs = run.reporter, run.options, run.inputs
    if isinstance(log, (list, tuple)):
        if len(log) > 1:
            return _run_several(robot, log, run)
        log = log[0]
    why = stream_reason(log, inputs, run.outputs.mjcf) if not robot.floating else None
    if why is not None:
        from ..ident.stream import NotStreamable

        try:
            return _streamed(robot, log, run, why), None
        except NotStreamable as exc:  # read whole: said as a note when streaming was asked for (stream=on)
            (rep.note if inputs.stream == "on" else rep.say)(f"stream={inputs.stream}: {exc}")
    from ..ident import identify as run_whole

    rep.say(f"reading {log}" if isinstance(log, (str, os.PathLike)) else "checking the log")
    read, val, robot = _identification_logs(robot, log, inputs, rep.note, options.allow_units)
    rep.say(f"identifying ({options.method}) on {read.n_samples} samples")
    result = run_whole(robot, read, options, validation=val, progress=rep.progress)
    if run.outputs.predictions is not None:
        write_predictions(result, (read, val), options.holdout, run.outputs.predictions, run.files, rep.note)
    return result, read


def _run_several(robot: Robot, logs, run: Run):
    """Several recordings in one identification, each read whole (:func:`baseparams.ident.identify` of a list)."""
    from ..ident import identify as run_whole

    rep, options, reads, val, small = run.reporter, run.options, [], None, robot
    for k, x in enumerate(logs):
        rep.say(f"reading {x}" if isinstance(x, (str, os.PathLike)) else f"checking recording {k + 1}")
        read, v, small = _identification_logs(robot, x, run.inputs if k == 0 else replace(run.inputs, validate=None),
                                              rep.note, options.allow_units)
        reads.append(read)
        val = v if k == 0 else val
    rep.say(f"identifying ({options.method}) on {len(reads)} recordings, {sum(r.n_samples for r in reads)} samples")
    result = run_whole(small, reads, options, validation=val, progress=rep.progress)
    if run.outputs.predictions is not None:
        write_predictions(result, (reads[0], val), options.holdout, run.outputs.predictions, run.files, rep.note)
    return result, reads[0]


def _streamed(robot: Robot, log, run: Run, why: str):
    """The identification streamed from the log's file; the predictions written as they come."""
    from ..ident.stream import check_effort, identify_stream
    from ..io.logs import LogStream

    rep, inputs, predictions = run.reporter, run.inputs, run.outputs.predictions
    units = run.options.allow_units
    src = LogStream(log, robot, columns=inputs.columns, allow_units=units)
    check_effort(src, run.options.effort, run.options.gain_anchor)  # motor currents: read whole
    rep.say(f"streaming {log} block by block ({why}): memory independent of the log's length")
    other = (LogStream(inputs.validate, robot, columns=inputs.columns, allow_units=units)
             if inputs.validate is not None else None)
    if predictions is None:
        return identify_stream(robot, src, run.options, validation=other, progress=rep.progress)
    import numpy as np

    from ..tables import column_writer

    names = ["t", *(f"tau_{j}" for j in robot.coordinate_names())]
    with column_writer(predictions, names, run.files, "predictions=") as write:
        result = identify_stream(robot, src, run.options, validation=other, progress=rep.progress,
                                 predictions=lambda t, tau: write(np.column_stack([t, tau])))
    rep.note(f"predictions of {result.validation['samples']} validation samples written to {predictions}")
    return result


def identify_logs(robot: Robot, files: list[str], keywords: dict, *, per_file: bool = True, pooled: bool = False,
                  scheduler: str | None = None, workers: int | None = None, progress=None):
    """Identify over several logs on Dask (``baseparams identify 'logs/*.csv' --per-file / --pooled``).

    Parameters
    ----------
    robot : Robot
        The robot the logs were recorded on (one robot each, or one kind).
    files : list of str
        The log files.
    keywords : dict
        :func:`identify`'s keywords: the options, and no other (a fleet has no validation log,
        hold-out, sub-chain, mapping or export).
    per_file, pooled : bool
        One estimate per log and the spread across them; one estimate from all logs.
    scheduler : str, optional
        A Dask scheduler's address (default ``DASK_SCHEDULER_ADDRESS``, else a local cluster).
    workers : int, optional
        A local cluster's size.
    progress : callable, optional
        Called with one line per finished log.

    Returns
    -------
    FleetResult
        The estimates (:class:`baseparams.fleet.FleetResult`); ``.model`` the identification model.

    Raises
    ------
    BaseparamsError
        A keyword that applies to one log only, bad options.
    """
    from ..fleet import identify_fleet
    from ..ident.model import model_for

    options = check_fleet(keywords)
    return identify_fleet(model_for(robot, options), files, options, per_file=per_file, pooled=pooled,
                          scheduler=scheduler, workers=workers, progress=progress)


#: identify's keywords that apply to one log, not to a fleet of logs
ONE_LOG = ("validate", "holdout", "joints", "weld", "columns", "save", "truth", "predictions", "urdf", "mjcf", "html",
           "plot", "gain_anchor")


def check_fleet(keywords: dict):
    """The options of an identification over several logs; a keyword that applies to one log refused.

    Parameters
    ----------
    keywords : dict
        :func:`identify`'s keywords.

    Returns
    -------
    IdentOptions
        The options, checked.

    Raises
    ------
    BaseparamsError
        A keyword of :data:`ONE_LOG` given, ``effort="current"`` (motor currents are identified one
        log at a time), or bad options.
    """
    from ..ident.options import IdentOptions

    given = [k for k in ONE_LOG if keywords.get(k) not in (None, (), [])]
    given += ["effort"] if keywords.get("effort") == "current" else []  # motor currents: one log at a time
    if given:
        raise BaseparamsError(f"identify: {given[0]}= applies to one log, not to a fleet of logs (per-file or pooled "
                              f"estimates)")
    names = {f.name for f in fields(IdentOptions)}
    return IdentOptions(**{k: v for k, v in keywords.items() if k in names})


def predict(model, result, log, *, raw_states: bool = False, columns=None, allow_units: bool = False, out=None):
    """Joint torques of a log from an identification: ``baseparams predict``.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot the result belongs to (its structure's fingerprint is checked).
    result : Identification, str or path
        The identification, or its saved file (``identify(..., save=...)``, ``--save``).
    log : JointLog, str or path
        The log or trajectory (``tau`` columns optional), e.g. an ``excite`` trajectory file.
    raw_states : bool
        The logged states as they are (default: low-passed at the identification's cutoff).
    columns : str, path or dict, optional
        A layout mapping for a log file.
    allow_units : bool
        Go on when the log's states look in other units (degrees, deg/s, rpm, ms, us, ns), which
        otherwise refuses (:func:`baseparams.ident.plausibility.check_states`).
    out : str or path, optional
        Also write ``t, tau_<joint>`` per log sample there (CSV, TSV or Parquet by the suffix;
        checked before the work, written atomically, never onto an input); a result from motor
        currents: also ``cur_<joint>``, the predicted currents [A].

    Returns
    -------
    ndarray, shape ``(S, m)``
        Predicted torques [N m or N] at every log sample; columns the measured joints
        (``Identification.joints``). A result from motor currents: the joint-side torques (a
        joint-torque sensor after the gear; no motor-side friction or rotor inertia).

    Raises
    ------
    BaseparamsError
        Another robot than the result's, a bad result file or log, an output that cannot be written.
    """
    return prediction(model, result, log, raw_states=raw_states, columns=columns, allow_units=allow_units,
                      out=out).tau


@dataclass(frozen=True)
class Prediction:
    """The torques of a log predicted by an identification (:func:`prediction`).

    Parameters
    ----------
    result : Identification
        The identification.
    log : JointLog
        The log, as read.
    tau : ndarray, shape ``(S, m)``
        Predicted torques [N m or N] per log sample, columns ``result.joints``; a result from
        motor currents: the joint-side torques (what a joint-torque sensor after the gear reads).
    raw_states : bool
        Predicted on the states as logged (not low-passed).
    cur : ndarray, shape ``(S, m)``, optional
        A result from motor currents: the predicted currents [A] per log sample, columns its
        motors (``result.currents.motors``); None for a result from torques.
    """

    result: object
    log: object
    tau: object
    raw_states: bool = False
    cur: object = None

    def __repr__(self) -> str:
        return (f"<Prediction of {counted(len(self.result.joints), 'joint')} at {counted(self.log.n_samples, 'sample')}"
                f"{' (raw states)' if self.raw_states else ''}>")

    def scores(self, score_cutoff: float | None = None) -> dict | None:
        """The RMS against the log's measured torques (None without them).

        Predicted and measured torques are both low-passed with the identification's zero-phase
        filter (what identify's train and validation RMS compare; ``rms``); away from the log's
        ends the filter's edge transient is left out (``rms_interior``, ``edge_samples``).

        Parameters
        ----------
        score_cutoff : float, optional
            Also score against the measured torques low-passed at this cutoff [Hz].

        Returns
        -------
        dict or None
            ``rms`` ``{"total", joint: value}``, and ``rms_interior``/``edge_samples``,
            ``score_cutoff``/``rms_lowpassed`` when they apply. A result from motor currents
            (:meth:`current_scores`) also ``torque`` (what its torques are) and ``rms_currents``
            [A], and is never None.
        """
        out = self._torque_scores(score_cutoff)
        return out if self.cur is None else {**(out or {"rms": None}), **self.current_scores()}

    def current_scores(self) -> dict:
        """A result from motor currents: what its torques are, and the RMS of its currents [A].

        Returns
        -------
        dict
            ``torque`` (the joint-side torque a sensor after the gear reads: the rigid body, no
            motor-side friction or rotor inertia) and ``rms_currents`` ``{"total", motor: value}``
            against the log's currents at every sample (None when the log has none, or for a
            result from torques: then ``{}``).
        """
        if self.cur is None:
            return {}
        out = {"torque": "joint side: the rigid body a joint-torque sensor after the gear reads (no motor-side "
                         "friction or rotor inertia)", "rms_currents": None}
        if self.log.cur is not None:
            from ..ident import validation_scores

            motors = list(self.result.currents.motors)
            s = validation_scores(replace(self.log, tau=self.log.cur), self.cur, motors)
            out["rms_currents"] = {"total": s["rms_total"], **s["rms"]}
        return out

    def _torque_scores(self, score_cutoff: float | None) -> dict | None:
        """:meth:`scores` against the log's measured torques (None without them)."""
        import numpy as np

        from ..ident import validation_scores

        log, joints, tau = self.log, self.result.joints, self.tau
        if log.tau is None:
            return None
        s = validation_scores(log, tau, joints, score_cutoff=score_cutoff)
        out = {"rms": {"total": s["rms_total"], **s["rms"]}}
        options = self.result.options
        edge = _edge_samples(log, None if options is None else options.cutoff)
        if log.n_samples > 2 * edge + 1 and not self.raw_states:
            inner = np.zeros(log.n_samples, dtype=bool)
            inner[edge:log.n_samples - edge] = True
            si = validation_scores(log, tau, joints, inner)
            out["rms_interior"] = {"total": si["rms_total"], **si["rms"]}
            out["edge_samples"] = edge
        if "score_cutoff" in s:
            out["score_cutoff"] = s["score_cutoff"]
            out["rms_lowpassed"] = {"total": s["rms_lowpassed_total"], **s["rms_lowpassed"]}
        return out


def _edge_samples(log, cutoff) -> int:
    """Samples at each end of a log that carry the smoothing filter's edge transient (2 cutoff periods)."""
    import numpy as np

    if not cutoff or log.n_samples < 3:
        return 0
    rate = (log.n_samples - 1) / float(log.t[-1] - log.t[0])
    return int(np.ceil(2.0 * rate / float(cutoff)))


def check_predict(model, result, log, keywords: dict) -> list[str]:
    """Every rule of :func:`predict`'s keywords that needs no model: types, the output.

    Parameters
    ----------
    model, result, log : object
        As given (their files are inputs, never overwritten).
    keywords : dict
        :func:`predict`'s keywords.

    Returns
    -------
    list of str
        The run's input files.

    Raises
    ------
    BaseparamsError
        The first keyword refused, in one line naming it.
    """
    from ..arguments import ArgumentTypeError, check_flags

    check_flags("predict", **{k: keywords[k] for k in ("raw_states", "allow_units") if k in keywords})
    if not isinstance(result, (str, os.PathLike)) and type(result).__name__ != "Identification":
        raise ArgumentTypeError(f"predict: result must be an Identification or its saved file, got "
                                f"{type(result).__name__}")
    columns = keywords.get("columns")
    inputs = input_files(model, result, log, columns if isinstance(columns, (str, os.PathLike)) else None)
    check_outputs("predict", inputs, out=keywords.get("out"))
    return inputs


def prediction(model, result, log, *, raw_states: bool = False, columns=None, allow_units: bool = False, out=None,
               reporter: Reporter | None = None) -> Prediction:
    """:func:`predict`, with the log as read (for scores): what ``baseparams predict`` runs.

    Parameters
    ----------
    model, result, log, raw_states, columns, allow_units, out
        As :func:`predict`.
    reporter : Reporter, optional
        Notes (default: :class:`ModelWarning` warnings) and the model file of a given Robot.

    Returns
    -------
    Prediction
        The result, the log and the predicted torques.

    Raises
    ------
    BaseparamsError
        As :func:`predict`.
    """
    reporter = reporter or Reporter()
    inputs = check_predict(model if reporter.source is None else reporter.source, result, log,
                           {"raw_states": raw_states, "allow_units": allow_units, "columns": columns, "out": out})
    robot = robot_of(model, "predict")
    if isinstance(result, (str, os.PathLike)):
        from ..ident import Identification

        result = Identification.load(result, robot)
    from ..ident.plausibility import check_prediction_log

    log = log_of(log, robot, columns, require_tau=False, allow_units=allow_units)
    for n in check_prediction_log(result.model, log, allow_units):  # the states' units (no torque needed)
        if "WARNING" in n:
            reporter.note(n)
    tau = result.predict(log, smooth=not raw_states)
    cur = None if result.currents is None else result.predict_currents(log, smooth=not raw_states)
    if out is not None:
        from ..tables import write_columns

        cols = {"t": log.t, **{f"tau_{j}": tau[:, k] for k, j in enumerate(result.joints)}}
        if cur is not None:  # a result from currents: the motors' currents beside the joint-side torques
            cols.update({f"cur_{m}": cur[:, k] for k, m in enumerate(result.currents.motors)})
        write_columns(out, cols, inputs, "out=")
    return Prediction(result, log, tau, raw_states, cur)
