"""An independent simulator of payload logs: MuJoCo's forward dynamics, servo-tracked, with drive effects.

A robot arm read by MuJoCo's own URDF/MJCF compiler, with armature, viscous damping and Coulomb
friction loss on its joints and a payload welded to a link as a body of its own (a rigid body at a
pose: its frame the payload's principal axes). A motor per joint tracks a desired trajectory with a
computed-torque servo built on the *nominal* arm (no payload, no friction loss: the servo does not
know what it carries), integrated by MuJoCo at 1 kHz; the log is the joint positions, velocities and
the motors' torques (``qfrc_actuator``) with correlated (AR(1)) noise of a given fraction of each
joint's RMS torque. Uses only ``mujoco``, numpy and scipy (the noise filter), nothing of ``baseparams``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Payload:
    """A rigid payload on ``link``: mass [kg], centre of mass [m] and principal moments [kg m^2], rotated.

    ``com`` is in the link's frame; ``quat`` (w, x, y, z) rotates the principal axes into the link's.
    """

    link: str
    mass: float
    com: tuple
    moments: tuple
    quat: tuple = (1.0, 0.0, 0.0, 0.0)

    def rotation(self) -> np.ndarray:
        w, x, y, z = np.asarray(self.quat, dtype=float) / np.linalg.norm(self.quat)
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])

    def inertia_com(self) -> np.ndarray:
        """The inertia about the centre of mass in the link's axes ``(3, 3)``."""
        r = self.rotation()
        return r @ np.diag(self.moments) @ r.T


def random_payload(link: str, rng, mass: float | None = None, reach: float = 0.12) -> Payload:
    """A box-like payload of a random size, off-axis, rotated (principal moments of a solid box)."""
    mass = float(rng.uniform(0.2, 10.0)) if mass is None else float(mass)
    sides = rng.uniform(0.04, 0.2, 3)
    moments = mass / 12.0 * np.array([sides[1] ** 2 + sides[2] ** 2, sides[0] ** 2 + sides[2] ** 2,
                                      sides[0] ** 2 + sides[1] ** 2])
    com = rng.uniform(-reach, reach, 3) + np.array([0.0, 0.0, 0.1])
    q = rng.normal(size=4)
    return Payload(link, mass, tuple(com), tuple(moments), tuple(q / np.linalg.norm(q)))


def arm(path, armature, damping, frictionloss, payload: Payload | None = None, timestep: float = 1e-3):
    """The MuJoCo model of the arm in ``path`` with drive effects and the payload; one motor per joint."""
    return arm_spec(path, armature, damping, frictionloss, payload, timestep).compile()


def arm_spec(path, armature, damping, frictionloss, payload: Payload | None = None, timestep: float = 1e-3):
    """:func:`arm`'s ``MjSpec`` (``.to_xml()``: the arm as an MJCF file, e.g. a model file with its armature)."""
    import mujoco

    spec = mujoco.MjSpec.from_file(str(path))
    spec.option.timestep = timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    joints = [j for j in spec.joints]
    for k, j in enumerate(joints):
        j.armature = float(np.broadcast_to(armature, len(joints))[k])
        j.damping = [float(np.broadcast_to(damping, len(joints))[k]), 0.0, 0.0]  # linear damping only
        j.frictionloss = float(np.broadcast_to(frictionloss, len(joints))[k])
        j.limited = 0
        a = spec.add_actuator()
        a.name, a.target = f"m_{j.name}", j.name
        a.trntype = mujoco.mjtTrn.mjTRN_JOINT
        a.ctrllimited = 0
    if payload is not None:
        b = spec.body(payload.link).add_body(name="payload", pos=list(payload.com), quat=list(payload.quat))
        b.explicitinertial = 1
        b.mass = payload.mass
        b.inertia = list(payload.moments)
        b.ipos = [0.0, 0.0, 0.0]
        b.iquat = [1.0, 0.0, 0.0, 0.0]
    return spec


def fourier(t, m, rng, amplitude=0.6, base_frequency=0.2, harmonics=4, move=None, centre=None):
    """A Fourier trajectory ``(q, dq, ddq)`` of ``m`` joints; ``move`` masks the joints that move."""
    w = 2 * np.pi * base_frequency
    q, dq, ddq = (np.zeros((len(t), m)) for _ in range(3))
    move = np.ones(m, dtype=bool) if move is None else np.asarray(move, dtype=bool)
    for j in np.flatnonzero(move):
        a, b = rng.normal(size=(2, harmonics)) / np.arange(1, harmonics + 1)
        phase = np.outer(t, np.arange(1, harmonics + 1)) * w
        x = (a * np.sin(phase) + b * (np.cos(phase) - 1.0)).sum(axis=1)
        scale = amplitude / max(np.abs(x).max(), 1e-9)
        k = np.arange(1, harmonics + 1) * w
        q[:, j] = scale * x
        dq[:, j] = scale * (a * k * np.cos(phase) - b * k * np.sin(phase)).sum(axis=1)
        ddq[:, j] = scale * (-a * k**2 * np.sin(phase) - b * k**2 * np.cos(phase)).sum(axis=1)
    if centre is not None:
        q = q + np.asarray(centre, dtype=float)
    return q, dq, ddq


def simulate(true_model, nominal_model, q_d, dq_d, ddq_d, rng, noise: float = 0.015, ar: float = 0.9,
             bandwidth: float = 8.0):
    """Track the desired states with a computed-torque servo on the nominal model; the log of the true one.

    Returns ``(t, q, dq, tau)``: every step's positions, velocities and motor torques, the torques with
    AR(1) noise of ``noise`` times each joint's RMS torque.
    """
    import mujoco

    d, dn = mujoco.MjData(true_model), mujoco.MjData(nominal_model)
    kp, kd = (2 * np.pi * bandwidth) ** 2, 2 * 0.9 * 2 * np.pi * bandwidth
    n = len(q_d)
    q, dq, tau = np.zeros((n, true_model.nv)), np.zeros((n, true_model.nv)), np.zeros((n, true_model.nv))
    d.qpos[:], d.qvel[:] = q_d[0], dq_d[0]
    mujoco.mj_forward(true_model, d)
    for k in range(n):
        dn.qpos[:], dn.qvel[:] = d.qpos, d.qvel
        dn.qacc[:] = ddq_d[k] + kd * (dq_d[k] - d.qvel) + kp * (q_d[k] - d.qpos)
        mujoco.mj_inverse(nominal_model, dn)
        d.ctrl[:] = dn.qfrc_inverse
        q[k], dq[k] = d.qpos, d.qvel
        mujoco.mj_step(true_model, d)
        tau[k] = d.qfrc_actuator
    t = np.arange(n) * true_model.opt.timestep
    e = rng.normal(size=tau.shape)
    from scipy.signal import lfilter

    e = lfilter([np.sqrt(1 - ar**2)], [1, -ar], e, axis=0)
    tau = tau + noise * np.sqrt(np.mean(tau**2, axis=0)) * e
    return t, q, dq, tau
