"""Seeded random robots for property tests: ``random_robot(rng, ...)``."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model import Inertia, Robot, RobotBuilder


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """Uniform random rotation ``(3, 3)``.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source (the result is deterministic given its state).

    Returns
    -------
    ndarray, shape ``(3, 3)``
        A rotation matrix (from a normalised Gaussian quaternion).
    """
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def random_pose(rng: np.random.Generator, scale: float = 0.5) -> np.ndarray:
    """Random rigid pose: a uniform rotation and a Gaussian translation.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source (the result is deterministic given its state).
    scale : float
        Standard deviation [m] of each translation component.

    Returns
    -------
    ndarray, shape ``(4, 4)``
        The homogeneous transform.
    """
    t = np.eye(4)
    t[:3, :3] = random_rotation(rng)
    t[:3, 3] = rng.normal(scale=scale, size=3)
    return t


def random_inertia(rng: np.random.Generator) -> Inertia:
    """A physically consistent random inertia (positive-definite pseudo-inertia).

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source (the result is deterministic given its state).

    Returns
    -------
    Inertia
        Mass in [0.5, 5] kg, a Gaussian centre of mass (0.2 m), principal moments satisfying
        the triangle inequality about randomly rotated axes.
    """
    mass = rng.uniform(0.5, 5.0)
    com = rng.normal(scale=0.2, size=3)
    r = random_rotation(rng)
    # principal moments satisfying the triangle inequality
    s = rng.uniform(0.01, 0.2, size=3) * mass * 0.1  # second moments along principal axes
    principal = np.array([s[1] + s[2], s[0] + s[2], s[0] + s[1]])
    return Inertia(mass, com=tuple(com), inertia=r @ np.diag(principal) @ r.T)


def random_robot(rng: np.random.Generator, n: int = 6, joint_types: str = "RPUS",
                 floating: bool = False, branching: float = 0.3,
                 gravity=(0.0, 0.0, -9.81), name: str | None = None) -> Robot:
    """A random tree of ``n`` bodies with joints drawn from ``joint_types``.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source (the result is deterministic given its state).
    n : int
        Number of bodies.
    joint_types : str
        The joint types to draw from, one letter each (``R P U S C``). ``C``: a compound joint
        of 2 to 4 elementary screws (hinges through random points, slides; sometimes two
        hinges through one point, or parallel slides), as MJCF bodies with several joints.
    floating : bool
        The first body is a floating (F) root.
    branching : float
        Probability that a body hangs from a random earlier body rather than the previous one.
    gravity : array_like, shape ``(3,)``
        Gravity [m/s^2] in the world frame.
    name : str, optional
        The robot's name (default ``random<n>``).

    Returns
    -------
    Robot
        Bodies ``b0`` ... ``b<n-1>`` with random poses, axes and inertias.
    """
    b = RobotBuilder(name or f"random{n}", gravity=gravity)
    for i in range(n):
        if i == 0:
            parent = None
        elif rng.random() < branching:
            parent = f"b{rng.integers(0, i)}"
        else:
            parent = f"b{i - 1}"
        jt = "F" if (floating and i == 0) else str(rng.choice(list(joint_types)))
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        perp = np.cross(axis, rng.normal(size=3))
        if jt == "C":
            axis = random_compound(rng)
        b.add_link(f"b{i}", parent=parent, joint=jt, origin=random_pose(rng), axis=axis,
                   axis2=perp / np.linalg.norm(perp), inertia=random_inertia(rng))
    return b.build()


def random_compound(rng: np.random.Generator, k: int | None = None) -> np.ndarray:
    """Twists of a random compound (C) joint in its frame.

    Hinges (through the origin, a shared point or a random point) and slides, sometimes
    parallel or repeated.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source (the result is deterministic given its state).
    k : int, optional
        Number of elementary screws (default: drawn from 2 to 4).

    Returns
    -------
    ndarray, shape ``(k, 6)``
        Unit twists ``(omega, v)`` (:func:`~baseparams.model.robot.compound_screw`).
    """
    from ..model.robot import compound_screw

    k = int(rng.integers(2, 5)) if k is None else k
    point = rng.normal(scale=0.2, size=3) if rng.random() < 0.5 else np.zeros(3)
    rows = []
    for _ in range(k):
        kind = rng.choice(["hinge", "hinge_shared", "slide", "world"])
        a = rng.normal(size=3)
        if kind == "world":
            a = np.eye(3)[rng.integers(0, 3)]
        if kind == "slide" or (kind == "world" and rng.random() < 0.5):
            rows.append(compound_screw(a, slide=True))
        else:
            pt = point if kind != "hinge" else rng.normal(scale=0.2, size=3)
            rows.append(compound_screw(a, point=pt))
    return np.array(rows)


# --- special geometry on purpose ------------------------------------------------------------

#: the 24 proper rotations with entries in {0, +1, -1} (exact signed permutations)
_SIGNED_PERMS = tuple(
    m for m in (np.array([[s[r] if c == p[r] else 0.0 for c in range(3)] for r in range(3)])
                for p in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0))
                for s in ((1, 1, 1), (1, 1, -1), (1, -1, 1), (1, -1, -1),
                          (-1, 1, 1), (-1, 1, -1), (-1, -1, 1), (-1, -1, -1)))
    if np.linalg.det(m) > 0)

_JOINTS = ("R", "P", "U", "S")
_JOINT_W = (0.55, 0.25, 0.1, 0.1)
_AXIS_MODES = ("parallel", "perpendicular", "coaxial", "intersecting", "world", "gravity", "generic")
_AXIS_W = (0.18, 0.15, 0.12, 0.12, 0.18, 0.08, 0.17)
_ORIGIN_MODES = ("zero", "along", "world", "random")
_ORIGIN_W = (0.25, 0.25, 0.2, 0.3)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def _random_unit(rng: np.random.Generator) -> np.ndarray:
    return _unit(rng.normal(size=3))


def _world_axis(rng: np.random.Generator, z_bias: float = 1 / 3) -> np.ndarray:
    """``+-e_x``, ``+-e_y`` or ``+-e_z`` exactly (``e_z`` with probability ``z_bias``)."""
    k = 2 if rng.random() < z_bias else int(rng.integers(0, 2))
    e = np.zeros(3)
    e[k] = 1.0 if rng.random() < 0.5 else -1.0
    return e


def _perpendicular(a: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A unit direction perpendicular to unit ``a``: another world axis (exact) when ``a`` is one."""
    nz = np.flatnonzero(a != 0.0)
    if len(nz) == 1:
        k = int(rng.choice([j for j in range(3) if j != nz[0]]))
        e = np.zeros(3)
        e[k] = 1.0 if rng.random() < 0.5 else -1.0
        return e
    for _ in range(10):
        c = np.cross(a, rng.normal(size=3))
        if np.linalg.norm(c) > 1e-3:
            return _unit(c)
    return _unit(np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0]))


