"""A floating base in a log: its pose and twist as written, and the smooth coordinates the pipeline filters.

A log of a floating-base robot (a legged robot, a humanoid) holds the base's pose and, optionally, its
twist beside the joints (docs/guides/log-layout.md; :mod:`baseparams.io.logs`):

* ``base_x, base_y, base_z`` [m]: the origin of the base body's frame (the floating joint's frame:
  a URDF's root link), world frame;
* ``base_qw, base_qx, base_qy, base_qz``: its orientation, a unit quaternion (Hamilton, scalar
  first, world <- base; ``q`` and ``-q`` alike);
* optionally ``base_vx, base_vy, base_vz`` [m/s] and ``base_wx, base_wy, base_wz`` [rad/s]: the
  linear velocity of that origin and the angular velocity, both expressed in the **base** frame
  (what ROS odometry's twist and an IMU's gyro give; Pinocchio's free-flyer velocity).

Accelerations are derived, like the joints'. In memory (:class:`~baseparams.jointlog.JointLog`)
the base is six coordinates :data:`BASE_COORDINATES` that are smooth in time, so that the
preprocessing filters and differentiates them like joint positions: the position and the
Z-Y-X Euler angles ``R = Rz(yaw) Ry(pitch) Rx(roll)``, roll and yaw unwrapped (a robot may turn
any number of times); the chart is singular at ``pitch = +-90 deg``, so a log beyond
:data:`MAX_PITCH` is refused. :func:`native_states` maps these coordinates and their time
derivatives to the robot's own floating-root states (twist coordinates of the displacement, the
spatial twist ``(omega, v)`` and its derivative, world frame: :mod:`baseparams.kinematics.tree`).
"""

from __future__ import annotations

import numpy as np

from ..pga import inverse_transform, se3_log

#: the floating base's six coordinates in a JointLog (position [m], then Z-Y-X angles [rad])
BASE_COORDINATES = ("base_x", "base_y", "base_z", "base_roll", "base_pitch", "base_yaw")
#: a log's base pose columns: position [m], then the unit quaternion (scalar first)
POSE_COLUMNS = ("base_x", "base_y", "base_z", "base_qw", "base_qx", "base_qy", "base_qz")
#: a log's optional base twist columns: linear [m/s], then angular [rad/s] velocity, base frame
TWIST_COLUMNS = ("base_vx", "base_vy", "base_vz", "base_wx", "base_wy", "base_wz")
#: largest ``|pitch|`` [rad] the Euler chart accepts (85 deg; it is singular at 90)
MAX_PITCH = np.deg2rad(85.0)
#: the windows a logged twist is integrated over to be compared with the logged pose [s] (:func:`twist_mismatch`)
TWIST_WINDOW = 0.1


def rotation_zyx(angles) -> np.ndarray:
    """Rotation matrices ``Rz(yaw) Ry(pitch) Rx(roll)``.

    Parameters
    ----------
    angles : array_like, shape ``(S, 3)``
        ``roll, pitch, yaw`` [rad].

    Returns
    -------
    ndarray, shape ``(S, 3, 3)``
        World <- base rotations.
    """
    a = np.asarray(angles, dtype=float)
    cr, sr = np.cos(a[:, 0]), np.sin(a[:, 0])
    cp, sp = np.cos(a[:, 1]), np.sin(a[:, 1])
    cy, sy = np.cos(a[:, 2]), np.sin(a[:, 2])
    r = np.empty((len(a), 3, 3))
    r[:, 0] = np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], axis=1)
    r[:, 1] = np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], axis=1)
    r[:, 2] = np.stack([-sp, cp * sr, cp * cr], axis=1)
    return r


def zyx_of_rotation(r) -> np.ndarray:
    """Z-Y-X angles of rotation matrices, roll and yaw unwrapped along the samples.

    Parameters
    ----------
    r : array_like, shape ``(S, 3, 3)``
        World <- base rotations, in time order.

    Returns
    -------
    ndarray, shape ``(S, 3)``
        ``roll, pitch, yaw`` [rad]: pitch in ``[-pi/2, pi/2]``, roll and yaw continuous (no jump
        of ``2 pi`` between samples).
    """
    r = np.asarray(r, dtype=float)
    pitch = -np.arcsin(np.clip(r[:, 2, 0], -1.0, 1.0))
    roll = np.unwrap(np.arctan2(r[:, 2, 1], r[:, 2, 2]))
    yaw = np.unwrap(np.arctan2(r[:, 1, 0], r[:, 0, 0]))
    return np.stack([roll, pitch, yaw], axis=1)


def quaternion_matrix(quat) -> np.ndarray:
    """Rotation matrices of unit quaternions.

    Parameters
    ----------
    quat : array_like, shape ``(S, 4)``
        ``w, x, y, z`` (Hamilton; normalised here).

    Returns
    -------
    ndarray, shape ``(S, 3, 3)``
        The rotations.
    """
    qq = np.asarray(quat, dtype=float)
    w, x, y, z = (qq / np.linalg.norm(qq, axis=1, keepdims=True)).T
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=1),
                     np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=1),
                     np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1)],
                    axis=1)


