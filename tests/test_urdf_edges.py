"""URDF edge cases: loop joints in either orientation, tolerant XML, exact ``write_urdf``."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from baseparams.base.regroup import base_parameters
from baseparams.errors import ModelError
from baseparams.io.urdf import load_urdf
from baseparams.kinematics.loops import evaluate
from baseparams.loading import load_model
from baseparams.model import RobotBuilder
from baseparams.nullspace.certify import certify
from baseparams.robots import get

from paths import SHARED

URDFPLUS = SHARED / "urdfplus"
#: without the shared folder, one placeholder: the test is marked ``shared`` and skips with the reason
LOOP_FILES = (sorted(p for p in URDFPLUS.glob("*.urdf") if "<loop" in p.read_text()) if URDFPLUS.is_dir()
              else [URDFPLUS / "absent.urdf"])


# ------------------------------------------------------------------ A: loop joint orientation
def _same_answer(r1, r2, samples: int = 1500, seed: int = 3, c1=None):
    """The same certified nullity, the same nullspace and the same regrouped base parameters
    (``c1``: ``r1``'s certificate, when already computed)."""
    c1 = certify(r1, samples=samples, seed=seed) if c1 is None else c1
    c2 = certify(r2, samples=samples, seed=seed)
    assert c1.certified, c1.message
    assert c2.certified, c2.message
    assert (c1.nullity, c1.status, c1.completed) == (c2.nullity, c2.status, c2.completed)
    b1, b2 = c1.basis, c2.basis
    assert np.abs(b1 - b2 @ (b2.T @ b1)).max() < 1e-7
    assert np.abs(b2 - b1 @ (b1.T @ b2)).max() < 1e-7
    p1, p2 = base_parameters(r1, b1, "khalil"), base_parameters(r2, b2, "khalil")
    assert np.array_equal(p1.independent, p2.independent)
    assert np.allclose(p1.K, p2.K, atol=1e-7)
    return c1


def _swapping_add_loop(swap: set[str], give_both: bool):
    """A replacement for ``RobotBuilder.add_loop`` writing the named loops the other way round
    (successor first); ``give_both``: also pass the (coinciding) successor-side frame."""
    orig = RobotBuilder.add_loop

    def add_loop(self, name, type, parent, child, origin=None, axis=(0, 0, 1.0), axis2=None, child_origin=None):
        pidx, pframe = self._frame(parent)
        cidx, cframe = self._frame(child)
        pm0 = np.eye(4) if pidx < 0 else self._m0[pidx]
        cm0 = np.eye(4) if cidx < 0 else self._m0[cidx]
        m = pm0 @ pframe @ (np.eye(4) if origin is None else origin)
        mc = m if child_origin is None else cm0 @ cframe @ child_origin
        if name not in swap:
            co = np.linalg.solve(cm0 @ cframe, mc) if give_both else child_origin
            return orig(self, name, type, parent, child, origin, axis, axis2, co)
        new_origin = np.linalg.solve(cm0 @ cframe, mc)  # the successor's frame, now the predecessor's
        new_child_origin = np.linalg.solve(pm0 @ pframe, m) if (give_both or child_origin is not None) else None
        if type.upper() == "U":
            axis, axis2 = axis2, axis
        return orig(self, name, type, child, parent, new_origin, axis, axis2, new_child_origin)

    return add_loop


BUILTIN_LOOPS = {"four-bar": ["closure"], "parallelogram": ["closure"],
                 "pkm-2rru-1rrs": ["U_b", "S_c"], "pkm-2prs-1psr": ["S_b", "R_c"]}


@pytest.mark.parametrize("name", sorted(BUILTIN_LOOPS))
def test_builtin_loop_robots_in_either_orientation(name, monkeypatch):
    ref = get(name)
    loops = BUILTIN_LOOPS[name]
    assert [lj.name for lj in ref.loops] == loops
    rng = np.random.default_rng(sum(map(ord, name)))
    subsets = [set(s) for k in range(1, len(loops) + 1) for s in itertools.combinations(loops, k)]
    c_ref = certify(ref, samples=1500, seed=3)
    for swap in subsets:
        monkeypatch.setattr(RobotBuilder, "add_loop", _swapping_add_loop(swap, bool(rng.integers(2))))
        robot = get(name)
        monkeypatch.undo()
        assert [lj.name for lj in robot.loops] == loops  # the names survive
        for a, b in zip(ref.loops, robot.loops):
            assert (a.parent, a.child, a.type) == (b.parent, b.child, b.type)
        _same_answer(ref, robot, c1=c_ref)


def _swap_in_file(text: str, names: set[str]) -> str:
    """The URDF+ text with the named loops' ``<predecessor>``/``<successor>`` exchanged (and a
    universal loop's ``<axis>``/``<axis2>``, which belong to those sides)."""

    def one(m: re.Match) -> str:
        block = m.group(0)
        if m.group(1) not in names:
            return block
        block = re.sub(r"<(/?)(predecessor|successor)\b", lambda t: f"<{t.group(1)}@{t.group(2)}", block)
        block = block.replace("@predecessor", "successor").replace("@successor", "predecessor")
        if 'type="universal"' in block:
            block = re.sub(r"<axis(2?)\b", lambda t: "<axis" + ("" if t.group(1) else "2"), block)
        return block

    return re.sub(r'<loop\s+name="([^"]+)".*?</loop>', one, text, flags=re.S)


@pytest.mark.shared
@pytest.mark.parametrize("path", LOOP_FILES, ids=[p.name for p in LOOP_FILES])
def test_urdfplus_loops_in_either_orientation(path, tmp_path):
    text = path.read_text()
    names = re.findall(r'<loop\s+name="([^"]+)"', text)
    assert names
    ref, _ = load_model(str(path))
    c_ref = certify(ref, samples=1500, seed=3)
    for k in range(1, len(names) + 1):
        for swap in itertools.combinations(names, k):
            swapped = _swap_in_file(text, set(swap))
            assert swapped != text
            f = tmp_path / path.name
            f.write_text(swapped)
            robot, _ = load_model(str(f))
            assert [lj.name for lj in robot.loops] == names
            _same_answer(ref, robot, c1=c_ref)


def _serial_four_bar(world_is: str) -> RobotBuilder:
    """A four-bar as a serial chain closed to the world by a loop R joint at D = (1, 0, 0)."""
    from baseparams.model import Inertia, pose

    b = RobotBuilder("chain", gravity=(0, -9.81, 0))
    b.add_link("crank", joint="R", inertia=Inertia(1.0, com=(0.1, 0.2, 0), inertia=(0.01, 0.02, 0.03)), actuated=True)
    b.add_link("coupler", parent="crank", joint="R", origin=pose((0.3, 0.5, 0)),
               inertia=Inertia(1.2, com=(0.4, 0.1, 0), inertia=(0.01, 0.03, 0.04)), actuated=False)
    b.add_link("rocker", parent="coupler", joint="R", origin=pose((0.95, 0.15, 0)),
               inertia=Inertia(0.8, com=(-0.1, -0.3, 0), inertia=(0.02, 0.01, 0.03)), actuated=False)
    d_in_rocker = pose((-0.25, -0.65, 0))
    if world_is == "predecessor":
        b.add_loop("ground", "R", parent=None, child="rocker", origin=pose((1.0, 0, 0)), axis=(0, 0, 1))
    else:
        b.add_loop("ground", "R", parent="rocker", child="world", origin=d_in_rocker, axis=(0, 0, 1),
                   child_origin=pose((1.0, 0, 0)))
    b.q_box = np.array([[-0.3, 0.3]])
    return b


def test_loop_joint_with_the_world_as_successor():
    r1, r2 = _serial_four_bar("predecessor").build(), _serial_four_bar("successor").build()
    assert (r2.loops[0].parent, r2.loops[0].child, r2.loops[0].name) == (-1, 2, "ground")
    assert np.allclose(r1.loops[0].M, r2.loops[0].M) and r2.loops[0].M_child is None
    c = _same_answer(r1, r2)
    assert c.nullity == 22  # the four-bar's


def test_loop_joint_orientation_unassembled_frames_swap_exactly():
    """Unassembled (the two frames differ at q = 0): the predecessor's frame becomes M and
    the successor's M_child, whichever side the file names first; U axes follow their sides."""
    from baseparams.model import pose

    def build(swap: bool):
        b = RobotBuilder("u")
        b.add_link("a", joint="R", axis=(0, 0, 1), actuated=True)
        b.add_link("b", joint="R", origin=pose((1, 0, 0)), axis=(0, 1, 0), actuated=False)
        fa, fb = pose((0.5, 0, 0), rpy=(0.1, 0, 0)), pose((-0.4, 0.02, 0), rpy=(0, 0.2, 0))
        if swap:
            b.add_loop("u1", "U", parent="b", child="a", origin=fb, axis=(0, 1, 0), axis2=(1, 0, 0), child_origin=fa)
        else:
            b.add_loop("u1", "U", parent="a", child="b", origin=fa, axis=(1, 0, 0), axis2=(0, 1, 0), child_origin=fb)
        return b.build().loops[0]

    l1, l2 = build(False), build(True)
    assert (l1.parent, l1.child) == (l2.parent, l2.child) == (0, 1)
    assert np.allclose(l1.M, l2.M) and np.allclose(l1.M_child, l2.M_child)
    assert np.allclose(l1.axes, l2.axes) and np.allclose(l1.axes, [[1, 0, 0], [0, 1, 0]])


def test_loop_joint_between_a_body_and_itself_or_the_world_and_itself_is_refused():
    b = RobotBuilder("x")
    b.add_link("a", joint="R", actuated=True)
    b.add_link("w", parent=None, joint="fixed")
    b.add_loop("self", "S", parent="a", child="a")
    with pytest.raises(ModelError, match="'self'.*same body"):
        b.build()
    b._loops.clear()
    b.add_loop("ground", "S", parent="w", child="world")
    with pytest.raises(ModelError, match="'ground'.*same body.*world"):
        b.build()


# ------------------------------------------------------------------ B: tolerant XML
SMALL = """<?xml version="1.0"?>
<robot name="small">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="1.0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.025"/></inertial></link>
  <link name="b"><inertial><origin xyz="0 0.2 0"/><mass value="0.5"/>
    <inertia ixx="0.01" ixy="0.001" ixz="0" iyy="0.01" iyz="0" izz="0.015"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <origin xyz="0 0 0.3" rpy="0.1 0.2 0.3"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><axis xyz="1 0 0"/>
    <origin xyz="0.5 0 0"/></joint>
</robot>
"""

TOLERATED = {
    "blank lines before <?xml": b"\n\n  \r\n" + SMALL.encode(),
    "trailing NUL bytes": SMALL.encode() + b"\x00" * 7,
    "trailing whitespace and NULs": SMALL.encode() + b"\n\n \x00\x00\n\x00",
    "UTF-8 BOM": b"\xef\xbb\xbf" + SMALL.encode(),
    "BOM, blank lines and NULs": b"\xef\xbb\xbf\n\n" + SMALL.encode() + b"\x00\n",
}


@pytest.mark.parametrize("label", sorted(TOLERATED))
def test_tolerated_xml_loads_like_the_clean_file(label, tmp_path):
    clean, odd = tmp_path / "clean.urdf", tmp_path / "odd.urdf"
    clean.write_text(SMALL)
    odd.write_bytes(TOLERATED[label])
    r1, r2 = load_urdf(clean), load_urdf(odd)
    assert r1.names == r2.names and np.array_equal(r1.N_body, r2.N_body) and np.array_equal(r1.M0, r2.M0)


MALFORMED = [
    ('xyz="0.5 0 0"', 'xyz="0.07, 0 0"', r"<joint name='j2'> <origin xyz>: expected 3 numbers, got '0.07, 0 0'$"),
    ('xyz="0.5 0 0"', 'xyz="$(optenv OFFSET 0.5) 0 0"',
     r"<joint name='j2'> <origin xyz>: .*unexpanded xacro/roslaunch substitution; run xacro first"),
    ('<mass value="0.5"/>', '<mass value="$(find pkg)"/>',
     r"<link name='b'> <mass value>: .*unexpanded xacro/roslaunch substitution; run xacro first"),
    ('<mass value="0.5"/>', '<mass value="${m_b}"/>', r"<link name='b'> <mass value>: .*run xacro first"),
    ('rpy="0.1 0.2 0.3"', 'rpy="0.1 0.2 0.3 0.4"', r"<joint name='j1'> <origin rpy>: expected 3 finite numbers"),
    # lines of the file
    ("</robot>\n", "</robot>\n<extra/>\n", r"malformed XML \(junk after document element: line 15"),
]


@pytest.mark.parametrize("old, new, message", MALFORMED, ids=[m[1][:24] for m in MALFORMED])
def test_malformed_values_are_one_line_errors(old, new, message, tmp_path):
    f = tmp_path / "robot.urdf"
    text = SMALL.replace(old, new, 1)
    assert text != SMALL
    f.write_bytes(b"\n\n" + text.encode() if "extra" in new else text.encode())
    with pytest.raises(ModelError) as exc:
        load_urdf(f)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(str(f))
    assert re.search(message, msg), msg


# ------------------------------------------------------------------ C: write_urdf is exact
def _erd(name: str) -> Path:
    from erd import urdf_files

    found = [f for f in urdf_files() if f.name == name]
    if not found:
        pytest.skip("example-robot-data is not installed")
    return found[0]


def _random_params(robot, convention: str, seed: int) -> np.ndarray:
    from baseparams.model.inertia import to_convention
    from baseparams.robots.random import random_inertia

    rng = np.random.default_rng(seed)
    return robot.with_parameters(np.concatenate([to_convention(random_inertia(rng).pseudo(), "khalil")
                                                 for _ in range(robot.n)]), "khalil").parameters(convention)


@pytest.mark.parametrize("convention, floating", [("khalil", False), ("paper", False), ("pinocchio", True)])
def test_write_urdf_round_trip_on_a_real_file(convention, floating, tmp_path):
    from baseparams.io.urdf import write_urdf

    src = _erd("kinova.urdf")
    robot = load_urdf(src, floating=floating)
    for seed in range(3):
        p = _random_params(robot, convention, seed)
        out = tmp_path / f"out{seed}.urdf"
        write_urdf(src, out, robot, p, convention)
        again = load_urdf(out, floating=floating, strict_inertia=True)
        assert again.names == robot.names and np.allclose(again.M0, robot.M0, atol=1e-15)
        scale = np.abs(robot.with_parameters(p, convention).N_body).max(axis=(1, 2))[:, None, None]
        assert np.all(np.abs(again.N_body - robot.with_parameters(p, convention).N_body) <= 1e-9 * scale)
        assert np.allclose(again.parameters(convention), p, rtol=1e-9, atol=1e-12)


def test_write_urdf_keeps_world_fixed_links_and_zeroes_merged_ones(tmp_path):
    import xml.etree.ElementTree as ET

    from baseparams.io.urdf import write_urdf

    src = _erd("kinova.urdf")
    robot = load_urdf(src)
    out = tmp_path / "out.urdf"
    write_urdf(src, out, robot, _random_params(robot, "khalil", 7), "khalil")
    before, after = ET.parse(src).getroot(), ET.parse(out).getroot()
    parent = {j.find("child").get("link"): (j.find("parent").get("link"), j.get("type"))
              for j in before.findall("joint")}
    root = next(ln.get("name") for ln in before.findall("link") if ln.get("name") not in parent)

    def welded(k):
        while k in parent and parent[k][1] == "fixed":
            k = parent[k][0]
        return k == root

    def inertial(r, name):
        el = r.find(f"link[@name='{name}']/inertial")
        return None if el is None else [(c.tag, dict(c.attrib)) for c in el]

    kept = [ln.get("name") for ln in before.findall("link") if welded(ln.get("name"))]
    assert root in kept and len(kept) >= 2 and inertial(before, root) is not None
    for name in kept:  # attribute strings unchanged
        assert inertial(after, name) == inertial(before, name), name
    merged = [ln.get("name") for ln in before.findall("link")
              if ln.get("name") not in robot.names and not welded(ln.get("name"))
              and inertial(before, ln.get("name")) is not None]
    assert merged
    for name in merged:
        assert float(after.find(f"link[@name='{name}']/inertial/mass").get("value")) == 0.0


def _small_robot(tmp_path):
    src = tmp_path / "small.urdf"
    src.write_text(SMALL)
    return src, load_urdf(src)


@pytest.mark.parametrize("mass, h, problem", [
    (0.0, (0.1, 0, 0), r"mass 0 with a nonzero first moment"),
    (-0.5, (0, 0.2, 0), r"mass -0.5 with a nonzero first moment"),
    (1e-14, (0.3, 0.1, 0), r"centre of mass 3.16e\+13 m from the link frame.*not representable"),
])
def test_write_urdf_refuses_a_body_it_cannot_write(mass, h, problem, tmp_path):
    from baseparams.io.urdf import write_urdf
    from baseparams.model.inertia import pseudo_from_origin, to_convention

    src, robot = _small_robot(tmp_path)
    n = robot.N_body.copy()
    n[1] = pseudo_from_origin(mass, np.array(h, float), np.diag([0.02, 0.03, 0.04]))
    out = tmp_path / "out.urdf"
    with pytest.raises(ModelError) as exc:
        write_urdf(src, out, robot, to_convention(n, "khalil").ravel(), "khalil")
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"{out}: <link name='b'>: ")
    assert re.search(problem, msg), msg
    assert not out.exists()  # nothing written


