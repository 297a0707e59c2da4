"""What identification says about its own results: excitation claims and the physical fit's masses."""

import numpy as np
import pytest

import baseparams
from baseparams.ident import identify
from baseparams.ident.report import format_identification
from baseparams.ident.simulate import simulate_log


def test_all_excited_only_when_every_term_is_determined():
    robot = baseparams.load("puma560")
    good, _ = simulate_log(robot, duration=20, rate=200, noise=0.01, seed=2)
    res = identify(robot, good, method="ols")
    e = res.to_json()["excitation"]
    # Puma560 has parameters near zero (link4.MX): %sigma above 100 there, known to the noise (not poorly
    # determined) but not "all excited": that claim needs every %sigma at most 100
    above = [n for n, s in zip(res.model.names, res.fit.estimate.pct_sigma) if s > 100]
    assert above and e["above_100"] == above
    assert not e["all_excited"] and not e["poorly_determined"]
    assert f"{len(above)} term(s) with %sigma above 100" in format_identification(res)
    # the claim is made only when nothing is weak, poorly determined or above 100 %sigma
    from baseparams.ident.report import _excitation_line

    clean = {"weak": [], "poorly_determined": [], "above_100": []}
    assert "every model parameter excited and determined" in _excitation_line(clean)
    assert "every model parameter" not in _excitation_line({**clean, "above_100": ["link4.MX"]})
    # a short, small, noisy motion: the values are not determined although no direction is singular
    poor, _ = simulate_log(robot, duration=3, rate=200, amplitude=0.05, noise=2.0, seed=2)
    res = identify(robot, poor, method="ols")
    e = res.to_json()["excitation"]
    pct = dict(zip(res.model.names, res.fit.estimate.pct_sigma))
    assert not e["all_excited"] and e["poorly_determined"]
    assert all(pct[n] > 100 for n in e["poorly_determined"])
    assert "poorly determined" in format_identification(res)


def test_physical_fit_names_bodies_whose_mass_moved_far_from_the_file():
    pytest.importorskip("cvxpy")
    robot = baseparams.load("puma560")
    log, _ = simulate_log(robot, duration=20, rate=200, noise=0.01, seed=4)
    # the model file says link3 weighs 5x what it does: the data pull it back
    n = robot.N_body.copy()
    n[2] *= 5.0
    from dataclasses import replace

    wrong = replace(robot, N_body=n)
    res = identify(wrong, log, method="physical")
    moved = res.to_json()["physical"]["masses_moved"]
    assert "link3" in moved and moved["link3"]["file"] == pytest.approx(5 * robot.N_body[2, 3, 3])
    assert moved["link3"]["identified"] < moved["link3"]["file"] / 2
    assert "body link3 has" in format_identification(res)
    assert set(moved) <= set(robot.names)
    assert np.isfinite(moved["link3"]["identified"])
