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
        (the states :meth:`~baseparams.ident.IdentModel.regressor` takes).
    """
    return robot.measured_coords


def joint_values(robot: Robot, value, what: str, pair: bool = False) -> np.ndarray:
    """A limit given for every designed coordinate, per coordinate in order, or by joint name.

    Parameters
    ----------
    robot : Robot
        The robot (:func:`design_coordinates`, their joints' names).
    value : None, float, array_like or mapping
        One value for all (a number; with ``pair`` a ``(lower, upper)`` pair), one per designed
        coordinate (``(m,)``; with ``pair`` ``(m, 2)``), or ``{joint name: value}`` (the others
        not given).
    what : str
        The limit's name, for messages (``position``, ``velocity``, ...).
    pair : bool
        Each value is a ``(lower, upper)`` pair.

    Returns
    -------
    ndarray, shape ``(m,)`` or ``(m, 2)``
        The values; NaN where none is given.

    Raises
    ------
    BaseparamsError
        A joint that is not designed, or a shape that is none of the above.
    """
    from collections.abc import Mapping

    names = robot.coordinate_names(design_coordinates(robot))
    shape = (len(names), 2) if pair else (len(names),)
    out = np.full(shape, np.nan)
    if value is None:
        return out
    one = "(lower, upper)" if pair else "a number"
    if isinstance(value, Mapping):
        for name, v in value.items():
            if name not in names:
                raise BaseparamsError(f"{what}= limit for {name!r}: not a designed joint of {robot.name!r} (joints: "
                                      f"{', '.join(names)})")
            x = _floats(v, f"{what}= limit for {name!r}:")
            if x.shape != shape[1:]:
                raise BaseparamsError(f"{what}= limit for {name!r}: expected {one}, got {v!r}")
            out[names.index(name)] = _valid(x, f"{what}= limit for {name!r}:", pair)
        return out
    x = _floats(value, f"{what}= limit:")
    if x.shape not in (shape, shape[1:]):
        raise BaseparamsError(f"{what}= limit: expected {one} for every joint or one per designed joint "
                              f"({len(names)}: {', '.join(names)}), got shape {x.shape}")
    out[:] = _valid(x, f"{what}= limit:", pair)
    return out


def _floats(value, what: str) -> np.ndarray:
    """A limit's value as floats, or one line naming it."""
    from ..arguments import ArgumentTypeError, brief

    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ArgumentTypeError(f"{what} must be numbers, got {brief(value)}") from None


def _valid(x: np.ndarray, what: str, pair: bool) -> np.ndarray:
    """A given limit: finite (NaN would mean no limit), ``lower < upper`` for a range, ``> 0`` otherwise."""
    from ..arguments import ArgumentError

    if not np.all(np.isfinite(x)) or not np.all(np.abs(x) <= 1e9):
        raise ArgumentError(f"{what} finite numbers within 1e9 expected, got {x.tolist()}")
    if pair and not np.all(x[..., 0] < x[..., 1]):
        raise ArgumentError(f"{what} lower < upper expected, got {x.tolist()}")
    if not pair and not np.all(x > 0):
        raise ArgumentError(f"{what} a limit > 0 expected, got {x.tolist()}")
    return x


def given_limits(robot: Robot, limits=None, position=None, velocity=None, effort=None) -> np.ndarray | None:
    """The ``(m, 4)`` override of :func:`excitation_limits` from per-limit values (:func:`joint_values`).

    Parameters
    ----------
    robot : Robot
        The robot.
    limits : array_like, shape ``(m, 4)``, optional
        ``[lower, upper, velocity, effort]`` per designed coordinate (NaN: the model's).
    position, velocity, effort : optional
        Per-limit values, for all joints, per joint or by name (:func:`joint_values`); they take
        precedence over ``limits``.

    Returns
    -------
    ndarray, shape ``(m, 4)``, or None
        The override, NaN where the model's limit stays; None when nothing is given.
    """
    if limits is None and position is None and velocity is None and effort is None:
        return None
    m = len(design_coordinates(robot))
    out = np.full((m, 4), np.nan) if limits is None else np.array(limits, dtype=float)
    if out.shape != (m, 4):
        raise BaseparamsError(f"robot {robot.name!r}: limits must have shape ({m}, 4) (lower, upper, velocity, "
                              f"effort per designed coordinate), got {out.shape}")
    for cols, value, what, pair in (([0, 1], position, "position", True), ([2], velocity, "velocity", False),
                                    ([3], effort, "effort", False)):
        given = joint_values(robot, value, what, pair).reshape(m, -1)
        out[:, cols] = np.where(np.isnan(given), out[:, cols], given)
    return out


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
    acceleration : float, array_like, shape ``(m,)``, or mapping, optional
        Acceleration limits [rad/s^2 or m/s^2] (models do not give them), for all, per designed
        coordinate or ``{joint: value}`` (:func:`joint_values`); default none.
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
        lim[:, 3] = joint_values(robot, acceleration, "acceleration")
    names = robot.coordinate_names(coords)
    notes = _default_positions(robot, coords, lim, names)
    notes += _coupled_ranges(robot, coords, lim, names)
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
            f"(+-{DEFAULT_RANGE['P']} m) around q = 0 used; give position= for the real ones"]


def _coupled_ranges(robot: Robot, coords: np.ndarray, lim: np.ndarray, names: list[str]) -> list[str]:
    """Narrow, in place, each designed coordinate's range to what keeps the joints it drives in theirs.

    A coupled joint ``q_f = r q_l + o`` (URDF ``<mimic>``, chains composed) stays within its own
    position limits exactly when ``q_l`` is in ``[(lower_f - o) / r, (upper_f - o) / r]`` (sorted);
    couplings with several driving coordinates are left to the model (not a box).
    """
    if not robot.couplings or robot.limits is None:
        return []
    from ..nullspace.coupled import coupled_coordinates

    lead, ratio, offset = coupled_coordinates(robot)
    where = {int(c): j for j, c in enumerate(coords)}
    notes = []
    for f in range(robot.dof):
        j = where.get(int(lead[f]), -1)
        lo_f, hi_f = robot.limits[f, :2]
        if f in where or j < 0 or ratio[f] == 0 or not np.all(np.isfinite([lo_f, hi_f])):
            continue
        ends = np.sort([(lo_f - offset[f]) / ratio[f], (hi_f - offset[f]) / ratio[f]])
        lo, hi = max(lim[j, 0], ends[0]), min(lim[j, 1], ends[1])
        follower = robot.joint_names[robot.dof_body[f]]
        if not hi - lo > 1e-9:
            raise BaseparamsError(f"robot {robot.name!r}: joint {names[j]!r}'s position range [{lim[j, 0]:.6g}, "
                                  f"{lim[j, 1]:.6g}] and the range [{lo_f:.6g}, {hi_f:.6g}] of joint {follower!r} "
                                  f"it drives ({follower} = {ratio[f]:.6g} {names[j]} + {offset[f]:.6g}) leave no "
                                  f"room for an excitation")
        if lo > lim[j, 0] + 1e-12 or hi < lim[j, 1] - 1e-12:
            notes.append(f"joint {names[j]!r}: position range narrowed to [{lo:.6g}, {hi:.6g}] to keep joint "
                         f"{follower!r} it drives within [{lo_f:.6g}, {hi_f:.6g}]")
            lim[j, :2] = lo, hi
    return notes


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
