"""Identification on simulated data: noise-free recovery, statistics, drives, physical consistency."""

import numpy as np
import pytest

import baseparams
from baseparams.errors import BaseparamsError
from baseparams.ident import accumulate, fit
from baseparams.ident.drives import MotorCoupling
from baseparams.ident.model import ident_model
from baseparams.ident.simulate import add_noise, fourier_trajectory


def _simulate(name, rows, rng, duration=20.0, rate=100.0, amplitude=0.6, friction=("viscous", "coulomb", "offset")):
    robot = baseparams.load(name)
    model = ident_model(baseparams.analyze(robot, rows=rows), friction=friction)
    t, q, dq, ddq = fourier_trajectory(model.state_columns, duration, rate, rng, amplitude=amplitude)
    delta = np.abs(rng.normal(size=model.drives.n_params))
    full = baseparams.regressor(robot, q, dq, ddq)
    if not robot.has_loops:
        full = full[:, model.coords]
    sel = model.coords if not robot.has_loops else np.arange(len(model.coords))
    tau = full @ robot.parameters("paper") + model.drives.regressor(dq[:, sel], ddq[:, sel], len(model.coords)) @ delta
    return robot, model, (q, dq, ddq), tau, model.theta(robot.parameters("paper"), delta)


@pytest.mark.parametrize("name, rows, amplitude", [("puma560", "all", 0.6), ("go2", "all", 0.5),
                                                   ("go2", "joints", 0.5), ("pkm-2rru-1rrs", "all", 0.05)])
@pytest.mark.parametrize("method", ["ols", "wls"])
def test_noise_free_recovery(name, rows, amplitude, method, rng):
    """The true model parameters come back to 1e-8 relative (joint torques, base wrench, loops)."""
    robot, model, states, tau, true = _simulate(name, rows, rng, amplitude=amplitude)
    f = fit(model, accumulate(model, *states, tau, chunk=700), method)
    assert np.abs(f.theta - true).max() <= 1e-8 * np.abs(true).max()
    assert f.estimate.rms_total <= 1e-8 * np.sqrt(np.mean(tau**2))


def test_rotor_inertia_regrouping_of_a_6r_arm():
    """Puma560 with rotor inertias: 36 -> 40, Ia1 and Ia2 regroup with the first links' ZZR."""
    model = ident_model(baseparams.analyze(baseparams.load("puma560")), friction=())
    assert model.n_params == 40
    regrouped = [e for e in model.regrouping.expressions() if " + " in e or " - " in e]
    assert regrouped == ["link1.ZZR + Ia_joint1", "link2.ZZR + Ia_joint2"]


def test_noise_statistics_are_honest(rng):
    """With Gaussian noise: residual RMS ~ the noise, errors within a few standard deviations."""
    robot, model, states, tau, true = _simulate("puma560", "all", rng, duration=60.0)
    sigma = np.array([0.5, 0.5, 0.3, 0.1, 0.1, 0.05])
    f = fit(model, accumulate(model, *states, add_noise(tau, sigma, rng)), "wls")
    assert np.allclose(f.estimate.rms, sigma, rtol=0.1)
    z = (f.theta - true) / f.estimate.std
    assert np.sqrt(np.mean(z**2)) < 2.0  # ~1 for honest standard deviations
    assert np.all(f.estimate.pct_sigma > 0)


def test_held_out_prediction(rng):
    robot, model, states, tau, true = _simulate("puma560", "all", rng, duration=40.0)
    noisy = add_noise(tau, 0.2, rng)
    half = len(tau) // 2
    train = tuple(x[:half] for x in states)
    test = tuple(x[half:] for x in states)
    f = fit(model, accumulate(model, *train, noisy[:half]))
    rms, total = f.rms(*test, noisy[half:])
    assert rms.shape == (6,) and 0.15 < total < 0.3


