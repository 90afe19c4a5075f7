"""The shortcuts of the eq. 11-12 kernels give the bits of the plain sums, not only values
within a tolerance: rho summed over the occupied bins only (``differences.rho_bins``), eq. 12
with p(x | theta) recalled for a repeated x (``layered_scores``), and the search's boxes
scored as they are measured (``association.box_scores``)."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered.association import layered_scores
from occbench.trackers.layered.differences import rho_bins
from occbench.trackers.layered.feature_models import load_feature_models
from occbench.trackers.layered.parts import N_FEATURES, N_PARTS
from pbm_scenes import random_models


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


@pytest.mark.parametrize("bins", [4, 32])
def test_part_features_on_a_shared_table_and_after_its_stamps_wrap_are_the_same(bins):
    """Two extractors of one pixel-bin table (``shared``, the tracker's candidates and search
    grids) and a table whose stamps wrap (32 bins: joint bins of 15 bits, stamps 1..3 in a
    uint32) measure as a fresh extractor does, frame after frame."""
    from occbench.trackers.layered.parts import PartFeatureExtractor

    rng = np.random.default_rng(bins)
    frames = [rng.integers(0, 256, (60, 70, 3), dtype=np.uint8) for _ in range(3)]
    fg = rng.random((60, 70)) < 0.7
    boxes = np.column_stack([rng.uniform(-10, 60, 9), rng.uniform(-10, 40, 9),
                             rng.uniform(5, 30, 9), rng.uniform(10, 50, 9)])
    first = PartFeatureExtractor(bins, 35, 15)
    second = PartFeatureExtractor(bins, 21, 9, shared=first)
    assert second.pixels is first.pixels
    for k in range(9):  # 18 starts of one table: its stamps wrap at 32 bins
        frame = frames[k % 3]
        first.start(frame, fg)
        second.start(frame, fg)
        got = (first.extract(boxes + 0.5, 0.45, 0.55), second.extract(boxes, 0.4, 0.6))
        for ex, feats, shift in zip((PartFeatureExtractor(bins, 35, 15), PartFeatureExtractor(bins, 21, 9)),
                                    got, (0.5, 0.0)):
            ex.start(frame, fg)
            ref = ex.extract(boxes + shift, *((0.45, 0.55) if shift else (0.4, 0.6)))
            for name in ("parts", "area", "perimeter", "hsv", "xyz", "centroid"):
                assert getattr(feats, name).tobytes() == getattr(ref, name).tobytes(), (k, name)
    with pytest.raises(ValueError, match="bins"):
        PartFeatureExtractor(bins + 1, 21, 9, shared=first)


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
    apart_p = {}
    for fresh, apart in ((True, False), (False, False), (True, True)):  # the frame's pixels
        ex.start(frame, fg)                                     # converted by box_scores, or before
        if not fresh:
            ex.extract(boxes[::-1], 0.5, 0.5)
        pj, p = box_scores(models, model, ex, boxes, alpha, beta, ti, misses, omega, gamma, 2.5,
                           apart=apart)
        ref_pj, ref_p = pair_scores(models, model, ex.extract(boxes, alpha, beta), ti,
                                    np.arange(K), misses, omega, gamma, 2.5, apart)
        assert pj.tobytes() == ref_pj.tobytes() and p.tobytes() == ref_p.tobytes()
        apart_p[apart] = p
    assert (apart_p[True] != apart_p[False]).any()  # adaptations.apart_undivided: some pair apart
    assert (p[10:14] == p[9]).all() and (pj[10:14] == pj[9]).all()
    pj0, p0 = box_scores(models, model, ex, np.zeros((0, 4)), np.zeros(0), np.zeros(0),
                         np.zeros(0, int), misses, omega, gamma, 2.5)
    assert pj0.shape == (0, N_PARTS) and p0.shape == (0,)
    with pytest.raises(IndexError):
        box_scores(models, model, ex, boxes[:1], alpha[:1], beta[:1], np.array([T]), misses,
                   omega, gamma, 2.5)
    with pytest.raises(ValueError, match="one per box"):
        box_scores(models, model, ex, boxes, alpha, beta, ti[:-1], misses, omega, gamma, 2.5)


def test_survival_bounds_bound_every_x_of_their_cell():
    """``survival_bounds``' entry for x's cell is >= p(x | theta) (``FeatureModels``' own
    kernel) at cell edges, just below them, inside cells and beyond x = 1."""
    from occbench.trackers.layered.association import _theta
    from occbench.trackers.layered.box_search import BOUND_CELLS, survival_bounds

    rng = np.random.default_rng(5)
    for models in (random_models(rng), load_feature_models()):
        table = survival_bounds(_theta(models))
        edges = np.arange(BOUND_CELLS + 1) / BOUND_CELLS
        x = np.concatenate([edges, np.nextafter(edges[1:], 0.0), rng.uniform(0, 1, 4000),
                            [1.5, 7.0, np.inf]])
        sv = models.match_probability(np.broadcast_to(x[:, None, None], (len(x), N_FEATURES, N_PARTS)))
        cell = np.minimum(np.floor(x * BOUND_CELLS), BOUND_CELLS).astype(int)
        assert (table[:, :, cell].transpose(2, 0, 1) >= sv).all()


def test_search_groups_keep_the_bits_of_each_groups_first_maximum():
    """``box_scores(best_of=25, grouped=...)`` (the search: only each group's first maximum
    counts) leaves unscored (p -inf) only boxes whose full score is below their group's
    maximum, gives every scored box its bits, hence the same first maximum, and scores
    boxes past the groups as before; a group with a NaN score and a group of ties are
    scored whole."""
    from occbench.trackers.layered.association import box_scores
    from occbench.trackers.layered.parts import PartFeatureExtractor

    rng = np.random.default_rng(8)
    frame = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    fg = rng.random((120, 160)) < 0.7
    ex = PartFeatureExtractor(4, 21, 9)
    ex.start(frame, fg)
    G, T, m = 12, 4, 25
    heads = np.column_stack([rng.uniform(20, 140, G), rng.uniform(0, 60, G)])
    scale = 1.0 + 0.1 * np.arange(-2, 3)
    w = (20 * scale)[:, None].repeat(5, 1).ravel()
    h = (50 * scale)[None, :].repeat(5, 0).ravel()
    boxes = np.concatenate([np.column_stack([hx - 0.5 * w, np.full(m, hy), w, h])
                            for hx, hy in heads] + [rng.uniform(10, 60, (7, 4))])
    boxes[m:2 * m] = boxes[m]  # a group of ties
    K = len(boxes)
    ti = np.concatenate([rng.integers(0, T, G).repeat(m), rng.integers(0, T, 7)])
    ti[2 * m:3 * m] = T  # the NaN model's group
    alpha, beta = np.full(K, 0.5), np.full(K, 0.5)
    model = ex.extract(np.vstack([boxes[::m][:T] + rng.normal(0, 2, (T, 4)), boxes[:1]]), 0.5, 0.5)
    model.hsv[T, 1, :] = np.nan  # every box of group 2 scores NaN
    misses = np.zeros(T + 1)
    models, omega, gamma = load_feature_models(), np.ones(N_FEATURES), np.ones(N_PARTS)
    ref_pj, ref_p = box_scores(models, model, ex, boxes, alpha, beta, ti, misses, omega, gamma, 4.5)
    pj, p = box_scores(models, model, ex, boxes, alpha, beta, ti, misses, omega, gamma, 4.5, m, G * m)
    scored = p != -np.inf
    assert np.isnan(ref_p[2 * m:3 * m]).all() and scored[m:3 * m].all()
    assert p[scored].tobytes() == ref_p[scored].tobytes()
    assert pj[scored].tobytes() == ref_pj[scored].tobytes()
    group_max = np.where(np.isnan(ref_p), -np.inf, ref_p)[:G * m].reshape(G, m).max(axis=1).repeat(m)
    assert (ref_p[:G * m][~scored[:G * m]] < group_max[~scored[:G * m]]).all()
    assert np.count_nonzero(~scored) >= G * m // 2  # the bound prunes
    def first(v):  # carved_rows' choice: the first NaN, else the first maximum
        return [int(np.argmax(np.nan_to_num(g, nan=np.inf))) for g in v[:G * m].reshape(G, m)]

    assert first(p) == first(ref_p)
    with pytest.raises(ValueError, match="tile"):
        box_scores(models, model, ex, boxes, alpha, beta, ti, misses, omega, gamma, 4.5, m, G * m - 1)
