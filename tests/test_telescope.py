"""Coupled prismatic joints in series (a telescoping arm, issue 46): every block of a column carried
through R-C and the regroupings, against Pinocchio; and every rule's columns checked against the
regressor before they are used, a wrong rule named."""

from __future__ import annotations

import importlib
import warnings

import numpy as np
import pinocchio as pin
import pytest

import baseparams as bp
from baseparams.analysis import format_report
from baseparams.enums import Source, Status
from baseparams.nullspace.checks import RuleCheck
from baseparams.nullspace.columns import Columns, on_bodies, to_dense
from baseparams.nullspace.drng import drng
from baseparams.numerics import stacked_regressor

from erd import pinocchio_nullity
from paths import SHARED

drng_module = importlib.import_module("baseparams.nullspace.drng")  # the package binds the name to the function


def _inertial(rng) -> str:
    a = rng.uniform(0.01, 0.05, 3)
    com = " ".join(f"{v:.4f}" for v in rng.uniform(-0.05, 0.05, 3))
    return (f'<inertial><origin xyz="{com}"/><mass value="{rng.uniform(0.2, 2):.3f}"/><inertia ixx="{a[1] + a[2]:.5f}" '
            f'ixy="0.001" ixz="0" iyy="{a[0] + a[2]:.5f}" iyz="0" izz="{a[0] + a[1]:.5f}"/></inertial>')


BASES = {
    "fixed": '<joint name="b" type="fixed"><parent link="world"/><child link="base"/><origin xyz="0 0 0.1"/></joint>',
    "yaw": ('<joint name="b" type="continuous"><parent link="world"/><child link="base"/>'
            '<origin xyz="0.1 0.2 0.1"/><axis xyz="0 0 1"/></joint>'),
    "planar": ('<joint name="b" type="planar"><parent link="world"/><child link="base"/><origin xyz="0 0 0.03"/>'
               '<axis xyz="0 0 1"/></joint>'),
}


def telescope_urdf(rng, k: int, base: str) -> str:
    """A base (fixed, turning about z, or on a URDF planar joint) carrying ``k`` prismatic joints in
    series along one axis, the 2nd to ``k``-th mimicking the first: a telescoping arm."""
    text = ['<robot name="telescope"><link name="world"/>', BASES[base], f'<link name="base">{_inertial(rng)}</link>']
    parent = "base"
    axis = rng.normal(size=3)
    axis = " ".join(f"{v:.4f}" for v in axis / np.linalg.norm(axis))
    for i in range(k):
        origin = " ".join(f"{v:.4f}" for v in (rng.uniform(-0.1, 0.1, 3) if i == 0 else [0.0135, 0.002, 0.0]))
        mimic = "" if i == 0 else '<mimic joint="a0" multiplier="1" offset="0"/>'
        text += [f'<joint name="a{i}" type="prismatic"><origin xyz="{origin}"/><parent link="{parent}"/>'
                 f'<child link="l{i}"/><axis xyz="{axis}"/><limit lower="0" upper="0.13" effort="1" velocity="1"/>'
                 f'{mimic}</joint>', f'<link name="l{i}">{_inertial(rng)}</link>']
        parent = f"l{i}"
    return "\n".join(text + ["</robot>"])


def _pinocchio_nullity(path) -> tuple[int, float]:
    with np.errstate(divide="ignore"):  # singular values exactly zero: an infinite gap
        return pinocchio_nullity(pin.buildModelFromUrdf(str(path)), path, 120)


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # random inertias: noted only
        return bp.load(str(path))


def _column_residuals(robot, cols: Columns, seed: int = 3) -> np.ndarray:
    """``||W b|| / (||W||_2 ||b||)`` of each column on 40 stacked states (the certification's measure)."""
    w = stacked_regressor(robot, 40, seed)
    b = to_dense(cols, robot.n)
    return np.linalg.norm(w @ b, axis=0) / (np.linalg.norm(w, 2) * np.maximum(np.linalg.norm(b, axis=0), 1e-300))


