"""Physically consistent least squares (baseparams.ident.physical): properties on seeded robots.

The compressed problem is built without the identification stack: ``G`` is the identity over
the full parameters ``phi = [pi; delta]`` and ``R11, r12`` come from a QR of the stacked
``[Y | tau]`` (``Y`` the TP regressor, drive columns appended).
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from baseparams.errors import BaseparamsError
from baseparams.ident import physical
from baseparams.ident.physical import PhysicalFit, feasibility, physical_fit, prior_pseudo_inertias
from baseparams.model.inertia import hat
from baseparams.regressor import regressor
from baseparams.robots import random_robot


def _states(rng, robot, samples, amplitude=np.pi):
    q = rng.uniform(-amplitude, amplitude, (samples, robot.dof))
    dq = rng.normal(scale=amplitude, size=(samples, robot.dof))
    ddq = rng.normal(scale=amplitude, size=(samples, robot.dof))
    return q, dq, ddq


def _drive_columns(dq, ddq, kinds):
    """Drive regressor ``(S, dof, nd)``: one column per ``(kind, joint)``."""
    S, dof = dq.shape
    cols = np.zeros((S, dof, len(kinds)))
    for k, (kind, j) in enumerate(kinds):
        cols[:, j, k] = {"Ia": ddq[:, j], "Fv": dq[:, j], "Fc": np.sign(dq[:, j]), "Fo": np.ones(S)}[kind]
    return cols


def _compressed(Y, tau):
    """``R11, r12`` of the stacked ``[Y | tau]`` (``Y (S, dof, p)``, ``tau (S, dof)``)."""
    A = Y.reshape(-1, Y.shape[-1])
    p = A.shape[1]
    R = np.linalg.qr(np.column_stack([A, tau.reshape(-1)]), mode="r")
    return R[:p, :p], R[:p, p]


def _perturbed_prior(rng, robot, spread=0.3):
    """A feasible prior that differs from the truth: each body scaled by a random factor."""
    return robot.N0 * rng.uniform(1 - spread, 1 + spread, size=(robot.n, 1, 1))


def _problem(seed, n=5, samples=60, noise=0.0, amplitude=np.pi):
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, n, joint_types="R")
    q, dq, ddq = _states(rng, robot, samples, amplitude)
    Y = regressor(robot, q, dq, ddq)
    tau = Y @ robot.parameters("paper")
    tau = tau + noise * np.std(tau) * rng.normal(size=tau.shape)
    return rng, robot, Y, tau


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_noiseless_fit_reproduces_the_torques_and_is_feasible(seed):
    rng, robot, Y, tau = _problem(seed)
    R11, r12 = _compressed(Y, tau)
    fit = physical_fit(R11, r12, np.eye(10 * robot.n), robot, (), prior=_perturbed_prior(rng, robot),
                       prior_weight=1e-10)
    assert isinstance(fit, PhysicalFit) and fit.solver_status == "optimal"
    assert np.linalg.norm(Y @ fit.pi - tau) <= 1e-6 * np.linalg.norm(tau)
    assert fit.feasible and np.all(np.linalg.eigvalsh(fit.N) >= -1e-9)
    assert fit.pi.shape == (10 * robot.n,) and fit.delta.shape == (0,) and fit.masses.shape == (robot.n,)
    np.testing.assert_allclose(fit.theta, fit.pi)
    np.testing.assert_allclose(fit.masses, fit.pi[9::10])
    assert fit.min_eigenvalues.shape == fit.relative_min_eigenvalues.shape == (robot.n,)
    assert fit.seconds > 0 and fit.notes == ()


@pytest.mark.parametrize("seed", [3, 4])
def test_noiseless_fit_with_drive_columns(seed):
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, 4, joint_types="R")
    q, dq, ddq = _states(rng, robot, 80)
    drives = [("Fv", j) for j in range(robot.dof)] + [("Fc", 0), ("Fo", 1), ("Ia", 2)]
    d_true = np.array([0.5, 0.2, 0.8, 0.1, 1.5, -0.7, 0.05])
    Y = np.concatenate([regressor(robot, q, dq, ddq), _drive_columns(dq, ddq, drives)], axis=2)
    tau = Y @ np.concatenate([robot.parameters("paper"), d_true])
    R11, r12 = _compressed(Y, tau)
    kinds = [k for k, _ in drives]
    fit = physical_fit(R11, r12, np.eye(Y.shape[2]), robot, kinds, prior=_perturbed_prior(rng, robot),
                       prior_weight=1e-10)
    phi = np.concatenate([fit.pi, fit.delta])
    assert np.linalg.norm(Y @ phi - tau) <= 1e-6 * np.linalg.norm(tau)
    assert fit.feasible
    # viscous, Coulomb and offset columns are identifiable: recovered; Ia of joint 2 shares its
    # column with the bodies' inertia, only its sign is guaranteed
    np.testing.assert_allclose(fit.delta[:6], d_true[:6], rtol=1e-4, atol=1e-6)
    assert fit.delta[6] >= -1e-9
    assert any("no drive_prior" in line for line in fit.notes)


def test_ols_infeasible_where_the_physical_fit_is_feasible():
    """Few samples, small motions and 5 % noise: the min-norm least-squares full vector has
    bodies with negative eigenvalues; the physical fit's bodies are all PSD."""
    rng, robot, Y, tau = _problem(7, n=4, samples=6, noise=0.05, amplitude=0.3)
    R11, r12 = _compressed(Y, tau)
    pi_ols = np.linalg.lstsq(Y.reshape(-1, 10 * robot.n), tau.reshape(-1), rcond=None)[0]
    eig_ols, ok_ols = feasibility(pi_ols, robot.n)
    assert not ok_ols and eig_ols.min() < 0 and np.sum(eig_ols < 0) >= 2
    fit = physical_fit(R11, r12, np.eye(10 * robot.n), robot, prior=_perturbed_prior(rng, robot))
    eig_fit, ok_fit = feasibility(fit.pi, robot.n)
    assert ok_fit and fit.feasible and np.all(eig_fit >= -1e-9)
    assert np.all(fit.masses > 0)