@dataclass
class _Draw:
    """What :func:`_special` has drawn so far, body after body."""

    base_lines: list[tuple[np.ndarray, np.ndarray]]  # candidate "parent axis" lines of the base
    frames: list[np.ndarray] = field(default_factory=list)  # world pose of each body at q = 0
    lines: list[list[tuple[np.ndarray, np.ndarray]]] = field(default_factory=list)  # axis lines per body
    notes: list[str] = field(default_factory=list)
    plan: list[tuple[str, str | None, str | None]] = field(default_factory=list)  # forced, chained joints
    kind: str = ""  # what the current plan is


def _special(rng: np.random.Generator, n: int | None = None,
             gravity: str | None = None) -> tuple[Robot, list[str]]:
    """:func:`special_robot` plus one note per body (joint type, parent, the relations drawn).

    The draws happen in a fixed order (the robots are reproducible from the seed): gravity,
    then per body its parent and joint, the parent's line, the joint point, axis, frame.
    """
    n = int(rng.integers(2, 8)) if n is None else int(n)
    gcase, g, g_dir = _special_gravity(rng, gravity)
    z_bias = 0.7 if gcase == "axis" else 1 / 3
    b = RobotBuilder(f"special{n}-{gcase}", gravity=tuple(g))
    st = _Draw(base_lines=[(np.array([0.0, 0.0, 1.0]), np.zeros(3))])
    if gcase == "generic":
        st.base_lines.append((g_dir, np.zeros(3)))
    for i in range(n):
        _special_body(rng, b, st, i, n, g_dir, z_bias)
    return b.build(), st.notes