def zyx_quaternion(angles) -> np.ndarray:
    """Unit quaternions of Z-Y-X angles.

    Parameters
    ----------
    angles : array_like, shape ``(S, 3)``
        ``roll, pitch, yaw`` [rad].

    Returns
    -------
    ndarray, shape ``(S, 4)``
        ``w, x, y, z`` of ``Rz(yaw) Ry(pitch) Rx(roll)``.
    """
    h = 0.5 * np.asarray(angles, dtype=float)
    cr, sr, cp, sp, cy, sy = np.cos(h[:, 0]), np.sin(h[:, 0]), np.cos(h[:, 1]), np.sin(h[:, 1]), \
        np.cos(h[:, 2]), np.sin(h[:, 2])
    return np.stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                     cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy], axis=1)


def euler_rate_matrix(angles) -> np.ndarray:
    """``E`` with ``omega_world = E d(roll, pitch, yaw)/dt``.

    Parameters
    ----------
    angles : array_like, shape ``(S, 3)``
        ``roll, pitch, yaw`` [rad].

    Returns
    -------
    ndarray, shape ``(S, 3, 3)``
        Columns: the roll axis ``Rz Ry e_x``, the pitch axis ``Rz e_y`` and the yaw axis ``e_z``
        (world frame); singular at ``pitch = +-pi/2``.
    """
    a = np.asarray(angles, dtype=float)
    cp, sp, cy, sy = np.cos(a[:, 1]), np.sin(a[:, 1]), np.cos(a[:, 2]), np.sin(a[:, 2])
    e = np.zeros((len(a), 3, 3))
    e[:, 0, 0], e[:, 1, 0], e[:, 2, 0] = cy * cp, sy * cp, -sp
    e[:, 0, 1], e[:, 1, 1] = -sy, cy
    e[:, 2, 2] = 1.0
    return e


def chart_rates(chart, twist) -> np.ndarray:
    """Time derivatives of the six base coordinates from the base-frame twist.

    Parameters
    ----------
    chart : array_like, shape ``(S, 6)``
        ``x, y, z, roll, pitch, yaw`` (:data:`BASE_COORDINATES`).
    twist : array_like, shape ``(S, 6)``
        ``vx, vy, vz, wx, wy, wz``: the origin's velocity and the angular velocity, base frame.

    Returns
    -------
    ndarray, shape ``(S, 6)``
        ``dx, dy, dz`` (world) and the Euler-angle rates.
    """
    c, tw = np.asarray(chart, dtype=float), np.asarray(twist, dtype=float)
    r = rotation_zyx(c[:, 3:])
    dp = np.einsum("sij,sj->si", r, tw[:, :3])
    w = np.einsum("sij,sj->si", r, tw[:, 3:])
    return np.concatenate([dp, np.linalg.solve(euler_rate_matrix(c[:, 3:]), w[..., None])[..., 0]], axis=1)


def chart_twist(chart, rates) -> np.ndarray:
    """The base-frame twist from the base coordinates and their rates (inverse of :func:`chart_rates`).

    Parameters
    ----------
    chart, rates : array_like, shape ``(S, 6)``
        Base coordinates and their time derivatives.

    Returns
    -------
    ndarray, shape ``(S, 6)``
        ``vx, vy, vz, wx, wy, wz``, base frame.
    """
    c, d = np.asarray(chart, dtype=float), np.asarray(rates, dtype=float)
    r = rotation_zyx(c[:, 3:])
    w = np.einsum("sij,sj->si", euler_rate_matrix(c[:, 3:]), d[:, 3:])
    return np.concatenate([np.einsum("sji,sj->si", r, d[:, :3]), np.einsum("sji,sj->si", r, w)], axis=1)


def _windows(t: np.ndarray) -> np.ndarray:
    """Start indices of consecutive windows of about :data:`TWIST_WINDOW` seconds (at least 4 samples), and the end."""
    n = len(t)
    width = max(4, int(round(TWIST_WINDOW / max(float(np.median(np.diff(t))), 1e-12))))
    starts = np.arange(0, n, width)
    return starts if starts[-1] == n - 1 else np.append(starts, n - 1)


