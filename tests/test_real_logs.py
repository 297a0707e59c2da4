"""Identification on real logs recorded by others (read from ../shared/ident, never copied).

Franka Emika Panda (Gaz et al. 2019): identify on the first 14.5 s with friction, predict the
last 6 s. The reference is a plain OLS with the same model computed independently: Pinocchio's
joint-torque regressor of the same URDF plus viscous, Coulomb and offset friction columns, on the
same preprocessed samples (the same filter on torques and regressor columns), numpy's lstsq.
"""

import numpy as np
import pinocchio as pin
import pytest

import baseparams
from baseparams.ident import identify
from baseparams.ident.preprocess import prepare
from baseparams.io.logs import read_log
from baseparams.jointlog import JointLog

from oracles import lowpass_score
from paths import SHARED

pytestmark = pytest.mark.shared

PANDA = SHARED.parent / "ident" / "panda_gaz2019"
URDF = PANDA / "panda_mdh_gaz2019.urdf"


@pytest.fixture(scope="module")
def panda(tmp_path_factory):
    """The Panda log converted to the default layout (the user's step: single-column, sample-major files)."""
    robot = baseparams.load(str(URDF))
    sig = {k: np.loadtxt(PANDA / f"exciting_traj_{f}.txt").reshape(-1, 7)
           for k, f in (("q", "positions"), ("dq", "velocity"), ("tau", "torques"))}
    t = np.loadtxt(PANDA / "exciting_traj_time.txt")
    path = tmp_path_factory.mktemp("panda") / "panda.csv"
    header = ["t"] + [f"{k}_{j}" for k in sig for j in robot.joint_names]
    np.savetxt(path, np.column_stack([t, *sig.values()]), delimiter=",", header=",".join(header), comments="",
               fmt="%.17g")
    log = read_log(path, robot)
    train = _span(log, 0.0, 14.5)
    test = _span(log, log.t[-1] - 6.0, np.inf)
    return robot, train, test


def _span(log: JointLog, t0: float, t1: float) -> JointLog:
    keep = (log.t >= t0) & (log.t <= t1)
    return JointLog(log.t[keep], log.joints, log.q[keep], log.tau[keep], dq=log.dq[keep], source=log.source)


def _pinocchio_ols(robot, train, test, cutoff, factor):
    """Plain OLS on Pinocchio's regressor + friction, parallel-filtered like ours; held-out RMS."""
    model = pin.buildModelFromUrdf(str(URDF))
    data = model.createData()
    order = [robot.joint_names.index(model.names[k]) for k in range(1, model.njoints)]

    def system(log):
        prep = prepare(log, cutoff=cutoff, decimate=factor)
        f = prep.full
        q, dq, ddq = (x[:, order] for x in (f.q, f.dq, f.ddq))
        rows = [pin.computeJointTorqueRegressor(model, data, q[k], dq[k], ddq[k]).copy() for k in range(len(q))]
        fr = np.zeros((len(q), 7, 21))
        for j in range(7):
            fr[:, j, 3 * j:3 * j + 3] = np.stack([dq[:, j], np.sign(dq[:, j]), np.ones(len(q))], axis=1)
        a = prep.apply(np.concatenate([np.array(rows), fr], axis=2))
        return a, prep.tau[:, order]

    a, b = system(train)
    x = np.linalg.lstsq(a.reshape(-1, a.shape[2]), b.reshape(-1), rcond=None)[0]
    a2, b2 = system(test)
    return float(np.sqrt(np.mean((a2 @ x - b2) ** 2)))


