"""Measured joint sets (passive joints, some joints logged): rules U and P1-P7 against the numerics.

A set of measured joints is ``joints:NAME,...``, ``base+joints:NAME,...``, ``passive:NAME,...`` or a
list of names (:func:`baseparams.numerics.row_mask`). DRNG adds rule U (a body no measured row
sees) and P1-P7 (``docs/extended-rules.md``, "Measured rows"); the certificate is the regressor
restricted to the measured rows, dense or body by body, and never takes DRNG's word.
"""

from dataclasses import replace

import numpy as np
import pytest

import baseparams as bp
from baseparams.cli import main
from baseparams.enums import Source
from baseparams.errors import BaseparamsError
from baseparams.nullspace.certify import certify
from baseparams.nullspace.drng import DRNGResult, drng, unseen_bodies
from baseparams.nullspace.rank import block_rank
from baseparams.nullspace.structured import structured_check
from baseparams.numerics import measured_joints, row_mask, rows_spec
from baseparams.robots import get, random_robot, special_robot


def _subset(robot, rng, p=0.6, base=False):
    """A random measured set (at least one joint), as a ``joints:`` or ``base+joints:`` form."""
    names = [nm for i, nm in enumerate(robot.joint_names) if robot.jtype[i] != "F"]
    meas = [nm for nm in names if rng.random() < p] or [names[int(rng.integers(len(names)))]]
    return ("base+joints:" if base else "joints:") + ",".join(meas)


def _case(seed, types="RPUS", floating=False):
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, int(rng.integers(2, 8)), types, floating=floating, branching=0.3)
    return robot, _subset(robot, rng, base=floating and rng.random() < 0.3)


# ---------------------------------------------------------------- the forms
def test_forms_and_masks():
    robot = get("puma560")
    assert rows_spec(["joint1", "joint3"]) == "joints:joint1,joint3"
    assert rows_spec("passive:joint2") == "passive:joint2"
    assert row_mask(robot, ["joint1", "joint3"]).tolist() == [True, False, True, False, False, False]
    assert row_mask(robot, "joints: joint1 , joint3").tolist() == [True, False, True, False, False, False]
    assert row_mask(robot, "passive:joint2").tolist() == [True, False, True, True, True, True]
    assert row_mask(robot, "joints:" + ",".join(robot.joint_names)).all()
    go2 = get("go2")
    base, per = measured_joints(go2, "base+joints:" + go2.joint_names[3])
    assert base and per.sum() == 2 and row_mask(go2, "base+joints:" + go2.joint_names[3]).sum() == 7
    # a floating root named in a set is its base wrench
    assert (row_mask(go2, "joints:" + go2.joint_names[0]) == row_mask(go2, "base")).all()


def test_bad_forms_are_one_clear_line():
    robot = get("puma560")
    with pytest.raises(BaseparamsError, match=r"has no joint 'elbow'; its joints: joint1, joint2, joint3, joint4"):
        row_mask(robot, "joints:joint1,elbow")
    with pytest.raises(BaseparamsError, match="no joint named"):
        row_mask(robot, "passive:")
    with pytest.raises(BaseparamsError, match="no floating base"):
        row_mask(robot, "base+joints:joint1")
    with pytest.raises(BaseparamsError, match="unknown measured rows 'torques'"):
        row_mask(robot, "torques")
    with pytest.raises(BaseparamsError, match="list of joint names"):
        rows_spec([1, 2])
    with pytest.raises(BaseparamsError, match="not defined with loops"):
        row_mask(get("four-bar"), "passive:" + get("four-bar").joint_names[0])
    with pytest.raises(BaseparamsError, match="has no joint 'elbow'"):
        bp.analyze(robot, rows=["elbow"])


