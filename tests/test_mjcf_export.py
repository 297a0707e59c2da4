"""``write_mjcf`` / ``identify --mjcf``: identified inertias and drive terms into a copy of an MJCF model.

The oracle is MuJoCo itself: the written file is reloaded by MuJoCo and its inverse dynamics
(``mj_inverse``) compared with the parameters' own generalized forces (the TP regressor times
the parameters plus the drive terms), and re-read by baseparams' MJCF reader. The fixture is
written here (a clone without ../shared tests the export); the Menagerie iiwa14 acceptance reads
the shared file where it is.
"""

import re
import warnings

import mujoco
import numpy as np
import pytest

from baseparams.cli import main
from baseparams.errors import BaseparamsError, ModelError
from baseparams.ident import identify
from baseparams.ident.export import identified_mjcf
from baseparams.ident.simulate import fourier_trajectory, simulate_log
from baseparams.io.mjcf import load_mjcf
from baseparams.io.mjcf_write import mjcf_inverse, write_mjcf
from baseparams.model.inertia import to_convention
from baseparams.regressor.tp import regressor
from baseparams.robots.random import random_inertia

from paths import SHARED

IIWA = SHARED / "mjcf" / "kuka_iiwa_14" / "iiwa14.xml"

#: degrees, inertias from geoms forced (inertiafromgeom="true"), a mass bound, rotated bodies, a joint
#: anchor away from its body's origin, a slide joint, a tool welded to a moving body, a static
#: pedestal welded to the world, a source damping the identification does not model, a default class
FIXTURE = """<mujoco model="fixture">
  <compiler angle="degree" inertiafromgeom="true" boundmass="0.001"/>
  <default>
    <joint damping="0.3"/>
    <default class="arm"><geom type="capsule" size="0.04"/></default>
  </default>
  <worldbody>
    <body name="pedestal" pos="0 0 0.1">
      <geom type="box" size="0.1 0.1 0.1"/>
      <body name="upper" pos="0 0 0.2" euler="10 0 30">
        <joint name="j1" axis="0 0 1"/>
        <geom class="arm" fromto="0 0 0 0.4 0 0"/>
        <body name="fore" pos="0.4 0 0" quat="0.9 0.1 0.3 0.2">
          <joint name="j2" axis="0 1 0" pos="0.05 0 0"/>
          <geom class="arm" fromto="0 0 0 0.3 0 0.1"/>
          <body name="slider" pos="0.3 0 0.1">
            <joint name="j3" type="slide" axis="1 0 0" range="-0.1 0.1"/>
            <geom type="box" size="0.05 0.03 0.02"/>
            <body name="tool" pos="0.06 0 0" euler="0 90 0">
              <geom type="sphere" size="0.03" pos="0 0 0.05"/>
            </body>
            <body name="wrist" pos="0.08 0.01 0">
              <joint name="j4" axis="1 0 0"/>
              <geom type="cylinder" size="0.02 0.04"/>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def _fixture(tmp_path):
    src = tmp_path / "robot.xml"
    src.write_text(FIXTURE)
    return src, load_mjcf(src)


def _random_params(robot, seed):
    """Physically consistent inertias in each body's link frame (khalil)."""
    rng = np.random.default_rng(seed)
    return np.concatenate([to_convention(random_inertia(rng).pseudo(), "khalil") for _ in range(robot.n)])


def _paper(robot, p):
    from baseparams.model import inertia as I

    n = I.transform(I.from_convention(p.reshape(robot.n, 10), "khalil"), robot.M0)
    return to_convention(n, "paper").ravel()


def _states(robot, seed, count=40):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.8, 0.8, (count, robot.dof)) * 0.1, rng.normal(size=(count, robot.dof)),
            rng.normal(size=(count, robot.dof)))


