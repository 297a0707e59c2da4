"""Loops sampled over their whole motion (issue 46): :mod:`baseparams.kinematics.manifold`.

Random planar closed chains (a four-bar crank-rocker: one degree of freedom; a five-bar: two),
assembled at a random reference. Properties: every traced configuration closes the loop and is on
the reference's assembly mode (the distal dyad's elbow keeps its side: the other circuit of a
Grashof linkage has the other side), a crank-rocker's crank turns fully (the whole motion), and the
count is the same at any anchor (the robot re-referenced at another traced configuration), decided
at a gap. Oracle: the same chain's closure solved in closed form (circle intersection on the
reference's elbow side), its tangent from the analytic closure Jacobian, and our separate
Newton-Euler (``tests/oracles.py``) at zero velocity with accelerations along the tangent (the
reduced mass matrix and gravity torques determine the whole dynamics, so these states see every
identifiable direction).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import baseparams as bp
from baseparams.kinematics.loops import evaluate
from baseparams.kinematics.manifold import loop_groups, sample_trace, trace_group, traced_groups
from baseparams.kinematics.tree import re_reference
from baseparams.model.builder import RobotBuilder, pose
from baseparams.model.inertia import Inertia

from oracles import rnea


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def _inertia(rng) -> Inertia:
    a = rng.normal(size=(3, 3))
    return Inertia(rng.uniform(0.5, 2), com=rng.uniform(-0.1, 0.1, 3), inertia=a @ a.T * 0.01 + np.eye(3) * 0.01)


def _tip(lengths, angles) -> np.ndarray:
    phi = np.cumsum(angles)
    return np.array([np.sum(lengths * np.cos(phi)), np.sum(lengths * np.sin(phi))])


def _chain(lengths, q0, rng) -> tuple:
    """A planar serial chain from the origin (R joints about z, joint i at link i-1's tip, reference angles
    ``q0``) whose last tip is pinned to the ground where it is at the reference: ``(robot, ground pivot)``."""
    d = _tip(lengths, q0)
    b = RobotBuilder("chain", gravity=(0.0, -9.81, 0.0))
    parent = None
    for i, a in enumerate(q0):
        t = np.eye(4)
        t[:3, :3] = _rz(a)
        if i:
            t[:3, 3] = (lengths[i - 1], 0, 0)
        b.add_link(f"l{i}", parent=parent, joint="R", origin=t, axis=(0, 0, 1), inertia=_inertia(rng),
                   actuated=i == 0 or (len(lengths) > 3 and i == 1))
        parent = f"l{i}"
    b.add_loop("pin", "R", parent=None, child=parent, origin=pose((d[0], d[1], 0.0)),
               child_origin=pose((lengths[-1], 0.0, 0.0)), axis=(0, 0, 1))
    return b.build(), d


def _elbow(lengths, angles, d) -> float:
    """The side of the distal dyad's elbow: sign of (D - B) x (C - B), B and C its two joints."""
    phi = np.cumsum(angles)
    pts = np.cumsum(np.c_[lengths * np.cos(phi), lengths * np.sin(phi)], axis=0)
    b, c = (np.zeros(2) if len(lengths) < 3 else pts[-3]), pts[-2]
    u, v = d - b, c - b
    return float(np.sign(u[0] * v[1] - u[1] * v[0]))


def _closed_form(lengths, q0, d, first: np.ndarray, side: float) -> np.ndarray | None:
    """The chain's relative angles (our q: from ``q0``) with the proximal joints' world angles ``first``, the
    dyad solved by circle intersection on ``side``; None where it does not reach."""
    phi = np.cumsum(first)
    k = len(first)
    b = np.array([np.sum(lengths[:k] * np.cos(phi)), np.sum(lengths[:k] * np.sin(phi))])
    l1, l2 = lengths[k], lengths[k + 1]
    e = np.linalg.norm(d - b)
    if not abs(l1 - l2) < e < l1 + l2:
        return None
    u = (d - b) / e
    along = (e * e + l1 * l1 - l2 * l2) / (2 * e)
    h = np.sqrt(max(l1 * l1 - along * along, 0.0))
    c = b + along * u + side * h * np.array([-u[1], u[0]])
    world = np.r_[phi, np.arctan2(*(c - b)[::-1]), np.arctan2(*(d - c)[::-1])]
    rel = np.diff(np.r_[0.0, world])
    return (rel - q0 + np.pi) % (2 * np.pi) - np.pi