def test_write_urdf_writes_representable_degenerate_bodies(tmp_path):
    """Zero mass and zero first moment, or a negative mass at the origin: exact, written."""
    from baseparams.io.urdf import write_urdf
    from baseparams.model.inertia import pseudo_from_origin, to_convention

    src, robot = _small_robot(tmp_path)
    n = robot.N_body.copy()
    n[0] = pseudo_from_origin(0.0, np.zeros(3), np.diag([0.02, 0.03, 0.04]))
    n[1] = pseudo_from_origin(-0.5, np.zeros(3), np.zeros((3, 3)))
    out = tmp_path / "out.urdf"
    write_urdf(src, out, robot, to_convention(n, "khalil").ravel(), "khalil")
    with pytest.warns(UserWarning, match="negative mass"):
        again = load_urdf(out)
    assert np.array_equal(again.N_body, n)


def test_write_urdf_needs_a_convention(tmp_path):
    from baseparams.io.urdf import write_urdf

    src, robot = _small_robot(tmp_path)
    with pytest.raises(TypeError):
        write_urdf(src, tmp_path / "out.urdf", robot, robot.parameters("khalil"))  # the point


# ------------------------------------------------------------------ D: what every other tool loads
def test_mimic_of_an_unknown_joint_is_ignored_with_one_warning_naming_it(tmp_path):
    from baseparams.io.urdf import URDFWarning

    f = tmp_path / "m.urdf"
    f.write_text(SMALL.replace('<origin xyz="0.5 0 0"/></joint>',
                               '<origin xyz="0.5 0 0"/><mimic joint="ghost" multiplier="2"/></joint>'))
    with pytest.warns(URDFWarning) as rec:
        robot = load_urdf(f)
    msgs = [str(w.message) for w in rec if issubclass(w.category, URDFWarning)]
    assert len(msgs) == 1 and "\n" not in msgs[0]
    assert msgs[0].startswith(f"{f}: <joint name='j2'> <mimic>: ignored (unknown joint 'ghost')")
    assert robot.couplings == () and robot.dof == 2 and not robot.has_loops


