"""The default estimate (``method="auto"``) generalizes to motions it was not trained on.

Simulated Puma560 logs: the true robot is the model file with every body's mass, centre of
mass and rotational inertia perturbed by up to 30 % (physically consistent), the torques carry
AR(1) noise (rho 0.95, like real logs' residuals), and the identified model is validated on
*another* trajectory (larger and longer), noise-free, against the raw torques. The reference is
plain OLS on the same training log.

* A short, poorly exciting log (4.7 s, +-0.25 rad: the situation of a robot recorded briefly):
  OLS fits noise along the weak directions and predicts the other motion badly; the prior must
  help a lot.
* A rich log (20 s, +-1 rad): the data determine the parameters; the prior must not bias them
  (no worse than OLS).
"""

from dataclasses import replace

import numpy as np
import pytest

import baseparams
from baseparams.ident import accumulate_prepared, identify, log_columns
from baseparams.ident.preprocess import prepare
from baseparams.ident.select import prior_covariance, prior_precision, ridge, select, split_blocks
from baseparams.ident.simulate import fourier_trajectory, simulate_log


def _perturbed(robot, rng, s=0.3):
    """The robot with each body's mass, CoM and inertia about the CoM perturbed by up to ``s``."""
    kh = robot.parameters("khalil").reshape(robot.n, 10)
    out = []
    for k in kh:
        m = k[9]
        c = k[6:9] / m
        i_o = np.array([[k[0], k[1], k[2]], [k[1], k[3], k[4]], [k[2], k[4], k[5]]])
        i_c = i_o - m * (c @ c * np.eye(3) - np.outer(c, c))
        size = np.sqrt(np.trace(i_o) / (2 * m))
        m2 = m * rng.uniform(1 - s, 1 + s)
        c2 = c + rng.normal(scale=s * size / 2, size=3)
        i2 = i_c * rng.uniform(1 - s, 1 + s) + m2 * (c2 @ c2 * np.eye(3) - np.outer(c2, c2))
        out.append([i2[0, 0], i2[0, 1], i2[0, 2], i2[1, 1], i2[1, 2], i2[2, 2], *(m2 * c2), m2])
    return robot.with_parameters(np.array(out).reshape(-1), "khalil")


def _ar1(tau, rng, rho=0.95, std=0.3):
    e = np.zeros_like(tau)
    e[0] = rng.normal(size=tau.shape[1]) * std
    xi = rng.normal(size=tau.shape) * std * np.sqrt(1 - rho**2)
    for k in range(1, len(e)):
        e[k] = rho * e[k - 1] + xi[k]
    return tau + e


def _case(seed, duration, amplitude):
    nominal = baseparams.load("puma560")
    true = _perturbed(nominal, np.random.default_rng(seed))
    traj = fourier_trajectory(nominal.dof, duration, 500.0, np.random.default_rng(100 + seed), amplitude=amplitude)
    log, _ = simulate_log(true, seed=seed, trajectory=traj)
    log = replace(log, tau=_ar1(log.tau, np.random.default_rng(200 + seed)))
    other = fourier_trajectory(nominal.dof, 10.0, 500.0, np.random.default_rng(300 + seed), amplitude=1.0)
    val, _ = simulate_log(true, seed=seed, trajectory=other)  # same drive terms (same seed), no noise
    return nominal, log, val


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_poorly_exciting_log_the_prior_generalizes(seed):
    nominal, log, val = _case(seed, 4.7, 0.25)
    ols = identify(nominal, log, method="ols", validation=val).validation["rms_total"]
    auto = identify(nominal, log, validation=val)
    assert auto.fit.selection is not None and auto.fit.selection.lam > 0  # the prior was chosen
    assert auto.validation["rms_total"] < 0.7 * ols  # measured: 0.09-0.59 x


@pytest.mark.parametrize("seed", [3, 4])
@pytest.mark.slow
def test_rich_log_the_prior_does_not_bias(seed):
    nominal, log, val = _case(seed, 20.0, 1.0)
    ols = identify(nominal, log, method="ols", validation=val).validation["rms_total"]
    auto = identify(nominal, log, validation=val)
    assert auto.validation["rms_total"] <= 1.05 * ols  # measured: 0.5-0.9 x
    assert any(n.startswith("default estimate: ") and "cross-validation" in n for n in auto.notes)
    j = auto.to_json()
    assert j["selection"]["weighting"] in ("ols", "wls") and j["estimator"].startswith("auto: ")
    from baseparams.report.html import identification_html

    page = identification_html(auto)  # the HTML report says how it was computed too
    assert "How it was computed" in page and "default estimate: " in page and j["covariance"][:20] in page


