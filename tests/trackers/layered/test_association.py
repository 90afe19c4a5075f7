"""PBM layered-association scoring (eqs. 11-13): the compiled kernels of
``occbench.trackers.layered.association`` against the plain-numpy equations
(``differences``, ``scores``), equal to rounding (rtol 1e-9: the kernels sum in their own
order and take the normal CDF from ``math.erfc``), on mixtures of 1-3 components, empty
parts, degenerate rectangles and any histogram size; and the best/runner-up rule.
"""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered.association import (
    ambiguous,
    ambiguous_rows,
    feature_differences,
    layered_scores,
    pair_scores,
    selected_differences,
)
from occbench.trackers.layered.differences import differences
from occbench.trackers.layered.feature_models import FeatureModels
from occbench.trackers.layered.parts import FEATURES, N_PARTS
from occbench.trackers.layered.scores import global_score, match_probability, part_scores
from pbm_scenes import random_features, random_models

NF = len(FEATURES)
RTOL, ATOL = 1e-9, 1e-12  # rounding: the kernels' summation order and erfc against numpy's


# ----------------------------------------------------------------------------- references


def ref_ambiguous(scores: np.ndarray, threshold: float, margin: float) -> tuple[int, int, bool]:
    """The argsort implementation the kernel replaced."""
    if len(scores) == 0:
        return -1, -1, False
    order = np.argsort(-scores, kind="stable")
    best = int(order[0])
    if not np.isfinite(scores[best]) or scores[best] < threshold:
        return -1, -1, False
    runner = int(order[1]) if len(order) > 1 and np.isfinite(scores[order[1]]) else -1
    amb = runner >= 0 and scores[runner] >= threshold and scores[best] < margin * scores[runner]
    return best, runner, bool(amb)


# ----------------------------------------------------------------------------- inputs


@pytest.fixture(scope="module")
def rng() -> np.random.Generator:
    return np.random.default_rng(20)


# ----------------------------------------------------------------------------- tests


def test_match_probability_equals_numpy_for_1_2_and_3_components(rng):
    models = random_models(rng)
    d = np.abs(rng.normal(0, 1, (400, NF, N_PARTS))) * rng.choice([1e-3, 0.05, 0.3, 3, 50],
                                                                   (400, NF, N_PARTS))
    d[::7] = 0.0
    d[1::11] *= -1.0  # negative differences count as 0
    np.testing.assert_allclose(models.match_probability(d), match_probability(models, d),
                               rtol=RTOL, atol=ATOL)
    assert models.match_probability(d[0]).shape == (NF, N_PARTS)
    default = FeatureModels.default()
    np.testing.assert_allclose(default.match_probability(d), match_probability(default, d),
                               rtol=RTOL, atol=ATOL)


@pytest.mark.parametrize("with_misses", [False, True])
def test_selected_and_all_pairs_differences_equal_numpy(rng, with_misses):
    model, cand = random_features(rng, 7), random_features(rng, 9)
    misses = rng.integers(0, 4, 7) if with_misses else None
    ti, n = np.nonzero(rng.random((7, 9)) < 0.5)
    got = selected_differences(model, cand, ti, n, misses)
    np.testing.assert_allclose(got, differences(model, cand, ti, n, misses), rtol=RTOL, atol=ATOL)
    np.testing.assert_array_equal(got, feature_differences(model, cand, misses)[ti, n])
    assert (got[:, 2:4][cand.area[n][:, None, :].repeat(2, 1) <= 0] == 1.0).all()  # empty parts
    assert feature_differences(model, cand.take([]), misses).shape == (7, 0, NF, N_PARTS)