def _oracle_rank(robot, lengths, q0, d, rng, samples: int = 80) -> tuple[int, float]:
    """``(rank, gap)`` of the closed chain's regressor from the closed form and our separate Newton-Euler."""
    side = _elbow(lengths, q0, d)
    k = len(lengths) - 2
    rows = []
    eye = np.eye(10 * robot.n)
    probes = [robot.with_parameters(eye[j], "paper") for j in range(10 * robot.n)]
    while len(rows) < samples * k:
        first = np.cumsum(q0[:k]) + rng.uniform(-np.pi, np.pi, k) * (1.0 if k == 1 else 0.8)
        first = np.diff(np.r_[0.0, first])
        q = _closed_form(lengths, q0, d, first, side)
        if q is None:
            continue
        phi = np.cumsum(q0 + q)
        jac = np.array([[np.sum(lengths[j:] * -np.sin(phi[j:])) for j in range(len(q))],
                        [np.sum(lengths[j:] * np.cos(phi[j:])) for j in range(len(q))]])
        tangent = np.linalg.svd(jac)[2][2:].T  # (dof, k)
        if np.linalg.svd(jac, compute_uv=False)[-1] < 1e-3:
            continue  # near the dyad's straight (singular) configuration
        ddq = tangent @ rng.normal(size=k)
        tau = np.array([rnea(p, q, np.zeros_like(q), ddq) for p in probes]).T  # (dof, 10 n)
        rows.extend(tangent.T @ tau)
    s = np.linalg.svd(np.array(rows), compute_uv=False)
    rank = int(np.sum(s > 1e-9 * s[0]))
    return rank, float(s[rank - 1] / s[rank]) if rank < len(s) else np.inf


def _four_bar(seed: int):
    """A random Grashof crank-rocker (the crank shortest, s + l < p + q) at a random reference."""
    rng = np.random.default_rng(seed)
    while True:
        lengths = np.r_[rng.uniform(0.1, 0.25), rng.uniform(0.5, 1.0, 2)]
        q0 = np.r_[rng.uniform(-np.pi, np.pi), rng.uniform(0.6, 2.5) * rng.choice([-1, 1]), rng.uniform(0.6, 2.5)]
        ground = np.linalg.norm(_tip(lengths, q0))
        links = np.sort(np.r_[lengths, ground])
        if links[0] == lengths[0] and links[0] + links[3] < links[1] + links[2] - 0.05:
            robot, d = _chain(lengths, q0, rng)
            return robot, lengths, q0, d, rng


def _five_bar(seed: int):
    rng = np.random.default_rng(seed)
    lengths = np.r_[rng.uniform(0.3, 0.6, 2), rng.uniform(0.5, 0.9, 2)]
    q0 = np.r_[rng.uniform(-np.pi, np.pi), rng.uniform(0.4, 1.2), rng.uniform(0.8, 2.2), rng.uniform(0.8, 2.2)]
    robot, d = _chain(lengths, q0, rng)
    return robot, lengths, q0, d, rng


def _traced(robot, seed=0):
    (group,) = traced_groups(robot)
    tr = trace_group(robot, group, np.random.default_rng(seed))
    return group, tr, sample_trace(robot, tr, 400, np.random.default_rng(seed + 1))


@pytest.mark.parametrize("seed", range(6))
def test_a_crank_rocker_is_traced_over_its_whole_turn_on_one_assembly_mode(seed):
    robot, lengths, q0, d, _ = _four_bar(seed)
    (group,) = loop_groups(robot)
    assert group.dim == 1 and group.elementary and list(group.coords) == [0, 1, 2]
    _, tr, q = _traced(robot, seed)
    assert tr.extent[0] > 2 * np.pi - 0.2  # the crank turns fully: the whole motion
    assert np.abs(evaluate(robot, q).r).max() < 1e-9  # on the loop
    side = _elbow(lengths, q0, d)
    assert {_elbow(lengths, q0 + row, d) for row in q} == {side}  # never on the other circuit
    # the closed form on that side agrees with every traced configuration
    for row in q[:50]:
        exact = _closed_form(lengths, q0, d, q0[:1] + row[:1], side)
        assert np.abs((exact - row + np.pi) % (2 * np.pi) - np.pi).max() < 1e-8


