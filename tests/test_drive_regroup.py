"""Which drive parameters regroup, decided on deep chains (issue 41: identification of large trees).

The decision is taken on the drive columns' part outside the base columns' span (``R22``, each
column scaled by its norm), so the base columns' scales and conditioning do not enter it. Oracle:
on fresh random states (not those the decision used), every eliminated column equals the kept
columns times ``K`` (``A_dep = A_ind K``), and no kept drive column is in the span of the others.
"""

from __future__ import annotations

import numpy as np
import pytest

from baseparams import load
from baseparams.analysis import analyze
from baseparams.ident.model import IdentModel, _identity_regrouping, ident_model
from baseparams.numerics import sample_states
from baseparams.robots.random import random_robot


def _probe_columns(model, states):
    """``[Yb | D]`` of the model's analysis and drives (nothing regrouped) at ``states``: ``(rows, nb + nd)``."""
    probe = IdentModel(model.analysis, model.drives, _identity_regrouping(model.analysis, model.drives),
                       model.coords, model.log_base)
    a = probe.regressor(*states)
    return a.reshape(-1, a.shape[2])


@pytest.mark.parametrize("n,seed", [(45, 0), (60, 1), (80, 2)])
def test_deep_chains_decide_and_the_regrouping_holds_on_fresh_states(n, seed):
    rng = np.random.default_rng(seed)
    robot = random_robot(rng, n=n, joint_types="RP", branching=0.0)
    model = ident_model(analyze(robot), True, ("viscous", "coulomb", "offset"), None)
    reg = model.regrouping
    assert reg.decided and reg.gap >= 1e4
    nb = len(model.analysis.base_names)
    assert np.all(reg.dependent >= nb)  # drive parameters are the ones absorbed
    q = sample_states(robot, 30, np.random.default_rng(seed + 100))[0]
    dq, ddq = np.random.default_rng(seed + 200).uniform(-1, 1, (2,) + q.shape)
    a = _probe_columns(model, (q, dq, ddq))
    ind, dep = reg.independent, reg.dependent
    scale = np.linalg.norm(a, axis=0)
    if len(dep):
        resid = a[:, dep] - a[:, ind] @ reg.K
        assert np.all(np.linalg.norm(resid, axis=0) <= 1e-8 * np.maximum(scale[dep], 1e-300) + 1e-12)
    # every kept drive column has a part outside the other kept columns' span
    kept = a[:, ind]
    kept = kept / np.maximum(np.linalg.norm(kept, axis=0), 1e-300)
    qmat, _ = np.linalg.qr(kept[:, :nb])
    for j in range(nb, len(ind)):
        col = kept[:, j]
        assert np.linalg.norm(col - qmat @ (qmat.T @ col)) > 1e-6


def test_a_6r_arm_regroups_as_before():
    model = ident_model(analyze(load("puma560")), True, ("viscous", "coulomb", "offset"), None)
    names = [model.regrouping.names[i] for i in model.regrouping.dependent]
    assert sorted(names) == ["Ia_joint1", "Ia_joint2"] and model.regrouping.gap > 1e10
