"""Sub-chains (``baseparams.model.weld``): welded joints reproduce the full robot's torques."""

import re

import numpy as np
import pytest

import baseparams
import baseparams.io.logs
from baseparams.errors import ModelError
from baseparams.model.weld import weld
from baseparams.robots.random import random_robot


def _torques(robot, q, dq, ddq):
    return np.einsum("sjp,p->sj", baseparams.regressor(robot, q, dq, ddq), robot.parameters("paper"))


@pytest.mark.parametrize("seed", range(8))
def test_welded_robot_has_the_full_robots_torques_on_the_kept_joints(seed):
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, n=7, joint_types="RP", floating=bool(seed % 2), branching=0.4)
    movable = [i for i, t in enumerate(robot.jtype) if t in "RP"]
    chosen = sorted(rng.choice(movable, size=3, replace=False))
    values = {robot.joint_names[i]: float(rng.uniform(-1, 1)) for i in chosen}
    small = weld(robot, values)
    assert small.n == robot.n - 3 and set(small.joint_names) == set(robot.joint_names) - set(values)
    s = 20
    q, dq, ddq = (np.zeros((s, robot.dof)) for _ in range(3))
    qs, dqs, ddqs = rng.uniform(-1, 1, (3, s, small.dof))
    kept = []  # coordinate indices of the kept joints in the full robot, in the small robot's order
    start = np.concatenate([[0], np.cumsum(robot.ndofs)[:-1]])
    for i in range(robot.n):
        if robot.joint_names[i] in values:
            q[:, start[i]] = values[robot.joint_names[i]]
        else:
            kept += list(range(start[i], start[i] + robot.ndofs[i]))
    q[:, kept], dq[:, kept], ddq[:, kept] = qs, dqs, ddqs
    np.testing.assert_allclose(_torques(small, qs, dqs, ddqs), _torques(robot, q, dq, ddq)[:, kept],
                               rtol=1e-9, atol=1e-9)


def test_bad_welds_are_one_line():
    robot = baseparams.load("puma560")
    with pytest.raises(ModelError, match="no joint 'nope'"):
        weld(robot, {"nope": 0.0})
    with pytest.raises(ModelError, match="cannot be welded at nan"):
        weld(robot, {robot.joint_names[0]: float("nan")})
    with pytest.raises(ModelError, match="with loops"):
        weld(baseparams.load("four-bar"), {})


def _still_wrist_log(tmp_path, wrist_moves: bool):
    from baseparams.ident.simulate import fourier_trajectory, simulate_log
    from baseparams.io.logs import write_log

    robot = baseparams.load("puma560")
    t, q, dq, ddq = fourier_trajectory(6, 20.0, 200.0, np.random.default_rng(3))
    if not wrist_moves:
        q[:, 4:], dq[:, 4:], ddq[:, 4:] = 0.3, 0.0, 0.0  # joints 5 and 6 held still at 0.3 rad
    log, _ = simulate_log(robot, trajectory=(t, q, dq, ddq), seed=3, friction=())
    return write_log(tmp_path / "log.csv", log), robot


def test_cli_identifies_a_sub_chain_with_the_still_joints_welded(tmp_path, capsys):
    import json

    from baseparams.cli import main

    path, robot = _still_wrist_log(tmp_path, wrist_moves=False)
    arm = ",".join(robot.joint_names[:4])
    assert main(["identify", "puma560", str(path), "--joints", arm, "--friction", "none", "--method", "ols",
                 "--json"]) == 0
    out = capsys.readouterr()
    d = json.loads(out.out)
    assert "welded at their logged (still) positions" in out.err
    assert set(d["train"]["rms"]) == set(robot.joint_names[:4])
    # the welded model is exact: noise-free torques reproduced up to the derivatives of the filtered states
    # (a weld at the wrong angle, 0 instead of 0.3 rad, leaves about 0.1 N m)
    assert d["train"]["rms_total"] < 1e-3


