"""Axioms of the PGA kernel, checked against the full-algebra reference implementation."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from baseparams import pga
from baseparams.pga import algebra as A

finite = st.floats(-3, 3, allow_nan=False, allow_infinity=False)
#: one batch shape per example, shared by every ``vecs(n)`` drawn in it, so that the arrays of a
#: test case always broadcast together and no example is thrown away
batch = st.shared(st.sampled_from([(), (1,), (3,), (2, 4)]), key="batch")


def vecs(n):
    """Arrays of shape ``batch + (n,)``, the batch shape being the one shared by the example."""
    return batch.flatmap(lambda b: arrays(float, b + (n,), elements=finite))


def motor_from(b):
    return pga.motor_exp(b)


@settings(max_examples=60, deadline=None)
@given(vecs(6))
def test_exp_log_round_trip(b):
    b = b.copy()
    # keep the rotation angle 2|d| below pi for a unique log
    nd = np.linalg.norm(b[..., :3], axis=-1, keepdims=True)
    b[..., :3] *= np.where(nd > 1.5, 1.5 / np.maximum(nd, 1e-300), 1.0)
    m = pga.motor_exp(b)
    assert np.allclose(pga.motor_log(m), b, atol=1e-8)
    # motor_exp agrees with the power series of the full algebra
    mv = np.zeros(b.shape[:-1] + (16,))
    mv[..., 0] = 1
    term = mv.copy()
    for k in range(1, 40):
        term = A.gp(term, A.from_line(b)) / k
        mv = mv + term
    assert np.allclose(A.to_motor(mv), m, atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(vecs(6), vecs(6))
def test_composition_and_inverse(b1, b2):
    m1, m2 = pga.motor_exp(b1), pga.motor_exp(b2)
    prod = pga.motor_product(m1, m2)
    assert prod.shape == b1.shape[:-1] + (8,)
    full = A.to_motor(A.gp(A.from_motor(m1), A.from_motor(m2)))
    assert np.allclose(prod, full, atol=1e-12)
    # a * b applies a first, then b
    assert np.allclose(pga.motor_to_matrix(prod), pga.motor_to_matrix(m2) @ pga.motor_to_matrix(m1), atol=1e-9)
    # ~M M = 1
    assert np.allclose(pga.motor_product(pga.reverse(m1), m1), pga.identity_motor(b1.shape[:-1]), atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(vecs(6), vecs(3), vecs(6))
def test_sandwich_is_matrix_action(b, x, line):
    m = pga.motor_exp(b)
    t = pga.motor_to_matrix(m)
    assert t.shape == b.shape[:-1] + (4, 4)
    assert np.allclose(pga.matrix_to_motor(t) * np.sign(pga.matrix_to_motor(t)[..., :1] + 1e-300),
                       m * np.sign(m[..., :1] + 1e-300), atol=1e-9)
    for p in (pga.point(x), pga.direction(x)):
        full = A.to_point(A.gp(A.gp(A.reverse(A.from_motor(m)), A.from_point(p)), A.from_motor(m)))
        assert np.allclose(pga.sandwich(m, p), full, atol=1e-9)
        assert np.allclose(full, np.einsum("...ij,...j->...i", t, p), atol=1e-9)
    full = A.to_line(A.gp(A.gp(A.reverse(A.from_motor(m)), A.from_line(line)), A.from_motor(m)))
    assert np.allclose(pga.sandwich(m, line), full, atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(vecs(3), vecs(3), st.floats(-2, 2), vecs(3))
def test_corollary1_point_on_line(p, d, lam, qx):
    line = pga.line_through(p, d)
    on_line = pga.point(p + lam * d)
    for q in (pga.point(qx), pga.direction(qx)):
        assert np.allclose(pga.wedge(line, pga.join(on_line, q)), 0, atol=1e-9)
        assert np.allclose(pga.wedge(line, pga.join(pga.direction(d), q)), 0, atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(vecs(6), vecs(6))
def test_wedge_is_power_and_commutator(w, v):
    f, n = w[..., :3], w[..., 3:]
    om, vel = v[..., :3], v[..., 3:]
    power = np.sum(f * vel + n * om, axis=-1)
    assert np.allclose(pga.wedge(w, v), power)
    assert np.allclose(pga.wedge(w, v), A.pseudoscalar(A.wedge(A.from_line(w), A.from_line(v))))
    comm = A.to_line((A.gp(A.from_line(w), A.from_line(v)) - A.gp(A.from_line(v), A.from_line(w))) / 2)
    assert np.allclose(pga.commutator(w, v), comm, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(vecs(4), vecs(4), vecs(6))
def test_join_and_point_velocity(p, q, v):
    assert np.allclose(pga.join(p, q), A.vee_points(p, q), atol=1e-12)
    full = A.to_point((A.gp(A.from_point(p), A.from_line(v)) - A.gp(A.from_line(v), A.from_point(p))) / 2)
    assert np.allclose(pga.commutator(p, v), full, atol=1e-12)


def test_velocity_of_moving_point_matches_finite_difference(rng):
    # X = ~M X0 M with M = exp(t B): dX/dt = X x V with V = 2 B (spatial twist)
    b = rng.normal(size=6) * 0.4
    x0 = pga.point(rng.normal(size=3))
    t, h = 0.7, 1e-6
    xp = pga.sandwich(pga.motor_exp((t + h) * b), x0)
    xm = pga.sandwich(pga.motor_exp((t - h) * b), x0)
    x = pga.sandwich(pga.motor_exp(t * b), x0)
    assert np.allclose((xp - xm) / (2 * h), pga.commutator(x, 2 * b), atol=1e-7)


def test_se3_log_near_pi(rng):
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    xi = np.r_[axis * (np.pi - 1e-7), rng.normal(size=3)]
    assert np.allclose(pga.se3_exp(pga.se3_log(pga.se3_exp(xi))), pga.se3_exp(xi), atol=1e-6)
