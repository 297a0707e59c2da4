"""Base parameters: regrouping is exact, maps round-trip, expressions are readable."""

import numpy as np
import pytest

from baseparams.base import base_parameters, paper_from
from baseparams.model import inertia as I
from baseparams.nullspace.certify import certify
from baseparams.numerics import stacked_regressor
from baseparams.robots import go2, puma560, random_robot


@pytest.mark.parametrize("convention", I.CONVENTIONS)
@pytest.mark.parametrize("make", [puma560, lambda: random_robot(np.random.default_rng(5), 5, "RPU")])
def test_regrouping_reproduces_torques(convention, make):
    robot = make()
    c = certify(robot, samples=80, seed=3)
    bp = base_parameters(robot, c.basis, convention)
    assert bp.n_base == 10 * robot.n - c.nullity
    w = stacked_regressor(robot, 30, 11) @ bp.T  # regressor in this convention's coordinates
    rng = np.random.default_rng(0)
    for _ in range(5):
        pi = rng.normal(size=10 * robot.n)
        beta = bp.to_base(pi, convention)
        assert np.allclose(w[:, bp.independent] @ beta, w @ pi, rtol=1e-8, atol=1e-8 * np.abs(w @ pi).max())
        back = bp.from_base(beta)  # minimum-norm full vector with the same base parameters
        assert np.allclose(bp.to_base(back, convention), beta)
        assert np.linalg.norm(back) <= np.linalg.norm(pi) + 1e-9
        assert np.allclose(w @ back, w @ pi, atol=1e-8 * np.abs(w @ pi).max())


def test_puma560_khalil_regrouping_reads_like_khalil():
    robot = puma560()
    bp = base_parameters(robot, certify(robot).basis, "khalil")
    ex = {e["name"]: e["expression"] for e in bp.expressions()}
    assert len(ex) == 36
    # link 1 only keeps ZZ1R = ZZ1 + YY2 + YY3 + lengths^2 * masses (Khalil's classic form)
    assert ex["link1.ZZR"].startswith("link1.ZZ ") and "link2.YY" in ex["link1.ZZR"]
    assert "0.18645124*link3.M" in ex["link1.ZZR"]  # a2^2 = 0.4318^2 exactly, cleaned
    unid = {bp.names[i] for i in bp.unidentifiable}
    assert {"link1.XX", "link1.M", "link1.MZ", "link2.M", "link2.MZ"} <= unid
    assert "link6.ZZ" in ex and ex["link6.ZZ"] == "link6.ZZ"


def test_base_basis_is_orthonormal_complement():
    robot = go2()
    c = certify(robot)
    bp = base_parameters(robot, c.basis, "paper")
    b = bp.base_basis
    assert b.shape == (130, 94)
    assert np.allclose(b.T @ b, np.eye(94), atol=1e-10)
    assert np.abs(b.T @ c.basis).max() < 1e-10


def test_paper_from_matches_robot_parameters():
    robot = random_robot(np.random.default_rng(2), 4)
    for conv in I.CONVENTIONS:
        assert np.allclose(paper_from(robot, conv) @ robot.parameters(conv), robot.parameters("paper"))
