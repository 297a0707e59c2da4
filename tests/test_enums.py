"""The named choices (:mod:`baseparams.enums`) and the one table of parameter conventions."""

from __future__ import annotations

import json

import numpy as np
import pytest

import baseparams
from baseparams.base.regroup import parameter_names
from baseparams.enums import Convention, JointType, Rows, Source, Status
from baseparams.errors import ModelError
from baseparams.model import inertia
from baseparams.model.robot import JOINT_TYPES, LOOP_TYPES, NDOF
from baseparams.nullspace.columns import EXTENDED, PAPER, PRINCIPLES, UNMEASURED
from baseparams.numerics import ROWS
from baseparams.robots import puma560


def test_values_are_todays_strings():
    assert [str(c) for c in Convention] == ["paper", "khalil", "pinocchio", "idyntree", "rpna"]
    assert [str(r) for r in Rows] == ["all", "joints", "base"]
    assert [str(s) for s in Status] == ["certified", "completed", "undecided", "failed", "unverified"]
    assert [str(t) for t in JointType] == ["R", "P", "U", "S", "F", "C", "fixed"]
    assert Status.CERTIFIED == "certified" and f"{Rows.JOINTS}" == "joints"
    assert json.dumps({"status": Status.FAILED}) == '{"status": "failed"}'
    assert repr(Status.CERTIFIED) == "'certified'" and repr((Rows.ALL, Convention.PAPER)) == "('all', 'paper')"


def test_public_tuples_are_plain_strings():
    assert baseparams.CONVENTIONS == ("paper", "khalil", "pinocchio", "idyntree", "rpna")
    assert ROWS == ("all", "joints", "base")
    assert baseparams.analysis.STATUSES == ("certified", "completed", "undecided", "failed", "unverified")
    assert JOINT_TYPES == ("R", "P", "U", "S", "F", "C")
    assert LOOP_TYPES == ("R", "P", "U", "S", "fixed")
    for t in (baseparams.CONVENTIONS, ROWS, JOINT_TYPES, LOOP_TYPES):
        assert all(type(x) is str for x in t)  # reprs in error messages read as before
    assert {t: NDOF[t] for t in ("R", "P", "U", "S", "F", "fixed")} == {"R": 1, "P": 1, "U": 2, "S": 3, "F": 6,
                                                                         "fixed": 0}


def test_sources_keep_their_printed_names():
    assert PAPER == ("shared points", "fixed points", "planar rotations")
    assert EXTENDED == ("R-A fixed vectors", "R-B sliding points", "R-L1 parallelograms", "R-L2 level chains",
                        "R-L3 planar loops", "R-L4 spatial parallelograms", "R-M coupled joints",
                        "R-C compound joints")
    assert UNMEASURED == "unmeasured root"
    # the measured rows' own sources follow the extended rules (added labels; the old ones kept)
    assert PRINCIPLES == PAPER + EXTENDED + (UNMEASURED, "unmeasured body", "passive joint", "numerical")
    assert [s for s in Source if s.is_rows] == [Source.UNMEASURED, Source.UNSEEN, Source.PASSIVE]
    assert [int(s) for s in Source] == list(range(len(PRINCIPLES)))
    assert [s.label for s in Source] == list(PRINCIPLES)
    assert [s for s in Source if s.is_paper] == [Source.SHARED_POINTS, Source.FIXED_POINTS, Source.PLANAR_ROTATIONS]


def test_check_convention_returns_the_enum():
    for c in Convention:
        assert inertia.check_convention(str(c)) is c
        assert inertia.check_convention(c) is c
    with pytest.raises(ModelError, match="unknown parameter convention 'symoro'"):
        inertia.check_convention("symoro")


def test_one_table_for_every_convention():
    assert tuple(inertia.SPECS) == tuple(Convention)
    for c, spec in inertia.SPECS.items():
        assert spec.convention is c
        assert len(spec.names) == len(spec.fields) == 10 == len(set(spec.fields)) == len(set(spec.names))
        assert set(spec.fields) <= set(inertia.PARAMETER_FIELDS)
        assert sorted(spec.regroup) == sorted(spec.fields)
        assert sorted(spec.regroup_order) == list(range(10))
        assert inertia.NAMES[c] == spec.names and inertia.FRAMES[c] == spec.frame
        # length exponents match the names: mass 0, first moments 1, second moments 2
        want = [0 if n.lower() == "m" else 1 if n.lower() in ("mx", "my", "mz", "mcx", "mcy", "mcz") else 2
                for n in spec.names]
        assert inertia.LENGTH_POWER[c].tolist() == want
        # the regrouping tries the mass first, then the first moments
        assert [spec.length_power[i] for i in spec.regroup_order[:4]] == [0, 1, 1, 1]


def _random_pseudo(rng, k):
    a = rng.normal(size=(k, 4, 4))
    return a @ np.swapaxes(a, -1, -2)  # symmetric positive definite: pseudo-inertias


@pytest.mark.parametrize("convention", list(Convention))
def test_converters_round_trip(convention):
    rng = np.random.default_rng(3)
    n = _random_pseudo(rng, 7)
    p = inertia.to_convention(n, convention)
    assert p.shape == (7, 10)
    np.testing.assert_allclose(inertia.from_convention(p, convention), n, rtol=0, atol=1e-12)
    np.testing.assert_allclose(inertia.from_convention(p, str(convention)), n, rtol=0, atol=1e-12)
    # every convention is a permutation of the same ten numbers as khalil's link-frame ones
    q = inertia.to_convention(n, "khalil")
    if convention != "paper":
        idx = [inertia.SPECS[Convention.KHALIL].fields.index(f) for f in inertia.SPECS[convention].fields]
        np.testing.assert_array_equal(p, q[:, idx])
    m, h, _ = inertia.split(n)
    by = dict(zip(inertia.SPECS[convention].fields, np.moveaxis(p, -1, 0)))
    np.testing.assert_array_equal(by["m"], m)
    np.testing.assert_array_equal(np.stack([by["hx"], by["hy"], by["hz"]], -1), h)


def test_unknown_convention_in_converters():
    with pytest.raises(ValueError, match="unknown parameter convention"):
        inertia.to_convention(np.eye(4), "symoro")
    with pytest.raises(ValueError, match="unknown parameter convention"):
        inertia.from_convention(np.zeros(10), "symoro")


def test_enum_accepted_at_the_boundaries():
    robot = puma560()
    for c in Convention:
        np.testing.assert_array_equal(robot.parameters(c), robot.parameters(str(c)))
        assert parameter_names(robot, c) == parameter_names(robot, str(c))
