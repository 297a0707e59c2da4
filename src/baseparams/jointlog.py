"""A recorded joint trajectory mapped to a model's joints (what the readers produce).

Units are the model's: rad or m for positions, N m or N for generalized forces, seconds for
time. Every array's first axis is the sample.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .display import clip, format_number


@dataclass(frozen=True, eq=False)
class JointLog:
    """A joint-space log: time, positions, optional rates, generalized forces.

    Parameters
    ----------
    t : ndarray, shape ``(S,)``
        Time stamps [s], strictly increasing.
    joints : tuple of str, shape ``(m,)``
        The model's joint names (1-dof joints: R or P) of the columns, in the log's column order;
        a floating base's six coordinates first, named
        :data:`~baseparams.kinematics.floating.BASE_COORDINATES` (position [m] and Z-Y-X angles
        [rad], smooth in time; their ``tau`` columns zero: a base wrench is not measured).
    q : ndarray, shape ``(S, m)``
        Joint positions [rad or m], joint side (after sign and gear ratio).
    tau : ndarray, shape ``(S, m)``, or None
        Joint generalized forces [N m or N], joint side (after sign, gear ratio and
        current-to-torque gain); ``None`` for a log of states, or of motor currents alone.
    dq, ddq : ndarray, shape ``(S, m)``, optional
        Measured velocities and accelerations; ``None`` when the log has none (derived from
        ``q`` by the preprocessing).
    source : str
        Where the log comes from (a file name), for messages.
    removed : dict of str to int
        Samples removed so far and why (reason -> count); nothing is dropped without a count.
    notes : tuple of str
        One line per decision taken on the data (defaults chosen, conversions), for the report.
    cur : ndarray, shape ``(S, m)``, optional
        Motor currents [A] (``cur_<joint>`` columns: the current of the motor named after each
        joint, sign applied, no gain): what an arm without joint-torque sensors logs
        (:mod:`baseparams.ident.fromcurrents`); ``None`` when the log has none.
    """

    t: np.ndarray
    joints: tuple[str, ...]
    q: np.ndarray
    tau: np.ndarray
    dq: np.ndarray | None = None
    ddq: np.ndarray | None = None
    source: str = "<memory>"
    removed: dict[str, int] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    cur: np.ndarray | None = None

    def __post_init__(self):
        from .arguments import ArgumentTypeError, check_array
        from .errors import DataError

        t = check_array(self.t, "JointLog: t", 1, finite=False)  # types and shapes; values: :meth:`checked`
        object.__setattr__(self, "t", t)
        if isinstance(self.joints, str) or not all(isinstance(j, str) for j in self.joints):
            raise ArgumentTypeError(f"JointLog: joints must be a sequence of joint names, got {self.joints!r:.80}")
        object.__setattr__(self, "joints", tuple(self.joints))
        shape = (len(t), len(self.joints))
        for name in ("q", "tau", "dq", "ddq", "cur"):
            value = getattr(self, name)
            if value is None and name != "q":
                continue
            a = check_array(value, f"JointLog: {name}", 2, finite=False)
            if a.shape != shape:
                raise DataError(f"{self.source}: {name} has shape {a.shape}; expected {shape} (the samples of t, the "
                                f"joints)")
            object.__setattr__(self, name, a)

    def checked(self) -> JointLog:
        """The log itself, its values checked: finite, time strictly increasing (what the readers guarantee).

        Returns
        -------
        JointLog
            ``self``.

        Raises
        ------
        DataError
            The first value that is not finite (naming the signal, the joint and the sample), or a
            time stamp that does not increase.
        """
        from .errors import DataError

        for name in ("t", "q", "tau", "dq", "ddq", "cur"):
            a = getattr(self, name)
            if a is not None and not np.all(np.isfinite(a)):
                i = int(np.argmax(~np.isfinite(a).reshape(len(a), -1).all(axis=1)))
                k = "" if a.ndim == 1 else f" of joint {self.joints[int(np.argmax(~np.isfinite(a[i])))]!r}"
                raise DataError(f"{self.source}: {name}{k}, sample {i}: {a[i] if a.ndim == 1 else a[i].tolist()} "
                                f"is not finite")
        if len(self.t) > 1 and not np.all(np.diff(self.t) > 0):
            i = int(np.argmax(~(np.diff(self.t) > 0))) + 1
            raise DataError(f"{self.source}: t, sample {i}: {self.t[i]:.9g} s does not follow {self.t[i - 1]:.9g} s; "
                            f"time must be strictly increasing")
        return self

    @property
    def n_samples(self) -> int:
        """Number of samples ``S``."""
        return len(self.t)

    @property
    def floating(self) -> bool:
        """Whether the first six columns are a floating base's coordinates (not joints)."""
        from .kinematics.floating import BASE_COORDINATES

        return tuple(self.joints[:6]) == BASE_COORDINATES

    @property
    def n_joints(self) -> int:
        """Number of joints (the columns without a floating base's six)."""
        return len(self.joints) - (6 if self.floating else 0)

    def __repr__(self) -> str:
        s = self.n_samples
        span = float(self.t[-1] - self.t[0]) if s > 1 else 0.0
        rate = f" ({format_number((s - 1) / span, 4)} Hz)" if span > 0 else ""
        has = [k for k in ("dq", "ddq") if getattr(self, k) is not None]
        has += ["currents"] if self.cur is not None else []
        base = " and a floating base" if self.floating else ""
        text = (f"<JointLog {self.source}: {s} samples of {self.n_joints} joints{base} over {format_number(span, 4)} s"
                f"{rate}{', with ' + ' and '.join(has) if has else ''}")
        removed = sum(self.removed.values())
        return clip(text + (f", {removed} removed" if removed else "") + ">")
