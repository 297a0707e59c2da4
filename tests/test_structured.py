"""The structured (body-by-body) certificate against the dense one, Pinocchio's rank, and wrong bases."""

from dataclasses import replace

import numpy as np
import pytest

from baseparams import analyze
from baseparams.nullspace import drng
from baseparams.nullspace.certify import certify, uses_structured
from baseparams.nullspace.drng import DRNGResult
from baseparams.nullspace.rank import block_rank, leading_spans
from baseparams.nullspace.structured import STRUCTURED_MIN_BODIES, structured_check
from baseparams.robots import BUILTINS, get, random_robot, special_robot

TYPES = ("R", "RP", "RPUS", "RPUSC")


def _tree(seed: int, n: int | None = None):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 14)) if n is None else n
    return random_robot(rng, n, joint_types=TYPES[seed % 4], floating=bool(seed % 2), branching=0.4)


@pytest.mark.parametrize("seed", range(16))
def test_structured_equals_dense_on_random_trees(seed):
    robot = _tree(seed)
    for rows in (("all", "joints") if robot.floating else ("all",)):
        res = drng(robot, rows=rows)
        dense = certify(robot, rows=rows, result=res, method="dense")
        chk = structured_check(robot, res, rows=rows)
        assert dense.status == "certified" and chk.status == "certified", chk.message
        assert chk.rank_b == dense.nullity == res.rank
        assert chk.rank_w == 10 * robot.n - dense.nullity
        cert = certify(robot, rows=rows, result=res, method="structured")
        assert cert.status == "certified" and cert.nullity == dense.nullity
        # the same subspace: the structured basis is in the dense one's span and vice versa
        assert np.linalg.svd(cert.basis.T @ dense.basis, compute_uv=False).min() > 1 - 1e-8


@pytest.mark.parametrize("seed", range(0, 60, 3))
def test_structured_equals_dense_on_special_geometry(seed):
    robot = special_robot(np.random.default_rng(seed))
    res = drng(robot)
    dense = certify(robot, result=res, method="dense")
    chk = structured_check(robot, res)
    assert (chk.status == "certified") == (dense.status == "certified")
    if dense.status == "certified":
        assert chk.rank_b == dense.nullity


@pytest.mark.parametrize("name", [b for b in BUILTINS if not get(b).has_loops])
@pytest.mark.parametrize("gravity", [None, (0.0, 0.0, 0.0)])
def test_structured_on_builtin_trees(name, gravity):
    robot = get(name, gravity=gravity)
    res = drng(robot)
    dense = certify(robot, result=res, method="dense")
    cert = certify(robot, result=res, method="structured")
    assert (cert.status, cert.nullity) == (dense.status, dense.nullity)


@pytest.mark.parametrize("seed, floating", [(5, True), (6, False), (8, True)])
def test_nullity_matches_pinocchio_rank(seed, floating):
    pin = pytest.importorskip("pinocchio")
    from baseparams.io.pinocchio import forces_from_pinocchio, state_to_pinocchio, to_pinocchio

    robot = random_robot(np.random.default_rng(seed), 9, "RP", floating, branching=0.4)
    model = to_pinocchio(robot)
    data = model.createData()
    rng = np.random.default_rng(2)
    q, dq, ddq = rng.uniform(-1, 1, (3, 60, robot.dof))
    rows = []
    for k in range(len(q)):
        qp, vp, ap = state_to_pinocchio(robot, q[k], dq[k], ddq[k])
        y = pin.computeJointTorqueRegressor(model, data, qp, vp, ap)
        rows.append(np.stack([forces_from_pinocchio(robot, q[k], y[:, c]) for c in range(y.shape[1])], 1))
    s = np.linalg.svd(np.concatenate(rows), compute_uv=False)
    chk = structured_check(robot, drng(robot))
    assert chk.status == "certified"
    assert 10 * robot.n - chk.rank_b == int(np.sum(s > 1e-9 * s[0]))


