"""Closed-loop built-in robots: a four-bar, a parallelogram, and the paper's two PKMs.

Every model is a spanning tree plus loop (cut) joints whose two frames coincide at q = 0,
the reference assembly; actuated coordinates are marked, and ``q_box`` is the sampling box
of the actuated coordinates (relative to q = 0) used by the numerical validation.

**2RRU-1RRS** (after Xu et al. 2023, the paper's Fig. "2RRU-1RRS"): three limbs from the base
to the moving platform. Limbs a and b (RRU) sit opposite each other on the x axis (base
points at angles 0 and pi), limb c (RRS) at pi/2. In each limb the two R axes are parallel and
tangent to the base circle; the U joint's first axis is parallel to them (carried by the
second link), its second axis radial (carried by the platform); limb c ends in an S joint.
Constraints: two forces along y and a couple about z from the RRU limbs (rank 2 together)
and a force along x from the RRS limb: 3 DOF (z translation and two rotations). Actuated:
the first R of each limb, at 45 deg elevation at q = 0 (the centre of the paper's boxes
(20, 70) deg and (110, 160) deg), sampled in +-25 deg. Generic dimensions: the three limbs
have slightly different base radii, platform radii and link lengths.
Tree: link1a - link2a - platform (U); link1b - link2b; link1c - link2c; loops: U (platform,
link2b) and S (platform, link2c). 7 bodies, 70 parameters.

**2PRS-1PSR** (after Shi et al. 2023): three vertical P actuators at base angles about 90,
210 and 330 deg. Limbs a and b: P, then an R joint on the slider (axis tangent to the base
circle), a link, and an S joint on the platform. Limb c: P, an S joint on the slider, a link,
and an R joint on the platform (axis tangent). Each limb exerts one constraint force
(horizontal, along its R axis): 3 DOF. Actuated: the three sliders, sampled in +-0.05 m.
Tree: slider a - link a - platform (S); slider b - link b; slider c - link c (S); loops: S
(platform, link b), R (platform, link c). 7 bodies, 70 parameters. ``symmetric=True`` gives
the mirror-symmetric layout with equal dimensions: the two PRS limbs opposite each other (base
angles 0 and 180 deg, their R axes parallel) and the PSR limb at 90 deg. Both sphere centres
then keep their y coordinate, the platform's R axis stays level, and the nullity is 48, not 47
(``docs/paper-corrections.md`` case 6; closed by rule R-L2, level chains).
"""

from __future__ import annotations

import numpy as np

from ..model import Inertia, Robot, RobotBuilder, pose


def _inertia(k: int, length: float = 0.3) -> Inertia:
    """Plausible, distinct link inertias (a rod-like body with an offset centre of mass)."""
    m = 1.0 + 0.17 * k
    c = (0.01 * (k % 3), 0.02 - 0.005 * k, length / 2)
    i = m * np.array([length**2 / 12 + 0.001 * k, length**2 / 12 + 0.002, 0.002 + 0.0005 * k])
    return Inertia(m, com=c, inertia=i)


