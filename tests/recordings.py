"""Simulated recordings with the defects real logs have (tests and the cross-recording benchmark).

Written apart from the identification's model terms: the true torques are the rigid-body torques
of a *true* robot (which may differ from the model file: a payload, inertias off, rounded angles,
a tilted mounting: gravity rotated), plus friction with pre-sliding integrated as Dahl's ODE by
explicit Euler sub-steps (not the identification's exact scan), then what the sensor does to them:
a scale, a delay (the torque's own samples shifted), a first-order lag, coloured (AR(1)) noise.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.signal import lfilter

import baseparams
from baseparams.jointlog import JointLog


@dataclass
class Plant:
    """What a recording is made of: the true robot and what friction and the sensors do.

    ``Fv``, ``Fc``, ``Fo`` per joint; ``dahl`` the pre-sliding distance [rad] (0: ``sign``);
    ``tilt`` a rotation vector [rad] applied to gravity; ``delay`` [s] and ``scale`` per joint;
    ``lag`` a first-order time constant [s]; ``noise`` the std [N m] of AR(1) noise with
    coefficient ``ar``.
    """

    robot: object
    Fv: np.ndarray
    Fc: np.ndarray
    Fo: np.ndarray
    dahl: float = 0.0
    tilt: np.ndarray = field(default_factory=lambda: np.zeros(3))
    delay: np.ndarray | None = None
    scale: np.ndarray | None = None
    lag: float = 0.0
    noise: float = 0.02
    ar: float = 0.0


def friction_of(robot, rng, scale: float = 1.0) -> dict:
    m = robot.dof
    return {"Fv": scale * rng.uniform(0.05, 0.4, m), "Fc": scale * rng.uniform(0.2, 1.0, m),
            "Fo": scale * rng.uniform(-0.2, 0.2, m)}


def motion(m: int, duration: float, rate: float, rng, amplitude: float = 0.8, base_frequency: float = 0.2,
           harmonics: int = 4, creep: np.ndarray | None = None):
    """A Fourier excitation; ``creep`` [rad/s] per joint adds a ramp so large that the joint never reverses."""
    from baseparams.ident.simulate import fourier_trajectory

    t, q, dq, ddq = fourier_trajectory(m, duration, rate, rng, harmonics=harmonics, base_frequency=base_frequency,
                                       amplitude=amplitude)
    if creep is not None:
        c = np.asarray(creep, dtype=float)
        move = c != 0
        # a ramp faster than the oscillation: the joint never reverses
        bump = np.where(move, np.abs(dq).max(axis=0) * 1.3 + np.abs(c), 0.0) * np.sign(np.where(move, c, 1.0))
        q = q + np.outer(t - t.mean(), bump)
        dq = dq + bump
    return t, q, dq, ddq


def dahl_ode(q: np.ndarray, delta: float, substeps: int = 20) -> np.ndarray:
    """Dahl's state by explicit Euler on ``dz = (1 - z sgn(dq)) dq / delta``, ``substeps`` per sample."""
    z = np.zeros_like(q)
    cur = np.zeros(q.shape[1])
    for k in range(1, len(q)):
        step = (q[k] - q[k - 1]) / substeps
        for _ in range(substeps):
            cur = cur + (1.0 - cur * np.sign(step)) * step / delta
        z[k] = np.clip(cur, -1.0, 1.0)
    return z


def record(plant: Plant, t, q, dq, ddq, rng, name: str = "sim") -> JointLog:
    """The recording of a motion on the plant."""
    r = plant.robot
    g = plant.robot.gravity
    if np.any(plant.tilt):
        from scipy.spatial.transform import Rotation

        g = Rotation.from_rotvec(plant.tilt).apply(g)
    truth = replace(r, gravity=g)
    tau = baseparams.regressor(truth, q, dq, ddq) @ truth.parameters("paper")
    coul = dahl_ode(q, plant.dahl) if plant.dahl > 0 else np.sign(dq)
    tau = tau + plant.Fv * dq + plant.Fc * coul + plant.Fo
    if plant.scale is not None:
        tau = tau * plant.scale
    if plant.delay is not None:
        tau = np.column_stack([np.interp(t - d, t, tau[:, j]) for j, d in enumerate(plant.delay)])
    if plant.lag > 0:
        a = np.exp(-1.0 / (plant.lag * (len(t) - 1) / (t[-1] - t[0])))
        tau = lfilter([1 - a], [1, -a], tau, axis=0, zi=tau[:1] * a)[0]
    e = rng.normal(size=tau.shape)
    if plant.ar:
        e = lfilter([np.sqrt(1 - plant.ar**2)], [1, -plant.ar], e, axis=0)
    tau = tau + plant.noise * e
    return JointLog(t, tuple(r.joint_names), q, tau, dq=dq, source=name)


def perturbed_file(robot, rng, inertia_error: float = 0.3):
    """The model file a user has: every body's mass, first and second moments off by up to ``inertia_error``."""
    kh = robot.parameters("khalil").reshape(robot.n, 10).copy()
    kh *= 1.0 + inertia_error * rng.uniform(-1, 1, (robot.n, 1))
    return robot.with_parameters(kh.reshape(-1), "khalil")


def with_payload(robot, mass: float, offset=(0.0, 0.0, 0.05)):
    """The true robot: a point mass on the last body (the file does not have it)."""
    kh = robot.parameters("khalil").reshape(robot.n, 10).copy()
    c = np.asarray(offset, dtype=float)
    kh[-1, 9] += mass
    kh[-1, 6:9] += mass * c
    kh[-1, 0] += mass * (c[1] ** 2 + c[2] ** 2)
    kh[-1, 3] += mass * (c[0] ** 2 + c[2] ** 2)
    kh[-1, 5] += mass * (c[0] ** 2 + c[1] ** 2)
    kh[-1, 1] -= mass * c[0] * c[1]
    kh[-1, 2] -= mass * c[0] * c[2]
    kh[-1, 4] -= mass * c[1] * c[2]
    return robot.with_parameters(kh.reshape(-1), "khalil")


