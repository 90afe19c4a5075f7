"""The shortcuts of the eq. 11-12 kernels give the bits of the plain sums, not only values
within a tolerance: rho summed over the occupied bins only (``_kernels.rho_bins``) and eq. 12
with p(x | theta) recalled for a repeated x (``layered_scores``)."""

from __future__ import annotations

import numpy as np
from pbm_scenes import random_models

from trackers.layered._kernels import rho_bins
from trackers.layered.association import layered_scores
from trackers.layered.parts import N_FEATURES, N_PARTS


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
    from trackers.layered.parts import PartFeatureExtractor

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
