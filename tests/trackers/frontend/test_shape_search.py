"""Reta 3.1's detector: the active-basis shape filter map and the greedy search over the
free foreground (trackers/frontend/shape_search.py)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from occbench.fit.active_basis import load
from occbench.trackers.frontend.active_basis import crop_patch
from occbench.trackers.frontend.calibration import Perspective
from occbench.trackers.frontend.shape_search import ActiveBasisDetector, ShapeSearch, shape_filter_map
from occbench.trackers.frontend.shape_search_params import ShapeAcceptance, ShapeHeights, ShapePlacements
from occbench.trackers.frontend.silhouette_template import load_template
from occbench.trackers.geometry import iou_matrix


def _search(template, lo: float, hi: float, n: int, threshold: float) -> ShapeSearch:
    return ShapeSearch(template, ShapeHeights(min_height=lo, max_height=hi, n_scales=n),
                       acceptance=ShapeAcceptance(threshold=threshold))


@pytest.fixture(scope="module")
def template():
    return load()  # the shipped template (trackers/frontend/data/active_basis.npz)


def _scene(template, people, height=96, seed=0):
    """A 288x384 grey frame with dark people drawn from the shipped mean person mask (the
    later ones in front), its foreground (their union) and their xywh boxes."""
    sil = load_template(None)
    rng = np.random.default_rng(seed)
    grey = np.full((288, 384), 170.0, np.float32)
    fg = np.zeros(grey.shape, bool)
    w = round(height * template.size[1] / template.size[0])
    mask = cv2.resize(sil, (w, height), interpolation=cv2.INTER_LINEAR) > 0.4
    for x, y in people:
        grey[y : y + height, x : x + w][mask] = 60.0
        fg[y : y + height, x : x + w] |= mask
    grey = cv2.GaussianBlur(grey, (0, 0), 1.0) + rng.normal(0, 3, grey.shape).astype(np.float32)
    return grey, fg, np.array([[x, y, w, height] for x, y in people], float)


def test_shape_filter_map_is_the_template_score_at_every_placement(template):
    rng = np.random.default_rng(1)
    img = cv2.GaussianBlur(rng.uniform(0, 255, (90, 60)).astype(np.float32), (0, 0), 1.5)
    S = shape_filter_map(img, template)
    H, W = template.size
    assert S.shape == (90 - H + 1, 60 - W + 1)
    for y, x in [(0, 0), (10, 5), (42, 40), (20, 33), (5, 17)]:  # border ones replicate, as crop_patch
        ref = template.score(crop_patch(img, (x, y, W, H), template.size, template.pad))
        assert S[y, x] == pytest.approx(ref, abs=1e-4)


def test_where_computes_only_its_components_with_the_same_values(template):
    rng = np.random.default_rng(2)
    img = cv2.GaussianBlur(rng.uniform(0, 255, (120, 90)).astype(np.float32), (0, 0), 1.5)
    S = shape_filter_map(img, template)
    where = np.zeros(S.shape, bool)
    where[3:10, 4:9] = where[40:50, 30:40] = True
    S2 = shape_filter_map(img, template, where=where)
    np.testing.assert_allclose(S2[where], S[where], atol=1e-9)
    assert np.isneginf(S2[~where]).all()


def test_greedy_search_finds_each_person_once_and_stops_when_the_foreground_is_explained(template):
    # two people apart, two overlapping (the one at 240 in front of the one at 262)
    grey, fg, gt = _scene(template, [(40, 120), (150, 110), (262, 100), (240, 100)])
    search = _search(template, 0.30, 0.38, 3, threshold=-1e9)
    boxes, scores = search.search(grey, fg)
    # no threshold: only the explained foreground stops it, after the four people
    assert len(boxes) == 4
    iou = iou_matrix(gt, boxes)
    assert (iou.max(axis=1) >= 0.7).all()  # everyone found ...
    assert sorted(iou.argmax(axis=1).tolist()) == [0, 1, 2, 3]  # ... once
    assert (np.diff(scores) <= 1e-9).all()  # greedy: each fit scores at most the previous one
    # a threshold above every fit's score accepts none; between fits, keeps the prefix
    assert len(_search(template, 0.30, 0.38, 3, threshold=scores[0] + 1).search(grey, fg)[0]) == 0
    mid = _search(template, 0.30, 0.38, 3, threshold=(scores[1] + scores[2]) / 2).search(grey, fg)
    np.testing.assert_allclose(mid[0], boxes[:2])


def test_on_background_only_nothing_is_searched(template):
    grey, fg, _ = _scene(template, [(40, 120)])
    search = _search(template, 0.30, 0.38, 3, threshold=-1e9)
    assert len(search.search(grey, np.zeros_like(fg))[0]) == 0


def test_the_calibrated_scales_only(template):
    grey, fg, gt = _scene(template, [(40, 120), (150, 110)])
    search = _search(template, 0.1, 0.6, 12, threshold=0.0)
    # feet at rows 216 and 206; a perspective expecting 96-pixel people there: both found
    boxes, _ = search.search(grey, fg, Perspective(a=0.4, b=12.0, width_ratio=0.42))
    assert len(boxes) == 2 and (iou_matrix(gt, boxes).max(axis=1) >= 0.7).all()
    # one expecting about 40-pixel people there: no scale near 96 pixels is searched
    boxes, _ = search.search(grey, fg, Perspective(a=0.4, b=-44.0, width_ratio=0.42))
    assert (boxes[:, 3] <= 40 * 1.2 + 2).all()


def test_arguments_are_checked(template):
    with pytest.raises(ValueError, match=r"^search\.placements\.min_vacant "):
        ShapePlacements(min_vacant=0.0)
    with pytest.raises(ValueError, match=r"^search\.heights\.height_tolerance "):  # NaN
        ShapeHeights(height_tolerance=float("nan"))
    with pytest.raises(ValueError, match=r"^search\.heights\.min_height "):
        ShapeHeights(min_height=0.7, max_height=0.6)
    with pytest.raises(ValueError, match=r"^search\.acceptance\.max_people "):
        ShapeAcceptance(max_people=0)
    with pytest.raises(TypeError, match="search.min_vacant: moved to search.placements.min_vacant"):
        ShapeSearch(template, min_vacant=0.5)  # a flat key before the groups (issue 36)
    with pytest.raises(TypeError, match="heights"):
        ShapeSearch(template, heights=ShapeAcceptance())
    with pytest.raises(TypeError, match="ActiveBasis"):
        ShapeSearch("template.npz")
    with pytest.raises(ValueError, match="search"):
        ActiveBasisDetector()
    with pytest.raises(ValueError, match="verifier"):
        ActiveBasisDetector(search=ShapeSearch(template), verifier=object())