@pytest.mark.slow
@pytest.mark.parametrize("make, seed", [(_four_bar, 0), (_four_bar, 1), (_five_bar, 2), (_five_bar, 3)])
def test_the_traced_count_is_the_oracles_at_every_anchor_and_decided_at_a_gap(make, seed):
    robot, lengths, q0, d, rng = make(seed)
    rank, gap = _oracle_rank(robot, lengths, q0, d, rng)
    assert gap > 1e6
    _, _, q = _traced(robot, seed)
    anchors = [robot] + [re_reference(robot, q[i]) for i in (7, 211)]
    for r in anchors:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = bp.analyze(r, samples=1500)
        assert a.status in ("certified", "completed") and a.n_base == rank, (a.n_base, rank, a.certificate.message)
        assert a.certificate.numerical.gap > 1e6
        assert a.certificate.sampling["motion"]  # traced, and said so


def test_a_five_bar_is_traced_in_two_dimensions_through_regular_turning_points():
    """A five-bar's distal dyad straightens where the closure Jacobian keeps its rank (a turning point of the
    proximal angles, not a singular configuration): the trace passes it, as continuation in the proximal angles
    cannot, and keeps the Jacobian's rank everywhere."""
    robot, lengths, q0, d, _ = _five_bar(5)
    group, tr, q = _traced(robot, 5)
    assert group.dim == 2 and len(tr.x) > 200
    assert np.abs(evaluate(robot, q).r).max() < 1e-9
    assert {_elbow(lengths, q0 + row, d) for row in q} == {-1.0, 1.0}
    k = evaluate(robot, q).K[:, :2]  # the planar closure rows (x, y of the pin)
    sv = np.linalg.svd(k, compute_uv=False)
    assert (sv[:, 1] / sv[:, 0]).min() > 1e-3
    assert tr.extent[0] > 1.0 and tr.extent[1] > 1.0  # far beyond a +-0.3 box


def test_a_parallelogram_stays_on_its_branch_and_short_of_the_flat_configurations():
    """The parallelogram and its anti-parallelogram meet where the mechanism is flat: the trace stops there."""
    robot = bp.load("parallelogram")
    _, tr, q = _traced(robot)
    assert np.abs(q - np.stack([q[:, 0], -q[:, 0], q[:, 0]], axis=1)).max() < 1e-8  # the parallelogram's branch
    ref = np.arctan2(0.5, 0.3)  # the crank's angle at q = 0; flat at 0 and pi
    assert q[:, 0].min() > -ref and q[:, 0].max() < np.pi - ref
    assert tr.extent[0] > 0.9 * np.pi  # nearly the whole half turn between them


def test_groups_split_independent_loops_and_leave_free_coordinates_out():
    """A floating base above a linkage moves both sides of its loop alike: it is in no group."""
    robot = bp.load("four-bar")
    groups = loop_groups(robot)
    assert [(list(g.coords), g.rank, g.dim) for g in groups] == [([0, 1, 2], 2, 1)]
    assert traced_groups(bp.load("pkm-2rru-1rrs")) == []  # three degrees of freedom: sampled in the box


def test_the_box_sampling_of_a_welded_arm_decides_no_gap_and_the_trace_does(tmp_path):
    """The issue's case in small: a redundant arm welded at its hand (mocap_welds='keep'). Sampled around its
    reference the spectrum has no decisive gap; over the whole self-motion loop it has one."""
    from baseparams.numerics import closed_samples, rank_decision
    from baseparams.regressor import closed_regressor
    from test_mocap import ARM

    path = tmp_path / "arm7.xml"
    path.write_text(ARM.format(joints='<joint name="j7" axis="1 0 0" range="-3 3"/>'))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = bp.load(str(path), mocap_welds="keep")
    (group,) = traced_groups(robot)
    assert group.dim == 1
    rng = np.random.default_rng(0)
    box = rank_decision(closed_regressor(robot, closed_samples(robot, 2000, rng)).reshape(-1, 10 * robot.n))
    rng = np.random.default_rng(0)
    whole = rank_decision(closed_regressor(robot, closed_samples(robot, 2000, rng, whole_motion=True))
                          .reshape(-1, 10 * robot.n))
    assert whole.gap > 1e5 and whole.gap > 100 * box.gap


