"""Issue 11, wrong answers with no error: each test here fails on the code before the fix.

Conventions must match (a mismatch is an error, never a number), the measured rows are honoured
without certification, each convention prints its own names and frame, the regressor of a loop
robot is the closed one, and the exit codes say what certification concluded."""

from __future__ import annotations

import json

import numpy as np
import pytest

from baseparams.analysis import analyze, format_report
from baseparams.base import base_parameters, paper_from
from baseparams.cli import EXIT_FAILED, EXIT_INPUT, EXIT_OK, EXIT_UNDECIDED, main
from baseparams.errors import BaseparamsError
from baseparams.model import inertia as I
from baseparams.nullspace import drng
from baseparams.nullspace.certify import certify
from baseparams.numerics import stacked_regressor
from baseparams.robots import get, puma560, random_robot


def run(args, capsys):
    code = main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


# ---------------------------------------------------------------- 5: conventions must match
def test_parameter_vectors_name_their_convention():
    robot = puma560()
    with pytest.raises(TypeError):
        robot.parameters()  # no default: a vector always says its convention
    with pytest.raises(BaseparamsError, match="unknown parameter convention 'kahlil'"):
        robot.parameters("kahlil")


@pytest.mark.parametrize("conv", I.CONVENTIONS)
def test_base_maps_refuse_a_vector_in_another_convention(conv):
    """Before: ``bp.to_base(robot.parameters())`` mixed paper and khalil silently (Puma560
    torques rebuilt 46 N m wrong). Now the mismatch is an error and the matching call is exact."""
    robot = puma560()
    bp = base_parameters(robot, certify(robot, seed=0).basis, conv)
    other = "paper" if conv != "paper" else "khalil"
    with pytest.raises(BaseparamsError, match=f"in the '{other}' convention given to base parameters regrouped "
                                              f"in the '{conv}' convention"):
        bp.to_base(robot.parameters(other), other)
    w = stacked_regressor(robot, 20, 4)
    beta = bp.to_base(robot.parameters(conv), conv)
    tau = w @ robot.parameters("paper")
    rebuilt = (w @ paper_from(robot, conv))[:, bp.independent] @ beta
    assert np.abs(rebuilt - tau).max() <= 1e-9 * np.abs(tau).max()


# ---------------------------------------------------------------- 6: measured rows, unverified
@pytest.mark.parametrize("rows, n_base", [("joints", 84), ("base", 94), ("all", 94)])
def test_rows_are_honoured_without_certification(rows, n_base, capsys):
    code, out, _ = run(["analyze", "go2", "--rows", rows, "--no-verify", "--json"], capsys)
    d = json.loads(out)
    assert code == EXIT_OK and d["status"] == "unverified"
    assert d["n_base"] == n_base  # before: 94 for joints (the unmeasured answer)
    code, out, _ = run(["analyze", "go2", "--rows", rows, "--json"], capsys)
    c = json.loads(out)
    assert c["status"] == "certified" and c["n_base"] == n_base and c["completed"] == 0


def test_unmeasured_root_columns_are_in_the_joint_rows_nullspace():
    """On random floating trees, the root's own ten parameters are invisible to joint torques:
    certification with joint rows never fails and DRNG's joint-row rank is 10 above all rows."""
    for seed in range(6):
        robot = random_robot(np.random.default_rng(seed), 4, "RPUS", floating=True)
        res_all, res_j = drng(robot), drng(robot, rows="joints")
        assert res_j.rank == res_all.rank + 10
        assert res_j.by_principle()["unmeasured root"] == 10
        c = certify(robot, seed=seed, rows="joints", result=res_j)
        assert c.certified and c.max_column_residual < 1e-10, c.message


# ---------------------------------------------------------------- 7: each convention's own header
@pytest.mark.parametrize("conv", I.CONVENTIONS)
def test_report_header_names_the_conventions_own_order_and_frame(conv):
    text = format_report(analyze(puma560(), convention=conv))
    header = [ln for ln in text.splitlines() if ln.startswith("base parameters (")][0]
    assert f"{conv} convention" in header and " ".join(I.NAMES[conv]) in header
    assert ("world frame at q = 0" in header) == (conv == "paper")
    assert ("link frame" in header) == (conv != "paper")


# ---------------------------------------------------------------- 8: regressor closes the loops
def test_regressor_of_a_loop_robot_is_closed(capsys):
    code, out, _ = run(["regressor", "four-bar", "--samples", "40", "--json"], capsys)
    d = json.loads(out)
    robot = get("four-bar")
    assert code == EXIT_OK and d["closed_loops"] is True
    assert d["shape"][1:] == [len(robot.actuated), 10 * robot.n] == [1, 30]  # before: 3 (the open tree)
    assert 30 <= d["kept"] <= 40 and d["shape"][0] == d["kept"]


# ---------------------------------------------------------------- 11: exit codes and edge input
def test_undecided_certification_exits_3(capsys):
    code, out, err = run(["analyze", "puma560", "--samples", "3"], capsys)
    assert code == EXIT_UNDECIDED == 3 and "UNDECIDED" in out and "certification UNDECIDED" in err


def test_failed_certification_exits_4(monkeypatch, capsys):
    """A column outside the nullspace (injected) must make the command fail, not exit 0."""
    import baseparams.analysis as A
    from baseparams.nullspace import Columns, DRNGResult, block_rank

    real = A.drng

    def bad_drng(robot, **kw):
        res = real(robot, **kw)
        h = np.zeros((1, 10))
        h[0, 9] = 1.0  # the last body's mass alone: seen by the torques
        cols = Columns.concat([res.columns, Columns(h, np.array([robot.n - 1]), np.array([-1]), np.array([0]),
                                                    np.array([robot.n - 1]), np.array(["bogus"], dtype=object))])
        return DRNGResult(robot, cols, block_rank(cols, robot.n), res.seconds, res.extended)

    monkeypatch.setattr(A, "drng", bad_drng)
    code, out, err = run(["analyze", "puma560"], capsys)
    assert code == EXIT_FAILED == 4 and "FAILED" in out and "certification FAILED" in err


def test_bad_options_are_one_line_errors(tmp_path, capsys):
    code, out, err = run(["analyze", "puma560", "--output", str(tmp_path / "missing" / "r.txt")], capsys)
    assert code == EXIT_INPUT and "does not exist" in err and "Traceback" not in err
    assert main(["analyze", "puma560", "--seed", "-1"]) == 2
    assert "--seed must be an integer in [0, " in capsys.readouterr().err


def test_a_model_with_no_moving_link_is_an_empty_certified_result(tmp_path, capsys):
    f = tmp_path / "static.urdf"
    f.write_text('<robot name="static"><link name="base"><inertial><mass value="1"/>'
                 '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link></robot>')
    code, out, _ = run(["analyze", str(f), "--json"], capsys)
    d = json.loads(out)
    assert code == EXIT_OK and d["n_base"] == 0 and d["n_params"] == 0 and d["certified"] is True
    code, out, _ = run(["analyze", str(f)], capsys)
    assert code == EXIT_OK and "--floating" in out and "0 base parameters" in out
    code, out, _ = run(["analyze", str(f), "--floating", "--json"], capsys)
    assert code == EXIT_OK and json.loads(out)["n_base"] == 10  # a free body: all ten identifiable
