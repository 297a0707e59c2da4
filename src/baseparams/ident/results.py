"""Identification results going back in: the saved file, the robot fingerprint, states, the truth.

The saved file's format, the robot fingerprint, states of a log for prediction, the comparison
with a simulation's truth.

The file (:meth:`~baseparams.ident.Identification.save`) is one JSON object::

    {"format": "baseparams-identification", "version": 1, "baseparams": "0.1.0",
     "robot": {"name", "fingerprint", "bodies", "dof", "parameters", "joints"},
     "options": {"method", "convention", "rows", "rotor", "friction", "coulomb_width",
                 "couplings": [{"name", "joints", "weights"}], "cutoff", "decimate", "min_speed"},
     "parameters": {"names", "values", "std"},       # the model parameters theta (p,)
     "base_parameters": [...], "drives": [...], "couplings": [...],   # as in to_json (readable)
     "estimate": {...}, "physical": {...} or null, "samples", "train", "validation", "notes"}

Numbers are written with :func:`repr` precision (read back bit for bit); non-finite numbers as
``null``. The parameter values are what predicts torques; the rest says where they come from.

The fingerprint (:func:`robot_fingerprint`) is a SHA-256 over the robot's structure, not over a
file's bytes: body and joint names, parents, joint types and axes, the joint frames at q = 0,
gravity, loops, couplings and the independent coordinates, every number rounded to
:data:`FINGERPRINT_DIGITS` decimals (``-0`` written ``0``), and the number of inertial
parameters. Inertias, armature and limits are left out: identified values belong to the
structure (the regressor does not depend on the inertias), and a model re-exported with the
identified inertias keeps its fingerprint.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np

from ..arguments import ArgumentTypeError
from ..errors import BaseparamsError
from ..jointlog import JointLog
from ..model.robot import Robot

#: the ``format`` field of a saved identification
FORMAT = "baseparams-identification"
#: the newest version this library reads and writes
VERSION = 1
#: decimals the fingerprint rounds every number to (1e-9 m, 1e-9 rad)
FINGERPRINT_DIGITS = 9


def _round(x) -> list[str]:
    """Numbers as fixed-point strings at :data:`FINGERPRINT_DIGITS` decimals (``-0`` as ``0``)."""
    a = np.round(np.asarray(x, dtype=float).ravel(), FINGERPRINT_DIGITS) + 0.0
    return [f"{v:.{FINGERPRINT_DIGITS}f}" for v in a]


def robot_fingerprint(robot: Robot) -> str:
    """SHA-256 of a robot's structure (module docstring): what identified values belong to.

    Parameters
    ----------
    robot : Robot
        The robot.

    Returns
    -------
    str
        ``sha256:`` and 64 hexadecimal digits; equal for two loads of one model, different when
        a joint, an axis, a frame (beyond 1e-9), gravity or the body count differs.
    """
    parts = {
        "bodies": list(robot.names), "joints": list(robot.joint_names), "types": list(robot.jtype),
        "parent": [int(p) for p in robot.parent], "axes": [_round(a) for a in robot.axes],
        "frames": [_round(m[:3, :]) for m in robot.M0], "gravity": _round(robot.gravity),
        "loops": [[lp.name, lp.type, int(lp.parent), int(lp.child), _round(lp.M[:3, :]), _round(lp.axes)]
                  for lp in robot.loops],
        "couplings": [[c.name, int(c.pred), int(c.succ), *_round([c.ratio, c.offset]),
                       [[int(k), *_round([r])] for k, r in c.more]] for c in robot.couplings],
        "independent": None if robot.independent is None else [int(i) for i in robot.independent],
        "parameters": 10 * robot.n,
    }
    text = json.dumps(parts, sort_keys=True, separators=(",", ":"))
    return "sha256:" + hashlib.sha256(text.encode()).hexdigest()


def number(x) -> float | None:
    """A float for JSON: ``None`` where not finite (JSON has no inf or NaN).

    Parameters
    ----------
    x : float
        The number.

    Returns
    -------
    float or None
        ``float(x)``, or ``None``.
    """
    x = float(x)
    return x if np.isfinite(x) else None


def numbers(a) -> list:
    """An array as nested lists of :func:`number` (any shape).

    Parameters
    ----------
    a : array_like
        The array.

    Returns
    -------
    list
        Nested lists, ``None`` where not finite.
    """
    a = np.asarray(a, dtype=float)
    return number(a) if a.ndim == 0 else [numbers(x) for x in a]


def array(x) -> np.ndarray:
    """Nested lists of :func:`numbers` back to a float array (``None`` as NaN).

    Parameters
    ----------
    x : list
        Nested lists of numbers or ``None``.

    Returns
    -------
    ndarray
        The array.
    """
    return np.array(x, dtype=float) if x is not None else np.array(np.nan)


def read_document(path) -> dict:
    """A saved identification's JSON object, its format and version checked, then its schema.

    Parameters
    ----------
    path : str or path
        The file.

    Returns
    -------
    dict
        The object (:data:`FORMAT`, version 1), checked against :data:`baseparams.schema.RESULT`
        (types, shapes, finite values; statistics written ``null`` read as NaN); unknown top-level
        keys are kept and named in ``doc["_notes"]``.

    Raises
    ------
    BaseparamsError
        No such file, not a regular file, larger than
        :data:`~baseparams.schema.RESULT_MAX_BYTES`, not JSON (or nested too deep, NaN, 1e400, a
        huge integer), another format, a version other than :data:`VERSION`, or a value that does
        not fit the schema (one line naming the file and where: ``estimate.R11[3][5]``).
    """
    from .. import schema
    from ..arguments import check_path

    p = str(check_path(path, "path"))
    doc = schema.read_json(path, "a saved identification", schema.RESULT_MAX_BYTES)
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        got = doc.get("format") if isinstance(doc, dict) else type(doc).__name__
        raise BaseparamsError(f"{p}: not a saved identification (format {got!r:.80}, expected {FORMAT!r}; "
                              f"write one with 'identify --save' or Identification.save)")
    version = doc.get("version")
    if version != VERSION or isinstance(version, bool):
        newer = isinstance(version, int) and not isinstance(version, bool) and version > VERSION
        raise BaseparamsError(f"{p}: identification file version {version!r:.40}; this baseparams reads version "
                              f"{VERSION}" + (" (the file is newer: upgrade baseparams)" if newer else ""))
    doc, notes = schema.check(doc, schema.RESULT, p)
    doc["_notes"] = notes
    return doc


def check_robot(doc: dict, robot: Robot, source: str) -> None:
    """Refuse a robot whose fingerprint is not the saved one, or whose counts are not the saved ones.

    Parameters
    ----------
    doc : dict
        The saved object (:func:`read_document`).
    robot : Robot
        The robot it is to be used with.
    source : str
        The file, for messages.

    Raises
    ------
    TypeError
        ``robot`` is not a :class:`~baseparams.model.robot.Robot`.
    BaseparamsError
        One line naming both robots and both fingerprints, or the count that differs.
    """
    if not isinstance(robot, Robot):
        raise ArgumentTypeError(f"robot: expected a baseparams Robot (baseparams.load(...)), got "
                                f"{type(robot).__name__}")
    saved = doc.get("robot", {})
    mine = robot_fingerprint(robot)
    if saved.get("fingerprint") != mine:
        raise BaseparamsError(f"{source}: identified on robot {saved.get('name')!r:.200} ({saved.get('fingerprint')}), "
                              f"not this robot {robot.name!r} ({mine}): another structure (joints, axes, frames, "
                              f"gravity or bodies); use the model it was identified on")
    from ..numerics import row_mask, rows_spec

    rows = doc.get("options", {}).get("rows", "all")
    coords = robot.actuated if robot.has_loops else np.flatnonzero(row_mask(robot, rows_spec(rows)))
    joints = [robot.joint_names[robot.dof_body[c]] for c in coords]
    for key, mine_n in (("bodies", robot.n), ("dof", robot.dof), ("parameters", 10 * robot.n), ("joints", joints)):
        if saved.get(key) != mine_n:
            raise BaseparamsError(f"{source}: robot.{key}: {saved.get(key)} in the file, {mine_n} in robot "
                                  f"{robot.name!r} of the same fingerprint: the file was edited")


def log_states(log: JointLog, cutoff: float | None, filtered: bool = False) -> tuple[np.ndarray, ...]:
    """States at every sample of a log, for predicting its torques.

    What the log has is used as it is; what it lacks is derived the way identification derives
    it (:func:`baseparams.ident.preprocess.prepare`): on a uniform grid (the log's own when its
    time is uniform, else resampled at its median rate), positions low-passed with the zero-phase
    Butterworth filter of the identification's ``cutoff``, ``dq`` by central differences of the
    filtered ``q`` (``np.gradient``), ``ddq`` by central differences of ``dq`` (a measured ``dq``
    low-passed first); derived rates are interpolated back to the log's time stamps (linear).
    No sample is dropped: within ``2 fs / cutoff`` samples of either end the derived rates carry
    the filter's edge transient (odd extension).

    Parameters
    ----------
    log : JointLog
        The log, ``S`` samples (``tau`` may be ``None``).
    cutoff : float or None
        The low-pass cutoff [Hz] (the identification's); ``None``: the default of
        :func:`~baseparams.ident.preprocess.prepare` for this log.
    filtered : bool
        Low-pass the logged ``q``, ``dq`` and ``ddq`` too (identification's treatment of every
        signal) instead of using them as logged.

    Returns
    -------
    q, dq, ddq : ndarray, shape ``(S, m)``
        States at ``log.t``, columns in ``log.joints`` order.
    notes : tuple of str
        How each was obtained, one line each.

    Raises
    ------
    DataError
        Fewer than 3 samples, time not increasing, a cutoff not below the log's Nyquist rate.
    """
    from . import preprocess as pp

    t = np.asarray(log.t, dtype=float)
    if log.dq is not None and log.ddq is not None and not filtered:
        return log.q, log.dq, log.ddq, ("q, dq, ddq: as logged",)
    u = pp.resample(log)
    rate = (u.n_samples - 1) / float(u.t[-1] - u.t[0])
    if cutoff is None:
        cutoff = float(np.clip(pp.BANDWIDTH_FACTOR * pp.excitation_bandwidth(u.q, rate), pp.CUTOFF_FLOOR,
                               min(rate / pp.CUTOFF_DIVISOR, pp.CUTOFF_CAP)))
    design = pp.lowpass_design(rate, cutoff)
    same_grid = u.n_samples == len(t) and np.array_equal(u.t, t)

    def back(x):  # grid -> the log's time stamps
        if same_grid:
            return x
        return np.column_stack([np.interp(t, u.t, x[:, k]) for k in range(x.shape[1])])

    how = f"zero-phase Butterworth low-pass at {cutoff:.4g} Hz"
    grid = "" if same_grid else f" on a uniform {rate:.6g} Hz grid, interpolated back"
    qf = pp.zero_phase(u.q, design)
    q, qn = (back(qf), f"q: {how}{grid}") if filtered else (log.q, "q: as logged")
    if log.dq is not None:
        dqf = pp.zero_phase(u.dq, design)
        dq, dqn = (back(dqf), f"dq: logged, {how}{grid}") if filtered else (log.dq, "dq: as logged")
    else:
        dqf = np.gradient(qf, 1.0 / rate, axis=0, edge_order=2)
        dq, dqn = back(dqf), f"dq: derived, central differences of q after the {how}{grid}"
    if log.ddq is not None:
        ddq, ddqn = ((back(pp.zero_phase(u.ddq, design)), f"ddq: logged, {how}{grid}") if filtered
                     else (log.ddq, "ddq: as logged"))
    else:
        ddq = back(np.gradient(dqf, 1.0 / rate, axis=0, edge_order=2))
        ddqn = f"ddq: derived, central differences of dq{' (logged, low-passed)' if log.dq is not None else ''}{grid}"
    return np.asarray(q, float), np.asarray(dq, float), np.asarray(ddq, float), (qn, dqn, ddqn)


def lowpass_at(t, x, cutoff: float) -> np.ndarray:
    """Signals low-passed as identification filters them, at their own time stamps.

    Parameters
    ----------
    t : array_like, shape ``(S,)``
        Time stamps [s], strictly increasing.
    x : array_like, shape ``(S, k)``
        Signals (e.g. measured and predicted torques).
    cutoff : float
        The cutoff [Hz] (the identification's).

    Returns
    -------
    ndarray, shape ``(S, k)``
        Zero-phase Butterworth low-passed (:func:`~baseparams.ident.preprocess.zero_phase`) on a
        uniform grid at the median rate (the log's own when uniform), interpolated back.

    Raises
    ------
    DataError
        A cutoff not below the Nyquist rate, fewer than 2 samples.
    """
    from .preprocess import lowpass_design, resample, zero_phase

    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    u = resample(JointLog(t, tuple(str(k) for k in range(x.shape[1])), x, x))
    rate = (u.n_samples - 1) / float(u.t[-1] - u.t[0])
    f = zero_phase(u.q, lowpass_design(rate, cutoff))
    if u.n_samples == len(t) and np.array_equal(u.t, t):
        return f
    return np.column_stack([np.interp(t, u.t, f[:, k]) for k in range(f.shape[1])])


def compare_truth(names, values, std, truth: dict, source: str = "truth") -> dict:
    """An identification against the true parameters of a simulation.

    Parameters
    ----------
    names : list of str, shape ``(p,)``
        The identified model parameters' names.
    values, std : array_like, shape ``(p,)``
        Their estimates and standard deviations.
    truth : dict
        As :func:`~baseparams.ident.simulate.simulate_log` returns and ``baseparams simulate``
        writes to ``OUT.truth.json``: ``{"model", "convention", "parameters": [{"name", "value"}],
        ...}``.
    source : str
        The truth's file, for messages.

    Returns
    -------
    dict
        ``{"source", "terms": [{"name", "true", "estimate", "error", "std", "z"}], "max_abs_z",
        "rms_z", "rel_error"}``: ``error = estimate - true``, ``z = error / std`` (``None``
        where ``std`` is zero or not finite); ``rel_error = ||error|| / ||true||`` over all terms.

    Raises
    ------
    BaseparamsError
        A truth that does not fit :data:`baseparams.schema.TRUTH` (no ``parameters``, a value
        that is not a finite number, a name given twice), or naming parameters the model does not
        have (or lacking some it has): another ``--friction``/``--rotor``/``--convention``.
    """
    from .. import schema

    if not isinstance(source, str):
        raise ArgumentTypeError(f"compare_truth: source= must be a string (the truth's file), got "
                                f"{type(source).__name__}")
    truth, _ = schema.check(truth, schema.TRUTH, source)
    true = {e["name"]: e["value"] for e in truth["parameters"]}
    names = list(names)
    extra = [n for n in true if n not in names]
    missing = [n for n in names if n not in true]
    if extra or missing:
        what = ", ".join(f"{k} {v[:4]}" + (" ..." if len(v) > 4 else "")
                         for k, v in (("not identified:", extra), ("not in the truth:", missing)) if v)
        raise BaseparamsError(f"{source}: the truth's parameters are not the identified model's ({what}); "
                              f"identify with the simulation's --friction, --rotor and --convention")
    terms = []
    for n, v, s in zip(names, np.asarray(values, float), np.asarray(std, float)):
        err = float(v - true[n])
        z = err / s if np.isfinite(s) and s > 0 else None
        terms.append({"name": n, "true": true[n], "estimate": float(v), "error": err, "std": number(s), "z": z})
    zs = np.array([t["z"] for t in terms if t["z"] is not None])
    err = np.array([t["error"] for t in terms])
    ref = np.linalg.norm([t["true"] for t in terms])
    return {"source": source, "terms": terms, "max_abs_z": number(np.max(np.abs(zs))) if len(zs) else None,
            "rms_z": number(np.sqrt(np.mean(zs**2))) if len(zs) else None,
            "rel_error": number(np.linalg.norm(err) / ref) if ref > 0 else None}


def format_truth(cmp: dict) -> str:
    """The comparison with the truth as a text table.

    Parameters
    ----------
    cmp : dict
        :func:`compare_truth`'s result.

    Returns
    -------
    str
        A header line, then per term ``name, true, estimate, error, z``, then the largest and the
        RMS ``|z|``.
    """
    lines = [f"compared with {cmp['source']}: error = estimate - true, z = error / std",
             f"  {'parameter':<24s} {'true':>14s} {'estimate':>14s} {'error':>11s} {'z':>7s}"]
    for t in cmp["terms"]:
        z = "-" if t["z"] is None else f"{t['z']:.2f}"
        lines.append(f"  {t['name']:<24s} {t['true']:14.6g} {t['estimate']:14.6g} {t['error']:11.3g} {z:>7s}")
    mz = "-" if cmp["max_abs_z"] is None else f"{cmp['max_abs_z']:.2f}"
    rz = "-" if cmp["rms_z"] is None else f"{cmp['rms_z']:.2f}"
    rel = "-" if cmp["rel_error"] is None else f"{cmp['rel_error']:.3g}"
    lines.append(f"  largest |z| {mz}, RMS z {rz} (about 1 when the std are right); ||error|| / ||true|| {rel}")
    return "\n".join(lines)