def _special_gravity(rng: np.random.Generator, gravity: str | None) -> tuple[str, np.ndarray, np.ndarray]:
    """``(case, gravity, its direction)`` (``+z`` for zero gravity), ``case`` drawn when None."""
    gcase = str(rng.choice(["axis", "generic", "zero"])) if gravity is None else gravity
    if gcase == "axis":
        g = np.array([0.0, 0.0, -9.81])
    elif gcase == "generic":
        g = _random_unit(rng) * 9.81
    elif gcase == "zero":
        g = np.zeros(3)
    else:
        raise ValueError(f"gravity must be 'axis', 'generic', 'zero' or None, got {gravity!r}")
    g_dir = _unit(g) if gcase != "zero" else np.array([0.0, 0.0, 1.0])
    return gcase, g, g_dir


def _special_body(rng: np.random.Generator, b: RobotBuilder, st: _Draw, i: int, n: int,
                  g_dir: np.ndarray, z_bias: float) -> None:
    """Draw body ``i`` (its parent, joint, point, axes and frame), add it to ``b``, note it."""
    floating, chained, parent, jt, amode, omode = _special_joint(rng, st, i, n)
    pframe = np.eye(4) if parent < 0 else st.frames[parent]
    plines = st.base_lines if parent < 0 else st.lines[parent]
    a_p, o_p = plines[int(rng.integers(0, len(plines)))]
    p_p = pframe[:3, 3]
    offset, omode = _special_offset(rng, floating, amode, omode, a_p, o_p, p_p, z_bias)
    a_w = None
    if not floating and jt != "S":
        a_w = _special_axis(rng, amode, a_p, o_p, p_p + offset, g_dir, z_bias)
    rot = _special_rotation(rng, floating)
    rp = pframe[:3, :3]
    origin = np.eye(4)
    origin[:3, :3] = rp.T @ rot
    origin[:3, 3] = rp.T @ offset
    frame = pframe @ origin  # exactly as RobotBuilder.add_link composes M0
    axis, axis2, mylines = _special_axes_in_frame(rng, jt, amode, a_w, a_p, frame)
    b.add_link(f"b{i}", parent=None if parent < 0 else f"b{parent}", joint=jt, origin=origin,
               axis=axis, axis2=axis2, inertia=random_inertia(rng))
    st.frames.append(frame)
    st.lines.append(mylines)
    rel = "" if floating or jt == "S" else f" axis={amode}"
    st.notes.append(f"{jt}<-{'w' if parent < 0 else parent}{rel} origin={omode or 'pose'}"
                    + (f" [{st.kind}]" if chained else ""))


