"""Drive and friction model of the measured joints: rotor inertia, viscous, Coulomb, offset.

Per driven joint ``j`` (a measured 1-dof coordinate), the generalized force gains

``tau_j += Ia_j ddq_j + Fv_j dq_j + Fc_j sign(dq_j) + Fo_j``

(``sign`` or, with ``coulomb_width`` ``w``, the smooth ``tanh(dq_j / w)``). ``Ia_j`` is the rotor
inertia reflected to the joint (MJCF ``armature``), ``Fv_j`` [N m s/rad], ``Fc_j`` and ``Fo_j``
[N m] (or N for prismatic joints).

Coupled transmissions (:class:`MotorCoupling`, e.g. a wrist whose last motor turns joints 5 and
6): a motor whose joint-side velocity is ``v_m = sum_j w_j dq_j`` and whose torque ``y`` reaches
joint ``j`` as ``w_j y`` (the transpose of the velocity map, by virtual work) adds

``tau_j += w_j (Iam a_m + Fvm v_m + Fcm sign(v_m))``, ``a_m = sum_k w_k ddq_k``,

for every joint ``j`` it drives: its rotor inertia ``Iam`` and viscous and Coulomb friction
``Fvm``, ``Fcm``, reflected to the joint side of the weights (a motor of gear ratio ``N`` turning
``N (dq_5 + dq_6)`` with weights 1, 1: ``Iam = N^2 J_motor``, ``Fvm = N^2 fv_motor``,
``Fcm = N fc_motor``). A coupled offset would be a combination of the joints' own ``Fo_j``, so
there is none. The per-joint terms of a coupled joint remain (its own gearing's friction; a joint
with no motor of its own has ``Ia_j`` near zero).

The drive parameters ``delta`` are ordered joint by joint, each joint's kinds in :data:`KINDS`
order (those selected), then coupling by coupling, each coupling's kinds in
:data:`COUPLED_KINDS` order (those whose per-joint kind is selected).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ..display import counted, summary_repr
from ..errors import BaseparamsError
from ..model.robot import Robot

#: drive parameter kinds, in their order within a joint
KINDS = ("Ia", "Fv", "Fc", "Fo")
#: friction names (CLI ``--friction``) -> kinds
FRICTION = {"viscous": "Fv", "coulomb": "Fc", "offset": "Fo"}
#: every friction term, in order: the default of the drive model and of identification
FRICTION_TERMS = tuple(FRICTION)
#: coupled-motor parameter kinds, in their order within a coupling -> the per-joint kind that selects them
COUPLED_KINDS = {"Iam": "Ia", "Fvm": "Fv", "Fcm": "Fc"}
_COUPLING_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")


@dataclass(frozen=True)
class MotorCoupling:
    """A motor driving several joints through a linear transmission (a coupled wrist).

    Its joint-side velocity is ``v_m = sum_j w_j dq_j``; its torque reaches joint ``j`` as
    ``w_j`` times the motor's (the transpose). Parameters ``Iam_<name>``, ``Fvm_<name>``,
    ``Fcm_<name>`` (module docstring).

    Parameters
    ----------
    name : str
        The motor's name (letters, digits, ``_``, ``.``, ``-``), e.g. ``m6``.
    joints : tuple of str, shape ``(k,)``
        Model joint names of the joints it drives (driven, measured 1-dof joints).
    weights : tuple of float, shape ``(k,)``
        ``w_j``, non-zero [dimensionless: joint-side units of the motor per unit of joint ``j``].

    Raises
    ------
    BaseparamsError
        A bad name, no joint, a repeated joint, a weight count that does not match or a weight
        that is zero or not finite.
    """

    name: str
    joints: tuple[str, ...]
    weights: tuple[float, ...]

    __repr__ = summary_repr

    def __post_init__(self):
        what = f"motor coupling {self.name!r}"
        if isinstance(self.joints, str):
            raise BaseparamsError(f"{what}: joints must be a sequence of joint names, got the string {self.joints!r}")
        joints = tuple(str(j) for j in self.joints)
        try:
            weights = tuple(float(w) for w in self.weights)
        except (TypeError, ValueError):
            raise BaseparamsError(f"{what}: weights must be numbers, got {self.weights!r}") from None
        if not isinstance(self.name, str) or not _COUPLING_NAME.match(self.name):
            raise BaseparamsError(f"{what}: the name must be letters, digits, '_', '.' or '-'")
        if not joints or len(joints) != len(weights):
            raise BaseparamsError(f"{what}: give one weight per joint, at least one joint "
                                  f"(got {counted(len(joints), 'joint')}, {counted(len(weights), 'weight')})")
        if len(set(joints)) != len(joints):
            raise BaseparamsError(f"{what}: a joint is named twice in {list(joints)}")
        if not all(math.isfinite(w) and w != 0 and abs(w) <= 1e6 for w in weights):
            raise BaseparamsError(f"{what}: weights must be finite and non-zero, at most 1e6 in size, got "
                                  f"{list(weights)}")
        object.__setattr__(self, "joints", joints)
        object.__setattr__(self, "weights", weights)

    @classmethod
    def parse(cls, text: str) -> MotorCoupling:
        """A coupling from ``NAME:JOINT=W,JOINT=W`` (the CLI's ``--coupling``).

        Parameters
        ----------
        text : str
            E.g. ``m6:joint_5=1,joint_6=1``.

        Returns
        -------
        MotorCoupling
            The coupling.

        Raises
        ------
        BaseparamsError
            Text not of that form, or a bad coupling (see the class).
        """
        name, sep, rest = str(text).partition(":")
        pairs = [p.partition("=") for p in rest.split(",")] if sep else []
        if not pairs or any(not j.strip() or not e or not w.strip() for j, e, w in pairs):
            raise BaseparamsError(f"motor coupling {text!r}: expected NAME:JOINT=WEIGHT,JOINT=WEIGHT "
                                  f"(e.g. m6:joint_5=1,joint_6=1)")
        weights = []
        for j, _, w in pairs:
            try:
                weights.append(float(w))
            except ValueError:
                raise BaseparamsError(f"motor coupling {text!r}: weight {w.strip()!r} of {j.strip()!r} "
                                      f"is not a number") from None
        return cls(name.strip(), tuple(j.strip() for j, _, _ in pairs), tuple(weights))


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
    couplings : tuple of MotorCoupling, optional
        Motors driving several joints (:class:`MotorCoupling`).
    coupling_rows : tuple of ndarray of int, optional
        Per coupling, the measured row of each of its joints (its ``joints`` order).
    """

    joints: tuple[str, ...]
    rows: np.ndarray
    kinds: tuple[str, ...]
    coulomb_width: float | None = None
    couplings: tuple[MotorCoupling, ...] = ()
    coupling_rows: tuple[np.ndarray, ...] = ()

    __repr__ = summary_repr

    @property
    def coupled_kinds(self) -> tuple[str, ...]:
        """The kinds per coupling: those of :data:`COUPLED_KINDS` whose per-joint kind is selected."""
        return tuple(c for c, k in COUPLED_KINDS.items() if k in self.kinds)

    @property
    def n_params(self) -> int:
        """Number of drive parameters ``nd = len(joints) len(kinds) + len(couplings) len(coupled_kinds)``."""
        return len(self.joints) * len(self.kinds) + len(self.couplings) * len(self.coupled_kinds)

    @property
    def names(self) -> list[str]:
        """``<kind>_<joint>`` for every drive parameter, e.g. ``Fv_joint2``, then ``Iam_<coupling>``, ..."""
        own = [f"{k}_{j}" for j in self.joints for k in self.kinds]
        return own + [f"{k}_{c.name}" for c in self.couplings for k in self.coupled_kinds]

    @property
    def param_kinds(self) -> list[str]:
        """The kind of every drive parameter, ``(nd,)``."""
        return [k for _ in self.joints for k in self.kinds] + [k for _ in self.couplings for k in self.coupled_kinds]

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
            Column ``k`` is drive parameter ``k``'s (:meth:`param_column`) on its rows; zero
            elsewhere.
        """
        out = np.zeros((dq.shape[0], nrows, self.n_params))
        for k in range(self.n_params):
            rows, values = self.param_column(k, dq, ddq)
            out[:, rows, k] = values
        return out

    def torques(self, dq: np.ndarray, ddq: np.ndarray, nrows: int, delta) -> np.ndarray:
        """The drives' generalized forces ``D delta`` without forming ``D`` (memory ``O(S nrows)``).

        Parameters
        ----------
        dq, ddq : ndarray, shape ``(S, nrows)``
            Velocities and accelerations of the measured rows' coordinates.
        nrows : int
            Number of measured rows.
        delta : array_like, shape ``(nd,)``
            Drive parameters (:attr:`names` order).

        Returns
        -------
        ndarray, shape ``(S, nrows)``
            ``regressor(dq, ddq, nrows) @ delta`` [N m or N].
        """
        delta = np.asarray(delta, dtype=float).reshape(-1)
        out = np.zeros((dq.shape[0], nrows))
        for k in np.flatnonzero(delta):
            rows, values = self.param_column(int(k), dq, ddq)
            out[:, rows] += values * delta[k]
        return out

    def param_kind(self, k: int) -> str:
        """The kind of drive parameter ``k`` (``"Ia"``, ``"Fv"``, ``"Fc"``, ``"Fo"`` or a coupled ``"Iam"`` ...).

        Parameters
        ----------
        k : int
            The drive parameter, ``0 <= k < nd``.

        Returns
        -------
        str
            Its kind.
        """
        own = len(self.joints) * len(self.kinds)
        if k < own:
            return self.kinds[k % len(self.kinds)]
        return self.coupled_kinds[(k - own) % len(self.coupled_kinds)]

    def param_column(self, k: int, dq: np.ndarray, ddq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The rows drive parameter ``k`` acts on and its column there.

        Parameters
        ----------
        k : int
            The drive parameter, ``0 <= k < nd``.
        dq, ddq : ndarray, shape ``(S, nrows)``
            Velocities and accelerations of the measured rows' coordinates.

        Returns
        -------
        rows : ndarray of int, shape ``(r,)``
            Its measured rows: the joint's one, or a coupling's joints' rows.
        values : ndarray, shape ``(S, r)``
            Its column on those rows: :meth:`column` of the joint's rates, or
            ``w_j column(v_m, a_m)`` of a coupling (module docstring).
        """
        own = len(self.joints) * len(self.kinds)
        if k < own:
            j, i = divmod(k, len(self.kinds))
            r = int(self.rows[j])
            return np.array([r]), self.column(self.kinds[i], dq[:, r], ddq[:, r])[:, None]
        c, i = divmod(k - own, len(self.coupled_kinds))
        rows, w = self.coupling_rows[c], np.asarray(self.couplings[c].weights)
        return rows, self.column(self.coupled_kinds[i], dq[:, rows] @ w, ddq[:, rows] @ w)[:, None] * w

    def column(self, kind: str, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """One drive column of one joint (or of a coupled motor).

        Parameters
        ----------
        kind : {"Ia", "Fv", "Fc", "Fo", "Iam", "Fvm", "Fcm"}
            The parameter kind (a coupled kind acts like its per-joint one on the motor's rates).
        v, a : ndarray, shape ``(S,)``
            The joint's (or motor's joint-side) velocity and acceleration.

        Returns
        -------
        ndarray, shape ``(S,)``
            ``a``, ``v``, ``sign(v)`` (or ``tanh(v / w)``) or ones.
        """
        kind = COUPLED_KINDS.get(kind, kind)
        if kind == "Ia":
            return a
        if kind == "Fv":
            return v
        if kind == "Fc":
            return np.sign(v) if self.coulomb_width is None else np.tanh(v / self.coulomb_width)
        return np.ones_like(v)


def friction_terms(friction) -> tuple[str, ...]:
    """Friction terms as a tuple of names: ``"viscous,coulomb"``, ``"none"`` or a sequence of names.

    Parameters
    ----------
    friction : str or iterable of str
        Comma-separated names, ``"none"`` (or empty), or a list, tuple or set of names, each of
        :data:`FRICTION` (``viscous``, ``coulomb``, ``offset``).

    Returns
    -------
    tuple of str
        The names (empty for ``"none"``).

    Raises
    ------
    ArgumentTypeError
        Neither a string nor a sequence of strings.
    BaseparamsError
        An unknown name.
    """
    if isinstance(friction, str):
        names = () if friction.strip().lower() in ("", "none") else tuple(x.strip() for x in friction.split(",")
                                                                          if x.strip())
    elif isinstance(friction, (list, tuple, set, frozenset)) and all(isinstance(x, str) for x in friction):
        names = tuple(friction)
    else:
        from ..arguments import ArgumentTypeError

        raise ArgumentTypeError(f"friction= must be 'viscous,coulomb,offset', 'none' or a sequence of those names, "
                                f"got {type(friction).__name__}")
    unknown = [f for f in names if f not in FRICTION]
    if unknown:
        raise BaseparamsError(f"unknown friction term(s) {unknown}; choose from {', '.join(FRICTION)}")
    return names


def drives_for(robot: Robot, coords: np.ndarray, rotor: bool = True, friction=FRICTION_TERMS,
               coulomb_width: float | None = None, couplings=()) -> Drives:
    """Drives on every measured 1-dof joint (R or P) among ``coords``, and coupled motors.

    Parameters
    ----------
    robot : Robot
        The robot.
    coords : array_like of int, shape ``(nrows,)``
        The coordinates of the measured rows, in row order (a floating base's six are not
        driven).
    rotor : bool
        Include the rotor inertia ``Ia`` (and a coupled motor's ``Iam``).
    friction : iterable of str
        Any of ``viscous``, ``coulomb``, ``offset`` (:data:`FRICTION`; a coupled motor gets
        ``Fvm``, ``Fcm`` with the first two).
    coulomb_width : float, optional
        Smooth Coulomb friction's velocity scale (see :class:`Drives`).
    couplings : iterable of MotorCoupling
        Motors driving several of the driven joints (:class:`MotorCoupling`).

    Returns
    -------
    Drives
        With no parameter at all when neither ``rotor`` nor any friction is asked for.

    Raises
    ------
    BaseparamsError
        An unknown friction name, a non-positive ``coulomb_width``, a coupling of a joint that is
        not driven, two couplings of one name, or couplings without rotor inertia, viscous or
        Coulomb friction.
    """
    friction = friction_terms(friction if isinstance(friction, str) else tuple(friction))
    if coulomb_width is not None and not coulomb_width > 0:
        raise BaseparamsError(f"coulomb_width must be > 0 (rad/s), got {coulomb_width}")
    chosen = {"Ia"} if rotor else set()
    chosen |= {FRICTION[f] for f in friction}
    kinds = tuple(k for k in KINDS if k in chosen)
    body = robot.dof_body
    rows = [r for r, c in enumerate(np.asarray(coords, dtype=int)) if robot.jtype[body[c]] in ("R", "P")]
    names = tuple(robot.joint_names[body[coords[r]]] for r in rows)
    drives = Drives(names if kinds else (), np.array(rows if kinds else [], dtype=int), kinds, coulomb_width)
    couplings = tuple(couplings)
    if not couplings:
        return drives
    if not drives.coupled_kinds:
        raise BaseparamsError("a motor coupling needs rotor inertia or viscous or Coulomb friction to identify")
    where = dict(zip(names, rows))
    for c in couplings:
        if not isinstance(c, MotorCoupling):
            raise BaseparamsError(f"couplings must be MotorCoupling objects, got {type(c).__name__}")
        missing = [j for j in c.joints if j not in where]
        if missing:
            raise BaseparamsError(f"motor coupling {c.name!r}: {missing} not among the driven joints {list(names)}")
    if len({c.name for c in couplings}) != len(couplings):
        raise BaseparamsError(f"motor couplings need distinct names, got {[c.name for c in couplings]}")
    rows_of = tuple(np.array([where[j] for j in c.joints], dtype=int) for c in couplings)
    return Drives(drives.joints, drives.rows, kinds, coulomb_width, couplings, rows_of)


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

    __repr__ = summary_repr

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


    def sparse_matrix(self):
        """:meth:`matrix` as a ``scipy.sparse`` CSR matrix (a large model: ``K`` has few columns).

        Returns
        -------
        scipy.sparse.csr_matrix, shape ``(p, nb + nd)``
            Identity on the independent columns, ``K`` on the dependent ones.
        """
        import scipy.sparse as sp

        p = len(self.independent)
        k = np.asarray(self.K, dtype=float).reshape(p, len(self.dependent))
        rows, cols = np.nonzero(k)
        return sp.csr_matrix((np.r_[np.ones(p), k[rows, cols]], (np.r_[np.arange(p), rows],
                                                                  np.r_[self.independent, self.dependent[cols]])),
                             shape=(p, len(self.names)))


def regroup_drives(factor: np.ndarray, base_names: list[str], drives: Drives, rtol: float = 1e-9,
                   min_gap: float = 1e4) -> DriveRegrouping:
    """Decide which drive parameters regroup, from the factor of a sampled ``[Yb | D]``.

    The rank is decided on the drive columns' part outside the base columns' span (``R22`` of the
    factor, each column scaled by its norm); the base columns are independent (certified).

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
    # The base columns are independent (certified): the drive parameters regroup exactly where the
    # drive columns' parts outside span(Yb), R22, are dependent. Deciding on R22 with each drive
    # column scaled by its norm keeps the base columns' scales and conditioning (a deep chain's span
    # orders of magnitude) out of the decision; a null vector u of R22 is [-R11^-1 R12 u; u].
    from scipy.linalg import solve_triangular

    r = np.asarray(factor, dtype=float)
    if r.shape[0] < nb + nd:
        r = np.vstack([r, np.zeros((nb + nd - r.shape[0], nb + nd))])
    scale = np.linalg.norm(r[:, nb:], axis=0)
    scale[scale == 0] = 1.0
    num = rank_decision(r[nb:, nb:] / scale, rtol, min_gap) if nd else None
    v2 = num.null_basis / scale[:, None] if nd else np.zeros((0, 0))
    k = v2.shape[1]
    v1 = solve_triangular(r[:nb, :nb], -r[:nb, nb:] @ v2) if k and nb else np.zeros((nb, k))
    nullb = np.vstack([v1, v2])
    nullb /= np.maximum(np.linalg.norm(nullb, axis=0), np.finfo(float).tiny)
    order = np.r_[np.arange(nb + nd - 1, nb - 1, -1), np.arange(nb - 1, -1, -1)]
    dep = choose_dependent(nullb, order) if k else np.zeros(0, dtype=int)
    ind = np.setdiff1d(np.arange(nb + nd), dep)
    kmat = np.zeros((len(ind), k))
    if k:
        kmat = -np.linalg.solve(nullb[dep].T, nullb[ind].T).T
        kmat[np.abs(kmat) <= 1e-9 * np.maximum(1.0, np.abs(kmat).max(axis=1, keepdims=True))] = 0.0
        kmat = clean(kmat, rtol=1e-12)  # decided on sampled states: rounding ~1e-15
    gap = float(num.gap) if k else np.inf
    return DriveRegrouping(names, ind, dep, kmat, k == 0 or bool(num.decided), gap)
