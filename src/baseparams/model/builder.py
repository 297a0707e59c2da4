"""A builder API for robots, in the spirit of URDF: links attached by joints.

Example::

    from baseparams.model import RobotBuilder, Inertia, pose

    b = RobotBuilder("two-link", gravity=(0, 0, -9.81))
    b.add_link("upper", joint="R", origin=pose(xyz=(0, 0, 0.3)), axis=(0, 1, 0),
               inertia=Inertia(2.0, com=(0, 0, 0.2), inertia=(0.01, 0.01, 0.002)))
    b.add_link("lower", parent="upper", joint="R", origin=pose(xyz=(0, 0, 0.4)),
               axis=(0, 1, 0), inertia=Inertia(1.0, com=(0, 0, 0.2)))
    robot = b.build()

``origin`` is the joint frame's pose in the parent link's frame at q = 0 (URDF ``<origin>``);
the link frame is the joint frame. Axes are normalised. A ``"fixed"`` joint adds no body:
its inertia is merged into the parent and its name can be used as a parent later.

A compound joint (``joint="C"``, an MJCF body with several joints) takes ``axis`` as ``(k, 6)``
unit twists ``(omega, v)`` in the joint frame, applied in order (product of exponentials); build
each with :func:`baseparams.model.robot.compound_screw`::

    b.add_link("torso", joint="C", axis=[compound_screw((1, 0, 0), slide=True),
                                         compound_screw((0, 0, 1), slide=True),
                                         compound_screw((0, 1, 0), point=(0, 0, 0.1))])

``armature`` (optional, one number per coordinate of the joint): rotor inertia, carried in
:attr:`Robot.armature`, not used by the analysis.
"""

from __future__ import annotations

import numpy as np

from ..enums import JointType, values
from ..errors import ModelError, NoMovingBodiesError
from ..pga.core import quat_to_rot
from .inertia import Inertia, transform
from .robot import JOINT_TYPES, LoopJoint, Robot, joint_ndof

#: every joint type a link may be added with: a body's (:data:`JOINT_TYPES`) and ``fixed``
ALL_TYPES = values(JointType)
_ALIASES = {"revolute": "R", "continuous": "R", "prismatic": "P", "universal": "U",
            "spherical": "S", "ball": "S", "floating": "F", "free": "F", "r": "R", "p": "P",
            "u": "U", "s": "S", "f": "F", "c": "C", "compound": "C"}


