"""Units and plausibility before fitting: wrong units refused naming the column, real logs pass."""

from dataclasses import replace

import numpy as np
import pytest

import baseparams
from baseparams.cli import main
from baseparams.errors import DataError
from baseparams.ident.pipeline import identify
from baseparams.ident.simulate import simulate_log
from baseparams.io.logs import read_log, write_log


@pytest.fixture(scope="module")
def sim():
    robot = baseparams.load("puma560")
    log, _ = simulate_log(robot, duration=10.0, rate=200.0, noise=0.05)
    return robot, log


def _bad_torque(log):
    tau = log.tau.copy()
    tau[100, 2] = 1e308
    return replace(log, tau=tau)


CASES = {
    "deg/s velocities": (lambda log: replace(log, dq=log.dq * 180 / np.pi), "column dq_joint1", "deg/s"),
    "ms time": (lambda log: replace(log, t=log.t * 1000), "column t", "milliseconds"),
    "mN m torques": (lambda log: replace(log, tau=log.tau * 1000), "column tau_", "mN m"),
    "kN m torques": (lambda log: replace(log, tau=log.tau / 1000), "column tau_", "kN m"),
    "degree positions": (lambda log: replace(log, q=log.q * 180 / np.pi), "column q_joint1", "degrees"),
    "degree positions, no dq": (lambda log: replace(log, q=log.q * 180 / np.pi, dq=None), "column q_", "degrees"),
    "a 1e308 sample": (_bad_torque, "column tau_joint3, sample 100", "plausible"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_wrong_units_refused_naming_the_column(sim, case):
    robot, log = sim
    change, column, unit = CASES[case]
    with pytest.raises(DataError, match="allow-units") as exc:
        identify(robot, change(log))
    msg = str(exc.value)
    assert log.source in msg and column in msg and unit in msg, msg


def test_clean_log_passes_and_allow_units_goes_on(sim):
    robot, log = sim
    res = identify(robot, log)
    assert any(n.startswith("units: checked") for n in res.notes)
    res = identify(robot, replace(log, dq=log.dq * 180 / np.pi), allow_units=True)
    assert any(n.startswith("units: WARNING") for n in res.notes)


def test_cli_refuses_in_one_line_and_allow_units(sim, tmp_path, capsys):
    robot, log = sim
    path = write_log(tmp_path / "mnm.csv", replace(log, tau=log.tau * 1000))
    assert main(["identify", "puma560", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("baseparams: error: ") and "mN m" in err[0]
    assert main(["identify", "puma560", str(path), "--allow-units"]) == 0


def test_boolean_parquet_velocities_refused(sim, tmp_path):
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    robot, log = sim
    cols = {"t": log.t}
    for k, j in enumerate(log.joints):
        cols[f"q_{j}"] = log.q[:, k]
        cols[f"dq_{j}"] = log.dq[:, k] > 0 if k == 1 else log.dq[:, k]
        cols[f"tau_{j}"] = log.tau[:, k]
    path = tmp_path / "bool.parquet"
    pq.write_table(pa.table(cols), path)
    with pytest.raises(DataError, match="dq_joint2.*booleans"):
        read_log(path, robot)


@pytest.mark.shared
def test_real_panda_log_not_flagged():
    from baseparams.ident.data import JointLog

    from paths import IDENT

    panda = IDENT / "panda_gaz2019"
    robot = baseparams.load(str(panda / "panda_mdh_gaz2019.urdf"))
    sig = {k: np.loadtxt(panda / f"exciting_traj_{f}.txt").reshape(-1, 7)
           for k, f in (("q", "positions"), ("dq", "velocity"), ("tau", "torques"))}
    log = JointLog(np.loadtxt(panda / "exciting_traj_time.txt"), tuple(robot.joint_names), sig["q"], sig["tau"],
                   dq=sig["dq"], source="panda")
    res = identify(robot, log)  # the TX40's: tests/test_tx40.py identifies it with the checks on
    assert any(n.startswith("units: checked") for n in res.notes)