def test_a_file_without_a_robot_name_is_named_after_the_file(tmp_path):
    from baseparams.errors import NoMovingBodiesError

    f = tmp_path / "unnamed_arm.urdf"
    f.write_text(SMALL.replace('<robot name="small">', "<robot>"))
    assert load_urdf(f).name == "unnamed_arm"
    f.write_text('<?xml version="1.0"?>\n<robot xmlns:xacro="http://wiki.ros.org/xacro">\n</robot>\n')  # ur3.urdf
    with pytest.raises(NoMovingBodiesError, match=r"unnamed_arm.urdf: no <link> elements"):
        load_urdf(f)
    f.write_text('<robot><link name="base"/><link name="plate"/><joint name="w" type="fixed">'
                 '<parent link="base"/><child link="plate"/></joint></robot>')
    with pytest.raises(NoMovingBodiesError, match=r"unnamed_arm.urdf: robot 'unnamed_arm': no moving links"):
        load_urdf(f)


def _erd_files():
    from erd import urdf_files

    return urdf_files()


#: example-robot-data files with nothing to identify at a fixed base (all links welded to the world)
NO_MOVING = {"ur3.urdf": "no <link> elements", "quadrotor_base.urdf": "no moving links",
             "iris_simple.urdf": "no moving links"}


