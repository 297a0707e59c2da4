"""Random serial arms as CAD exports write them: a design with degenerate features (the first axis
vertical, consecutive axes parallel) expressed in generic joint frames, so that rounding or a tiny
perturbation is not a value near a right angle or zero (nothing for the snapping to catch)."""

from __future__ import annotations

import numpy as np


def _rotation(rng) -> np.ndarray:
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def _rpy(r: np.ndarray) -> np.ndarray:
    """Roll-pitch-yaw (URDF: R = Rz(yaw) Ry(pitch) Rx(roll)) of a rotation matrix."""
    return np.array([np.arctan2(r[2, 1], r[2, 2]), np.arcsin(-np.clip(r[2, 0], -1, 1)), np.arctan2(r[1, 0], r[0, 0])])


def _tilt(rng, a: np.ndarray, angle: float) -> np.ndarray:
    d = rng.normal(size=3)
    d -= d @ a * a
    d /= np.linalg.norm(d)
    return a * np.cos(angle) + d * np.sin(angle)


def cad_chain(seed: int, eps: float = 0.0, digits: int | None = None, real: float = 0.0,
              size: float = 1.0, shift: float = 0.0) -> str:
    """URDF text of a random arm (3-7 revolute joints, seeded).

    The design: the first axis vertical (70 %), each later axis parallel to the previous one (50 %),
    generic offsets of about ``0.3 size``. ``eps``: the first and the parallel axes tilted by that
    many radians in a random direction (70 % of them; an error of the file); ``digits``: every
    number written to that many significant digits (a CAD export); ``real``: the first axis tilted
    by that much (a design feature, not an error); ``shift``: the whole arm moved that far along x.
    The random draws of the design do not depend on ``eps``, ``digits``, ``real`` or ``shift``.
    """
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 8))
    design = np.random.default_rng([seed, 1])
    z, p = [], []
    for i in range(n):
        u = design.random()
        if i == 0 and u < 0.7:
            a = np.array([0.0, 0.0, 1.0])
        elif i > 0 and u < 0.5:
            a = z[-1].copy()
        else:
            a = design.normal(size=3)
            a /= np.linalg.norm(a)
        z.append(a)
        p.append((p[-1] if p else np.array([shift, 0.0, 0.0])) + design.uniform(-1, 1, 3) * 0.3 * size)
    frames = [_rotation(design) for _ in range(n)]
    errors = np.random.default_rng([seed, 2])
    fmt = (lambda x: repr(float(x))) if digits is None else (lambda x: f"{x:.{digits}g}")
    links, joints = ['<link name="base"/>'], []
    for i in range(n):
        rp, pp = (frames[i - 1], p[i - 1]) if i else (np.eye(3), np.zeros(3))
        ang, xyz, ax = _rpy(rp.T @ frames[i]), rp.T @ (p[i] - pp), frames[i].T @ z[i]
        if i == 0 and real:
            ax = _tilt(errors, ax, real)
        if eps and (i == 0 or np.allclose(z[i], z[i - 1])) and errors.random() < 0.7:
            ax = _tilt(errors, ax, eps)
        m = float(design.uniform(0.5, 3))
        c = design.uniform(-0.1, 0.1, 3) * size
        ii = design.uniform(0.01, 0.05, 3) * size**2 * m
        links.append(f'<link name="l{i}"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}"/><mass value="{m}"/>'
                     f'<inertia ixx="{ii[0] + ii[1]}" iyy="{ii[1] + ii[2]}" izz="{ii[2] + ii[0]}" ixy="0" ixz="0" '
                     f'iyz="0"/></inertial></link>')
        joints.append(f'<joint name="j{i}" type="revolute"><parent link="{"base" if i == 0 else f"l{i - 1}"}"/>'
                      f'<child link="l{i}"/><origin xyz="{" ".join(fmt(x) for x in xyz)}" '
                      f'rpy="{" ".join(fmt(x) for x in ang)}"/><axis xyz="{" ".join(fmt(x) for x in ax)}"/>'
                      f'<limit lower="-3" upper="3" effort="10" velocity="2"/></joint>')
    return f'<robot name="cad{seed}">' + "".join(links + joints) + "</robot>"


def cad_hand(seed: int, eps: float = 0.0, digits: int | None = None, size: float = 0.03, fingers: int = 4) -> str:
    """URDF text of a random hand as a CAD export writes it (seeded): a fixed palm, fingers of an
    abduction joint and three flexion joints about parallel axes (the design; in half of the fingers
    the flexion axes are vertical, as in a hand lying on its side), lengths about ``size``, every joint
    frame generically rotated. ``eps``: each flexion axis but the first of a finger tilted
    that many radians (60 % of them); ``digits``: numbers written to that many significant digits."""
    design = np.random.default_rng([seed, 3])
    errors = np.random.default_rng([seed, 4])
    fmt = (lambda x: repr(float(x))) if digits is None else (lambda x: f"{x:.{digits}g}")
    links, joints = ['<link name="palm"/>'], []
    for f in range(fingers):
        abd = design.normal(size=3)
        abd = np.array([0.0, 0.0, 1.0]) if design.random() < 0.7 else abd / np.linalg.norm(abd)
        flex = np.cross(abd, design.normal(size=3))
        flex /= np.linalg.norm(flex)
        along = np.cross(abd, flex)  # the finger's direction, across both axes
        pp, rp, parent = np.zeros(3), np.eye(3), "palm"
        base = np.array([f * size, 0.0, 2 * size]) + design.uniform(-0.2, 0.2, 3) * size
        for k in range(4):
            a = abd if k == 0 else flex
            step = along * design.uniform(0.8, 1.5) + flex * design.uniform(-0.2, 0.2)
            p = base if k == 0 else pp + step * size
            r = _rotation(design)
            ang, xyz, ax = _rpy(rp.T @ r), rp.T @ (p - pp), r.T @ a
            if eps and k != 1 and errors.random() < 0.6:
                ax = _tilt(errors, ax, eps)
            name = f"f{f}j{k}"
            m = float(design.uniform(0.01, 0.05))
            c = design.uniform(-0.3, 0.3, 3) * size
            ii = design.uniform(0.05, 0.2, 3) * size**2 * m
            links.append(f'<link name="{name}_link"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}"/><mass value="{m}"/>'
                         f'<inertia ixx="{ii[0] + ii[1]}" iyy="{ii[1] + ii[2]}" izz="{ii[2] + ii[0]}" ixy="0" '
                         f'ixz="0" iyz="0"/></inertial></link>')
            joints.append(f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{name}_link"/>'
                          f'<origin xyz="{" ".join(fmt(x) for x in xyz)}" rpy="{" ".join(fmt(x) for x in ang)}"/>'
                          f'<axis xyz="{" ".join(fmt(x) for x in ax)}"/>'
                          f'<limit lower="-3" upper="3" effort="1" velocity="2"/></joint>')
            pp, rp, parent = p, r, f"{name}_link"
    return f'<robot name="hand{seed}">' + "".join(links + joints) + "</robot>"
