"""Practical identifiability: geometry a file states to within rounding of a right angle or zero.

A URDF carrying ``rpy="1.5708"`` or a first joint tilted 7.3e-6 rad from gravity has, taken
literally, more base parameters than the exact design; the extra directions move the torques by
about the rounding error and are not identifiable in practice. The analysis takes such values as
the special value when that changes the count, says so naming the joint, and keeps the literal
count behind ``literal=True`` / ``--literal``. Exact files are unaffected.
"""

import json

import numpy as np
import pytest

import baseparams
from baseparams.cli import main
from baseparams.model.snap import SNAP_TOL, near_special, rotation, rpy

from paths import SHARED

PANDA = SHARED.parent / "ident" / "panda_gaz2019" / "panda_mdh_gaz2019.urdf"
SPECIAL = (0.0, np.pi / 2, -np.pi / 2, np.pi)
AXES = ((1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, -1))


def _fmt(x: float, digits: int | None) -> str:
    return repr(float(x)) if digits is None else f"{x:.{digits}f}"


def chain_urdf(rng, n: int, perturb: float = 0.0, digits: int | None = None) -> tuple[str, list[str]]:
    """A random serial arm in the way URDFs are written: rpy in multiples of pi/2 or generic, axes along a
    frame axis, offsets zero or generic. ``perturb``: that many radians/metres added to some special values;
    ``digits``: special values written rounded to that many decimals. Returns the text and the joints touched."""
    links = ['<link name="base"/>']
    joints, touched = [], []
    for i in range(n):
        # generic angles stay clear of multiples of pi/2, generic offsets clear of zero
        generic = (rng.uniform(0.1, np.pi / 2 - 0.1, 3) + np.pi / 2 * rng.integers(-2, 2, 3))
        ang = [float(rng.choice(SPECIAL)) if rng.random() < 0.8 else float(g) for g in generic]
        xyz = [0.0 if rng.random() < 0.5 else float(rng.choice([-1, 1]) * rng.uniform(0.05, 0.4)) for _ in range(3)]
        name = f"j{i}"
        hit, signs = rng.random() < 0.5, rng.choice([-1.0, 1.0], 3)
        if perturb and hit and any(a in SPECIAL for a in ang):
            ang = [a + sg * perturb if a in SPECIAL else a for a, sg in zip(ang, signs)]
            touched.append(name)
        axis = AXES[int(rng.integers(0, len(AXES)))]
        m = float(rng.uniform(0.5, 5))
        c = rng.uniform(-0.1, 0.1, 3)
        ixx, iyy, izz = rng.uniform(0.01, 0.05, 3)
        rpy_text = " ".join(_fmt(a, digits if a in SPECIAL else None) for a in ang)
        links.append(f'<link name="l{i}"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}"/><mass value="{m}"/>'
                     f'<inertia ixx="{ixx + iyy}" iyy="{iyy + izz}" izz="{izz + ixx}" ixy="0" ixz="0" iyz="0"/>'
                     f'</inertial></link>')
        parent = "base" if i == 0 else f"l{i - 1}"
        joints.append(f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="l{i}"/>'
                      f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy_text}"/>'
                      f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
                      f'<limit lower="-3" upper="3" effort="100" velocity="2"/></joint>')
    return f'<robot name="arm{n}">' + "".join(links + joints) + "</robot>", touched


def _load(tmp_path, text: str, name: str = "arm.urdf"):
    path = tmp_path / name
    path.write_text(text)
    return baseparams.load(str(path))


