"""The wording of a decision: one line for each thing the identification decided or assumed.

Notes about the model (drive terms regrouped, geometry taken at a right angle), a floating base's
assumptions, drive terms the log cannot separate or that came out negative, the model terms tried,
and the log's units (:func:`check_log_units`, which refuses when they look wrong).
"""

from __future__ import annotations

import numpy as np

from ..model.robot import Robot
from .fitting import Fit
from .model import IdentModel
from .select import fold_scope


def model_notes(model: IdentModel) -> list[str]:
    """One line per drive parameter regrouped into a base parameter.

    Parameters
    ----------
    model : IdentModel
        The model.

    Returns
    -------
    list of str
        ``regrouped: <expression>`` lines.
    """
    a = model.analysis
    practical = [] if a.practical is None else [a.practical.note(a.n_base).replace(
        "; the literal count: --literal", "; these directions are not fitted (identify --literal fits them)")]
    return practical + [f"regrouped: {e}" for e in model.regrouping.expressions() if " + " in e or " - " in e]


def floating_notes(robot: Robot) -> list[str]:
    """What a floating base's identification from a joint log assumes (one line), else nothing.

    Parameters
    ----------
    robot : Robot
        The model.

    Returns
    -------
    list of str
        Notes for the report.
    """
    if not robot.floating:
        return []
    return ["floating base: the base's motion is the log's pose and twist; the joint torques are modelled with no "
            "external force on any other link (a foot on the ground pushes: measured contact wrenches belong on the "
            "measured side, baseparams.kinematics.wrench_forces in Python), the base wrench is not measured"]


#: two drive columns of one joint whose cosine exceeds this cannot be told apart by the log
COLLINEAR_COS = 0.99


def drive_notes(f: Fit, acc) -> list[str]:
    """Drive terms to say something about: negative friction or rotor inertia, pairs the log cannot separate.

    A pair of one joint's drive terms whose columns on its rows have a cosine above
    :data:`COLLINEAR_COS` (Coulomb friction and offset of a joint that hardly reverses) is named,
    with how it was resolved: by the drive terms' weak prior (the default and physical
    estimates: the smallest values that fit) or not at all (plain least squares). Negative
    viscous or Coulomb friction or rotor inertia (only plain least squares can give them) is named.

    Parameters
    ----------
    f : Fit
        The fit.
    acc : RowAccumulator
        Its rows.

    Returns
    -------
    list of str
        Notes, one line each.
    """
    from .physical import NONNEGATIVE_KINDS

    model = f.model
    nb = len(model.analysis.base_names)
    kinds = model.drives.param_kinds
    plain = f.method in ("ols", "wls")
    drive = {k: kinds[i - nb] for k, i in enumerate(model.regrouping.independent) if i >= nb}
    notes = []
    negative = [f"{model.names[k]} = {f.theta[k]:.3g}" for k, kind in drive.items()
                if kind in NONNEGATIVE_KINDS and f.theta[k] < 0]
    if negative:
        notes.append(f"NEGATIVE drive terms ({', '.join(negative)}): friction and rotor inertia cannot be negative; "
                     f"plain least squares (--method {f.method}) fits what the log shows (a poorly excited joint or "
                     f"a model error); the default and physical estimates keep them >= 0")
    seen = set()
    cols = np.array(sorted(drive), dtype=int)
    col2 = acc.column_norms2()
    for row in range(acc.nrows):
        ks = [int(k) for k in cols if col2[row, k] > 0]  # the row's own drive terms
        gr = acc.row_gram(row, ks)
        g = {(a, b): gr[i, j] for i, a in enumerate(ks) for j, b in enumerate(ks)}
        for a_i, a in enumerate(ks):
            for b in ks[a_i + 1:]:
                cos = abs(g[a, b]) / np.sqrt(g[a, a] * g[b, b])
                if cos <= COLLINEAR_COS or (a, b) in seen:
                    continue
                seen.add((a, b))
                how = ("plain least squares: their separate values are not meaningful, only their sum on this motion"
                       if plain else f"resolved by the drive terms' weak prior: {model.names[a]} = {f.theta[a]:.3g}, "
                       f"{model.names[b]} = {f.theta[b]:.3g}")
                notes.append(f"{model.names[a]} and {model.names[b]} cannot be told apart by this log (their columns' "
                             f"cosine {cos:.4f}: the joint hardly reverses or hardly moves); {how}")
    return notes


