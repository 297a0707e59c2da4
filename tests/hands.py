"""Five-finger hands as CAD exports write them (seeded), for the snapping and rank-decision tests.

The design: a palm fixed to the world (a wrist turned by right angles: the hand on its side,
palm down or fingers up), four fingers of an abduction joint about the palm normal (half of
them have none) and three flexion joints about parallel axes across the finger, and a thumb
whose first axis is oblique (designed generic angles), the next one at a right angle to it and
two flexion axes parallel to that one; the last joint of every finger a ``<mimic>`` of the one
before it (tendon-coupled hands); links 3-5 cm, 10-50 g. Each joint frame is the design frame
turned by a random right-angle rotation (CAD link frames have their own conventions) and each
finger sits on a mount link (a fixed joint, merged into the palm) turned by a designed splay
angle, so that the frames a reader composes are not the file's own rotations.

The file as a CAD export writes it: every number to ``digits`` significant digits (``1.5708``,
``3.14159``, ``0.707107``) and some right angles, zeros and axis components off by 2e-5 - 8e-4
rad (``mates``: assembly mates a little off), each one listed. The design: the same file with
every number exact (``repr``), no mate errors. URDF (``<origin rpy>``) or MJCF (bodies with
``quat``, ``euler`` in degrees or ``axisangle``, joint equalities for the mimics).
"""

from __future__ import annotations

import itertools
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def right_angle_rotations() -> list[np.ndarray]:
    """The 24 rotations that permute the frame axes (with signs)."""
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            m = np.zeros((3, 3))
            m[list(range(3)), list(perm)] = signs
            if np.linalg.det(m) > 0:
                out.append(m)
    return out


RIGHT = right_angle_rotations()

#: how the wrist turns the palm (right angles): on its side (flexion axes vertical), palm down (abduction axes
#: vertical), fingers up
POSES = {"side": np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]]), "down": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),
         "up": np.eye(3)}