def _frame(origin: np.ndarray, z: np.ndarray) -> np.ndarray:
    """A pose at ``origin`` whose z axis is ``z`` (x chosen perpendicular)."""
    z = z / np.linalg.norm(z)
    h = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(h, z)
    x /= np.linalg.norm(x)
    t = np.eye(4)
    t[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    t[:3, 3] = origin
    return t


def _rel(parent_world: np.ndarray, child_world: np.ndarray) -> np.ndarray:
    return np.linalg.inv(parent_world) @ child_world


def four_bar(parallelogram: bool = False, gravity=(0.0, -9.81, 0.0)) -> Robot:
    """Planar four-bar in the xy plane (R axes along z), crank actuated.

    Ground pivots A = (0, 0), D = (1, 0); at q = 0 the crank tip is B = (0.3, 0.5) and the
    rocker tip C = (1.25, 0.65) (generic), or C = (1.3, 0.5) for the parallelogram
    (opposite sides equal). Tree: crank (A) - coupler (B); rocker (D); loop R at C between
    coupler and rocker. Gravity in the plane (-y).

    Parameters
    ----------
    parallelogram : bool
        The parallelogram's dimensions instead of the generic ones.
    gravity : array_like, shape ``(3,)``
        Gravity [m/s^2] in the world frame.

    Returns
    -------
    Robot
        3 bodies, 1 loop joint, the crank actuated (``q_box`` +-0.3 rad).
    """
    a, b, d = np.zeros(3), np.array([0.3, 0.5, 0]), np.array([1.0, 0, 0])
    c = np.array([1.3, 0.5, 0]) if parallelogram else np.array([1.25, 0.65, 0])
    bl = RobotBuilder("parallelogram" if parallelogram else "four-bar", gravity=gravity)
    bl.add_link("crank", joint="R", origin=pose(a), axis=(0, 0, 1), inertia=_inertia(1), actuated=True)
    bl.add_link("coupler", parent="crank", joint="R", origin=pose(b - a), axis=(0, 0, 1),
                inertia=_inertia(2), actuated=False)
    bl.add_link("rocker", joint="R", origin=pose(d), axis=(0, 0, 1), inertia=_inertia(3), actuated=False)
    bl.add_loop("closure", "R", parent="coupler", child="rocker", origin=pose(c - b), axis=(0, 0, 1))
    bl.q_box = np.array([[-0.3, 0.3]])
    return bl.build()


def parallelogram(gravity=(0.0, -9.81, 0.0)) -> Robot:
    """The four-bar with a parallelogram's dimensions (nullity 27 of 30 on this branch).

    Parameters
    ----------
    gravity : array_like, shape ``(3,)``
        Gravity [m/s^2] in the world frame.

    Returns
    -------
    Robot
        :func:`four_bar` with ``parallelogram=True``.
    """
    return four_bar(parallelogram=True, gravity=gravity)


def pkm_2rru_1rrs(gravity=(0.0, 0.0, -9.81)) -> Robot:
    """The 2RRU-1RRS PKM (see module doc), generic dimensions.

    Parameters
    ----------
    gravity : array_like, shape ``(3,)``
        Gravity [m/s^2] in the world frame.

    Returns
    -------
    Robot
        7 bodies, 70 parameters, 3 actuated coordinates (``q_box`` +-25 deg).
    """
    z = np.array([0, 0, 1.0])
    limbs = {  # angle, base radius, link-1 length, platform radius
        "a": (0.0, 0.300, 0.300, 0.200),
        "b": (np.pi, 0.315, 0.290, 0.195),
        "c": (np.pi / 2, 0.290, 0.310, 0.205),
    }
    height = 0.45
    alpha = np.pi / 4
    bl = RobotBuilder("pkm-2rru-1rrs", gravity=gravity)
    world = {}
    k = 0
    for name, (th, rb, l1, rp) in limbs.items():
        r = np.array([np.cos(th), np.sin(th), 0.0])
        u = np.cross(z, r)  # tangent
        a_pt = rb * r
        b_pt = a_pt + l1 * (np.cos(alpha) * r + np.sin(alpha) * z)
        c_pt = rp * r + height * z
        fa, fb = _frame(a_pt, u), _frame(b_pt, u)
        bl.add_link(f"link1{name}", joint="R", origin=fa, axis=(0, 0, 1), inertia=_inertia(k, l1),
                    actuated=True)
        bl.add_link(f"link2{name}", parent=f"link1{name}", joint="R", origin=_rel(fa, fb), axis=(0, 0, 1),
                    inertia=_inertia(k + 1, float(np.linalg.norm(c_pt - b_pt))), actuated=False)
        world[name] = (fb, c_pt, u, r)
        k += 2
        if name == "a":  # the platform hangs from limb a by the U joint (tree)
            fc = _frame(c_pt, u)
            # first U axis = u (z of this frame), second = radial, both in the joint frame
            r_local = fc[:3, :3].T @ r
            pf = np.eye(4)
            pf[:3, 3] = [0, 0, height]
            bl.add_link("platform", parent="link2a", joint="U", origin=_rel(fb, fc), axis=(0, 0, 1),
                        axis2=r_local, inertia=Inertia(2.5, com=(0.01, -0.02, 0.03), inertia=(0.02, 0.025, 0.04),
                                                       frame=_rel(fc, pf)), actuated=False)
            world["platform"] = fc
    fpl = world["platform"]
    # loop U at C_b: first axis (predecessor = platform) radial, second (successor = link2b) tangent
    fb_b, c_b, u_b, r_b = world["b"]
    fl = _frame(c_b, r_b)
    u_local = fl[:3, :3].T @ u_b
    bl.add_loop("U_b", "U", parent="platform", child="link2b", origin=_rel(fpl, fl), axis=(0, 0, 1), axis2=u_local)
    fb_c, c_c, _, _ = world["c"]
    bl.add_loop("S_c", "S", parent="platform", child="link2c", origin=_rel(fpl, pose(c_c)))
    bl.q_box = np.tile([-np.deg2rad(25), np.deg2rad(25)], (3, 1))
    return bl.build()


def pkm_2prs_1psr(symmetric: bool = False, gravity=(0.0, 0.0, -9.81)) -> Robot:
    """The 2PRS-1PSR PKM (see module doc).

    Parameters
    ----------
    symmetric : bool
        The mirror-symmetric layout (nullity 48, not 47).
    gravity : array_like, shape ``(3,)``
        Gravity [m/s^2] in the world frame.

    Returns
    -------
    Robot
        7 bodies, 70 parameters, 3 actuated sliders (``q_box`` +-0.05 m).
    """
    z = np.array([0, 0, 1.0])
    if symmetric:
        limbs = {n: (np.deg2rad(th), 0.25, 0.12) for n, th in (("a", 0), ("b", 180), ("c", 90))}
    else:
        limbs = {"a": (np.deg2rad(90), 0.250, 0.120), "b": (np.deg2rad(213), 0.262, 0.114),
                 "c": (np.deg2rad(328), 0.243, 0.127)}
    slider_h, height = 0.10, 0.45
    bl = RobotBuilder("pkm-2prs-1psr" + ("-symmetric" if symmetric else ""), gravity=gravity)
    world = {}
    k = 0
    for name, (th, rb, rp) in limbs.items():
        r = np.array([np.cos(th), np.sin(th), 0.0])
        u = np.cross(z, r)
        b_pt = rb * r + slider_h * z
        c_pt = rp * r + height * z
        fs = _frame(b_pt, z)  # slider frame: translation along z
        bl.add_link(f"slider{name}", joint="P", origin=fs, axis=(0, 0, 1), inertia=_inertia(k, 0.1), actuated=True)
        length = float(np.linalg.norm(c_pt - b_pt))
        if name in ("a", "b"):  # P R (link) S
            fr = _frame(b_pt, u)
            bl.add_link(f"link{name}", parent=f"slider{name}", joint="R", origin=_rel(fs, fr), axis=(0, 0, 1),
                        inertia=_inertia(k + 1, length), actuated=False)
        else:  # P S (link) R
            fr = pose(b_pt)
            bl.add_link(f"link{name}", parent=f"slider{name}", joint="S", origin=_rel(fs, fr),
                        inertia=_inertia(k + 1, length), actuated=False)
        world[name] = (fr, c_pt, u)
        k += 2
        if name == "a":
            fpl = pose(c_pt)
            pc = np.eye(4)
            pc[:3, 3] = [0, 0, height]
            bl.add_link("platform", parent="linka", joint="S", origin=_rel(fr, fpl),
                        inertia=Inertia(2.5, com=(0.01, -0.02, 0.03), inertia=(0.02, 0.025, 0.04),
                                        frame=_rel(fpl, pc)), actuated=False)
            world["platform"] = fpl
    fpl = world["platform"]
    _, c_b, _ = world["b"]
    bl.add_loop("S_b", "S", parent="platform", child="linkb", origin=_rel(fpl, pose(c_b)))
    _, c_c, u_c = world["c"]
    bl.add_loop("R_c", "R", parent="platform", child="linkc", origin=_rel(fpl, _frame(c_c, u_c)), axis=(0, 0, 1))
    bl.q_box = np.tile([-0.05, 0.05], (3, 1))
    return bl.build()
