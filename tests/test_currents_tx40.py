"""Identification from motor currents on a real log: the Stäubli TX40's motor-side signals (issue 50).

Read from ../shared/ident/staubli_tx40_figaroh (never copied; SOURCE.md there). The log holds each
motor's torque ``y`` (current x torque constant) and its encoder angle; the gear ratios
``N = [32, 32, 45, -48, 45, 32]`` take them to the joints, motor 6 turning joints 5 and 6. Here ``y``
plays the current and ``N`` the unknown gain: identified from ``y`` alone with joint 2's ratio as
the anchor, the other ratios must come back as ``N`` (within their std), and the held-out currents
(the last 30 % of the motion) must be predicted as well as the torque-based fit, which was given
every ``N``. What the currents cannot tell is named: the wrist's rigid-body torque (0.15-0.2 N m) is
below its friction and the noise, so its three gains are not determined, and the first two joints'
rotor inertias regroup with the links' ``ZZ``.
"""

import json
import re
from dataclasses import replace

import numpy as np
import pytest

import baseparams
from baseparams.ident import identify
from baseparams.ident.drives import MotorCoupling
from baseparams.jointlog import JointLog

from paths import SHARED

pytestmark = [pytest.mark.shared, pytest.mark.slow]

TX40 = SHARED.parent / "ident" / "staubli_tx40_figaroh"
#: motor 6 is joint 6's current column and turns joints 5 and 6 (the coupling named after its column)
M6 = MotorCoupling("joint_6", ("joint_5", "joint_6"), (1.0, 1.0))


@pytest.fixture(scope="module")
def tx40():
    robot = baseparams.load(str(TX40 / "tx40_mdh_modified.urdf"))
    text = (TX40 / "T40X_config.yaml").read_text()

    def value(key):
        return json.loads(re.search(rf"^\s*-?\s*{key}\s*:\s*(.+)$", text, re.M).group(1).strip())

    ts, n, lim = value("ts"), np.array(value("N"), dtype=float), np.array(value("dq_lim_def"))
    q_motor = np.loadtxt(TX40 / "pos_read_data.csv", delimiter=",", skiprows=1)
    y = np.loadtxt(TX40 / "curr_data.csv", delimiter=",", skiprows=1)
    rq, rt = np.diag(n), np.diag(n)
    rq[5, 4], rt[4, 5] = n[5], n[5]
    q = np.linalg.solve(rq, q_motor.T).T
    q[:, 1] -= np.pi / 2  # the URDF's (MDH) zero
    q[:, 2] += np.pi / 2
    t = np.arange(len(q)) * ts
    log = JointLog(t, tuple(robot.joint_names), q, y @ rt.T, source="TX40", cur=y)
    hold = 0.3 * float(t[-1] - t[0])
    common = dict(rotor=True, couplings=(M6,), cutoff=15.0, min_speed=lim, terms="none", holdout=hold)
    ours = identify(robot, log, effort="current", gain_anchor=f"joint_2={n[1]}", **common)
    torque = identify(robot, replace(log, cur=None), method="ols", **common)
    return robot, log, n, rt, hold, ours, torque


def test_the_gear_ratios_come_back_from_the_motor_torques(tx40):
    robot, _, n, _, _, ours, _ = tx40
    g = ours.currents
    assert g.gains[1] == n[1] and np.array_equal(g.transmission.matrix[:, 5], [0, 0, 0, 0, 1, 1])
    arm = [0, 2]  # joints 1 and 3: determined (joint 2 the anchor)
    z = (g.gains[arm] - n[arm]) / g.std[arm]
    assert np.all(np.abs(z) < 3), z
    assert np.all(np.abs(g.gains[arm] / n[arm] - 1) < 0.1), g.gains / n


def test_what_the_currents_cannot_tell_is_named(tx40):
    *_, ours, _ = tx40
    g = ours.currents
    assert set(g.undetermined) == {"joint_4", "joint_5", "joint_6"}
    assert {x["members"][0] for x in g.groups if x["kind"] == "undetermined"} == {"k_joint_4", "k_joint_5",
                                                                                   "k_joint_6"}
    assert {x["members"][0] for x in g.groups if x["kind"] == "regrouped"} == {"Ia_joint_1", "Ia_joint_2"}
    line = next(x for x in ours.notes if x.startswith("gains"))
    assert line.count("NOT DETERMINED") == 3 and "joint_2 32 (anchor)" in line


def test_held_out_currents_as_well_as_the_torque_fit_given_every_ratio(tx40):
    """The last 30 % of the motion: every motor's current predicted within 10 % of the torque fit's RMS."""
    robot, log, _, rt, hold, ours, torque = tx40
    mask = log.t >= log.t[-1] - hold
    y_torque = np.linalg.solve(rt, torque.predict(log).T).T
    theirs = np.sqrt(np.mean((y_torque - log.cur)[mask] ** 2, axis=0))
    mine = np.array([ours.validation["rms"][j] for j in robot.joint_names])
    assert np.all(mine < 1.1 * theirs + 0.003), (mine, theirs)


def test_joint_side_torques_of_the_arm_agree_with_the_torque_fit(tx40):
    """Held out, the rigid-body (joint-side) torques of joints 1-3 within 15 % of their size of the torque fit's.

    (Their gains are known to 5-9 % from these 6 s of currents: 0.77, 0.89, 0.36 N m on 8.5, 23, 3.2.)
    """
    _, log, _, _, hold, ours, torque = tx40
    mask = log.t >= log.t[-1] - hold
    theta = torque.fit.theta.copy()
    nb = len(torque.model.analysis.base_names)
    theta[np.asarray(torque.model.regrouping.independent) >= nb] = 0.0
    theirs = replace(torque, fit=replace(torque.fit, theta=theta)).predict(log)[mask, :3]
    mine = ours.predict(log)[mask, :3]
    assert np.all(np.sqrt(np.mean((mine - theirs) ** 2, axis=0)) < 0.15 * np.sqrt(np.mean(theirs**2, axis=0)))
