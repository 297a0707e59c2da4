"""``write_urdf`` / ``identify --urdf``: values changed in place, drive terms in ``<dynamics>``.

The written file is compared line by line with its source: every changed line differs only in
attribute values, the added lines are ``<dynamics>`` elements, XML comments and the elements an
``<inertial>`` lacked, nothing is removed; numbers have at most 10 significant digits. The real
Panda export (``--method physical --friction viscous,coulomb``) reloads in Pinocchio with the
identified inertias, damping and friction.
"""

import difflib
import json
import re

import numpy as np
import pytest

import baseparams
from baseparams.cli import main
from baseparams.errors import BaseparamsError, ModelError
from baseparams.io import xmledit
from baseparams.io.urdf import load_urdf, write_urdf

from paths import IDENT

PANDA = IDENT / "panda_gaz2019"

#: comments, a tab-indented link, single quotes, an <inertial> without <origin>, a rotated
#: inertial frame, a moving link without <inertial> written as <link/>, an existing <dynamics>
SOURCE = """<?xml version="1.0" encoding="utf-8"?>
<!-- a hand-written test robot -->
<robot name="edit">

  <link name="base"/>
  <joint name="j1" type="revolute">
    <parent link="base"/>
    <child link="a"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/>   <!-- shoulder -->
    <axis xyz="0 0 1"/>
    <dynamics damping='0.5'/>
  </joint>
  <link name="a">
\t<inertial>
\t\t<mass value='2.0'/>
\t\t<inertia ixx='0.01' ixy='0' ixz='0' iyy='0.02' iyz='0' izz='0.025'/>
\t</inertial>
  </link>
  <joint name="j2" type="revolute">
    <parent link="a"/>
    <child link="b"/>
    <origin xyz="0.5 0 0"/>
    <axis xyz="1 0 0"/>
  </joint>
  <link name="b">
    <!-- inertia in a rotated frame -->
    <inertial>
      <origin xyz="0 0.2 0" rpy="0.3 0 0.2"/>
      <mass value="0.5"/>
      <inertia ixx="0.01" ixy="0.001" ixz="0" iyy="0.01" iyz="0" izz="0.015"/>
    </inertial>
  </link>
  <joint name="j3" type="prismatic">
    <parent link="b"/><child link="c"/>
    <origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/>
    <limit lower="-0.1" upper="0.1" effort="10" velocity="1"/>
  </joint>
  <link name="c"/>
</robot>
"""

_VALUE = re.compile(r"""=\s*("[^"]*"|'[^']*')""")
_ATTR = re.compile(r"""\s([\w:.-]+)\s*=\s*("[^"]*"|'[^']*')""")


def _skeleton(line: str) -> tuple[str, set]:
    """A line without its attributes, and its attribute names."""
    return _ATTR.sub("", line), {m.group(1) for m in _ATTR.finditer(line)}


def _same_but_values(old: str, new: str) -> bool:
    """``new`` is ``old`` with attribute values changed (and attributes added at the end of a tag)."""
    (a, names_a), (b, names_b) = _skeleton(old), _skeleton(new)
    return a == b and names_a <= names_b and _VALUE.sub("=V", _ATTR.sub(
        lambda m: m.group(0) if m.group(1) in names_a else "", new)) == _VALUE.sub("=V", old)


def _check_only_values_changed(src: str, out: str, added: re.Pattern) -> list[str]:
    """Changed lines differ only in attribute values; added lines match ``added``; none removed."""
    a, b = src.splitlines(), out.splitlines()
    adds = []
    for op, i1, i2, j1, j2 in difflib.SequenceMatcher(None, a, b, autojunk=False).get_opcodes():
        if op == "equal":
            continue
        new = list(b[j1:j2])
        for old in a[i1:i2]:  # each old line is still there, its values changed (an empty element opened)
            k = next((k for k, line in enumerate(new) if _same_but_values(old, line)
                      or _same_but_values(old.replace("/>", ">"), line)), None)
            assert k is not None, (old, new)
            new.pop(k)
        adds += new
    for line in adds:
        assert added.fullmatch(line.strip()), line
    return adds


def _random_params(robot, seed):
    from baseparams.model.inertia import to_convention
    from baseparams.robots.random import random_inertia

    rng = np.random.default_rng(seed)
    return np.concatenate([to_convention(random_inertia(rng).pseudo(), "khalil") for _ in range(robot.n)])