def urdf_rpy(r: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (URDF: ``R = Rz(yaw) Ry(pitch) Rx(roll)``) as an exporter computes them."""
    pitch = np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0]))
    if np.hypot(r[0, 0], r[1, 0]) < 1e-9:  # gimbal lock: the roll takes the whole angle
        return np.array([np.arctan2(-r[1, 2], r[1, 1]), pitch, 0.0])
    return np.array([np.arctan2(r[2, 1], r[2, 2]), pitch, np.arctan2(r[1, 0], r[0, 0])])


@dataclass
class Hand:
    """A generated hand: the file's text, the design's text and the mate errors written into the file."""

    text: str
    design: str
    mates: list  # (element, what, component, special value, value written)


@dataclass
class _Part:
    """One joint of the design: its child link, the frame relative to the parent link's, its axis (None: fixed)."""

    name: str
    parent: str
    child: str
    rot: np.ndarray
    xyz: np.ndarray
    axis: np.ndarray | None
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    mimic: tuple | None = None  # (leader joint, multiplier)


def _special(x: float) -> float | None:
    """The multiple of pi/2 (or 0) that an angle is, exactly to 1e-12, else None."""
    k = np.round(x / (np.pi / 2))
    return float(k * np.pi / 2) if abs(x - k * np.pi / 2) < 1e-12 else None


def _link(rng, length: float) -> tuple[float, np.ndarray, np.ndarray]:
    m = float(rng.uniform(0.01, 0.05))
    c = rng.uniform(-0.2, 0.2, 3) * length + np.array([0, 0, 0.5 * length])
    ii = rng.uniform(0.05, 0.2, 3) * length**2 * m
    return m, c, np.array([ii[0] + ii[1], ii[1] + ii[2], ii[2] + ii[0]])


def _design(seed: int, mimic: bool, fingers: int, pose: str | None) -> list[_Part]:
    """The hand's joints in file order (the wrist first), exact."""
    rng = np.random.default_rng([seed, 13])
    design = np.random.default_rng([seed, 11])
    pose = pose or ("side", "down", "up")[seed % 3]
    wrist = _rz(np.pi / 2 * int(design.integers(4))) @ POSES[pose]
    parts = [_Part("wrist", "world", "palm", wrist, np.array([0, 0, 0.5]), None, float(design.uniform(0.2, 0.4)),
                   np.array([0, 0, 0.04]), np.array([2e-4, 2e-4, 1e-4]))]
    for f in range(fingers):
        parts += _finger(rng, f, mimic)
    return parts


def _finger(rng, f: int, mimic: bool) -> list[_Part]:
    thumb = f == 4
    if thumb:  # oblique: designed generic angles
        d = _rz(rng.uniform(0.4, 0.8)) @ _ry(-rng.uniform(0.5, 0.9)) @ _rx(rng.uniform(0.2, 0.4))
        base = np.array([-0.035, 0.015, 0.02])
    else:
        splay = 0.0 if f in (1, 2) else (-1 if f == 0 else 1) * rng.uniform(0.08, 0.2)
        d = _ry(splay)  # about the palm normal y; fingers along z, flexion axes along x
        base = np.array([(f - 1.5) * 0.022, 0.0, 0.09])
    mount = d @ RIGHT[int(rng.integers(24))]  # the mount link (fixed, merged into the palm)
    out = [_Part(f"f{f}_mount_joint", "palm", f"f{f}_mount", mount, base, None, 0.0, np.zeros(3), np.zeros(3))]
    parent, pr, pp = f"f{f}_mount", mount, base
    axes = [np.array([0.0, 0.0, 1.0]) if thumb else np.array([0.0, 1.0, 0.0])] + [np.array([1.0, 0, 0])] * 3
    steps = [0.0, 0.0 if rng.random() < 0.5 else 0.004] + list(rng.uniform(0.03, 0.05, 2))
    tip = rng.uniform(0.03, 0.05)
    p = base.copy()
    first = 0 if thumb or rng.random() < 0.5 else 1  # half of the fingers without an abduction joint
    for k in range(first, 4):
        name = f"f{f}j{k}"
        p = p + d @ np.array([0.0, 0.0, steps[k]])
        frame = d @ RIGHT[int(rng.integers(24))]
        m, c, ii = _link(rng, rng.uniform(0.03, 0.05))
        lead = (f"f{f}j2", float(np.round(rng.uniform(0.6, 1.0), 3))) if mimic and k == 3 else None
        out.append(_Part(name, parent, f"{name}_link", pr.T @ frame, pr.T @ (p - pp), frame.T @ d @ axes[k], m, c, ii,
                         lead))
        parent, pr, pp = f"{name}_link", frame, p
    m, c, ii = _link(rng, 0.01)
    out.append(_Part(f"f{f}_tip_joint", parent, f"f{f}_tip", np.eye(3), pr.T @ (d @ np.array([0.0, 0.0, tip])), None,
                     m, c, ii))
    return out


class _Writer:
    """Numbers written as the file (rounded, with mate errors) or as the design (exact)."""

    def __init__(self, seed: int, digits: int | None, rate: float, exact: bool):
        self.rng = np.random.default_rng([seed, 12])
        self.digits, self.rate, self.exact = digits, rate, exact
        self.mates: list = []

    def num(self, x: float) -> str:
        x = 0.0 if abs(x) < 1e-12 else float(x)
        return repr(x) if self.exact or self.digits is None else f"{x:.{self.digits}g}"

    def mate(self) -> bool:
        """Whether this special value is written off by a mate error (the draw is made in both writers)."""
        hit = self.rng.random() < self.rate
        return hit and not self.exact

    def error(self) -> float:
        return float(self.rng.choice([-1, 1]) * self.rng.uniform(2e-5, 8e-4))

    def angles(self, element: str, ang: np.ndarray) -> str:
        out = []
        for k, a in enumerate(ang):
            s = _special(a)
            if s is not None and self.mate():
                a = s + self.error()
                self.mates.append((element, "angle", k, s, float(self.num(a))))
            out.append(self.num(a))
        return " ".join(out)

    def axis(self, element: str, ax: np.ndarray) -> str:
        ax = np.array(ax, dtype=float)
        zero = np.flatnonzero(np.abs(ax) < 1e-12)
        if self.mate() and self.rng.random() < 0.5:
            k = int(self.rng.choice(zero))
            ax[k] = self.error()
            self.mates.append((element, "axis", k, 0.0, float(self.num(ax[k]))))
        return " ".join(self.num(a) for a in ax)

    def rotation(self, element: str, r: np.ndarray) -> np.ndarray:
        """The rotation as written (MJCF): turned by a mate error about a random axis, sometimes."""
        if self.mate():
            w = self.rng.normal(size=3)
            w *= abs(self.error()) / np.linalg.norm(w)
            self.mates.append((element, "rotation", -1, 0.0, float(np.linalg.norm(w))))
            return r @ Rotation.from_rotvec(w).as_matrix()
        return r


def five_finger_hand(seed: int, digits: int | None = 6, mates: float = 0.25, mimic: bool = True,
                     fingers: int = 5, pose: str | None = None) -> Hand:
    """A five-finger hand as a CAD export writes its URDF, and its design (module docstring).

    ``digits``: significant digits of every number in the file (None: full precision);
    ``mates``: the chance of each right angle or zero of a joint frame (and of each axis) being
    written off by 2e-5 - 8e-4 rad; ``mimic``: the last flexion joint of each finger mimics the
    one before it; ``fingers``: 1-5 (the thumb is the fifth); ``pose``: a key of :data:`POSES`
    (default by seed: side, down, up).
    """
    return _written(seed, _design(seed, mimic, fingers, pose), digits, mates, _urdf)


def _written(seed: int, parts: list[_Part], digits: int | None, mates: float, write) -> Hand:
    """The file (rounded, mates off) and the design (exact), both by ``write(seed, parts, writer)``."""
    texts = {exact: (w := _Writer(seed, digits, mates, exact), write(seed, parts, w)) for exact in (True, False)}
    return Hand(texts[False][1], texts[True][1], texts[False][0].mates)


def _urdf(seed: int, parts: list[_Part], w: _Writer) -> str:
    links, joints = ['<link name="world"/>'], []
    for p in parts:
        inertial = "" if p.mass == 0 else (
            f'<inertial><origin xyz="{p.com[0]:.6g} {p.com[1]:.6g} {p.com[2]:.6g}"/><mass value="{p.mass:.6g}"/>'
            f'<inertia ixx="{p.inertia[0]:.6g}" iyy="{p.inertia[1]:.6g}" izz="{p.inertia[2]:.6g}" ixy="0" ixz="0" '
            f'iyz="0"/></inertial>')
        links.append(f'<link name="{p.child}">{inertial}</link>')
        el = f'<joint name="{p.name}">'
        ang = w.angles(el, urdf_rpy(w.rotation(el, p.rot)))  # a mate error before the exporter's rpy, or in one
        out = (f'<joint name="{p.name}" type="{"fixed" if p.axis is None else "revolute"}"><parent link="{p.parent}"/>'
               f'<child link="{p.child}"/><origin xyz="{" ".join(w.num(x) for x in p.xyz)}" rpy="{ang}"/>')
        if p.axis is not None:
            out += f'<axis xyz="{w.axis(el, p.axis)}"/><limit lower="-1.5" upper="1.5" effort="1" velocity="3"/>'
        if p.mimic is not None:
            out += f'<mimic joint="{p.mimic[0]}" multiplier="{p.mimic[1]}" offset="0"/>'
        joints.append(out + "</joint>")
    return f'<robot name="hand{seed}">' + "".join(links + joints) + "</robot>"


def five_finger_hand_mjcf(seed: int, digits: int | None = 6, mates: float = 0.25, mimic: bool = True,
                          fingers: int = 5, pose: str | None = None) -> Hand:
    """The same hands as MJCF: each link a body whose orientation is a ``quat``, an ``euler`` (degrees) or an
    ``axisangle`` (degrees), chosen at random; mimics as ``<equality><joint polycoef>``. ``mates``: the chance of
    each body's rotation being turned by 2e-5 - 8e-4 rad about a random axis, and of each axis being off."""
    return _written(seed, _design(seed, mimic, fingers, pose), digits, mates, _mjcf)


def _orientation(w: _Writer, element: str, r: np.ndarray, form: int) -> str:
    rot = Rotation.from_matrix(w.rotation(element, r))
    if form == 0:
        q = rot.as_quat(scalar_first=True)
        return f'quat="{" ".join(w.num(x) for x in q)}"'
    if form == 1:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # gimbal lock: scipy sets the third angle to zero, as an exporter may
            ang = rot.as_euler("XYZ")
        return f'euler="{" ".join(w.num(x) for x in np.degrees(ang))}"'
    v = rot.as_rotvec()
    ang = float(np.linalg.norm(v))
    ax = v / ang if ang > 0 else np.array([0.0, 0.0, 1.0])
    return f'axisangle="{" ".join(w.num(x) for x in ax)} {w.num(np.degrees(ang))}"'


def _mjcf(seed: int, parts: list[_Part], w: _Writer) -> str:
    forms = np.random.default_rng([seed, 14])
    children: dict[str, list[_Part]] = {}
    for p in parts:
        children.setdefault(p.parent, []).append(p)

    def body(p: _Part) -> str:
        el = f"body '{p.child}'"
        text = (f'<body name="{p.child}" pos="{" ".join(w.num(x) for x in p.xyz)}" '
                f'{_orientation(w, el, p.rot, int(forms.integers(3)))}>')
        if p.axis is not None:
            text += f'<joint name="{p.name}" axis="{w.axis(el, p.axis)}" range="-1.5 1.5"/>'
        if p.mass > 0:
            text += (f'<inertial pos="{p.com[0]:.6g} {p.com[1]:.6g} {p.com[2]:.6g}" mass="{p.mass:.6g}" '
                     f'diaginertia="{p.inertia[0]:.6g} {p.inertia[1]:.6g} {p.inertia[2]:.6g}"/>')
        return text + "".join(body(c) for c in children.get(p.child, [])) + "</body>"

    eq = "".join(f'<joint joint1="{p.name}" joint2="{p.mimic[0]}" polycoef="0 {p.mimic[1]} 0 0 0"/>'
                 for p in parts if p.mimic is not None)
    return (f'<mujoco model="hand{seed}"><compiler angle="degree" autolimits="true"/><worldbody>'
            f'{body(parts[0])}</worldbody>{f"<equality>{eq}</equality>" if eq else ""}</mujoco>')
