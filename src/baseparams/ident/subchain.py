"""Identify part of a robot: the listed joints, every other joint welded.

``identify MODEL LOG --joints A,B,...`` (``joints=``) identifies the listed joints' model. Every other
1-dof joint becomes rigid (:func:`baseparams.model.weld.weld`):

* at ``weld=`` ``NAME=VALUE`` (``--weld``) when given: a joint the log shows moving (a range above
  :data:`STILL`) is refused, naming how far it moved; one the log shows still elsewhere is welded
  where asked, with a note saying how far that is from its logged position;
* else, when the log has the joint, at the median of its logged position, provided it does not
  move (a range above :data:`STILL` is refused: a moving joint cannot be welded, list it);
* else at 0, with a note naming the joints.

Options are named by their keywords (``joints=``); the command line names its flags.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import DataError, ModelError
from ..jointlog import JointLog
from ..model.robot import Robot
from ..model.weld import weld

#: largest logged range [rad or m] of a joint held still (welded at its median)
STILL = 1e-3


def parse_welds(items: Sequence[str] | None) -> dict[str, float]:
    """The ``weld=`` items (``--weld``) as a dict.

    Parameters
    ----------
    items : sequence of str or None
        ``["NAME=VALUE", ...]`` (rad or m).

    Returns
    -------
    dict of str to float
        Joint name -> value.

    Raises
    ------
    ModelError
        An item that is not ``NAME=VALUE`` with a number.
    """
    out: dict[str, float] = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if not sep or not name.strip():
            raise ModelError(f"weld= {item!r}: expected NAME=VALUE (a joint name and a number)")
        if not abs(out[name.strip()]) <= 1e6:
            raise ModelError(f"weld= {item!r}: the value must be a finite number within [-1e6, 1e6] (rad or m)")
    return out


def subchain(robot: Robot, log: JointLog, joints: Sequence[str],
             welds: Mapping[str, float] | None = None) -> tuple[Robot, JointLog, list[str]]:
    """The model of the listed joints and the log restricted to them.

    Parameters
    ----------
    robot : Robot
        The whole robot (a tree without loops or couplings).
    log : JointLog
        The log, read with ``allow_subset=True`` (it may lack the joints that are welded).
    joints : sequence of str
        The joints to identify (R or P).
    welds : mapping of str to float, optional
        Values at which to weld other joints (rad or m).

    Returns
    -------
    robot : Robot
        The robot with every other R/P joint welded.
    log : JointLog
        The log's columns of the listed joints, in the new robot's joint order.
    notes : list of str
        Where each welded joint was welded.

    Raises
    ------
    ModelError
        An unknown joint, a weld of a listed joint, a floating base.
    DataError
        A listed joint missing from the log, or an unlisted joint that moves in the log (welded at
        its logged position or at a given value).
    """
    if robot.floating:
        raise ModelError(f"robot {robot.name!r}: sub-chains (joints=) of a floating base are not supported; identify "
                         "every joint")
    welds = dict(welds or {})
    names = list(robot.joint_names)
    for j in list(joints) + list(welds):
        if j not in names:
            raise ModelError(f"robot {robot.name!r}: no joint {j!r} (joints: {', '.join(names)})")
    both = sorted(set(joints) & set(welds))
    if both:
        raise ModelError(f"joint(s) {', '.join(both)} both identified (joints=) and welded (weld=)")
    missing = [j for j in joints if j not in log.joints]
    if missing:
        raise DataError(f"{log.source}: no column for the listed joint(s) {', '.join(missing)}")
    values, held, zero, off = _weld_values(robot, log, joints, welds)
    small = weld(robot, values)
    other = [j for j in small.joint_names if j not in joints]
    if other:
        raise ModelError(f"robot {robot.name!r}: joint(s) {', '.join(other)} can be neither welded (not R or P) nor "
                         "identified (not in joints=)")
    cols = [log.joints.index(j) for j in small.joint_names]
    rest = {k: None if getattr(log, k) is None else getattr(log, k)[:, cols] for k in ("tau", "dq", "ddq", "cur")}
    sub = JointLog(log.t, tuple(small.joint_names), log.q[:, cols], **rest, source=log.source,
                   removed=dict(log.removed), notes=log.notes)
    notes = [f"sub-chain: {len(small.joint_names)} joint(s) identified, {len(values)} welded"]
    if held:
        notes.append(f"welded at their logged (still) positions: {', '.join(held)}")
    if welds:
        notes.append("welded at weld= values: " + ", ".join(f"{k}={v:g}" for k, v in welds.items()))
    if off:
        notes.append("WARNING: welded where the log does not hold them (weld= over the log's still position): "
                     + "; ".join(off))
    if zero:
        notes.append(f"not in the log, welded at 0 (weld= NAME=VALUE to choose): {', '.join(zero)}")
    return small, sub, notes


def _weld_values(robot: Robot, log: JointLog, joints, welds: dict) -> tuple[dict, list, list, list]:
    """Where each unlisted R/P joint is welded: ``(values, held at the log, at 0, given away from the log)``."""
    values, held, zero, off = {}, [], [], []
    for i, j in enumerate(robot.joint_names):
        if j in joints or robot.jtype[i] not in ("R", "P"):
            continue
        if j not in log.joints:
            values[j] = welds.get(j, 0.0)
            zero += [] if j in welds else [j]
            continue
        qj = log.q[:, log.joints.index(j)]
        span, still = float(np.ptp(qj)), float(np.median(qj))
        if span > STILL:  # a joint the log shows moving cannot be welded, wherever asked
            how = f"is welded at weld= {j}={welds[j]:g}" if j in welds else "is not in joints="
            raise DataError(f"{log.source}: joint {j!r} moves in the log (range {span:.3g} "
                            f"{'m' if robot.jtype[i] == 'P' else 'rad'}) and {how}: identify it too, or cut the log "
                            f"where it is still")
        values[j] = welds.get(j, still)
        if j in welds and abs(welds[j] - still) > STILL:
            off.append(f"{j} at {welds[j]:g}, logged still at {still:.4g}")
        held += [] if j in welds else [j]
    return values, held, zero, off