def _significant(number: str) -> int:
    mantissa = number.lower().split("e")[0].lstrip("+-").replace(".", "").lstrip("0")
    return len(mantissa)


def test_only_values_change_and_drive_terms_go_to_dynamics(tmp_path):
    src = tmp_path / "robot.urdf"
    src.write_text(SOURCE)
    robot = load_urdf(src)
    p = _random_params(robot, 3)
    drives = {"j1": {"Fv": 0.25, "Fc": 1.5, "Ia": 0.012, "Fo": -0.3}, "j2": {"Fv": 0.125, "Fc": None},
              "j3": {"Fv": 2.0, "Fc": 3.0, "Fo": 0.5}}
    out = tmp_path / "out.urdf"
    notes = write_urdf(src, out, robot, p, "khalil", drives=drives)
    text = out.read_text()
    adds = _check_only_values_changed(
        SOURCE, text, re.compile(r"<dynamics( \w+=\"[^\"]*\")+/>|<!-- baseparams: [^\n]* -->|<origin [^\n]*/>|"
                                 r"</?inertial>|<mass [^\n]*/>|<inertia [^\n]*/>|</link>"))
    assert sum(a.strip().startswith("<dynamics") for a in adds) == 2  # j2, j3 new; j1's edited in place
    again = load_urdf(out)
    assert np.allclose(again.parameters("khalil"), p, rtol=1e-9, atol=1e-12)
    assert np.array_equal(again.M0, robot.M0)
    # attribute quoting and tabs kept; the rotated inertial frame kept
    assert "\t\t<mass value='" in text and "<dynamics damping='0.25' friction=\"1.5\"/>" in text
    assert 'rpy="0.3 0 0.2"' in text
    import xml.etree.ElementTree as ET

    root = ET.fromstring(text.encode())
    dyn = {j.get("name"): j.find("dynamics") for j in root.findall("joint")}
    assert dict(dyn["j2"].attrib) == {"damping": "0.125"}
    assert dict(dyn["j3"].attrib) == {"damping": "2", "friction": "3"}
    comments = re.findall(r"<!-- baseparams: (.*?) -->", text)
    assert len(comments) == 2
    assert "rotor inertia (armature) Ia = 0.012 kg m^2" in comments[0] and "torque offset Fo = -0.3 N m" in comments[0]
    assert "torque offset Fo = 0.5 N" in comments[1]  # the prismatic joint's unit
    assert any("URDF cannot hold rotor inertia" in n and "torque offsets Fo (2 joints)" in n for n in notes)
    for number in re.findall(r"-?\d[\d.]*(?:e[-+]?\d+)?", " ".join(_VALUE.findall(text))):
        assert _significant(number) <= 10, number
    # written again from the output: the comments are replaced, not repeated
    out2 = tmp_path / "out2.urdf"
    write_urdf(out, out2, robot, p, "khalil", drives={"j1": {"Fv": 0.5, "Fc": 1.0}})
    text2 = out2.read_text()
    assert "baseparams:" not in text2 and text2.count("<dynamics") == 3
    assert len(text2.splitlines()) == len(text.splitlines()) - 2


def test_drive_terms_that_cannot_be_written_are_refused(tmp_path):
    src = tmp_path / "robot.urdf"
    src.write_text(SOURCE)
    robot = load_urdf(src)
    out = tmp_path / "out.urdf"
    with pytest.raises(ModelError, match=r"joint 'j2': viscous friction Fv = -0.1 < 0"):
        write_urdf(src, out, robot, robot.parameters("khalil"), "khalil", drives={"j2": {"Fv": -0.1}})
    with pytest.raises(ModelError, match="joints \\['nope'\\] that are not in the file"):
        write_urdf(src, out, robot, robot.parameters("khalil"), "khalil", drives={"nope": {"Fv": 0.1}})
    with pytest.raises(BaseparamsError, match="would overwrite the input"):
        write_urdf(src, src, robot, robot.parameters("khalil"), "khalil")
    assert not out.exists() and src.read_text() == SOURCE


def test_unchanged_values_give_the_same_bytes_as_the_source(tmp_path):
    """Writing the model's own parameters changes nothing (numbers that re-read the same)."""
    src = tmp_path / "robot.urdf"
    src.write_text(SOURCE.replace('rpy="0.3 0 0.2"', 'rpy="0 0 0"'))
    robot = load_urdf(src)
    out = tmp_path / "out.urdf"
    write_urdf(src, out, robot, robot.parameters("khalil"), "khalil")
    assert out.read_text() == src.read_text()