def test_poor_excitation_names_the_parameters(rng):
    """A trajectory where one joint never moves cannot identify its parameters: one clear error."""
    robot, model, (q, dq, ddq), tau, _ = _simulate("puma560", "all", rng, duration=10.0)
    q[:, 5] = dq[:, 5] = ddq[:, 5] = 0.0
    with pytest.raises(BaseparamsError, match="do not excite.*weakest: .*joint6|link6"):
        fit(model, accumulate(model, q, dq, ddq, tau))


def test_excitation_names_the_weak_parameter(rng):
    """A column nearly a combination of two others (1e-5 apart) is named; a well-spread one is not."""
    from baseparams.ident.estimate import excitation
    from baseparams.numerics import StreamingQR

    a = rng.normal(size=(500, 5))
    assert excitation(StreamingQR(5).add(a).r, list("abcde"))[1] == []
    a[:, 3] = a[:, 0] - 2 * a[:, 1] + 1e-5 * rng.normal(size=500)
    cond, weak = excitation(StreamingQR(5).add(a).r, list("abcde"))
    assert cond > 1e4 and weak and weak[0] in ("a", "b", "d")


@pytest.mark.parametrize("min_speed", [None, 0.05])
@pytest.mark.slow
def test_chunked_identification_equals_the_whole_log(min_speed):
    """Parallel filtering chunk by chunk (overlaps of 12 cutoff periods) gives the whole log's
    estimate to 1e-10 relative, slow-sample removal and decimation included."""
    from baseparams.ident import identify
    from baseparams.ident.simulate import simulate_log

    robot = baseparams.load("puma560")
    log, _ = simulate_log(robot, duration=40, rate=500, noise=0.1, seed=4)
    whole = identify(robot, log, method="ols", memory_mb=1e4, min_speed=min_speed)
    chunked = identify(robot, log, method="ols", memory_mb=1.0, min_speed=min_speed)
    assert any("chunks of" in n for n in chunked.notes) and not any("chunks of" in n for n in whole.notes)
    assert chunked.samples == whole.samples
    assert np.abs(chunked.fit.theta - whole.fit.theta).max() <= 1e-10 * np.abs(whole.fit.theta).max()


@pytest.mark.parametrize("weights", [(1.0, 1.0), (0.7, -1.3)])
def test_coupled_motor_noise_free_recovery(weights, rng):
    """A motor driving joints 5 and 6 (velocity w . dq, torque w * y): Iam, Fvm, Fcm come back exactly.

    The torques are made without the package's drive columns: the motor's joint-side rate
    ``v = w5 dq5 + w6 dq6``, its torque ``y = Iam a + Fvm v + Fcm sign(v)`` and ``w * y`` added to
    joints 5 and 6 (the transpose of the velocity map).
    """
    robot = baseparams.load("puma560")
    m6 = MotorCoupling("m6", ("joint5", "joint6"), weights)
    model = ident_model(baseparams.analyze(robot), couplings=(m6,))
    assert model.drives.names[-3:] == ["Iam_m6", "Fvm_m6", "Fcm_m6"]
    assert model.n_params == 40 + 18 + 3  # rigid + Ia3..Ia6, friction, the coupled motor's three
    t, q, dq, ddq = fourier_trajectory(6, 20.0, 100.0, rng, amplitude=0.6)
    own = np.abs(rng.normal(size=model.drives.n_params - 3))
    motor = np.array([0.02, 0.4, 1.5])  # Iam, Fvm, Fcm
    w = np.asarray(weights)
    v, a = dq[:, 4:6] @ w, ddq[:, 4:6] @ w
    tau = baseparams.regressor(robot, q, dq, ddq) @ robot.parameters("paper")
    tau += model.drives.regressor(dq, ddq, 6)[:, :, :-3] @ own
    tau[:, 4:6] += np.outer(motor[0] * a + motor[1] * v + motor[2] * np.sign(v), w)
    f = fit(model, accumulate(model, q, dq, ddq, tau))
    true = model.theta(robot.parameters("paper"), np.r_[own, motor])
    assert np.abs(f.theta - true).max() <= 1e-8 * np.abs(true).max()
    assert np.allclose(f.theta[-3:], motor, rtol=1e-8)