@pytest.mark.parametrize("base", sorted(BASES))
@pytest.mark.parametrize("k", [2, 3, 4])
def test_telescope_certified_at_pinocchios_count(k, base, tmp_path):
    """2-4 coupled prismatic joints on a fixed, a yawing and a planar base: certified, DRNG complete, at
    Pinocchio's rank deficiency (mimic couplings imposed on its coordinates); every column DRNG emits
    is in the nullspace without the rule check's help (it failed with >= 3 on the planar base: R-C
    passed R-M's widest columns on without their fourth block)."""
    rng = np.random.default_rng(10 * k + len(base))
    path = tmp_path / f"telescope_{base}_{k}.urdf"
    path.write_text(telescope_urdf(rng, k, base))
    robot = _load(path)
    a = bp.analyze(robot)
    assert a.status == Status.CERTIFIED and a.certificate.completed == 0, a.certificate.message
    assert a.drng_notes == ()
    nullity, gap = _pinocchio_nullity(path)
    assert gap > 1e6 and a.nullity == nullity
    raw = drng(robot, check=False)
    assert raw.rank == a.drng_rank and _column_residuals(robot, raw.columns).max() < 1e-10


@pytest.mark.shared
def test_telescope_file_of_the_issue_is_certified():
    """issue 46's minimal reproduction (planar base, three coupled slides): exit 4 before; Pinocchio's 8."""
    path = SHARED / "turn5" / "telescope_planar_nolift_k3.urdf"
    robot = _load(path)
    a = bp.analyze(robot)
    assert a.status == Status.CERTIFIED and a.n_base == 8 and a.certificate.completed == 0
    assert a.nullity == _pinocchio_nullity(path)[0]


def _old_new_directions(cols, prior, unit):
    """R-C's new directions as they were: grouped by child, parent and extra only, the ``more`` blocks dropped."""
    from baseparams.nullspace.coupled import NEW, prior_rows

    known, out = prior if prior is not None else Columns.empty(), []
    sets = [tuple(sorted({int(b) for b in (cols.child[j], cols.parent[j], cols.extra[j]) if b >= 0}))
            for j in range(len(cols))]
    for who in sorted(set(sets), key=lambda w: (len(w), w)):
        sel = cols.subset(np.array([w == who for w in sets]))
        x = to_dense(sel, max(who) + 1).reshape(max(who) + 1, 10, -1)[list(who)] / unit[None, :, None]
        x = (x / np.maximum(np.linalg.norm(x, axis=(0, 1)), 1e-300)).reshape(10 * len(who), -1).T
        seed = prior_rows(known, list(who), unit)
        u_, s, _ = np.linalg.svd(x - (x @ seed.T) @ seed, full_matrices=False)
        if int(np.sum(s > NEW)):
            y = (u_[:, :int(np.sum(s > NEW))].T @ x).reshape(-1, len(who), 10) * unit
            out.append(on_bodies(list(who), y.reshape(len(y), -1), Source.R_C, "truncated"))
            known = Columns.concat([known, out[-1]])
    return out


def test_a_rule_that_drops_a_block_is_named_and_left_out(monkeypatch, tmp_path):
    """The defect of issue 46 put back: its column fails the check, is left out with R-C named (in the
    result, the report and the JSON), and the analysis is still right (certified, Pinocchio's count)."""
    from baseparams.nullspace import compound

    path = tmp_path / "telescope.urdf"
    path.write_text(telescope_urdf(np.random.default_rng(5), 3, "planar"))
    monkeypatch.setattr(compound, "_new_directions", _old_new_directions)
    robot = _load(path)
    unchecked = drng(robot, check=False)
    assert _column_residuals(robot, unchecked.columns).max() > 1e-4  # the defect is real
    res = drng(robot)
    assert len(res.notes) == 1 and res.notes[0].startswith("R-C compound joints: ")
    assert "not in the nullspace" in res.notes[0] and "\n" not in res.notes[0]
    assert _column_residuals(robot, res.columns).max() < 1e-10
    a = bp.analyze(robot)
    assert a.certified and a.nullity == _pinocchio_nullity(path)[0]
    assert a.to_json()["drng"]["notes"] == list(res.notes)
    assert f"  note: {res.notes[0]}" in format_report(a)


def _bogus(robot, label: str, source: Source) -> Columns:
    """A column that no rule may give: the last body's mass alone."""
    e = np.zeros(10)
    e[9] = 1.0
    return on_bodies([robot.n - 1], e[None], source, label)


