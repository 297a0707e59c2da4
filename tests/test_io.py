"""Robot files: the shared models, error messages on bad input, parser fuzzing, export."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from baseparams.errors import BaseparamsError, ModelError
from baseparams.io.mjcf import load_mjcf
from baseparams.io.urdf import URDFWarning, load_urdf, write_urdf
from baseparams.loading import load_model
from baseparams.nullspace.certify import certify
from baseparams.numerics import stacked_regressor

from paths import SHARED

SHARED_FILES = [  # (file, floating, certified nullity, directions left to numerical completion)
    # a parallelogram on its parallelogram branch, gravity along the axes: one base parameter
    ("urdfplus/four_bar.urdf", False, 29, 0),
    ("urdfplus/six_bar.urdf", False, 40, 0),
    # a horizontal parallelogram carried by the moving thigh: R-L1's coupled-joint completion
    ("urdfplus/planar_leg_linkage.urdf", False, 36, 0),
    ("urdfplus/mini_cheetah.urdf", False, 72, 0),
    ("mjcf/unitree_go2/go2.xml", False, 36, 0),
    ("mjcf/universal_robots_ur5e/ur5e.xml", False, None, 0),
    ("mjcf/kuka_iiwa_14/iiwa14.xml", False, None, 0),
    # the foot four-bar of each leg, carried by the moving tarsus: R-L3 planar loops
    ("mjcf/agility_cassie/cassie.xml", False, 70, 0),
]


@pytest.mark.shared
@pytest.mark.parametrize("rel, floating, nullity, completed", SHARED_FILES, ids=[r[0] for r in SHARED_FILES])
def test_shared_models_load_analyse_certify(rel, floating, nullity, completed):
    path = SHARED / rel
    assert path.exists(), f"../shared/models/{rel} is missing"
    robot, notes = load_model(str(path), floating=floating, strict_inertia=False)
    c = certify(robot, seed=0)
    assert c.certified, c.message
    assert c.max_column_residual < 1e-9
    if nullity is not None:
        assert c.nullity == nullity
    assert c.completed == completed == 0  # DRNG alone is complete on every shared file


@pytest.mark.shared
def test_go2_file_equals_builtin():
    from baseparams.robots import go2

    robot, _ = load_model(str(SHARED / "mjcf/unitree_go2/go2.xml"))
    assert np.allclose(robot.parameters("paper"), go2().parameters("paper"))
    assert np.allclose(robot.M0, go2().M0)


@pytest.mark.shared
def test_loops_are_never_dropped():
    robot = load_urdf(SHARED / "urdfplus/four_bar.urdf")
    assert len(robot.loops) == 1 and robot.loops[0].type == "R"
    cassie = load_mjcf(SHARED / "mjcf/agility_cassie/cassie.xml")
    assert len(cassie.loops) == 4 and all(lj.type == "S" for lj in cassie.loops)


@pytest.mark.shared
def test_infeasible_inertia_is_a_note_by_default_and_an_error_when_strict():
    from baseparams.model.inertia import InertiaWarning

    msg = r"planar_leg_linkage.urdf: <link name='thigh'>: inertia not physically feasible .* triangle inequality"
    with pytest.warns(InertiaWarning, match=msg):
        robot = load_urdf(SHARED / "urdfplus/planar_leg_linkage.urdf")
    assert "thigh" in robot.names
    with pytest.raises(ModelError, match=msg + r".*strict"):
        load_urdf(SHARED / "urdfplus/planar_leg_linkage.urdf", strict_inertia=True)
    # the CLI: one note per offending link by default, exit 0; --strict-inertia refuses
    from baseparams.cli import main

    assert main(["analyze", str(SHARED / "urdfplus/planar_leg_linkage.urdf"), "--no-verify"]) == 0
    assert main(["analyze", str(SHARED / "urdfplus/planar_leg_linkage.urdf"), "--strict-inertia"]) == 2


def test_world_fixed_links_never_block(tmp_path):
    """A link welded to the world (the fixed root, a 1 microgram antenna on it) is never checked,
    even with strict checking: its inertia cannot matter."""
    bad = '<inertial><mass value="1e-9"/><inertia ixx="-1" ixy="0" ixz="0" iyy="0" iyz="0" izz="5"/></inertial>'
    text = GOOD.replace('<link name="base"/>', f'<link name="base">{bad}</link><link name="antenna">{bad}</link>'
                        ).replace("</robot>", '<joint name="ja" type="fixed"><parent link="base"/>'
                                  '<child link="antenna"/></joint></robot>')
    f = tmp_path / "r.urdf"
    f.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        robot = load_urdf(f, strict_inertia=True)
    assert robot.names == ("a", "b")


# ------------------------------------------------------------------------------ bad input
GOOD = """<?xml version="1.0"?>
<robot name="two">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="1.0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.025"/></inertial></link>
  <link name="b"><inertial><origin xyz="0 0.2 0"/><mass value="0.5"/>
    <inertia ixx="0.01" ixy="0.001" ixz="0" iyy="0.01" iyz="0" izz="0.015"/></inertial></link>
  <link name="tool"><inertial><mass value="0.2"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <origin xyz="0 0 0.3" rpy="0.1 0.2 0.3"/></joint>
  <joint name="j2" type="prismatic"><parent link="a"/><child link="b"/><axis xyz="1 0 0"/>
    <origin xyz="0.5 0 0"/></joint>
  <joint name="j3" type="fixed"><parent link="b"/><child link="tool"/><origin xyz="0 0 0.1"/></joint>