def _special_joint(rng: np.random.Generator, st: _Draw, i: int, n: int):
    """``(floating, chained, parent, joint type, axis mode, origin mode)`` of body ``i``.

    The next joint of the current plan, maybe a new plan, or a free draw.
    """
    floating = i == 0 and rng.random() < 0.1
    chained = bool(st.plan)
    if i == 0:
        parent = -1
    elif chained or rng.random() >= 0.3:
        parent = i - 1
    else:
        parent = int(rng.integers(0, i))
    if floating:
        return floating, chained, parent, "F", None, None
    if not st.plan and rng.random() < 0.22:
        _special_plan(rng, st, n - i)
    if st.plan:
        jt, amode, omode = st.plan.pop(0)
        chained = True
    else:
        jt, amode, omode = str(rng.choice(_JOINTS, p=_JOINT_W)), None, None
    amode = amode or str(rng.choice(_AXIS_MODES, p=_AXIS_W))
    omode = omode or str(rng.choice(_ORIGIN_MODES, p=_ORIGIN_W))
    return floating, chained, parent, jt, amode, omode


def _special_plan(rng: np.random.Generator, st: _Draw, left: int) -> None:
    """Draw a plan of chained joints (with ``left`` bodies to go).

    A translation stage, a lift then a coaxial R, or an R then a coaxial P; none when fewer
    than two bodies are left.
    """
    u = rng.random()
    if u < 0.45 and left >= 2:  # translation stage: 2 or 3 perpendicular (or parallel) P
        k = int(min(left, rng.integers(2, 4)))
        modes = ["world" if rng.random() < 0.6 else "generic"]
        modes += ["perpendicular" if rng.random() < 0.8 else "parallel" for _ in range(k - 1)]
        st.plan = [("P", m, str(rng.choice(["zero", "world", "along"]))) for m in modes]
        if left > k and rng.random() < 0.4:  # ... then a rotation about the last slide line
            st.plan.append(("R", "coaxial", "along"))
        st.kind = "stage"
    elif u < 0.8 and left >= 2:  # lift then rotation about the same line
        first = "world" if rng.random() < 0.5 else str(rng.choice(_AXIS_MODES, p=_AXIS_W))
        st.plan = [("P", first, None), ("R", "coaxial", str(rng.choice(["zero", "along"])))]
        st.kind = "lift+R"
    elif left >= 2:  # rotation then coaxial slide (cylindrical pair)
        st.plan = [("R", None, None), ("P", "coaxial", "zero")]
        st.kind = "R+P"


def _special_offset(rng: np.random.Generator, floating: bool, amode, omode, a_p: np.ndarray, o_p: np.ndarray,
                    p_p: np.ndarray, z_bias: float) -> tuple[np.ndarray, str | None]:
    """The joint point as an offset (in world) from the parent's frame origin ``p_p``.

    Also the origin mode (``on-line`` for a coaxial joint).
    """
    if floating:
        offset = rng.normal(scale=0.5, size=3) if rng.random() < 0.5 else np.zeros(3)
    elif amode == "coaxial":
        # on the parent's axis line: from the line's point along the axis
        offset = (o_p - p_p) + (0.0 if omode == "zero" else rng.uniform(-0.6, 0.6)) * a_p
        omode = "on-line"
    elif omode == "zero":
        offset = np.zeros(3)
    elif omode == "along":
        offset = (o_p - p_p) + rng.uniform(-0.6, 0.6) * a_p
    elif omode == "world":
        offset = rng.uniform(-0.6, 0.6) * _world_axis(rng, z_bias)
    else:
        offset = rng.normal(scale=0.4, size=3)
    return offset, omode


def _special_axis(rng: np.random.Generator, amode: str, a_p: np.ndarray, o_p: np.ndarray, point: np.ndarray,
                  g_dir: np.ndarray, z_bias: float) -> np.ndarray:
    """The joint axis in world, related to the parent's line ``(a_p, o_p)`` as ``amode`` says."""
    if amode in ("parallel", "coaxial"):
        return a_p if rng.random() < 0.7 else -a_p
    if amode == "perpendicular":
        return _perpendicular(a_p, rng)
    if amode == "intersecting":
        on_line = o_p + rng.uniform(-0.6, 0.6) * a_p  # a point of the parent's axis line
        d = on_line - point
        if np.linalg.norm(d) > 1e-3 and np.linalg.norm(np.cross(d, a_p)) > 1e-3 * np.linalg.norm(d):
            return _unit(d)
        # the joint point is on the line already: any non-parallel direction
        return _perpendicular(a_p, rng) if rng.random() < 0.5 else _random_unit(rng)
    if amode == "world":
        return _world_axis(rng, z_bias)
    if amode == "gravity":
        return g_dir if rng.random() < 0.7 else -g_dir
    return _random_unit(rng)


