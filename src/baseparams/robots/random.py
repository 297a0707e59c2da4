"""Seeded random robots for property tests: ``random_robot(rng, ...)``."""

from __future__ import annotations

import numpy as np

from ..model import Inertia, Robot, RobotBuilder


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """Uniform random rotation ``(3, 3)``."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def random_pose(rng: np.random.Generator, scale: float = 0.5) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = random_rotation(rng)
    t[:3, 3] = rng.normal(scale=scale, size=3)
    return t


def random_inertia(rng: np.random.Generator) -> Inertia:
    """A physically consistent random inertia (positive-definite pseudo-inertia)."""
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

    ``floating``: the first body is a floating (F) root. ``branching``: probability that a
    body hangs from a random earlier body rather than the previous one.
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
        b.add_link(f"b{i}", parent=parent, joint=jt, origin=random_pose(rng), axis=axis,
                   axis2=perp / np.linalg.norm(perp), inertia=random_inertia(rng))
    return b.build()
