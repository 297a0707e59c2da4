"""MJCF (MuJoCo XML) reader: the kinematic tree and inertials -> :class:`Robot`.

Supported now: nested ``<body pos quat>``, ``<inertial pos quat mass diaginertia|fullinertia>``,
``<joint type="hinge|slide|ball|free">`` (one joint per body, ``pos`` and ``axis``),
``<freejoint/>``, default classes with inheritance and ``childclass``. A body without a joint is
welded to its parent (its inertia merged). Meshes are never read, so missing assets are fine.
Anything else that changes the kinematics (several joints in one body, ``euler`` orientations,
``<equality>`` loops, couplings) is reported as a clear error rather than ignored.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..model.builder import RobotBuilder, quat_pose
from ..model.inertia import Inertia

_JOINTS = {"hinge": "R", "slide": "P", "ball": "S", "free": "F"}


def _floats(s: str | None, n: int, what: str, default=None) -> np.ndarray:
    if s is None:
        if default is None:
            raise ModelError(f"{what}: missing attribute")
        return np.asarray(default, dtype=float)
    try:
        v = np.array([float(x) for x in s.split()])
    except ValueError:
        raise ModelError(f"{what}: expected {n} numbers, got {s!r}") from None
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ModelError(f"{what}: expected {n} finite numbers, got {s!r}")
    return v


class _Defaults:
    def __init__(self, root: ET.Element | None):
        self.classes: dict[str, dict[str, dict[str, str]]] = {"main": {}}
        if root is not None:
            self._walk(root, "main", {})

    def _walk(self, node: ET.Element, name: str, inherited: dict[str, dict[str, str]]) -> None:
        own = {k: dict(v) for k, v in inherited.items()}
        for child in node:
            if child.tag != "default":
                own.setdefault(child.tag, {}).update(child.attrib)
        self.classes[name] = own
        for child in node:
            if child.tag == "default":
                self._walk(child, child.get("class", "main"), own)

    def attrs(self, elem: ET.Element, active_class: str, path: str) -> dict[str, str]:
        cls = elem.get("class", active_class)
        if cls not in self.classes:
            raise ModelError(f"{path}: unknown default class {cls!r}")
        out = dict(self.classes[cls].get(elem.tag, {}))
        out.update(elem.attrib)
        return out


def _pose(attrs: dict[str, str], what: str) -> np.ndarray:
    for bad in ("euler", "axisangle", "xyaxes", "zaxis"):
        if bad in attrs:
            raise ModelError(f"{what}: orientation given as {bad!r} is not supported yet; use quat")
    return quat_pose(_floats(attrs.get("pos"), 3, f"{what} pos", (0, 0, 0)),
                     _floats(attrs.get("quat"), 4, f"{what} quat", (1, 0, 0, 0)))


def load_mjcf(path: str | Path, name: str | None = None, gravity=None) -> "Robot":  # noqa: F821
    """Read an MJCF file into a :class:`Robot` (world gravity from ``<option gravity>`` unless
    ``gravity`` is given; MuJoCo's default is ``0 0 -9.81``)."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ModelError(f"{path}: malformed XML ({exc})") from None
    except OSError as exc:
        raise ModelError(f"{path}: cannot read ({exc.strerror})") from None
    if root.tag != "mujoco":
        raise ModelError(f"{path}: root element is <{root.tag}>, expected <mujoco>")
    for tag in ("equality", "tendon"):
        if root.find(tag) is not None and len(root.find(tag)):
            raise ModelError(f"{path}: <{tag}> (closed loops / couplings) is not supported yet")
    if gravity is None:
        opt = root.find("option")
        gravity = _floats(opt.get("gravity") if opt is not None else None, 3, f"{path}: <option gravity>",
                          (0, 0, -9.81))
    defaults = _Defaults(root.find("default"))
    world = root.find("worldbody")
    if world is None:
        raise ModelError(f"{path}: no <worldbody>")
    b = RobotBuilder(name or root.get("model", path.stem), gravity=gravity)

    def visit(body: ET.Element, parent: str | None, active: str, frame_in_parent: np.ndarray) -> None:
        bname = body.get("name")
        what = f"{path}: <body name={bname!r}>"
        if not bname:
            raise ModelError(f"{path}: a <body> has no name")
        active = body.get("childclass", active)
        t_body = frame_in_parent @ _pose(body.attrib, what)
        joints = [j for j in body if j.tag in ("joint", "freejoint")]
        if len(joints) > 1:
            raise ModelError(f"{what}: {len(joints)} joints in one body are not supported yet")
        inertia = None
        inl = body.find("inertial")
        if inl is not None:
            ia = inl.attrib
            mass = float(_floats(ia.get("mass"), 1, f"{what} <inertial mass>")[0])
            if mass < 0:
                raise ModelError(f"{what} <inertial>: negative mass {mass}")
            if "fullinertia" in ia:
                ixx, iyy, izz, ixy, ixz, iyz = _floats(ia["fullinertia"], 6, f"{what} fullinertia")
                j = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
            else:
                j = np.diag(_floats(ia.get("diaginertia"), 3, f"{what} <inertial diaginertia>"))
            inertia = (mass, _pose(ia, f"{what} <inertial>"), j)
        if not joints:
            jt, t_joint, axis = "fixed", np.eye(4), (0, 0, 1)
        else:
            ja = defaults.attrs(joints[0], active, what)
            jt = "F" if joints[0].tag == "freejoint" else _JOINTS.get(ja.get("type", "hinge"))
            if jt is None:
                raise ModelError(f"{what}: unknown joint type {ja.get('type')!r}")
            pos = _floats(ja.get("pos"), 3, f"{what} joint pos", (0, 0, 0))
            t_joint = np.eye(4)
            t_joint[:3, 3] = pos
            axis = _floats(ja.get("axis"), 3, f"{what} joint axis", (0, 0, 1))
            if jt in ("R", "P") and np.linalg.norm(axis) < 1e-12:
                raise ModelError(f"{what}: zero joint axis")
        inv_joint = np.linalg.inv(t_joint)
        inert = None
        if inertia is not None:
            mass, t_in, j = inertia
            inert = Inertia(mass, com=(0, 0, 0), inertia=j, frame=inv_joint @ t_in)
        jname = joints[0].get("name", f"{bname}_joint") if joints else None
        b.add_link(bname, parent=parent, joint=jt, origin=t_body @ t_joint, axis=axis,
                   inertia=inert, joint_name=jname)
        # children are placed relative to the MJCF body frame = joint frame @ inv(t_joint)
        for child in body:
            if child.tag == "body":
                visit(child, bname, active, inv_joint if jt != "fixed" else inv_joint)
    for top in world:
        if top.tag == "body":
            visit(top, None, "main", np.eye(4))
    return b.build()
