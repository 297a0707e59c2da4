"""Excitation trajectories: the motion that identifies every base parameter, within the limits.

A finite Fourier series per designed coordinate (Swevers et al. 1997): the joints of a tree, or a
robot with loops' actuated coordinates, the passive ones following from the loop closure,

``q_j(t) = q0_j + sum_l a_lj / (l w) sin(l w t) - b_lj / (l w) cos(l w t)``, ``w = 2 pi f``,

so ``dq_j = sum_l a_lj cos(l w t) + b_lj sin(l w t)`` and ``ddq_j = sum_l l w (b_lj cos - a_lj sin)``
(exact derivatives, period ``T = 1 / f``). **Rest at both ends**: ``dq(0) = sum_l a_l = 0`` and
``ddq(0) = w sum_l l b_l = 0`` are imposed by eliminating the first harmonic's coefficients,
``a_1 = -sum_{l>=2} a_l`` and ``b_1 = -sum_{l>=2} l b_l``; the series is periodic, so the motion is
at rest at ``t = T`` too and can be repeated. The free variables per coordinate are the offset
``q0`` and ``a_l, b_l`` for ``l = 2..L`` (:func:`fourier_basis`).

Criterion, on the identification model's regressor (:class:`~baseparams.ident.pipeline.IdentModel`:
the certified base parameters, and the drive columns when asked), evaluated on a coarse grid of
one period (``grid`` samples): ``cond``, the condition number of the column-scaled stacked
regressor (minimised as ``log cond``), or ``logdet``, D-optimality, ``log det`` of the
information matrix per sample (maximised; independent of the parameters' units up to a
constant). ``cond`` balances the columns whatever their size (it does not reward a larger
motion); ``logdet`` rewards information, hence smaller standard deviations under noise. The
gradient is exact up to finite differences of the regressor per state column (the regressor of a
sample depends on that sample's state only, so ``3 m + 1`` batched evaluations give every
sample's derivative at once; at ``|dq| < 2e-6`` the velocity derivative is dropped: Coulomb
friction's ``sign(dq)`` jumps there).

Constraints, on the same grid: position, velocity and acceleration limits (linear in the
coefficients; every :data:`LIMIT_STRIDE`-th sample), optionally the torques of the model's own
(prior) parameters within the effort limits and, for loops, ``cond(J_p) <= cond_max`` at every
sample (which keeps the motion inside the workspace, away from singularities, and on the
reference assembly mode reached by continuation from q = 0). SLSQP from several seeded random
starts; the best design is then sampled at the controller's rate, each coordinate's oscillation
scaled down if a sample there exceeds a limit, and checked (loops: every sample closed with
``cond(J_p) <= cond_max``).
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .analysis import Analysis, analyze
from .display import clip, format_number
from .errors import BaseparamsError
from .files import check_input
from .ident.model import IdentModel, ident_model
from .model.robot import Robot

#: the criteria: ``cond`` (column-scaled condition number) and ``logdet`` (D-optimality)
CRITERIA = ("cond", "logdet")
#: position range around q = 0 of a coordinate whose limits the model does not give [rad, m]
DEFAULT_RANGE = {"R": 1.0, "P": 0.1}
#: a loop robot whose reference cond(J_p) is above this is singular there
SINGULAR_COND = 1e6
#: the limits used while optimising are this fraction of the given ones (the controller-rate check
#: then rarely has to scale anything)
MARGIN = 0.99
#: the bound on cond(J_p) while optimising is this fraction of the one checked at the controller's rate
LOOP_MARGIN = 0.9
#: position, velocity and acceleration limits are imposed on every LIMIT_STRIDE-th sample of the design grid
LIMIT_STRIDE = 2
#: finite-difference steps of the regressor per state column: q, dq (rad, rad/s), ddq (exact: linear)
STEPS = (1e-6, 1e-6, 1.0)
#: a point counts as feasible while optimising when no constraint row (fractions of the limits; log
#: cond(J_p)) is violated by more than this (inside the margins above)
FEAS_TOL = 5e-3
#: a start stops when its best value has not improved by STALL[0] (log cond, or logdet / p) in STALL[1] iterations
STALL = (1e-3, 20)
#: the keep-out height is raised by this [m] while optimising (the controller-rate check then rarely scales)
KEEPOUT_MARGIN = 0.01
#: a design whose condition number is above this does not excite the model
COND_LIMIT = 1e8


@dataclass(frozen=True, eq=False)
class Excitation:
    """A designed excitation trajectory (:func:`design_excitation`).

    Parameters
    ----------
    robot : str
        The robot's name.
    joints : tuple of str, shape ``(m,)``
        The designed coordinates' joint names (a tree's joints; a loop robot's actuated ones).
    harmonics : int
        Harmonics ``L`` of the series.
    base_frequency : float
        ``f`` [Hz]; the period is ``1 / f``.
    rate : float
        Sampling rate of :attr:`t` [Hz] (the controller's).
    offsets : ndarray, shape ``(m,)``
        ``q0`` [rad or m].
    a, b : ndarray, shape ``(L, m)``
        Sine and cosine coefficients of the velocity [rad/s or m/s] (module doc), at rest at both
        ends.
    t : ndarray, shape ``(S,)``
        Time [s], ``0, 1/rate, ..., T`` (one period, both ends included).
    q, dq, ddq : ndarray, shape ``(S, m)``
        Positions, velocities, accelerations of the designed coordinates.
    criterion : str
        ``cond`` or ``logdet``.
    value : float
        The criterion at the controller's rate over one period: the condition number (``cond``)
        or ``log det`` of the information matrix per sample (``logdet``; SI units).
    condition_number : float
        Condition number of the column-scaled model regressor over :attr:`t`.
    limits : ndarray, shape ``(m, 5)``
        The limits used: ``lower, upper`` [rad or m], ``velocity``, ``acceleration``, ``effort``
        (NaN: not constrained).
    parameters : tuple of str
        The model parameters the criterion was computed on (base, then drive parameters).
    notes : tuple of str
        Defaults taken, scaling applied, loop conditioning, timings: one line each.
    """

    robot: str
    joints: tuple[str, ...]
    harmonics: int
    base_frequency: float
    rate: float
    offsets: np.ndarray
    a: np.ndarray
    b: np.ndarray
    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    criterion: str
    value: float
    condition_number: float
    limits: np.ndarray
    parameters: tuple[str, ...] = ()
    notes: tuple[str, ...] = field(default_factory=tuple)

    def __repr__(self) -> str:
        crit = "" if self.criterion == "cond" else f"{self.criterion} {format_number(self.value, 4)}, "
        return clip(f"<Excitation {self.robot}: {len(self.joints)} joints, {self.harmonics} harmonics of "
                    f"{format_number(self.base_frequency, 4)} Hz, {crit}condition number "
                    f"{format_number(self.condition_number, 4)}, {len(self.t)} samples at "
                    f"{format_number(self.rate, 6)} Hz>")

    @property
    def period(self) -> float:
        """The period ``T = 1 / f`` [s]."""
        return 1.0 / self.base_frequency

    def states(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The series at any times.

        Parameters
        ----------
        t : array_like, shape ``(S,)``
            Times [s] (any; the series is periodic).

        Returns
        -------
        q, dq, ddq : ndarray, shape ``(S, m)``
            Positions, velocities and accelerations, exact.
        """
        x = np.column_stack([self.offsets, free_coefficients(self.a, self.b)])
        bq, bv, ba = fourier_basis(np.asarray(t, dtype=float), self.harmonics, 2 * np.pi * self.base_frequency)
        return bq @ x.T, bv @ x.T, ba @ x.T

    def to_csv(self, path) -> Path:
        """Write the trajectory: ``t, q_<joint>..., dq_<joint>..., ddq_<joint>...`` (header line).

        The identification logs' default layout without torques: it feeds a robot controller and
        ``baseparams simulate --trajectory`` (:func:`read_trajectory`).

        Parameters
        ----------
        path : str or Path
            ``.csv`` (comma-separated) or ``.tsv`` (tab-separated).

        Returns
        -------
        Path
            The file written.

        Raises
        ------
        BaseparamsError
            Another suffix, or a file that cannot be written.
        """
        from .io.logs import write_table

        cols = {"t": self.t}
        for kind, arr in (("q", self.q), ("dq", self.dq), ("ddq", self.ddq)):
            cols.update({f"{kind}_{j}": arr[:, k] for k, j in enumerate(self.joints)})
        return write_table(path, cols, "a trajectory as .csv or .tsv")

    def to_json(self) -> dict:
        """The design as one JSON-able object (no sampled arrays: :meth:`to_csv` writes those).

        Returns
        -------
        dict
            ``robot, joints, harmonics, base_frequency, period, rate, samples, criterion, value,
            condition_number, parameters, offsets, a, b`` (``[L][m]``), ``limits`` (per joint:
            ``lower, upper, velocity, acceleration, effort``, null where not constrained),
            ``reached`` (per joint: ``min, max, max_velocity, max_acceleration``) and ``notes``.
        """
        def clean(x):
            return [None if not np.isfinite(v) else float(v) for v in x]

        keys = ("lower", "upper", "velocity", "acceleration", "effort")
        return {"robot": self.robot, "joints": list(self.joints), "harmonics": self.harmonics,
                "base_frequency": self.base_frequency, "period": self.period, "rate": self.rate,
                "samples": len(self.t), "criterion": self.criterion, "value": self.value,
                "condition_number": self.condition_number, "parameters": list(self.parameters),
                "offsets": self.offsets.tolist(), "a": self.a.tolist(), "b": self.b.tolist(),
                "limits": {j: dict(zip(keys, clean(row))) for j, row in zip(self.joints, self.limits)},
                "reached": {j: {"min": float(self.q[:, k].min()), "max": float(self.q[:, k].max()),
                                "max_velocity": float(np.abs(self.dq[:, k]).max()),
                                "max_acceleration": float(np.abs(self.ddq[:, k]).max())}
                            for k, j in enumerate(self.joints)},
                "notes": list(self.notes)}

    def summary(self) -> str:
        """A text summary: criterion, limits used and reached, notes.

        Returns
        -------
        str
            A header line, one line per coordinate (offset, range, peak velocity and acceleration
            against the limits) and the notes.
        """
        lines = [f"{self.robot}: excitation, {self.harmonics} harmonics, base frequency {self.base_frequency:.6g} Hz "
                 f"(period {self.period:.6g} s), {len(self.t)} samples at {self.rate:g} Hz; criterion {self.criterion} "
                 f"{self.value:.6g}, condition number {self.condition_number:.6g} ({len(self.parameters)} parameters)",
                 f"  {'joint':<20s} {'offset':>8s} {'min':>8s} {'max':>8s} {'lower':>8s} {'upper':>8s} "
                 f"{'|dq|':>7s} {'vmax':>7s} {'|ddq|':>7s} {'amax':>7s}"]
        def lim(x, width, digits):  # a limit, or '-' where none is set
            return f"{x:{width}.{digits}f}" if np.isfinite(x) else f"{'-':>{width}s}"

        for j, name in enumerate(self.joints):
            lo, hi, v, acc, _ = self.limits[j]
            lines.append(f"  {name:<20s} {self.offsets[j]:8.4f} {self.q[:, j].min():8.4f} {self.q[:, j].max():8.4f} "
                         f"{lim(lo, 8, 4)} {lim(hi, 8, 4)} {np.abs(self.dq[:, j]).max():7.3f} {lim(v, 7, 3)} "
                         f"{np.abs(self.ddq[:, j]).max():7.3f} {lim(acc, 7, 3)}")
        if not np.all(np.isfinite(self.limits[:, 2:4])):
            lines.append("  (-: no limit set)")
        return "\n".join(lines + [f"note: {n}" for n in self.notes])


def rest_map(harmonics: int) -> np.ndarray:
    """The map from free coefficients to all of them, at rest at ``t = 0``.

    Parameters
    ----------
    harmonics : int
        ``L >= 2``.

    Returns
    -------
    ndarray, shape ``(2 L, 2 L - 2)``
        ``[a_1..a_L, b_1..b_L] = N [a_2..a_L, b_2..b_L]`` with ``a_1 = -sum a_l`` and
        ``b_1 = -sum l b_l`` (``dq(0) = ddq(0) = 0``).
    """
    n = np.zeros((2 * harmonics, 2 * harmonics - 2))
    rest = np.arange(2, harmonics + 1)
    n[0, : harmonics - 1] = -1.0
    n[1:harmonics, : harmonics - 1] = np.eye(harmonics - 1)
    n[harmonics, harmonics - 1:] = -rest
    n[harmonics + 1:, harmonics - 1:] = np.eye(harmonics - 1)
    return n


def free_coefficients(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The free coefficients of a series at rest at ``t = 0`` (inverse of :func:`rest_map`).

    Parameters
    ----------
    a, b : ndarray, shape ``(L, m)``
        Sine and cosine coefficients.

    Returns
    -------
    ndarray, shape ``(m, 2 L - 2)``
        ``[a_2..a_L, b_2..b_L]`` per coordinate.
    """
    return np.column_stack([np.asarray(a)[1:].T, np.asarray(b)[1:].T])


def fourier_basis(t: np.ndarray, harmonics: int, omega: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The series' basis at rest at both ends: ``q = Bq x``, ``dq = Bv x``, ``ddq = Ba x``.

    Parameters
    ----------
    t : ndarray, shape ``(S,)``
        Times [s].
    harmonics : int
        ``L >= 2``.
    omega : float
        ``w = 2 pi f`` [rad/s].

    Returns
    -------
    Bq, Bv, Ba : ndarray, shape ``(S, 2 L - 1)``
        Columns: the offset ``q0``, then ``a_2..a_L, b_2..b_L`` (:func:`rest_map`); a coordinate's
        variables are ``x = [q0, a_2..a_L, b_2..b_L]``.
    """
    lw = omega * np.arange(1, harmonics + 1)
    wt = np.outer(t, lw)
    s, c = np.sin(wt), np.cos(wt)
    n = rest_map(harmonics)
    pos = np.hstack([s / lw, -c / lw]) @ n
    vel = np.hstack([c, s]) @ n
    acc = np.hstack([-s * lw, c * lw]) @ n
    one, zero = np.ones((len(t), 1)), np.zeros((len(t), 1))
    return np.hstack([one, pos]), np.hstack([zero, vel]), np.hstack([zero, acc])


def coefficients(x: np.ndarray, harmonics: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Offsets and all coefficients of the variables.

    Parameters
    ----------
    x : ndarray, shape ``(m, 2 L - 1)``
        Per coordinate ``[q0, a_2..a_L, b_2..b_L]``.
    harmonics : int
        ``L``.

    Returns
    -------
    offsets : ndarray, shape ``(m,)``
        ``q0``.
    a, b : ndarray, shape ``(L, m)``
        Every coefficient, ``a_1`` and ``b_1`` included.
    """
    full = x[:, 1:] @ rest_map(harmonics).T  # (m, 2 L)
    return x[:, 0].copy(), full[:, :harmonics].T.copy(), full[:, harmonics:].T.copy()


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
        user = np.asarray(limits, dtype=float)
        if user.shape != (m, 4):
            raise BaseparamsError(f"robot {robot.name!r}: limits must have shape ({m}, 4) (lower, upper, velocity, "
                                  f"effort per designed coordinate), got {user.shape}")
        lim[:, [0, 1, 2, 4]] = np.where(np.isnan(user), lim[:, [0, 1, 2, 4]], user)
    if acceleration is not None:
        lim[:, 3] = np.broadcast_to(np.asarray(acceleration, dtype=float), (m,))
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


@dataclass(frozen=True, eq=False)
class _Problem:
    """One design: the model, the grid and its bases, the limits and the constraints' data."""

    model: IdentModel
    criterion: str
    harmonics: int
    omega: float
    t: np.ndarray  # (G,) the design grid
    bases: tuple[np.ndarray, np.ndarray, np.ndarray]  # Bq, Bv, Ba (G, k)
    limits: np.ndarray  # (m, 5)
    theta: np.ndarray | None  # (p,) prior model parameters (torque limits), or None
    cond_max: float | None  # loops: the bound on cond(J_p), else None
    keepout: tuple[int, float] | None = None  # (body, lowest height of its origin [m]), or None

    @property
    def m(self) -> int:
        """Designed coordinates."""
        return self.limits.shape[0]

    @property
    def k(self) -> int:
        """Variables per coordinate."""
        return 2 * self.harmonics - 1

    def states(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``q, dq, ddq (G, m)`` on the grid of the variables ``x (m * k,)``."""
        xm = x.reshape(self.m, self.k)
        return tuple(b @ xm.T for b in self.bases)


def criterion_terms(a: np.ndarray, criterion: str) -> tuple[float, np.ndarray]:
    """The criterion to minimise and its gradient with respect to the information matrix.

    Parameters
    ----------
    a : ndarray, shape ``(S, m, p)``
        Model regressor.
    criterion : {"cond", "logdet"}
        ``cond``: ``log cond`` of the column-scaled stacked regressor; ``logdet``:
        ``-log det(M / S) / p``, ``M = sum_s A_s^T A_s``.

    Returns
    -------
    value : float
        The value (inf when ``M`` is singular).
    gamma : ndarray, shape ``(p, p)``
        ``d value / d M`` (symmetric): the gradient with respect to ``A`` is ``2 A gamma``.
    """
    p = a.shape[2]
    w = a.reshape(-1, p)
    mm = w.T @ w
    d = np.sqrt(np.diag(mm))
    if np.any(d <= 0):
        return np.inf, np.zeros((p, p))
    g = mm / np.outer(d, d)
    lam, v = np.linalg.eigh(g)
    if lam[0] <= lam[-1] * 1e-15:
        return np.inf, np.zeros((p, p))
    if criterion == "logdet":
        ginv = (v / lam) @ v.T
        value = -(np.sum(np.log(lam)) + 2 * np.sum(np.log(d)) - p * np.log(len(a))) / p
        return float(value), -ginv / np.outer(d, d) / p
    h = 0.5 * (np.outer(v[:, -1], v[:, -1]) / lam[-1] - np.outer(v[:, 0], v[:, 0]) / lam[0])
    gamma = h / np.outer(d, d) - np.diag(np.sum(h * g, axis=1) / d**2)
    return float(0.5 * np.log(lam[-1] / lam[0])), gamma


def _perturbed(q: np.ndarray, dq: np.ndarray, ddq: np.ndarray) -> tuple[np.ndarray, ...]:
    """The ``3 m`` perturbations of the states, one column and kind at a time: ``3 m G`` samples each."""
    m = q.shape[1]
    out = []
    for kind, x in enumerate((q, dq, ddq)):
        blocks = []
        for which in range(3):
            for j in range(m):
                y = x.copy()
                if which == kind:
                    y[:, j] += STEPS[kind]
                blocks.append(y)
        out.append(np.concatenate(blocks))
    return tuple(out)


def _values(prob: _Problem, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray) -> dict | None:
    """The criterion and the nonlinear constraints' data at grid states ``(G, m)``.

    ``{"a" (G, m, p), "value", "gamma" (p, p), "tau" (G, m) or None, "logc" (G,) or None}``; ``None``
    when a sample does not close the loops from the reference (outside the workspace).
    """
    from .kinematics.loops import close_loops

    logc, cs = None, None
    if prob.cond_max is not None:
        cs = close_loops(prob.model.robot, q, dq, ddq, cond_max=np.inf)
        if cs.kept != len(q):
            return None
        logc = np.log(cs.cond)
    a = prob.model.regressor(q, dq, ddq, closed=cs)
    value, gamma = criterion_terms(a, prob.criterion)
    return {"a": a, "value": value, "gamma": gamma, "tau": None if prob.theta is None else a @ prob.theta,
            "logc": logc, "z": None if prob.keepout is None else _height(prob, q)}


def _height(prob: _Problem, q: np.ndarray) -> np.ndarray:
    """Height ``(S,)`` [m] of the keep-out body's frame origin (world z) at tree states ``q (S, dof)``."""
    from .kinematics.tree import forward_kinematics

    body = prob.keepout[0]
    robot = prob.model.robot
    return (forward_kinematics(robot, q).g[:, body] @ robot.M0[body])[:, 2, 3]


def _gradients(prob: _Problem, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, val: dict) -> dict | None:
    """Derivatives per grid sample and state column, by batched finite differences.

    ``{"g" (3, m, G): d value / d (q, dq, ddq), "dtau" (3, m, G, m) or None, "dlogc" (m, G) or None}``;
    ``None`` when a perturbed sample does not close the loops.
    """
    from .kinematics.loops import close_loops

    g, m = q.shape
    out = {"dtau": None, "dlogc": None, "dz": None}
    states, cs = _perturbed(q, dq, ddq), None
    if prob.keepout is not None:  # the first m blocks move q
        out["dz"] = (_height(prob, states[0][: g * m]).reshape(m, g) - val["z"]) / STEPS[0]
    if prob.cond_max is not None:  # the first m blocks move q: cond(J_p) changes with them only
        cs = close_loops(prob.model.robot, *states, cond_max=np.inf)
        if cs.kept != 3 * g * m:
            return None
        out["dlogc"] = (np.log(cs.cond[: g * m]).reshape(m, g) - val["logc"]) / STEPS[0]
    big = prob.model.regressor(*states, closed=cs).reshape(3 * m, g, m, -1)
    deriv = (big - val["a"]) / np.repeat(STEPS, m)[:, None, None, None]  # (3 m, G, m, p)
    grad = np.einsum("kgrp,grp->kg", deriv, 2.0 * val["a"] @ val["gamma"]).reshape(3, m, g)
    grad[1][(np.abs(dq) < 2 * STEPS[1]).T] = 0.0  # sign(dq) columns jump there: no derivative
    out["g"] = grad
    if prob.theta is not None:
        out["dtau"] = (deriv @ prob.theta).reshape(3, m, g, m)
    return out


class _Evaluator:
    """The criterion, the nonlinear constraints and their gradients at ``x``, cached.

    Values and gradients are computed on demand (a line search needs values only). Keeps the best
    feasible point seen (``best``: value, x).
    """

    def __init__(self, prob: _Problem, lin: tuple[np.ndarray, np.ndarray]):
        self.prob, self.lin = prob, lin
        self.x = None
        self.val: dict | None = None
        self.out: dict = {}
        self.best = (np.inf, None)

    def __call__(self, x: np.ndarray, grad: bool = False) -> dict:
        """``{"value", "cons", "valid"}`` at ``x (m k,)``, and ``"grad", "jac"`` with ``grad``."""
        prob = self.prob
        if self.x is None or not np.array_equal(x, self.x):
            self.x, self.states = x.copy(), prob.states(x)
            self.val = _values(prob, *self.states)
            self.out = self._value_part(x)
        if grad and "grad" not in self.out:
            d = _gradients(prob, *self.states, self.val) if self.val is not None else None
            if d is None:
                self.out.update(grad=np.zeros_like(x), jac=np.zeros((_n_nonlinear(prob), x.size)))
            else:
                self.out.update(grad=sum(d["g"][i] @ prob.bases[i] for i in range(3)).reshape(-1),
                                jac=_nonlinear_jacobian(prob, d))
        return self.out

    def _value_part(self, x: np.ndarray) -> dict:
        """Value and constraints at ``x``; the best feasible point updated."""
        if self.val is None:  # outside the workspace: reject the step
            return {"value": 1e3, "cons": -np.ones(_n_nonlinear(self.prob)), "valid": False}
        cons = _nonlinear_values(self.prob, self.val)
        value = self.val["value"]
        feasible = np.all(self.lin[0] @ x + self.lin[1] >= -FEAS_TOL) and np.all(cons >= -FEAS_TOL)
        if np.isfinite(value) and feasible and value < self.best[0]:
            self.best = (value, x.copy())
        return {"value": value if np.isfinite(value) else 1e3, "cons": cons, "valid": True}


def _n_nonlinear(prob: _Problem) -> int:
    """Number of nonlinear constraint rows: torques (two per grid sample and limited joint), loops."""
    n = 0 if prob.theta is None else 2 * prob.t.size * int(np.isfinite(prob.limits[:, 4]).sum())
    return n + (prob.t.size if prob.cond_max is not None else 0) + (prob.t.size if prob.keepout is not None else 0)


def _nonlinear_values(prob: _Problem, val: dict) -> np.ndarray:
    """Torque rows ``MARGIN -+ tau / effort >= 0`` then loop rows ``log(LOOP_MARGIN cond_max / cond(J_p)) >= 0``."""
    out = [np.zeros(0)]
    if val["tau"] is not None:
        eff = prob.limits[:, 4]
        rows = np.flatnonzero(np.isfinite(eff))
        frac = val["tau"][:, rows] / eff[rows]  # torques as fractions of the effort limits
        out += [(MARGIN - frac).reshape(-1), (MARGIN + frac).reshape(-1)]
    if val["logc"] is not None:
        out.append(np.log(LOOP_MARGIN * prob.cond_max) - val["logc"])
    if val["z"] is not None:  # keep-out: height above the floor [m]
        out.append(val["z"] - prob.keepout[1] - KEEPOUT_MARGIN)
    return np.concatenate(out)


def _nonlinear_jacobian(prob: _Problem, d: dict) -> np.ndarray:
    """The Jacobian ``(rows, m k)`` of :func:`_nonlinear_values`."""
    g, m, k = prob.t.size, prob.m, prob.k
    jac = [np.zeros((0, m * k))]
    if d["dtau"] is not None:
        rows = np.flatnonzero(np.isfinite(prob.limits[:, 4]))
        dt = sum(np.einsum("jsr,sk->srjk", d["dtau"][i][:, :, rows], prob.bases[i]) for i in range(3))
        dt = dt / prob.limits[rows, 4][None, :, None, None]
        dt = dt.reshape(g * len(rows), m * k)
        jac += [-dt, dt]
    if d["dlogc"] is not None:
        jl = -d["dlogc"].T[:, :, None] * prob.bases[0][:, None, :]  # (G, m, k)
        jac.append(jl.reshape(g, m * k))
    if d["dz"] is not None:
        jac.append((d["dz"].T[:, :, None] * prob.bases[0][:, None, :]).reshape(g, m * k))
    return np.vstack(jac)


def _linear_constraints(prob: _Problem) -> tuple[np.ndarray, np.ndarray]:
    """``(C, c)``: position, velocity and acceleration limits on the grid, ``C x + c >= 0``.

    Each row is divided by its limit (the range's width for positions): values are fractions. Every
    ``LIMIT_STRIDE``-th grid sample only: the rows cost SLSQP more than the criterion does, and the
    controller-rate check closes the gaps.
    """
    c, rhs, _ = _linear_rows(prob)
    return c, rhs


def _linear_rows(prob: _Problem) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int]]]:
    """:func:`_linear_constraints` and, per row, ``(kind, joint)`` (kind 0, 1, 2: position, velocity, acceleration)."""
    m, k = prob.m, prob.k
    bases = [b[::LIMIT_STRIDE] for b in prob.bases]
    g = len(bases[0])
    lim = prob.limits
    lo, hi = _shrunk_range(lim)
    rows, rhs, labels = [], [], []
    for j in range(m):
        for kind, lower, upper, unit in ((0, lo[j], hi[j], lim[j, 1] - lim[j, 0]),
                                         (1, -MARGIN * lim[j, 2], MARGIN * lim[j, 2], lim[j, 2]),
                                         (2, -MARGIN * lim[j, 3], MARGIN * lim[j, 3], lim[j, 3])):
            if not np.isfinite(upper):
                continue
            block = np.zeros((g, m * k))
            block[:, j * k:(j + 1) * k] = bases[kind] / unit
            rows += [block, -block]
            rhs += [np.full(g, -lower / unit), np.full(g, upper / unit)]
            labels += [(kind, j)] * (2 * g)
    if not rows:
        return np.zeros((0, m * k)), np.zeros(0), []
    return np.vstack(rows), np.concatenate(rhs), labels


def _nonlinear_labels(prob: _Problem) -> list[tuple[int, int]]:
    """Per row of :func:`_nonlinear_values`: ``(kind, joint)``, kind 3 torque, 4 loops, 5 keep-out (joint -1)."""
    g = prob.t.size
    out = []
    if prob.theta is not None:
        rows = np.flatnonzero(np.isfinite(prob.limits[:, 4]))
        out += [(3, int(rows[i % len(rows)])) for i in range(g * len(rows))] * 2
    if prob.cond_max is not None:
        out += [(4, -1)] * g
    if prob.keepout is not None:
        out += [(5, -1)] * g
    return out


def _constraint_text(prob: _Problem, kind: int, joint: int) -> tuple[str, str]:
    """A constraint named for a user, and what would loosen it."""
    lim, robot = prob.limits, prob.model.robot
    name = robot.joint_names[robot.dof_body[design_coordinates(robot)[joint]]] if joint >= 0 else ""
    if kind == 0:
        return (f"joint {name!r}: position range [{lim[joint, 0]:.4g}, {lim[joint, 1]:.4g}]",
                "widen its position limits (or a smaller --margin)")
    if kind == 1:
        return (f"joint {name!r}: velocity limit {lim[joint, 2]:.4g}",
                "a lower base frequency or fewer harmonics (slower motion), or a higher velocity limit")
    if kind == 2:
        return (f"joint {name!r}: acceleration limit {lim[joint, 3]:.4g}",
                "a higher --acceleration, a lower base frequency or fewer harmonics")
    if kind == 3:
        return (f"joint {name!r}: effort limit {lim[joint, 4]:.4g} N m (model torques, --torque)",
                "a lower base frequency (smaller inertial torques), or no --torque")
    if kind == 4:
        return (f"the loops' conditioning cond(J_p) <= {prob.cond_max:.3g}",
                "narrower actuated ranges around the reference assembly")
    link = robot.names[prob.keepout[0]]
    return f"the keep-out of link {link!r} (z >= {prob.keepout[1]:.4g} m)", "a lower keep-out height"


def _binding(prob: _Problem, x: np.ndarray, at_rest: bool = False) -> str:
    """Why ``x (m k,)`` is not a usable design, with what would help.

    The most violated constraint; else the ones that bind and the parameters the motion leaves
    unexcited.
    """
    c, rhs, labels = _linear_rows(prob)
    ev = _Evaluator(prob, (c, rhs))
    out = ev(x)
    if not out["valid"]:
        kind, joint = 4, -1
        text, helps = _constraint_text(prob, kind, joint)
        return f"the loops do not close there: the binding constraint is {text}; {helps}"
    slack = np.concatenate([c @ x + rhs, out["cons"]])
    labels = labels + _nonlinear_labels(prob)
    if at_rest:  # motion rows do not bind at rest
        keep = [i for i, (kind, _) in enumerate(labels) if kind >= 3]
        slack, labels = slack[keep], [labels[i] for i in keep]
    if slack.size and slack.min() < -FEAS_TOL:
        text, helps = _constraint_text(prob, *labels[int(np.argmin(slack))])
        return f"the binding constraint is {text}; {helps}"
    tight = [lab for lab in dict.fromkeys(labels[i] for i in np.flatnonzero(slack < 0.02)) if lab[0] >= 3]
    tight += _limiting(prob, x.reshape(prob.m, prob.k))
    tight = list(dict.fromkeys(tight))[:4]
    a = ev.val["a"].reshape(-1, ev.val["a"].shape[2])
    norm = np.linalg.norm(a, axis=0)
    weak = [prob.model.names[i] for i in np.flatnonzero(norm <= 1e-9 * max(norm.max(), 1e-300))]
    if not weak:
        from .ident.estimate import excitation
        from .numerics import StreamingQR

        weak = list(excitation(StreamingQR(prob.model.n_params).add(a).r, prob.model.names)[1])
    texts = [_constraint_text(prob, *lab) for lab in tight]
    what = f"the motion leaves {', '.join(weak[:5])}{' ...' if len(weak) > 5 else ''} unexcited"
    if not texts:
        return f"{what}; more harmonics or looser limits (a wider, faster motion) would help"
    return (f"{what}; binding: {'; '.join(t for t, _ in texts)}; what would help: "
            f"{'; '.join(dict.fromkeys(h for _, h in texts))}")


def _shrunk_range(lim: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The position range used while optimising: ``MARGIN`` of the width, centred."""
    pad = 0.5 * (1 - MARGIN) * (lim[:, 1] - lim[:, 0])
    return lim[:, 0] + pad, lim[:, 1] - pad


def _scaled(x: np.ndarray, bases, lim: np.ndarray, fill: float, grow: bool) -> np.ndarray:
    """``x (m, k)`` with each coordinate's oscillation scaled to ``fill`` of its tightest limit.

    Positions are scaled about the offset (inside the range); ``grow=False`` only shrinks.
    """
    q, dq, ddq = (b @ x.T for b in bases)
    dev = q - x[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(dev > 0, (lim[:, 1] - x[:, 0]) / dev, np.where(dev < 0, (lim[:, 0] - x[:, 0]) / dev, np.inf))
        ratios = np.vstack([room.min(axis=0), lim[:, 2] / np.abs(dq).max(axis=0), lim[:, 3] / np.abs(ddq).max(axis=0)])
    s = fill * np.nanmin(np.where(np.isnan(ratios), np.inf, ratios), axis=0)
    s = np.where(np.isfinite(s), s, 1.0)
    out = x.copy()
    out[:, 1:] *= s[:, None] if grow else np.minimum(s, 1.0)[:, None]
    return out


def _start(prob: _Problem, rng: np.random.Generator, fill: float = 0.5) -> np.ndarray:
    """A random feasible start ``(m k,)``.

    Offsets near the range's centre (loops: the reference), random coefficients filling ``fill`` of
    the limits, shrunk until the loops and torques are satisfied.
    """
    lim = prob.limits
    lo, hi = _shrunk_range(lim)
    off = 0.5 * (lo + hi) + rng.uniform(-0.15, 0.15, prob.m) * (hi - lo)
    if prob.cond_max is not None:  # q = 0 is known feasible (the loops' reference)
        off = np.clip(0.0, lo, hi)
    elif prob.keepout is not None:
        off = _keepout_offsets(prob, off)
    x = np.column_stack([off, rng.normal(size=(prob.m, prob.k - 1))])
    x = _scaled(x, prob.bases, np.column_stack([lo, hi, MARGIN * lim[:, 2:4]]), fill, grow=True).reshape(-1)
    if prob.theta is None and prob.cond_max is None and prob.keepout is None:
        return x
    ev = _Evaluator(prob, (np.zeros((0, x.size)), np.zeros(0)))
    for _ in range(40):
        out = ev(x)
        if out["valid"] and np.all(out["cons"] >= 0):
            return x
        x = x.reshape(prob.m, prob.k)
        x[:, 1:] *= 0.7
        x = x.reshape(-1)
    raise BaseparamsError(f"robot {prob.model.robot.name!r}: no feasible start: even at rest at the offsets "
                          f"{_binding(prob, x, at_rest=True)}")


def _limiting(prob: _Problem, xm: np.ndarray) -> list[tuple[int, int]]:
    """Per joint ``(kind, joint)``, tightest first: which limit bounds its oscillation most.

    Kind 0, 1, 2: position, velocity, acceleration; the room is the factor by which the
    oscillation could grow.
    """
    q, dq, ddq = (b @ xm.T for b in prob.bases)
    lim = prob.limits
    dev = q - xm[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(dev > 0, (lim[:, 1] - xm[:, 0]) / dev, np.where(dev < 0, (lim[:, 0] - xm[:, 0]) / dev, np.inf))
        ratios = np.vstack([room.min(axis=0), lim[:, 2] / np.abs(dq).max(axis=0), lim[:, 3] / np.abs(ddq).max(axis=0)])
    ratios = np.where(np.isfinite(ratios), ratios, np.inf)
    kinds = np.argmin(ratios, axis=0)
    best = ratios[kinds, np.arange(prob.m)]
    return [(int(kinds[j]), int(j)) for j in np.argsort(best) if np.isfinite(best[j])]


def _keepout_offsets(prob: _Problem, off: np.ndarray) -> np.ndarray:
    """Offsets ``(m,)`` at which the keep-out link rests above its height, with room to move every joint.

    Tried in turn: ``off`` (near the ranges' middle), the middle, then points on the way from the
    middle to the nearest point to q = 0 (known above the height) that keeps a quarter of each
    range on either side; the last resort is that point itself.
    """
    lim = prob.limits
    lo, hi = _shrunk_range(lim)
    mid = 0.5 * (lo + hi)
    near0 = np.clip(0.0, lo + 0.25 * (hi - lo), hi - 0.25 * (hi - lo))
    cands = [off, mid] + [(1 - s) * mid + s * near0 for s in (0.25, 0.5, 0.75, 1.0)] + [np.clip(0.0, lo, hi)]
    z = _height(prob, np.array(cands))
    ok = np.flatnonzero(z >= prob.keepout[1] + 2 * KEEPOUT_MARGIN)
    if ok.size == 0 and z.max() > prob.keepout[1]:
        ok = np.array([int(np.argmax(z))])  # the most room there is
    if ok.size == 0:
        link, z_min = prob.model.robot.names[prob.keepout[0]], prob.keepout[1]
        raise BaseparamsError(f"robot {prob.model.robot.name!r}: the keep-out binds: link {link!r} is below "
                              f"z = {z_min:.4g} m even at rest at the middle of the joint ranges (z = {z[1]:.4g} m) "
                              f"and at the point nearest to q = 0 within them (z = {z[-1]:.4g} m); lower the "
                              f"keep-out height or widen the position limits")
    return cands[ok[0]]


def _optimise(prob: _Problem, x0: np.ndarray, max_iter: int, say) -> tuple[float, np.ndarray | None, int, np.ndarray]:
    """SLSQP from ``x0``: ``(best value, best feasible x or None, iterations, the last point evaluated)``."""
    from scipy.optimize import minimize

    lin = _linear_constraints(prob)
    ev = _Evaluator(prob, lin)
    lo, hi = _shrunk_range(prob.limits)
    bounds = [(lo[j], hi[j]) if i == 0 else (None, None) for j in range(prob.m) for i in range(prob.k)]
    cons = [{"type": "ineq", "fun": lambda x: lin[0] @ x + lin[1], "jac": lambda x: lin[0]}]
    if _n_nonlinear(prob):
        cons.append({"type": "ineq", "fun": lambda x: ev(x)["cons"], "jac": lambda x: ev(x, True)["jac"]})
    it, seen = [0], [(np.inf, 0)]

    def callback(xk):
        it[0] += 1
        if it[0] % 25 == 0:
            say(f"iteration {it[0]}: {_shown(prob, ev.best[0])}")
        if ev.best[0] < seen[0][0] - STALL[0]:
            seen[0] = (ev.best[0], it[0])
        elif it[0] - seen[0][1] >= STALL[1]:
            raise StopIteration  # no progress: the next start is worth more

    ev(x0)
    minimize(lambda x: ev(x)["value"], x0, jac=lambda x: ev(x, True)["grad"], method="SLSQP", bounds=bounds,
             constraints=cons, callback=callback, options={"maxiter": max_iter, "ftol": 1e-7})
    return ev.best[0], ev.best[1], it[0], ev.x


def _shown(prob: _Problem, value: float) -> str:
    """The internal value as the user reads it: ``cond 12.3`` or ``logdet -4.5``."""
    if not np.isfinite(value):
        return f"{prob.criterion} not finite"
    p = prob.model.n_params
    return f"cond {np.exp(value):.6g}" if prob.criterion == "cond" else f"logdet {-value * p:.6g}"


def trajectory_criterion(model: IdentModel, q, dq, ddq, chunk: int = 4000) -> tuple[float, float]:
    """Condition number and ``log det`` of a trajectory's model regressor (the numbers a design reports).

    Parameters
    ----------
    model : IdentModel
        The identification model (its regressor's columns: base and drive parameters).
    q, dq, ddq : array_like, shape ``(S, state_columns)``
        The states (a loop robot's actuated coordinates).
    chunk : int
        Samples per regressor block (memory ``chunk * m * p`` floats).

    Returns
    -------
    cond : float
        Condition number of the column-scaled stacked regressor
        (:func:`baseparams.ident.estimate.excitation`; inf when singular).
    logdet : float
        ``log det(M / S)``, ``M`` the information matrix ``A^T A`` (SI units).
    """
    from .ident.estimate import excitation
    from .numerics import StreamingQR

    q, dq, ddq = (np.asarray(x, dtype=float) for x in (q, dq, ddq))
    qr = StreamingQR(model.n_params)
    for k in range(0, len(q), chunk):
        qr.add(model.regressor(q[k:k + chunk], dq[k:k + chunk], ddq[k:k + chunk]))
    cond, _ = excitation(qr.r, model.names)
    diag = np.abs(np.diag(qr.r))
    logdet = float(2 * np.sum(np.log(diag)) - model.n_params * np.log(len(q))) if np.all(diag > 0) else -np.inf
    return float(cond), logdet


def _model(obj, drives: bool, rotor: bool) -> IdentModel:
    """The identification model of a robot, an analysis or a model (checked: fixed base, loops regular)."""
    if isinstance(obj, IdentModel):
        robot = obj.robot
    else:
        robot = obj.robot if isinstance(obj, Analysis) else obj
        if not isinstance(robot, Robot):
            raise BaseparamsError(f"design_excitation needs a Robot, an Analysis or an IdentModel, "
                                  f"got {type(obj).__name__}")
    if robot.floating:
        raise BaseparamsError(f"robot {robot.name!r}: no actuated coordinate moves its floating base; the excitation "
                              f"designer needs a fixed base (every designed coordinate driven by a joint)")
    if robot.has_loops:
        loop_bound(robot)
    if isinstance(obj, IdentModel):
        return obj
    analysis = obj if isinstance(obj, Analysis) else analyze(robot)
    friction = ("viscous", "coulomb", "offset") if drives else ()
    return ident_model(analysis, rotor=bool(drives and rotor), friction=friction)


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
    from .numerics import COND_FACTOR, COND_MAX, reference_cond

    ref = reference_cond(robot)
    if not ref < SINGULAR_COND:
        raise BaseparamsError(f"robot {robot.name!r}: the reference configuration q = 0 is singular (cond(J_p) = "
                              f"{ref:.3g}): the passive coordinates are not determined there; re-reference the model "
                              f"at a regular configuration (baseparams.kinematics.loops.assemble)")
    return COND_MAX if ref < COND_MAX else COND_FACTOR * ref


def design_excitation(robot_or_analysis, harmonics: int = 5, base_frequency: float = 0.1, rate: float = 1000.0,
                      criterion: str = "cond", drives: bool = False, limits=None, acceleration=None,
                      torque: bool = False, starts: int = 4, seed: int = 0, grid: int = 200, max_iter: int = 150,
                      rotor: bool = False, progress=None, keepout: tuple[str, float] | None = None,
                      margin: float = 0.0) -> Excitation:
    """Design a periodic excitation trajectory that identifies every base parameter (module doc).

    Parameters
    ----------
    robot_or_analysis : Robot, Analysis or IdentModel
        The robot (analysed here), its certified analysis, or an identification model (its
        columns are the criterion's: e.g. ``ident_model(analysis, friction=(...))``).
    harmonics : int
        Harmonics ``L >= 2`` per coordinate.
    base_frequency : float
        ``f`` [Hz] (period ``1 / f``), rounded so that a period is a whole number of controller
        samples (a note says so).
    rate : float
        The controller's sampling rate [Hz] of the returned trajectory.
    criterion : {"cond", "logdet"}
        Minimise the condition number of the column-scaled regressor, or maximise ``log det`` of
        the information matrix (D-optimality).
    drives : bool
        Include the drive columns (viscous, Coulomb and offset friction per joint; rotor inertia
        with ``rotor``) besides the base parameters (ignored for an ``IdentModel``).
    limits : array_like, shape ``(m, 4)``, optional
        ``[lower, upper, velocity, effort]`` per designed coordinate overriding the model's
        (:func:`excitation_limits`; NaN keeps the model's).
    acceleration : float or array_like, shape ``(m,)``, optional
        Acceleration limits [rad/s^2 or m/s^2].
    torque : bool
        Keep the torques of the model's own inertial parameters within the effort limits.
    starts : int
        Random starts (SLSQP from each).
    seed : int
        Seed of the starts: the same seed gives the same design.
    grid : int
        Samples of one period on which the criterion and the constraints are optimised.
    max_iter : int
        SLSQP iterations per start.
    rotor : bool
        With ``drives``: rotor inertia columns too.
    progress : callable, optional
        Called with one line of text per start (and every 25 iterations).
    keepout : tuple of (str, float), optional
        ``(link, z_min)``: the named link's frame origin stays at or above the height ``z_min``
        [m, world z] at every sample (a floor plane or a table; trees only).
    margin : float
        Fraction of each position range kept free at both ends (:func:`excitation_limits`).

    Returns
    -------
    Excitation
        The trajectory at ``rate`` over one period, its coefficients and criterion.

    Raises
    ------
    BaseparamsError
        Bad options; a floating base; a loop robot whose reference configuration is singular;
        limits that leave no room for motion; no start that satisfies the loops or torque limits;
        a result that does not excite every model parameter (the limits are too tight).
    """
    from .numerics import blas_threads

    _check_options(harmonics, base_frequency, rate, criterion, starts, grid)
    t0 = time.perf_counter()
    model = _model(robot_or_analysis, drives, rotor)
    prob, notes = _problem(model, criterion, harmonics, base_frequency, rate, grid, limits, acceleration, torque,
                           margin)
    if keepout is not None:
        prob, note = _with_keepout(prob, keepout)
        notes.append(note)
    with blas_threads(), _kernel_threads():
        x, value = _multistart(prob, starts, seed, max_iter, progress or (lambda msg: None))
        notes.append(f"best of {starts} starts (seed {seed}): {_shown(prob, value)} on the {grid}-sample design "
                     f"grid; designed in {time.perf_counter() - t0:.1f} s")
        return _finish(prob, x, rate, notes)


def _with_keepout(prob: _Problem, keepout) -> tuple[_Problem, str]:
    """The problem with a keep-out height for a named link, checked at the start (q = offsets)."""
    from dataclasses import replace

    robot = prob.model.robot
    try:
        link, z_min = keepout
        z_min = float(z_min)
    except (TypeError, ValueError):
        raise BaseparamsError(f"keepout must be (link name, lowest height in m), got {keepout!r}") from None
    if robot.has_loops:
        raise BaseparamsError(f"robot {robot.name!r}: a Cartesian keep-out is supported for trees only")
    if link not in robot.names:
        raise BaseparamsError(f"robot {robot.name!r}: no link {link!r} for the keep-out; links: "
                              f"{', '.join(robot.names)}")
    prob = replace(prob, keepout=(robot.names.index(link), z_min))
    z0 = float(_height(prob, np.zeros((1, robot.dof)))[0])
    if z0 < z_min:
        raise BaseparamsError(f"robot {robot.name!r}: link {link!r} is at z = {z0:.4g} m at q = 0, already below the "
                              f"keep-out height {z_min:.4g} m")
    return prob, f"keep-out: link {link!r} stays at z >= {z_min:.4g} m (world) at every sample"


def random_excitation(robot_or_analysis, harmonics: int = 5, base_frequency: float = 0.1, rate: float = 1000.0,
                      drives: bool = False, limits=None, acceleration=None, torque: bool = False, seed: int = 0,
                      rotor: bool = False, margin: float = 0.0) -> Excitation:
    """A random excitation within the same limits, not optimised: the baseline a design is compared with.

    Random normal coefficients (at rest at both ends), offsets near the middle of the ranges (loops:
    the reference), each coordinate's oscillation scaled until its tightest limit is reached (then
    shrunk, if needed, for the loops and torques), exactly as a design's starting point.

    Parameters
    ----------
    robot_or_analysis : Robot, Analysis or IdentModel
        As :func:`design_excitation`.
    harmonics, base_frequency, rate, drives, limits, acceleration, torque, rotor, margin
        As :func:`design_excitation`.
    seed : int
        Seed of the coefficients.

    Returns
    -------
    Excitation
        The trajectory and its criteria (``criterion`` is ``cond``).

    Raises
    ------
    BaseparamsError
        As :func:`design_excitation`.
    """
    from .numerics import blas_threads

    _check_options(harmonics, base_frequency, rate, "cond", 1, 8 * harmonics)
    model = _model(robot_or_analysis, drives, rotor)
    prob, notes = _problem(model, "cond", harmonics, base_frequency, rate, 200, limits, acceleration, torque, margin)
    with blas_threads(), _kernel_threads():
        x = _start(prob, np.random.default_rng(seed), fill=1.0 / MARGIN)
        return _finish(prob, x, rate, notes + [f"random coefficients (seed {seed}), not optimised"])


@contextmanager
def _kernel_threads():
    """The compiled regressor kernels loaded (numba installed), on one thread inside the block.

    A design evaluates the regressor hundreds of times on small batches (a grid, its perturbations):
    the kernels beat numpy there, but their thread pool's start-up costs about 10 ms a call on two
    cores, ten times the work; one thread was faster at every batch size measured (200 to 13000
    samples).
    """
    from .regressor import compiled

    if not compiled.available():
        yield
        return
    import numba

    from .regressor import kernels  # noqa: F401  (loading them makes backend="auto" use them)

    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


def _multistart(prob: _Problem, starts: int, seed: int, max_iter: int, say) -> tuple[np.ndarray, float]:
    """The best feasible design ``(x (m k,), value)`` of ``starts`` seeded random starts."""
    rng = np.random.default_rng(seed)
    best, last = (np.inf, None), None
    for s in range(starts):
        ts = time.perf_counter()
        value, x, nit, last = _optimise(prob, _start(prob, rng), max_iter,
                                        lambda msg: say(f"start {s + 1}/{starts}: {msg}"))
        say(f"start {s + 1}/{starts}: {_shown(prob, value)} on the design grid after {nit} iterations "
            f"({time.perf_counter() - ts:.1f} s)")
        if x is not None and value < best[0]:
            best = (value, x)
    if best[1] is None:
        raise BaseparamsError(f"robot {prob.model.robot.name!r}: no start reached a feasible design that excites every "
                              f"model parameter: {_binding(prob, last)}")
    return best[1], best[0]


def _check_options(harmonics, base_frequency, rate, criterion, starts, grid) -> None:
    """Raise on options that cannot give a design."""
    if criterion not in CRITERIA:
        raise BaseparamsError(f"unknown criterion {criterion!r}; choose {' or '.join(CRITERIA)}")
    if int(harmonics) != harmonics or harmonics < 2:
        raise BaseparamsError(f"harmonics must be an integer >= 2 (the first harmonic brings the motion to rest), "
                              f"got {harmonics}")
    if not (base_frequency > 0 and rate > 0):
        raise BaseparamsError(f"base frequency and rate must be > 0, got {base_frequency} Hz and {rate} Hz")
    if rate < 4 * harmonics * base_frequency:
        raise BaseparamsError(f"rate {rate:g} Hz is too slow for {harmonics} harmonics of {base_frequency:g} Hz "
                              f"(at least {4 * harmonics * base_frequency:g} Hz)")
    if starts < 1 or grid < 8 * harmonics:
        raise BaseparamsError(f"need starts >= 1 and grid >= {8 * harmonics} samples, got {starts} and {grid}")


def _problem(model: IdentModel, criterion, harmonics, base_frequency, rate, grid, limits, acceleration,
             torque, margin=0.0) -> tuple[_Problem, list[str]]:
    """The design problem and the notes of its defaults."""
    robot = model.robot
    lim, notes = excitation_limits(robot, limits, acceleration, margin)
    if robot.has_loops and not np.all((lim[:, 0] < 0) & (lim[:, 1] > 0)):
        raise BaseparamsError(f"robot {robot.name!r}: the reference configuration q = 0 (where the loops are "
                              f"assembled) is outside the actuated coordinates' position limits")
    per = max(1, int(round(rate / base_frequency)))
    f = rate / per
    if abs(f - base_frequency) > 1e-12 * base_frequency:
        notes.append(f"base frequency {base_frequency:.6g} Hz rounded to {f:.8g} Hz: a period of {per} samples "
                     f"at {rate:g} Hz")
    omega = 2 * np.pi * f
    t = (np.arange(grid) + 0.5) / (grid * f)
    theta = None
    if torque:
        if not np.isfinite(lim[:, 4]).any():
            raise BaseparamsError(f"robot {robot.name!r}: torque limits asked, but no effort limit is known")
        theta = model.theta(robot.parameters("paper"))
    cond_max = loop_bound(robot) if robot.has_loops else None
    if cond_max is not None:
        notes.append(f"loops: cond(J_p) <= {cond_max:.3g} at every sample (continuation from the reference assembly)")
    return _Problem(model, criterion, int(harmonics), omega, t, fourier_basis(t, int(harmonics), omega), lim, theta,
                    cond_max), notes


def _finish(prob: _Problem, x: np.ndarray, rate: float, notes: list[str]) -> Excitation:
    """The design at the controller's rate: scaled into the limits, checked, its criterion computed."""
    model, robot = prob.model, prob.model.robot
    f = prob.omega / (2 * np.pi)
    t = np.arange(int(round(rate / f)) + 1) / rate
    bases = fourier_basis(t, prob.harmonics, prob.omega)
    xm = _scaled(x.reshape(prob.m, prob.k), bases, prob.limits, 1.0, grow=False)
    shrunk = 1.0 - np.abs(xm[:, 1:]).sum(axis=1) / np.maximum(np.abs(x.reshape(prob.m, prob.k)[:, 1:]).sum(axis=1),
                                                               1e-300)
    for _ in range(30):
        q, dq, ddq = (b @ xm.T for b in bases)
        why = _violation(prob, q, dq, ddq)
        if not why:
            break
        xm[:, 1:] *= 0.95
        shrunk = 1.0 - (1.0 - shrunk) * 0.95
    else:
        raise BaseparamsError(f"robot {robot.name!r}: the design fails at the controller's rate ({why})")
    if shrunk.max() > 1e-12:
        notes.append(f"oscillations scaled down by up to {100 * shrunk.max():.2g} % to meet every limit at {rate:g} Hz")
    cond, logdet = trajectory_criterion(model, q, dq, ddq)
    if not cond < COND_LIMIT:
        from .ident.estimate import excitation
        from .numerics import StreamingQR

        weak = excitation(StreamingQR(model.n_params).add(model.regressor(q, dq, ddq)).r, model.names)[1]
        raise BaseparamsError(f"robot {robot.name!r}: within these limits the trajectory does not excite {weak[:5]} "
                              f"(condition number {cond:.3g}): {_binding(prob, xm.reshape(-1))}")
    if prob.cond_max is not None:
        from .kinematics.loops import close_loops

        notes.append(f"loops: every sample closed on the reference assembly mode, cond(J_p) <= "
                     f"{close_loops(robot, q, cond_max=np.inf).cond.max():.3g}")
    offsets, a, b = coefficients(xm, prob.harmonics)
    joints = tuple(robot.joint_names[robot.dof_body[c]] for c in design_coordinates(robot))
    return Excitation(robot.name, joints, prob.harmonics, f, float(rate), offsets, a, b, t, q, dq, ddq, prob.criterion,
                      cond if prob.criterion == "cond" else logdet, cond, prob.limits.copy(), tuple(model.names),
                      tuple(notes))


def _violation(prob: _Problem, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray) -> str:
    """What a sampled trajectory violates among the loop and torque limits ('' when nothing)."""
    robot = prob.model.robot
    if prob.cond_max is not None:
        from .kinematics.loops import close_loops

        cs = close_loops(robot, q, dq, ddq, cond_max=prob.cond_max)
        if cs.kept < len(q):
            return (f"{len(q) - cs.kept} samples outside the workspace, off the assembly mode or with "
                    f"cond(J_p) > {prob.cond_max:.3g}: narrower actuated ranges would help")
    if prob.keepout is not None:
        low = _height(prob, q) < prob.keepout[1] - 1e-9
        if low.any():
            return (f"{int(low.sum())} samples with {robot.names[prob.keepout[0]]!r} below the keep-out height "
                    f"{prob.keepout[1]:.4g} m: a lower keep-out height would help")
    if prob.theta is not None:
        tau = np.concatenate([prob.model.regressor(q[k:k + 4000], dq[k:k + 4000], ddq[k:k + 4000]) @ prob.theta
                              for k in range(0, len(q), 4000)])
        with np.errstate(invalid="ignore"):
            over = np.abs(tau) > prob.limits[:, 4]
        if over.any():
            names = [robot.joint_names[robot.dof_body[c]] for c in design_coordinates(robot)]
            return (f"{int(over.any(axis=1).sum())} samples with torques above the effort limits of "
                    f"{[n for n, o in zip(names, over.any(axis=0)) if o]}: a lower base frequency or no --torque "
                    f"would help")
    return ""


def read_trajectory(path, robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Read a trajectory file (:meth:`Excitation.to_csv`) for a robot's designed coordinates.

    Parameters
    ----------
    path : str or Path
        ``.csv`` or ``.tsv`` with a header ``t, q_<joint>..., dq_<joint>..., ddq_<joint>...``
        (further columns, e.g. ``tau_<joint>``, are ignored).
    robot : Robot
        The model: its designed coordinates' joints (:func:`design_coordinates`) must all be
        there.

    Returns
    -------
    t : ndarray, shape ``(S,)``
        Time [s].
    q, dq, ddq : ndarray, shape ``(S, m)``
        States of the designed coordinates, in the model's order.

    Raises
    ------
    BaseparamsError
        A missing or unreadable file, a missing column, non-numeric values.
    """
    p = check_input(path)
    delim = "\t" if p.suffix.lower() == ".tsv" else ","
    try:
        with open(p) as fh:
            header = [h.strip() for h in fh.readline().strip().split(delim)]
            data = np.atleast_2d(np.loadtxt(fh, delimiter=delim, ndmin=2))
    except (OSError, ValueError) as exc:
        raise BaseparamsError(f"{p}: cannot read a trajectory ({exc})") from None
    joints = [robot.joint_names[robot.dof_body[c]] for c in design_coordinates(robot)]
    where = {h: k for k, h in enumerate(header)}
    want = ["t"] + [f"{k}_{j}" for k in ("q", "dq", "ddq") for j in joints]
    missing = [w for w in want if w not in where]
    if missing:
        raise BaseparamsError(f"{p}: no column {missing[0]!r} (a trajectory needs t, q_, dq_ and ddq_ of the "
                              f"joints {joints})")
    if data.shape[1] != len(header) or not np.all(np.isfinite(data)):
        raise BaseparamsError(f"{p}: {data.shape[1]} values per row for {len(header)} columns, or NaN / inf")
    cols = [data[:, [where[f"{k}_{j}"] for j in joints]] for k in ("q", "dq", "ddq")]
    return data[:, where["t"]], cols[0], cols[1], cols[2]
