"""Pinocchio interop (optional extra ``pinocchio``: ``pip install pin``).

``to_pinocchio(robot)`` builds the same tree as a ``pin.Model`` (R and P joints, a
free-flyer root); ``state_to_pinocchio`` maps our states to Pinocchio's, and
``forces_from_pinocchio`` maps Pinocchio's generalized forces back to ours.

Our floating root: ``q`` = twist coordinates (world) with body pose ``exp(q^) M0``, velocities
= the spatial twist (omega, v) and its derivative; generalized forces = world wrench
components (moment about the origin, then force). Pinocchio's free flyer: (xyz, quaternion
xyzw) of the joint placement, body-frame (v, omega) velocities, body-frame (f, n) forces.
"""

from __future__ import annotations

import numpy as np

from ..errors import BaseparamsError
from ..model.inertia import split
from ..model.robot import Robot
from ..pga import inverse_transform, se3_exp


def _pin():
    try:
        import pinocchio as pin
    except ImportError:  # pragma: no cover - depends on the environment
        raise BaseparamsError("Pinocchio is not installed: pip install 'baseparams[pinocchio]'") from None
    return pin


def _ad(t: np.ndarray) -> np.ndarray:
    r, p = t[:3, :3], t[:3, 3]
    x = np.zeros((6, 6))
    x[:3, :3] = r
    x[3:, 3:] = r
    x[3:, :3] = np.array([[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]]) @ r
    return x


_SWAP = np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])


def to_pinocchio(robot: Robot):
    """A ``pin.Model`` of the same tree, inertias and gravity (R, P, F-root joints).

    Parameters
    ----------
    robot : Robot
        A tree of R and P joints, optionally on a floating (F) root (loops and couplings are
        not carried over).

    Returns
    -------
    pinocchio.Model
        One joint per body, named ``robot.joint_names``, placed at the body's joint frame at
        q = 0 relative to its parent's (``robot.M0``); each body's inertia in its joint frame;
        ``gravity.linear = robot.gravity``.

    Raises
    ------
    BaseparamsError
        Pinocchio is not installed, or a joint type other than R, P and F.
    """
    pin = _pin()
    model = pin.Model()
    model.name = robot.name
    ids = []
    for i in range(robot.n):
        p = robot.parent[i]
        pid = 0 if p < 0 else ids[p]
        t = robot.jtype[i]
        if t == "R":
            jm = pin.JointModelRevoluteUnaligned(*robot.axes[i][0])
        elif t == "P":
            jm = pin.JointModelPrismaticUnaligned(*robot.axes[i][0])
        elif t == "F":
            jm = pin.JointModelFreeFlyer()
        else:
            raise BaseparamsError(f"to_pinocchio: joint type {t} of body {robot.names[i]!r} is not mapped")
        rel = robot.M0[i] if p < 0 else inverse_transform(robot.M0[p]) @ robot.M0[i]
        placement = pin.SE3(rel[:3, :3].copy(), rel[:3, 3].copy())
        jid = model.addJoint(pid, jm, placement, robot.joint_names[i])
        m, h, j_o = split(robot.N_body[i])
        c = h / m if m > 0 else np.zeros(3)
        j_c = j_o - m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
        model.appendBodyToJoint(jid, pin.Inertia(float(m), c, j_c), pin.SE3.Identity())
        ids.append(jid)
    model.gravity.linear = np.asarray(robot.gravity, dtype=float)
    return model


def _root_maps(robot: Robot, q: np.ndarray):
    """For the F root: pose T (4, 4) and P = pin-velocity-from-ours (6, 6)."""
    t = se3_exp(q[:6]) @ robot.M0[0]
    return t, _SWAP @ _ad(inverse_transform(t))


def state_to_pinocchio(robot: Robot, q, dq, ddq):
    """One state ``(dof,)`` each -> Pinocchio ``(q, v, a)``.

    Without a floating root the coordinates are the same (copies). With one, the root's six
    coordinates become Pinocchio's free flyer (see the module doc).

    Parameters
    ----------
    robot : Robot
        The robot (a tree, as for :func:`to_pinocchio`).
    q, dq, ddq : array_like, shape ``(dof,)``
        Our coordinates, velocities and accelerations (floating root: twist coordinates in the
        world frame, spatial twist ``(omega, v)`` and its derivative).

    Returns
    -------
    q, v, a : ndarray
        Pinocchio's ``(nq,)`` configuration (free flyer: position and quaternion ``xyzw`` of the
        joint placement) and ``(nv,)`` velocity and acceleration (free flyer: body-frame
        ``(v, omega)``).
    """
    q, dq, ddq = (np.asarray(x, dtype=float) for x in (q, dq, ddq))
    if robot.jtype[0] != "F":
        return q.copy(), dq.copy(), ddq.copy()
    pin = _pin()
    t, pmap = _root_maps(robot, q)
    rel = inverse_transform(robot.M0[0]) @ t  # joint motion relative to its placement
    quat = pin.Quaternion(rel[:3, :3].copy())
    qp = np.r_[rel[:3, 3], quat.coeffs(), q[6:]]
    return qp, np.r_[pmap @ dq[:6], dq[6:]], np.r_[pmap @ ddq[:6], ddq[6:]]


def forces_from_pinocchio(robot: Robot, q, tau_pin) -> np.ndarray:
    """Pinocchio generalized forces -> ours (the root wrench re-expressed, see module doc).

    Parameters
    ----------
    robot : Robot
        The robot (a tree, as for :func:`to_pinocchio`).
    q : array_like, shape ``(dof,)``
        Our coordinates of the state (the floating root's pose).
    tau_pin : array_like, shape ``(nv,)``
        Pinocchio's generalized forces (free flyer: body-frame ``(f, n)``).

    Returns
    -------
    ndarray, shape ``(dof,)``
        Our generalized forces (floating root: world wrench components, moment about the
        origin, then force); a copy of ``tau_pin`` without a floating root.
    """
    tau_pin = np.asarray(tau_pin, dtype=float)
    if robot.jtype[0] != "F":
        return tau_pin.copy()
    _, pmap = _root_maps(robot, np.asarray(q, dtype=float))
    return np.r_[pmap.T @ tau_pin[:6], tau_pin[6:]]
