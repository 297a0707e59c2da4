"""MJCF (MuJoCo XML) reader: kinematic tree, inertials and closed loops -> :class:`Robot`.

Supported: nested ``<body>`` with ``pos`` and any orientation (``quat``, ``euler`` with the
compiler's ``angle``/``eulerseq``, ``axisangle``, ``xyaxes``, ``zaxis``); ``<inertial>``
(``diaginertia`` or ``fullinertia``); one ``<joint>`` per body (``hinge`` R, ``slide`` P,
``ball`` S, ``free`` F) or ``<freejoint/>``; default classes with inheritance and
``childclass``; bodies without a joint are welded to their parent (inertia merged). Closed
loops from ``<equality>``: ``connect`` (body or site form) -> spherical loop joint, ``weld`` ->
fixed loop joint, ``joint`` with a linear ``polycoef`` -> a coupling. The reference
configuration q = 0 is the XML pose (MuJoCo's qpos0, i.e. hinge ``ref`` angles).
Meshes are never read. Not supported (clear errors): several joints in one body, tendon
equalities, nonlinear joint couplings.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..model.builder import RobotBuilder, quat_pose
from ..model.inertia import Inertia, check_inertia
from ..model.robot import Coupling, Robot

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


def _axis_rot(axis: np.ndarray, angle: float) -> np.ndarray:
    a = axis / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


class _Compiler:
    def __init__(self, root: ET.Element):
        comp = root.find("compiler")
        self.radian = comp is not None and comp.get("angle", "degree") == "radian"
        self.eulerseq = comp.get("eulerseq", "xyz") if comp is not None else "xyz"

    def angle(self, v: float) -> float:
        return v if self.radian else np.deg2rad(v)

    def pose(self, attrs: dict[str, str], what: str) -> np.ndarray:
        t = quat_pose(_floats(attrs.get("pos"), 3, f"{what} pos", (0, 0, 0)),
                      _floats(attrs.get("quat"), 4, f"{what} quat", (1, 0, 0, 0)))
        given = [k for k in ("quat", "euler", "axisangle", "xyaxes", "zaxis") if k in attrs]
        if len(given) > 1:
            raise ModelError(f"{what}: several orientations given ({', '.join(given)})")
        if "axisangle" in attrs:
            v = _floats(attrs["axisangle"], 4, f"{what} axisangle")
            if np.linalg.norm(v[:3]) < 1e-12:
                raise ModelError(f"{what}: zero axis in axisangle")
            t[:3, :3] = _axis_rot(v[:3], self.angle(v[3]))
        elif "euler" in attrs:
            v = _floats(attrs["euler"], 3, f"{what} euler")
            r = np.eye(3)
            for ax, ang in zip(self.eulerseq, v):
                e = np.eye(3)["xyz".index(ax.lower())]
                rot = _axis_rot(e, self.angle(ang))
                r = r @ rot if ax.islower() else rot @ r  # lowercase: axes move with the frame
            t[:3, :3] = r
        elif "xyaxes" in attrs:
            v = _floats(attrs["xyaxes"], 6, f"{what} xyaxes")
            x = v[:3] / np.linalg.norm(v[:3])
            y = v[3:] - (v[3:] @ x) * x
            if np.linalg.norm(y) < 1e-12:
                raise ModelError(f"{what}: xyaxes are parallel")
            y /= np.linalg.norm(y)
            t[:3, :3] = np.column_stack([x, y, np.cross(x, y)])
        elif "zaxis" in attrs:
            z = _floats(attrs["zaxis"], 3, f"{what} zaxis")
            z = z / np.linalg.norm(z)
            c = np.cross([0, 0, 1.0], z)
            if np.linalg.norm(c) < 1e-12:
                t[:3, :3] = np.eye(3) if z[2] > 0 else np.diag([1.0, -1, -1])
            else:
                t[:3, :3] = _axis_rot(c, np.arctan2(np.linalg.norm(c), z[2]))
        return t


def load_mjcf(path: str | Path, name: str | None = None, gravity=None, floating: bool = False,
              strict_inertia: bool = False) -> Robot:
    """Read an MJCF file into a :class:`Robot` (see the module doc). ``gravity``: default
    from ``<option gravity>`` (MuJoCo's default ``0 0 -9.81``). ``floating``: a top-level body
    without a joint gets a floating (F) joint."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ModelError(f"{path}: malformed XML ({exc})") from None
    except OSError as exc:
        raise ModelError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if root.tag != "mujoco":
        raise ModelError(f"{path}: root element is <{root.tag}>, expected <mujoco>")
    if root.find("include") is not None:
        raise ModelError(f"{path}: <include> is not supported; pass the expanded model")
    if gravity is None:
        opt = root.find("option")
        gravity = _floats(opt.get("gravity") if opt is not None else None, 3, f"{path}: <option gravity>",
                          (0, 0, -9.81))
    comp = _Compiler(root)
    defaults = _Defaults(root.find("default"))
    world = root.find("worldbody")
    if world is None:
        raise ModelError(f"{path}: no <worldbody>")
    b = RobotBuilder(name or root.get("model", path.stem), gravity=gravity)
    link_world: dict[str, np.ndarray] = {}  # world pose (q = 0) of each body's builder frame
    body_world: dict[str, np.ndarray] = {}  # world pose (q = 0) of each MJCF body frame
    sites: dict[str, tuple[str, np.ndarray]] = {}  # site -> (body, world pose)
    joint_coord: dict[str, str] = {}  # joint name -> body (for couplings)
    independent_flags: list[bool] = []

    def visit(body: ET.Element, parent: str | None, active: str, world_parent: np.ndarray, top: bool) -> None:
        bname = body.get("name")
        what = f"{path}: <body name={bname!r}>"
        if not bname:
            raise ModelError(f"{path}: a <body> has no name")
        if bname in body_world:
            raise ModelError(f"{what}: duplicate body name")
        active = body.get("childclass", active)
        t_rel = comp.pose(body.attrib, what)
        w_body = world_parent @ t_rel
        body_world[bname] = w_body
        joints = [j for j in body if j.tag in ("joint", "freejoint")]
        if len(joints) > 1:
            raise ModelError(f"{what}: {len(joints)} joints in one body are not supported yet")
        inertia = None
        inl = body.find("inertial")
        if inl is not None:
            ia = inl.attrib
            mass = float(_floats(ia.get("mass"), 1, f"{what} <inertial mass>")[0])
            if "fullinertia" in ia:
                ixx, iyy, izz, ixy, ixz, iyz = _floats(ia["fullinertia"], 6, f"{what} fullinertia")
                j = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
            else:
                j = np.diag(_floats(ia.get("diaginertia"), 3, f"{what} <inertial diaginertia>"))
            check_inertia(mass, j, f"{what} <inertial>", strict=strict_inertia)
            inertia = (mass, comp.pose(ia, f"{what} <inertial>"), j)
        if not joints:
            jt, t_joint, axis = ("F" if (top and floating) else "fixed"), np.eye(4), (0, 0, 1)
        else:
            ja = defaults.attrs(joints[0], active, what)
            jt = "F" if joints[0].tag == "freejoint" else _JOINTS.get(ja.get("type", "hinge"))
            if jt is None:
                raise ModelError(f"{what}: unknown joint type {ja.get('type')!r}")
            if jt == "F" and not top:
                raise ModelError(f"{what}: a free joint is only supported on a top-level body")
            t_joint = np.eye(4)
            t_joint[:3, 3] = _floats(ja.get("pos"), 3, f"{what} joint pos", (0, 0, 0))
            axis = _floats(ja.get("axis"), 3, f"{what} joint axis", (0, 0, 1))
            if jt in ("R", "P") and np.linalg.norm(axis) < 1e-12:
                raise ModelError(f"{what}: zero joint axis")
            if joints[0].get("name"):
                joint_coord[joints[0].get("name")] = bname
        inv_joint = np.linalg.inv(t_joint)
        inert = None
        if inertia is not None:
            mass, t_in, j = inertia
            inert = Inertia(mass, com=(0, 0, 0), inertia=j, frame=inv_joint @ t_in)
        jname = (joints[0].get("name") or f"{bname}_joint") if joints else f"{bname}_joint"
        parent_link = link_world.get(parent, np.eye(4)) if parent is not None else np.eye(4)
        origin = np.linalg.inv(parent_link) @ w_body @ t_joint
        b.add_link(bname, parent=parent, joint=jt, origin=origin, axis=axis, inertia=inert, joint_name=jname,
                   actuated=None if jt == "fixed" else True)
        if jt != "fixed":
            independent_flags.append(True)
        link_world[bname] = w_body @ t_joint
        for child in body:
            if child.tag == "site" and child.get("name"):
                sa = defaults.attrs(child, active, f"{what} <site>")
                sites[child.get("name")] = (bname, w_body @ comp.pose(sa, f"{what} <site name={child.get('name')!r}>"))
        for child in body:
            if child.tag == "body":
                visit(child, bname, active, w_body, False)

    for top in world:
        if top.tag == "body":
            visit(top, None, "main", np.eye(4), True)
        elif top.tag == "site" and top.get("name"):
            sites[top.get("name")] = ("world", comp.pose(top.attrib, f"{path}: <site>"))
    couplings = _equalities(root, path, b, link_world, body_world, sites, joint_coord)
    robot = b.build()
    if couplings:
        from dataclasses import replace

        qi = robot.q_index
        out = []
        for cname, lead, follow, ratio, offset in couplings:
            i, k = robot.names.index(lead), robot.names.index(follow)
            if robot.ndofs[i] != 1 or robot.ndofs[k] != 1:
                raise ModelError(f"{path}: <equality><joint name={cname!r}>: only 1-dof joints can be coupled")
            out.append(Coupling(cname, int(qi[i]), int(qi[k]), ratio, offset))
        robot = replace(robot, couplings=tuple(out))
    if robot.has_loops:  # MJCF does not say which coordinates are independent: choose them
        from ..kinematics.loops import choose_independent

        motors = {a.get("joint") for a in root.iter() if a.get("joint") and a.tag in
                  ("motor", "position", "velocity", "general", "intvelocity", "damper")}
        qi = robot.q_index
        prefer = {int(qi[robot.joint_names.index(j)]) + d for j in motors if j in robot.joint_names
                  for d in range(int(robot.ndofs[robot.joint_names.index(j)]))}
        prefer |= set(range(int(robot.ndofs[0]))) if robot.jtype[0] == "F" else set()
        robot = choose_independent(robot, prefer)
    return robot


def _equalities(root, path, b: RobotBuilder, link_world, body_world, sites, joint_coord) -> list:
    """Add loop joints for connect/weld; return couplings for joint equalities."""
    couplings = []
    eq = root.find("equality")
    if eq is None:
        return couplings
    for k, e in enumerate(eq):
        if e.get("active", "true") == "false":
            continue
        ename = e.get("name") or f"{e.tag}{k}"
        what = f"{path}: <equality><{e.tag} name={ename!r}>"
        if e.tag in ("connect", "weld"):
            if e.get("site1") is not None or e.get("site2") is not None:
                s1, s2 = e.get("site1"), e.get("site2")
                for s in (s1, s2):
                    if s not in sites:
                        raise ModelError(f"{what}: unknown site {s!r}")
                (b1, w1), (b2, w2) = sites[s1], sites[s2]
            else:
                b1, b2 = e.get("body1"), e.get("body2", "world")
                for bb in (b1, b2):
                    if bb != "world" and bb not in body_world:
                        raise ModelError(f"{what}: unknown body {bb!r}")
                wb1 = body_world.get(b1, np.eye(4))
                if e.tag == "connect":
                    anchor = _floats(e.get("anchor"), 3, f"{what} anchor")
                    w1 = wb1.copy()
                    w1[:3, 3] = wb1[:3, :3] @ anchor + wb1[:3, 3]
                    w1[:3, :3] = np.eye(3)
                else:
                    w1 = wb1 @ quat_pose(*np.split(_floats(e.get("relpose"), 7, f"{what} relpose",
                                                           (0, 0, 0, 1, 0, 0, 0)), [3])) \
                        if e.get("relpose") else wb1
                w2 = w1  # MuJoCo fixes the body2 side from the qpos0 pose
            i1 = b._frames[b1][0] if b1 != "world" else -1
            i2 = b._frames[b2][0] if b2 != "world" else -1
            if i1 == i2:
                raise ModelError(f"{what}: both sides are on the same body")
            (pb, pw), (cb, cw) = ((b1, w1), (b2, w2)) if i1 < i2 else ((b2, w2), (b1, w1))
            pl = link_world.get(pb, np.eye(4)) if pb != "world" else np.eye(4)
            cl = link_world[cb]
            w_frame = pw if e.tag == "weld" else np.r_[np.c_[np.eye(3), pw[:3, 3]], [[0, 0, 0, 1]]]
            c_frame = cw if e.tag == "weld" else np.r_[np.c_[np.eye(3), cw[:3, 3]], [[0, 0, 0, 1]]]
            b.add_loop(ename, "S" if e.tag == "connect" else "fixed", parent=None if pb == "world" else pb,
                       child=cb, origin=np.linalg.inv(pl) @ w_frame, child_origin=np.linalg.inv(cl) @ c_frame)
        elif e.tag == "joint":
            j1, j2 = e.get("joint1"), e.get("joint2")
            if j2 is None:
                raise ModelError(f"{what}: a joint locked by an equality is not supported (no joint2)")
            for j in (j1, j2):
                if j not in joint_coord:
                    raise ModelError(f"{what}: unknown joint {j!r}")
            coef = _floats(e.get("polycoef"), 5, f"{what} polycoef", (0, 1, 0, 0, 0))
            if np.any(coef[2:] != 0):
                raise ModelError(f"{what}: nonlinear polycoef {coef.tolist()} is not supported")
            couplings.append((ename, joint_coord[j2], joint_coord[j1], float(coef[1]), float(coef[0])))
        elif e.tag == "tendon":
            raise ModelError(f"{what}: tendon equalities are not supported")
        else:
            raise ModelError(f"{what}: unknown equality type")
    return couplings