def pose(xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0)) -> np.ndarray:
    """4x4 pose from a translation and URDF roll-pitch-yaw (``Rz(y) Ry(p) Rx(r)``).

    Parameters
    ----------
    xyz : array_like, shape ``(3,)``
        Translation [m].
    rpy : array_like, shape ``(3,)``
        Roll, pitch, yaw [rad] (URDF ``<origin rpy>``).

    Returns
    -------
    ndarray, shape ``(4, 4)``
        The homogeneous transform.
    """
    r, p, y = (float(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    t = np.eye(4)
    t[:3, :3] = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                 [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                 [-sp, cp * sr, cp * cr]]
    t[:3, 3] = np.asarray(xyz, dtype=float)
    return t


def quat_pose(xyz=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0)) -> np.ndarray:
    """4x4 pose from a translation and a (not necessarily unit) quaternion ``w x y z``.

    Parameters
    ----------
    xyz : array_like, shape ``(3,)``
        Translation [m].
    quat : array_like, shape ``(4,)``
        Quaternion ``w x y z`` (MJCF order), normalised here.

    Returns
    -------
    ndarray, shape ``(4, 4)``
        The homogeneous transform.

    Raises
    ------
    ModelError
        A zero quaternion.
    """
    q = np.asarray(quat, dtype=float)
    nq = np.linalg.norm(q)
    if nq < 1e-12:
        raise ModelError(f"zero quaternion {q.tolist()}")
    t = np.eye(4)
    t[:3, :3] = quat_to_rot(q / nq)
    t[:3, 3] = np.asarray(xyz, dtype=float)
    return t


def joint_type(name: str) -> str:
    """Normalise a joint type name (``revolute`` -> ``R``, ...); ``fixed`` stays ``fixed``.

    Parameters
    ----------
    name : str
        A joint type (``R P U S F C fixed``) or a URDF/MJCF name (``revolute``, ``continuous``,
        ``prismatic``, ``ball``, ``free``, ...), any case.

    Returns
    -------
    str
        The type in :data:`ALL_TYPES`, or ``name`` unchanged when it is not recognised (the
        caller reports it).
    """
    if name in ALL_TYPES:
        return name
    return _ALIASES.get(str(name).lower(), str(name))


class RobotBuilder:
    """Collects links and joints, then :meth:`build` validates and returns a :class:`Robot`.

    See the module doc for an example.

    Parameters
    ----------
    name : str
        The robot's name.
    gravity : array_like, shape ``(3,)``
        Gravity [m/s^2] in the world frame.
    """

    def __init__(self, name: str, gravity=(0.0, 0.0, -9.81)):
        self.name = name
        self.gravity = np.asarray(gravity, dtype=float)
        self._names: list[str] = []
        self._jnames: list[str] = []
        self._types: list[str] = []
        self._parents: list[int] = []
        self._m0: list[np.ndarray] = []
        self._axes: list[np.ndarray] = []
        self._n: list[np.ndarray] = []
        self._frames: dict[str | None, tuple[int, np.ndarray]] = {None: (-1, np.eye(4))}
        self._loops: list[tuple] = []
        self._actuated: list[bool | None] = []
        self._armature: list[np.ndarray | None] = []
        self.q_box = None

    def _frame(self, name: str | None) -> tuple[int, np.ndarray]:
        # "world" names the fixed base unless a link of that name was added (URDF often has one)
        key = None if (name is None or (name == "world" and "world" not in self._frames)) else name
        if key not in self._frames:
            raise ModelError(f"robot {self.name!r}: unknown parent link {key!r} (add it before its children)")
        return self._frames[key]

    def body_index(self, name: str) -> int:
        """Index of a link added so far.

        Parameters
        ----------
        name : str
            A (moving) link's name.

        Returns
        -------
        int
            Its body index in the built robot.

        Raises
        ------
        ModelError
            No moving link of that name.
        """
        if name not in self._names:
            raise ModelError(f"robot {self.name!r}: no link {name!r}")
        return self._names.index(name)

    def add_link(self, name: str, parent: str | None = None, joint: str = "R", origin=None,
                 axis=(0.0, 0.0, 1.0), axis2=None, inertia: Inertia | None = None,
                 joint_name: str | None = None, actuated: bool | None = None, armature=None) -> RobotBuilder:
        """Attach link ``name`` to ``parent`` (default: the fixed base) by a joint.

        Parameters
        ----------
        name : str
            The new link's name (unique).
        parent : str, optional
            An earlier link (or fixed link); ``None`` or ``"world"`` (unless a link is named
            so): the fixed base.
        joint : str
            ``R P U S F C fixed`` or URDF/MJCF names (``revolute``, ``ball``, ...).
        origin : array_like, shape ``(4, 4)``, optional
            The joint frame's pose in the parent link's frame at q = 0 (URDF ``<origin>``);
            default identity.
        axis : array_like, shape ``(3,)`` or ``(k, 6)``
            Joint axis in the joint frame (normalised); C: ``(k, 6)`` twists (module doc).
            Ignored for S, F and fixed.
        axis2 : array_like, shape ``(3,)``, optional
            Second axis of a U joint, in the joint frame.
        inertia : Inertia, optional
            The link's inertia in the link frame (default: massless). A fixed link's is merged
            into its parent.
        joint_name : str, optional
            Default ``name + "_joint"``.
        actuated : bool, optional
            Whether the joint's coordinates are independent (actuated); unspecified counts
            as independent when any link says (URDF+ default).
        armature : array_like, shape ``(ndof,)``, optional
            Rotor inertia per coordinate (default 0).

        Returns
        -------
        RobotBuilder
            ``self``, for chaining.

        Raises
        ------
        ModelError
            Duplicate name, unknown joint type or parent, a bad origin, axis or armature.
        """
        jt = joint_type(joint)
        jname = joint_name or f"{name}_joint"
        what = f"robot {self.name!r}, link {name!r} (joint {jname!r})"
        if name in self._frames:
            raise ModelError(f"{what}: duplicate link name {name!r}")
        if jt not in ALL_TYPES:
            raise ModelError(f"{what}: unknown joint type {joint!r}; expected one of "
                             f"{ALL_TYPES} or a URDF/MJCF name")
        pidx, pframe = self._frame(parent)
        origin = np.eye(4) if origin is None else np.asarray(origin, dtype=float)
        if origin.shape != (4, 4) or not np.all(np.isfinite(origin)):
            raise ModelError(f"{what}: origin must be a finite 4x4 pose")
        pm0 = np.eye(4) if pidx < 0 else self._m0[pidx]
        frame_in_body = pframe @ origin  # joint frame in the parent body's frame
        m0 = pm0 @ frame_in_body
        n_link = np.zeros((4, 4)) if inertia is None else np.asarray(inertia.pseudo())
        if jt == "fixed":
            if pidx >= 0:
                self._n[pidx] = self._n[pidx] + transform(n_link, frame_in_body)
            # a link welded to the world is static: it only names a frame
            self._frames[name] = (pidx, frame_in_body)
            return self
        axes = self._axes_for(jt, axis, axis2, what)
        self._actuated.append(actuated)
        if armature is not None:
            armature = np.asarray(armature, dtype=float).reshape(-1)
            if len(armature) != joint_ndof(jt, axes):
                raise ModelError(f"{what}: armature needs {joint_ndof(jt, axes)} numbers, got {len(armature)}")
        self._armature.append(armature)
        self._names.append(name)
        self._jnames.append(jname)
        self._types.append(jt)
        self._parents.append(pidx)
        self._m0.append(m0)
        self._axes.append(axes)
        self._n.append(n_link)
        self._frames[name] = (len(self._names) - 1, np.eye(4))
        return self

    @staticmethod
    def _axes_for(jt: str, axis, axis2, what: str) -> np.ndarray:
        if jt in ("S", "F"):
            return np.eye(3) if jt == "S" else np.zeros((0, 3))
        if jt == "C":
            c = np.asarray(axis, dtype=float)
            if c.ndim != 2 or c.shape[1] != 6 or not len(c) or not np.all(np.isfinite(c)):
                raise ModelError(f"{what}: a compound (C) joint needs axis as (k, 6) finite twists, got {axis!r}")
            return c
        a = np.asarray(axis, dtype=float).reshape(-1)
        if a.shape != (3,) or not np.all(np.isfinite(a)):
            raise ModelError(f"{what}: axis must be 3 finite numbers, got {axis!r}")
        if np.linalg.norm(a) < 1e-12:
            raise ModelError(f"{what}: zero joint axis")
        a = a / np.linalg.norm(a)
        if jt != "U":
            return a[None]
        if axis2 is None:
            raise ModelError(f"{what}: a universal joint needs axis2")
        b = np.asarray(axis2, dtype=float).reshape(-1)
        if b.shape != (3,) or np.linalg.norm(b) < 1e-12:
            raise ModelError(f"{what}: axis2 must be a nonzero 3-vector")
        b = b / np.linalg.norm(b)
        return np.stack([a, b])

    def add_loop(self, name: str, type: str, parent: str | None, child: str, origin=None, axis=(0, 0, 1.0),
                 axis2=None, child_origin=None, anchor_free: bool = False) -> RobotBuilder:
        """Record a loop (cut) joint between two links.

        The two links may come in either tree order (URDF+ allows it; either may be the
        world): the built :class:`LoopJoint` has ``parent < child``, with the frames (and a U
        joint's two axes) swapped when needed. Checked by :meth:`build`.

        Parameters
        ----------
        name : str
            The loop joint's name.
        type : str
            ``R P U S fixed`` (or URDF/MJCF names, as for :meth:`add_link`).
        parent : str or None
            One link (``None``: the world).
        child : str
            The other link.
        origin : array_like, shape ``(4, 4)``, optional
            The loop frame in the parent link's frame (default identity).
        axis : array_like, shape ``(3,)``
            Joint axis in the loop frame (a U joint's first axis, carried by ``parent``).
        axis2 : array_like, shape ``(3,)``, optional
            A U joint's second axis, carried by ``child``.
        child_origin : array_like, shape ``(4, 4)``, optional
            The same frame in the child link's frame (when the two do not coincide at q = 0
            the robot is not assembled there: see :func:`baseparams.kinematics.loops.assemble`).
        anchor_free : bool, default False
            One side is the world through a control device (a mocap body) that may be placed
            anywhere (:attr:`LoopJoint.anchor_free`).

        Returns
        -------
        RobotBuilder
            ``self``, for chaining.
        """
        jt = joint_type(type)
        self._loops.append((name, jt, parent, child, origin, axis, axis2, child_origin, anchor_free))
        return self

    def build(self) -> Robot:
        """Validate and return the :class:`Robot`.

        Returns
        -------
        Robot
            Bodies in the order added; ``independent`` set when any link gave ``actuated``;
            ``armature`` when any link gave one; loops with ``parent < child``.

        Raises
        ------
        ModelError
            An invalid model; :class:`NoMovingBodiesError` when no moving link was added.
        """
        if not self._names:
            raise NoMovingBodiesError(f"robot {self.name!r}: no moving links")
        loops = []
        for name, jt, parent, child, origin, axis, axis2, child_origin, free in self._loops:
            what = f"robot {self.name!r}, loop joint {name!r}"
            pidx, pframe = self._frame(parent)
            cidx, cframe = self._frame(child)
            if pidx == cidx:
                raise ModelError(f"{what}: the predecessor {parent!r} and the successor {child!r} are the same "
                                 f"body" + (" (the world)" if pidx < 0 else ""))
            pm0 = np.eye(4) if pidx < 0 else self._m0[pidx]
            cm0 = np.eye(4) if cidx < 0 else self._m0[cidx]
            m = pm0 @ pframe @ (np.eye(4) if origin is None else np.asarray(origin, dtype=float))
            # the successor's copy of the frame (the predecessor's when the file gives none)
            mc = m if child_origin is None else cm0 @ cframe @ np.asarray(child_origin, dtype=float)
            axes = self._axes_for(jt, axis, axis2, what) if jt in JOINT_TYPES else np.zeros((0, 3))
            if pidx > cidx:
                # written in the other orientation (URDF+ allows it): swap the roles. The
                # frames swap; a U joint's first axis is carried by the predecessor and its
                # second by the successor, so its axes swap too; R/P axes are the same line in
                # both frames, S and fixed have none to swap. The constraints are the same.
                pidx, cidx, m, mc = cidx, pidx, mc, m
                if jt == "U":
                    axes = axes[::-1].copy()
            # not assembled at q = 0: kinematics.loops.assemble() solves it
            m_child = mc if np.abs(mc - m).max() > 1e-9 else None
            loops.append(LoopJoint(name, jt, pidx, cidx, m, axes, m_child, anchor_free=bool(free) and pidx < 0))
        independent = None
        if any(a is not None for a in self._actuated):
            independent, k = [], 0
            for t, a, ax in zip(self._types, self._actuated, self._axes):
                nd = joint_ndof(t, ax)
                if a is None or a:  # unspecified = independent (URDF+ default)
                    independent += list(range(k, k + nd))
                k += nd
            if not independent:
                raise ModelError(f"robot {self.name!r}: every joint is marked passive (independent=\"false\"): "
                                 f"nothing drives the mechanism; mark its actuated joints independent")
        armature = None
        if any(a is not None for a in self._armature):
            armature = np.concatenate([np.zeros(joint_ndof(t, ax)) if a is None else a
                                       for t, ax, a in zip(self._types, self._axes, self._armature)])
        return Robot(self.name, tuple(self._names), tuple(self._jnames), tuple(self._types),
                     np.array(self._parents, dtype=int), np.array(self._m0), tuple(self._axes),
                     np.array(self._n), self.gravity, tuple(loops),
                     None if independent is None else tuple(independent), self.q_box, armature=armature)