def test_editor_keeps_everything_it_does_not_touch():
    text = "\ufeff<?xml version='1.0'?>\n<r a = 'x' b=\"y>\">\r\n  <e/><!-- c -->\n  <f k='1'></f>\n</r>\n\x00"
    root = xmledit.parse(text, "t")
    e, f = root.children
    ed = xmledit.Editor(text)
    ed.set(root, b="z", new="n")
    ed.set(f, k="2")
    ed.append(e, ["<g/>"])
    got = ed.text()
    assert got == ("\ufeff<?xml version='1.0'?>\n<r a = 'x' b=\"z\" new=\"n\">\r\n  <e>\r\n    <g/>\r\n  </e>"
                   "<!-- c -->\n  <f k='2'></f>\n</r>\n\x00")
    with pytest.raises(ModelError, match="t: malformed XML"):
        xmledit.parse("<r><a></r>", "t")


def _panda_csv(tmp_path):
    robot = baseparams.load(str(PANDA / "panda_mdh_gaz2019.urdf"))
    sig = {k: np.loadtxt(PANDA / f"exciting_traj_{f}.txt").reshape(-1, 7)
           for k, f in (("q", "positions"), ("dq", "velocity"), ("tau", "torques"))}
    csv = tmp_path / "panda.csv"
    header = ["t"] + [f"{k}_{j}" for k in sig for j in robot.joint_names]
    np.savetxt(csv, np.column_stack([np.loadtxt(PANDA / "exciting_traj_time.txt"), *sig.values()]), delimiter=",",
               header=",".join(header), comments="", fmt="%.17g")
    return robot, csv


@pytest.mark.shared
@pytest.mark.slow
def test_panda_physical_export_reloads_in_pinocchio(tmp_path, capsys):
    """The acceptance: damping and friction on all 7 joints, one element per line, Pinocchio agrees."""
    pin = pytest.importorskip("pinocchio")
    from baseparams.ident import identify
    from baseparams.io.logs import read_log
    from baseparams.model import inertia as I
    from baseparams.pga import inverse_transform

    robot, csv = _panda_csv(tmp_path)
    source = PANDA / "panda_mdh_gaz2019.urdf"
    out = tmp_path / "identified.urdf"
    assert main(["identify", str(source), str(csv), "--method", "physical", "--friction", "viscous,coulomb",
                 "--urdf", str(out), "--json"]) == 0
    captured = capsys.readouterr()
    j = json.loads(captured.out)
    assert "baseparams: note: --urdf: <dynamics> of 7 joints" in captured.err
    text = out.read_text()
    _check_only_values_changed(source.read_text(), text,
                               re.compile(r"<dynamics damping=\"[^\"]+\" friction=\"[^\"]+\"/>"))
    for line in text.splitlines():  # one element per line (the source's <parent/><child/> pair aside)
        assert line.count("<") <= 1 or line.strip().startswith("<parent"), line
    model = pin.buildModelFromUrdf(str(out))
    drives = {d["joint"]: d for d in j["drives"]}
    assert np.allclose(model.damping, [drives[n]["Fv"] for n in model.names[1:]], rtol=1e-8, atol=1e-12)
    assert np.allclose(model.friction, [drives[n]["Fc"] for n in model.names[1:]], rtol=1e-8)
    assert np.all(model.friction > 0.1)
    # the identified inertias, as the Python API gives them, are what Pinocchio reads
    ident = identify(robot, read_log(csv, robot), method="physical", friction=("viscous", "coulomb"))
    n_body = I.transform(I.from_convention(ident.fit.physical.pi.reshape(7, 10), "paper"),
                         inverse_transform(robot.M0))
    for i in range(7):
        inertia = model.inertias[model.getJointId(robot.joint_names[i])]
        m, h, j_o = I.split(n_body[i])
        c = h / m
        j_c = j_o - m * (c @ c * np.eye(3) - np.outer(c, c))
        assert np.isclose(inertia.mass, m, rtol=1e-8)
        assert np.allclose(inertia.lever, c, rtol=1e-7, atol=1e-10)
        assert np.allclose(inertia.inertia, j_c, rtol=1e-6, atol=1e-10 * np.abs(j_c).max())