def test_cli_rows_forms(capsys):
    code = main(["analyze", "puma560", "--rows", "passive:joint2", "--json"])
    out = capsys.readouterr().out
    import json

    d = json.loads(out)
    assert code == 0 and d["rows"] == "passive:joint2" and d["status"] == "certified" and d["nullity"] == 27
    assert d["drng"]["by_rule"]["passive joint"] == 3 and d["completed"] == 0
    code = main(["analyze", "puma560", "--rows", "joints:joint1,nope"])
    err = capsys.readouterr().err
    assert code == 2 and err.strip().count("\n") == 0 and "no joint 'nope'" in err and "joint6" in err
    with pytest.raises(SystemExit):
        main(["analyze", "--help"])
    assert "passive:NAME" in capsys.readouterr().out


# ---------------------------------------------------------------- the rules on known robots
def test_first_joint_passive_loses_the_first_body():
    """Fixed base, joint 1 passive: body 1 enters no row (rule U); its ten parameters are null.

    The paper's principles already give nine of them for the PUMA (a vertical first axis: only
    ZZ1R is identifiable), so rule U adds one."""
    robot = get("puma560")
    rows = list(robot.joint_names[1:])
    assert unseen_bodies(robot, rows).tolist() == [True] + [False] * 5
    a = bp.analyze(robot, rows=rows)
    assert a.status == "certified" and a.nullity == 25 and a.by_principle["unmeasured body"] == 1
    assert not any("link1" in e["name"] or "link1" in e["expression"] for e in a.expressions())
    assert {f"link1.{p}" for p in ("XX", "ZZ", "MX", "M")} <= set(a.to_json()["unidentifiable"])


def test_puma_passive_shoulder_is_decided_geometrically():
    """Joint 2 passive: the vertical joint 1 sees links 2-6 through the moment about its axis.

    Link 2 turns about the fixed point where axes 1 and 2 meet: its first moments there are seen
    only through gravity, whose moment about the vertical axis is zero (P4, 2 new after the
    paper's), and the inertia about the horizontal axis 2 makes a couple normal to axis 1 (P5)."""
    robot = get("puma560")
    res = drng(robot, rows="passive:joint2")
    c = certify(robot, rows="passive:joint2", result=res)
    assert c.status == "certified" and c.nullity == 27 and c.completed == 0
    labels = [str(x) for x in res.columns.label[res.columns.principle == Source.PASSIVE]]
    assert any(x.startswith("P4") for x in labels) and any(x.startswith("P5") for x in labels)
    assert "passive joint: bodies link2" in res.provenance(int(np.flatnonzero(res.columns.principle
                                                                            == Source.PASSIVE)[0]))


def test_prismatic_stage_under_a_passive_hinge():
    """P-R chain, only the slide measured: the hinge's body is seen through a force along the slide."""
    b = bp.RobotBuilder("slide-hinge")
    b.add_link("carriage", joint="P", axis=(1, 0, 0), inertia=bp.Inertia(2.0, com=(0.1, 0.2, 0.0)))
    b.add_link("arm", parent="carriage", joint="R", origin=np.eye(4), axis=(0, 1, 0),
               inertia=bp.Inertia(1.0, com=(0.3, 0.1, 0.2), inertia=np.diag([0.02, 0.03, 0.04])))
    robot = b.build()
    res = drng(robot, rows="passive:" + robot.joint_names[1])
    c = certify(robot, rows="passive:" + robot.joint_names[1], result=res)
    assert c.status == "certified", c.message
    assert res.by_principle()["passive joint"] > 0