def test_a_gap_divides_displacement_and_overlap(rng):
    """Eq. 11 after m frames unfound: displacement and overlap 1 - IoU / (1 + m) (our
    reading); a target found last frame has no gap."""
    model, cand = random_features(rng, 2), random_features(rng, 1)
    cand.parts[0] = model.parts[1] + [500.0, 0.0, 0.0, 0.0]  # far right of target 1: IoU 0
    ti, n, misses = np.array([0, 1]), np.array([0, 0]), np.array([0, 3])
    step = selected_differences(model, cand, ti, n)
    divided = selected_differences(model, cand, ti, n, misses)
    np.testing.assert_array_equal(step[1, 5], 1.0)
    np.testing.assert_allclose(divided[1, 4:6], step[1, 4:6] / 4, rtol=RTOL)
    np.testing.assert_array_equal(divided[0], step[0])  # found last frame: no gap
    np.testing.assert_array_equal(divided[:, :4], step[:, :4])
    np.testing.assert_array_equal(feature_differences(model, cand, misses)[ti, n], divided)


def test_parts_apart_from_the_candidate_keep_their_whole_overlap_after_a_gap(rng):
    """``adaptations.apart_undivided``: a target none of whose parts overlaps the
    candidate's (every 1 - IoU = 1) has overlap 1 whatever its gap; its displacement is
    still divided, and a target with one part overlapping is divided as before (the
    stairwell, ecp1-180 gt seed 1000 frame 168: 1 / (1 + 9) made no overlap beat some)."""
    model, cand = random_features(rng, 3), random_features(rng, 1)
    cand.parts[0] = model.parts[1] + [500.0, 0.0, 0.0, 0.0]  # far right of target 1: IoU 0
    model.parts[2] = cand.parts[0] + [600.0, 0.0, 0.0, 0.0]  # target 2 apart too ...
    model.parts[2, 0] = cand.parts[0, 0]                     # ... but for its head part
    ti, n, misses = np.array([0, 1, 2]), np.array([0, 0, 0]), np.array([0, 9, 9])
    divided = selected_differences(model, cand, ti, n, misses)
    whole = selected_differences(model, cand, ti, n, misses, apart=True)
    np.testing.assert_array_equal(divided[1, 5], 0.1)    # the gap division: 1 / (1 + 9)
    np.testing.assert_array_equal(whole[1, 5], 1.0)      # apart: undivided
    np.testing.assert_array_equal(whole[1, :5], divided[1, :5])  # displacement still divided
    np.testing.assert_array_equal(whole[[0, 2]], divided[[0, 2]])  # a part overlaps: as before
    assert whole[2, 5, 0] == 0.0 and (whole[2, 5, 1:] == 0.1).all()
    np.testing.assert_allclose(differences(model, cand, ti, n, misses, True), whole,
                               rtol=RTOL, atol=ATOL)
    np.testing.assert_array_equal(differences(model, cand, ti, n, misses, True)[:, 5],
                                  whole[:, 5])
    np.testing.assert_array_equal(feature_differences(model, cand, misses, True)[ti, n], whole)
    np.testing.assert_array_equal(selected_differences(model, cand, ti, n, None, True),
                                  selected_differences(model, cand, ti, n))  # no gap: 1 anyway


@pytest.mark.parametrize("bins", [1, 2, 3, 5, 6, 8])
def test_histogram_term_for_any_bins(rng, bins):
    """B = bins**3 from 1 to 512."""
    model, cand = random_features(rng, 3, bins), random_features(rng, 4, bins)
    ti, n = np.nonzero(np.ones((3, 4), bool))
    np.testing.assert_allclose(selected_differences(model, cand, ti, n),
                               differences(model, cand, ti, n, None), rtol=RTOL, atol=ATOL)