#: a Sawyer-like arm (seven hinges with lateral offsets, two finger slides), bent at qpos0 by {bend}; {weld}
SAWYER = """<mujoco model="sawyerish">
  <worldbody>{mocap}
    <body name="l0" pos="0 0 0.3"><joint name="j0" axis="0 0 1"/>
      <inertial pos="0.02 0.01 0.1" mass="3" diaginertia="0.05 0.04 0.03"/>
      <body name="l1" pos="0.08 0 0.25" euler="{b0} 0 0"><joint name="j1" axis="0 1 0"/>
        <inertial pos="0.01 0.05 0.02" mass="2.5" diaginertia="0.03 0.04 0.02"/>
        <body name="l2" pos="0 0.12 0.05" euler="0 {b1} 0"><joint name="j2" axis="0 0 1"/>
          <inertial pos="0.0 0.02 0.15" mass="2" diaginertia="0.04 0.03 0.01"/>
          <body name="l3" pos="0 -0.04 0.3" euler="{b2} 0 0"><joint name="j3" axis="0 1 0"/>
            <inertial pos="0.01 0.03 0.05" mass="1.5" diaginertia="0.02 0.02 0.01"/>
            <body name="l4" pos="0 0.1 0.12" euler="0 {b3} 0"><joint name="j4" axis="0 0 1"/>
              <inertial pos="0.0 0.01 0.12" mass="1.2" diaginertia="0.015 0.012 0.005"/>
              <body name="l5" pos="0 -0.03 0.28" euler="{b4} 0 0"><joint name="j5" axis="0 1 0"/>
                <inertial pos="0.01 0.02 0.03" mass="1" diaginertia="0.008 0.007 0.004"/>
                <body name="hand" pos="0 0.08 0.1" euler="0 {b5} 0"><joint name="j6" axis="0 0 1"/>
                  <inertial pos="0.01 0.005 0.04" mass="0.6" diaginertia="0.003 0.002 0.002"/>
                  <body name="fl" pos="0 0.02 0.08"><joint name="sl" type="slide" axis="0 1 0"/>
                    <inertial pos="0.005 0 0.02" mass="0.05" diaginertia="1e-5 2e-5 1e-5"/></body>
                  <body name="fr" pos="0 -0.02 0.08"><joint name="sr" type="slide" axis="0 -1 0"/>
                    <inertial pos="0.005 0 0.02" mass="0.05" diaginertia="1e-5 2e-5 1e-5"/></body>
                </body></body></body></body></body></body></body>
  </worldbody>{weld}
  <actuator><motor joint="sl"/><motor joint="sr"/></actuator>
</mujoco>
"""


def _sawyerish(tmp_path, seed: int):
    """The arm bent at random (an anchor), its hand welded to a mocap body placed where the hand is at qpos0."""
    import mujoco

    rng = np.random.default_rng(seed)
    bend = {f"b{i}": f"{v:.6f}" for i, v in enumerate(rng.uniform(20, 70, 6) * rng.choice([-1, 1], 6))}
    free = tmp_path / f"tree{seed}.xml"
    free.write_text(SAWYER.format(mocap="", weld="", **bend))
    m = mujoco.MjModel.from_xml_path(str(free))
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    hand = m.body("hand").id
    pos, quat = " ".join(f"{x:.17g}" for x in d.xpos[hand]), " ".join(f"{x:.17g}" for x in d.xquat[hand])
    path = tmp_path / f"welded{seed}.xml"
    path.write_text(SAWYER.format(mocap=f'<body name="mocap" mocap="true" pos="{pos}" quat="{quat}"/>',
                                  weld='<equality><weld body1="mocap" body2="hand"/></equality>', **bend))
    return path, free


