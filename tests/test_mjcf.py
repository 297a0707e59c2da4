"""MJCF read through MuJoCo: constructs the old hand-written reader refused or misread, checked
against MuJoCo's own compiled world poses; missing meshes; armature; equalities; and the corpus
of models shipped with gymnasium and dm_control against MuJoCo's own regressor rank."""

from __future__ import annotations

import importlib.util
import warnings
from pathlib import Path

import numpy as np
import pytest

from baseparams.enums import Status
from baseparams.errors import ModelError, NoMovingBodiesError
from baseparams.io.mjcf import MJCFWarning, load_mjcf
from baseparams.kinematics import forward_kinematics
from baseparams.loading import load_model
from baseparams.nullspace.certify import certify

from mujoco_oracle import mujoco_rank


def _mj(path):
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(path))
    return mujoco, m, mujoco.MjData(m)


def assert_same_poses(path, seed=0):
    """Our link frames at random q equal MuJoCo's body frames moved to the first joint's anchor
    (rotation = body rotation), and our inertias equal MuJoCo's (world frame)."""
    robot = load_mjcf(path)
    mujoco, m, d = _mj(path)
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1, 1, robot.dof)
    assert all(t in "RPUC" for t in robot.jtype)
    qpos = m.qpos0.copy()
    for j in range(m.njnt):  # our coordinates are MuJoCo's dofs in order (hinge/slide only here)
        qpos[m.jnt_qposadr[j]] += q[m.jnt_dofadr[j]]
    d.qpos[:] = qpos
    mujoco.mj_kinematics(m, d)
    g = forward_kinematics(robot, q).g[0] @ robot.M0
    for i, name in enumerate(robot.names):
        b = m.body(name).id
        rot = d.xmat[b].reshape(3, 3)
        assert np.allclose(g[i][:3, :3], rot, atol=1e-10), name
        assert np.allclose(g[i][:3, 3], d.xpos[b] + rot @ m.jnt_pos[m.body_jntadr[b]], atol=1e-10), name
        com = g[i] @ (robot.N_body[i][:, 3] / robot.N_body[i][3, 3])
        assert np.isclose(robot.N_body[i][3, 3], m.body_mass[b])
        assert np.allclose(com[:3], d.xipos[b], atol=1e-10), name
    return robot


def _write(tmp_path, text, name="m.xml"):
    f = tmp_path / name
    f.write_text(text)
    return f


INERT = '<inertial pos="0.01 0.02 0.03" mass="1" diaginertia="0.1 0.2 0.25"/>'


def test_second_top_level_default(tmp_path):
    f = _write(tmp_path, f"""<mujoco><default><joint axis="1 0 0"/></default>
      <default><joint axis="0 1 0"/><default class="c"><joint axis="0 0 1"/></default></default>
      <worldbody><body name="a" pos="0 0 1"><joint name="ja"/>{INERT}
        <body name="b" pos="0.3 0 0"><joint name="jb" class="c" pos="0 0.1 0"/>{INERT}</body></body>
      </worldbody></mujoco>""")
    robot = assert_same_poses(f)
    assert robot.jtype == ("R", "R")


def test_bodies_inside_frame(tmp_path):
    f = _write(tmp_path, f"""<mujoco><worldbody><frame pos="0.5 0 0" euler="0 0 90">
      <body name="a" pos="0.2 0 0"><joint axis="1 0 0"/>{INERT}
        <frame pos="0 0.3 0" euler="30 0 0"><body name="b"><joint/>{INERT}</body></frame></body>
      </frame></worldbody></mujoco>""")
    assert_same_poses(f)


def test_global_coordinates_give_one_line(tmp_path):
    f = _write(tmp_path, f'<mujoco><compiler coordinate="global"/><worldbody><body name="a"><joint/>{INERT}'
                         f'</body></worldbody></mujoco>')
    with pytest.raises(ModelError) as exc:
        load_mjcf(f)
    assert "global coordinates no longer supported" in str(exc.value) and "\n" not in str(exc.value)
    assert str(exc.value).startswith(str(f))


def test_include(tmp_path):
    _write(tmp_path, f'<mujoco><body name="b" pos="0 0.2 0"><joint axis="1 0 0"/>{INERT}</body></mujoco>', "arm.xml")
    f = _write(tmp_path, f'<mujoco><worldbody><body name="a" pos="0 0 1"><joint/>{INERT}<include file="arm.xml"/>'
                         f'</body></worldbody></mujoco>')
    robot = assert_same_poses(f)
    assert robot.names == ("a", "b")