def twist_mismatch(t, chart, twist) -> np.ndarray:
    """How well a logged twist integrates to the logged pose, read in the base frame and in the world frame.

    Over consecutive windows of about :data:`TWIST_WINDOW` seconds, the change of the base
    coordinates is compared with the integral (trapezoid rule) of their rates from the twist
    (:func:`chart_rates`), the twist read as the module docstring says (base frame) and as if it
    were expressed in the world frame (rotated by ``R^T`` first). Integrating over windows averages
    the noise of a twist and of a differentiated pose out.

    Parameters
    ----------
    t : array_like, shape ``(S,)``
        Time [s], increasing.
    chart : array_like, shape ``(S, 6)``
        ``x, y, z, roll, pitch, yaw`` (:data:`BASE_COORDINATES`, roll and yaw unwrapped).
    twist : array_like, shape ``(S, 6)``
        ``vx, vy, vz, wx, wy, wz`` as logged.

    Returns
    -------
    ndarray, shape ``(2, 2)``
        Rows: base frame, world frame; columns: linear, angular part. Each the RMS of
        ``change - integral`` over the windows relative to the RMS change: 0 for a twist that is
        the pose's derivative, about 1 or more for an unrelated one; NaN for a part that does not
        move (or fewer than two windows).
    """
    t, c, tw = (np.asarray(x, dtype=float) for x in (t, chart, twist))
    out = np.full((2, 2), np.nan)
    if len(t) < 9:
        return out
    starts = _windows(t)
    r = rotation_zyx(c[:, 3:])
    world = np.concatenate([np.einsum("sji,sj->si", r, tw[:, :3]), np.einsum("sji,sj->si", r, tw[:, 3:])], axis=1)
    change = c[starts[1:]] - c[starts[:-1]]
    for row, body_twist in enumerate((tw, world)):
        rates = chart_rates(c, body_twist)
        steps = 0.5 * (rates[1:] + rates[:-1]) * np.diff(t)[:, None]
        integral = np.concatenate([np.zeros((1, 6)), np.cumsum(steps, axis=0)])
        err = change - (integral[starts[1:]] - integral[starts[:-1]])
        for col, part in enumerate((slice(0, 3), slice(3, 6))):
            scale = np.sqrt(np.mean(np.sum(change[:, part] ** 2, axis=1)))
            if scale > 1e-9:
                out[row, col] = np.sqrt(np.mean(np.sum(err[:, part] ** 2, axis=1))) / scale
    return out


def native_states(m0, chart, rates, accel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The floating root's own states from the base coordinates and their derivatives.

    Parameters
    ----------
    m0 : array_like, shape ``(4, 4)``
        The root body's pose at q = 0 (``Robot.M0[0]``).
    chart, rates, accel : array_like, shape ``(S, 6)``
        ``x, y, z, roll, pitch, yaw`` and their first and second time derivatives.

    Returns
    -------
    q : ndarray, shape ``(S, 6)``
        Twist coordinates of the displacement ``g = P M0^-1`` (``P`` the base pose), world frame.
    twist : ndarray, shape ``(S, 6)``
        Spatial twist ``(omega, v)``, ``v`` the velocity of the body point at the world origin.
    dtwist : ndarray, shape ``(S, 6)``
        Its time derivative (the spatial acceleration).
    """
    c, d, dd = (np.asarray(x, dtype=float) for x in (chart, rates, accel))
    p, ang, dang = c[:, :3], c[:, 3:], d[:, 3:]
    pose = np.zeros((len(c), 4, 4))
    pose[:, :3, :3] = rotation_zyx(ang)
    pose[:, :3, 3] = p
    pose[:, 3, 3] = 1.0
    q = se3_log(pose @ inverse_transform(np.asarray(m0, dtype=float)))
    e = euler_rate_matrix(ang)
    cp, sp, cy, sy = np.cos(ang[:, 1]), np.sin(ang[:, 1]), np.cos(ang[:, 2]), np.sin(ang[:, 2])
    dp_, dy_ = dang[:, 1], dang[:, 2]
    de = np.zeros_like(e)  # dE/dt
    de[:, 0, 0] = -sy * cp * dy_ - cy * sp * dp_
    de[:, 1, 0] = cy * cp * dy_ - sy * sp * dp_
    de[:, 2, 0] = -cp * dp_
    de[:, 0, 1], de[:, 1, 1] = -cy * dy_, -sy * dy_
    w = np.einsum("sij,sj->si", e, dang)
    dw = np.einsum("sij,sj->si", e, dd[:, 3:]) + np.einsum("sij,sj->si", de, dang)
    v = d[:, :3] - np.cross(w, p)
    dv = dd[:, :3] - np.cross(dw, p) - np.cross(w, d[:, :3])
    return q, np.concatenate([w, v], axis=1), np.concatenate([dw, dv], axis=1)


def robot_states(robot, q, dq, ddq) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A log's states ``(S, dof)`` as the robot's own: a floating root's six columns mapped by :func:`native_states`.

    Parameters
    ----------
    robot : Robot
        The robot (a floating root is its first body, its coordinates the first six).
    q, dq, ddq : array_like, shape ``(S, dof)``
        States, a floating base's as :data:`BASE_COORDINATES` and their time derivatives.

    Returns
    -------
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Copies, the root's six columns the robot's own (unchanged without a floating root).
    """
    q, dq, ddq = (np.array(np.atleast_2d(x), dtype=float) for x in (q, dq, ddq))
    if robot.floating:
        q[:, :6], dq[:, :6], ddq[:, :6] = native_states(robot.M0[0], q[:, :6], dq[:, :6], ddq[:, :6])
    return q, dq, ddq