@pytest.mark.slow
@pytest.mark.parametrize("path", _erd_files(), ids=[f.name for f in _erd_files()])
def test_every_erd_urdf_loads_and_certifies_with_default_flags(path):
    """Default flags: fixed base, no --floating, inertia problems are notes."""
    from baseparams.errors import NoMovingBodiesError

    if path.name in NO_MOVING:
        with pytest.raises(NoMovingBodiesError, match=NO_MOVING[path.name]):
            load_model(str(path))
        return
    robot, _ = load_model(str(path))
    assert "F" not in robot.jtype  # a fixed base
    cert = certify(robot, seed=1)
    assert cert.certified, cert.message


# ------------------------------------------------------------------ planar joints (issue 39)
PLANAR = """<robot name="slider">
  <link name="world"/>
  <joint name="base_joint" type="planar"><parent link="world"/><child link="base"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.2 -0.1 0.4"/>{axis}</joint>
  <link name="base"><inertial><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.25"/>
  </inertial></link>
</robot>
"""


@pytest.mark.parametrize("axis, normal", [('<axis xyz="0 0 2"/>', (0, 0, 1)), ('<axis xyz="1 1 0"/>', (1, 1, 0)),
                                          ("", (1, 0, 0))])
def test_urdf_planar_joint_moves_in_the_plane_normal_to_its_axis(axis, normal, tmp_path):
    """urdfdom's planar joint: translations normal to ``<axis>`` (default ``1 0 0``) and a rotation about it;
    an axis other than z (where Pinocchio, which ignores it, differs) is read with a warning."""
    import warnings

    from baseparams.io.urdf import URDFWarning
    from baseparams.kinematics.tree import forward_kinematics

    path = tmp_path / "slider.urdf"
    path.write_text(PLANAR.format(axis=axis))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load_urdf(path)
    said = [str(w.message) for w in caught if issubclass(w.category, URDFWarning)]
    assert len(said) == (normal != (0, 0, 1))
    assert all("<joint name='base_joint'>: planar joint" in s and "Pinocchio" in s for s in said)
    assert robot.jtype == ("C",) and robot.dof == 3
    frame = robot.M0[0]
    n = frame[:3, :3] @ (np.array(normal) / np.linalg.norm(normal))  # the plane's normal in the world
    rng = np.random.default_rng(0)
    q = rng.uniform(-2, 2, (20, 3))
    pose = forward_kinematics(robot, q).g[:, 0] @ frame
    moved = pose[:, :3, 3] - frame[:3, 3]
    assert np.abs(moved @ n).max() < 1e-12 and np.linalg.matrix_rank(moved, 1e-9) == 2  # in the plane, all of it
    rot = np.einsum("sij,jk->sik", pose[:, :3, :3], frame[:3, :3].T)
    assert np.abs(np.einsum("sij,j->si", rot, n) - n).max() < 1e-12  # rotations about the normal
    np.testing.assert_allclose(np.arccos(np.clip((np.trace(rot, axis1=1, axis2=2) - 1) / 2, -1, 1)),
                               np.abs(np.angle(np.exp(1j * q[:, 2]))), atol=1e-9)
    c = certify(robot)
    assert c.status == "certified" and c.completed == 0 and c.nullity == 6


