"""``adaptations.coarse_search`` (``box_search._coarse_group``): a searched pair's boxes
coarse to fine, a switch (not exact): every other width and height first, then the
neighbours of the best of those; the boxes it scores keep the exact search's bits."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.association import box_scores
from occbench.trackers.layered.feature_models import load_feature_models
from occbench.trackers.layered.parts import N_FEATURES, N_PARTS, PartFeatureExtractor

SIDE, M = 5, 25


def _visited(ref: np.ndarray) -> np.ndarray:
    """The boxes the coarse search measures in one group of exact scores ``ref`` (25,):
    even width and height indices, then the neighbours of their first maximum."""
    coarse = [i * SIDE + k for i in range(0, SIDE, 2) for k in range(0, SIDE, 2)]
    top = coarse[int(np.argmax(ref[coarse]))]
    ci, ck = divmod(top, SIDE)
    near = [i * SIDE + k for i in range(max(ci - 1, 0), min(ci + 2, SIDE))
            for k in range(max(ck - 1, 0), min(ck + 2, SIDE))]
    seen = np.zeros(M, bool)
    seen[coarse + near] = True
    return seen


def test_coarse_search_scores_the_coarse_boxes_and_the_best_ones_neighbours_exactly():
    rng = np.random.default_rng(11)
    frame = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    fg = rng.random((120, 160)) < 0.7
    ex = PartFeatureExtractor(4, 21, 9)
    ex.start(frame, fg)
    G, T = 16, 4
    heads = np.column_stack([rng.uniform(20, 140, G), rng.uniform(0, 60, G)])
    scale = 1.0 + 0.1 * np.arange(-2, 3)
    w = (20 * scale)[:, None].repeat(SIDE, 1).ravel()
    h = (50 * scale)[None, :].repeat(SIDE, 0).ravel()
    boxes = np.concatenate([np.column_stack([hx - 0.5 * w, np.full(M, hy), w, h])
                            for hx, hy in heads] + [rng.uniform(10, 60, (5, 4))])
    K = len(boxes)
    ti = np.concatenate([rng.integers(0, T, G).repeat(M), rng.integers(0, T, 5)])
    ti[M:2 * M] = T  # the NaN model's group: measured and scored whole
    alpha, beta = np.full(K, 0.5), np.full(K, 0.5)
    model = ex.extract(np.vstack([boxes[::M][:T] + rng.normal(0, 2, (T, 4)), boxes[:1]]), 0.5, 0.5)
    model.hsv[T, 1, :] = np.nan
    misses = np.zeros(T + 1)
    models, omega, gamma = load_feature_models(), np.ones(N_FEATURES), np.ones(N_PARTS)
    args = (models, model, ex, boxes, alpha, beta, ti, misses, omega, gamma, 4.5)
    ref_pj, ref_p = box_scores(*args)  # every box scored
    pj, p = box_scores(*args, M, G * M, True)
    scored = p != -np.inf
    assert p[scored].tobytes() == ref_p[scored].tobytes()
    assert pj[scored].tobytes() == ref_pj[scored].tobytes()
    assert np.isnan(pj[~scored]).all()
    assert scored[M:2 * M].all() and np.isnan(p[M:2 * M]).all()
    assert scored[G * M:].all()  # boxes past the groups: scored as before
    fewer = 0
    for g in range(G):
        if g == 1:
            continue
        ref, got = ref_p[g * M:(g + 1) * M], p[g * M:(g + 1) * M]
        seen = _visited(ref)
        assert not (scored[g * M:(g + 1) * M] & ~seen).any()  # only visited boxes scored
        # the chosen box (first maximum) is the first maximum of the exact scores visited
        assert int(np.argmax(got)) == int(np.argmax(np.where(seen, ref, -np.inf)))
        fewer += np.count_nonzero(~seen)
    assert fewer >= (G - 1) * 8  # at most 17 of 25 boxes measured per group
    exact_pj, exact_p = box_scores(*args, M, G * M, False)  # the switch off: the exact search
    first = [int(np.argmax(np.nan_to_num(v, nan=np.inf))) for v in exact_p[:G * M].reshape(G, M)]
    assert first == [int(np.argmax(np.nan_to_num(v, nan=np.inf))) for v in ref_p[:G * M].reshape(G, M)]


def test_coarse_search_is_an_adaptation_off_in_paper_mode():
    assert Adaptations.paper().coarse_search is False and Adaptations().coarse_search is False
    assert set(Adaptations(coarse_search=True).changed()) - set(Adaptations().changed()) == {
        "coarse_search"}
    assert Adaptations.paper().changed() == []


def test_the_exact_search_never_calls_the_coarse_kernel(monkeypatch):
    """The switch off: ``box_scores`` runs ``box_scores_kernel`` only, so a default run never
    compiles ``coarse_box_scores_kernel`` (a cold numba cache compiles what is called)."""
    from occbench.trackers.layered import association

    def called(*_args):
        raise AssertionError("coarse_box_scores_kernel called with coarse_search off")

    monkeypatch.setattr(association, "coarse_box_scores_kernel", called)
    rng = np.random.default_rng(3)
    ex = PartFeatureExtractor(4, 21, 9)
    ex.start(rng.integers(0, 256, (60, 80, 3), dtype=np.uint8), rng.random((60, 80)) < 0.7)
    boxes = np.column_stack([rng.uniform(5, 30, M), rng.uniform(0, 10, M),
                             np.full(M, 20.0), np.full(M, 40.0)])
    model = ex.extract(boxes[:1], 0.5, 0.5)
    args = (load_feature_models(), model, ex, boxes, np.full(M, 0.5), np.full(M, 0.5),
            np.zeros(M, int), np.zeros(1), np.ones(N_FEATURES), np.ones(N_PARTS), 4.5)
    _, p = box_scores(*args, M, M, False)
    assert np.isfinite(p).any()
    with pytest.raises(AssertionError, match="coarse_search off"):
        box_scores(*args, M, M, True)
