"""A rank is stated only at a gap (issue 46): the structure of a spectrum - clusters of singular values and
the gaps between them - decides a count, never a fixed threshold that lands inside a cluster. Spectra are
built from clusters whose neighbour ratios are at most 3 and joined by true gaps (>= 1000x) or by steps
that are no gap (<= 20x), so the right answer is known by construction."""

from __future__ import annotations

import numpy as np
import pytest

from baseparams.numerics import GAP_RATIO, rank_decision, spectrum


def clustered(rng, zeros: int = 5):
    """``(values, boundaries)``: a descending spectrum of 2-5 clusters and the true cluster boundaries (ranks)."""
    values, bounds, level = [], [], 1.0
    for c in range(int(rng.integers(2, 6))):
        if c and level < 1e-4:
            break  # the real values stay above 1e-12, the zeros 1e4 below them
        if c:
            if rng.random() < 0.6:
                level /= 10 ** rng.uniform(3, 4)  # a true gap
                bounds.append(len(values))
            else:
                level /= rng.uniform(1.0, 20.0)  # a step inside a continuum: no gap
        for _ in range(int(rng.integers(1, 8))):
            values.append(level)
            level /= rng.uniform(1.0, 3.0)
    bounds.append(len(values))
    values += list(rng.uniform(1e-18, 1e-16, zeros))  # rounding of zero
    return np.array(values), [0, *bounds, len(values)]


@pytest.mark.parametrize("seed", range(200))
def test_cuts_are_the_true_gaps_and_a_bound_inside_a_cluster_decides_nothing(seed):
    rng = np.random.default_rng(seed)
    s, bounds = clustered(rng)
    sp = spectrum(rng.permutation(s) * 7.0)  # any order, any scale
    assert list(sp.cuts) == bounds
    assert sum(c.count for c in sp.clusters) == len(s)
    for c in sp.clusters:
        assert c.spread < GAP_RATIO or c.zero
    for bound in 10 ** rng.uniform(-15, 0, 20):
        k = int(np.sum(s > bound))  # the count a threshold states
        inside = sp.straddling(bound)
        assert (inside is None) == (k in bounds)
        if inside is not None:  # the count would be inside this cluster: both candidates are at gaps
            assert inside.first < k < inside.stop and inside.first in bounds and inside.stop in bounds


@pytest.mark.parametrize("seed", range(40))
def test_the_literal_rank_is_decided_only_at_a_gap(seed):
    """numerics.rank_decision: ``decided`` iff the 1e-9 tolerance lies in a true gap of at least 1e4 (min_gap)."""
    rng = np.random.default_rng(seed)
    s, bounds = clustered(rng)
    n = len(s)
    u = np.linalg.qr(rng.normal(size=(3 * n, n)))[0]
    v = np.linalg.qr(rng.normal(size=(n, n)))[0]
    res = rank_decision((u * s) @ v.T)
    k = int(np.sum(s > 1e-9 * s[0]))
    gap = s[k - 1] / s[k] if 0 < k < n else np.inf
    assert res.rank == k
    assert res.decided == (k in bounds and gap >= 1e4)


def test_the_issue_hand_spectrum():
    """The CAD hand of issue 46: 34 directions >= 6.5e-3, a gap of 680, 10 between 9.5e-6 and 9.4e-7
    (neighbour ratios <= 1.9), a gap of 300, 9 between 4e-9 and 2e-11, zeros. The practical threshold
    (1e-6) and the literal one (1e-9) both fall inside a cluster: no count; the candidates are 34, 44, 53;
    the snapped geometry's spectrum (34, then zeros 5e13 below) states 34."""
    rng = np.random.default_rng(1)
    s = np.r_[np.geomspace(1, 6.5e-3, 34), np.geomspace(9.5e-6, 9.4e-7, 10), np.geomspace(4e-9, 2e-11, 9),
              rng.uniform(1e-18, 1e-16, 27)]
    sp = spectrum(s)
    assert sp.cuts == (0, 34, 44, 53, 80)
    practical, literal = sp.straddling(1e-6), sp.straddling(1e-9)
    assert (practical.first, practical.stop) == (34, 44) and (literal.first, literal.stop) == (44, 53)
    assert "10 directions 9.4e-07 - 9.5e-06" in sp.lines()[1]
    snapped = spectrum(np.r_[np.geomspace(1, 6.5e-3, 34), 1.3e-16 * rng.uniform(0.1, 1, 46)])
    assert snapped.cuts == (0, 34, 80) and snapped.straddling(1e-6) is None and snapped.gap(34) > 1e12


def test_a_continuum_has_no_gap_and_a_lone_large_step_in_it_is_none():
    """Neighbour ratios of 30-60 with one step of 150: the step does not stand out (10x) from the steps around it."""
    rng = np.random.default_rng(3)
    steps = rng.uniform(30, 60, 12)
    steps[6] = 150.0
    s = np.r_[1.0, np.cumprod(1 / steps)]
    sp = spectrum(s)
    assert sp.cuts == (0, len(s)) and sp.straddling(1e-9) is not None