def test_feasibility_of_known_vectors():
    rng = np.random.default_rng(11)
    robot = random_robot(rng, 3)
    eig, ok = feasibility(robot.parameters("paper"), robot.n)
    assert ok and np.all(eig > 0)
    N = robot.N0.copy()
    N[1, 3, 3] = -1.0  # negative mass
    eig, ok = feasibility(hat(N).reshape(-1), robot.n)
    assert not ok and eig[1] < 0 and eig[0] > 0 and eig[2] > 0
    with pytest.raises(BaseparamsError, match="expected 30 finite"):
        feasibility(np.zeros(29), 3)


@pytest.mark.parametrize("seed", [5, 6])
def test_large_prior_weight_gives_the_prior(seed):
    rng, robot, Y, tau = _problem(seed, noise=0.02)
    R11, r12 = _compressed(Y, tau)
    prior = _perturbed_prior(rng, robot)
    fit = physical_fit(R11, r12, np.eye(10 * robot.n), robot, prior=prior, prior_weight=1e6)
    pi0 = hat(prior).reshape(-1)
    assert np.abs(fit.pi - pi0).max() <= 1e-4 * np.abs(pi0).max()
    assert fit.prior_divergence.max() < 1e-8


@pytest.mark.parametrize("seed", [5, 6])
def test_tiny_prior_weight_gives_the_least_squares_residual(seed):
    """The fit term approaches the unconstrained least-squares residual as the weight shrinks;
    what is left is the price of physical consistency (a tiny part of the torques' energy)."""
    rng, robot, Y, tau = _problem(seed, noise=0.02)
    R11, r12 = _compressed(Y, tau)
    prior = _perturbed_prior(rng, robot)
    theta_ols = np.linalg.lstsq(R11, r12, rcond=None)[0]
    ols = float(np.sum((R11 @ theta_ols - r12) ** 2))
    rho2 = float(np.sum((Y.reshape(-1, 10 * robot.n) @ theta_ols - tau.reshape(-1)) ** 2)) - ols
    fits = {w: physical_fit(R11, r12, np.eye(10 * robot.n), robot, prior=prior, prior_weight=w)
            for w in (1e-2, 1e-6, 1e-10)}
    scale = float(r12 @ r12)
    tiny = fits[1e-10]
    assert tiny.fit_scale == pytest.approx(scale)
    assert ols - 1e-12 * scale <= tiny.fit_residual <= ols + 1e-5 * scale
    assert tiny.fit_residual + rho2 <= 1.01 * (ols + rho2)  # the whole residual, |Y pi - tau|^2
    assert fits[1e-2].fit_residual > fits[1e-6].fit_residual > tiny.fit_residual  # the pull costs fit
    assert all(f.feasible for f in fits.values())
    # the objective is the scaled fit plus the weighted divergences
    assert tiny.objective == pytest.approx(tiny.fit_residual / scale + 1e-10 * tiny.prior_divergence.sum(),
                                           rel=1e-6, abs=1e-12)