# ------------------------------------------------------------------ Drake-flavoured URDF (issue 39)
DRAKE = """<?xml version="1.0"?>
<!-- Drake's URDFs use drake: elements without declaring the prefix: see http://drake.mit.edu -->
<robot name="drake_arm"{xmlns}>
  <link name="world"/>
  <link name="base"><inertial><mass value="3"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>
    </inertial><collision><geometry><box size="0.1 0.1 0.1"/></geometry>
    <drake:proximity_properties><drake:compliant_hydroelastic/><drake:mu_dynamic value="0.5"/>
    </drake:proximity_properties></collision></link>
  <joint name="fix" type="fixed"><parent link="world"/><child link="base"/></joint>
  <link name="l1"><inertial><origin xyz="0 0.05 0.1"/><mass value="2"/>
    <inertia ixx="0.02" ixy="0.001" ixz="0" iyy="0.03" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="100" velocity="1" drake:acceleration="10"/></joint>
  <link name="l2"><inertial><origin xyz="0.1 0.01 0.02"/><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0.001" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  {j2}
  <transmission type="SimpleTransmission" name="t1"><actuator name="a1"><drake:rotor_inertia value="0.0001"/>
    <drake:gear_ratio value="100"/></actuator><joint name="j1"/></transmission>
  <drake:collision_filter_group name="g"><drake:member link="l1"/><drake:member link="l2"/>
  </drake:collision_filter_group>
</robot>
"""
J2 = ('<joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3" rpy="0.3 0 0"/>'
      '<axis xyz="0 1 0"/></joint>')


