"""Sub-chains: a robot with some joints welded at given values.

Identifying part of a robot (a TIAGo's arm without its head, wheels and gripper) means a model
in which every other joint is rigid. :func:`weld` turns 1-dof joints (R, P) into rigid
connections at given coordinates: the welded joint's body, displaced by the joint's motion at
that value, is merged into its parent (pseudo-inertias added exactly, as a URDF fixed joint is
merged), its subtree re-posed, and a body welded to the world disappears (no measurement can see
its inertia). Loop robots and coupled coordinates are refused.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import ModelError
from . import inertia as _inertia
from .robot import Robot


def _local_motion(jtype: str, axis: np.ndarray, value: float) -> np.ndarray:
    """The joint frame's displacement ``(4, 4)`` at ``value`` (R: rotation about the axis, P: slide)."""
    m = np.eye(4)
    a = axis / np.linalg.norm(axis)
    if jtype == "R":
        k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        m[:3, :3] = np.eye(3) + np.sin(value) * k + (1 - np.cos(value)) * (k @ k)
    else:
        m[:3, 3] = a * value
    return m


def _with_couplings(robot: Robot, index: dict[str, int], values: dict[str, float]) -> dict[str, float]:
    """The values with each coupled coordinate set by its coupling; a coupling half welded is refused.

    A coupling whose coordinates are all welded disappears; its driven coordinate is welded where
    the coupling puts it (``ratio * pred + ... + offset``), whatever value it was given.
    """
    body_of = robot.dof_body
    for c in robot.couplings:
        coords = [c.succ] + [k for k, _ in c.terms()]
        names = [robot.joint_names[body_of[k]] for k in coords]
        inside = [n in values for n in names]
        if any(inside) and not all(inside):
            raise ModelError(f"robot {robot.name!r}: coupling {c.name!r} ties {', '.join(names)}: weld all of them "
                             "or none")
        if all(inside):
            x = values[robot.joint_names[body_of[c.pred]]]
            values[names[0]] = (c.offset + sum(r * values[robot.joint_names[body_of[k]]] for k, r in c.terms())
                                + sum(a * x ** (k + 2) for k, a in enumerate(c.poly)))
    return values


def _reposed_and_merged(robot: Robot, index: dict[str, int], values: Mapping[str, float]):
    """World poses with the welded joints at their values, merged inertias, merge targets, welded mask."""
    m0 = robot.M0.copy()
    parent = robot.parent.copy()
    n_body = robot.N_body.copy()
    children: list[list[int]] = [[] for _ in range(robot.n)]
    for i, p in enumerate(parent):
        if p >= 0:
            children[p].append(i)
    welded = np.zeros(robot.n, dtype=bool)
    for name, v in values.items():
        j = index[name]
        welded[j] = True
        d = m0[j] @ _local_motion(robot.jtype[j], robot.axes[j][0], float(v)) @ np.linalg.inv(m0[j])
        stack = [j]
        while stack:  # re-pose the subtree in the world
            k = stack.pop()
            m0[k] = d @ m0[k]
            stack += children[k]
    # merge each welded body into its nearest kept ancestor (or drop it on the world), deepest first
    target = np.arange(robot.n)
    for i in range(robot.n):
        if welded[i]:
            target[i] = target[parent[i]] if parent[i] >= 0 else -1
    for i in range(robot.n - 1, -1, -1):
        if welded[i] and target[i] >= 0:
            t = np.linalg.inv(m0[target[i]]) @ m0[i]
            n_body[target[i]] += _inertia.transform(n_body[i], t)
    return m0, n_body, target, welded


def weld(robot: Robot, values: Mapping[str, float]) -> Robot:
    """The robot with the named joints welded at the given coordinates.

    Parameters
    ----------
    robot : Robot
        A tree robot without loops or couplings.
    values : mapping of str to float
        Joint name -> coordinate at which it is welded (rad for R, m for P). Only 1-dof R and
        P joints can be welded.

    Returns
    -------
    Robot
        Bodies of the welded joints merged into their parents (each merged body's pseudo-inertia
        added to the parent's, in the parent's frame); bodies welded to the world removed;
        ``limits`` and ``armature`` of the remaining coordinates kept. The remaining bodies'
        frames are their poses with the welded joints at their values.

    Raises
    ------
    ModelError
        An unknown joint, a joint that is not R or P, a non-finite value, or a robot with loops
        or couplings.
    """
    if robot.loops:
        raise ModelError(f"robot {robot.name!r}: welding joints of a robot with loops is not supported")
    index = {j: i for i, j in enumerate(robot.joint_names)}
    values = _with_couplings(robot, index, dict(values))
    for name, v in values.items():
        if name not in index:
            raise ModelError(f"robot {robot.name!r}: no joint {name!r} to weld "
                             f"(joints: {', '.join(robot.joint_names)})")
        if robot.jtype[index[name]] not in ("R", "P"):
            raise ModelError(f"robot {robot.name!r}: joint {name!r} is {robot.jtype[index[name]]}; only R and P "
                             "joints can be welded")
        if not np.isfinite(v):
            raise ModelError(f"robot {robot.name!r}: joint {name!r} cannot be welded at {v}")
    m0, n_body, target, welded = _reposed_and_merged(robot, index, values)
    parent = robot.parent
    keep = np.flatnonzero(~welded)
    new_index = -np.ones(robot.n, dtype=int)
    new_index[keep] = np.arange(len(keep))
    new_parent = np.array([new_index[target[parent[i]]] if parent[i] >= 0 and target[parent[i]] >= 0 else -1
                           for i in keep], dtype=int)
    coord_keep = np.concatenate([np.arange(s, s + k) for s, k, w in
                                 zip(np.concatenate([[0], np.cumsum(robot.ndofs)[:-1]]), robot.ndofs, welded)
                                 if not w] or [np.zeros(0, dtype=int)]).astype(int)
    return Robot(
        name=robot.name,
        names=tuple(robot.names[i] for i in keep),
        joint_names=tuple(robot.joint_names[i] for i in keep),
        jtype=tuple(robot.jtype[i] for i in keep),
        parent=new_parent,
        M0=m0[keep],
        axes=tuple(robot.axes[i] for i in keep),
        N_body=n_body[keep],
        gravity=robot.gravity,
        couplings=tuple(_renumbered(c, coord_keep) for c in robot.couplings
                        if robot.joint_names[robot.dof_body[c.succ]] not in values),
        independent=(None if robot.independent is None or not any(
            robot.joint_names[robot.dof_body[c.succ]] not in values for c in robot.couplings)
            else tuple(int(np.flatnonzero(coord_keep == k)[0]) for k in robot.independent if k in coord_keep)),
        armature=None if robot.armature is None else np.asarray(robot.armature)[coord_keep],
        limits=None if robot.limits is None else np.asarray(robot.limits)[coord_keep],
    )


def _renumbered(c, coord_keep: np.ndarray):
    """A coupling of kept coordinates, with the welded robot's coordinate indices."""
    from dataclasses import replace

    new = {int(k): i for i, k in enumerate(coord_keep)}
    return replace(c, pred=new[c.pred], succ=new[c.succ], more=tuple((new[k], r) for k, r in c.more))
