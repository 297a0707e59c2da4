"""The limits a design respects: position, velocity, acceleration and effort per designed coordinate.

Which coordinates are designed (a tree's joints, a loop robot's actuated ones), the limits read
from the model (:attr:`~baseparams.model.robot.Robot.limits`) or given, the defaults taken where
none is known, and the bound on ``cond(J_p)`` that keeps a loop robot's motion regular.
"""

from __future__ import annotations

import numpy as np

from ..errors import BaseparamsError
from ..model.robot import Robot

#: position range around q = 0 of a coordinate whose limits the model does not give [rad, m]
DEFAULT_RANGE = {"R": 1.0, "P": 0.1}


#: a loop robot whose reference cond(J_p) is above this is singular there
SINGULAR_COND = 1e6


def design_coordinates(robot: Robot) -> np.ndarray:
    """The coordinates a trajectory is designed for.

    Parameters
    ----------
    robot : Robot
        The robot.

    Returns
    -------
    ndarray of int, shape ``(m,)``
        Indices into ``q``: every coordinate of a tree, the actuated ones of a robot with loops
        (the states :meth:`~baseparams.ident.pipeline.IdentModel.regressor` takes).
    """
    return np.asarray(robot.actuated, dtype=int) if robot.has_loops else np.arange(robot.dof)


def excitation_limits(robot: Robot, limits=None, acceleration=None,
                      margin: float = 0.0) -> tuple[np.ndarray, list[str]]:
    """The limits a design respects, per designed coordinate.

    Parameters
    ----------
    robot : Robot
        The robot (:attr:`Robot.limits` where known).
    limits : array_like, shape ``(m, 4)``, optional
        ``[lower, upper, velocity, effort]`` per designed coordinate (:func:`design_coordinates`)
        overriding the model's; NaN entries keep the model's.
    acceleration : float or array_like, shape ``(m,)``, optional
        Acceleration limits [rad/s^2 or m/s^2] (models do not give them); default none.
    margin : float
        A fraction ``0 <= margin < 0.5`` of each position range kept free at both ends: the range
        used is ``[lower + margin w, upper - margin w]``, ``w = upper - lower`` (0.05: 5 %).

    Returns
    -------
    limits : ndarray, shape ``(m, 5)``
        ``lower, upper, velocity, acceleration, effort``; NaN: not constrained. Unknown position
        limits are the robot's sampling box (``q_box``) or ``+-DEFAULT_RANGE`` around q = 0.
    notes : list of str
        The defaults taken.

    Raises
    ------
    BaseparamsError
        ``limits`` of the wrong shape, or limits that leave no room for motion (an empty position
        range, a non-positive velocity or acceleration limit, a margin outside ``[0, 0.5)``).
    """
    if not 0.0 <= margin < 0.5:
        raise BaseparamsError(f"margin must be a fraction of each position range in [0, 0.5), got {margin}")
    coords = design_coordinates(robot)
    m = len(coords)
    lim = np.full((m, 5), np.nan)
    if robot.limits is not None:
        lim[:, [0, 1, 2, 4]] = robot.limits[coords]
    if limits is not None:
        from ..arguments import check_array

        user = check_array(limits, "limits=", 2, finite=False)  # NaN keeps the model's
        if user.shape != (m, 4):
            raise BaseparamsError(f"robot {robot.name!r}: limits must have shape ({m}, 4) (lower, upper, velocity, "
                                  f"effort per designed coordinate), got {user.shape}")
        lim[:, [0, 1, 2, 4]] = np.where(np.isnan(user), lim[:, [0, 1, 2, 4]], user)
    if acceleration is not None:
        acc = np.atleast_1d(np.asarray(acceleration, dtype=float))
        if acc.ndim != 1 or len(acc) not in (1, m):
            raise BaseparamsError(f"robot {robot.name!r}: acceleration= takes one limit or one per designed "
                                  f"coordinate ({m}), got {acc.size}")
        lim[:, 3] = np.broadcast_to(acc, (m,))
    names = [robot.joint_names[robot.dof_body[c]] for c in coords]
    notes = _default_positions(robot, coords, lim, names)
    if margin > 0:
        pad = margin * (lim[:, 1] - lim[:, 0])
        lim[:, 0] += pad
        lim[:, 1] -= pad
        notes.append(f"position margin: {100 * margin:.3g} % of each range kept free at both ends (the limits "
                     f"shown are the narrowed ones)")
    _check_room(robot, lim, names)
    unknown = [n for n, v in zip(names, lim[:, 2]) if np.isnan(v)]
    if unknown:
        notes.append(f"no velocity limit for {unknown}: not constrained")
    return lim, notes


def _default_positions(robot: Robot, coords: np.ndarray, lim: np.ndarray, names: list[str]) -> list[str]:
    """Fill unknown (or infinite) position limits in place: ``q_box`` or the default range."""
    bad = ~np.all(np.isfinite(lim[:, :2]), axis=1)
    if not bad.any():
        return []
    if robot.q_box is not None:
        lim[bad, :2] = robot.q_box[bad]
        return [f"no position limits for {[n for n, b in zip(names, bad) if b]}: the robot's sampling box used"]
    half = np.array([DEFAULT_RANGE.get(robot.jtype[robot.dof_body[c]], 1.0) for c in coords])
    lim[bad, 0], lim[bad, 1] = -half[bad], half[bad]
    return [f"no position limits for {[n for n, b in zip(names, bad) if b]}: +-{DEFAULT_RANGE['R']} rad "
            f"(+-{DEFAULT_RANGE['P']} m) around q = 0 used; give limits= for the real ones"]


def _check_room(robot: Robot, lim: np.ndarray, names: list[str]) -> None:
    """Raise on limits that leave no room for motion."""
    for j, name in enumerate(names):
        lo, hi, v, acc = lim[j, :4]
        if not hi - lo > 1e-9:
            raise BaseparamsError(f"robot {robot.name!r}: joint {name!r}: the position range [{lo:.6g}, {hi:.6g}] "
                                  f"leaves no room for an excitation")
        for what, val in (("velocity", v), ("acceleration", acc)):
            if val <= 0:
                raise BaseparamsError(f"robot {robot.name!r}: joint {name!r}: {what} limit {val:.6g} leaves no room "
                                      f"for an excitation")


def loop_bound(robot: Robot) -> float:
    """The bound on ``cond(J_p)`` a loop robot's design keeps (that of the analysis's samples).

    Parameters
    ----------
    robot : Robot
        A robot with loops.

    Returns
    -------
    float
        :data:`~baseparams.numerics.COND_MAX`, or :data:`~baseparams.numerics.COND_FACTOR` times the
        reference's cond(J_p) when that is already above it.

    Raises
    ------
    BaseparamsError
        The reference configuration q = 0 is singular (cond(J_p) above :data:`SINGULAR_COND`, or the
        loops do not close there).
    """
    from ..numerics import COND_FACTOR, COND_MAX, reference_cond

    ref = reference_cond(robot)
    if not ref < SINGULAR_COND:
        raise BaseparamsError(f"robot {robot.name!r}: the reference configuration q = 0 is singular (cond(J_p) = "
                              f"{ref:.3g}): the passive coordinates are not determined there; re-reference the model "
                              f"at a regular configuration (baseparams.kinematics.loops.assemble)")
    return COND_MAX if ref < COND_MAX else COND_FACTOR * ref