@pytest.mark.parametrize("seed", range(4))
def test_a_basis_missing_directions_is_not_certified(seed):
    robot = _tree(seed, 12)
    res = drng(robot)
    cols = res.columns
    keep = cols.child != cols.child[len(cols) // 2]  # drop every column of one joint
    sub = cols.subset(keep)
    short = DRNGResult(robot, sub, block_rank(sub, robot.n), 0.0)
    chk = structured_check(robot, short)
    assert chk.status == "undecided" and chk.missing == res.rank - short.rank > 0
    # through certify: the dense check decides and completes the missing directions
    cert = certify(robot, result=short, method="structured")
    assert cert.status == "completed" and cert.nullity == res.rank


@pytest.mark.parametrize("seed", range(4))
def test_a_perturbed_column_fails(seed):
    robot = _tree(seed, 10)
    res = drng(robot)
    h = res.columns.h.copy()
    h[len(h) // 3] += 1e-4 * np.random.default_rng(seed).normal(size=10)
    bad = DRNGResult(robot, replace(res.columns, h=h, hp=res.columns.hp.copy()), res.rank, 0.0)
    chk = structured_check(robot, bad)
    assert chk.status == "failed" and chk.worst > 1e-8
    assert certify(robot, result=bad, method="structured").status == "failed"


def test_leading_spans_complement_the_span():
    robot = _tree(3, 8)
    res = drng(robot)
    q, lead, indep = leading_spans(res.columns, robot.n)
    assert lead.sum() == res.rank
    b = res.dense()
    u = np.zeros((10 * robot.n, 10 * robot.n - lead.sum()))
    k = 0
    for i in range(robot.n):
        c = 10 - lead[i]
        u[10 * i:10 * i + 10, k:k + c] = q[i][:, lead[i]:]
        k += c
    assert np.linalg.matrix_rank(np.hstack([b, u])) == 10 * robot.n
    if indep is not None:
        assert len(indep) == res.rank


def test_structured_refuses_base_rows_and_loops():
    robot = _tree(1, 5)
    with pytest.raises(Exception, match="structured"):
        structured_check(robot, drng(robot, rows="base"), rows="base")
    assert not uses_structured(robot, "base")
    with pytest.raises(Exception, match="method"):
        uses_structured(robot, "all", "fast")


def test_large_tree_takes_the_structured_path():
    robot = random_robot(np.random.default_rng(7), STRUCTURED_MIN_BODIES + 20, "R", True)
    a = analyze(robot)
    assert a.status == "certified" and a.nullity == 3 * (robot.n - 1)
    assert "structured certificate" in a.certificate.message
    j = a.to_json()
    assert j["numerical"]["rank"] == 10 * robot.n - a.nullity


def test_medium_tree_n300():
    robot = random_robot(np.random.default_rng(11), 300, "R", True)
    res = drng(robot)
    chk = structured_check(robot, res)
    assert chk.status == "certified" and chk.rank_b == 3 * 299
    assert chk.blocks == 300 and chk.largest == 1


def _regroupings(robot, conv):
    from baseparams.base import base_parameters
    from baseparams.base.sparse import tree_base_parameters
    from baseparams.nullspace.columns import to_dense

    chk = structured_check(robot, drng(robot))
    assert chk.status == "certified" and chk.independent is not None
    return base_parameters(robot, to_dense(chk.independent, robot.n), conv), \
        tree_base_parameters(robot, chk.independent, conv)


def _aligned_k(dense, sparse):
    """Sparse K as dense, its columns in the dense K's dependent order."""
    pos = {int(d): k for k, d in enumerate(sparse.dependent)}
    k = sparse.K.toarray() if hasattr(sparse.K, "toarray") else sparse.K  # dense arrays for small models
    return k[:, [pos[int(d)] for d in dense.dependent]]


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("conv", ["khalil", "paper", "pinocchio"])
def test_sparse_regrouping_equals_dense(seed, conv):
    robot = _tree(seed, 12 + seed)
    dense, sparse = _regroupings(robot, conv)
    assert set(dense.dependent.tolist()) == set(sparse.dependent.tolist())
    assert np.array_equal(dense.independent, sparse.independent)
    assert dense.base_names() == sparse.base_names()
    assert np.array_equal(dense.unidentifiable, sparse.unidentifiable)
    kd, ks = dense.K, _aligned_k(dense, sparse)
    row = np.maximum(1.0, np.abs(kd).max(axis=1, keepdims=True))
    assert np.all(np.abs(kd - ks) <= 1e-9 * row)
    assert np.array_equal(kd != 0, ks != 0)
    pi = robot.parameters(conv)
    beta = sparse.to_base(pi, conv)
    assert np.allclose(beta, dense.to_base(pi, conv), rtol=1e-8, atol=1e-9 * np.abs(beta).max())
    back = sparse.from_base(beta)  # the minimum-norm vector: unique, the dense pinv's
    ref = dense.from_base(beta)
    assert np.linalg.norm(back - ref) <= 1e-7 * np.linalg.norm(ref)
    assert np.allclose(sparse.to_base(back, conv), beta, rtol=1e-7, atol=1e-9 * np.abs(beta).max())


@pytest.mark.parametrize("seed", range(0, 40, 4))
def test_sparse_regrouping_on_special_geometry(seed):
    robot = special_robot(np.random.default_rng(seed))
    if robot.has_loops:
        pytest.skip("loops")
    dense, sparse = _regroupings(robot, "khalil")
    assert set(dense.dependent.tolist()) == set(sparse.dependent.tolist())
    kd, ks = dense.K, _aligned_k(dense, sparse)
    assert np.all(np.abs(kd - ks) <= 1e-8 * np.maximum(1.0, np.abs(kd).max(axis=1, keepdims=True)))


@pytest.mark.parametrize("csr", [False, True])
def test_analysis_of_a_large_tree_is_sparse_and_consistent(csr, monkeypatch):
    from baseparams.base import sparse

    if csr:  # scipy.sparse matrices, as above sparse.DENSE_MAX_PARAMS parameters
        monkeypatch.setattr(sparse, "DENSE_MAX_PARAMS", 0)
    robot = random_robot(np.random.default_rng(9), STRUCTURED_MIN_BODIES + 5, "RP", True)
    a = analyze(robot)
    assert hasattr(a.base.K, "tocsr") == csr and a.base.base_basis is None  # regrouped from compact columns
    assert a.nullity == a.certificate.nullity == 10 * robot.n - a.n_base
    rng = np.random.default_rng(0)
    q, dq, ddq = rng.uniform(-1, 1, (3, 4, robot.dof))
    from baseparams.analysis import regressor

    tau = regressor(robot, q, dq, ddq) @ robot.parameters("paper")
    tau_b = a.base_regressor(q, dq, ddq) @ a.base_values
    assert np.allclose(tau_b, tau, rtol=1e-9, atol=1e-9 * np.abs(tau).max())
    names = [e["name"] for e in a.expressions()]
    assert names == a.base_names and len(names) == a.n_base


def test_deep_chain_is_refused_before_allocating(monkeypatch):
    from baseparams import analysis
    from baseparams.errors import BaseparamsError

    robot = random_robot(np.random.default_rng(1), 60, "R", True, branching=0.0)
    monkeypatch.setattr(analysis, "_available_bytes", lambda: 1e6)
    with pytest.raises(BaseparamsError, match=r"60 bodies: the analysis needs about .* GB and .* available"):
        analyze(robot)  # linear in the bodies in either form (issue 51: the expanded one is written as it is made)
    with pytest.raises(BaseparamsError, match=r"60 bodies: the analysis needs about"):
        analyze(robot, form="expanded")


def test_undecided_when_the_dense_check_does_not_fit(monkeypatch):
    from baseparams.base.sparse import tree_base_parameters
    from baseparams.nullspace import structured as structured_mod

    robot = _tree(2, 12)
    res = drng(robot)
    sub = res.columns.subset(res.columns.child != res.columns.child[len(res.columns) // 2])
    short = DRNGResult(robot, sub, block_rank(sub, robot.n), 0.0)
    monkeypatch.setattr(structured_mod, "dense_fits", lambda *a, **k: False)
    cert = certify(robot, result=short, method="structured")
    assert cert.status == "undecided" and "does not fit in memory" in cert.message
    assert cert.nullity == short.rank and cert.columns is not None
    assert tree_base_parameters(robot, cert.columns, "khalil").n_base == 10 * robot.n - short.rank


def test_no_verify_on_a_large_tree_regroups_sparsely_the_same(monkeypatch):
    from baseparams.base import sparse

    monkeypatch.setattr(sparse, "DENSE_MAX_PARAMS", 0)  # scipy.sparse matrices, as for larger models
    robot = random_robot(np.random.default_rng(4), STRUCTURED_MIN_BODIES + 3, "RP", True)
    a, b = analyze(robot), analyze(robot, verify=False)
    assert b.status == "unverified" and b.basis is None and hasattr(b.base.K, "tocsr")
    assert b.nullity == a.nullity and b.expressions() == a.expressions()


@pytest.mark.parametrize("seed", range(0, 60, 3))
def test_structured_on_coupled_trees_agrees_with_dense(seed):
    """Mimic hands (chains of couplings, R and P, ratios +-1, 2, -0.5): a structured certificate is
    the dense one's, and DRNG short of one body's columns is never certified."""
    from test_coupled import mimic_hand

    robot = mimic_hand(np.random.default_rng(seed), offsets=bool(seed % 2))
    res = drng(robot)
    dense = certify(robot, result=res, method="dense")
    chk = structured_check(robot, res)
    assert chk.status in ("certified", "undecided"), chk.message
    if chk.status == "certified":
        assert dense.status == "certified" and chk.rank_b == dense.nullity
        assert chk.rank_w == 10 * robot.n - dense.nullity
    cert = certify(robot, result=res, method="structured")  # undecided: the dense check decides
    assert (cert.status, cert.nullity) == (dense.status, dense.nullity)
    assert np.linalg.svd(cert.basis.T @ dense.basis, compute_uv=False).min() > 1 - 1e-8
    cols = res.columns
    keep = cols.child != cols.child[len(cols) // 2]
    short = DRNGResult(robot, cols.subset(keep), block_rank(cols.subset(keep), robot.n), 0.0)
    assert structured_check(robot, short).status == "undecided"


def test_talos_mimic_couplings_take_the_structured_path():
    """talos_full_v2 (45 bodies, 12 ``<mimic>`` couplings): certified body by body, the dense
    check's nullity and span; without R-M's 58 directions the check says what is missing."""
    from baseparams.loading import load_model

    from erd import urdf_files

    found = [f for f in urdf_files() if f.name == "talos_full_v2.urdf"]
    if not found:
        pytest.skip("example-robot-data not installed")
    robot = load_model(str(found[0]), floating=True)[0]
    assert robot.couplings and uses_structured(robot, "all")
    res = drng(robot)
    auto, dense = certify(robot, result=res), certify(robot, result=res, method="dense")
    assert "structured certificate" in auto.message
    assert (auto.status, auto.nullity) == (dense.status, dense.nullity) == ("certified", 190)
    assert auto.sampling["kept"] == auto.sampling["requested"] and "cond_max" in auto.sampling
    assert np.linalg.svd(auto.basis.T @ dense.basis, compute_uv=False).min() > 1 - 1e-8
    rm = np.array([p.startswith("R-M") for p in (res.provenance(k) for k in range(len(res.columns)))])
    short = DRNGResult(robot, res.columns.subset(~rm), block_rank(res.columns.subset(~rm), robot.n), 0.0)
    chk = structured_check(robot, short)
    assert chk.status == "undecided" and chk.missing == res.rank - short.rank == 58


@pytest.mark.parametrize("seed", range(12))
def test_tree_kinematics_is_forward_kinematics(seed):
    """The structured pass's kinematics (poses chained body by body, the rest batched over the
    coordinates) equal :func:`baseparams.kinematics.tree.forward_kinematics`: every joint type,
    fixed and floating roots."""
    from baseparams.kinematics.tree import forward_kinematics
    from baseparams.nullspace.structured import tree_kinematics
    from baseparams.numerics import sample_states

    rng = np.random.default_rng(seed)
    robot = random_robot(rng, int(rng.integers(1, 12)), "RPUSC", floating=bool(seed % 2))
    q, dq, ddq = sample_states(robot, 4, rng)
    ref = forward_kinematics(robot, q, dq, ddq)
    for got, want in zip(tree_kinematics(robot, q, dq, ddq), (ref.g, ref.V, ref.dV, ref.lines)):
        assert np.abs(got - want).max() <= 1e-12 * max(1.0, np.abs(want).max())
