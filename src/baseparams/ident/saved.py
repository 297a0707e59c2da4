"""An identification's file: written, read back for its robot; the robot fingerprint; the truth.

The saved file's format (:func:`document`, :func:`save`, :func:`read`), the robot fingerprint, the
comparison with a simulation's truth (:func:`compare_truth`).

The file (:meth:`~baseparams.ident.Identification.save`) is one JSON object::

    {"format": "baseparams-identification", "version": 1, "baseparams": "0.1.0",
     "robot": {"name", "fingerprint", "bodies", "dof", "parameters", "joints"},
     "options": {"method", "rotor", "friction", "coulomb_width", "couplings": [{"name", "joints", "weights"}],
                 "holdout", "cutoff", "decimate", "min_speed", "prior_weight", "convention", "covariance",
                 "score_cutoff", "allow_units", "literal", "terms", "analysis_samples", "seed", "memory_mb",
                 "rows"},       # IdentOptions.to_json() (cutoff, decimate: as used) and the measured rows
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

from .. import schema
from ..arguments import ArgumentTypeError
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..schema import array
from .terms.registry import term_schema

#: the ``format`` field of a saved identification
FORMAT = "baseparams-identification"
#: the newest version this library reads and writes
VERSION = 1
#: decimals the fingerprint rounds every number to (1e-9 m, 1e-9 rad)
FINGERPRINT_DIGITS = 9
#: the schema of a saved identification (:func:`baseparams.schema.result`) with each model term's own
#: fields (:func:`~baseparams.ident.terms.registry.term_schema`): checked on :func:`save` and on :func:`read`
RESULT = schema.result(term_schema())


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


def read_document(path) -> dict:
    """A saved identification's JSON object, its format and version checked, then its schema.

    Parameters
    ----------
    path : str or path
        The file.

    Returns
    -------
    dict
        The object (:data:`FORMAT`, version 1), checked against :data:`RESULT` (types, shapes,
        finite values, each term's fields and bounds, its joints the robot's, no term twice;
        statistics written ``null`` read as NaN); unknown top-level keys are kept and named in
        ``doc["_notes"]``.

    Raises
    ------
    BaseparamsError
        No such file, not a regular file, larger than
        :data:`~baseparams.schema.RESULT_MAX_BYTES`, not JSON (or nested too deep, NaN, 1e400, a
        huge integer), another format, a version other than :data:`VERSION`, or a value that does
        not fit the schema (one line naming the file and where: ``estimate.R11[3][5]``).
    """
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
    doc, notes = schema.check(doc, RESULT, p)
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
    try:
        coords = robot.actuated if robot.has_loops else np.flatnonzero(row_mask(robot, rows_spec(rows)))
    except BaseparamsError as exc:
        raise type(exc)(f"{source}: options.rows: {exc}") from None
    joints = robot.coordinate_names(coords)
    for key, mine_n in (("bodies", robot.n), ("dof", robot.dof), ("parameters", 10 * robot.n), ("joints", joints)):
        if saved.get(key) != mine_n:
            raise BaseparamsError(f"{source}: robot.{key}: {saved.get(key)} in the file, {mine_n} in robot "
                                  f"{robot.name!r} of the same fingerprint: the file was edited")


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
        have (or lacking some it has): another ``--friction``/``--rotor``/``--convention``. Rotor inertia
        the truth lacks (``Ia_``, ``Iam_``: a simulation without it) is compared with 0.
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
    for n in [n for n in missing if n.startswith(("Ia_", "Iam_"))]:  # rotor inertia the data kept (rotor="auto")
        true[n] = 0.0  # a simulation without rotor inertia writes none: its true value is 0
    missing = [n for n in missing if n not in true]
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


def document(ident) -> dict:
    """The JSON object an identification's file holds (module docstring).

    Parameters
    ----------
    ident : Identification
        The result.

    Returns
    -------
    dict
        Format, version, the robot's name and fingerprint, the options, the model parameters'
        names, values and std, the readable tables, the estimate's statistics and triangular
        factor, the physical fit, counts and notes (JSON types only).
    """
    from dataclasses import fields

    from ..version import version

    r = ident.model.analysis.source_robot
    from .options import IdentOptions

    opts = {**(ident.options or IdentOptions()).to_json(), "rows": str(ident.model.analysis.rows)}
    est = ident.fit.estimate
    phys = ident.fit.physical
    body = ident.to_json()
    doc = {"format": FORMAT, "version": VERSION, "baseparams": version(),
           "robot": {"name": r.name, "fingerprint": robot_fingerprint(r), "bodies": r.n, "dof": r.dof,
                     "parameters": 10 * r.n, "joints": ident.joints},
           "options": opts,
           "parameters": {"names": list(ident.model.names), "values": numbers(ident.fit.theta),
                          "std": numbers(est.std)},
           "base_parameters": body["base_parameters"], "drives": body["drives"], "couplings": body["couplings"],
           "estimate": {f.name: (numbers(getattr(est, f.name)) if isinstance(getattr(est, f.name), np.ndarray)
                                 else getattr(est, f.name)) for f in fields(est) if f.name != "pct_sigma"},
           "physical": None if phys is None else {
               f.name: (numbers(getattr(phys, f.name)) if isinstance(getattr(phys, f.name), np.ndarray)
                        else list(getattr(phys, f.name)) if isinstance(getattr(phys, f.name), tuple)
                        else getattr(phys, f.name)) for f in fields(phys)},
           "samples": ident.samples, "train": ident.train, "validation": ident.validation, "notes": list(ident.notes),
           "terms": [t.to_json(ident.joints) for t in ident.fit.terms],
           "term_choices": [{"name": c.name, "kept": c.kept, "why": c.why, "cv_rms": c.cv_rms}
                            for c in ident.fit.term_choices],
           "motion": ident.motion}
    if ident.currents is not None:  # identified from motor currents: the gains, the anchor, the groups
        doc["currents"] = ident.currents.to_json()
    return plain(doc)


def save(ident, path, inputs=(), what: str = "output"):
    """Write an identification to its JSON file, atomically (:func:`baseparams.files.write_text`).

    Parameters
    ----------
    ident : Identification
        The result.
    path : str or path
        The file (``RESULT.json``).
    inputs : iterable of str or path
        The run's input files, which the output must not overwrite.
    what : str
        The output's role, for messages (``--save``).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    BaseparamsError
        An output onto an input, a missing folder, a non-regular target; a document that
        :func:`read` would refuse (checked against :data:`RESULT` first: nothing is written).
    """
    import json

    from ..files import write_text

    doc = document(ident)
    schema.check(doc, RESULT, f"{path} (not written)")
    return write_text(path, json.dumps(doc, indent=1, allow_nan=False) + "\n", inputs, what)


def read(path, robot: Robot) -> dict:
    """A saved identification read back for the robot it was identified on: the result's fields.

    The model is rebuilt from the saved options (analysis, drive model and regrouping, as
    :func:`~baseparams.ident.identify` built it) and its parameter names checked against the
    saved ones; the values, statistics, counts and notes are the saved ones.

    Parameters
    ----------
    path : str or path
        The file (:func:`save`).
    robot : Robot
        The model: its structure's fingerprint must be the saved one.

    Returns
    -------
    dict
        :class:`~baseparams.ident.result.Identification`'s fields (``fit``, ``samples``, ``train``,
        ``validation``, ``notes``, ``series`` None, ``options``, ``motion``).

    Raises
    ------
    BaseparamsError
        No such file, another format, another version, another robot (both fingerprints
        named), or a model whose rebuilt parameters differ from the saved ones.
    """
    from .fitting import Fit
    from .model import model_for
    from .options import IdentOptions

    doc = read_document(path)  # checked against RESULT: types, shapes, bounds, the terms' joints
    check_robot(doc, robot, str(path))
    try:
        opts = IdentOptions.from_json(doc["options"])
    except BaseparamsError as exc:
        raise type(exc)(f"{path}: options: {exc}") from None
    _check_terms_allowed(doc, opts, str(path))
    model = model_for(robot, opts, rows=doc["options"]["rows"])
    names = doc["parameters"]["names"]
    if list(model.names) != list(names):
        diff = next((f"{a} vs {b}" for a, b in zip(model.names, names) if a != b),
                    f"{len(model.names)} vs {len(names)} parameters")
        raise BaseparamsError(f"{path}: the model rebuilt for {robot.name!r} has other parameters than the "
                              f"saved ones ({diff}); saved by another baseparams version?")
    theta = array(doc["parameters"]["values"])
    terms, choices = _terms(doc, model, str(path))
    f = Fit(model, opts.method, theta, _estimate(doc["estimate"], theta), _physical(doc.get("physical")),
            terms=terms, term_choices=choices)
    out = {"fit": f, "samples": doc["samples"], "train": doc["train"], "validation": doc["validation"],
           "notes": (*doc["notes"], *doc["_notes"]), "series": None, "options": opts, "motion": doc.get("motion")}
    if doc.get("currents") is not None:
        from .gains import CurrentGains

        out["currents"] = CurrentGains.from_json(doc["currents"])
    return out


def _estimate(e: dict, theta: np.ndarray):
    """The saved least-squares estimate (its %sigma recomputed from its std)."""
    from .estimate import Estimate

    std = array(e["std"])
    with np.errstate(divide="ignore", invalid="ignore"):
        pct = 100 * std / np.abs(theta if e.get("cov") is not None else array(e["theta"]))
    extra = {k: e[k] for k in ("covariance",) if e.get(k) is not None}
    if e.get("cov") is not None:
        extra["cov"] = array(e["cov"])
    return Estimate(e["method"], array(e["theta"]), std, pct, array(e["weights"]), array(e["rms"]),
                    float(e["rms_total"]), float(e["condition_number"]), int(e["samples"]), array(e["R11"]),
                    array(e["r12"]), **extra)


def _physical(p: dict | None):
    """The saved physically consistent fit, or None."""
    if p is None:
        return None
    from .physical import PhysicalFit

    return PhysicalFit(**{k: (array(v) if isinstance(v, list) and k != "notes" else
                              tuple(v) if k == "notes" else v) for k, v in p.items()})


def _check_terms_allowed(doc: dict, opts, source: str) -> None:
    """Refuse kept terms that disagree with the options (``options.terms``) or the choices (``term_choices``).

    A term its own options did not try, or one the choices do not say was kept, or a kept one
    missing: an edited file.
    """
    from .terms.fit import CORE_TERMS, parse_terms

    candidates, _ = parse_terms(opts.terms)
    for k, t in enumerate(doc["terms"]):
        if t["name"] not in candidates:
            raise BaseparamsError(f"{source}: terms[{k}]: {t['name']!r} is not among the terms options.terms "
                                  f"tried ({opts.terms!r}): the file was edited")
    kept = [c["name"] for c in doc["term_choices"] if c["kept"] and c["name"] not in CORE_TERMS]  # rotor: the core's
    listed = [t["name"] for t in doc["terms"]]
    if sorted(kept) != sorted(listed):
        raise BaseparamsError(f"{source}: terms: {', '.join(listed) or 'none'} listed, but term_choices says "
                              f"{', '.join(kept) or 'none'} kept: the file was edited (a term left out or added "
                              f"would change the predictions)")


def _terms(doc: dict, model, source: str) -> tuple[tuple, tuple]:
    """The saved model terms (checked against :data:`RESULT`, loaded for ``model``) and every term tried."""
    from .terms.fit import Choice
    from .terms.registry import make_term

    terms = []
    for k, t in enumerate(doc["terms"]):
        term = make_term(t["name"], t["forced"])
        try:
            term.load(t, model.joints, model)
        except BaseparamsError as exc:
            raise type(exc)(f"{source}: terms[{k}]: {exc}") from None
        term.std = {k: v for k, v in t["std"].items() if v is not None}
        terms.append(term)
    choices = tuple(Choice(c["name"], bool(c["kept"]), str(c["why"]),
                           float("nan") if c.get("cv_rms") is None else float(c["cv_rms"]))
                    for c in doc.get("term_choices") or ())
    return tuple(terms), choices


def plain(x):
    """A document as JSON types: numpy scalars, arrays and tuples as numbers and lists; non-finite floats as ``None``.

    Parameters
    ----------
    x : object
        A dict, list, tuple, array or number (nested).

    Returns
    -------
    object
        The same with JSON types only (what ``json.dumps(..., allow_nan=False)`` writes).
    """
    if isinstance(x, dict):
        return {str(k): plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [plain(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    return x
