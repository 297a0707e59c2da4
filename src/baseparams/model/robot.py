"""The robot model: what the paper's Table "rbt" holds, validated.

Indices are 0-based; the fixed base (world) is ``-1``. Bodies are in depth-first
(topological) order: ``parent[i] < i``. Every body's frame is its joint frame (URDF
convention); ``M0[i]`` is its world pose at the reference configuration ``q = 0``.

Joint types and their coordinates (each joint's axes are given in its own frame):

==== ===== =================================================================
type dofs  motion of the child relative to the parent, in the joint frame
==== ===== =================================================================
R    1     rotation about ``axes[0]`` through the frame origin
P    1     translation along ``axes[0]``
U    2     ``Rot(axes[0], q1) Rot(axes[1], q2)`` (axes perpendicular)
S    3     ``Rot(x, q1) Rot(y, q2) Rot(z, q3)`` about the origin (XYZ Euler angles)
F    6     floating; only at the root: configuration ``exp(q^)`` with ``q`` a twist
           (omega, v) in world coordinates; velocities and accelerations are the
           body's spatial twist and its derivative (quasi-velocities, as the paper's Go2)
C    k     compound: ``exp(xi_1 q_1) ... exp(xi_k q_k)`` with ``axes (k, 6)`` unit twists
           ``xi = (omega, v)`` in the joint frame (basis ``e23 e31 e12 e01 e02 e03``): a
           rotation about a line (``|omega| = 1``, ``v = c x omega`` for a point ``c`` on it,
           i.e. ``pga.adjoint`` of the translation to ``c`` applied to ``(omega, 0)``) or a
           translation (``omega = 0``, ``|v| = 1``). MJCF bodies with several joints.
==== ===== =================================================================

``armature (dof,)``: rotor inertia per coordinate (MJCF ``armature``), a prior for
identification; the link base-parameter analysis does not use it.

``limits (dof, 4)``: per coordinate ``[lower, upper, velocity, effort]`` (rad or m, rad/s or m/s,
N m or N), NaN where the file does not say (``None``: nothing known). URDF ``<limit>`` of
revolute and prismatic joints (continuous joints: no position limits), MJCF ``range`` of limited
joints and actuator force ranges. Position limits are in the robot's coordinates: they shift with
the reference (:func:`~baseparams.kinematics.tree.re_reference`: ``lower - q0, upper - q0``). The
analysis does not use them; the excitation designer (:mod:`baseparams.excitation`) does.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from ..display import clip, counted, summary_repr
from ..enums import JointType, values
from ..errors import ModelError
from ..pga import adjoint
from . import inertia as _inertia

#: a body's joint types, and a loop (cut) joint's (plain strings; :class:`~baseparams.enums.JointType`)
JOINT_TYPES = values(t for t in JointType if t is not JointType.FIXED)
LOOP_TYPES = values((JointType.R, JointType.P, JointType.U, JointType.S, JointType.FIXED))
NDOF = {JointType.R: 1, JointType.P: 1, JointType.U: 2, JointType.S: 3, JointType.F: 6,
        JointType.FIXED: 0}  # C: len(axes), see joint_ndof


def joint_ndof(jtype: str, axes: np.ndarray) -> int:
    """Dofs of one joint: :data:`NDOF`, or the number of elementary screws of a C joint.

    Parameters
    ----------
    jtype : str
        Joint type (``R P U S F C`` or ``fixed``).
    axes : array_like
        The joint's axes; only their number counts, for a C joint (``(k, 6)`` twists).

    Returns
    -------
    int
        The number of coordinates of the joint.
    """
    return len(axes) if jtype == "C" else NDOF[jtype]


def compound_screw(axis, point=None, slide: bool = False) -> np.ndarray:
    """One elementary screw of a C joint, in the joint frame.

    A rotation about the unit ``axis`` through ``point``, or a translation along it
    (``slide``).

    Parameters
    ----------
    axis : array_like, shape ``(3,)``
        Direction in the joint frame (normalised here).
    point : array_like, shape ``(3,)``, optional
        A point of the rotation axis in the joint frame [m] (default the origin); ignored with
        ``slide``.
    slide : bool
        A translation along ``axis`` instead of a rotation.

    Returns
    -------
    ndarray, shape ``(6,)``
        The unit twist ``(omega, v)`` (basis ``e23 e31 e12 e01 e02 e03``): ``(a, c x a)`` for
        a rotation, ``(0, a)`` for a translation.
    """
    a = np.asarray(axis, dtype=float).reshape(3)
    a = a / np.linalg.norm(a)
    if slide:
        return np.r_[np.zeros(3), a]
    t = np.eye(4)
    if point is not None:
        t[:3, 3] = np.asarray(point, dtype=float).reshape(3)
    return adjoint(t, np.r_[a, np.zeros(3)])


@dataclass(frozen=True)
class Coupling:
    """A coupling of 1-dof coordinates: linear, or a polynomial of one coordinate.

    ``q[succ] = ratio * q[pred] + sum(r * q[k] for k, r in more) + offset``
    ``+ sum(c * q[pred] ** (k + 2) for k, c in enumerate(poly))`` (URDF+ ``<coupling>``, URDF
    ``<mimic multiplier offset>``, MJCF ``<equality><joint>`` with its ``polycoef`` and
    fixed-tendon equalities).

    Parameters
    ----------
    name : str
        The coupling's name.
    pred : int
        Index in ``q`` of the driving coordinate.
    succ : int
        Index in ``q`` of the driven coordinate.
    ratio : float
        Multiplier of ``q[pred]``.
    offset : float
        Constant term (coordinate units: rad or m).
    more : tuple of (int, float)
        Further coordinates and their ratios, e.g. a tendon tying three joints.
    poly : tuple of float
        Coefficients of ``q[pred] ** 2``, ``q[pred] ** 3``, ... (a nonlinear coupling, MJCF's
        ``polycoef``; only without ``more``).
    """

    name: str
    pred: int
    succ: int
    ratio: float
    offset: float = 0.0
    more: tuple[tuple[int, float], ...] = ()
    poly: tuple[float, ...] = ()

    __repr__ = summary_repr

    def coefficients(self) -> np.ndarray:
        """``q[succ]`` as a polynomial of ``q[pred]`` (the other terms of :attr:`more` aside).

        Returns
        -------
        ndarray, shape ``(d + 1,)``
            Coefficients, lowest power first: ``offset, ratio, *poly``.
        """
        return np.array([self.offset, self.ratio, *self.poly], dtype=float)

    def terms(self) -> list[tuple[int, float]]:
        """Every coordinate on the right-hand side, with its ratio.

        Returns
        -------
        list of (int, float)
            ``[(coordinate, ratio)]``: ``(pred, ratio)`` first, then :attr:`more`.
        """
        return [(self.pred, self.ratio), *self.more]


@dataclass(frozen=True, eq=False)
class LoopJoint:
    """A cut joint closing a loop.

    Parameters
    ----------
    name : str
        The joint's name.
    type : str
        Joint type, one of :data:`LOOP_TYPES` (``R P U S fixed``).
    parent : int
        The predecessor body (``parent < child``; -1 = the world).
    child : int
        The successor body.
    M : ndarray, shape ``(4, 4)``
        The joint frame's world pose at q = 0, carried by the predecessor.
    axes : ndarray, shape ``(k, 3)``
        The joint's axes in the joint frame (U: ``axes[0]`` carried by the predecessor,
        ``axes[1]`` by the successor).
    M_child : ndarray, shape ``(4, 4)``, optional
        The successor's copy of the frame (world pose at q = 0) when it does not coincide with
        ``M`` (an unassembled file; see :func:`baseparams.kinematics.loops.assemble`); ``None``
        when they coincide.
    anchor_free : bool, default False
        The predecessor's side is the world through a control device (a MuJoCo mocap body): its
        frame may be placed where the successor's is, at any reference
        (:func:`~baseparams.kinematics.loops.assemble` moves it off a singular configuration).
    """

    name: str
    type: str
    parent: int
    child: int
    M: np.ndarray
    axes: np.ndarray
    M_child: np.ndarray | None = None
    anchor_free: bool = False

    __repr__ = summary_repr


def _check_frame(t: np.ndarray, what: str) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    if t.shape != (4, 4):
        raise ModelError(f"{what}: frame must be a 4x4 homogeneous matrix, got shape {t.shape}")
    if not np.isfinite(t).all():
        raise ModelError(f"{what}: frame contains NaN or inf")
    r = t[:3, :3]
    if (np.abs(r.T @ r - np.eye(3)).max() > 1e-8 or abs(np.linalg.det(r) - 1) > 1e-8
            or np.abs(t[3] - [0, 0, 0, 1]).max() > 1e-12):
        raise ModelError(f"{what}: frame is not rigid (rotation not orthonormal with det +1, "
                         f"or last row not [0 0 0 1])")
    return t


def _check_compound(axes: np.ndarray, what: str) -> np.ndarray:
    axes = np.asarray(axes, dtype=float)
    if axes.ndim != 2 or axes.shape[1] != 6 or axes.shape[0] == 0:
        raise ModelError(f"{what}: a compound (C) joint needs (k, 6) unit twists (omega, v), got shape {axes.shape}")
    if not np.all(np.isfinite(axes)):
        raise ModelError(f"{what}: axis contains NaN or inf")
    for row in axes:
        w, v = np.linalg.norm(row[:3]), np.linalg.norm(row[3:])
        if w > 1e-12:
            if abs(w - 1) > 1e-9 or abs(row[:3] @ row[3:]) > 1e-9:
                raise ModelError(f"{what}: compound twist {row.tolist()} is not a unit rotation "
                                 f"(|omega| = 1, omega . v = 0)")
        elif abs(v - 1) > 1e-9:
            raise ModelError(f"{what}: compound twist {row.tolist()} is neither a unit rotation nor a unit "
                             f"translation (omega = 0, |v| = 1)")
    return axes


def _check_axes(axes: np.ndarray, jtype: str, what: str) -> np.ndarray:
    if jtype == "C":
        return _check_compound(axes, what)
    axes = np.asarray(axes, dtype=float).reshape(-1, 3) if np.size(axes) else np.zeros((0, 3))
    want = {"R": 1, "P": 1, "U": 2, "S": 0, "F": 0, "fixed": 0}[jtype]
    if jtype == "S" and axes.shape[0] == 0:
        axes = np.eye(3)
    if jtype == "S" and not np.allclose(axes, np.eye(3)):
        raise ModelError(f"{what}: a spherical joint's axes are x, y, z of its frame (rotate the frame instead)")
    if jtype not in ("S",) and axes.shape[0] != want:
        raise ModelError(f"{what}: joint type {jtype} needs {want} axis/axes, got {axes.shape[0]}")
    if not np.all(np.isfinite(axes)):
        raise ModelError(f"{what}: axis contains NaN or inf")
    norms = np.linalg.norm(axes, axis=1)
    if np.any(norms < 1e-12):
        raise ModelError(f"{what}: zero joint axis")
    if np.any(np.abs(norms - 1) > 1e-9):
        raise ModelError(f"{what}: joint axis {axes[np.argmax(np.abs(norms - 1))].tolist()} is not a unit vector")
    if jtype == "U" and abs(axes[0] @ axes[1]) > 1e-9:
        raise ModelError(f"{what}: the two axes of a universal joint must be perpendicular")
    return axes


@dataclass(frozen=True, eq=False)
class Robot:
    """A validated tree robot (plus loop joints recorded for later use).

    The paper's Table "rbt" (module doc). Construction validates every field (a one-line
    :class:`ModelError` naming the robot and the part) and stores the arrays normalised.
    ``n`` is the number of bodies, ``dof`` the number of coordinates.

    Parameters
    ----------
    name : str
        The robot's name.
    names : tuple of str, shape ``(n,)``
        Body (link) names, unique.
    joint_names : tuple of str, shape ``(n,)``
        Each body's joint name.
    jtype : tuple of str, shape ``(n,)``
        Joint types in ``R P U S F C`` (:data:`JOINT_TYPES`); F only at a root.
    parent : array_like of int, shape ``(n,)``
        Parent body, ``-1`` = fixed base, ``parent[i] < i``.
    M0 : array_like, shape ``(n, 4, 4)``
        World pose of each joint/body frame at q = 0.
    axes : tuple of ndarray
        Per body ``(k, 3)`` joint axes in the joint frame (C: ``(k, 6)`` twists).
    N_body : array_like, shape ``(n, 4, 4)``
        Pseudo-inertias in the body frame.
    gravity : array_like, shape ``(3,)``
        Gravity [m/s^2] in the world frame (default ``(0, 0, -9.81)``).
    loops : tuple of LoopJoint
        Loop (cut) joints.
    independent : tuple of int, optional
        The independent (actuated) coordinates, distinct indices into ``q`` (stored sorted);
        required when there are loops or couplings. ``None``: every coordinate.
    q_box : array_like, shape ``(na, 2)``, optional
        Sampling box (low < high) of the independent coordinates (``na`` of them).
    couplings : tuple of Coupling
        Linear couplings of coordinates.
    armature : array_like, shape ``(dof,)``, optional
        Rotor inertia per coordinate (default zeros; not used by the analysis).
    limits : array_like, shape ``(dof, 4)``, optional
        Per coordinate ``[lower, upper, velocity, effort]`` (rad or m; rad/s or m/s; N m or N),
        NaN where unknown (module doc); ``None`` (default): all unknown. ``lower <= upper`` where
        both are known; velocity and effort limits are non-negative.
    source : FileSource, optional
        The file the robot was read from (:class:`~baseparams.model.snap.FileSource`, set by the
        readers), so that values the file states to within rounding of a right angle can be
        re-read exact; ignored once the robot's geometry differs from the file's.

    Raises
    ------
    ModelError
        Any field invalid (shapes, names, joint types, parent order, frames, axes, inertias,
        loops, couplings, ``independent``, ``q_box``, ``armature``, ``limits``).
    """

    name: str
    names: tuple[str, ...]
    joint_names: tuple[str, ...]
    jtype: tuple[str, ...]
    parent: np.ndarray
    M0: np.ndarray
    axes: tuple[np.ndarray, ...]
    N_body: np.ndarray
    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -9.81]))
    loops: tuple[LoopJoint, ...] = ()
    independent: tuple[int, ...] | None = None
    q_box: np.ndarray | None = None
    couplings: tuple[Coupling, ...] = ()
    armature: np.ndarray | None = None
    limits: np.ndarray | None = None
    source: object | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        """Validate every field and store the arrays normalised.

        A failure is a one-line :class:`ModelError` naming the robot and the part.
        """
        what = f"robot {self.name!r}"
        parent, m0, nb = self._check_shapes(what)
        axes = self._check_bodies(what, parent, m0, nb)
        g = np.asarray(self.gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ModelError(f"{what}: gravity must be 3 finite numbers, got {self.gravity!r}")
        self._check_loops(what)
        dof = int(sum(joint_ndof(t, a) for t, a in zip(self.jtype, axes)))
        self._check_armature(what, dof)
        self._check_independent(what, dof)
        self._check_couplings(what, dof)
        self._check_q_box(what, dof)
        self._check_limits(what, dof)
        object.__setattr__(self, "parent", parent)
        object.__setattr__(self, "M0", m0)
        object.__setattr__(self, "N_body", nb)
        object.__setattr__(self, "axes", tuple(axes))
        object.__setattr__(self, "gravity", g)

    def _check_shapes(self, what: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At least one body, per-body fields of one length, unique names.

        Returns ``(parent, M0, N_body)`` as arrays of the right shapes.
        """
        n = len(self.names)
        if n == 0:
            raise ModelError(f"{what}: no bodies")
        for arr, label in ((self.joint_names, "joint_names"), (self.jtype, "jtype"), (self.axes, "axes")):
            if len(arr) != n:
                raise ModelError(f"{what}: {label} has {counted(len(arr), 'entry', 'entries')} for "
                                 f"{counted(n, 'body', 'bodies')}")
        if len(set(self.names)) != n:
            dup = [x for x in self.names if self.names.count(x) > 1][0]
            raise ModelError(f"{what}: duplicate body name {dup!r}")
        parent = np.asarray(self.parent, dtype=int)
        if parent.shape != (n,):
            raise ModelError(f"{what}: parent must have shape ({n},), got {parent.shape}")
        m0 = np.asarray(self.M0, dtype=float)
        if m0.shape != (n, 4, 4):
            raise ModelError(f"{what}: M0 must have shape ({n}, 4, 4), got {m0.shape}")
        nb = np.asarray(self.N_body, dtype=float)
        if nb.shape != (n, 4, 4):
            raise ModelError(f"{what}: N_body must have shape ({n}, 4, 4), got {nb.shape}")
        return parent, m0, nb

    def _check_bodies(self, what: str, parent: np.ndarray, m0: np.ndarray, nb: np.ndarray) -> list[np.ndarray]:
        """Each body's joint type, parent index, frame, axes and pseudo-inertia; the checked axes."""
        axes = []
        for i in range(len(self.names)):
            jw = f"{what}, body {self.names[i]!r} (joint {self.joint_names[i]!r})"
            if self.jtype[i] not in JOINT_TYPES:
                raise ModelError(f"{jw}: unknown joint type {self.jtype[i]!r}; expected one of {JOINT_TYPES}")
            if not (-1 <= parent[i] < i):
                raise ModelError(f"{jw}: parent index {parent[i]} must come before the child "
                                 f"(depth-first order, -1 = fixed base)")
            if self.jtype[i] == "F" and parent[i] != -1:
                raise ModelError(f"{jw}: a floating (F) joint must connect the fixed base (parent -1)")
            _check_frame(m0[i], jw)
            axes.append(_check_axes(self.axes[i], self.jtype[i], jw))
            if not np.all(np.isfinite(nb[i])) or np.abs(nb[i] - nb[i].T).max() > 1e-9 * (1 + np.abs(nb[i]).max()):
                raise ModelError(f"{jw}: inertia must be a finite symmetric pseudo-inertia")
        return axes

    def _check_loops(self, what: str) -> None:
        """Each loop joint's type, body indices and frame."""
        n = len(self.names)
        for lj in self.loops:
            lw = f"{what}, loop joint {lj.name!r}"
            if lj.type not in LOOP_TYPES:
                raise ModelError(f"{lw}: unknown loop joint type {lj.type!r}; expected one of {LOOP_TYPES}")
            if not (-1 <= lj.parent < lj.child < n):
                raise ModelError(f"{lw}: needs parent index < child index < {n}, got {lj.parent}, {lj.child}")
            _check_frame(lj.M, lw)

    def _check_armature(self, what: str, dof: int) -> None:
        """``armature``: ``(dof,)`` finite numbers, zeros when not given."""
        arm = np.zeros(dof) if self.armature is None else np.asarray(self.armature, dtype=float)
        if arm.shape != (dof,) or not np.all(np.isfinite(arm)):
            raise ModelError(f"{what}: armature must be ({dof},) finite numbers, got shape {arm.shape}")
        object.__setattr__(self, "armature", arm)

    def _check_independent(self, what: str, dof: int) -> None:
        """``independent``: distinct coordinates, stored sorted."""
        if self.independent is not None:
            ind = tuple(int(k) for k in self.independent)
            if len(set(ind)) != len(ind) or any(not (0 <= k < dof) for k in ind) or not ind:
                raise ModelError(f"{what}: independent coordinates {ind} must be distinct indices in [0, {dof})")
            object.__setattr__(self, "independent", tuple(sorted(ind)))

    def _check_couplings(self, what: str, dof: int) -> None:
        """Each coupling's coordinates and ratios; loops or couplings need ``independent``."""
        for c in self.couplings:
            idx = [c.succ] + [k for k, _ in c.terms()]
            if (len(set(idx)) != len(idx) or not all(0 <= k < dof for k in idx)
                    or not all(np.isfinite(r) for _, r in c.terms()) or not np.isfinite(c.offset)
                    or not all(np.isfinite(x) for x in c.poly)):
                raise ModelError(f"{what}, coupling {c.name!r}: needs distinct coordinates in [0, {dof}) "
                                 f"and finite ratios")
            if c.poly and c.more:
                raise ModelError(f"{what}, coupling {c.name!r}: a polynomial coupling has one driving coordinate")
        if self.independent is None and (self.loops or self.couplings):
            raise ModelError(f"{what}: a robot with loop joints must say which coordinates are "
                             f"independent (actuated)")

    def _check_q_box(self, what: str, dof: int) -> None:
        """``q_box``: ``(independent coordinates, 2)`` with low < high."""
        if self.q_box is not None:
            box = np.asarray(self.q_box, dtype=float)
            na = len(self.independent) if self.independent is not None else dof
            if box.shape != (na, 2) or not np.all(box[:, 0] < box[:, 1]):
                raise ModelError(f"{what}: q_box must be ({na}, 2) with low < high, got {box.shape}")
            object.__setattr__(self, "q_box", box)

    def _check_limits(self, what: str, dof: int) -> None:
        """``limits``: ``(dof, 4)`` numbers or NaN, lower <= upper, rates and efforts >= 0."""
        if self.limits is None:
            return
        lim = np.array(self.limits, dtype=float)
        if lim.shape != (dof, 4):
            raise ModelError(f"{what}: limits must have shape ({dof}, 4) (lower, upper, velocity, effort per "
                             f"coordinate), got {lim.shape}")
        with np.errstate(invalid="ignore"):
            bad = np.flatnonzero((lim[:, 0] > lim[:, 1]) | np.any(lim[:, 2:] < 0, axis=1))
        if bad.size:
            raise ModelError(f"{what}: limits of coordinate {int(bad[0])} {lim[bad[0]].tolist()}: need lower <= upper "
                             f"and non-negative velocity and effort (NaN: unknown)")
        object.__setattr__(self, "limits", lim)

    def __repr__(self) -> str:
        kinds = Counter(self.jtype)
        joints = ", ".join(f"{kinds[t]} {t}" for t in JOINT_TYPES if kinds[t])
        text = f"<Robot {self.name}: {self.n} bodies, {self.dof} dofs ({joints}), "
        text += "floating base" if self.floating else "fixed base"
        if self.loops:
            text += f", {len(self.loops)} loop joint{'s' if len(self.loops) > 1 else ''}"
        if self.couplings:
            text += f", {len(self.couplings)} coupling{'s' if len(self.couplings) > 1 else ''}"
        if self.has_loops:
            text += f", {len(self.actuated)} actuated"
        return clip(text + ">")

    # ---------------------------------------------------------------- derived data
    @property
    def n(self) -> int:
        """Number of moving bodies."""
        return len(self.names)

    @property
    def floating(self) -> bool:
        """True when the root is a floating (F) joint."""
        return "F" in self.jtype

    @cached_property
    def ndofs(self) -> np.ndarray:
        """Dofs per joint ``(n,)`` (cached, read-only)."""
        out = np.array([joint_ndof(t, a) for t, a in zip(self.jtype, self.axes)], dtype=int)
        out.flags.writeable = False
        return out

    @property
    def dof(self) -> int:
        """Number of coordinates (length of ``q``), the sum of :attr:`ndofs`."""
        return int(self.ndofs.sum())

    @property
    def actuated(self) -> np.ndarray:
        """Indices of the independent (actuated) coordinates ``(na,)``; all of q for a tree."""
        if self.independent is None:
            return np.arange(self.dof)
        return np.array(self.independent, dtype=int)

    @property
    def has_loops(self) -> bool:
        """True when loop joints or couplings constrain the tree coordinates."""
        return len(self.loops) > 0 or len(self.couplings) > 0

    @property
    def measured_coords(self) -> np.ndarray:
        """The coordinates a joint log measures ``(m,)``: the actuated ones with loops, else every one."""
        return np.asarray(self.actuated, dtype=int) if self.has_loops else np.arange(self.dof)

    def coordinate_names(self, coords=None) -> list[str]:
        """The name of each coordinate: a joint log's and a trajectory's column names, one per coordinate.

        A 1-dof joint's coordinate is named as the joint. A joint of several coordinates names
        each one apart: an MJCF body's joints, merged into one compound joint ``rootx+rootz+rooty``,
        by their own names (``rootx``, ``rootz``, ``rooty``), any other (URDF ``planar``, a ball,
        a universal joint) by the joint's name and the coordinate's place in it (``p.0``, ``p.1``,
        ``p.2``, in the order of the joint's axes). Every name differs from every other.

        Parameters
        ----------
        coords : array_like of int, shape ``(m,)``, optional
            Coordinates (indices into ``q``); default :attr:`measured_coords`.

        Returns
        -------
        list of str
            The name of each coordinate.
        """
        coords = self.measured_coords if coords is None else coords
        names = self._coordinate_labels
        return [names[c] for c in coords]

    @cached_property
    def _coordinate_labels(self) -> tuple[str, ...]:
        """:meth:`coordinate_names` of every coordinate (cached)."""
        joints = set(self.joint_names)
        out: list[str] = []
        for name, d in zip(self.joint_names, self.ndofs):
            parts = name.split("+")
            if d == 1:
                parts = [name]
            elif len(parts) != d or len(set(parts)) != d or any(not p or p in joints for p in parts):
                parts = [f"{name}.{k}" for k in range(d)]
            for p in parts:
                while p in out or (p in joints and p != name):
                    p += "_"
                out.append(p)
        return tuple(out)

    @property
    def only_couplings(self) -> bool:
        """True when couplings (URDF ``<mimic>``) constrain the tree and no loop joint does.

        Linear couplings hold at every configuration: nothing is assembled, no sample is
        discarded, and reports say "coupled joints", not "loops".
        """
        return len(self.couplings) > 0 and len(self.loops) == 0

    @property
    def q_index(self) -> np.ndarray:
        """First coordinate of each joint in ``q`` ``(n,)``."""
        return np.concatenate([[0], np.cumsum(self.ndofs)[:-1]]).astype(int)

    @property
    def dof_body(self) -> np.ndarray:
        """Body moved by each coordinate ``(dof,)``."""
        return np.repeat(np.arange(self.n), self.ndofs)

    @cached_property
    def local_screws(self) -> np.ndarray:
        """Unit twists ``(dof, 6)`` of every coordinate in its own joint frame (cached)."""
        out = np.zeros((self.dof, 6))
        k = 0
        for i, t in enumerate(self.jtype):
            nd = joint_ndof(t, self.axes[i])
            if t == "P":
                out[k, 3:] = self.axes[i][0]
            elif t == "C":
                out[k:k + nd] = self.axes[i]
            elif t == "F":
                out[k:k + 6] = np.eye(6)
            elif nd:
                out[k:k + nd, :3] = self.axes[i]
            k += nd
        out.flags.writeable = False
        return out

    @cached_property
    def screws(self) -> np.ndarray:
        """Joint lines ``L0 (dof, 6)``: unit twists in world coordinates at q = 0.

        Cached; do not modify. For F, the world basis ``e23 e31 e12 e01 e02 e03`` (the root
        frame is ignored).
        """
        body = self.dof_body
        s = adjoint(self.M0[body], self.local_screws)
        f = np.array([self.jtype[b] == "F" for b in body], dtype=bool)
        s[f] = self.local_screws[f]
        s.flags.writeable = False
        return s

    def path_dofs(self, body: int) -> np.ndarray:
        """The coordinates that move ``body``: those of the joints on its path to the root.

        ``O(depth)``: the column ``support[:, body]`` without the ``(dof, n)`` matrix.

        Parameters
        ----------
        body : int
            A body index.

        Returns
        -------
        ndarray of int
            Coordinate indices, increasing (root side first).
        """
        qi, nd, out = self.q_index, self.ndofs, []
        b = int(body)
        while b >= 0:
            out.append(np.arange(qi[b], qi[b] + nd[b]))
            b = int(self.parent[b])
        return np.concatenate(out[::-1]) if out else np.zeros(0, dtype=int)

    @property
    def subtree_end(self) -> np.ndarray:
        """``(n,)`` int: one past the last body of each body's subtree when contiguous, else -1.

        Body ``i``'s subtree is then ``i .. end[i] - 1``. ``O(n)`` (parents precede children): what
        :attr:`support` shows row by row, without it.
        """
        n = self.n
        size = np.ones(n, dtype=np.int64)
        last = np.arange(n, dtype=np.int64)
        for i in range(n - 1, -1, -1):
            p = self.parent[i]
            if p >= 0:
                size[p] += size[i]
                last[p] = max(last[p], last[i])
        return np.where(last - np.arange(n) + 1 == size, last + 1, -1)

    @property
    def support(self) -> np.ndarray:
        """``(dof, n)`` bool: coordinate ``j`` moves body ``i`` (``j`` on ``i``'s path).

        Dense (quadratic in the body count): large trees use :meth:`path_dofs` and
        :attr:`subtree_end` instead.
        """
        anc = np.zeros((self.n, self.n), dtype=bool)
        for i in range(self.n):
            anc[i, i] = True
            p = self.parent[i]
            if p >= 0:
                anc[:, i] |= anc[:, p]
        return anc[self.dof_body]

    @property
    def N0(self) -> np.ndarray:
        """Spatial pseudo-inertias ``(n, 4, 4)``: world frame at q = 0 (the paper's ``N``)."""
        return _inertia.transform(self.N_body, self.M0)

    def parameters(self, convention: str) -> np.ndarray:
        """The robot's inertial parameters in ``convention``.

        Parameters
        ----------
        convention : str
            Required: a parameter vector always says its convention (see
            :data:`baseparams.model.inertia.CONVENTIONS`). ``"paper"``: spatial pseudo-inertia
            entries in the world frame at q = 0 (what the TP regressor multiplies); every other
            convention: link (body/joint) frame, e.g. ``"khalil"``
            (``XX XY XZ YY YZ ZZ MX MY MZ M``) or ``"pinocchio"``.

        Returns
        -------
        ndarray, shape ``(10 n,)``
            Ten parameters per body, bodies in order, each in the convention's order.

        Raises
        ------
        ModelError
            Unknown convention.
        """
        _inertia.check_convention(convention)
        n = self.N0 if convention == "paper" else self.N_body
        return _inertia.to_convention(n, convention).reshape(-1)

    def with_parameters(self, params: np.ndarray, convention: str) -> Robot:
        """The same robot with other inertial parameters.

        Parameters
        ----------
        params : array_like, shape ``(10 n,)``
            Ten parameters per body in ``convention`` (as :meth:`parameters` returns them).
        convention : str
            The convention of ``params`` (required; see :meth:`parameters`): ``"paper"`` in
            the world frame at q = 0, the others in the link frames.

        Returns
        -------
        Robot
            A copy with :attr:`N_body` replaced; everything else is shared.

        Raises
        ------
        ModelError
            Unknown convention or a wrong number of parameters.
        """
        _inertia.check_convention(convention)
        p = np.asarray(params, dtype=float)
        if p.size != 10 * self.n:
            raise ModelError(f"robot {self.name!r}: expected {10 * self.n} parameters (10 per body), got {p.size}")
        n = _inertia.from_convention(p.reshape(self.n, 10), convention)
        if convention == "paper":
            from ..pga import inverse_transform

            n = _inertia.transform(n, inverse_transform(self.M0))
        return replace(self, N_body=n)

    def in_world(self, t: np.ndarray) -> Robot:
        """The same robot seen from another world frame: ``M0 -> t M0``, gravity rotated.

        Body-frame inertias and joint axes (in joint frames) are unchanged, so every physical
        quantity is the same. Loop joints' frames ``M`` move with the world. The coordinates do
        not change, nor do :attr:`limits`.

        Parameters
        ----------
        t : array_like, shape ``(4, 4)``
            Pose of the old world frame in the new one (rigid).

        Returns
        -------
        Robot
            The robot with ``M0``, ``gravity`` and the loop frames expressed in the new world
            frame.

        Raises
        ------
        ModelError
            ``t`` is not a rigid 4x4 transform.
        """
        t = _check_frame(t, f"robot {self.name!r}: world transform")
        loops = tuple(replace(lj, M=t @ lj.M, M_child=None if lj.M_child is None else t @ lj.M_child)
                      for lj in self.loops)  # both copies of the frame are world poses
        return replace(self, M0=t @ self.M0, gravity=t[:3, :3] @ self.gravity, loops=loops)

    def describe(self) -> str:
        """A text summary of the robot.

        Returns
        -------
        str
            A header line (name, bodies, dofs, gravity), then one line per body: index, name,
            joint type, parent.
        """
        lines = [f"{self.name}: {self.n} bodies, {self.dof} dofs, gravity {self.gravity.tolist()} m/s^2"]
        for i in range(self.n):
            p = "world" if self.parent[i] < 0 else self.names[self.parent[i]]
            lines.append(f"  {i:3d} {self.names[i]:<24s} {self.jtype[i]}  parent {p}")
        return "\n".join(lines)
