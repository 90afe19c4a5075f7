"""Ellipse histograms (Reta eq. 1), Bhattacharyya rho (eq. 4) and region similarity delta (eq. 5)."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.geometry import box_ellipses, ellipse_mask
from occbench.trackers.histograms import masked_histogram
from occbench.trackers.three_hypothesis.features import (
    bhattacharyya,
    bin_image,
    ellipse_histograms,
    region_similarity,
)


def test_known_colour_lands_in_known_bin():
    img = np.zeros((4, 4, 3), dtype=np.uint8)
    img[:] = (200, 17, 255)  # channel bins 12, 1, 15
    assert (bin_image(img) == (12 * 16 + 1) * 16 + 15).all()
    h = ellipse_histograms(img, np.array([[0, 0, 4, 4]]))
    assert h.shape == (1, 4096)
    assert h[0, (12 * 16 + 1) * 16 + 15] == pytest.approx(1.0)


def test_ellipse_histograms_match_masked_histogram_of_ellipse_mask():
    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, size=(60, 80, 3), dtype=np.uint8)
    boxes = np.array([[5.0, 7.0, 20.0, 40.0], [40.5, 10.2, 31.0, 17.0], [70.0, 50.0, 30.0, 30.0]])
    fg = rng.random((60, 80)) < 0.5
    got = ellipse_histograms(img, boxes, mask=fg)
    for i, e in enumerate(box_ellipses(boxes)):
        m = ellipse_mask(e, img.shape[:2])
        np.testing.assert_allclose(got[i], masked_histogram(img, m & fg))
        assert got[i].sum() == pytest.approx(1.0)


def test_empty_region_gives_zero_histogram():
    img = np.zeros((10, 10, 3), dtype=np.uint8)
    h = ellipse_histograms(img, np.array([[50, 50, 5, 5]]))
    assert not h.any()


def test_rho_identical_one_disjoint_zero():
    img = np.zeros((20, 40, 3), dtype=np.uint8)
    img[:, :20] = (255, 0, 0)
    img[:, 20:] = (0, 0, 255)
    h = ellipse_histograms(img, np.array([[0, 0, 20, 20], [2, 2, 15, 15], [20, 0, 20, 20]]))
    rho = bhattacharyya(h, h)
    assert rho[0, 1] == pytest.approx(1.0)
    assert rho[0, 2] == pytest.approx(0.0)


def test_region_similarity_box_hand_cases():
    a = np.array([[0.0, 0.0, 10.0, 10.0]])
    b = np.array([[0.0, 0.0, 10.0, 10.0], [5.0, 0.0, 10.0, 10.0], [20.0, 20.0, 5.0, 5.0],
                  [0.0, 0.0, 5.0, 10.0]])
    # delta = 2 |A & B| / (|A| + |B|): 1, 2*50/200, 0, 2*50/150
    np.testing.assert_allclose(region_similarity(a, b, region="box")[0], [1, 0.5, 0, 2 / 3])


def test_region_similarity_ellipse():
    a = np.array([[0.0, 0.0, 20.0, 40.0]])
    inner = np.array([[5.0, 10.0, 10.0, 20.0]])  # concentric, half the axes: area ratio 1/4
    far = np.array([[100.0, 100.0, 5.0, 5.0]])
    d = region_similarity(a, np.vstack([a, inner, far]), samples=64)
    assert d[0, 0] == pytest.approx(1.0)
    assert d[0, 1] == pytest.approx(2 * 0.25 / 1.25, abs=0.01)
    assert d[0, 2] == 0.0
    shifted = np.array([[7.0, 3.0, 20.0, 40.0]])
    np.testing.assert_allclose(region_similarity(a, shifted), region_similarity(shifted, a).T,
                               atol=0.02)


def test_region_similarity_rejects_unknown_region():
    with pytest.raises(ValueError, match="region"):
        region_similarity(np.zeros((1, 4)), np.zeros((1, 4)), region="circle")