def test_cli_refuses_to_weld_a_joint_that_moves(tmp_path, capsys):
    from baseparams.cli import main

    path, robot = _still_wrist_log(tmp_path, wrist_moves=True)
    assert main(["identify", "puma560", str(path), "--joints", ",".join(robot.joint_names[:4])]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"joint '{robot.joint_names[4]}' moves in the log" in err


def test_front_door_identifies_the_same_sub_chain_as_the_cli(tmp_path, capsys):
    """``baseparams.identify(..., joints=..., weld=...)`` is ``identify --joints ... --weld ...``: same values, the
    welds said as ModelWarning warnings."""
    import json

    from baseparams.cli import main

    path, robot = _still_wrist_log(tmp_path, wrist_moves=False)
    arm = robot.joint_names[:4]
    with pytest.warns(baseparams.ModelWarning) as notes:
        ident = baseparams.identify("puma560", path, joints=arm, friction="none", method="ols")
    assert any("welded at their logged (still) positions" in str(n.message) for n in notes)
    assert ident.joints == list(arm) and ident.train["rms_total"] < 1e-3
    assert main(["identify", "puma560", str(path), "--joints", ",".join(arm), "--friction", "none", "--method", "ols",
                 "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    assert [e["value"] for e in cli["base_parameters"]] == [e["value"] for e in ident.to_json()["base_parameters"]]
    with pytest.raises(baseparams.BaseparamsError, match="weld= applies with joints="):
        baseparams.identify("puma560", path, weld={"joint5": 0.3})


def _no_fit(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("the fit started")

    monkeypatch.setattr("baseparams.ident.identify", boom)


def test_a_weld_on_a_joint_that_moves_in_the_log_is_refused_with_how_far_it_moved(tmp_path, capsys, monkeypatch):
    """``--weld`` on a joint the log shows moving: refused before the fit, naming the joint and its range, in both
    doors (was: accepted, the fit made on a robot the log contradicts)."""
    from baseparams.cli import main

    path, robot = _still_wrist_log(tmp_path, wrist_moves=True)
    q5 = baseparams.io.logs.read_log(path, robot).q[:, 4]
    span = f"range {np.ptp(q5):.3g} rad"
    _no_fit(monkeypatch)
    arm = ",".join(robot.joint_names[:4])
    assert main(["identify", "puma560", str(path), "--joints", arm, "--weld", "joint5=0.3", "--weld",
                 "joint6=0.3"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"joint 'joint5' moves in the log ({span}) and is welded at --weld joint5=0.3" in err, err
    with pytest.raises(baseparams.BaseparamsError, match=rf"joint 'joint5' moves in the log \({span}\) and is "
                                                           rf"welded at weld= joint5=0.3"):
        baseparams.identify("puma560", path, joints=arm, weld={"joint5": 0.3, "joint6": 0.3})


def test_a_weld_away_from_where_the_log_holds_the_joint_is_said_with_the_figure(tmp_path, capsys):
    from baseparams.cli import main

    path, robot = _still_wrist_log(tmp_path, wrist_moves=False)  # joints 5 and 6 held at 0.3 rad
    arm = ",".join(robot.joint_names[:4])
    assert main(["identify", "puma560", str(path), "--joints", arm, "--weld", "joint5=0.8", "--friction", "none",
                 "--method", "ols", "--json"]) == 0
    err = capsys.readouterr().err
    assert "WARNING: welded where the log does not hold them (--weld over the log's still position): joint5 at " \
           "0.8, logged still at 0.3" in err, err


@pytest.mark.parametrize("weld, words", [({"joint5": "x"}, "weld= 'joint5=?': expected NAME=VALUE"),
                                         (["joint5"], "weld= 'joint5': expected NAME=VALUE"),
                                         (["joint5=1e9"], "finite number within [-1e6, 1e6]")])
def test_bad_welds_are_refused_before_the_model_loads(weld, words, monkeypatch):
    def boom(*a, **k):
        raise AssertionError("the model was loaded")

    import sys

    monkeypatch.setattr(sys.modules["baseparams.workflow.identify"], "robot_of", boom)
    with pytest.raises(baseparams.BaseparamsError, match=re.escape(words)):
        baseparams.identify("puma560", "log.csv", joints="joint1,joint2", weld=weld)
