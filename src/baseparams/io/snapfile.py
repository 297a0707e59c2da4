"""Values a robot file writes to within rounding of a right angle or zero, found in the file itself.

:mod:`baseparams.model.snap` states the rules; this module applies them to the numbers as the
file writes them, each named by its element, and re-reads the file with chosen values exact
(through the same reader, so that every composition the reader makes - fixed joints merged,
MJCF frames, default classes, MuJoCo's orientation conventions - is the file's own):

* URDF (and expanded xacro): every ``<joint>``'s ``<origin rpy>`` angles and ``xyz`` offsets and
  its ``<axis>`` / ``<axis2>`` components, fixed joints included (they compose the frames of the
  moving joints after them);
* MJCF (through ``MjSpec``, default classes resolved): every body's and ``<frame>``'s ``pos`` and
  orientation (``quat`` as a whole rotation, ``euler`` and ``axisangle`` angles in the compiler's
  unit, ``axisangle`` / ``xyaxes`` / ``zaxis`` components) and every hinge's and slide's ``axis``
  and ``pos``.

A robot with loop joints is not examined (changing a frame could open a loop); couplings are
(they tie coordinates, not frames). Inertial frames are not examined: they never change a count.
"""

from __future__ import annotations

import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import BaseparamsError
from ..model.robot import Robot
from ..model.snap import EXACT_TOL, SNAP_TOL, Snap, file_source, robot_size, rotation, rpy, snap_rotation

_URDF = (".urdf", ".xacro")
_MJCF = (".xml", ".mjcf")


def _near(v: float, step: float, tol: float, exact: float) -> float | None:
    """The nearest multiple of ``step`` (0: zero) when ``exact < |v - it| <= tol``, else None."""
    target = 0.0 if step == 0 else float(np.round(v / step) * step)
    return target if exact < abs(v - target) <= tol else None


def _components(values, kind: str, scale: float, tol: float, exact: float, unit: str = "rad"):
    """``(k, literal, special, deviation)`` of each component of ``values`` near its special value.

    ``kind``: ``angle`` (multiples of pi/2, or of 90 with ``unit`` degree), ``offset`` (zero,
    relative to ``scale``) or ``unit`` (zero, relative to the vector's length).
    """
    v = [float(x) for x in values]
    out = []
    if kind == "unit":
        scale = float(np.linalg.norm(v)) or 1.0
    for k, x in enumerate(v):
        if kind == "angle":
            f = np.pi / 180 if unit == "degree" else 1.0
            s = _near(x * f, np.pi / 2, tol, exact)
            if s is not None:
                out.append((k, x, s / f, abs(x * f - s)))
        elif _near(x / scale, 0.0, tol, exact) is not None:
            out.append((k, x, 0.0, abs(x) / scale))
    return out


def _urdf_values(root, robot: Robot, size: float, tol: float, exact: float) -> list[Snap]:
    """The near-special values of a URDF document (module doc), in file order."""
    index = {nm: i for i, nm in enumerate(robot.joint_names)}
    out: list[Snap] = []
    for jt in root.findall("joint"):
        name = jt.get("name") or ""
        body = index.get(name, -1)
        parts = [("origin", a, a, k) for a, k in (("rpy", "angle"), ("xyz", "offset"))]
        parts += [(tag, "xyz", "axis" if tag == "axis" else "axis2", "unit") for tag in ("axis", "axis2")]
        for tag, attr, what, kind in parts:
            el = jt.find(tag)
            text = None if el is None else el.get(attr)
            tokens = [] if text is None else text.split()
            try:
                vals = [float(t) for t in tokens]
            except ValueError:
                continue  # the reader names the element and refuses it
            if len(vals) != 3 or not np.all(np.isfinite(vals)):
                continue
            element, key = f'<joint name="{name}"> <{tag} {attr}>', ("urdf", name, tag, attr)
            comps = _components(vals, kind, size, tol, exact)
            for k, lit, special, dev in comps:
                out.append(Snap(body, name, what, k, lit, special, dev, element=element, text=tokens[k], key=key))
            if attr == "rpy":
                out += _urdf_rotation(vals, comps, body, name, element, text, key, tol, exact)
    return out