def test_drive_prior_pulls_delta():
    rng = np.random.default_rng(8)
    robot = random_robot(rng, 3, joint_types="R")
    q, dq, ddq = _states(rng, robot, 40)
    drives = [("Fv", j) for j in range(robot.dof)]
    Y = np.concatenate([regressor(robot, q, dq, ddq), _drive_columns(dq, ddq, drives)], axis=2)
    tau = Y @ np.concatenate([robot.parameters("paper"), [0.3, 0.4, 0.5]])
    R11, r12 = _compressed(Y, tau)
    d0 = np.array([1.0, 1.0, 1.0])
    fit = physical_fit(R11, r12, np.eye(Y.shape[2]), robot, ["Fv"] * 3, drive_prior=d0, prior_weight=1e4)
    np.testing.assert_allclose(fit.delta, d0, atol=1e-3)
    assert not any("no drive_prior" in line for line in fit.notes)


@pytest.mark.parametrize("placeholder", ["zero", "negative"])
def test_non_positive_definite_prior_body_is_replaced_with_a_note(placeholder):
    rng, robot, Y, tau = _problem(9, n=4, noise=0.01)
    R11, r12 = _compressed(Y, tau)
    prior = robot.N0.copy()
    if placeholder == "zero":
        prior[2] = 0.0  # a massless placeholder link
    else:
        prior[2, 3, 3] = -0.5  # a broken mass
    fit = physical_fit(R11, r12, np.eye(10 * robot.n), robot, prior=prior)
    assert fit.feasible and fit.solver_status == "optimal"
    assert len(fit.notes) == 1 and "'b2'" in fit.notes[0] and "not positive definite" in fit.notes[0]
    used, notes = prior_pseudo_inertias(robot, prior)
    assert notes == list(fit.notes)
    assert np.all(np.linalg.eigvalsh(used) > 0)
    np.testing.assert_allclose(np.delete(used, 2, axis=0), np.delete(robot.N0, 2, axis=0), rtol=1e-14, atol=1e-15)


def test_mass_bounds_hold_and_infeasible_bounds_are_one_error():
    rng, robot, Y, tau = _problem(10, n=4, samples=6, noise=0.05, amplitude=0.3)
    R11, r12 = _compressed(Y, tau)
    G = np.eye(10 * robot.n)
    free = physical_fit(R11, r12, G, robot)
    bounds = np.full((robot.n, 2), np.nan)
    bounds[1] = [free.masses[1] + 1.0, np.nan]
    bounds[3] = [np.nan, 0.5 * free.masses[3]]
    fit = physical_fit(R11, r12, G, robot, mass_bounds=bounds)
    assert fit.masses[1] >= bounds[1, 0] - 1e-7 and fit.masses[3] <= bounds[3, 1] + 1e-7
    assert fit.feasible
    bounds[2] = [3.0, 2.0]
    with pytest.raises(BaseparamsError, match=r"infeasible mass bounds.*'b2' \(3 > 2\)"):
        physical_fit(R11, r12, G, robot, mass_bounds=bounds)


def test_bad_inputs_are_one_line_errors(monkeypatch):
    rng, robot, Y, tau = _problem(12, n=3)
    R11, r12 = _compressed(Y, tau)
    G = np.eye(10 * robot.n)
    with pytest.raises(BaseparamsError, match="unknown drive kind"):
        physical_fit(R11, r12, np.eye(10 * robot.n + 1)[:30], robot, ["Fx"])
    with pytest.raises(BaseparamsError, match="G must be"):
        physical_fit(R11, r12, G[:, :-1], robot)
    with pytest.raises(BaseparamsError, match="prior_weight"):
        physical_fit(R11, r12, G, robot, prior_weight=-1.0)
    with pytest.raises(BaseparamsError, match="prior must be"):
        physical_fit(R11, r12, G, robot, prior=np.zeros(7))
    monkeypatch.setattr(physical, "SOLVER", "NO_SUCH_SOLVER")
    with pytest.raises(BaseparamsError, match="not installed"):
        physical_fit(R11, r12, G, robot)
    monkeypatch.undo()
    monkeypatch.setitem(sys.modules, "cvxpy", None)  # import cvxpy -> ImportError
    with pytest.raises(BaseparamsError, match=r"pip install 'baseparams\[ident\]'"):
        physical_fit(R11, r12, G, robot)


def test_min_eig_bounds_every_body():
    rng, robot, Y, tau = _problem(13, n=3, samples=6, noise=0.05, amplitude=0.3)
    R11, r12 = _compressed(Y, tau)
    fit = physical_fit(R11, r12, np.eye(10 * robot.n), robot, min_eig=1e-3)
    assert np.all(fit.min_eigenvalues >= 1e-3 - 1e-8)