</robot>
"""

BAD = [
    (GOOD.replace("</robot>", ""), r"malformed XML"),
    (GOOD.replace('<child link="b"/>', '<child link="nope"/>'), r"<joint name='j2'>: unknown link 'nope'"),
    (GOOD.replace('<link name="tool">', '<link name="a">'), r"duplicate link 'a'"),
    (GOOD.replace('<parent link="base"/><child link="a"/>', '<parent link="b"/><child link="a"/>'),
     r"not connected to the root link|no root link|reached twice"),
    (GOOD.replace('type="prismatic"', 'type="helical"'),
     r"<joint name='j2'>: unknown or unsupported joint type 'helical'"),
    (GOOD.replace('<mass value="0.5"/>', '<mass value="-0.5"/>'), r"<link name='b'>: .*negative mass -0.5"),
    (GOOD.replace('izz="0.025"', 'izz="0.5"'), r"<link name='a'>: inertia not physically feasible"),
    (GOOD.replace('<axis xyz="1 0 0"/>', '<axis xyz="0 0 0"/>'), r"<joint name='j2'>: zero joint axis"),
    (GOOD.replace('<axis xyz="1 0 0"/>', '<axis xyz="1 0"/>'), r"<joint name='j2'> <axis xyz>: expected 3"),
    (GOOD.replace('xyz="0.5 0 0"', 'xyz="0.5 nan 0"'), r"<joint name='j2'> <origin xyz>: expected 3 finite"),
    (GOOD.replace("</robot>", '<loop name="l" type="revolute"><predecessor link="a"/><successor link="ghost"/>'
                              '</loop></robot>'), r"<loop name='l'>: unknown link 'ghost'"),
    (GOOD.replace("</robot>", '<loop name="l" type="screw"><predecessor link="a"/><successor link="b"/>'
                              '</loop></robot>'), r"<loop name='l'>: unknown or unsupported loop type 'screw'"),
    ("<mujoco/>", r"root element is <mujoco>, expected <robot>"),
]


@pytest.mark.parametrize("text, message", BAD)
def test_bad_urdf_gives_one_clear_line(tmp_path, text, message):
    f = tmp_path / "robot.urdf"
    f.write_text(text)
    with pytest.raises(ModelError) as exc:
        load_urdf(f, strict_inertia=True)  # strict: inertia problems are errors too
    msg = str(exc.value)
    assert "\n" not in msg and str(f) in msg
    assert re.search(message, msg), msg


def test_cli_reports_bad_file_in_one_line(tmp_path, capsys):
    from baseparams.cli import main

    f = tmp_path / "robot.urdf"
    f.write_text(GOOD.replace('<mass value="0.5"/>', '<mass value="-0.5"/>'))
    assert main(["analyze", str(f), "--strict-inertia"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "negative mass" in err and str(f) in err
    assert main(["analyze", str(f), "--no-verify"]) == 0  # by default: a note, and the analysis goes on
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("baseparams: note:") and "negative mass" in err
    assert main(["analyze", str(tmp_path / "missing.urdf")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_fixed_joint_merge_matches_two_body_model(tmp_path):
    f = tmp_path / "robot.urdf"
    f.write_text(GOOD)
    robot = load_urdf(f)
    assert robot.n == 2 and robot.names == ("a", "b")
    # the tool's inertia is merged into b: total mass and first moment about b's frame
    assert np.isclose(robot.N_body[1][3, 3], 0.7)
    assert np.allclose(robot.N_body[1][:3, 3], 0.5 * np.array([0, 0.2, 0]) + 0.2 * np.array([0, 0, 0.1]))


@pytest.mark.shared
def test_urdfplus_tolerated_spellings_warn(tmp_path):
    f = tmp_path / "robot.urdf"
    f.write_text((SHARED / "urdfplus/four_bar.urdf").read_text()
                 .replace("<successor link", "<sucessor name").replace("</successor>", "</sucessor>"))
    with pytest.warns(URDFWarning, match="sucessor"):
        robot = load_urdf(f)
    assert len(robot.loops) == 1


def test_mjcf_errors(tmp_path):
    """What MuJoCo rejects is one line naming the file (MuJoCo's message); an unsupported
    equality is one line naming it."""
    f = tmp_path / "m.xml"
    f.write_text('<mujoco><worldbody><body name="a"><joint type="hinge"/><inertial pos="0 0 0" mass="1" '
                 'diaginertia="1 1 1"/></body></worldbody><equality><tendon tendon1="t"/></equality></mujoco>')
    with pytest.raises(ModelError, match=r"m\.xml: .*'t'") as exc:
        load_mjcf(f)
    assert "\n" not in str(exc.value)
    f.write_text('<mujoco><worldbody><body name="a"><joint type="hinge"/><inertial pos="0 0 0" mass="1" '
                 'diaginertia="1 1 1"/></body></worldbody><equality><connect body1="a" body2="zz" anchor="0 0 0"/>'
                 '</equality></mujoco>')
    with pytest.raises(ModelError, match="zz"):
        load_mjcf(f)


# ------------------------------------------------------------------------------ fuzzing
def _regressor_signature(robot):
    return stacked_regressor(robot, samples=3, seed=0) @ robot.parameters("paper")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.integers(0, len(GOOD) - 1), st.integers(1, 8), st.sampled_from(["", "x", "-", "<", ">", '"', "9", " ", "/"]))
def test_fuzzed_urdf_never_tracebacks(tmp_path, pos, width, insert):
    f = tmp_path / "fuzz.urdf"
    f.write_text(GOOD[:pos] + insert + GOOD[pos + width:])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            robot = load_urdf(f)
    except BaseparamsError as exc:
        assert "\n" not in str(exc)
        return
    assert robot.n >= 1 and np.all(np.isfinite(robot.parameters("paper")))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.permutations(range(4)), st.booleans(), st.booleans())
def test_semantics_preserving_edits_give_the_same_model(tmp_path, order, comments, spaces):
    """Reordered links, comments and whitespace must not change the model (never silently)."""
    ref = tmp_path / "ref.urdf"
    ref.write_text(GOOD)
    base = load_urdf(ref)
    lines = GOOD.split("\n")
    links = [lines[2], "\n".join(lines[3:5]), "\n".join(lines[5:7]), "\n".join(lines[7:9])]
    text = "\n".join(lines[:2] + [links[k] for k in order] + lines[9:])
    if comments:
        text = text.replace("<joint ", "<!-- a comment --><joint ")
    if spaces:
        text = text.replace('xyz="', 'xyz="  ').replace("><", ">\n   <")
    f = tmp_path / "edit.urdf"
    f.write_text(text)
    robot = load_urdf(f)
    assert robot.names == base.names
    assert np.allclose(_regressor_signature(robot), _regressor_signature(base))


def test_write_urdf_round_trip(tmp_path):
    src = tmp_path / "robot.urdf"
    src.write_text(GOOD)
    robot = load_urdf(src)
    rng = np.random.default_rng(0)
    from baseparams.robots.random import random_inertia

    new = np.concatenate([__import__("baseparams").model.inertia.to_convention(random_inertia(rng).pseudo(), "khalil")
                          for _ in range(robot.n)])
    out = tmp_path / "identified.urdf"
    write_urdf(src, out, robot, new, "khalil")
    again = load_urdf(out)
    assert np.allclose(again.parameters("khalil"), new)
    assert np.allclose(again.M0, robot.M0)


MJCF_LOOPS = """<mujoco model="loops">
  <compiler angle="radian"/>
  <worldbody>
    <site name="ground_pin" pos="1 0 0"/>
    <body name="crank" pos="0 0 0">
      <joint name="j_crank" type="hinge" axis="0 0 1"/>
      <inertial pos="0.15 0 0" mass="1" diaginertia="0.001 0.01 0.01"/>
      <body name="coupler" pos="0.3 0.5 0" euler="0 0 0.1">
        <joint name="j_coupler" type="hinge" axis="0 0 1"/>
        <inertial pos="0.4 0 0" mass="0.8" diaginertia="0.001 0.02 0.02"/>
        <site name="coupler_end" pos="0.6952 -0.1978 0"/>
      </body>
    </body>
    <body name="rocker" pos="1 0 0" xyaxes="0 1 0 -1 0 0">
      <joint name="j_rocker" type="hinge" axis="0 0 1"/>
      <inertial pos="0.3 0 0" mass="0.6" diaginertia="0.001 0.01 0.01"/>
      <body name="tip" pos="0.3 0 0"><joint name="j_tip" type="hinge" axis="0 0 1"/>
        <inertial pos="0.05 0 0" mass="0.2" diaginertia="0.0001 0.001 0.001"/></body>
      <body name="tip2" pos="0.3 0 0"><joint name="j_tip2" type="hinge" axis="0 0 1"/>
        <inertial pos="0.05 0.01 0" mass="0.1" diaginertia="0.0001 0.001 0.001"/></body>
    </body>
  </worldbody>
  <equality>
    <connect name="close" body1="coupler" body2="rocker" anchor="0.6952 -0.1978 0"/>
    <joint name="gear" joint1="j_tip2" joint2="j_tip" polycoef="0 2 0 0 0"/>
  </equality>
</mujoco>
"""


def test_mjcf_connect_and_joint_coupling(tmp_path):
    f = tmp_path / "loops.xml"
    f.write_text(MJCF_LOOPS)
    robot, notes = load_model(str(f))
    assert len(robot.loops) == 1 and robot.loops[0].type == "S" and len(robot.couplings) == 1
    assert robot.couplings[0].ratio == 2.0
    c = certify(robot, samples=300, seed=0)
    assert c.certified, c.message
    from baseparams.numerics import numerical_nullspace

    assert c.nullity == numerical_nullspace(robot, 300, 5).nullity
    # the site form (sites only approximately coincident: assembled, then analysed the same)
    g = tmp_path / "sites.xml"
    g.write_text(MJCF_LOOPS.replace('<connect name="close" body1="coupler" body2="rocker" anchor="0.6952 -0.1978 0"/>',
                                    '<connect name="close" site1="coupler_end" site2="rocker_end"/>')
                 .replace('<body name="tip" pos="0.3 0 0">', '<site name="rocker_end" pos="0.3726 -0.0115 0"/>'
                          '<body name="tip" pos="0.3 0 0">'))
    robot2, notes2 = load_model(str(g))
    assert any("do not coincide" in n for n in notes2)
    c2 = certify(robot2, samples=300, seed=0)
    assert c2.certified and c2.nullity == c.nullity


def test_mjcf_weld_is_a_fixed_loop(tmp_path):
    f = tmp_path / "weld.xml"
    f.write_text(MJCF_LOOPS.replace('<connect name="close" body1="coupler" body2="rocker" anchor="0.6952 -0.1978 0"/>',
                                    '<weld name="w" body1="tip" body2="tip2"/>'))
    robot = load_mjcf(f)
    assert [lj.type for lj in robot.loops] == ["fixed"]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.integers(0, len(MJCF_LOOPS) - 1), st.integers(1, 6), st.sampled_from(["", "x", "<", '"', "-1", " "]))
def test_fuzzed_mjcf_never_tracebacks(tmp_path, pos, width, insert):
    f = tmp_path / "fuzz.xml"
    f.write_text(MJCF_LOOPS[:pos] + insert + MJCF_LOOPS[pos + width:])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            robot, _ = load_model(str(f))
    except BaseparamsError as exc:
        assert "\n" not in str(exc)
        return
    assert robot.n >= 1 and np.all(np.isfinite(robot.parameters("paper")))
