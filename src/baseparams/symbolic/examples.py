"""Closed chains with symbolic dimensions, built with :class:`~.geometry.SymbolicBuilder`.

Both close at q = 0 for every value of their symbols (the loop frames are placed where the tree
puts them), as the numeric built-ins :func:`baseparams.robots.loops.parallelogram` and
:func:`baseparams.robots.loops.pkm_2rru_1rrs`, whose default numbers they carry.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .geometry import SymbolicBuilder, SymbolicRobot, inverse, transform


def _syms(names: str) -> list:
    return [sp.Symbol(n, real=True) for n in names.split()]


def parallelogram() -> SymbolicRobot:
    """Planar parallelogram four-bar: crank at A = 0, rocker at D = (L, 0), B = (BX, BY), C = B + D.

    Returns
    -------
    SymbolicRobot
        Crank (actuated), coupler, rocker; loop R at C between coupler and rocker; R axes
        along z, gravity along -y. Symbols ``BX BY L``.
    """
    bx, by, ell = _syms("BX BY L")
    b = SymbolicBuilder("parallelogram-symbolic", gravity=(0, -9.81, 0), values={"BX": 0.3, "BY": 0.5, "L": 1.0},
                        description="planar parallelogram four-bar, symbols BX BY (crank) L (ground link)")
    b.add_link("crank", joint="R", actuated=True)
    b.add_link("coupler", parent="crank", joint="R", origin=transform(translation=(bx, by, 0)), actuated=False)
    b.add_link("rocker", joint="R", origin=transform(translation=(ell, 0, 0)), actuated=False)
    b.add_loop("closure", "R", "coupler", "rocker", origin=transform(translation=(ell, 0, 0)))
    b.q_box = np.array([[-0.3, 0.3]])
    return b.build()


def _frame(origin, z) -> sp.Matrix:
    """A pose at ``origin`` whose z axis is the exact unit ``z`` (x as the numeric ``_frame`` picks)."""
    z = sp.Matrix(z)
    h = sp.Matrix([1, 0, 0]) if abs(z[0]) < sp.Rational(9, 10) else sp.Matrix([0, 1, 0])
    x = h.cross(z)
    return transform(sp.Matrix.hstack(x, z.cross(x), z), origin)


def pkm_2rru_1rrs() -> SymbolicRobot:
    """The 2RRU-1RRS PKM of :func:`baseparams.robots.loops.pkm_2rru_1rrs` with symbolic dimensions.

    Per limb ``k`` in ``a b c`` (base angles 0, pi, pi/2): base radius ``RBk``, link-1 length
    ``L1k``, platform radius ``RPk``; platform height ``H``. Link 1 is at elevation
    ``atan(4/3)`` at q = 0 (exact cosine 3/5).

    Returns
    -------
    SymbolicRobot
        7 bodies, loops U (platform, link2b) and S (platform, link2c), 3 actuated joints.
    """
    z = sp.Matrix([0, 0, 1])
    h = sp.Symbol("H", real=True)
    dirs = {"a": (1, 0, 0), "b": (-1, 0, 0), "c": (0, 1, 0)}
    values = {"H": 0.45}
    defaults = {"a": (0.300, 0.300, 0.200), "b": (0.315, 0.290, 0.195), "c": (0.290, 0.310, 0.205)}
    bl = SymbolicBuilder("pkm-2rru-1rrs-symbolic", gravity=(0, 0, -9.81), values=values,
                         description="2RRU-1RRS PKM, symbols RBk L1k RPk (limbs k = a b c) and H")
    world = {}
    for name, d in dirs.items():
        rb, l1, rp = _syms(f"RB{name} L1{name} RP{name}")
        bl.values.update(dict(zip((f"RB{name}", f"L1{name}", f"RP{name}"), defaults[name])))
        r = sp.Matrix(d)
        u = z.cross(r)
        a_pt = rb * r
        b_pt = a_pt + l1 * (sp.Rational(3, 5) * r + sp.Rational(4, 5) * z)
        c_pt = rp * r + h * z
        fa, fb = _frame(a_pt, u), _frame(b_pt, u)
        bl.add_link(f"link1{name}", joint="R", origin=fa, actuated=True)
        bl.add_link(f"link2{name}", parent=f"link1{name}", joint="R", origin=inverse(fa) * fb, actuated=False)
        world[name] = (fb, c_pt, u, r)
        if name == "a":
            fc = _frame(c_pt, u)
            bl.add_link("platform", parent="link2a", joint="U", origin=inverse(fb) * fc, axis=(0, 0, 1),
                        axis2=list(fc[:3, :3].T * r), actuated=False)
    _, c_b, u_b, r_b = world["b"]
    fl = _frame(c_b, r_b)
    bl.add_loop("U_b", "U", "platform", "link2b", origin=fl, axis=(0, 0, 1), axis2=list(fl[:3, :3].T * u_b),
                in_world=True)
    bl.add_loop("S_c", "S", "platform", "link2c", origin=transform(translation=world["c"][1]), in_world=True)
    bl.q_box = np.tile([-np.deg2rad(25), np.deg2rad(25)], (3, 1))
    return bl.build()


#: name -> (factory, one-line description)
EXAMPLES = {
    "parallelogram-symbolic": (parallelogram, "planar parallelogram four-bar, symbols BX BY L"),
    "pkm-2rru-1rrs-symbolic": (pkm_2rru_1rrs, "2RRU-1RRS PKM, symbols RBk L1k RPk (limbs a b c) and H"),
}
