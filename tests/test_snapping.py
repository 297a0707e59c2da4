"""Snapping finds every near-right angle a file writes (issue 46): CAD hands whose angles are written to 5-6
digits, with ``<mimic>`` couplings (where snapping used to stay silent: robots with couplings were not
examined), fixed mount joints, frames turned by right angles, a few assembly mates 0.02-0.8 mrad off; URDF
and MJCF (quat, euler in degrees, axisangle). The default count is the design's, with a note naming each
value of the file taken exact; every count equals an independent rank of the file with exactly those
values set (Pinocchio's regressor for URDF: ``rank([W_ours | W_pin]) = rank(W_ours) = rank(W_pin)``, at a
gap; MuJoCo's own inverse dynamics for MJCF)."""

from __future__ import annotations

import re
import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import baseparams
from baseparams.cli import EXIT_OK, main
from baseparams.model.inertia import LENGTH_POWER
from hands import five_finger_hand, five_finger_hand_mjcf

from mujoco_oracle import mujoco_rank

#: the hands' link length, for the column scales (M L^u) and the rate sqrt(g / L)
L = 0.04


def _load(tmp_path, text: str, name: str):
    path = tmp_path / name
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return baseparams.load(str(path)), path


def _analyze(robot, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return baseparams.analyze(robot, **kw)


def apply_urdf(text: str, snaps: list[dict]) -> str:
    """The URDF with the values the JSON names set exact (independently of the program's re-reading)."""
    root = ET.fromstring(text)
    joints = {j.get("name"): j for j in root.findall("joint")}
    written = {}
    for s in snaps:  # the note gives each value as the file writes it
        name, tag, attr = re.fullmatch(r'<joint name="([^"]*)"> <(\w+) (\w+)>', s["element"]).groups()
        el = joints[name].find(tag)
        written[id(s)] = el, attr
        assert (el.get(attr) if s["component"] < 0 else el.get(attr).split()[s["component"]]) == s["text"]
    for s in sorted(snaps, key=lambda x: x["component"] < 0):  # a whole rotation after its angles
        el, attr = written[id(s)]
        tokens = el.get(attr).split()
        if s["component"] < 0:
            tokens = [repr(v) for v in s["new"]]
        else:
            tokens[s["component"]] = repr(s["special"])
        el.set(attr, " ".join(tokens))
    return ET.tostring(root, encoding="unicode")


def apply_mjcf(text: str, snaps: list[dict]) -> str:
    """The MJCF with the values the JSON names set exact: a whole rotation becomes a ``quat``."""
    for s in sorted(snaps, key=lambda x: x["component"] < 0):
        kind, name = re.match(r"(body|joint) '([^']*)'", s["element"]).groups()
        attr = "axis" if kind == "joint" else s["what"]
        pat = re.compile(rf'(<{kind} name="{name}"[^>]*?) {attr}="([^"]*)"')
        m = pat.search(text)
        if s["component"] < 0:
            new = f'{m.group(1)} quat="{" ".join(repr(v) for v in s["new"])}"'
        else:
            tokens = m.group(2).split()
            assert float(tokens[s["component"]]) == pytest.approx(s["literal"], abs=1e-12)
            tokens[s["component"]] = repr(s["special"])
            new = f'{m.group(1)} {attr}="{" ".join(tokens)}"'
        text = text[:m.start()] + new + text[m.end():]
    return text


def _rank(w: np.ndarray, count: int) -> tuple[int, float]:
    """Rank of ``w`` (singular values above 1e-9 of the largest) and the ratio of singular values across ``count``.
    Columns are not normalised: an exactly vanishing column is rounding (1e-14), and scaling it up is not rank."""
    s = np.linalg.svd(w, compute_uv=False)
    s = s / s[0]
    return int(np.sum(s > 1e-9)), float(s[count - 1] / max(s[count], 1e-300)) if count < len(s) else np.inf


def regressors(robot, path, samples: int = 60, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Ours (the TP regressor, paper convention) and Pinocchio's (mimic joints tied to their leaders, rows the
    actuated generalized forces) at the same actuated states, rows in the same order."""
    pin = pytest.importorskip("pinocchio")
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    names = [robot.joint_names[robot.dof_body[k]] for k in robot.actuated]
    col = {nm: i for i, nm in enumerate(names)}
    g = np.zeros((model.nv, len(names)))
    root = ET.parse(path).getroot()
    for jt in root.findall("joint"):
        if jt.get("type") == "fixed":
            continue
        j = model.joints[model.getJointId(jt.get("name"))]
        m = jt.find("mimic")
        if m is None:
            g[j.idx_v, col[jt.get("name")]] = 1.0
        else:
            g[j.idx_v, col[m.get("joint")]] = float(m.get("multiplier"))
    rng = np.random.default_rng(seed)
    rate = np.sqrt(9.81 / L)
    qa, va, aa = (rng.uniform(-1, 1, (samples, len(names))) for _ in range(3))
    va, aa = va * rate, aa * rate**2
    ours = baseparams.regressor(robot, qa, va, aa).reshape(-1, 10 * robot.n)
    theirs = np.vstack([g.T @ pin.computeJointTorqueRegressor(model, data, g @ q, g @ v, g @ a)
                        for q, v, a in zip(qa, va, aa)])
    ours = ours * L ** np.tile(LENGTH_POWER["paper"], robot.n)
    theirs = theirs * L ** np.tile([0, 1, 1, 1, 2, 2, 2, 2, 2, 2], model.njoints - 1)
    return ours, theirs


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 4, 5, 7])
def test_cad_hands_give_the_design_count_which_is_pinocchios_rank_of_the_snapped_file(tmp_path, seed):
    """Five-finger hands with mimic couplings, angles to 6 digits and mates off: the literal count is not the
    design's (often not decided at all); the default is the design's, with the note naming each value taken
    exact; Pinocchio's regressor of the file with those values set has that rank at a gap (>= 1e6), and the
    same column space as ours."""
    hand = five_finger_hand(seed)
    robot, path = _load(tmp_path, hand.text, "hand.urdf")
    design, _ = _load(tmp_path, hand.design, "design.urdf")
    d = _analyze(design, literal=True)
    assert d.status == "certified" and d.certificate.numerical.gap > 1e8
    lit, a = _analyze(robot, literal=True), _analyze(robot)
    assert a.status.ok and a.n_base == d.n_base
    assert lit.n_base > d.n_base or not lit.status.ok  # the rounding adds directions (or no gap decides)
    j = a.to_json()
    snaps = j["practical"]["snaps"]
    assert snaps and all(s["element"].startswith("<joint name=") for s in snaps)
    assert all(s["text"] in hand.text for s in snaps)
    assert j["rank_decision"]["decided"] and j["rank_decision"]["snapped"] and j["rank_decision"]["gap"] > 1e8
    snapped_text = apply_urdf(hand.text, snaps)
    mine, spath = _load(tmp_path, snapped_text, "snapped.urdf")
    assert _analyze(mine, literal=True).n_base == a.n_base  # the file with those values exact, read literally
    ours, theirs = regressors(mine, spath)
    ours, theirs = ours / np.linalg.norm(ours, 2), theirs / np.linalg.norm(theirs, 2)
    n = a.n_base
    (r_o, g_o), (r_p, g_p), (r_c, g_c) = (_rank(w, n) for w in (ours, theirs, np.hstack([ours, theirs])))
    assert r_o == r_p == r_c == n, (r_o, r_p, r_c, n)
    assert min(g_o, g_p, g_c) > 1e6


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 3, 4, 10])
def test_mjcf_hands_quaternions_euler_axisangle(tmp_path, seed):
    """The same hands in MJCF (orientations as quat, euler in degrees or axisangle, turned 0.02-0.8 mrad off at
    random, rounded to 6 digits; mimics as joint equalities): the design's count, each value named by its
    body, and MuJoCo's own regressor of the file with those values set has that rank at a gap."""
    hand = five_finger_hand_mjcf(seed)
    robot, path = _load(tmp_path, hand.text, "hand.xml")
    design, dpath = _load(tmp_path, hand.design, "design.xml")
    d = _analyze(design, literal=True)
    assert d.status == "certified"
    a = _analyze(robot)
    assert a.status.ok and a.n_base == d.n_base
    assert mujoco_rank(dpath)[0] == d.n_base
    j = a.to_json()
    if j["practical"] is None:  # the rounding changed nothing here
        assert _analyze(robot, literal=True).n_base == d.n_base
        return
    snaps = j["practical"]["snaps"]
    assert all(re.match(r"(body|joint) '", s["element"]) for s in snaps)
    _, spath = _load(tmp_path, apply_mjcf(hand.text, snaps), "snapped.xml")
    rank, gap = mujoco_rank(spath)
    assert rank == a.n_base and gap > 1e6


def test_mimic_couplings_no_longer_silence_the_snapping(tmp_path):
    """The root cause of the CAD hands of issue 46: robots with couplings were not examined at all. With and
    without the ``<mimic>`` elements, the rounded hand is snapped to its design's count; a robot changed after
    reading (no file to go back to) is examined through its own frames, couplings or not."""
    from dataclasses import replace

    from baseparams.model.snap import near_special

    for mimic in (True, False):
        hand = five_finger_hand(1, mimic=mimic, fingers=2)
        robot, _ = _load(tmp_path, hand.text, "h.urdf")
        design, _ = _load(tmp_path, hand.design, "d.urdf")
        a = _analyze(robot)
        assert a.practical is not None and a.n_base == _analyze(design).n_base
        assert bool(robot.couplings) == mimic
        changed = replace(robot, M0=robot.M0.copy())  # same geometry, no longer "as read": the model's frames
        assert changed.source is not None and near_special(changed)
    coupled, _ = _load(tmp_path, five_finger_hand(1, fingers=2).text, "h.urdf")
    moved = replace(coupled, gravity=np.array([0.0, 0.0, -9.80665]))  # changed: its file is not used
    b = _analyze(moved)
    assert b.practical is not None and all(not s.element for s in b.practical.snaps)


ARM = ('<robot name="arm"><link name="base"/>{links}'
       '<joint name="j1" type="revolute"><parent link="{p1}"/><child link="l1"/><origin xyz="0 0 0.3" rpy="{r1}"/>'
       '<axis xyz="{a1}"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
       '<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.05 0 0.4" rpy="{r2}"/>'
       '<axis xyz="0 0.6 0.8"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint></robot>')
INERT = ('<inertial><origin xyz="0.03 0.02 0.1" rpy="{rpy}"/><mass value="2"/>'
         '<inertia ixx="0.03" iyy="0.04" izz="0.02" ixy="0.001" ixz="0" iyz="0"/></inertial>')


def _arm(r1="0 0 0", a1="0 0 1", r2="0.3 0.2 0.1", mount=None, inertial="0 0 0") -> str:
    links = "".join(f'<link name="{n}">{INERT.format(rpy=inertial)}</link>' for n in ("l1", "l2"))
    if mount is not None:
        links += ('<link name="m"/><joint name="mount" type="fixed"><parent link="base"/><child link="m"/>'
                  f'<origin xyz="0 0 0.1" rpy="{mount}"/></joint>')
    return ARM.format(links=links, p1="base" if mount is None else "m", r1=r1, a1=a1, r2=r2)


@pytest.mark.parametrize("case", ["rpy", "gimbal", "axis", "mount"])
def test_every_place_a_urdf_writes_an_angle(tmp_path, case):
    """A first axis within 0.5 mrad of vertical (through its rpy, at gimbal lock as an exporter writes it - pitch
    pi/2 and a generic roll and yaw whose difference is the right angle -, its axis, or the rpy of a fixed mount
    before it): the count of the exact file, the note naming that element."""
    kw, exact = {
        "rpy": ({"r1": "0.0005 0 0.4"}, {"r1": "0 0 0.4"}),
        "gimbal": ({"r1": "0.4 1.5708 0.4", "a1": "1 0 0"}, {"r1": "0 1.5707963267948966 0", "a1": "1 0 0"}),
        "axis": ({"a1": "0 0.0004 1"}, {"a1": "0 0 1"}),
        "mount": ({"mount": "3.14159 0 0", "a1": "0 0 -1"}, {"mount": "3.141592653589793 0 0", "a1": "0 0 -1"}),
    }[case]
    robot, _ = _load(tmp_path, _arm(**kw), "a.urdf")
    ref, _ = _load(tmp_path, _arm(**exact), "x.urdf")
    want = _analyze(ref).n_base
    lit, a = _analyze(robot, literal=True), _analyze(robot)
    assert lit.n_base > want and a.n_base == want
    element = '<joint name="mount">' if case == "mount" else '<joint name="j1">'
    assert all(s.element.startswith(element) for s in a.practical.snaps)


MJ = ('<mujoco><compiler angle="{unit}"/>{defaults}<worldbody>{frame_open}'
      '<body name="b1" pos="0 0 0.3" {orient}><joint name="j1" {axis}/>'
      '<inertial pos="0.03 0.02 0.1" mass="2" fullinertia="0.03 0.04 0.02 0.001 0 0"/>'
      '<body name="b2" pos="0.05 0 0.4" euler="{e2}"><joint name="j2" axis="0 0.6 0.8"/>'
      '<inertial pos="0.03 0.02 0.1" mass="2" fullinertia="0.03 0.04 0.02 0.001 0 0"/></body></body>'
      '{frame_close}</worldbody></mujoco>')


@pytest.mark.parametrize("case", ["quat", "euler_degree", "euler_radian", "axisangle", "xyaxes", "zaxis", "frame",
                                  "default_axis"])
def test_every_place_an_mjcf_writes_an_angle(tmp_path, case):
    """A first hinge within 0.5 mrad of vertical through each orientation form MJCF has (and a ``<frame>``, and
    a joint axis from a default class): the exact file's count, the note naming that element; MuJoCo's regressor
    of the file with the named values set has that rank."""
    base = {"unit": "degree", "defaults": "", "frame_open": "", "frame_close": "", "axis": 'axis="0 0 1"',
            "e2": "17 11 5", "orient": ""}
    t = 4e-4
    forms = {
        "quat": {"orient": f'quat="0.707107 {t / 2:.6f} 0 0.707107"'},
        "euler_degree": {"orient": f'euler="{np.degrees(t):.6f} 0 90"'},
        "euler_radian": {"unit": "radian", "e2": "0.3 0.2 0.1", "orient": f'euler="0 {t} 1.5708"'},
        "axisangle": {"orient": f'axisangle="{t} 0 1 90"'},
        "xyaxes": {"orient": f'xyaxes="0 1 {t} -1 0 0"'},
        "zaxis": {"orient": f'zaxis="{t} 0 1"'},
        "frame": {"frame_open": f'<frame euler="0 {np.degrees(t):.6f} 0">', "frame_close": "</frame>"},
        "default_axis": {"defaults": f'<default><joint axis="0 {t} 1"/></default>', "axis": ""},
    }
    text = MJ.format(**{**base, **forms[case]})
    robot, path = _load(tmp_path, text, "a.xml")
    lit, a = _analyze(robot, literal=True), _analyze(robot)
    assert a.practical is not None and a.n_base < lit.n_base
    j = a.to_json()
    snaps = j["practical"]["snaps"]
    where = {"frame": "frame", "default_axis": "joint 'j1'"}.get(case, "body 'b1'")
    assert all(s["element"].startswith(where) for s in snaps), snaps
    if case in ("frame",):  # the test's own substitution does not edit <frame>: MuJoCo on the exact frame
        text_x = text.replace(f'euler="0 {np.degrees(t):.6f} 0"', 'euler="0 0 0"')
    elif case == "default_axis":
        text_x = text.replace(f'axis="0 {t} 1"', 'axis="0 0 1"')
    else:
        text_x = apply_mjcf(text, snaps)
    _, xpath = _load(tmp_path, text_x, "x.xml")
    rank, gap = mujoco_rank(xpath)
    assert rank == a.n_base and gap > 1e6


def test_inertial_frames_never_change_the_count(tmp_path):
    """A link's parameters are a general inertia in any frame: turning the inertial frames (by generic angles, or
    to within 1e-4 of a right angle) changes no count, and snapping does not look at them."""
    counts = set()
    for rpy in ("0 0 0", "0.3 -1.1 2.0", "1.5708 0 0.0001"):
        robot, _ = _load(tmp_path, _arm(inertial=rpy), "i.urdf")
        a = _analyze(robot)
        counts.add(a.n_base)
        assert a.practical is None
    assert len(counts) == 1


def test_exact_files_and_the_literal_flag(tmp_path, capsys):
    """The design file is analysed as it is; ``--literal`` gives the file as written; the JSON and the text
    report name the gap the count was stated at and each value taken exact."""
    hand = five_finger_hand(1, fingers=3)
    design, _ = _load(tmp_path, hand.design, "d.urdf")
    assert _analyze(design).practical is None
    _, path = _load(tmp_path, hand.text, "h.urdf")
    assert main(["analyze", str(path)]) == EXIT_OK
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("rank "))
    assert "decided at a gap of" in line and "on the snapped geometry" in line
    note = next(x for x in out.splitlines() if x.startswith("practical identifiability"))
    assert '<joint name="' in note and "--literal" in note
    assert main(["analyze", str(path), "--literal", "--json"]) in (EXIT_OK, 3)
    assert '"practical": null' in capsys.readouterr().out
