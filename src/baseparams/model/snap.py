"""Geometry a model file states to within rounding of a special value: a right angle, zero.

Real files carry ``rpy="3.1416"`` or ``"1.5708"`` (pi and pi/2 to 5 digits), an axis ``0
0.00001 1``, a quaternion ``0.707107 0 0.707107 0`` or an offset of a micrometre left by a CAD
export. Taken literally, such a value breaks a symmetry: a first joint tilted 7.3e-6 rad from
gravity makes two first moments of its link "identifiable", with regressor columns about 1e-5 of
the others. No measurement resolves them; least squares fits them to absurd values that explode
on another recording.

Where the robot was read from a file (:class:`FileSource`, set by the readers), the values are
found in the file itself, each named by its element (:mod:`baseparams.io.snapfile`): URDF joint
``<origin rpy>`` angles and ``xyz`` offsets and ``<axis>`` components (fixed joints included:
they compose the moving joints' frames), MJCF body and frame ``pos``, ``quat``, ``euler``,
``axisangle``, ``xyaxes`` and ``zaxis`` and joint ``axis`` and ``pos``. Inertial frames are not
examined: a body's parameters are a general symmetric inertia in any frame, so the frame's
orientation never changes the count. Otherwise (a robot built in code, or changed after reading)
each joint frame relative to its parent's is read as roll-pitch-yaw angles and an offset
(:func:`near_special`). The rules:

* an angle within :data:`SNAP_TOL` rad of a multiple of pi/2 is that multiple (MJCF angles in
  degrees: of a multiple of 90);
* an offset component within :data:`SNAP_TOL` of zero relative to the robot's size
  (:func:`robot_size`: its extent, at most ten of its longest links), or an axis component within
  :data:`SNAP_TOL` of zero relative to the axis' length, is zero;
* a rotation whose frame has an axis within :data:`SNAP_TOL` rad of parallel to one of its
  parent's (a quaternion; or angles whose components are not near a right angle one by one,
  e.g. roll and yaw at pitch pi/2 as exporters write them) is turned the least that makes it
  so, the angle across it snapped too when near a right angle (:func:`snap_rotation`).

Why 1e-3: a geometric feature of relative size ``e`` creates directions whose regressor columns
are about ``e`` times the others' at the file's own mass and size scales; ``e = 1e-3`` (0.06
degree, or 1 mm on a 1 m robot) moves the torques by 0.1 % of their scale, below what joint
torque sensors or motor-current models resolve (0.5-2 % is typical). A deviation below
:data:`EXACT_TOL` is rounding of an exact value (``1.9e-17`` from a DH conversion) and is left as
it is: the numerics treat it as exact already. Values exactly special are not touched, so exact
files are unaffected. The decision whether a snapped value changes the count is the analysis's
(:func:`baseparams.analyze`, ``literal=False``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..display import summary_repr
from .robot import Robot

#: geometry within this of a special value (rad; offsets: relative to the robot's size) is that value
SNAP_TOL = 1e-3
#: deviations below this (same units) are rounding of an exact value: left as they are
EXACT_TOL = 1e-9


@dataclass(frozen=True)
class Snap:
    """One value of the model within :data:`SNAP_TOL` of a special value.

    Parameters
    ----------
    body : int
        The body whose joint frame or axis holds it (-1: an element of the file that is no one
        body's own, e.g. a fixed joint merged into its parent).
    joint : str
        That body's joint name, or the name of the file's element holding the value.
    what : str
        ``"rpy"`` (an origin angle), ``"xyz"`` (an origin offset), ``"axis"``; from MJCF files
        also ``"pos"``, ``"quat"``, ``"euler"``, ``"axisangle"``, ``"xyaxes"``, ``"zaxis"``.
    index : int
        The component (0, 1, 2 = roll, pitch, yaw or x, y, z; -1: the whole value, a quaternion).
    literal : float
        The model's value [rad, degree, m or unit-vector component] (NaN for a whole value).
    snapped : float
        The special value taken instead (NaN for a whole value: :attr:`new`).
    deviation : float
        ``|literal - snapped|``, relative (rad; offsets divided by the robot's size; axis
        components by the axis' length; a whole rotation: the angle it is turned by).
    element : str, optional
        The file's element and attribute, e.g. ``<joint name="j2"> <origin rpy>`` (empty for a
        value of the model, not of a file).
    text : str, optional
        The value as the file writes it (the whole attribute for a whole value).
    new : tuple of float, optional
        The numbers written instead, for a whole value.
    key : tuple, optional
        Where the value is in the file, for re-reading it (:mod:`baseparams.io.snapfile`).
    unit : str, optional
        ``"rad"`` or ``"degree"`` for angles.
    """

    __repr__ = summary_repr

    body: int
    joint: str
    what: str
    index: int
    literal: float
    snapped: float
    deviation: float
    element: str = ""
    text: str = ""
    new: tuple = ()
    key: tuple = ()
    unit: str = "rad"

    def describe(self) -> str:
        """One phrase, e.g. ``panda_joint1 origin rpy 3.1416 = pi to 5 digits``.

        Returns
        -------
        str
            The element (or joint), the value and what it is close to.
        """
        if self.index < 0:
            new = " ".join(f"{v:.17g}" for v in self.new)
            return (f"{self.element} {self.text} = {new} (the frame turned by {self.deviation:.2g} rad to make its "
                    f"axes parallel or perpendicular to its parent's)")
        comp = ("roll", "pitch", "yaw")[self.index] if self.what == "rpy" else "xyz"[self.index % 3] \
            if self.what != "axisangle" or self.index < 3 else "angle"
        if self.what == "xyaxes":
            comp = ("x", "y")[self.index // 3] + " " + "xyz"[self.index % 3]
        where = self.element or f"{self.joint} {'axis' if self.what == 'axis' else 'origin ' + self.what}"
        unit = "decimal places" if self.snapped == 0 else "digits"
        lit = self.text or f"{self.literal:.6g}"
        return f"{where} {comp} {lit} = {_special_name(self.snapped, self.what, self.unit)} to {_digits(self)} {unit}"

    def to_json(self) -> dict:
        """The value, machine-readable.

        Returns
        -------
        dict
            ``joint, element, what, component, literal, text, special, new, deviation``.
        """
        def num(x: float):
            return None if not np.isfinite(x) else float(x)

        return {"joint": self.joint, "element": self.element, "what": self.what, "component": self.index,
                "literal": num(self.literal), "text": self.text, "special": num(self.snapped),
                "new": list(self.new), "deviation": self.deviation}


def _special_name(v: float, what: str, unit: str = "rad") -> str:
    if what not in ("rpy", "euler", "axisangle") or v == 0:
        return "0" if v == 0 else f"{v:g}"
    if unit == "degree":
        return f"{v:g}"
    k = int(round(v / (np.pi / 2)))
    names = {1: "pi/2", -1: "-pi/2", 2: "pi", -2: "-pi", 3: "3pi/2", -3: "-3pi/2", 4: "2pi", -4: "-2pi"}
    return names.get(k, f"{k}pi/2")


def _digits(s: Snap) -> int:
    """Significant digits (after the point, for a zero) to which the literal equals the special value."""
    angle = s.what in ("rpy", "euler", "axisangle")
    scale = max(abs(s.snapped), 1.0) if angle else 1.0
    dev = abs(s.literal - s.snapped) if angle else s.deviation
    return max(1, int(np.floor(-np.log10(max(dev / scale, 1e-300)))))


@dataclass(frozen=True, eq=False)
class FileSource:
    """The file a robot was read from and how, so that its values can be re-read snapped.

    Set by :func:`baseparams.io.load.load_file` on the robot it returns (``Robot.source``).

    Parameters
    ----------
    path : str
        The file.
    options : dict
        The reader's keyword arguments (``floating``, ``gravity``, ``strict_inertia``, ...).
    fingerprint : bytes
        :func:`geometry_fingerprint` of the robot as read: a robot changed since (re-referenced,
        welded, built anew) no longer matches, and its file is not used.
    """

    __repr__ = summary_repr

    path: str
    options: dict
    fingerprint: bytes


def geometry_fingerprint(robot: Robot) -> bytes:
    """A digest of everything that decides the robot's count: tree, joints, frames, axes, gravity, constraints.

    Parameters
    ----------
    robot : Robot
        The robot.

    Returns
    -------
    bytes
        SHA-1 of the names, joint types, parents, ``M0``, axes, gravity, couplings and loop joints.
    """
    import hashlib

    h = hashlib.sha1()
    for part in (robot.names, robot.joint_names, robot.jtype, robot.couplings, robot.loops):
        h.update(repr(part).encode())
    for arr in (robot.parent, robot.M0, robot.gravity, *robot.axes):
        h.update(np.ascontiguousarray(arr, dtype=float).tobytes())
    return h.digest()


def file_source(robot: Robot) -> FileSource | None:
    """The file the robot was read from, if the robot is still as read (else None).

    Parameters
    ----------
    robot : Robot
        The robot.

    Returns
    -------
    FileSource or None
        ``robot.source`` when its fingerprint matches the robot's geometry.
    """
    src = getattr(robot, "source", None)
    return src if src is not None and src.fingerprint == geometry_fingerprint(robot) else None


def snap_rotation(r: np.ndarray, tol: float = SNAP_TOL, exact: float = EXACT_TOL) -> np.ndarray | None:
    """The least turn of a rotation that makes a near-parallel pair of axes exact, or None if it has none.

    Entry ``r[i, j]`` is the cosine of the angle between the parent's axis ``i`` and the frame's
    axis ``j``. When one pair is within ``tol`` rad of parallel (``|r_ij| >= cos tol``, but not
    within ``exact``), that row and column become a signed unit vector and the rest the nearest
    rotation in the plane across them, itself snapped to a right angle when within ``tol``: a
    rotation about a frame axis composed with right angles (a splay angle on a right-angled
    mount) keeps its designed angle. A pair merely near perpendicular is not enough: in generic
    (CAD) frames one of the nine angles falls within a milliradian of a right angle by chance
    (0.6 % of frames), and turning such a frame would move a designed axis with it; single angles
    near a right angle are the file's own components (:func:`near_special`, MJCF ``euler``).

    Parameters
    ----------
    r : ndarray, shape ``(3, 3)``
        A rotation.
    tol, exact : float
        Angles [rad]: snapped when within ``tol``, already exact within ``exact``.

    Returns
    -------
    ndarray, shape ``(3, 3)`` or None
        The snapped rotation, or None when no pair of axes is within ``tol`` of parallel or all
        such are within ``exact`` (with the plane's angle).
    """
    r = np.asarray(r, dtype=float)
    a = np.abs(r)
    par = [(i, j) for i in range(3) for j in range(3) if a[i, j] >= np.cos(tol)]
    if not par:
        return None
    i, j = max(par, key=lambda ij: a[ij])
    out = np.zeros((3, 3))
    out[i, j] = np.sign(r[i, j])
    rows, cols = [k for k in range(3) if k != i], [k for k in range(3) if k != j]
    u, _, vt = np.linalg.svd(r[np.ix_(rows, cols)])
    want = np.sign(r[i, j]) * (-1) ** (i + j)  # det(out) = +1
    b = u @ np.diag([1.0, want * np.sign(np.linalg.det(u @ vt))]) @ vt
    ang = np.arctan2(b[1, 0], b[0, 0])
    k = np.round(ang / (np.pi / 2))
    if abs(ang - k * np.pi / 2) <= tol:
        c, s_ = np.round(np.cos(k * np.pi / 2)), np.round(np.sin(k * np.pi / 2))
        b = np.array([[c, -s_], [s_, c]]) @ np.diag([1.0, np.sign(np.linalg.det(b))])
    out[np.ix_(rows, cols)] = b
    turn = float(np.arccos(np.clip((np.trace(r.T @ out) - 1) / 2, -1.0, 1.0)))
    return out if turn > exact else None


#: the robot's size is at most this many times its longest link (:func:`robot_size`)
LINKS_PER_SIZE = 10


def robot_size(robot: Robot, frames: np.ndarray | None = None) -> float:
    """The length offsets are measured against: the robot's extent, at most ten of its longest links.

    The largest distance between two joint frames at q = 0 (not to the world origin: a hand
    mounted half a metre from it is 10 cm in size), but at most :data:`LINKS_PER_SIZE`
    times the longest link (a joint frame's distance from its parent's): an offset acts on the
    torques through the links near it, so on a chain of 10 000 links the whole chain's length
    would make every offset below ten links "near zero" (1 988 of them snapped on a random deep
    tree). An arm's extent is a few links: unchanged there.

    Parameters
    ----------
    robot : Robot
        The robot.
    frames : ndarray, shape ``(n, 4, 4)``, optional
        :func:`relative_frames` of the robot, when already computed.

    Returns
    -------
    float
        [m], at least 1e-3 (a robot of one body at the origin).
    """
    # the joint frames (the world origin only for one body: where a robot stands changes nothing)
    p = robot.M0[:, :3, 3] if robot.n > 1 else np.vstack([np.zeros((1, 3)), robot.M0[:, :3, 3]])
    rel = (relative_frames(robot) if frames is None else frames)[:, :3, 3]
    inner = [i for i, par in enumerate(robot.parent) if par >= 0]  # a root's pose in the world is not a link
    longest = float(np.linalg.norm(rel[inner], axis=1).max()) if inner else np.inf
    return max(min(diameter(p), LINKS_PER_SIZE * longest), 1e-3)


def diameter(p: np.ndarray, block: int = 1024) -> float:
    """The largest distance between two of the points ``p (m, 3)``, exactly, in ``O(m block)`` memory.

    A lower bound ``D`` (the farthest point from the farthest point from the centroid) prunes:
    a pair at distance ``>= D`` has both points at least ``D - R`` from the centroid ``c`` (``R``
    the largest radius), since ``|p - q| <= |p - c| + |q - c|``; the remaining points are compared
    pairwise, ``block`` rows at a time.

    Parameters
    ----------
    p : ndarray, shape ``(m, 3)``
        Points (``m >= 1``).
    block : int
        Rows per block of the pairwise comparison.

    Returns
    -------
    float
        ``max |p_i - p_j|``.
    """
    c = p.mean(axis=0)
    r = np.linalg.norm(p - c, axis=1)
    a = p[int(np.argmax(r))]
    b = p[int(np.argmax(np.linalg.norm(p - a, axis=1)))]
    best = float(np.linalg.norm(a - b))
    cand = p[r >= best - r.max() - 1e-12 * max(best, 1.0)]
    for i in range(0, len(cand), block):
        d = np.linalg.norm(cand[i:i + block, None, :] - cand[None, :, :], axis=2)
        best = max(best, float(d.max()))
    return best


def relative_frames(robot: Robot) -> np.ndarray:
    """Each body's joint frame in its parent's frame at q = 0 (the URDF ``<origin>``).

    Parameters
    ----------
    robot : Robot
        The robot.

    Returns
    -------
    ndarray, shape ``(n, 4, 4)``
        ``M0[parent]^-1 M0[i]`` (the world for a root).
    """
    out = np.empty_like(robot.M0)
    for i, p in enumerate(robot.parent):
        out[i] = robot.M0[i] if p < 0 else np.linalg.solve(robot.M0[p], robot.M0[i])
    return out


def rpy(r: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw of a rotation, URDF's convention ``R = Rz(yaw) Ry(pitch) Rx(roll)``.

    Parameters
    ----------
    r : ndarray, shape ``(3, 3)``
        The rotation.

    Returns
    -------
    ndarray, shape ``(3,)``
        [rad]; at pitch ``+-pi/2`` the roll takes the whole remaining angle (yaw 0).
    """
    pitch = float(np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0])))  # accurate near +-pi/2 (arcsin is not)
    if np.hypot(r[0, 0], r[1, 0]) < 1e-12:  # gimbal lock
        return np.array([float(np.arctan2(-r[1, 2], r[1, 1])), pitch, 0.0])
    return np.array([float(np.arctan2(r[2, 1], r[2, 2])), pitch, float(np.arctan2(r[1, 0], r[0, 0]))])