@pytest.mark.parametrize("declared", [False, True])
def test_drake_urdf_is_read_leniently_with_one_note(declared, tmp_path):
    """Drake's elements (undeclared ``drake:`` prefix, as Drake's own files write them, or declared) are ignored
    and counted in one warning; the rest is plain URDF, read as Pinocchio (urdfdom, namespace-blind) reads it."""
    import warnings

    from baseparams.io.urdf import URDFWarning

    from erd import pinocchio_model, pinocchio_nullity

    path = tmp_path / "drake_arm.urdf"
    path.write_text(DRAKE.format(xmlns=' xmlns:drake="http://drake.mit.edu"' if declared else "", j2=J2))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load_urdf(path)
    said = [str(w.message) for w in caught if issubclass(w.category, URDFWarning)]
    assert len(said) == 1, said
    assert ("'drake' used without a declaration: read leniently" in said[0]) is not declared
    assert ("4 namespaced elements and 1 attribute describe no rigid body and were ignored: "
            "<drake:collision_filter_group>, <drake:gear_ratio>, <drake:proximity_properties>, <drake:rotor_inertia>, "
            "drake:acceleration") in said[0]
    assert robot.names == ("l1", "l2") and robot.jtype == ("R", "R")
    c = certify(robot)
    assert c.status == "certified" and c.completed == 0
    model = pinocchio_model(path, False)  # urdfdom reads the undeclared prefix; erd's mimic scan needs it declared
    plain = tmp_path / "declared.urdf"
    plain.write_text(DRAKE.format(xmlns=' xmlns:drake="http://drake.mit.edu"', j2=J2))
    assert model is not None and c.nullity == pinocchio_nullity(model, plain, 100)[0]