def test_unnamed_bodies_and_joints(tmp_path):
    f = _write(tmp_path, f'<mujoco><worldbody><body pos="0 0 1"><joint/>{INERT}<body pos="0.3 0 0">'
                         f'<joint axis="1 0 0"/><joint axis="0 1 0" pos="0 0 0.1"/>{INERT}</body></body>'
                         f'</worldbody></mujoco>')
    robot = load_mjcf(f)
    assert robot.names == ("body1", "body2")
    assert robot.joint_names == ("body1_joint0", "body2_joint0+body2_joint1")


def test_planar_root_and_three_hinge_hip(tmp_path):
    f = _write(tmp_path, f"""<mujoco><worldbody><body name="torso" pos="0 0 1.2">
      <joint name="rootx" type="slide" axis="1 0 0"/><joint name="rootz" type="slide" axis="0 0 1" ref="1.2"/>
      <joint name="rooty" type="hinge" axis="0 1 0" pos="0 0 -0.1"/>{INERT}
      <body name="thigh" pos="0 0.1 -0.2" euler="10 0 0">
        <joint name="hx" axis="1 0 0" pos="0 0 0.05"/><joint name="hz" axis="0 0 1" pos="0 0 0.05"/>
        <joint name="hy" axis="0 1 0" pos="0 0 0.05"/>{INERT}
        <body name="shin" pos="0 0 -0.4"><joint name="k1" axis="0 1 0"/><joint name="k2" axis="1 0 0"/>{INERT}</body>
      </body></body></worldbody></mujoco>""")
    robot = assert_same_poses(f)
    assert robot.jtype == ("C", "C", "U") and robot.dof == 8 and robot.n == 3
    assert np.allclose(robot.axes[0][:2], [[0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 0, 1]])
    c = certify(robot, seed=0)
    assert c.certified
    assert 10 * robot.n - c.nullity == mujoco_rank(f)[0]


def test_missing_mesh_loads_with_explicit_inertial(tmp_path):
    f = _write(tmp_path, f"""<mujoco><asset><mesh name="m" file="nope.stl"/><mesh name="m2" file="gone.stl"/></asset>
      <worldbody><body name="a"><joint/>{INERT}<geom type="mesh" mesh="m"/>
        <body name="b" pos="0.3 0 0"><joint/><geom type="mesh" mesh="m2"/></body></body></worldbody></mujoco>""")
    with pytest.warns(MJCFWarning, match="body 'b': its inertia came from stripped geoms") as rec:
        robot = load_mjcf(f)
    assert not any("body 'a'" in str(w.message) for w in rec)
    np.testing.assert_allclose(robot.N_body[0][3, 3], 1.0)
    np.testing.assert_allclose(robot.N_body[0][:3, 3], [0.01, 0.02, 0.03])
    assert robot.names == ("a", "b")


def test_armature_is_read(tmp_path):
    f = _write(tmp_path, f"""<mujoco><worldbody><body name="a" pos="0 0 1"><freejoint/>{INERT}
      <body name="b"><joint armature="0.5"/><joint axis="1 0 0" armature="0.25" pos="0 0 0.1"/>{INERT}
      <body name="c"><joint type="ball" armature="0.125"/>{INERT}</body></body></body></worldbody></mujoco>""")
    robot = load_mjcf(f)
    _, m, _ = _mj(f)
    arm = m.dof_armature
    assert robot.armature.shape == (robot.dof,)
    np.testing.assert_allclose(robot.armature, np.r_[arm[3:6], arm[0:3], arm[6:]])  # free: (omega, v)
    np.testing.assert_allclose(robot.armature[6:], [0.5, 0.25, 0.125, 0.125, 0.125])


def test_equalities(tmp_path):
    base = f"""<mujoco><worldbody>
      <body name="a"><joint name="ja"/>{INERT}<body name="a2" pos="0.2 0 0"><joint name="ja2"/>{INERT}</body></body>
      <body name="b" pos="1 0 0"><joint name="jb"/>{INERT}</body></worldbody>
      <tendon><fixed name="t"><joint joint="ja" coef="1"/><joint joint="jb" coef="-2"/></fixed>
        <fixed name="t3"><joint joint="ja" coef="1"/><joint joint="jb" coef="1"/>
          <joint joint="ja2" coef="1"/></fixed></tendon>
      <equality>EQ</equality></mujoco>"""
    f = _write(tmp_path, base.replace("EQ", '<tendon name="tc" tendon1="t"/>'))
    robot = load_mjcf(f)
    (c,) = robot.couplings
    assert (c.pred, c.succ, c.ratio) == (0, 2, 0.5)  # q_b = q_a / 2
    # a tendon tying three joints (dm_control's quadruped: pitch + knee + ankle = 0) is one coupling
    f = _write(tmp_path, base.replace("EQ", '<tendon name="t3c" tendon1="t3"/>'))
    robot = load_mjcf(f)
    (c,) = robot.couplings
    k = np.zeros(robot.dof)
    k[c.succ] = 1.0
    for j, r in c.terms():
        k[j] -= r
    np.testing.assert_allclose(k / k[0], [1.0, 1.0, 1.0])  # ja, ja2, jb: q_a + q_a2 + q_b = 0
    assert len(c.more) == 1 and c.offset == 0.0
    f = _write(tmp_path, base.replace("EQ", '<connect name="off" body1="a2" body2="b" anchor="0 0 0" active="false"/>'))
    with pytest.warns(MJCFWarning, match="inactive"):
        assert not load_mjcf(f).loops
    f = _write(tmp_path, base.replace("EQ", '<weld name="w" body1="a2" body2="b" torquescale="2"/>'))
    with pytest.warns(MJCFWarning, match="torquescale 2 ignored"):
        assert [lj.type for lj in load_mjcf(f).loops] == ["fixed"]