#: the time constant [s] of the excursion to the extreme poses at both ends of a motion (:func:`recorder_motion`)
END_SECONDS = 2.0


def recorder_motion(robot, seconds: float, rate: float, rng, base_frequency: float, jitter: float,
                    recorder_cutoff: float | None, noise: float, ar: float, name: str, ends=None, plant_robot=None,
                     friction=None):
    """A recording like a service arm's: a slow Fourier motion sampled at uneven stamps, torques low-passed by
    the recorder (a causal 2nd-order Butterworth at ``recorder_cutoff`` Hz), AR(1) noise, friction.

    The motion is computed on a grid 10x finer than ``rate``; the log keeps the samples nearest to uneven
    stamps ``k / rate + U(-jitter, jitter) / rate``. ``ends`` [rad] per joint: the motion starts and ends at its
    extreme poses (``ends * (exp(-t / END_SECONDS) + exp(-(T - t) / END_SECONDS))`` added: the poses
    within a few seconds of either end are visited nowhere else). ``plant_robot``: the true robot when it is
    not ``robot``; ``friction``: the plant's friction (:func:`friction_of`), the same for every motion of one
    plant.
    """
    from scipy.signal import butter

    fine = 10.0 * rate
    t, q, dq, ddq = motion(robot.dof, seconds, fine, rng, amplitude=1.0 if ends is None else 0.6,
                           base_frequency=base_frequency, harmonics=4)
    if ends is not None:  # a pose reached within END_SECONDS of either end and nowhere else, within the limits
        lim = np.asarray(robot.limits, dtype=float)[:, :2] if robot.limits is not None else np.zeros((robot.dof, 2))
        q = q + np.where(np.isfinite(lim).all(axis=1), lim.mean(axis=1), 0.0)
        e, tc = np.asarray(ends, dtype=float), END_SECONDS
        a, b = np.exp(-t / tc), np.exp(-(seconds - t) / tc)
        q, dq, ddq = q + np.outer(a + b, e), dq + np.outer((b - a) / tc, e), ddq + np.outer((a + b) / tc**2, e)
    plant = Plant(plant_robot or robot, **(friction or friction_of(robot, rng)), noise=0.0)
    log = record(plant, t, q, dq, ddq, rng, name)
    tau = log.tau
    if recorder_cutoff is not None:
        b, a = butter(2, recorder_cutoff / (fine / 2))
        tau = lfilter(b, a, tau - tau[0], axis=0) + tau[0]
    stamps = (np.arange(int(seconds * rate)) + rng.uniform(-jitter, jitter, int(seconds * rate))) / rate
    idx = np.unique(np.clip(np.rint(stamps * fine).astype(int), 0, len(t) - 1))
    e = rng.normal(size=(len(idx), robot.dof))
    e = lfilter([np.sqrt(1 - ar**2)], [1, -ar], e, axis=0)
    return replace(log, t=t[idx], q=q[idx], dq=None, ddq=None, tau=tau[idx] + noise * e)


@dataclass
class Motors:
    """The motors behind an arm without joint-torque sensors (issue 50).

    ``gains`` [N m/A at the joint side] per motor; ``rotor`` the reflected rotor inertia per joint
    [kg m^2]; ``matrix`` the transmission ``C`` (joints x motors: ``tau = C diag(k) i``; None: the
    identity); ``noise`` the current noise as a torque [N m] per motor (AR(1) with ``ar``);
    ``sensor_noise`` [N m] of the joint-torque sensors after the gears (white).
    """

    gains: np.ndarray
    rotor: np.ndarray
    matrix: np.ndarray | None = None
    noise: float = 0.05
    ar: float = 0.0
    sensor_noise: float = 0.0


def record_currents(plant: Plant, motors: Motors, t, q, dq, ddq, rng, name: str = "sim") -> JointLog:
    """A recording of currents and of joint-torque sensors after the gears, written apart from the estimator.

    The sensor reads the rigid body's torque (the plant's true robot, gravity tilted as the plant
    says), plus its noise. The motors make it plus what lies before the sensor: each joint's rotor
    inertia ``Ia ddq`` and the plant's friction (Dahl's pre-sliding when the plant has it); the
    currents are ``diag(k)^-1 C^-1`` of that, plus AR(1) noise (``motors.noise / |k|`` amperes).
    """
    from scipy.spatial.transform import Rotation

    r = plant.robot
    g = Rotation.from_rotvec(plant.tilt).apply(r.gravity) if np.any(plant.tilt) else r.gravity
    truth = replace(r, gravity=g)
    rigid = baseparams.regressor(truth, q, dq, ddq) @ truth.parameters("paper")
    coul = dahl_ode(q, plant.dahl) if plant.dahl > 0 else np.sign(dq)
    motor_side = rigid + motors.rotor * ddq + plant.Fv * dq + plant.Fc * coul + plant.Fo
    c = np.eye(r.dof) if motors.matrix is None else np.asarray(motors.matrix, dtype=float)
    cur = np.linalg.solve(c, motor_side.T).T / motors.gains
    e = rng.normal(size=cur.shape)
    if motors.ar:
        e = lfilter([np.sqrt(1 - motors.ar**2)], [1, -motors.ar], e, axis=0)
    cur = cur + e * motors.noise / np.abs(motors.gains)
    tau = rigid + motors.sensor_noise * rng.normal(size=rigid.shape)
    return JointLog(t, tuple(r.joint_names), q, tau, dq=dq, source=name, cur=cur)