def test_panda_held_out_prediction(panda):
    robot, train, test = panda
    ours = identify(robot, train, method="ols", validation=test, terms="none")
    assert ours.samples["read"] == train.n_samples
    assert ours.model.n_params == 43 + 21  # the published structural count: 43 + 3 friction terms per joint
    cutoff = float(next(n for n in ours.notes if n.startswith("low-pass")).split("cutoff ")[1].split(" Hz")[0])
    ref = _pinocchio_ols(robot, train, test, cutoff, None)
    rms = _filtered_rms(ours, test, cutoff)
    assert rms <= 1.01 * ref  # at most the independent OLS (same data, same filter)
    # N m; the published parameter set gives ~0.30 on these samples. Every held-out sample counts, the log's
    # ends too since issue 48 (they were trimmed: 0.099 then), where the independent OLS scores ~0.102 as well
    assert rms < 0.105
    # the reported validation: every held-out sample, against the raw measured torques
    v = ours.validation
    assert v["samples"] == test.n_samples
    raw = np.sqrt(np.mean((ours.predict(test) - test.tau) ** 2))
    assert v["rms_total"] == pytest.approx(raw, rel=1e-9)
    assert 0.2 < v["rms_total"] < 0.35  # the sensor's content above the motion's band is ~0.27 N m alone
    phys = identify(robot, train, method="physical", validation=test, terms="none")
    assert phys.fit.physical.feasible and np.all(phys.fit.physical.masses > 0)
    assert _filtered_rms(phys, test, cutoff) <= 1.25 * rms


def _filtered_rms(result, test, cutoff):
    """Held-out RMS in the fit's own domain: test log filtered like the training log, our regressor."""
    prep = prepare(test, cutoff=cutoff)
    f = prep.full
    a = prep.apply(result.model.regressor(f.q, f.dq, f.ddq))
    return float(np.sqrt(np.mean((a @ result.fit.theta - prep.tau) ** 2)))


@pytest.fixture(scope="module")
def panda_whole(tmp_path_factory):
    """The whole Panda log (the measure of the identification issue holds out its last 6 s)."""
    robot = baseparams.load(str(URDF))
    sig = {k: np.loadtxt(PANDA / f"exciting_traj_{f}.txt").reshape(-1, 7)
           for k, f in (("q", "positions"), ("dq", "velocity"), ("tau", "torques"))}
    t = np.loadtxt(PANDA / "exciting_traj_time.txt")
    return robot, JointLog(t, robot.joint_names, sig["q"], sig["tau"], dq=sig["dq"], source="panda")


@pytest.mark.parametrize("method, limit", [("auto", 0.075), ("physical", 0.080)])
@pytest.mark.slow
def test_panda_model_terms_beat_least_squares_on_the_held_out_part(panda_whole, method, limit):
    """The issue's measure (last 6 s held out, predictions at every held-out sample against the measured
    torques low-passed at 5 Hz by an outsider's filtfilt): the model class with the terms the training span's
    cross-validation keeps beats the independent OLS (0.0953) by far; the terms are the physical ones."""
    robot, log = panda_whole
    res = identify(robot, log, method=method, holdout=6.0)
    mask = log.t >= log.t[-1] - 6.0
    pred = res.predict(log)[mask]
    score = lowpass_score(log.t, log.tau, pred, mask)
    assert score <= limit
    kept = {t.name: t for t in res.fit.terms}
    assert {"dahl", "tilt"} <= set(kept)
    assert 0.1 < kept["tilt"].tilt_degrees() < 0.5  # the mounting tilt measured outside: 0.2-0.3 degree
    assert np.all((kept["dahl"].delta >= 2e-4) & (kept["dahl"].delta <= 1e-2))  # pre-sliding: ~2 mrad
    # the choices are reported: every term tried, with its cross-validated figure
    assert {c.name for c in res.fit.term_choices} == {"dahl", "tilt", "delay", "scale", "rotor"}
    rotor = next(c for c in res.fit.term_choices if c.name == "rotor")  # blocks of 1.4 periods: not tried
    assert not rotor.kept and "not tried" in rotor.why
    assert any(n.startswith("model terms") for n in res.notes)
    # the raw held-out figure is what an outsider computes from the predictions
    raw = np.sqrt(np.mean((pred - log.tau[mask]) ** 2))
    assert res.validation["rms_total"] == pytest.approx(raw, rel=1e-9)
    if method == "auto":
        plain = identify(robot, log, method="ols", holdout=6.0, terms="none")
        assert score < 0.85 * lowpass_score(log.t, log.tau, plain.predict(log)[mask], mask)