def _urdf_rotation(vals, comps, body: int, name: str, element: str, text: str, key: tuple, tol: float,
                   exact: float) -> list[Snap]:
    """The whole ``rpy`` turned to make its near-right angles exact, when its angles one by one do not."""
    ang = list(vals)
    for k, _, special, _ in comps:
        ang[k] = special
    r = snap_rotation(rotation(ang), tol, exact)
    if r is None:
        return []
    new = tuple(float(a) for a in rpy(r))
    return [Snap(body, name, "rpy", -1, np.nan, np.nan, _angle(rotation(vals), r), element=element, text=text,
                 new=new, key=key)]


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle [rad] of the rotation between two frames."""
    return float(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1.0, 1.0)))


def _apply_urdf(root, snaps: list[Snap]) -> None:
    """Write the special values of ``snaps`` into the URDF document (exact decimal: ``repr``)."""
    joints = {jt.get("name"): jt for jt in root.findall("joint")}
    for s in sorted(snaps, key=lambda x: x.index < 0):  # a whole rotation after the angles it includes
        _, name, tag, attr = s.key
        el = joints[name].find(tag)
        tokens = el.get(attr).split()
        if s.index < 0:
            tokens = [repr(float(v)) for v in s.new]
        else:
            tokens[s.index] = repr(float(s.snapped))
        el.set(attr, " ".join(tokens))


def _quat_matrix(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _matrix_quat(r: np.ndarray, like) -> np.ndarray:
    """The unit quaternion ``(w, x, y, z)`` of ``r``, with the sign of ``like``; exact zeros kept."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(r).as_quat()
    q = np.array([w, x, y, z])
    q[np.abs(q) < 1e-15] = 0.0
    like = np.asarray(like, dtype=float)
    return -q if q @ like < 0 else q


def _mjcf_elements(spec):
    """``(kind, position, element)`` of the spec's bodies (world excluded), frames and hinge/slide joints."""
    import mujoco

    moving = (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)
    out = [("body", i, b) for i, b in enumerate(spec.bodies) if i > 0]
    out += [("frame", i, f) for i, f in enumerate(spec.frames)]
    out += [("joint", i, j) for i, j in enumerate(spec.joints) if j.type in moving]
    return out


def _mjcf_name(kind: str, pos: int, el) -> str:
    info = f" ({el.info})" if getattr(el, "info", "") else ""
    return f"{kind} {el.name!r}{info}" if el.name else f"{kind} #{pos}{info}"


def _orientation(el, degree: bool):
    """``(attribute, values, kind, unit)`` of a body's or frame's orientation as the file gives it."""
    import mujoco

    t = el.alt.type
    o = mujoco.mjtOrientation
    unit = "degree" if degree else "rad"
    if t == o.mjORIENTATION_EULER:
        return "euler", list(el.alt.euler), "angle", unit
    if t == o.mjORIENTATION_AXISANGLE:
        return "axisangle", list(el.alt.axisangle), "axisangle", unit
    if t == o.mjORIENTATION_XYAXES:
        return "xyaxes", list(el.alt.xyaxes), "xyaxes", unit
    if t == o.mjORIENTATION_ZAXIS:
        return "zaxis", list(el.alt.zaxis), "unit", unit
    return "quat", list(el.quat), "quat", unit


def _mjcf_values(spec, robot: Robot, size: float, tol: float, exact: float) -> list[Snap]:
    """The near-special values of an MJCF spec (module doc), bodies, then frames, then joints."""
    bodies = {nm: i for i, nm in enumerate(robot.names)}
    joints = {nm: i for i, nm in enumerate(robot.joint_names)}
    degree = bool(spec.compiler.degree)
    out: list[Snap] = []
    for kind, pos, el in _mjcf_elements(spec):
        name = _mjcf_name(kind, pos, el)
        body = (joints if kind == "joint" else bodies).get(el.name, -1)
        fields = [("pos", list(el.pos), "offset", "rad")]
        fields += [("axis", list(el.axis), "unit", "rad")] if kind == "joint" else [_orientation(el, degree)]
        for attr, vals, how, unit in fields:
            key = ("mjcf", kind, pos, attr)
            text = " ".join(f"{v:.10g}" for v in vals)
            comps = [] if how == "quat" else _mjcf_field(vals, how, unit, size, tol, exact)
            for k, lit, special, dev in comps:
                out.append(Snap(body, el.name or name, attr, k, lit, special, dev, element=f"{name} {attr}",
                                text=f"{lit:.10g}", key=key, unit=unit))
            if how != "offset" and attr != "axis":
                out += _mjcf_rotation(spec, el, vals, comps, attr, (body, el.name or name, f"{name} {attr}", text, key),
                                      tol, exact)
    return out


def _mjcf_field(vals, how: str, unit: str, size: float, tol: float, exact: float) -> list[tuple]:
    """``(component, literal, special, deviation)`` of one MJCF attribute's components near a special value."""
    if how == "axisangle":
        return (_components(vals[:3], "unit", 1.0, tol, exact)
                + [(3 + c[0], *c[1:]) for c in _components(vals[3:], "angle", 1.0, tol, exact, unit)])
    if how == "xyaxes":
        return (_components(vals[:3], "unit", 1.0, tol, exact)
                + [(3 + c[0], *c[1:]) for c in _components(vals[3:], "unit", 1.0, tol, exact)])
    return _components(vals, how, size, tol, exact, unit)