@pytest.mark.parametrize("seed", range(12))
def test_rounded_or_perturbed_special_values_give_the_exact_designs_count(tmp_path, seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 7))
    eps = float(10.0 ** rng.uniform(-7, np.log10(0.5 * SNAP_TOL)))
    state = rng.bit_generator.state
    exact_text, _ = chain_urdf(rng, n)
    rng.bit_generator.state = state
    pert_text, touched = chain_urdf(rng, n, perturb=eps)
    exact = baseparams.analyze(_load(tmp_path, exact_text, "exact.urdf"))
    assert exact.practical is None  # an exact file is analysed as it is
    pert = _load(tmp_path, pert_text, "pert.urdf")
    literal = baseparams.analyze(pert, literal=True)
    practical = baseparams.analyze(pert)
    assert practical.n_base == exact.n_base
    assert literal.n_base >= exact.n_base
    if literal.n_base > exact.n_base:
        assert practical.practical is not None
        # an undecided literal count (no gap) is no count: None
        decided = literal.status.ok
        assert practical.practical.literal_n_base == (literal.n_base if decided else None)
        named = {s.joint for s in practical.practical.snaps}
        assert named and named <= set(touched)
        note = practical.practical.note(practical.n_base)
        assert (f"{literal.n_base} -> {exact.n_base}" if decided else "not decided") in note and "--literal" in note
    else:
        assert practical.practical is None


@pytest.mark.parametrize("digits", [4, 5])
def test_rounded_decimals_in_a_file(tmp_path, digits):
    """pi/2 written as 1.5708 or 1.57080: the count of the exact arm, every time."""
    for seed in range(4):
        rng = np.random.default_rng(100 + seed)
        state = rng.bit_generator.state
        exact_text, _ = chain_urdf(rng, 6)
        rng.bit_generator.state = state
        rounded_text, _ = chain_urdf(rng, 6, digits=digits)
        exact = baseparams.analyze(_load(tmp_path, exact_text, "e.urdf"))
        rounded = baseparams.analyze(_load(tmp_path, rounded_text, "r.urdf"))
        assert rounded.n_base == exact.n_base


@pytest.mark.shared
def test_a_generic_small_angle_beyond_the_tolerance_is_taken_literally(tmp_path):
    """0.01 rad is a design, not a rounding: counted as the file states it."""
    text = PANDA.read_text().replace('rpy="0 0 0"/>', 'rpy="0.01 0 0"/>', 1)
    a = baseparams.analyze(_load(tmp_path, text))
    assert a.practical is None and a.n_base == 45


@pytest.mark.shared
def test_tilted_panda_counts_43_naming_joint_1(tmp_path):
    text = PANDA.read_text().replace('<origin xyz="0 -0 0.333" rpy="0 0 0"/>',
                                     '<origin xyz="0 -0 0.333" rpy="7.3e-06 0 0"/>')
    assert "7.3e-06" in text
    path = tmp_path / "tilted.urdf"
    path.write_text(text)
    robot = baseparams.load(str(path))
    a = baseparams.analyze(robot)
    assert a.n_base == 43 and a.status == "certified"
    assert [s.joint for s in a.practical.snaps] == ["panda_joint1"]
    assert baseparams.analyze(robot, literal=True).n_base == 45
    j = a.to_json()
    assert j["practical"]["literal_n_base"] == 45 and j["practical"]["counted_out"] == 2
    assert j["practical"]["snaps"][0]["joint"] == "panda_joint1"
    assert abs(j["practical"]["snaps"][0]["deviation"] - 7.3e-6) < 1e-9
    # the exact file is untouched
    assert baseparams.analyze(baseparams.load(str(PANDA))).practical is None


@pytest.mark.shared
def test_cli_says_it_and_literal_flag_gives_the_literal_count(tmp_path, capsys):
    text = PANDA.read_text().replace('rpy="-1.5707963267948966 0 0"', 'rpy="-1.5708 0 0"')
    text = text.replace('<origin xyz="0 -0 0.333" rpy="0 0 0"/>', '<origin xyz="0 -0 0.333" rpy="0 3.1416 0"/>')
    path = tmp_path / "rounded.urdf"
    path.write_text(text)
    assert main(["analyze", str(path)]) == 0
    out = capsys.readouterr().out
    assert "43 base parameters" in out and "practical identifiability" in out and "panda_joint1" in out
    assert main(["analyze", str(path), "--literal", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["n_base"] > 43 and j["practical"] is None


def test_rpy_round_trip_and_no_candidates_on_exact_values():
    rng = np.random.default_rng(0)
    for _ in range(50):
        a = rng.uniform(-3, 3, 3)
        a[1] = rng.uniform(-1.5, 1.5)
        np.testing.assert_allclose(rotation(rpy(rotation(a))), rotation(a), atol=1e-12)
    assert near_special(baseparams.load("puma560")) == []