def _rel(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_inertias_and_drive_terms_are_what_mujoco_computes(seed, tmp_path):
    src, robot = _fixture(tmp_path)
    p = _random_params(robot, seed)
    rng = np.random.default_rng(100 + seed)
    drives = {j: {"Ia": rng.uniform(0.01, 0.1), "Fv": rng.uniform(0.05, 0.5), "Fc": None, "Fo": None}
              for j in robot.joint_names}
    out = tmp_path / "sub" / "out.xml"
    out.parent.mkdir()
    notes = write_mjcf(src, out, robot, p, "khalil", drives=drives)
    assert any("mj_inverse reproduces the parameters' own rigid-body" in n for n in notes)
    assert any('inertiafromgeom="auto"' in n for n in notes) and any("boundmass" in n for n in notes)
    # MuJoCo, an independent oracle: the written model's inverse dynamics is the parameters'
    q, dq, ddq = _states(robot, seed)
    ia = np.array([drives[j]["Ia"] for j in robot.joint_names])
    fv = np.array([drives[j]["Fv"] for j in robot.joint_names])
    back = load_mjcf(out)  # the written file re-read: the same robot, the written inertias
    assert back.names == robot.names and np.allclose(back.M0, robot.M0, atol=1e-6)
    got = mjcf_inverse(out, robot, q, dq, ddq)
    model = mujoco.MjModel.from_xml_path(str(out))
    assert _rel(got, regressor(back, q, dq, ddq) @ back.parameters("paper") + back.armature * ddq
                + model.dof_damping * dq) < 1e-10
    # ... and the identified parameters' to MuJoCo's six written digits
    assert _rel(got, regressor(robot, q, dq, ddq) @ _paper(robot, p) + ia * ddq + fv * dq) < 1e-5
    assert np.allclose(back.parameters("khalil"), p, rtol=1e-5, atol=1e-6)
    assert np.allclose(back.armature, ia, rtol=1e-5)
    assert np.allclose(model.dof_damping, fv, rtol=1e-5) and not model.dof_frictionloss.any()
    assert model.body("tool").mass[0] == 0  # welded to the slider: its share is in the slider's values
    assert model.body("pedestal").mass[0] == pytest.approx(mujoco.MjModel.from_xml_path(str(src)).body(
        "pedestal").mass[0])  # welded to the world: kept


def test_coulomb_friction_goes_to_frictionloss_and_missing_kinds_are_cleared(tmp_path):
    src, robot = _fixture(tmp_path)
    out = tmp_path / "out.xml"
    drives = {"j1": {"Fc": 0.7, "Fo": 0.2}, "j2": {"Fc": 0.4}}
    notes = write_mjcf(src, out, robot, robot.parameters("paper"), "paper", drives=drives)
    model = mujoco.MjModel.from_xml_path(str(out))
    assert np.allclose(model.dof_frictionloss, [0.7, 0.4, 0, 0])
    assert not model.dof_damping.any()  # the source's class damping 0.3: not in the identified model
    text = " ".join(notes)
    assert "damping of j1, j2, j3, j4 set to 0 (nonzero in the source" in text
    assert "Fo left out (j1 0.2)" in text
    assert "frictionloss, a soft constraint bounded by Fc" in text


def test_assets_stay_found_from_another_folder(tmp_path):
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "tet.obj").write_text("v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\n"
                                                 "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    src = tmp_path / "robot.xml"
    src.write_text(FIXTURE.replace('<compiler angle="degree"', '<compiler meshdir="meshes" angle="degree"')
                   .replace("<worldbody>", '<asset><mesh file="tet.obj"/></asset>\n  <worldbody>')
                   .replace('<geom type="sphere" size="0.03" pos="0 0 0.05"/>', '<geom type="mesh" mesh="tet"/>'))
    robot = load_mjcf(src)
    (tmp_path / "a" / "b").mkdir(parents=True)
    out = tmp_path / "a" / "b" / "out.xml"
    write_mjcf(src, out, robot, robot.parameters("paper"), "paper")
    assert 'meshdir="../../meshes"' in out.read_text()
    assert mujoco.MjModel.from_xml_path(str(out)).nmesh == 1


def test_simulated_log_identified_and_exported_reproduces_the_log(tmp_path):
    """Noise-free log with rotor inertia and viscous friction: MuJoCo's mj_inverse of OUT matches it."""
    src, robot = _fixture(tmp_path)
    log, truth = simulate_log(robot, duration=12.0, rate=250.0, amplitude=0.5, rotor=True, friction=("viscous",),
                              seed=3)
    ident = identify(robot, log, method="physical", rotor=True, friction=("viscous",))
    out = tmp_path / "out.xml"
    notes = identified_mjcf(ident, src, out, log)
    assert any("reproduces the identification's own predicted rigid-body" in n for n in notes)
    assert any("identification's own prediction on" in n for n in notes)
    rng = np.random.default_rng(3)  # simulate_log's trajectory: its first draws
    _, q, dq, ddq = fourier_trajectory(robot.dof, 12.0, 250.0, rng, amplitude=0.5)
    assert np.array_equal(q, log.q)
    after = _rel(mjcf_inverse(out, robot, q, dq, ddq), log.tau)
    before = _rel(mjcf_inverse(src, robot, q, dq, ddq), log.tau)  # the source file: its own inertias, damping
    assert after < 0.005 and after < before / 100  # the acceptance bound


def test_refusals_write_nothing(tmp_path):
    src, robot = _fixture(tmp_path)
    out = tmp_path / "out.xml"
    p = robot.parameters("paper")
    with pytest.raises(ModelError, match=r"joint 'j2': viscous friction Fv = -0.1 < 0 has no MJCF damping"):
        write_mjcf(src, out, robot, p, "paper", drives={"j2": {"Fv": -0.1}})
    with pytest.raises(ModelError, match=r"joints \['nope'\] that are not in the robot"):
        write_mjcf(src, out, robot, p, "paper", drives={"nope": {"Fv": 0.1}})
    with pytest.raises(ModelError, match="expected 40 parameters"):
        write_mjcf(src, out, robot, p[:-1], "paper")
    with pytest.raises(ModelError, match=r"\(> 1e-30\) on 64 states; not written"):
        write_mjcf(src, out, robot, _random_params(robot, 5), "khalil", tolerance=1e-30)
    with pytest.raises(BaseparamsError, match="would overwrite the input"):
        write_mjcf(src, src, robot, p, "paper")
    assert not out.exists() and src.read_text() == FIXTURE
    assert [f.name for f in tmp_path.iterdir()] == ["robot.xml"]  # no temporary left either


@pytest.mark.parametrize("change, problem", [
    (lambda n: n - 2 * n[3, 3] * np.diag([0, 0, 0, 1.0]), "mass -"),
    (lambda n: n - np.diag([0.5, 0, 0, 0]) * n[3, 3], "principal moment of inertia"),
])
def test_a_body_mjcf_cannot_hold_is_refused(change, problem, tmp_path):
    from baseparams.model import inertia as I

    src, robot = _fixture(tmp_path)
    n = I.from_convention(robot.parameters("khalil").reshape(robot.n, 10), "khalil")
    n[1] = change(n[1])
    with pytest.raises(ModelError, match=f"<body name='fore'>: {problem}"):
        write_mjcf(src, tmp_path / "out.xml", robot, to_convention(n, "khalil").ravel(), "khalil")
    assert not (tmp_path / "out.xml").exists()


def test_loops_and_floating_bases_are_refused(tmp_path):
    src = tmp_path / "free.xml"
    src.write_text("<mujoco><worldbody><body name='b'><freejoint/><geom size='0.1'/></body></worldbody></mujoco>")
    robot = load_mjcf(src)
    with pytest.raises(ModelError, match="fixed-base robots"):
        write_mjcf(src, tmp_path / "out.xml", robot, robot.parameters("paper"), "paper")


def _cli_log(tmp_path):
    src, robot = _fixture(tmp_path)
    csv = tmp_path / "log.csv"
    assert main(["simulate", str(src), str(csv), "--duration", "8", "--rate", "250", "--amplitude", "0.08",
                 "--rotor", "--friction", "viscous"]) == 0
    return src, csv


def test_cli_identify_writes_the_mjcf(tmp_path, capsys):
    src, csv = _cli_log(tmp_path)
    out = tmp_path / "identified.xml"
    capsys.readouterr()
    assert main(["identify", str(src), str(csv), "--method", "physical", "--rotor", "--friction", "viscous",
                 "--mjcf", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"baseparams: MJCF written to {out}" in err
    assert "baseparams: note: --mjcf: armature of 4 joints; damping of 4 joints set to the identified values" in err
    assert "vs the log's measured torques" in err
    assert mujoco.MjModel.from_xml_path(str(out)).dof_armature.min() > 0


@pytest.mark.parametrize("flags, model, message", [
    (["--method", "wls"], None, "--mjcf needs --method physical"),
    (["--method", "physical"], "puma560", "it needs an MJCF (.xml) or URDF (.urdf) model file"),
    (["--method", "physical"], "robot.txt", "it needs an MJCF (.xml) or URDF (.urdf) model file"),
    (["--method", "physical", "--joints", "j1,j2"], None, "--mjcf with --joints"),
])
def test_cli_refusals(flags, model, message, tmp_path, capsys):
    src, csv = _cli_log(tmp_path)
    if model == "robot.txt":
        (tmp_path / model).write_text(FIXTURE)
        model = str(tmp_path / model)
    code = main(["identify", model or str(src), str(csv), "--mjcf", str(tmp_path / "o.xml"), *flags])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert "--joints" in flags or "nothing was fitted" in err  # refused by the preflight
    assert not (tmp_path / "o.xml").exists()


@pytest.mark.parametrize("joints", ["slide x, slide z, hinge y", "free"])
def test_a_robot_the_writer_refuses_is_refused_before_the_fit(joints, tmp_path, capsys, monkeypatch):
    """``identify ROBOT LOG --method physical --urdf out.urdf --mjcf out.xml`` on a body of several joints (an MJCF
    slide+slide+hinge, a URDF planar joint) fitted, wrote the URDF, then refused the MJCF with exit 2: the robot
    says it before any fit. Refused in one line, nothing fitted, nothing written."""
    import sys

    body = ("<joint name='sx' type='slide' axis='1 0 0'/><joint name='sz' type='slide' axis='0 0 1'/>"
            "<joint name='hy' type='hinge' axis='0 1 0'/>") if joints != "free" else "<freejoint/>"
    src = tmp_path / "robot.xml"
    src.write_text(f"<mujoco><worldbody><body name='b'>{body}<geom size='0.1' mass='1'/><body name='c' pos='0.3 0 0'>"
                   "<joint name='h2' type='hinge' axis='0 1 0'/><geom size='0.05' mass='0.5'/></body></body>"
                   "</worldbody></mujoco>")
    csv = tmp_path / "log.csv"
    assert main(["simulate", str(src), str(csv), "--duration", "4", "--rate", "200"]) == 0
    monkeypatch.setattr(sys.modules["baseparams.workflow.identify"], "_run_identification",
                        lambda *a, **k: pytest.fail("fitted before the export's refusal"))
    capsys.readouterr()
    code = main(["identify", str(src), str(csv), "--method", "physical", "--mjcf", str(tmp_path / "o.xml")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--mjcf writes" in err[0], err
    assert not (tmp_path / "o.xml").exists()


def test_cli_mjcf_suffix_is_checked_first(tmp_path, capsys):
    src, csv = _cli_log(tmp_path)
    assert main(["identify", str(src), str(csv), "--method", "physical", "--mjcf", str(tmp_path / "o.urdf")]) != 0
    err = capsys.readouterr().err
    assert "--mjcf" in err and ".xml" in err


@pytest.mark.shared
def test_iiwa14_acceptance(tmp_path):
    """Menagerie iiwa14, noise-free log with rotor inertia and viscous friction: OUT.xml reproduces it to 0.5 %."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its mesh files are not in the shared folder: stripped
        robot = load_mjcf(IIWA)
    log, _ = simulate_log(robot, rotor=True, friction=("viscous",), seed=1)
    ident = identify(robot, log, method="physical", rotor=True, friction=("viscous",))
    out = tmp_path / "OUT.xml"
    notes = identified_mjcf(ident, IIWA, out, log)
    assert any("the copy is written without the stripped asset files" in n for n in notes)
    _, q, dq, ddq = fourier_trajectory(robot.dof, 20.0, 500.0, np.random.default_rng(1), amplitude=0.5)
    model = mujoco.MjModel.from_xml_path(str(out))  # loads as written: default options, contacts included
    data = mujoco.MjData(model)
    got = np.empty_like(q)
    for k in range(len(q)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k], dq[k], ddq[k]
        mujoco.mj_inverse(model, data)
        got[k] = data.qfrc_inverse
    assert _rel(got, log.tau) < 0.005  # the acceptance bound; measured: 1e-6
    assert _rel(got, log.tau) < 1e-4


def test_identified_mjcf_needs_a_physical_fit_of_every_joint(tmp_path):
    src, robot = _fixture(tmp_path)
    log, _ = simulate_log(robot, duration=6.0, rate=250.0, amplitude=0.3, friction=("viscous",), seed=4)
    ident = identify(robot, log, method="ols", friction=("viscous",))
    with pytest.raises(BaseparamsError, match="--mjcf needs --method physical"):
        identified_mjcf(ident, src, tmp_path / "out.xml", log)
    assert not (tmp_path / "out.xml").exists()


def test_a_body_mujoco_refuses_is_named_and_nothing_written(tmp_path):
    """A point mass (no rotational inertia) is consistent but MuJoCo refuses it for a moving body."""
    from baseparams.model import inertia as I

    src, robot = _fixture(tmp_path)
    n = I.from_convention(robot.parameters("khalil").reshape(robot.n, 10), "khalil")
    c = np.array([0.1, 0.02, -0.03, 1.0])
    n[1] = 2.0 * np.outer(c, c)
    with pytest.raises(ModelError, match=r"out.xml: MuJoCo refuses the identified model \(Error: .*Element name "
                                         r"'fore'.*\); not written"):
        write_mjcf(src, tmp_path / "out.xml", robot, to_convention(n, "khalil").ravel(), "khalil")
    assert not (tmp_path / "out.xml").exists()


#: a URDF: a tool link fixed to the last moving link, a link without <inertial> fixed to the base
URDF = """<?xml version="1.0"?>
<robot name="urdfarm">
  <link name="base"/>
  <link name="plate"/>
  <joint name="plate_fix" type="fixed"><parent link="base"/><child link="plate"/></joint>
  <joint name="j1" type="revolute">
    <parent link="plate"/><child link="a"/>
    <origin xyz="0 0 0.3" rpy="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="50" velocity="2"/>
    <dynamics damping="0.5" friction="0.1"/>
  </joint>
  <link name="a">
    <inertial><origin xyz="0.2 0 0" rpy="0.1 0 0"/><mass value="2"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.05" iyz="0" izz="0.05"/></inertial>
  </link>
  <joint name="j2" type="continuous">
    <parent link="a"/><child link="b"/>
    <origin xyz="0.4 0 0" rpy="0.3 0.1 0"/><axis xyz="0 1 0"/>
  </joint>
  <link name="b">
    <inertial><origin xyz="0.15 0.01 0"/><mass value="1"/>
      <inertia ixx="0.005" ixy="0.001" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
  </link>
  <joint name="tool_fix" type="fixed">
    <parent link="b"/><child link="tool"/><origin xyz="0.3 0 0" rpy="0 1.2 0"/>
  </joint>
  <link name="tool">
    <inertial><origin xyz="0 0 0.05"/><mass value="0.4"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
  </link>
</robot>
"""


def test_a_urdf_is_written_as_mjcf_through_mujocos_import(tmp_path):
    from baseparams.io.urdf import load_urdf

    src = tmp_path / "arm.urdf"
    src.write_text(URDF)
    robot = load_urdf(src)
    p = _random_params(robot, 7)
    out = tmp_path / "arm.xml"
    notes = write_mjcf(src, out, robot, p, "khalil", drives={"j1": {"Ia": 0.02, "Fv": 0.3, "Fc": 0.2},
                                                              "j2": {"Ia": 0.01, "Fv": 0.1, "Fc": None}})
    assert any("arm.urdf is a URDF: written as MuJoCo imports it" in n for n in notes)
    model = mujoco.MjModel.from_xml_path(str(out))
    assert np.allclose(model.dof_armature, [0.02, 0.01]) and np.allclose(model.dof_frictionloss, [0.2, 0])
    q, dq, ddq = _states(robot, 7)
    want = regressor(robot, q, dq, ddq) @ _paper(robot, p) + [0.02, 0.01] * ddq + [0.3, 0.1] * dq
    assert _rel(mjcf_inverse(out, robot, q, dq, ddq, frictionloss=False), want) < 1e-5
    back = load_mjcf(out)  # the MJCF re-read: the URDF's bodies (the tool fused into b), the identified values
    assert back.names == robot.names and np.allclose(back.parameters("khalil"), p, rtol=1e-5, atol=1e-6)


def test_cli_identify_writes_a_urdf_model_as_mjcf(tmp_path, capsys):
    src = tmp_path / "arm.urdf"
    src.write_text(URDF)
    csv = tmp_path / "log.csv"
    assert main(["simulate", str(src), str(csv), "--duration", "8", "--rate", "250", "--rotor", "--friction",
                 "viscous"]) == 0
    out = tmp_path / "arm.xml"
    capsys.readouterr()
    assert main(["identify", str(src), str(csv), "--method", "physical", "--rotor", "--friction", "viscous",
                 "--mjcf", str(out)]) == 0
    err = capsys.readouterr().err
    assert "is a URDF: written as MuJoCo imports it" in err and f"MJCF written to {out}" in err


@pytest.mark.shared
@pytest.mark.slow
def test_real_panda_log_exported_as_mjcf(tmp_path, capsys):
    """Real Panda data (URDF through MuJoCo's import): MuJoCo's mj_inverse of OUT reproduces the measured torques
    as well as the identification does (its residual is ~3 %)."""
    import re

    from test_urdf_export import PANDA, _panda_csv

    _, csv = _panda_csv(tmp_path)
    out = tmp_path / "panda.xml"
    assert main(["identify", str(PANDA / "panda_mdh_gaz2019.urdf"), str(csv), "--method", "physical", "--rotor",
                 "--friction", "viscous,coulomb", "--mjcf", str(out), "--output", str(tmp_path / "r.txt")]) == 0
    err = capsys.readouterr().err
    assert "armature of 7 joints; damping of 7 joints; frictionloss of 7 joints" in err
    exact = float(re.search(r"predicted rigid-body, armature and damping torques to (\S+) of", err).group(1))
    measured = float(re.search(r"vs the log's measured torques: relative RMS difference (\S+)", err).group(1))
    assert exact < 1e-5 and measured < 0.05
    assert mujoco.MjModel.from_xml_path(str(out)).dof_frictionloss.min() > 0


def test_front_door_identify_writes_the_mjcf_like_the_cli(tmp_path, capsys):
    """``bp.identify(..., mjcf=OUT)``: the CLI's ``--mjcf`` from Python, the same file, checked first."""
    import baseparams as bp

    src, csv = _cli_log(tmp_path)
    cli_out, api_out = tmp_path / "cli.xml", tmp_path / "api.xml"
    flags = {"method": "physical", "rotor": True, "friction": "viscous"}
    assert main(["identify", str(src), str(csv), "--method", "physical", "--rotor", "--friction", "viscous",
                 "--mjcf", str(cli_out)]) == 0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        bp.identify(str(src), str(csv), mjcf=api_out, **flags)
    assert any("vs the log's measured torques" in str(w.message) for w in caught)
    a, b = (mujoco.MjModel.from_xml_path(str(p)) for p in (cli_out, api_out))
    assert np.allclose(a.body_mass, b.body_mass) and np.allclose(a.dof_armature, b.dof_armature)
    assert np.allclose(a.body_inertia, b.body_inertia) and a.dof_armature.min() > 0
    # refused before the fit, nothing written: a least-squares method, a built-in model, another suffix
    for model, kw, words in ((str(src), {"method": "wls"}, 'mjcf= needs method=physical'),
                             ("puma560", flags, "needs an MJCF (.xml) or URDF (.urdf) model file"),
                             (str(src), {**flags, "mjcf": tmp_path / "o.urdf"}, "format comes from the suffix: .xml")):
        with pytest.raises(BaseparamsError, match=re.escape(words)):
            bp.identify(model, str(csv), **{"mjcf": tmp_path / "o.xml", **kw})
    assert not (tmp_path / "o.xml").exists() and not (tmp_path / "o.urdf").exists()


def test_a_urdf_whose_package_meshes_do_not_resolve_is_written_without_them(tmp_path, capsys):
    """example-robot-data and ROS URDFs name their meshes ``package://...``, which MuJoCo's import does not
    resolve: the meshes (not needed for inertias) are left out with a note, including those of links the
    import fuses into the world (the base), whose names are gone once compiled (was an AttributeError)."""
    mesh = '<collision><geometry><mesh filename="package://nowhere/meshes/{}.stl"/></geometry></collision>'
    text = URDF.replace('<link name="base"/>', f'<link name="base">{mesh.format("base")}</link>')
    text = text.replace('<link name="a">', f'<link name="a">{mesh.format("a")}')
    assert text.count("package://") == 2
    src = tmp_path / "arm.urdf"
    src.write_text(text)
    csv = tmp_path / "log.csv"
    assert main(["simulate", str(src), str(csv), "--duration", "8", "--rate", "250", "--friction", "viscous"]) == 0
    out = tmp_path / "arm.xml"
    capsys.readouterr()
    assert main(["identify", str(src), str(csv), "--method", "physical", "--friction", "viscous",
                 "--mjcf", str(out)]) == 0
    err = capsys.readouterr().err
    assert "missing asset files" in err and "package:/" in err and "written without the stripped asset files" in err
    assert f"MJCF written to {out}" in err and "Traceback" not in err
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.nmesh == 0 and model.nv == 2