@pytest.mark.parametrize("n", [6, 45])  # the stacked regressor; the structured wrench maps (large trees)
def test_a_wrong_rule_is_named(n, monkeypatch):
    """A rule emitting a column outside the nullspace: named in the notes, its column not used, the
    others kept (the rank is the right one)."""
    robot = bp.robots.random_robot(np.random.default_rng(n), n, "RP")
    right = drng(robot)
    assert right.notes == ()
    real = drng_module.rule_columns
    monkeypatch.setattr(drng_module, "rule_columns",
                        lambda r, tol=1e-9: Columns.concat([real(r, tol), _bogus(r, "a mass alone", Source.R_B)]))
    res = drng(robot)
    assert len(res.notes) == 1 and res.notes[0].startswith("R-B sliding points: 1 of ")
    assert f"bodies {robot.names[-1]}: a mass alone" in res.notes[0]
    assert res.rank == right.rank and len(res.columns) == len(right.columns)


@pytest.mark.parametrize("seed", range(4))
def test_the_check_passes_every_right_rule(seed):
    """Random trees with compound joints, couplings and unmeasured joints, and a loop robot: no rule's
    column is left out (the check must not cost a right direction)."""
    rng = np.random.default_rng(40 + seed)
    robot = bp.robots.random_robot(rng, int(rng.integers(3, 9)), "RPCUS", floating=bool(seed % 2))
    assert drng(robot).notes == ()
    assert drng(robot, rows="joints").notes == ()
    chk = RuleCheck(robot)
    raw = drng(robot, check=False).columns
    res, tol = chk.residuals(raw)
    assert res.max() < 1e-6 * tol  # far below the tolerance: the check is coarse on purpose


@pytest.mark.shared
@pytest.mark.parametrize("rel", ["urdfplus/four_bar.urdf", "urdfplus/six_bar.urdf", "mjcf/agility_cassie/cassie.xml"])
def test_the_check_passes_loop_robots(rel):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = bp.load(str(SHARED / rel))
    assert drng(robot).notes == ()


def _widened(cols: Columns, n: int, rng) -> Columns:
    """The same span with each column plus random multiples of up to four columns of lower bodies:
    columns on four to six bodies, carried in ``more``."""
    b = to_dense(cols, n)
    out = []
    for j in range(len(cols)):
        lower = np.flatnonzero(cols.child < cols.child[j])
        x = b[:, j] + (b[:, rng.choice(lower, min(4, len(lower)), replace=False)] @ rng.normal(size=min(4, len(lower)))
                       if len(lower) else 0.0)
        blk = x.reshape(n, 10)
        who = [int(i) for i in np.flatnonzero(np.abs(blk).max(axis=1) > 0)]
        out.append(on_bodies(who, blk[who].reshape(1, -1), Source.R_M, "widened"))
    return Columns.concat(out)


@pytest.mark.parametrize("seed", range(3))
def test_every_consumer_carries_every_block(seed):
    """Columns with blocks on more than three bodies (``more``): the per-body maps, the norms, the
    sparse and the recursive regroupings treat them as the dense matrix does (the regroupings read
    child, parent and extra only before: K off by up to 170)."""
    from baseparams.base.recursive import recursive_base_parameters
    from baseparams.base.sparse import tree_base_parameters
    from baseparams.model.scale import decision_frames
    from baseparams.nullspace.structured import independent_columns

    rng = np.random.default_rng(seed)
    robot = bp.robots.random_robot(rng, 8, "RP")
    cols = independent_columns(robot, drng(robot))
    wide = _widened(cols, robot.n, rng)
    assert wide.has_more().sum() >= len(wide) // 3
    f = decision_frames(robot)[0]
    dense = to_dense(wide, robot.n)
    mapped = np.einsum("bij,bjk->bik", f, dense.reshape(robot.n, 10, -1)).reshape(10 * robot.n, -1)
    assert np.allclose(to_dense(wide.transformed(f), robot.n), mapped, rtol=1e-12, atol=1e-12)
    assert np.allclose(wide.norms(), np.linalg.norm(dense, axis=0))
    s = rng.uniform(0.5, 2, len(wide))
    assert np.allclose(to_dense(wide.times(s), robot.n), dense * s)
    for convention in ("paper", "khalil"):
        ref = tree_base_parameters(robot, cols, convention)
        k_ref = np.asarray(ref.K)
        for got in (tree_base_parameters(robot, wide, convention), recursive_base_parameters(robot, wide, convention)):
            assert np.array_equal(got.dependent, ref.dependent)
            assert np.abs(np.asarray(got.K) - k_ref).max() <= 1e-9 * np.abs(k_ref).max()