def term_note(tf, joints: list[str], unit: str = "blocks") -> str:
    """One line: every model term tried, kept or rejected, with its cross-validated figure and values.

    Parameters
    ----------
    tf : TermsFit
        :func:`~baseparams.ident.terms.fit.select_terms`'s outcome.
    joints : list of str
        The measured joints.
    unit : {"blocks", "recordings"}
        The cross-validation's folds: blocks of one log, or whole recordings (several in one identification).

    Returns
    -------
    str
        The note.
    """
    kept = {t.name: t for t in tf.terms}
    parts = []
    for c in tf.choices:
        if c.kept:
            parts.append(f"{c.name} KEPT ({c.why}): {kept[c.name].describe(joints)}")
        else:
            parts.append(f"{c.name} rejected ({c.why})")
    return f"model terms ({fold_scope(unit)}, linear core alone {tf.cv_rms:.4g}): " + "; ".join(parts)


def rotor_note(choice) -> str:
    """One line: ``rotor="auto"``'s choice of the rotor inertia columns, with its cross-validated figures.

    Parameters
    ----------
    choice : Choice
        :func:`~baseparams.ident.terms.fit.select_columns`' outcome (or why it was not tried).

    Returns
    -------
    str
        The note.
    """
    if not choice.kept and choice.why.startswith("not tried"):
        return f"rotor inertia (rotor=auto): {choice.why}"
    verdict = "KEPT" if choice.kept else "rejected"
    return (f"rotor inertia (rotor=auto, {fold_scope('blocks')}, the model terms' rule): "
            f"{verdict} ({choice.why}); --rotor / --no-rotor force it")


#: why ``rotor="auto"`` leaves the rotor inertia out, by the kind of run that does not try it (one home: the
#: notes of a log streamed from its file, of several recordings in one identification and of a fleet)
ROTOR_NOT_TRIED = {
    "stream": "a log streamed from its file: the choice cross-validates the fitted rows, which a stream does not "
              "keep (--stream off reads the log whole and tries it)",
    "recordings": "several recordings in one identification (not implemented: the choice is made on one log's "
                  "blocks; identifying one recording alone shows its verdict)",
    "fleet": "a fleet of logs: one model for every log, so the per-file estimates, their spread and the pooled "
             "estimate have the same parameters (a choice per log would not)",
}


def rotor_not_tried(run: str) -> str:
    """One line: ``rotor="auto"`` left the rotor inertia out of this run's model without trying it.

    Parameters
    ----------
    run : {"stream", "recordings", "fleet"}
        The kind of run (:data:`ROTOR_NOT_TRIED`).

    Returns
    -------
    str
        The note: the model has no rotor inertia, why, and the flag that fits it.
    """
    return (f"rotor inertia (rotor=auto): not tried for {ROTOR_NOT_TRIED.get(run, run)}, so the model has none; "
            f"--rotor fits it, --no-rotor leaves it out without this note")


def check_log_units(model: IdentModel, log, cols, allow_units: bool) -> list[str]:
    """Units and plausibility of the log before any fit (:func:`~baseparams.ident.plausibility.check_units`).

    Parameters
    ----------
    model : IdentModel
        The model (its robot's own torques are the comparison).
    log : JointLog
        The (training) log.
    cols : ndarray of int, shape ``(state_columns,)``
        Log column of each state column.
    allow_units : bool
        Go on with a warning note instead of refusing.

    Returns
    -------
    list of str
        Notes for the report.

    Raises
    ------
    DataError
        Units that look wrong, unless ``allow_units``.
    """
    from ..errors import DataError, going_on
    from ..regressor.tp import generalized_forces
    from .plausibility import check_units

    robot = model.robot
    params = robot.parameters("paper")
    coords = robot.measured_coords
    revolute = np.array([robot.jtype[robot.dof_body[c]] == "R" or (model.log_base and 3 <= c < 6) for c in coords])

    def torques(q, dq, ddq):  # inverse dynamics, O(S n): no (S, dof, 10 n) regressor
        if robot.has_loops:  # actuated coordinates: the loops closed and projected by the regressor (small robots)
            from ..analysis import regressor

            return regressor(robot, q, dq, ddq) @ params
        if not model.log_base:
            return generalized_forces(robot, q, dq, ddq, params)
        from ..kinematics.floating import robot_states

        tau = generalized_forces(robot, *robot_states(robot, q, dq, ddq), params)
        tau[:, :6] = 0.0  # the base wrench is not measured (the log's zeros)
        return tau

    try:
        limits = None if robot.limits is None else np.asarray(robot.limits, dtype=float)[coords]
        return check_units(log, cols, torques, revolute, limits)
    except DataError as exc:
        if not allow_units:
            raise
        return [going_on("units", exc)]
