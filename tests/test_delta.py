"""R-L4 spatial parallelograms: Delta robots built here (issue 39).

Three arms on revolute joints, each carrying a pair of rods (universal joints on the arm, ball joints on
a platform that only translates). Before R-L4, DRNG found 33 of the 66 nullspace directions of the
standard build; the rest was completed numerically.
"""

from __future__ import annotations

import numpy as np
import pytest

from baseparams.model import RobotBuilder
from baseparams.nullspace.certify import certify
from baseparams.nullspace.drng import drng
from baseparams.numerics import stacked_regressor
from baseparams.robots.random import random_inertia


def _frame(origin) -> np.ndarray:
    t = np.eye(4)
    t[:3, 3] = origin
    return t


def delta(rng, rb=0.2, la=0.3, rp=0.06, h=0.05, z0=0.6, gravity=(0, 0, -9.81), tilt=0.0, skew=0.0,
          angles=(0.0, 0.0, 0.0)):
    """A Delta robot: arm ``i`` on a revolute joint at ``rb`` from the centre (tangential axis, at ``angles[i]``
    from horizontal), rods from universal joints ``+-h`` along the arm's axis at its tip to ball joints
    ``+-h`` on a platform of radius ``rp`` at depth ``z0`` (assembled there); ``skew`` moves one ball joint
    of arm 0's pair along the platform's radius (the rods no longer parallel: no parallelogram)."""
    b = RobotBuilder("delta", gravity=gravity)
    arms = []
    for i in range(3):
        phi = 2 * np.pi * i / 3 + tilt
        er, u = np.array([np.cos(phi), np.sin(phi), 0.0]), np.array([-np.sin(phi), np.cos(phi), 0.0])
        tip = rb * er + la * (np.cos(angles[i]) * er - np.sin(angles[i]) * np.array([0, 0, 1.0]))
        arms.append((er, u, tip))
    # the platform's depth so that every rod has one length L: the arms' tips may differ in height
    p = np.array([0.0, 0.0, -z0])
    rods = []
    for i, (er, u, tip) in enumerate(arms):
        b.add_link(f"arm{i}", joint="R", origin=_frame(rb * er), axis=u, inertia=random_inertia(rng), actuated=True)
        for s, side in ((-1, "a"), (1, "b")):
            ui = tip + s * h * u
            si = p + rp * er + s * h * u + (skew * er if (i, side) == (0, "b") else 0.0)
            b.add_link(f"rod{i}{side}", parent=f"arm{i}", joint="U", origin=_frame(ui - rb * er), axis=u,
                       axis2=np.cross(si - ui, u), inertia=random_inertia(rng), actuated=False)
            rods.append((f"rod{i}{side}", ui, si))
    name0, u0, s0 = rods[0]
    b.add_link("platform", parent=name0, joint="S", origin=_frame(s0 - u0), inertia=random_inertia(rng),
               actuated=False)
    for name, ui, si in rods[1:]:
        b.add_loop(f"ball_{name}", "S", parent=name, child="platform", origin=_frame(si - ui),
                   child_origin=_frame(si - s0))
    return b.build()


CASES = [dict(), dict(gravity=(0, 0, 0)), dict(gravity=(3.0, -2.0, -9.0)), dict(tilt=0.4, rp=0.1),
         dict(la=0.4, h=0.08, z0=0.5), dict(angles=(0.3, 0.3, 0.3)), dict(angles=(0.2, -0.1, 0.35))]


@pytest.mark.parametrize("k", range(len(CASES)))
def test_delta_robots_are_complete_and_certified(k):
    """Random inertias, gravity along the platform's normal, oblique or zero, other proportions, arms not
    horizontal at the reference: DRNG complete, certified; every R-L4 column in the numerical nullspace."""
    from baseparams.enums import Source

    robot = delta(np.random.default_rng(k), **CASES[k])
    res = drng(robot)
    c = certify(robot, result=res, seed=k)
    assert c.status == "certified" and c.completed == 0, c.message
    b = res.dense()[:, res.columns.principle == Source.R_L4]
    assert b.shape[1] == 9 + 3 * 10
    w = stacked_regressor(robot, 300, k)
    assert np.abs(w @ (b / np.linalg.norm(b, axis=0))).max() < 1e-10 * np.linalg.norm(w, 2)


def test_rl4_is_needed(monkeypatch):
    from baseparams.nullspace import rules

    robot = delta(np.random.default_rng(0))
    monkeypatch.setattr(rules, "spatial_parallelogram_columns", lambda *a, **k: rules.Columns.empty())
    c = certify(robot, seed=0)
    assert c.status == "completed" and c.nullity == 66 and c.completed == 33


def test_rods_that_are_not_parallel_make_no_pair():
    """One ball joint moved along the platform: arm 0's rods are no longer a parallelogram; the rule keeps
    the two other pairs but not the platform's translation (the platform turns), and nothing is wrong."""
    from baseparams.nullspace.spatial import _translates, spatial_pairs

    robot = delta(np.random.default_rng(1), skew=0.03)
    pairs = spatial_pairs(robot)
    plat = robot.names.index("platform")
    assert len(pairs[plat]) == 2 and not _translates(robot, plat, 1e-9)
    c = certify(robot, seed=1)
    assert c.certified  # completed or certified, never a column outside the nullspace