@pytest.mark.parametrize("kind, jtype, ndof", [("ball", "S", 3), ("universal", "U", 2), ("planar", "C", 3)])
def test_drake_joints_are_the_joints_urdf_lacks(kind, jtype, ndof, tmp_path):
    import warnings

    j2 = J2.replace('<joint name="j2" type="continuous">', f'<drake:joint name="j2" type="{kind}">')
    j2 = j2.replace("</joint>", "</drake:joint>").replace('<axis xyz="0 1 0"/>', '<axis xyz="0 0 1"/>')
    path = tmp_path / "drake_arm.urdf"
    path.write_text(DRAKE.format(xmlns="", j2=j2))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = load_urdf(path)
    assert robot.jtype == ("R", jtype) and robot.dof == 1 + ndof
    c = certify(robot)
    assert c.status == "certified" and c.completed == 0


def test_drake_screw_joint_and_ball_constraint(tmp_path):
    import warnings

    screw = J2.replace('<joint name="j2" type="continuous">', '<drake:joint name="j2" type="screw">')
    path = tmp_path / "drake_arm.urdf"
    path.write_text(DRAKE.format(xmlns="", j2=screw.replace("</joint>", "</drake:joint>")))
    with pytest.raises(ModelError, match=r"drake_arm.urdf: <drake:joint name='j2'>: Drake's 'screw' joint is not "
                                         r"supported") as info:
        load_urdf(path)
    assert "\n" not in str(info.value)
    # a ball constraint closes a loop: read as the spherical URDF+ loop it is (l2's tip on the base)
    ball = ('<drake:ball_constraint><drake:ball_constraint_body_A name="base"/>'
            '<drake:ball_constraint_p_AP value="0.2 0.1 0.5"/><drake:ball_constraint_body_B name="l2"/>'
            '<drake:ball_constraint_p_BQ value="0.2 0.1 0"/></drake:ball_constraint>')
    path.write_text(DRAKE.format(xmlns="", j2=J2 + ball))
    # two joints, a point pinned: the ball constraint locks the arm (issue 51): one line naming it, no invariant
    from baseparams.errors import NoMotionError
    from baseparams.loading import load_model

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(NoMotionError, match=r"drake_arm.urdf: robot 'drake_arm': the constraints "
                                                r"\(ball_constraint_base_l2\) leave this mechanism no motion") as info:
            load_model(str(path))
    assert "\n" not in str(info.value)
    # with a third joint the arm moves: the loop is the spherical URDF+ loop, the independent joint chosen
    j3 = ('<link name="l3"><inertial><origin xyz="0.1 0 0"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" '
          'iyy="0.02" iyz="0" izz="0.02"/></inertial></link><joint name="j3" type="continuous"><parent link="l2"/>'
          '<child link="l3"/><origin xyz="0.2 0 0"/><axis xyz="0 0 1"/></joint>'
          '<link name="l4"><inertial><origin xyz="0.1 0 0"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" '
          'iyy="0.02" iyz="0" izz="0.02"/></inertial></link><joint name="j4" type="continuous"><parent link="l3"/>'
          '<child link="l4"/><origin xyz="0.2 0 0"/><axis xyz="0 1 0"/></joint>')
    path.write_text(DRAKE.format(xmlns="", j2=J2 + j3 + ball.replace('body_B name="l2"', 'body_B name="l4"')
                                 .replace('p_BQ value="0.2 0.1 0"', 'p_BQ value="0 0.1 0"')))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load_urdf(path)
    assert len(robot.loops) == 1 and robot.loops[0].type == "S" and robot.loops[0].name == "ball_constraint_base_l4"
    assert any("no joint says which coordinates are independent" in str(w.message) for w in caught)
    assert robot.dof == 4 and len(robot.actuated) == 4 - np.linalg.matrix_rank(evaluate(robot, np.zeros((1, 4))).K[0])


def test_other_malformed_xml_is_still_refused(tmp_path):
    path = tmp_path / "bad.urdf"
    path.write_text(DRAKE.format(xmlns="", j2=J2).replace("</robot>", "</robt>"))
    with pytest.raises(ModelError, match="malformed XML"):
        load_urdf(path)