def test_prior_covariance_is_the_regrouped_body_scales():
    """S = G J D J^T G^T is positive definite; a determined term keeps its value, an undetermined one the file's."""
    robot = baseparams.load("puma560")
    nominal, log, _ = _case(0, 20.0, 1.0)
    res = identify(nominal, log, method="ols")
    model = res.model
    s = prior_covariance(model)
    assert np.allclose(s, s.T) and np.linalg.eigvalsh(s).min() > 0
    p = prior_precision(model)
    assert np.all(p[model.n_base:] == 0) and np.all(p[:, model.n_base:] == 0)  # no prior on drive terms
    # the shrink of a direction is var_LS / (var_LS + var_prior / lam): exact on a diagonal toy system
    r11 = np.diag([1e3, 1e-3])
    theta0 = np.array([1.0, 1.0])
    est = ridge(r11, r11 @ np.array([2.0, 2.0]), theta0, np.eye(2))
    assert est[0] == pytest.approx(2.0, rel=1e-5)  # information 1e6 >> 1: keeps its value
    assert est[1] == pytest.approx(1.0, rel=1e-5)  # information 1e-6 << 1: the prior's
    assert robot.n == model.robot.n


def test_selection_rejects_a_strong_prior_when_the_file_is_wrong():
    """A file 5x off loses the cross-validation at the strong weights: at most a weak prior is kept."""
    nominal, log, _ = _case(5, 20.0, 1.0)
    res = identify(nominal, log, method="ols")
    model = res.model
    prep = prepare(log)
    parts: list = []
    acc, _ = accumulate_prepared(model, prep, log_columns(model, log), 128.0, log, None, parts_out=parts)
    wrong = model.theta(nominal.parameters("paper")) * 5.0  # every base parameter 5x: a bad file
    ones = np.ones(len(model.coords))
    sel = select(split_blocks(parts), {"ols": ones}, wrong, prior_precision(model))
    rms = sel.cv_rms["ols"]
    assert rms[-1] > 1.05 * rms[0]  # trusting the wrong file to 10 % predicts worse than no prior
    assert sel.lam <= 10.0 and rms[sel.lambdas.index(sel.lam)] <= rms[0]
    right = select(split_blocks(parts), {"ols": ones}, model.theta(nominal.parameters("paper")), prior_precision(model))
    assert right.lam >= sel.lam  # the right file is trusted at least as much
    no_prior = select(split_blocks(parts), {"ols": ones}, wrong, prior_precision(model), lambdas=(0.0, 100.0))
    assert no_prior.lam == 0.0 and no_prior.penalty is None and "did not predict better" in no_prior.note()


@pytest.mark.parametrize("duration, amplitude", [(4.7, 0.25), (20.0, 1.0)])
@pytest.mark.slow
def test_default_std_is_calibrated_when_the_file_is_wrong(duration, amplitude):
    """The prior's own error is in the std: with the file 30 % off, ~95 % within 2 sigma, not inflated.

    Without the file's error (the prior's weight alone) 77 % (short log) and 85 % (long log) of
    the base parameters were within 2 sigma. The short log's cross-validation blocks are too short
    (issue 48): the evidence rule decides, and picks the physically consistent fit on 2 of the 6
    seeds, whose HAC std leaves the prior's pull out: on the safe side there (median |z| 0.34).
    """
    z = []
    for seed in range(6):
        nominal, log, _ = _case(seed, duration, amplitude)
        truth = simulate_log(_perturbed(nominal, np.random.default_rng(seed)), seed=seed,
                             trajectory=(log.t, log.q, log.dq, np.gradient(log.dq, log.t, axis=0)))[1]
        res = identify(nominal, log)
        assert res.fit.selection.lam > 0
        if res.fit.selection.estimator != "physical":  # a least-squares prior: its own error in the std
            assert "the file's error as the" in res.fit.estimate.covariance
        z += [t["z"] for t in res.compare_truth(truth)["terms"]]  # every term: base and drive
    z = np.abs(z)
    assert np.mean(z < 2) >= 0.90, np.mean(z < 2)  # measured 0.97 and 0.95
    # measured 0.54 and 0.57 (base parameters alone 0.43 and 0.57: the prior's shape, body scales,
    # is not the perturbation's, so some pulled terms are more uncertain than their error)
    assert (0.30 if duration < 10 else 0.45) <= np.median(z) <= 0.90, np.median(z)