def _special_rotation(rng: np.random.Generator, floating: bool) -> np.ndarray:
    """The joint frame's rotation in world: identity, a signed permutation or random."""
    u = rng.random()
    if floating:
        return random_rotation(rng) if u < 0.5 else _SIGNED_PERMS[int(rng.integers(0, 24))]
    if u < 0.35:
        return np.eye(3)
    if u < 0.7:
        return _SIGNED_PERMS[int(rng.integers(0, 24))]
    return random_rotation(rng)


def _special_axes_in_frame(rng: np.random.Generator, jt: str, amode, a_w: np.ndarray | None, a_p: np.ndarray,
                           frame: np.ndarray):
    """``(axis, axis2, lines)``: the joint axes in the joint ``frame`` and the body's lines.

    U: a second axis perpendicular to the first, often to the parent's line too. The body's
    axis lines are in world (S / F: the frame's axes).
    """
    r_i = frame[:3, :3]
    axis, axis2, mylines = (0.0, 0.0, 1.0), None, []
    if a_w is None:  # S / F: the frame's axes
        mylines += [(r_i[:, k].copy(), frame[:3, 3]) for k in range(3)]
        return axis, axis2, mylines
    axis = r_i.T @ a_w
    mylines.append((a_w, frame[:3, 3]))
    if jt == "U":
        if amode == "perpendicular" or (rng.random() < 0.5 and np.linalg.norm(np.cross(a_w, a_p)) > 1e-3):
            a2 = _unit(np.cross(a_w, a_p)) if np.linalg.norm(np.cross(a_w, a_p)) > 1e-3 \
                else _perpendicular(a_w, rng)
        else:
            a2 = _perpendicular(a_w, rng)
        a2 = a2 - (a2 @ a_w) * a_w
        a2 = _unit(a2)
        axis2 = r_i.T @ a2
        mylines.append((a2, frame[:3, 3]))
    return axis, axis2, mylines


def special_robot(rng: np.random.Generator, n: int | None = None, gravity: str | None = None) -> Robot:
    """A random tree of ``n`` bodies with special geometry drawn on purpose.

    Joints are mostly R and P (weights R 0.55, P 0.25, U 0.1, S 0.1; a floating root with
    probability 0.1); a body hangs from the previous one or (probability 0.3) an earlier one.
    Each joint axis, in world at q = 0, is parallel, perpendicular, coaxial with or
    intersecting one of its parent's axes, along a world axis, along gravity, or generic; the
    joint point coincides with the parent's, lies on its axis line, is offset along a world
    axis, or is generic. Translation stages (2-3 chained P), a lift followed by a coaxial R,
    and an R followed by a coaxial P are drawn as such. Exact values (signed permutation
    frames, ``+-1`` axes) make the relations hold to rounding. Deterministic given ``rng``.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source (the result is deterministic given its state).
    n : int, optional
        Number of bodies (default: drawn from 2..7).
    gravity : {"axis", "generic", "zero"}, optional
        The gravity case: ``"axis"`` (``-9.81 z``, axes biased to ``z``), ``"generic"`` (a
        random direction), ``"zero"``; ``None`` draws one uniformly.

    Returns
    -------
    Robot
        Named ``special<n>-<gravity case>``, bodies ``b0`` ... ``b<n-1>``.

    Raises
    ------
    ValueError
        An unknown ``gravity``.
    """
    return _special(rng, n, gravity)[0]