def test_drake_joint_of_a_standard_type_is_that_joint(tmp_path):
    """``<drake:joint type="revolute">`` (issue 51) is the revolute joint it says, as the plain ``<joint>`` is."""
    import warnings

    path = tmp_path / "drake_arm.urdf"
    for kind in ("revolute", "continuous"):
        j2 = J2.replace('<joint name="j2" type="continuous">', f'<drake:joint name="j2" type="{kind}">')
        path.write_text(DRAKE.format(xmlns="", j2=j2.replace("</joint>", "</drake:joint>").replace(
            "<axis", '<limit lower="-1" upper="1" effort="1" velocity="1"/><axis')))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            robot = load_urdf(path)
        plain = tmp_path / "plain.urdf"
        plain.write_text(DRAKE.format(xmlns="", j2=J2))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ref = load_urdf(plain)
        assert robot.jtype == ("R", "R") and np.allclose(robot.M0, ref.M0) and np.allclose(robot.screws, ref.screws)


@settings(max_examples=80, deadline=None)
@given(drake=st.dictionaries(st.sampled_from(["<drake:a>", "<drake:b>", "drake:c", "drake:d"]),
                             st.integers(1, 3), max_size=4),
       other=st.dictionaries(st.sampled_from(["<foo:joint>", "<bar:x>", "foo:y"]), st.integers(1, 3), max_size=3),
       undeclared=st.lists(st.sampled_from(["drake", "foo"]), max_size=2, unique=True))
def test_the_namespace_note_counts_in_the_number_it_counts(drake, other, undeclared):
    """Property (issue 51: "1 elements and attributes"): the note's counts are its elements (shown ``<tag>``) and
    attributes, each noun and verb in the number of its count, the listing's multiplicities summing to them."""
    from baseparams.io.urdf import _foreign_note

    note = _foreign_note(drake, other, undeclared)
    assert not re.search(r"(?<![\d.])1 (namespaced )?\w+s\b", note), note  # never "1 elements"
    for items, marker in ((drake, " no rigid body "), (other, " of other namespaces ")):
        part = [p for p in note.split("; ") if marker in p]
        assert len(part) == bool(items), note
        if not items:
            continue
        elements = sum(v for k, v in items.items() if k.startswith("<"))
        want = {w: n for w, n in (("element", elements), ("attribute", sum(items.values()) - elements)) if n}
        got = re.findall(r"(\d+) (?:namespaced )?(element|attribute)", part[0].split(":")[0])
        assert {w: int(n) for n, w in got} == want, part
        one = sum(items.values()) == 1
        assert (" was ignored" in part[0]) is one and (" were ignored" in part[0]) is not one, part
    assert ("namespace prefix " in note) is (len(undeclared) == 1) and ("prefixes" in note) is (len(undeclared) > 1)


@pytest.mark.parametrize("xmlns, prefix", [(' xmlns:foo="http://example.com/foo"', "foo"), ("", "foo"),
                                            (' xmlns:drake="http://example.com/not-drake"', "drake")])
def test_elements_of_another_namespace_are_never_urdf(xmlns, prefix, tmp_path):
    """Namespaces are honoured as declared (issue 51): ``<foo:joint>`` (declared or not), and ``drake:`` bound to
    another namespace, are not joints of the robot; they are ignored and counted in the one note."""
    import warnings

    from baseparams.io.urdf import URDFWarning

    other = J2.replace('<joint name="j2" type="continuous">', f'<{prefix}:joint name="j3" type="continuous">')
    other = other.replace("</joint>", f"</{prefix}:joint>").replace('link="l2"', 'link="l3"')
    body = DRAKE.format(xmlns=xmlns, j2=J2 + other).replace(
        "</robot>", '<link name="l3"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" '
                    'iyz="0" izz="0.01"/></inertial></link></robot>')
    if prefix == "drake":  # the rest of the file's drake: elements are then not Drake's either
        body = body.replace("<drake:", "<x:").replace("</drake:", "</x:")
        body = body.replace("drake:acceleration", "x:acceleration")
        body = body.replace(f"<{prefix}:joint".replace("drake", "x"), f"<{prefix}:joint")
        body = body.replace(f"</{prefix}:joint".replace("drake", "x"), f"</{prefix}:joint")
    path = tmp_path / "ns.urdf"
    path.write_text(body)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(ModelError, match=r"root links \['world', 'l3'\]: the tree is not connected") as info:
            load_urdf(path)  # l3 hangs on nothing: the foreign joint was not read as a joint
    said = [str(w.message) for w in caught if issubclass(w.category, URDFWarning)]
    assert len(said) == 1 and f"<{prefix}:joint>" in said[0] and "of other namespaces" in said[0]
    other_part = said[0].split("of other namespaces")[1]
    assert f"<{prefix}:joint>" in other_part, said[0]  # classed by its namespace, not by its prefix's spelling
    # the refusal says what was left out, the likely cause (the note is lost with the refusal on the command line)
    message = str(info.value)
    assert "\n" not in message and "(note: " in message and f"<{prefix}:joint>" in message.split("(note: ")[1]