def test_layered_scores_equal_numpy(rng):
    models = random_models(rng)
    d = np.abs(rng.normal(0, 0.3, (5, 8, NF, N_PARTS)))
    d[0, 0] = 0.0
    omega = rng.uniform(0.1, 1, NF)
    gamma = rng.uniform(0.1, 1, N_PARTS)
    pj, p = layered_scores(models, d, omega, gamma, 3.0)
    np.testing.assert_allclose(pj, part_scores(models, d, omega, 3.0), rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(p, global_score(pj, gamma), rtol=RTOL, atol=ATOL)
    assert pj.shape == (5, 8, N_PARTS) and p.shape == (5, 8)
    pj1, p1 = layered_scores(models, d[0, 0], omega, gamma)
    assert pj1.shape == (N_PARTS,) and p1.shape == ()
    with pytest.raises(ValueError, match="omega"):
        layered_scores(models, d, omega[:5], gamma)


def test_pair_scores_fuse_the_three_layers(rng):
    models = random_models(rng)
    model, cand = random_features(rng, 6), random_features(rng, 40)
    misses = rng.integers(0, 3, 6)
    omega, gamma = rng.uniform(0.1, 1, NF), rng.uniform(0.1, 1, N_PARTS)
    ti, n = np.nonzero(rng.random((6, 40)) < 0.3)
    pj, p = pair_scores(models, model, cand, ti, n, misses, omega, gamma, 2.5)
    pj_ref, p_ref = layered_scores(models, selected_differences(model, cand, ti, n, misses),
                                   omega, gamma, 2.5)
    np.testing.assert_array_equal(pj, pj_ref)
    np.testing.assert_array_equal(p, p_ref)
    # the search path: every carved box k scored against the model of its target tis[k]
    tis = rng.integers(0, 6, 40)
    cand.parts[:5] = model.parts[tis[:5]]  # identical rectangles: IoU 1
    pj, p = pair_scores(models, model, cand, tis, np.arange(40), misses, omega, gamma, 2.5)
    d_ref = differences(model.take(tis), cand, np.arange(40), np.arange(40), misses[tis])
    pj_ref, p_ref = layered_scores(models, d_ref, omega, gamma, 2.5)
    np.testing.assert_allclose(pj, pj_ref, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(p, p_ref, rtol=RTOL, atol=ATOL)
    # no pairs; a pair index out of range
    pj, p = pair_scores(models, model, cand, np.zeros(0, int), np.zeros(0, int), misses, omega, gamma)
    assert pj.shape == (0, N_PARTS) and p.shape == (0,)
    with pytest.raises(IndexError):
        pair_scores(models, model, cand, np.array([6]), np.array([0]), misses, omega, gamma)


def test_ambiguous_equals_the_sort_based_rule(rng):
    cases = [np.array([]), np.array([0.5]), np.array([-np.inf, -np.inf]),
             np.array([np.nan, 0.7, 0.7]), np.array([0.6, 0.6, np.nan]), np.array([np.inf, 0.3])]
    for _ in range(300):
        s = np.round(rng.uniform(0, 1, rng.integers(1, 12)), 1)  # ties are frequent
        s[rng.random(len(s)) < 0.3] = -np.inf
        cases.append(s)
    for s in cases:
        for threshold, margin in ((0.25, 1.1), (0.5, 1.5)):
            got = ambiguous(s, threshold, margin)
            assert got == ref_ambiguous(s, threshold, margin), s
            assert type(got[0]) is int and type(got[2]) is bool


def test_ambiguous_rows_equal_ambiguous_per_row(rng):
    scores = np.round(rng.uniform(0, 1, (40, 9)), 1)
    scores[rng.random(scores.shape) < 0.4] = -np.inf
    scores[3] = -np.inf
    best, runner, amb = ambiguous_rows(scores, 0.25, 1.1)
    for t in range(40):
        assert (int(best[t]), int(runner[t]), bool(amb[t])) == ambiguous(scores[t], 0.25, 1.1)
    assert ambiguous_rows(np.zeros((0, 4)), 0.25, 1.1)[0].shape == (0,)
    assert ambiguous_rows(np.zeros((2, 0)), 0.25, 1.1)[0].tolist() == [-1, -1]


def test_bad_pairs_raise(rng):
    model, cand = random_features(rng, 3), random_features(rng, 4)
    with pytest.raises(IndexError, match="out of range"):
        selected_differences(model, cand, np.array([0, 3]), np.array([0, 1]))
    with pytest.raises(IndexError, match="out of range"):
        selected_differences(model, cand, np.array([0]), np.array([4]))
    with pytest.raises(ValueError, match="equal-length"):
        selected_differences(model, cand, np.array([0, 1]), np.array([0]))
    with pytest.raises(ValueError, match="bins differ"):
        selected_differences(model, random_features(rng, 4, bins=3), np.array([0]), np.array([0]))
