"""Drive and friction model of the measured joints: rotor inertia, viscous, Coulomb, offset.

Per driven joint ``j`` (a measured 1-dof coordinate), the generalized force gains

``tau_j += Ia_j ddq_j + Fv_j dq_j + Fc_j sign(dq_j) + Fo_j``

(``sign`` or, with ``coulomb_width`` ``w``, the smooth ``tanh(dq_j / w)``). ``Ia_j`` is the rotor
inertia reflected to the joint (MJCF ``armature``), ``Fv_j`` [N m s/rad], ``Fc_j`` and ``Fo_j``
[N m] (or N for prismatic joints). The drive parameters ``delta`` are ordered joint by joint, each
joint's kinds in :data:`KINDS` order (those selected).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import BaseparamsError
from ..model.robot import Robot

#: drive parameter kinds, in their order within a joint
KINDS = ("Ia", "Fv", "Fc", "Fo")
#: friction names (CLI ``--friction``) -> kinds
FRICTION = {"viscous": "Fv", "coulomb": "Fc", "offset": "Fo"}


@dataclass(frozen=True, eq=False)
class Drives:
    """The drive parameters of the measured rows.

    Parameters
    ----------
    joints : tuple of str
        Model joint names of the driven coordinates.
    rows : ndarray of int, shape ``(m,)``
        Position of each driven coordinate among the measured rows (the rows of the base
        regressor) and among the states' columns.
    kinds : tuple of str
        The kinds per joint, a subset of :data:`KINDS` in that order.
    coulomb_width : float, optional
        Velocity scale ``w`` of a smooth Coulomb term ``tanh(dq / w)`` [rad/s or m/s]; ``None``:
        ``sign(dq)``.
    """

    joints: tuple[str, ...]
    rows: np.ndarray
    kinds: tuple[str, ...]
    coulomb_width: float | None = None

    @property
    def n_params(self) -> int:
        """Number of drive parameters ``nd = len(joints) * len(kinds)``."""
        return len(self.joints) * len(self.kinds)

    @property
    def names(self) -> list[str]:
        """``<kind>_<joint>`` for every drive parameter, e.g. ``Fv_joint2``."""
        return [f"{k}_{j}" for j in self.joints for k in self.kinds]

    @property
    def param_kinds(self) -> list[str]:
        """The kind of every drive parameter, ``(nd,)``."""
        return [k for _ in self.joints for k in self.kinds]

    def regressor(self, dq: np.ndarray, ddq: np.ndarray, nrows: int) -> np.ndarray:
        """The drive columns of the measured rows.

        Parameters
        ----------
        dq, ddq : ndarray, shape ``(S, nrows)``
            Velocities and accelerations of the measured rows' coordinates.
        nrows : int
            Number of measured rows.

        Returns
        -------
        D : ndarray, shape ``(S, nrows, nd)``
            ``D[s, rows[j], j * len(kinds) + k]`` is kind ``k``'s column of joint ``j``; zero
            elsewhere.
        """
        s = dq.shape[0]
        out = np.zeros((s, nrows, self.n_params))
        nk = len(self.kinds)
        for j, r in enumerate(self.rows):
            v, a = dq[:, r], ddq[:, r]
            for k, kind in enumerate(self.kinds):
                out[:, r, j * nk + k] = self.column(kind, v, a)
        return out

    def column(self, kind: str, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """One drive column of one joint.

        Parameters
        ----------
        kind : {"Ia", "Fv", "Fc", "Fo"}
            The parameter kind.
        v, a : ndarray, shape ``(S,)``
            The joint's velocity and acceleration.

        Returns
        -------
        ndarray, shape ``(S,)``
            ``a``, ``v``, ``sign(v)`` (or ``tanh(v / w)``) or ones.
        """
        if kind == "Ia":
            return a
        if kind == "Fv":
            return v
        if kind == "Fc":
            return np.sign(v) if self.coulomb_width is None else np.tanh(v / self.coulomb_width)
        return np.ones_like(v)


def drives_for(robot: Robot, coords: np.ndarray, rotor: bool = True, friction=("viscous", "coulomb", "offset"),
               coulomb_width: float | None = None) -> Drives:
    """Drives on every measured 1-dof joint (R or P) among ``coords``.

    Parameters
    ----------
    robot : Robot
        The robot.
    coords : array_like of int, shape ``(nrows,)``
        The coordinates of the measured rows, in row order (a floating base's six are not
        driven).
    rotor : bool
        Include the rotor inertia ``Ia``.
    friction : iterable of str
        Any of ``viscous``, ``coulomb``, ``offset`` (:data:`FRICTION`).
    coulomb_width : float, optional
        Smooth Coulomb friction's velocity scale (see :class:`Drives`).

    Returns
    -------
    Drives
        With no parameter at all when neither ``rotor`` nor any friction is asked for.

    Raises
    ------
    BaseparamsError
        An unknown friction name or a non-positive ``coulomb_width``.
    """
    friction = tuple(friction)
    unknown = [f for f in friction if f not in FRICTION]
    if unknown:
        raise BaseparamsError(f"unknown friction term(s) {unknown}; choose from {', '.join(FRICTION)}")
    if coulomb_width is not None and not coulomb_width > 0:
        raise BaseparamsError(f"coulomb_width must be > 0 (rad/s), got {coulomb_width}")
    chosen = {"Ia"} if rotor else set()
    chosen |= {FRICTION[f] for f in friction}
    kinds = tuple(k for k in KINDS if k in chosen)
    body = robot.dof_body
    rows = [r for r, c in enumerate(np.asarray(coords, dtype=int)) if robot.jtype[body[c]] in ("R", "P")]
    names = tuple(robot.joint_names[body[coords[r]]] for r in rows)
    return Drives(names if kinds else (), np.array(rows if kinds else [], dtype=int), kinds, coulomb_width)


@dataclass(frozen=True, eq=False)
class DriveRegrouping:
    """Which drive parameters regroup with base parameters, decided on sampled states.

    The model ``tau = Yb beta + D delta`` has the regressor ``[Yb | D]``; a drive column in the
    span of the others (e.g. the first joint's rotor inertia ``Ia_1``, whose column ``ddq_1`` is
    that of the first link's inertia about the same axis) is not identifiable on its own: it is
    eliminated and the base parameters absorb it, ``theta = phi_I + K phi_D`` with
    ``phi = [beta; delta]``.

    Parameters
    ----------
    names : list of str, shape ``(nb + nd,)``
        Base-parameter names then drive-parameter names.
    independent : ndarray of int, shape ``(p,)``
        Columns of ``[Yb | D]`` kept (the model parameters).
    dependent : ndarray of int, shape ``(k,)``
        Columns eliminated (drive parameters first).
    K : ndarray, shape ``(p, k)``
        ``theta = phi[independent] + K phi[dependent]``.
    decided : bool
        The rank decision had a clear singular-value gap (``gap >= min_gap``).
    gap : float
        That gap (inf when ``[Yb | D]`` has full column rank with a clear margin).
    """

    names: list[str]
    independent: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    decided: bool
    gap: float

    @property
    def model_names(self) -> list[str]:
        """Names of the model parameters ``theta``, ``(p,)``."""
        return [self.names[i] for i in self.independent]

    def expressions(self) -> list[str]:
        """Each model parameter as a combination, e.g. ``link1.ZZR + Ia_joint1``.

        Returns
        -------
        list of str, shape ``(p,)``
            The name alone when nothing regroups into it.
        """
        from ..base.regroup import format_coefficient

        out = []
        for row, i in enumerate(self.independent):
            terms = [self.names[i]]
            for col, d in enumerate(self.dependent):
                c = self.K[row, col]
                if c != 0.0:
                    mag = "" if abs(c) == 1 else f"{format_coefficient(abs(c))}*"
                    terms.append(f"{'-' if c < 0 else '+'} {mag}{self.names[d]}")
            out.append(" ".join(terms))
        return out

    def matrix(self) -> np.ndarray:
        """The map ``E (p, nb + nd)`` with ``theta = E phi``.

        Returns
        -------
        ndarray, shape ``(p, nb + nd)``
            Identity on the independent columns, ``K`` on the dependent ones.
        """
        e = np.zeros((len(self.independent), len(self.names)))
        e[np.arange(len(self.independent)), self.independent] = 1.0
        e[:, self.dependent] = self.K
        return e


def regroup_drives(factor: np.ndarray, base_names: list[str], drives: Drives, rtol: float = 1e-9,
                   min_gap: float = 1e4) -> DriveRegrouping:
    """Decide which drive parameters regroup, from the factor of a sampled ``[Yb | D]``.

    Parameters
    ----------
    factor : ndarray, shape ``(nb + nd, nb + nd)``
        Triangular factor of ``[Yb | D]`` stacked over random states
        (:class:`~baseparams.numerics.StreamingQR`).
    base_names : list of str, shape ``(nb,)``
        Names of the (certified, independent) base parameters.
    drives : Drives
        The drive model (``nd`` parameters).
    rtol, min_gap : float
        The rank decision's tolerances (:func:`~baseparams.numerics.rank_decision`).

    Returns
    -------
    DriveRegrouping
        Drive parameters are the preferred dependents (last joint first): base parameters
        absorb them, never the other way round.
    """
    from ..base.regroup import choose_dependent, clean
    from ..numerics import rank_decision

    nb, nd = len(base_names), drives.n_params
    names = list(base_names) + drives.names
    num = rank_decision(factor, rtol, min_gap)
    nullb = num.null_basis
    k = nullb.shape[1]
    order = np.r_[np.arange(nb + nd - 1, nb - 1, -1), np.arange(nb - 1, -1, -1)]
    dep = choose_dependent(nullb, order) if k else np.zeros(0, dtype=int)
    ind = np.setdiff1d(np.arange(nb + nd), dep)
    kmat = np.zeros((len(ind), k))
    if k:
        kmat = -np.linalg.solve(nullb[dep].T, nullb[ind].T).T
        kmat[np.abs(kmat) <= 1e-9 * np.maximum(1.0, np.abs(kmat).max(axis=1, keepdims=True))] = 0.0
        kmat = clean(kmat, rtol=1e-12)  # decided on sampled states: rounding ~1e-15
    gap = float(num.gap) if k else np.inf
    return DriveRegrouping(names, ind, dep, kmat, bool(num.decided) or k == 0, gap)
