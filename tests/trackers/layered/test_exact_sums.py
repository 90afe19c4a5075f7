"""The shortcuts of the eq. 11-12 kernels give the bits of the plain sums, not only values
within a tolerance: rho summed over the occupied bins only (``_kernels.rho_bins``), eq. 12
with p(x | theta) recalled for a repeated x (``layered_scores``), and the search's boxes
scored as they are measured (``association.box_scores``)."""

from __future__ import annotations

import numpy as np
import pytest
from pbm_scenes import random_models

from occbench.trackers.layered._kernels import rho_bins
from occbench.trackers.layered.association import layered_scores
from occbench.trackers.layered.parts import N_FEATURES, N_PARTS


def _plain_rho(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """rho = sum_u sqrt(a_u b_u) over every bin, in bin order."""
    out = np.empty(a.shape[:2])
    for t in range(a.shape[0]):
        for j in range(a.shape[1]):
            tot = 0.0
            for u in range(a.shape[2]):
                with np.errstate(invalid="ignore"):  # inf * 0
                    tot += float(np.sqrt(a[t, j, u] * b[t, j, u]))
            out[t, j] = tot
    return out


def test_rho_over_occupied_bins_has_the_bits_of_the_full_sum():
    rng = np.random.default_rng(3)
    a = rng.random((40, 5, 64)) * (rng.random((40, 5, 64)) < 0.3)
    b = rng.random((40, 5, 64)) * (rng.random((40, 5, 64)) < 0.1)
    b[0] = 0.0  # an empty candidate
    a[1] = 0.0  # an empty model
    a[2, 0, 5], b[2, 0, 5] = np.nan, 0.0  # a model's NaN or inf where the candidate is 0
    a[3, 1, 7], b[3, 1, 7] = np.inf, 0.0
    a[4, 2, 9], b[4, 2, 9] = 0.25, np.nan
    b[5], a[5] = 0.125, 0.125  # every bin equal (ties): every term counts
    b[6, 0, 3] = -0.0
    out = np.empty((40, 5))
    rho_bins(a, b, out)
    ref = _plain_rho(a, b)
    assert out.tobytes() == ref.tobytes()
    assert np.isnan(out[2, 0]) and np.isnan(out[3, 1]) and np.isnan(out[4, 2])
    empty = np.zeros((0, 5, 64))
    rho_bins(empty, empty, np.empty((0, 5)))


def test_eq12_13_with_recalled_terms_have_the_bits_of_the_plain_sums():
    rng = np.random.default_rng(4)
    models = random_models(rng)
    # few distinct values (as area and perimeter differences are), so most terms repeat
    d = rng.choice([0.0, -0.0, -0.3, 0.02, 0.1, 0.5, 1.0, 2.0, np.inf], (300, N_FEATURES, N_PARTS))
    d[:100] = rng.uniform(0, 1, (100, N_FEATURES, N_PARTS))  # and distinct ones
    d[7, 2, 3] = np.nan
    omega, gamma, spread = rng.uniform(0.1, 1, N_FEATURES), rng.uniform(0.1, 1, N_PARTS), 2.5
    pj, p = layered_scores(models, d, omega, gamma, spread)
    prob = models.match_probability(d / spread)  # p(x | theta) of every term, one by one
    w_omega = omega / _sequential_sum(omega)
    w_gamma = gamma / _sequential_sum(gamma)
    ref_pj, ref_p = np.empty((len(d), N_PARTS)), np.empty(len(d))
    for k in range(len(d)):
        total = 0.0
        for j in range(N_PARTS):
            acc = 0.0
            for i in range(N_FEATURES):
                acc += float(w_omega[i]) * float(prob[k, i, j])
            ref_pj[k, j] = acc
            total += float(w_gamma[j]) * acc
        ref_p[k] = total
    assert pj.tobytes() == ref_pj.tobytes() and p.tobytes() == ref_p.tobytes()
    assert np.isnan(p[7]) and not np.isnan(p[8:]).any()
    pj0, p0 = layered_scores(models, np.zeros((0, N_FEATURES, N_PARTS)), omega, gamma, spread)
    assert pj0.shape == (0, N_PARTS) and p0.shape == (0,)


def _sequential_sum(v: np.ndarray) -> float:
    tot = 0.0
    for x in v.tolist():
        tot += x
    return tot


def test_part_features_with_the_frames_pixels_converted_before_are_the_same():
    from occbench.trackers.layered.parts import PartFeatureExtractor

    rng = np.random.default_rng(6)
    frames = [rng.integers(0, 256, (80, 100, 3), dtype=np.uint8) for _ in range(2)]
    fg = rng.random((80, 100)) < 0.6
    boxes = np.column_stack([rng.uniform(-10, 90, 12), rng.uniform(-10, 70, 12),
                             rng.uniform(5, 40, 12), rng.uniform(10, 60, 12)])
    warm = PartFeatureExtractor(4, 21, 9)
    for frame in frames:  # the second frame must not see the first one's pixels
        warm.start(frame, fg)
        warm.extract(boxes[::-1] + 1.5)  # converts most of the pixels the boxes read
        got = warm.extract(boxes, 0.4, 0.6)
        fresh = PartFeatureExtractor(4, 21, 9)
        fresh.start(frame, fg)
        ref = fresh.extract(boxes, 0.4, 0.6)
        for name in ("parts", "area", "perimeter", "hsv", "xyz", "centroid"):
            assert getattr(got, name).tobytes() == getattr(ref, name).tobytes(), name


@pytest.mark.parametrize("bins, with_fg", [(4, True), (4, False), (5, True)])
def test_box_scores_have_the_bits_of_extract_then_pair_scores(bins, with_fg):
    """``box_scores`` (features made and scored box by box, rho over the occupied bins)
    equals extracting the boxes' features and scoring them as pairs, bit for bit: boxes
    partly or wholly outside the image, repeated boxes (ties), parts without foreground,
    models with non-finite histograms; 5 bins (125 > 64) take the scan."""
    from occbench.trackers.layered.association import box_scores, pair_scores
    from occbench.trackers.layered.parts import PartFeatureExtractor

    rng = np.random.default_rng(bins * 10 + with_fg)
    frame = rng.integers(0, 256, (90, 120, 3), dtype=np.uint8)
    frame[20:60, 30:70] = (40, 90, 200)  # a flat patch: few occupied bins, repeated values
    fg = (rng.random((90, 120)) < 0.5) if with_fg else None
    if with_fg:
        fg[:, 100:] = False  # boxes there have parts without foreground
    K, T = 60, 7
    boxes = np.column_stack([rng.uniform(-30, 110, K), rng.uniform(-30, 80, K),
                             rng.uniform(4, 50, K), rng.uniform(8, 70, K)])
    boxes[10:14] = boxes[9]  # ties: one box scored four times
    boxes[20] = (130.0, 100.0, 10.0, 20.0)  # wholly outside the image
    boxes[21] = (105.0, 10.0, 12.0, 40.0)  # in the band without foreground
    ex = PartFeatureExtractor(bins, 21, 9)
    ex.start(frame, fg)
    model = ex.extract(boxes[rng.integers(0, K, T)] + rng.normal(0, 3, (T, 4)), 0.45, 0.55)
    model.hsv[2, 1, 7] = np.nan  # a non-finite model bin: scanned as _rho does
    model.xyz[3, 4, 0] = np.inf
    ti = rng.integers(0, T, K)
    alpha, beta = rng.uniform(0.2, 0.8, K), rng.uniform(0.2, 0.8, K)
    ti[10:14], alpha[10:14], beta[10:14] = ti[9], alpha[9], beta[9]
    misses = rng.integers(0, 4, T).astype(float)
    models = random_models(rng)
    omega, gamma = rng.uniform(0.1, 1, N_FEATURES), rng.uniform(0.1, 1, N_PARTS)
    for fresh in (True, False):  # the frame's pixels converted by box_scores, or before it
        ex.start(frame, fg)
        if not fresh:
            ex.extract(boxes[::-1], 0.5, 0.5)
        pj, p = box_scores(models, model, ex, boxes, alpha, beta, ti, misses, omega, gamma, 2.5)
        ref_pj, ref_p = pair_scores(models, model, ex.extract(boxes, alpha, beta), ti,
                                    np.arange(K), misses, omega, gamma, 2.5)
        assert pj.tobytes() == ref_pj.tobytes() and p.tobytes() == ref_p.tobytes()
    assert (p[10:14] == p[9]).all() and (pj[10:14] == pj[9]).all()
    pj0, p0 = box_scores(models, model, ex, np.zeros((0, 4)), np.zeros(0), np.zeros(0),
                         np.zeros(0, int), misses, omega, gamma, 2.5)
    assert pj0.shape == (0, N_PARTS) and p0.shape == (0,)
    with pytest.raises(IndexError):
        box_scores(models, model, ex, boxes[:1], alpha[:1], beta[:1], np.array([T]), misses,
                   omega, gamma, 2.5)
    with pytest.raises(ValueError, match="one per box"):
        box_scores(models, model, ex, boxes, alpha, beta, ti[:-1], misses, omega, gamma, 2.5)