def test_coupling_errors_are_one_line():
    robot = baseparams.load("puma560")
    analysis = baseparams.analyze(robot)
    with pytest.raises(BaseparamsError, match=r"not among the driven joints"):
        ident_model(analysis, couplings=(MotorCoupling("m", ("joint5", "wrist9"), (1, 1)),))
    with pytest.raises(BaseparamsError, match=r"needs rotor inertia or viscous or Coulomb"):
        ident_model(analysis, rotor=False, friction=("offset",), couplings=(MotorCoupling("m", ("joint5",), (1,)),))
    with pytest.raises(BaseparamsError, match=r"expected NAME:JOINT=WEIGHT"):
        MotorCoupling.parse("m6 joint5=1")
    with pytest.raises(BaseparamsError, match=r"non-zero"):
        MotorCoupling.parse("m6:joint5=1,joint6=0")
    assert MotorCoupling.parse(" m6: joint5=1, joint6=-2.5") == MotorCoupling("m6", ("joint5", "joint6"), (1.0, -2.5))


@pytest.mark.parametrize("frame", ["world", "body"])
def test_wrench_forces_do_the_wrench_power(frame, rng):
    """``Q . dq`` equals the wrench's power on the body's twist (force . v + moment . omega)."""
    from baseparams.kinematics.tree import forward_kinematics, wrench_forces

    robot = baseparams.load("go2")
    q, dq = rng.uniform(-0.5, 0.5, (2, 20, robot.dof))
    body = robot.n - 1
    w = rng.normal(size=(20, 6))
    Q = wrench_forces(robot, q, body, w, frame=frame)
    st = forward_kinematics(robot, q, dq)
    f, m = w[:, :3], w[:, 3:]
    if frame == "body":
        pose = st.g[:, body] @ robot.M0[body]
        f = np.einsum("sij,sj->si", pose[:, :3, :3], f)
        m = np.einsum("sij,sj->si", pose[:, :3, :3], m) + np.cross(pose[:, :3, 3], f)
    power = np.sum(f * st.V[:, body, 3:], axis=1) + np.sum(m * st.V[:, body, :3], axis=1)
    assert np.allclose(np.sum(Q * dq, axis=1), power, rtol=1e-10, atol=1e-10)
    assert np.all(Q[:, ~robot.support[:, body]] == 0)


def test_floating_base_with_measured_contact_wrenches(rng):
    """Go2, all rows (base wrench + joints): feet pushed by measured wrenches; moving them to the
    measured side, ``tau + sum J^T W = Y pi``, recovers the true parameters exactly."""
    from baseparams.kinematics.tree import wrench_forces

    robot = baseparams.load("go2")
    model = ident_model(baseparams.analyze(robot, rows="all"), rotor=False, friction=())
    t, q, dq, ddq = fourier_trajectory(robot.dof, 10.0, 100.0, rng, amplitude=0.4)
    feet = [robot.names.index(n) for n in robot.names if n.endswith("calf")] or [robot.n - 1]
    wrenches = {b: rng.normal(scale=20.0, size=(len(t), 6)) for b in feet}
    contact = sum(wrench_forces(robot, q, b, w, frame="body") for b, w in wrenches.items())
    tau = baseparams.regressor(robot, q, dq, ddq) @ robot.parameters("paper") - contact  # what is measured
    f = fit(model, accumulate(model, q, dq, ddq, tau + contact))
    true = model.theta(robot.parameters("paper"))
    assert np.abs(f.theta - true).max() <= 1e-8 * np.abs(true).max()
    # ignoring the contacts is visibly wrong
    g = fit(model, accumulate(model, q, dq, ddq, tau))
    assert np.abs(g.theta - true).max() > 1e-3 * np.abs(true).max()
