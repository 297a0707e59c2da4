"""Synthetic excitation trajectories and torques with a known parameter vector (tests, demos).

A user checking a pipeline simulates a log from the model with known parameters and noise, runs
the identification on it and compares: what comes back must be what went in, to the noise.
"""

from __future__ import annotations

import numpy as np

from ..analysis import analyze
from ..errors import BaseparamsError
from ..model.robot import Robot
from .drives import FRICTION_TERMS
from .model import IdentModel, ident_model

#: harmonics of :func:`simulate_log`'s random trajectory
SIM_HARMONICS = 5


def fourier_trajectory(m: int, duration: float, rate: float, rng: np.random.Generator, harmonics: int = 5,
                       base_frequency: float = 0.1, amplitude: float = 0.6,
                       center: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """A finite Fourier series per joint (Swevers et al. 1997), with exact derivatives.

    ``q_j(t) = c_j + sum_l a_lj / (l w) sin(l w t) - b_lj / (l w) cos(l w t)``, ``w = 2 pi f``,
    coefficients drawn normal and scaled so that each joint's peak excursion is about
    ``amplitude``.

    Parameters
    ----------
    m : int
        Number of joints.
    duration : float
        Length [s].
    rate : float
        Sampling rate [Hz].
    rng : numpy.random.Generator
        Source of the coefficients.
    harmonics : int
        Number of harmonics.
    base_frequency : float
        Fundamental frequency ``f`` [Hz].
    amplitude : float
        Approximate peak excursion of each joint [rad or m].
    center : ndarray, shape ``(m,)``, optional
        Offsets ``c`` (default zero).

    Returns
    -------
    t : ndarray, shape ``(S,)``
        Time [s], uniform.
    q, dq, ddq : ndarray, shape ``(S, m)``
        Positions, velocities and accelerations (exact).

    Raises
    ------
    BaseparamsError
        A non-positive duration or rate.
    """
    if not (duration > 0 and rate > 0):
        raise BaseparamsError(f"duration and rate must be > 0, got {duration} s and {rate} Hz")
    t = np.arange(int(round(duration * rate))) / rate
    w = 2 * np.pi * base_frequency * np.arange(1, harmonics + 1)  # (L,)
    a, b = fourier_draws(rng, harmonics, m)
    wt = np.outer(t, w)  # (S, L)
    s, c = np.sin(wt), np.cos(wt)
    q = s @ (a / w[:, None]) - c @ (b / w[:, None])
    dq = c @ a + s @ b
    ddq = -s @ (a * w[:, None]) + c @ (b * w[:, None])
    peak = np.abs(q - q.mean(axis=0)).max(axis=0)
    k = amplitude / np.where(peak > 0, peak, 1.0)
    off = (np.zeros(m) if center is None else np.asarray(center, dtype=float)) - (q * k).mean(axis=0)
    return t, q * k + off, dq * k, ddq * k


def fourier_draws(rng: np.random.Generator, harmonics: int, m: int) -> np.ndarray:
    """The random coefficients of :func:`fourier_trajectory` (the first draws of its ``rng``).

    Parameters
    ----------
    rng : numpy.random.Generator
        The source.
    harmonics, m : int
        Harmonics and joints.

    Returns
    -------
    ndarray, shape ``(2, harmonics, m)``
        Standard normal draws: the sine and cosine coefficients before scaling.
    """
    return rng.normal(size=(2, harmonics, m))


def add_noise(tau: np.ndarray, std, rng: np.random.Generator) -> np.ndarray:
    """Gaussian noise on the generalized forces.

    Parameters
    ----------
    tau : ndarray, shape ``(S, m)``
        Noise-free generalized forces.
    std : float or array_like, shape ``(m,)``
        Standard deviation per joint [N m or N].
    rng : numpy.random.Generator
        Source of the noise.

    Returns
    -------
    ndarray, shape ``(S, m)``
        ``tau`` plus noise.
    """
    return tau + rng.normal(size=tau.shape) * np.broadcast_to(np.asarray(std, dtype=float), tau.shape[1:])


def default_amplitude(robot: Robot) -> float:
    """The default joint excursion of a simulated log: 0.5, within a loop robot's sampling box.

    Parameters
    ----------
    robot : Robot
        The model.

    Returns
    -------
    float
        0.5 [rad or m]; for a robot with loops the largest of :func:`amplitude_ladder`.
    """
    return amplitude_ladder(robot)[0]


def amplitude_ladder(robot: Robot) -> list[float]:
    """Default excursions to try, largest first: a loop robot's loops may not close on the first.

    Parameters
    ----------
    robot : Robot
        The model.

    Returns
    -------
    list of float
        ``[0.5]`` [rad or m] for a tree; for a robot with loops ``a, a/2, a/4, a/8`` with ``a``
        0.8 of its sampling box's narrowest half-width (``q_box``), at most 0.5: the largest
        motion excites best (a four-bar's crank at a fifth of its box gave condition numbers near
        1e8, at 0.8 near 3e5), the smaller ones for workspaces narrower than the box.
    """
    if robot.has_loops and robot.q_box is not None:
        half = 0.5 * (np.asarray(robot.q_box)[:, 1] - np.asarray(robot.q_box)[:, 0])
        top = float(min(0.5, 0.8 * half.min()))
        return [top, top / 2, top / 4, top / 8]
    return [0.5]


#: bytes of regressor formed at once for a robot with loops (a tree's torques need none)
_BLOCK_BYTES = 32e6


def simulate_log(robot: Robot, duration: float = 20.0, rate: float = 500.0, amplitude: float | None = None,
                 noise: float = 0.0, seed: int = 0, rotor: bool = False, friction=FRICTION_TERMS,
                 convention: str = "khalil", trajectory=None, samples: int | None = None):
    """A synthetic joint log, with its true model parameters.

    A floating base moves too: its position [m] and Z-Y-X angles [rad] follow Fourier series like
    the joints (``amplitude`` each); the log holds its pose and twist (docs/guides/log-layout.md) and
    the torques of the joints alone (the base wrench that carries it is not measured), the
    truth the base parameters those torques determine.

    Parameters
    ----------
    robot : Robot
        The model (a tree, fixed or floating base; loops closed by the actuated joints).
    duration, rate : float
        Length [s] and sampling rate [Hz].
    amplitude : float, optional
        Joint excursion of the Fourier excitation [rad or m] (default :func:`default_amplitude`).
    noise : float
        Standard deviation of the Gaussian torque noise [N m or N].
    seed : int
        Seed of the trajectory's coefficients (drawn, or skipped with ``trajectory``: the same drive
        parameters, the same robot, either way), then of the drive parameters and the noise.
    rotor : bool
        Include rotor inertias (the model's armature where it has one, else drawn in 0.01-0.1).
    friction : iterable of str
        Friction terms (drawn: ``Fv`` in 0.05-0.5, ``Fc`` in 0.1-1, ``Fo`` in -0.2-0.2).
    convention : str
        Convention of the true base parameters written out.
    trajectory : tuple of ndarray, optional
        ``(t (S,), q, dq, ddq (S, state_columns))``: the motion to simulate (e.g. a designed
        excitation, :func:`baseparams.excitation.read_trajectory`) instead of a random Fourier series
        (``duration``, ``rate`` and ``amplitude`` are then ignored).
    samples : int, optional
        Random states of the base-parameter analysis (default: the analysis's own).

    Returns
    -------
    log : JointLog
        ``t``, ``q``, ``dq`` and ``tau`` of the measured joints (no accelerations, like a real log).
    truth : dict
        ``{"model", "convention", "noise", "parameters": [{"name", "value"}], "drives": {name: value}}``:
        the model parameters an identification should return.

    Raises
    ------
    BaseparamsError
        Loops the trajectory does not close (lower ``amplitude``); a trajectory for a floating base.
    """
    from ..jointlog import JointLog
    from ..kinematics.floating import BASE_COORDINATES

    check_trajectory(robot, trajectory)
    rows = "joints" if robot.floating else "all"
    model = ident_model(analyze(robot, samples=samples, convention=convention, rows=rows), rotor, tuple(friction),
                        log_base=robot.floating)
    if amplitude is not None and not amplitude > 0:
        raise BaseparamsError(f"amplitude must be > 0 rad, got {amplitude}")
    ladder = [amplitude] if amplitude is not None or trajectory is not None else amplitude_ladder(robot)
    for k, amp in enumerate(ladder):
        rng = np.random.default_rng(seed)
        if trajectory is None:
            t, q, dq, ddq = fourier_trajectory(model.state_columns, duration, rate, rng, SIM_HARMONICS, amplitude=amp)
        else:  # the draws a random trajectory takes, skipped: the same drives (the same robot) either way
            fourier_draws(rng, SIM_HARMONICS, model.state_columns)
            t, q, dq, ddq = (np.asarray(x, dtype=float) for x in trajectory)
        delta = _draw_drives(model, rng)
        try:
            rigid = rigid_torques(robot, model, q, dq, ddq)
        except BaseparamsError as exc:
            if k + 1 == len(ladder) or "close the loops" not in str(exc):
                raise
            continue  # the loops do not close that far: a smaller default excursion
        break
    sel = model.row_states
    tau = rigid + model.drives.torques(dq[:, sel], ddq[:, sel], len(model.coords), delta)
    tau = add_noise(tau, noise, rng) if noise > 0 else tau
    joints = tuple(model.joints)
    if robot.floating:  # the base's coordinates first, its wrench not measured
        joints, tau = BASE_COORDINATES + joints, np.concatenate([np.zeros((len(t), 6)), tau], axis=1)
    log = JointLog(t, joints, q, tau, dq=dq, source=f"simulated {robot.name}")
    theta = model.theta(robot.parameters("paper"), delta)
    truth = {"model": robot.name, "convention": convention, "noise": noise,
             **({"amplitude": float(amp)} if trajectory is None else {}),
             "parameters": [{"name": n, "value": float(v)} for n, v in zip(model.names, theta)],
             "drives": dict(zip(model.drives.names, delta.tolist()))}
    return log, truth


def rigid_torques(robot: Robot, model: IdentModel, q, dq, ddq) -> np.ndarray:
    """The rigid bodies' generalized forces of the measured rows, the robot's own parameters.

    A tree's by inverse dynamics (:func:`baseparams.regressor.tp.generalized_forces`: ``O(S n)``
    work and memory, no regressor); a loop robot's through its closed regressor, a bounded block
    of samples at a time.

    Parameters
    ----------
    robot : Robot
        The robot.
    model : IdentModel
        Its identification model (the measured rows, a floating base's log coordinates).
    q, dq, ddq : ndarray, shape ``(S, state_columns)``
        States (a floating base's six first, in the log's coordinates).

    Returns
    -------
    ndarray, shape ``(S, m)``
        ``Y pi`` on the measured rows [N m or N].

    Raises
    ------
    BaseparamsError
        States that do not close the loops.
    """
    from ..kinematics.floating import robot_states
    from ..regressor.tp import generalized_forces

    pi = robot.parameters("paper")
    q, dq, ddq = robot_states(robot, q, dq, ddq)
    if not robot.has_loops:
        return generalized_forces(robot, q, dq, ddq, pi, rows=model.coords)
    step = max(1, int(_BLOCK_BYTES // (8 * max(len(model.coords), 1) * 10 * robot.n)))
    return np.concatenate([regressor_of(robot, q[i:i + step], dq[i:i + step], ddq[i:i + step]) @ pi
                           for i in range(0, max(len(q), 1), step)])


def check_trajectory(robot: Robot, trajectory) -> None:
    """Refuse a given trajectory for a floating base (its motion is drawn, not read from a trajectory file).

    Parameters
    ----------
    robot : Robot
        The model.
    trajectory : object or None
        The trajectory given, if any.

    Raises
    ------
    BaseparamsError
        A trajectory for a floating base.
    """
    if robot.floating and trajectory is not None:
        raise BaseparamsError(f"robot {robot.name!r}: a floating base's motion is not in a trajectory file; simulate "
                              "draws it (without a trajectory)")


def regressor_of(robot: Robot, q, dq, ddq) -> np.ndarray:
    """The full regressor of the measured rows (a tree's coordinates, a loop robot's actuated).

    Parameters
    ----------
    robot : Robot
        The robot (fixed base).
    q, dq, ddq : ndarray, shape ``(S, state_columns)``
        States.

    Returns
    -------
    ndarray, shape ``(S, m, 10 n)``
        ``paper`` convention columns (:func:`baseparams.analysis.regressor`).
    """
    from ..analysis import regressor

    return regressor(robot, q, dq, ddq)


def _draw_drives(model: IdentModel, rng: np.random.Generator) -> np.ndarray:
    """Plausible drive parameters: armature where the model has it, friction drawn."""
    arm = model.robot.armature
    out = []
    for row in model.drives.rows:
        coord = model.coords[row]
        for kind in model.drives.kinds:
            if kind == "Ia":
                out.append(float(arm[coord]) if arm is not None and arm[coord] > 0 else rng.uniform(0.01, 0.1))
            else:
                lo, hi = {"Fv": (0.05, 0.5), "Fc": (0.1, 1.0), "Fo": (-0.2, 0.2)}[kind]
                out.append(rng.uniform(lo, hi))
    return np.array(out)
