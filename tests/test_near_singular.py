"""Loops near a singular configuration (issue 30): a parallelogram close to its flat configuration.

The family ``parallelogram-symbolic`` has 3 base parameters for every ``BY != 0`` (the crank's
reference angle ``atan2(BY, BX)``; ``BY = 0`` is the flat configuration, where the
parallelogram and anti-parallelogram branches meet). Oracles: the parallelogram's closed form
on its branch (the coupler keeps its orientation, the rocker follows the crank: ``q =
(a, -a, a)``, and so its rates), and the certified count of a well-conditioned reference
(``BY = 0.05``).
"""

import numpy as np
import pytest

import baseparams
from baseparams.errors import BaseparamsError
from baseparams.kinematics.loops import close_loops, restrict

sp = pytest.importorskip("sympy")
from baseparams.symbolic import load_symbolic, probe, symbolic_analysis  # noqa: E402


def _robot(by: float):
    return load_symbolic("parallelogram-symbolic").to_robot({"BY": by})


@pytest.mark.parametrize("by", [0.05, 0.01, 1e-3, 1e-4, 1e-6])
def test_near_flat_parallelogram_is_certified_with_three(by):
    a = baseparams.analyze(_robot(by))
    assert a.status == "certified", a.certificate.message
    assert a.n_base == 3
    s = a.certificate.sampling
    assert s["kept"] >= 1000 and s["max_loop_residual"] < 1e-13


@pytest.mark.parametrize("by", [1e-2, 1e-4])
def test_samples_stay_on_the_reference_branch_to_rounding(by):
    """Every kept sample is the parallelogram's closed form; samples past the flat configuration
    (crank angle below zero: the branch is not known there) are discarded as branch jumps."""
    rng = np.random.default_rng(3)
    qa = rng.uniform(-0.3, 0.3, (400, 1))
    dqa, ddqa = rng.uniform(0, 1, (400, 1)), rng.uniform(0, 1, (400, 1))
    cs = close_loops(_robot(by), qa, dqa, ddqa, cond_max=np.inf)
    ref = np.arctan2(by, 0.3)  # the crank's angle at q = 0
    assert cs.kept + cs.branch_jumps == 400 and cs.not_converged == 0
    assert cs.branch_jumps == int(np.sum(qa[:, 0] < -ref))
    a = cs.q[:, 0]
    assert np.all(a > -ref)
    exact = np.stack([a, -a, a], axis=1)
    assert np.abs(cs.q - exact).max() < 1e-12
    cond = cs.cond
    well = cond < 100  # the rates lose about cond (dq) and cond^2 (ddq) of their precision
    assert np.abs(cs.dq - np.stack([cs.dq[:, 0]] * 3, 1) * [1, -1, 1]).max(axis=1)[well].max() < 1e-11
    assert np.abs(cs.ddq - np.stack([cs.ddq[:, 0]] * 3, 1) * [1, -1, 1]).max(axis=1)[well].max() < 1e-9
    r = restrict(cs, 50.0)
    assert r.kept == int(np.sum(cond < 50)) and r.ill_conditioned == cs.kept - r.kept and r.cond_max == 50.0


def test_flat_reference_is_refused_with_what_would_help():
    with pytest.raises(BaseparamsError, match="reference configuration .* is singular.*move the reference"):
        baseparams.analyze(_robot(0.0))


def test_symbolic_flat_condition_claims_no_count():
    """BY = 0 stays a condition of the formulas, and no base-parameter count is claimed there."""
    sa = symbolic_analysis(load_symbolic("parallelogram-symbolic"))
    probe(sa)
    flat = [c for c in sa.conditions if sp.Symbol("BY", real=True) in c.polynomials]
    assert flat and all("base parameters there" not in c.effect for c in flat)
    assert "singular" in flat[0].effect


def test_residual_within_the_conditioning_is_undecided_not_failed():
    """A DRNG column off the numerical nullspace by what rounding in ill-conditioned loop samples
    can cause is UNDECIDED (with what would help); beyond it, or with well-conditioned samples,
    FAILED as before."""
    from baseparams.nullspace import certify as cert_mod

    cert = cert_mod.certify(_robot(1e-2))
    res, num = cert.drng, cert.numerical
    ncol = res.dense().shape[1]

    def verdict(worst, cond_max):
        col = np.full(ncol, worst)
        return cert_mod._verdict(res, num, 10**6, cert.drng_rank, col, worst, 1e-9, 1e4, 1e-8,
                                 {"cond_max": cond_max})

    status, msg = verdict(1e-6, 1000.0)  # tolerance 1e-8 (1000 / 30)^3 = 3.7e-4
    assert status == "undecided" and "move it away" in msg
    assert verdict(1e-6, 30.0)[0] == "failed"
    assert verdict(1e-2, 1000.0)[0] == "failed"
    assert verdict(1e-12, 1000.0)[0] == "certified"