def _resolved(spec, el, attr: str, vals) -> np.ndarray:
    """The rotation MuJoCo makes of the orientation ``attr`` with the values ``vals`` (its own conversion)."""
    if attr == "quat":
        return _quat_matrix(vals)
    old = list(getattr(el.alt, attr))
    setattr(el.alt, attr, list(vals))
    try:
        q = spec.resolve_orientation(bool(spec.compiler.degree), spec.compiler.eulerseq, el.alt)
    finally:
        setattr(el.alt, attr, old)
    return _quat_matrix(q)


def _mjcf_rotation(spec, el, vals, comps, attr: str, where: tuple, tol: float, exact: float) -> list[Snap]:
    """The whole orientation made a quaternion whose near-right angles are exact, when its components do not."""
    body, name, element, text, key = where
    fixed = list(vals)
    for k, _, special, _ in comps:
        fixed[k] = special
    r = _resolved(spec, el, attr, fixed)
    snapped = snap_rotation(r, tol, exact)
    if snapped is None:
        return []
    new = tuple(float(v) for v in _matrix_quat(snapped, [1.0, 0, 0, 0]))
    return [Snap(body, name, attr, -1, np.nan, np.nan, _angle(_resolved(spec, el, attr, vals), snapped),
                 element=element, text=text, new=new, key=key)]


def _apply_mjcf(spec, snaps: list[Snap]) -> None:
    """Set the special values of ``snaps`` in the spec (before it is compiled); a whole rotation as a ``quat``."""
    import mujoco

    elements = {(kind, pos): el for kind, pos, el in _mjcf_elements(spec)}
    for s in sorted(snaps, key=lambda x: x.index < 0):  # a whole rotation after the components it includes
        _, kind, pos, attr = s.key
        el = elements[(kind, pos)]
        if s.index < 0:
            el.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
            el.quat = list(s.new)
            continue
        holder = el if attr in ("pos", "axis") else el.alt
        vals = list(getattr(holder, attr))
        vals[s.index] = s.snapped
        setattr(holder, attr, vals)


def file_snaps(robot: Robot, tol: float = SNAP_TOL, exact: float = EXACT_TOL) -> list[Snap] | None:
    """The values of the robot's file within ``tol`` of a special value (module doc), each named by its element.

    Parameters
    ----------
    robot : Robot
        A robot read from a file and not changed since (:func:`~baseparams.model.snap.file_source`).
    tol, exact : float
        As for :func:`~baseparams.model.snap.near_special` (rad; offsets relative to
        :func:`~baseparams.model.snap.robot_size`).

    Returns
    -------
    list of Snap or None
        In file order (empty for a robot with loop joints); None when the robot has no usable
        source file (built in code, or changed since it was read): then the model's own frames
        are examined instead (:func:`~baseparams.model.snap.near_special`).
    """
    src = file_source(robot)
    suffix = Path(src.path).suffix.lower() if src is not None else ""
    if suffix not in _URDF + _MJCF:
        return None
    if robot.loops:
        return []
    size = robot_size(robot)
    found: list[Snap] = []

    def look(doc) -> None:
        found.extend(_urdf_values(doc, robot, size, tol, exact) if suffix in _URDF else
                     _mjcf_values(doc, robot, size, tol, exact))

    _read(src, look)
    return found


def _read(src, edit) -> Robot:
    """The robot read from ``src``'s file with its options, ``edit`` called on the parsed document."""
    from .load import load_file

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the file's warnings were given when it was first read
        return load_file(src.path, **src.options, edit=edit)[0]


def reread(robot: Robot, snaps) -> Robot:
    """The robot with the given file values exact: its geometry read again from the file, the rest kept.

    Parameters
    ----------
    robot : Robot
        A robot read from a file and not changed since.
    snaps : iterable of Snap
        Values of :func:`file_snaps` to set to their special values.

    Returns
    -------
    Robot
        ``robot`` with ``M0`` and ``axes`` of the file read again with those values (inertias,
        limits, couplings and everything else as ``robot``'s); without a source.

    Raises
    ------
    BaseparamsError
        The robot has no usable source file, or the file read again has another structure.
    """
    src = file_source(robot)
    if src is None:
        raise BaseparamsError(f"robot {robot.name!r}: no source file to re-read (built in code, or changed since)")
    snaps = list(snaps)
    suffix = Path(src.path).suffix.lower()
    apply = _apply_urdf if suffix in _URDF else _apply_mjcf
    new = _read(src, lambda doc: apply(doc, snaps))
    same = (new.names == robot.names and new.jtype == robot.jtype and np.array_equal(new.parent, robot.parent)
            and len(new.couplings) == len(robot.couplings))
    if not same:
        raise BaseparamsError(f"{src.path}: read again with {len(snaps)} values exact, it has another structure")
    return replace(robot, M0=new.M0, axes=new.axes, source=None)
