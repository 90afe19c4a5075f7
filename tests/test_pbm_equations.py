"""The compiled PBM kernels against the plain-numpy equations of
``trackers.layered.equations`` (eqs. 1-2, 9-10, 11, 12, 13), to a tolerance (rtol 1e-9),
not bit for bit."""

from __future__ import annotations

import numpy as np
from test_pbm_scoring import random_features, random_models

from trackers.layered.parts import N_PARTS, PartFeatureExtractor
from trackers.layered import equations as E
from trackers.layered.association import pair_scores, selected_differences
from trackers.layered.search import search_boxes_many

RTOL, ATOL = 1e-9, 1e-12


def test_eq11_to_13_kernels_equal_the_equations():
    rng = np.random.default_rng(7)
    models = random_models(rng)
    model, cand = random_features(rng, 6), random_features(rng, 30)
    misses = rng.integers(0, 4, 6)
    omega, gamma = rng.uniform(0.1, 1, 6), rng.uniform(0.1, 1, N_PARTS)
    ti, n = np.nonzero(rng.random((6, 30)) < 0.4)
    d = E.differences(model, cand, ti, n, misses)                       # eq. 11
    np.testing.assert_allclose(selected_differences(model, cand, ti, n, misses), d,
                               rtol=RTOL, atol=ATOL)
    pj_ref = E.part_scores(models, d, omega, 2.5)                       # eq. 12
    p_ref = E.global_score(pj_ref, gamma)                               # eq. 13
    pj, p = pair_scores(models, model, cand, ti, n, misses, omega, gamma, 2.5)
    np.testing.assert_allclose(pj, pj_ref, rtol=RTOL, atol=1e-9)  # the kernels' ndtr table: 3e-10
    np.testing.assert_allclose(p, p_ref, rtol=RTOL, atol=1e-9)
    assert ((p >= 0) & (p <= 1)).all()


def test_eq9_10_kernel_equals_the_equation():
    rng = np.random.default_rng(8)
    heads = np.column_stack([rng.uniform(0, 300, 5), rng.uniform(0, 200, 5), rng.uniform(4, 20, 5)])
    wh = rng.uniform(10, 120, (5, 2))
    alpha = rng.uniform(0.3, 0.7, 5)
    got = search_boxes_many(heads, wh, alpha, 0.05, 2)
    for s in range(5):
        np.testing.assert_allclose(got[s], E.search_boxes(heads[s], wh[s], alpha[s], 0.05, 2),
                                   rtol=RTOL, atol=ATOL)


def test_eq1_2_ratios_of_the_extractor_equal_the_equation():
    """extract_at_centroids measures the centroids and alpha, beta (eqs. 1-2) in one
    compiled pass; the parts it splits equal those split at eqs. 1-2's ratios."""
    rng = np.random.default_rng(9)
    frame = rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)
    fg = rng.random((120, 160)) < 0.6
    boxes = np.array([[10.0, 5.0, 40.0, 100.0], [70.0, 20.0, 30.0, 84.0]])
    ex = PartFeatureExtractor()
    ex.start(frame, fg)
    cents, feats = ex.extract_at_centroids(boxes)
    alpha, beta = E.centroid_ratios(boxes, cents)                       # eqs. 1-2
    ref = ex.extract(boxes, alpha, beta)
    np.testing.assert_allclose(feats.parts, ref.parts, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(feats.hsv, ref.hsv, rtol=RTOL, atol=ATOL)
