"""A designed trajectory, :class:`Excitation`: its coefficients, samples, criterion; saved and read back.

The file is the identification logs' default layout without torques (``t, q_<joint>,
dq_<joint>, ddq_<joint>``): what a robot controller and ``baseparams simulate --trajectory``
(:func:`read_trajectory`, :func:`baseparams.simulate`) read.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..display import clip, counted, format_number
from ..errors import BaseparamsError
from ..files import check_input
from ..model.robot import Robot
from .fourier import fourier_basis, free_coefficients
from .limits import design_coordinates


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
        return clip(f"<Excitation {self.robot}: {counted(len(self.joints), 'joint')}, {self.harmonics} harmonics of "
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
        from ..tables import write_table

        return write_table(path, self._columns(), "a trajectory as .csv or .tsv")

    def _columns(self) -> dict:
        """``t, q_<joint>..., dq_<joint>..., ddq_<joint>...``: the trajectory file's columns."""
        cols = {"t": self.t}
        for kind, arr in (("q", self.q), ("dq", self.dq), ("ddq", self.ddq)):
            cols.update({f"{kind}_{j}": arr[:, k] for k, j in enumerate(self.joints)})
        return cols

    def save(self, path, inputs=(), what: str = "output") -> Path:
        """Write the trajectory atomically, never onto an input (:func:`baseparams.files.atomic_path`).

        The file :meth:`to_csv` writes (``t, q_<joint>, dq_<joint>, ddq_<joint>``): what a robot
        controller, ``baseparams simulate --trajectory`` and :func:`baseparams.simulate` read.

        Parameters
        ----------
        path : str or Path
            ``.csv`` or ``.tsv``.
        inputs : iterable of str or Path
            The run's input files, which the output must not overwrite.
        what : str
            The output's role, for messages (``--out``).

        Returns
        -------
        Path
            The file written.

        Raises
        ------
        BaseparamsError
            Another suffix, an output onto an input, a missing folder, a non-regular target.
        """
        from ..tables import TRAJECTORY_SUFFIXES, write_table

        return write_table(path, self._columns(), "a trajectory as .csv or .tsv", TRAJECTORY_SUFFIXES, inputs=inputs,
                           what=what)

    @property
    def trajectory(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(t (S,), q, dq, ddq (S, m))``: the samples, as :func:`read_trajectory` returns them from the file."""
        return self.t, self.q, self.dq, self.ddq

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
                 f"{self.value:.6g}, condition number {self.condition_number:.6g} "
                 f"({counted(len(self.parameters), 'parameter')})",
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
        What :func:`baseparams.io.logs.read_log` refuses in a log (a missing or unreadable file,
        a missing column, values that are not finite, time that is not strictly increasing, an
        angle beyond 4 pi or a translation beyond 10 m), a missing rate column.
    """
    from ..io.logs import read_log

    check_input(path)  # a file (a folder would read as a ROS bag)
    joints = robot.coordinate_names(design_coordinates(robot))
    log = read_log(path, robot, require_tau=False)  # the reader identify reads the simulated log with: its checks
    lack = [k for k in ("dq", "ddq") if getattr(log, k) is None]
    if lack:
        raise BaseparamsError(f"{path}: no {lack[0]}_ columns (a trajectory needs t, q_, dq_ and ddq_ of the joints "
                              f"{joints})")
    cols = [log.joints.index(j) for j in joints]
    return log.t, log.q[:, cols], log.dq[:, cols], log.ddq[:, cols]