def rotation(angles) -> np.ndarray:
    """``Rz(yaw) Ry(pitch) Rx(roll)`` of roll, pitch, yaw.

    Parameters
    ----------
    angles : array_like, shape ``(3,)``
        Roll, pitch, yaw [rad].

    Returns
    -------
    ndarray, shape ``(3, 3)``
        The rotation.
    """
    r, p, y = (float(a) for a in angles)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _snap_value(v: float, step: float, tol: float, exact: float) -> float | None:
    """The nearest multiple of ``step`` (``step`` 0: zero) when ``exact < |v - it| <= tol``, else None."""
    target = 0.0 if step == 0 else float(np.round(v / step) * step)
    d = abs(v - target)
    return target if exact < d <= tol else None


def near_special(robot: Robot, tol: float = SNAP_TOL, exact: float = EXACT_TOL) -> list[Snap]:
    """The values of the model within ``tol`` of a special value, but not within ``exact`` of it.

    Robots with loop joints are not examined (changing a frame could open a loop): an empty
    list. Couplings (``<mimic>``) tie coordinates, not frames: such robots are examined.

    Parameters
    ----------
    robot : Robot
        The robot.
    tol : float
        The snapping tolerance (module docstring): rad, or relative to :func:`robot_size`.
    exact : float
        Below this a value counts as exact already.

    Returns
    -------
    list of Snap
        In body order, origins' angles, then offsets, then axes.
    """
    if robot.loops:
        return []
    frames = relative_frames(robot)
    size = robot_size(robot, frames)
    out: list[Snap] = []
    for i, t in enumerate(frames):
        if robot.jtype[i] == "F":
            continue
        name = robot.joint_names[i]
        for k, a in enumerate(rpy(t[:3, :3])):
            s = _snap_value(a, np.pi / 2, tol, exact)
            if s is not None:
                out.append(Snap(i, name, "rpy", k, float(a), s, abs(a - s)))
        for k, x in enumerate(t[:3, 3]):
            s = _snap_value(x / size, 0.0, tol, exact)
            if s is not None:
                out.append(Snap(i, name, "xyz", k, float(x), 0.0, abs(x) / size))
        if robot.jtype[i] in ("R", "P", "U"):
            for row in robot.axes[i]:
                for k, c in enumerate(row):
                    s = _snap_value(c, 0.0, tol, exact)
                    if s is not None:
                        out.append(Snap(i, name, "axis", k, float(c), 0.0, abs(c)))
    return out