def test_mjcf_errors_are_one_line(tmp_path):
    f = _write(tmp_path, f'<mujoco><worldbody><body name="a"><joint/>{INERT}</body></worldbody><equality>'
                         f'<connect body1="a" body2="zz" anchor="0 0 0"/></equality></mujoco>')
    with pytest.raises(ModelError) as exc:
        load_mjcf(f)
    assert "zz" in str(exc.value) and "\n" not in str(exc.value) and str(exc.value).startswith(str(f))


# ------------------------------------------------------------------------------ corpus
def _package_dir(name):
    spec = importlib.util.find_spec(name)
    return None if spec is None or spec.origin is None else Path(spec.origin).parent


def _corpus():
    out = []
    gym, dmc = _package_dir("gymnasium"), _package_dir("dm_control")
    if gym is not None:
        out += sorted((gym / "envs" / "mujoco" / "assets").glob("*.xml"))
    if dmc is not None:
        out += sorted((dmc / "suite").glob("*.xml"))
    return out


CORPUS = _corpus()
#: files that are not complete models or that we refuse, with the reason
EXPECTED = {
    "lqr.xml": (NoMovingBodiesError, "no moving links"),  # a template: dm_control adds the bodies in Python
}
#: directions still completed numerically, with the reason
NUMERICAL: dict[str, int] = {}  # none since R-M's groups driven by several coordinates (quadruped's tendons)
SLOW = {"dog.xml", "stacker.xml", "manipulator.xml", "humanoid_CMU.xml"}


def test_corpus_is_installed():
    assert len(CORPUS) >= 30, "pip install gymnasium dm-control (test dependencies)"


@pytest.mark.parametrize("path", [pytest.param(p, marks=pytest.mark.slow) if p.name in SLOW else p for p in CORPUS],
                         ids=[f"{p.parent.parent.name if p.parent.name == 'suite' else 'gymnasium'}/{p.name}"
                              for p in CORPUS])
def test_corpus_certified_and_rank_equals_mujoco(path):
    if path.name in EXPECTED:
        err, msg = EXPECTED[path.name]
        with pytest.raises(err, match=msg):
            load_model(str(path))
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot, _ = load_model(str(path))
    c = certify(robot, seed=0)
    assert c.certified and c.status in (Status.CERTIFIED, Status.COMPLETED), c.message
    assert c.status is (Status.CERTIFIED if c.completed == 0 else Status.COMPLETED)
    assert c.completed == NUMERICAL.get(path.name, 0)  # DRNG complete (R-C: the planar robots' compound roots)
    rank, gap = mujoco_rank(path)
    assert gap > 1e6  # a clear rank decision (relative tolerance 1e-9)
    assert 10 * robot.n - c.nullity == rank


@pytest.mark.parametrize("name", ["half_cheetah.xml", "walker2d.xml", "hopper.xml", "swimmer.xml", "point.xml"])
def test_gymnasium_planar_robots_need_rule_rc(name, monkeypatch):
    """gymnasium's planar robots (a slide-slide-hinge root): complete with R-C, not without (issue 39)."""
    from baseparams.nullspace import compound
    from baseparams.nullspace.columns import Columns

    path = _package_dir("gymnasium") / "envs" / "mujoco" / "assets" / name
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot, _ = load_model(str(path))
    assert certify(robot, seed=0).completed == 0
    monkeypatch.setattr(compound, "compound_columns", lambda *a, **k: Columns.empty())
    left = certify(robot, seed=0)
    assert left.certified and left.completed == {"half_cheetah.xml": 14, "walker2d.xml": 14, "hopper.xml": 8,
                                                 "swimmer.xml": 6, "point.xml": 2}[name]