def test_lift_turn_reach_with_only_the_lift_measured():
    """A vertical lift (measured), a hinge about the lift and a horizontal slide (both passive):
    the lift's force sees no horizontal motion, so the hinge's and the slide's bodies move to
    their parents whole (P7), and DRNG alone is the nullspace."""
    b = bp.RobotBuilder("lift-turn-reach")
    pose = np.eye(4)
    pose[:3, 3] = (0.2, 0.1, 0.3)
    b.add_link("lift", joint="P", axis=(0, 0, 1), inertia=bp.Inertia(3.0, com=(0.1, 0.0, 0.1)))
    b.add_link("turn", parent="lift", joint="R", origin=pose, axis=(0, 0, 1),
               inertia=bp.Inertia(2.0, com=(0.2, 0.1, 0.0), inertia=np.diag([0.02, 0.03, 0.04])))
    b.add_link("reach", parent="turn", joint="P", origin=pose, axis=(1, 0, 0),
               inertia=bp.Inertia(1.0, com=(0.3, 0.0, 0.1), inertia=np.diag([0.01, 0.02, 0.02])))
    robot = b.build()
    rows = [robot.joint_names[0]]
    res = drng(robot, rows=rows)
    c = certify(robot, rows=rows, result=res)
    assert c.status == "certified" and c.completed == 0, c.message
    assert c.nullity == 29  # only the total mass is seen: the lift's force is M (q'' + g)
    labels = [str(x) for x in res.columns.label[res.columns.principle == Source.PASSIVE]]
    assert any(x.startswith("P7") for x in labels)


# ---------------------------------------------------------------- properties over random robots
@pytest.mark.parametrize("types, floating", [("RP", False), ("RPUS", False), ("RPUS", True), ("RPUSC", False)])
def test_random_subsets_are_complete_by_drng(types, floating):
    """DRNG + U + P1-P7 alone is the nullspace of the restricted regressor on generic random trees
    (compound joints: as complete as with every row measured)."""
    for seed in range(30):
        robot, rows = _case(seed, types, floating)
        res = drng(robot, rows=rows)
        c = certify(robot, rows=rows, result=res, seed=seed)
        assert c.status.ok and c.max_column_residual < 1e-10, (seed, rows, c.message)
        if c.completed:  # only compound joints, and no more than with every row
            assert "C" in robot.jtype and c.completed <= certify(robot, seed=seed).completed, (seed, rows)


@pytest.mark.parametrize("seed", range(0, 120, 4))
def test_special_geometry_subsets_are_never_wrong(seed):
    rng = np.random.default_rng(seed)
    robot = special_robot(rng)
    rows = _subset(robot, rng)
    res = drng(robot, rows=rows)
    c = certify(robot, rows=rows, result=res)
    assert c.status.ok, c.message  # never failed: every rule column is in the nullspace
    assert res.rank <= c.nullity == c.drng_rank + c.completed


@pytest.mark.parametrize("seed", range(6))
def test_subsets_only_add_directions(seed):
    """Fewer rows, never fewer null directions; the full set of joints is the same as all rows."""
    robot, rows = _case(seed)
    every = "joints:" + ",".join(robot.joint_names)
    assert drng(robot, rows=every).rank == drng(robot).rank
    assert certify(robot, rows=rows).nullity >= certify(robot).nullity


@pytest.mark.parametrize("seed", [1, 4, 9])
def test_nullity_matches_pinocchio_restricted_regressor(seed):
    """The nullity with passive joints is 10 n minus the rank of Pinocchio's joint-torque
    regressor restricted to the measured rows."""
    pin = pytest.importorskip("pinocchio")
    from baseparams.io.pinocchio import forces_from_pinocchio, state_to_pinocchio, to_pinocchio

    rng = np.random.default_rng(seed)
    robot = random_robot(rng, 6, "RP", branching=0.3)
    rows = _subset(robot, rng, p=0.5)
    model, mask = to_pinocchio(robot), row_mask(robot, rows)
    data = model.createData()
    q, dq, ddq = rng.uniform(-1, 1, (3, 80, robot.dof))
    ys = []
    for k in range(len(q)):
        qp, vp, ap = state_to_pinocchio(robot, q[k], dq[k], ddq[k])
        y = pin.computeJointTorqueRegressor(model, data, qp, vp, ap)
        ys.append(np.stack([forces_from_pinocchio(robot, q[k], y[:, c]) for c in range(y.shape[1])], 1)[mask])
    s = np.linalg.svd(np.concatenate(ys), compute_uv=False)
    c = certify(robot, rows=rows)
    assert c.status == "certified", c.message
    assert 10 * robot.n - c.nullity == int(np.sum(s > 1e-9 * s[0])), rows