def snapped(robot: Robot, snaps) -> Robot:
    """The robot with the given values set to their special values.

    Parameters
    ----------
    robot : Robot
        The robot (without loop joints).
    snaps : iterable of Snap
        Values to set (:func:`near_special`).

    Returns
    -------
    Robot
        Same bodies, inertias (in their own frames), limits and couplings; each snapped joint
        frame recomposed from its angles and offset, world poses recomputed down the tree, axes
        renormalised.
    """
    snaps = list(snaps)
    if not snaps:
        return robot
    rel = relative_frames(robot)
    axes = [np.array(a, dtype=float) for a in robot.axes]
    by_body: dict[int, list[Snap]] = {}
    for s in snaps:
        by_body.setdefault(s.body, []).append(s)
    for i, group in by_body.items():
        ang, off = rpy(rel[i][:3, :3]), rel[i][:3, 3].copy()
        frame = False
        for s in group:
            if s.what == "rpy":
                ang[s.index], frame = s.snapped, True
            elif s.what == "xyz":
                off[s.index], frame = s.snapped, True
            else:
                for row in axes[i]:
                    if abs(row[s.index] - s.literal) < 1e-15:
                        row[s.index] = s.snapped
                axes[i] = axes[i] / np.linalg.norm(axes[i], axis=1, keepdims=True)
        if frame:
            rel[i][:3, :3] = rotation(ang)
            rel[i][:3, 3] = off
    m0 = np.empty_like(robot.M0)
    for i, p in enumerate(robot.parent):
        m0[i] = rel[i] if p < 0 else m0[p] @ rel[i]
    return replace(robot, M0=m0, axes=tuple(axes))