def _mujoco_loop_rank(path, seed: int = 0) -> tuple[int, float]:
    """``(rank, gap)`` from MuJoCo alone: the weld's self-motion traced by a simple predictor-corrector on MuJoCo's
    own constraint rows, point-mass probes, ``mj_inverse`` at zero velocity with accelerations along the motion,
    the rows projected on it (constraint forces drop out)."""
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    arm = np.arange(7)

    def rows(q):
        d.qpos[:] = q
        mujoco.mj_forward(m, d)
        return np.array(d.efc_J).reshape(-1, m.nv)[:6], np.array(d.efc_pos)[:6]

    q, t_prev, loop = m.qpos0.copy(), None, []
    for _ in range(1500):  # steps of 0.02 rad along the loop
        j, _ = rows(q)
        t = np.linalg.svd(j[:, arm])[2][-1]
        t = t if t_prev is None or t @ t_prev > 0 else -t
        q[arm] += 0.02 * t
        for _ in range(20):
            j, r = rows(q)
            q[arm] -= np.linalg.lstsq(j[:, arm], r, rcond=None)[0]
        t_prev = t
        loop.append(q.copy())
        if len(loop) > 50 and np.abs((q[arm] - m.qpos0[arm] + np.pi) % (2 * np.pi) - np.pi).max() < 0.03:
            break
    rng = np.random.default_rng(seed)
    bodies = [b for b in range(1, m.nbody) if m.body_weldid[b] != 0]
    points = rng.normal(scale=0.2, size=(10, 3))
    off = int(mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_LIMIT)
    m.opt.disableflags |= off
    m.dof_armature[:] = m.dof_damping[:] = 0
    m.body_sameframe[:] = m.body_simple[:] = 0
    m.dof_simplenum[:] = 0
    m.body_mass[:], m.body_inertia[:] = 0, 0
    nocon = int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    out = []
    for q in [loop[i] for i in rng.integers(0, len(loop), 60)]:
        q = q.copy()
        q[7:] = rng.uniform(-0.02, 0.02, 2)
        j, _ = rows(q)
        n = np.linalg.svd(j)[2][6:].T  # (nv, 3): the self-motion and the fingers
        acc = n @ rng.normal(size=3)
        cols = []
        m.opt.disableflags |= nocon  # no constraint forces in mj_inverse (and none in the projected rows)
        for b in bodies:
            for p in points:
                m.body_mass[b], m.body_ipos[b], m.body_iquat[b] = 1.0, p, (1, 0, 0, 0)
                d.qpos[:], d.qvel[:], d.qacc[:] = q, 0, acc
                mujoco.mj_inverse(m, d)
                cols.append(n.T @ d.qfrc_inverse)
            m.body_mass[b] = 0.0
        m.opt.disableflags &= ~nocon
        out.append(np.array(cols).T)
    s = np.linalg.svd(np.vstack(out), compute_uv=False)
    rank = int(np.sum(s > 1e-9 * s[0]))
    return rank, float(s[rank - 1] / s[rank])


@pytest.mark.slow
def test_a_welded_redundant_arm_is_mujocos_count_at_every_anchor(tmp_path):
    """Issue 46's Meta-World case in our own file: kept (mocap_welds='keep'), the weld leaves a one-dimensional
    self-motion loop, traced whole; the count equals MuJoCo's (its own kinematics and inverse dynamics along its
    own trace of the loop) at three anchors, each decided at a gap; left out (the default) it is the tree's."""
    from mujoco_oracle import mujoco_rank

    counts = set()
    for seed in range(3):
        path, free = _sawyerish(tmp_path, seed)
        rank, gap = _mujoco_loop_rank(path, seed)
        assert gap > 1e6
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = bp.analyze(bp.load(str(path), mocap_welds="keep"))
            tree = bp.analyze(bp.load(str(path)))
        assert a.status.ok and a.n_base == rank and a.certificate.numerical.gap > 1e6, (a.n_base, rank)
        assert a.certificate.sampling["motion"]
        assert tree.status == "certified" and tree.n_base == mujoco_rank(free)[0]
        counts.add(a.n_base)
    assert len(counts) == 1
