"""The compiled PBM kernels against the plain-numpy equations beside them (eqs. 1-2,
``split``; 7, 8, ``dynamics``; 9-10, ``search``; 11, ``differences``; 12, 13, ``scores``;
the section 4.2 update, ``model_update``), to a tolerance (rtol 1e-9), not bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered.association import pair_scores, selected_differences
from occbench.trackers.layered.differences import differences
from occbench.trackers.layered.dynamics import cv_predicted, cv_updated, kf1_z, kf2_z
from occbench.trackers.layered.model_update import update_global, update_parts
from occbench.trackers.layered.parts import N_PARTS, PartFeatureExtractor
from occbench.trackers.layered.scores import global_score, part_scores
from occbench.trackers.layered.search import search_boxes, search_boxes_many
from occbench.trackers.layered.split import centroid_ratios, dof_from_head, part_boxes
from pbm_scenes import random_features, random_models

RTOL, ATOL = 1e-9, 1e-12


@pytest.mark.parametrize("apart", [False, True])
def test_eq11_to_13_kernels_equal_the_equations(apart):
    rng = np.random.default_rng(7)
    models = random_models(rng)
    model, cand = random_features(rng, 6), random_features(rng, 30)
    cand.parts[:5] += [400.0, 0.0, 0.0, 0.0]  # apart from every model's parts (IoU 0)
    misses = rng.integers(0, 4, 6)
    omega, gamma = rng.uniform(0.1, 1, 6), rng.uniform(0.1, 1, N_PARTS)
    ti, n = np.nonzero(rng.random((6, 30)) < 0.4)
    d = differences(model, cand, ti, n, misses, apart)  # eq. 11
    np.testing.assert_allclose(selected_differences(model, cand, ti, n, misses, apart), d,
                               rtol=RTOL, atol=ATOL)
    pj_ref = part_scores(models, d, omega, 2.5)                       # eq. 12
    p_ref = global_score(pj_ref, gamma)                               # eq. 13
    pj, p = pair_scores(models, model, cand, ti, n, misses, omega, gamma, 2.5, apart)
    np.testing.assert_allclose(pj, pj_ref, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(p, p_ref, rtol=RTOL, atol=ATOL)
    assert ((p >= 0) & (p <= 1)).all()


def test_eq9_10_batch_equals_the_equation():
    rng = np.random.default_rng(8)
    heads = np.column_stack([rng.uniform(0, 300, 5), rng.uniform(0, 200, 5), rng.uniform(4, 20, 5)])
    wh = rng.uniform(10, 120, (5, 2))
    alpha = rng.uniform(0.3, 0.7, 5)
    got = search_boxes_many(heads, wh, alpha, 0.05, 2)
    for s in range(5):
        np.testing.assert_allclose(got[s], search_boxes(heads[s], wh[s], alpha[s], 0.05, 2),
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
    alpha, beta = centroid_ratios(boxes, cents)                       # eqs. 1-2
    ref = ex.extract(boxes, alpha, beta)
    np.testing.assert_allclose(feats.parts, ref.parts, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(feats.hsv, ref.hsv, rtol=RTOL, atol=ATOL)


def test_eq7_8_filter_kernels_equal_the_equations():
    """KF1 (eq. 7) and KF2 (eq. 8): the per-axis compiled steps of ``ConstantVelocity2D``
    against the matrix form of ``dynamics.cv_predicted`` / ``cv_updated``."""
    from occbench.trackers.layered.dynamics import ConstantVelocity2D

    rng = np.random.default_rng(10)
    kf = ConstantVelocity2D(0.5, 0.2, 0.5)
    kf.add(np.array([40.0, 60.0]), 12.0)
    kf.add(np.array([120.0, 30.0]), 8.0)
    x, P = kf.state(1)
    for _ in range(30):
        kf.predict()
        x, P = cv_predicted(x, P, kf.qp[1], kf.qv[1])
        np.testing.assert_allclose(kf.state(1)[0], x, rtol=RTOL, atol=ATOL)
        np.testing.assert_allclose(kf.state(1)[1], P, rtol=RTOL, atol=ATOL)
        dof = np.r_[0.0, 0.0, x[:2] + rng.normal(0, 3, 2), 30.0, 80.0]
        z = kf1_z(dof)  # eq. 7
        kf.update(np.array([1]), z[None])
        x, P = cv_updated(x, P, z, kf.r[1])
        np.testing.assert_allclose(kf.state(1)[0], x, rtol=RTOL, atol=ATOL)
        np.testing.assert_allclose(kf.state(1)[1], P, rtol=RTOL, atol=ATOL)
    assert np.array_equal(kf2_z(np.arange(6.0)), [5.0, 4.0])  # eq. 8: (h, w)


def test_section_4_2_update_kernels_equal_the_equations():
    """The model update (PBM 4.2): ``Targets.update`` (global DOF, ratios, eqs. 1-2) and
    ``update_parts`` (running averages, frozen parts, rectangles) against
    ``model_update.update_global`` and ``model_update.update_parts``."""
    from occbench.trackers.layered.dynamics import Gate
    from occbench.trackers.layered import targets as T

    rng = np.random.default_rng(12)
    ex = PartFeatureExtractor()
    ex.start(rng.integers(0, 255, (160, 200, 3), dtype=np.uint8), rng.random((160, 200)) < 0.6)
    tg = T.Targets(Gate(3.0, 0.5, 2.0, 1.15, 4.0), (0.5, 0.2, 0.5), (0.2, 0.02, 0.5), 4, 3, 4)
    box = np.array([50.0, 20.0, 40.0, 110.0])
    tg.add(1, np.r_[box[:2], box[:2] + [20.0, 50.0], box[2:]], 0.5, 0.5, ex.extract(box[None]), None)
    window, ratio_window = [tg.dof[0].copy()], [[0.5, 0.5]]
    for k in range(8):
        occluded = k in (3, 4)
        dof = tg.dof[0] + np.r_[rng.normal(0, 2, 4), rng.normal(0, 1, 2)]
        window = (window + [dof])[-3:]
        want, ab = update_global(np.array(window), dof, occluded, np.array(ratio_window[-3:]))
        tg.predict()
        tg.update([0], [dof], [True], [occluded], np.ones((1, N_PARTS)), 0.4)
        np.testing.assert_allclose(tg.dof[0], want, rtol=RTOL, atol=ATOL)
        if ab is not None:
            a, b = centroid_ratios(want[[0, 1, 4, 5]], want[2:4])    # eqs. 1-2
            ratio_window.append([a[0], b[0]])
            np.testing.assert_allclose([tg.alpha[0], tg.beta[0]], ab, rtol=RTOL, atol=ATOL)
    boxes = np.column_stack([rng.uniform(0, 150, 7), rng.uniform(0, 60, 7), rng.uniform(10, 50, 7),
                             rng.uniform(30, 100, 7)])
    model, cand = ex.extract(boxes[:4], 0.45, 0.5), ex.extract(boxes, 0.5, 0.45)
    rows, ks = np.array([3, 0]), np.array([6, 2])
    pj = rng.random((2, N_PARTS))
    relearn = np.zeros((2, N_PARTS), bool)
    relearn[1, 2] = True
    shift, new_boxes = rng.normal(0, 2, (2, 2)), boxes[[1, 5]] + 1.0
    alpha, beta = rng.uniform(0.3, 0.7, 2), rng.uniform(0.3, 0.7, 2)
    want = [update_parts(model.take(r), cand.take(k), pj[q], 0.4, 0.3, shift[q], new_boxes[q],
                           alpha[q], beta[q], relearn[q], 0.8)
            for q, (r, k) in enumerate(zip(rows, ks))]
    T.update_parts(model, cand, T.PartMatches(rows, ks, pj, shift, new_boxes, alpha, beta, relearn),
                   T.PartRates(0.4, 0.3, 0.8))
    for q, r in enumerate(rows):
        for name in ("parts", "area", "perimeter", "hsv", "xyz", "centroid", "height"):
            np.testing.assert_allclose(getattr(model, name)[r], getattr(want[q], name)[0],
                                       rtol=RTOL, atol=ATOL, err_msg=name)
    assert ((pj >= 0.4) & ~relearn).any() and ((pj < 0.4) & ~relearn).any()  # both branches


def test_eq1_2_kernels_equal_the_equations():
    """The part split (``_part_rects``), the ratios (``_centroid_ratios``) and the DOF
    under occlusion (``_dof_from_head``, in ``carved_rows``) against eqs. 1-2."""
    from occbench.trackers.layered.gating import carved_rows

    rng = np.random.default_rng(13)
    frame = rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)
    boxes = np.column_stack([rng.uniform(0, 120, 6), rng.uniform(0, 40, 6), rng.uniform(10, 40, 6),
                             rng.uniform(30, 80, 6)])
    alpha, beta = rng.uniform(0.1, 0.9, 6), rng.uniform(0.1, 0.9, 6)
    ex = PartFeatureExtractor()
    ex.start(frame, None)
    np.testing.assert_allclose(ex.extract(boxes, alpha, beta).parts,
                               part_boxes(boxes, alpha, beta), rtol=RTOL, atol=ATOL)  # eqs. 1-2
    heads = np.column_stack([rng.uniform(0, 150, 6), rng.uniform(0, 50, 6), np.full(6, 8.0)])
    p, pj = rng.random(6), rng.random((6, N_PARTS))
    ti = np.arange(6)
    kept, _, _, k, dof = carved_rows(p, pj, boxes, heads, ti, alpha, beta, np.zeros(0, np.intp),
                                     np.arange(6), 1)
    assert kept.all() and np.array_equal(k, np.arange(6))
    np.testing.assert_allclose(dof, dof_from_head(heads, boxes[:, 2], boxes[:, 3], alpha, beta),
                               rtol=RTOL, atol=ATOL)