# ---------------------------------------------------------------- the certificate is independent
def _without_a_rule_column(robot, rows):
    res = drng(robot, rows=rows)
    cols = res.columns
    for k in np.flatnonzero(cols.principle >= Source.UNSEEN):
        sub = cols.subset(np.arange(len(cols)) != k)
        r = block_rank(sub, robot.n)
        if r < res.rank:
            return res, DRNGResult(robot, sub, r, 0.0, rows=res.rows)
    return res, None


def _cases_with_rule_columns(start, count):
    """``count`` random cases, from seed ``start`` on, whose DRNG has a rule column of rank one."""
    out, s = [], start
    while len(out) < count:
        robot, rows = _case(s, "RP")
        res, short = _without_a_rule_column(robot, rows)
        if short is not None:
            out.append((robot, rows, res, short))
        s += 1
    return out


@pytest.mark.parametrize("seed", range(0, 60, 10))
def test_a_dropped_rule_column_is_completed_by_exactly_what_is_missing(seed):
    robot, rows, res, short = _cases_with_rule_columns(seed, 1)[0]
    dense = certify(robot, rows=rows, result=short, method="dense")
    assert dense.status == "completed" and dense.completed == res.rank - short.rank
    assert dense.nullity == res.rank
    chk = structured_check(robot, short, rows=rows)
    assert chk.status == "undecided" and chk.missing == res.rank - short.rank
    cert = certify(robot, rows=rows, result=short, method="structured")
    assert cert.status == "completed" and cert.nullity == res.rank


@pytest.mark.parametrize("seed", range(0, 60, 10))
def test_a_wrong_rule_column_fails(seed):
    """A rule column pushed off the nullspace (a random block on a body whose own joint is
    measured) fails both certificates."""
    robot, rows, res, _ = _cases_with_rule_columns(seed, 1)[0]
    cols = res.columns
    k = int(np.flatnonzero(cols.principle >= Source.UNSEEN)[0])
    _, measured = measured_joints(robot, rows)
    h, child, parent = cols.h.copy(), cols.child.copy(), cols.parent.copy()
    h[k] = np.random.default_rng(seed).normal(size=10)
    child[k], parent[k] = int(np.flatnonzero(measured)[-1]), -1
    bad = DRNGResult(robot, replace(cols, h=h, child=child, parent=parent, hp=cols.hp.copy()), res.rank, 0.0,
                     rows=res.rows)
    assert certify(robot, rows=rows, result=bad, method="dense").status == "failed"
    assert structured_check(robot, bad, rows=rows).status == "failed"


@pytest.mark.parametrize("seed", range(10))
def test_structured_equals_dense_with_passive_joints(seed):
    rng = np.random.default_rng(100 + seed)
    robot = random_robot(rng, int(rng.integers(3, 12)), ("R", "RP", "RPUS", "RPUSC")[seed % 4],
                         floating=bool(seed % 2), branching=0.4)
    rows = _subset(robot, rng, base=seed % 4 == 1)
    res = drng(robot, rows=rows)
    dense = certify(robot, rows=rows, result=res, method="dense")
    cert = certify(robot, rows=rows, result=res, method="structured")
    assert (cert.status, cert.nullity) == (dense.status, dense.nullity), (rows, cert.message)
    if dense.status == "certified":
        assert np.linalg.svd(cert.basis.T @ dense.basis, compute_uv=False).min() > 1 - 1e-8


def test_large_tree_with_passive_joints_is_certified_body_by_body():
    rng = np.random.default_rng(11)
    robot = random_robot(rng, 45, "RP", branching=0.3)
    rows = _subset(robot, rng, p=0.7)
    a = bp.analyze(robot, rows=rows)
    assert a.status == "certified" and "structured certificate" in a.certificate.message
    assert a.nullity == certify(robot, rows=rows, method="dense").nullity
