"""``_template_kernels.ccoeff_normed`` and ``best_ccoeff_normed``: PBM 4.1's head-template scores and their best corner, bit for bit
``cv2.matchTemplate(..., cv2.TM_CCOEFF_NORMED)`` on random and edge cases."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from occbench.trackers.layered._template_kernels import best_ccoeff_normed, ccoeff_normed


def _same(image: np.ndarray, template: np.ndarray) -> np.ndarray:
    """The kernel's scores, asserted equal bit for bit to OpenCV's."""
    ref = cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED)
    out = ccoeff_normed(image, template)
    assert out.shape == ref.shape and out.dtype == np.float32
    bad = np.flatnonzero(out.view(np.uint32) != ref.view(np.uint32))
    assert not len(bad), (image.shape, template.shape, out.flat[bad[:3]], ref.flat[bad[:3]])
    return out


def _smooth(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """Grey texture with blobs a few pixels wide, as heads and clothes are."""
    small = rng.integers(0, 256, (max(h // 6, 2), max(w // 6, 2)), dtype=np.uint8)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)


def _random_case(rng: np.random.Generator, th_max: int = 40, tw_max: int = 90
                 ) -> tuple[np.ndarray, np.ndarray]:
    """A window and a template: windows from the template's own size (one position; OpenCV's
    DFT path when the template is over a quarter of the window) to ten times it (its IPP
    path), smooth or noise; the template cut from the window (a peak of 1; its negative,
    -1) or not."""
    th, tw = int(rng.integers(1, th_max)), int(rng.integers(1, tw_max))
    h, w = th + int(rng.integers(0, 4 * th + 2)), tw + int(rng.integers(0, 4 * tw + 2))
    image = _smooth(rng, h, w) if rng.random() < 0.7 else rng.integers(0, 256, (h, w), np.uint8)
    if rng.random() < 0.5:
        y, x = int(rng.integers(0, h - th + 1)), int(rng.integers(0, w - tw + 1))
        template = image[y:y + th, x:x + tw].copy()
        return image, 255 - template if rng.random() < 0.3 else template
    return image, _smooth(rng, th, tw)


@pytest.mark.parametrize("seed", range(4))
def test_random_windows_and_templates_score_as_opencv(seed):
    rng = np.random.default_rng(seed)
    for _ in range(40):
        _same(*_random_case(rng))


def test_flat_template_scores_one_everywhere_and_flat_windows_zero():
    rng = np.random.default_rng(5)
    image = _smooth(rng, 60, 90)
    assert (_same(image, np.full((8, 20), 77, np.uint8)) == 1.0).all()  # no template variance
    image[10:40, 20:70] = 200  # flat windows inside: OpenCV's floor, denominator 0
    out = _same(image, _smooth(rng, 8, 20))
    assert (out[10:33, 20:51] == 0.0).all() and (out != 0.0).any()
    for value in (0, 255):  # saturated images
        _same(np.full((30, 40), value, np.uint8), _smooth(rng, 6, 9))
    # flat windows whose variance rounds above 0 (1 / n inexact): OpenCV's floor
    for th, tw in ((1, 3), (3, 5), (5, 7), (7, 11), (9, 13)):
        for value in (3, 17, 101, 254):
            image = np.full((2 * th + 3, 2 * tw + 3), value, np.uint8)
            assert (_same(image, _smooth(rng, th, tw)) == 0.0).all()


def test_planted_heads_and_their_negatives_reach_plus_and_minus_one():
    rng = np.random.default_rng(6)
    hits = 0
    for _ in range(30):
        image = rng.integers(0, 256, (50, 70), np.uint8)
        template = image[20:32, 30:55].copy()
        out = _same(image, template)
        assert abs(out[20, 30] - 1.0) < 1e-6
        hits += out[20, 30] == 1.0
        image[20:32, 30:55] = 255 - template
        assert abs(_same(image, template)[20, 30] + 1.0) < 1e-6
    assert hits  # some peaks are OpenCV's clamp to exactly 1


def test_other_inputs_are_refused():
    grey = np.zeros((20, 20), np.uint8)
    with pytest.raises(ValueError, match="uint8"):
        ccoeff_normed(grey.astype(np.float32), grey[:5, :5])
    with pytest.raises(ValueError, match="uint8"):
        ccoeff_normed(np.zeros((20, 20, 3), np.uint8), grey[:5, :5])
    with pytest.raises(ValueError, match="larger"):
        ccoeff_normed(grey[:4], grey[:5, :5])


def test_a_template_too_tall_for_int32_column_sums_scores_as_opencv():
    # 255^2 th overflows the kernel's int32 column sums past th = 33,025 rows
    rng = np.random.default_rng(7)
    th = 40_000
    template = rng.integers(0, 256, (th, 2), dtype=np.uint8)
    image = rng.integers(250, 256, (th + 2, 4), dtype=np.uint8)  # sums of I^2 near 2.5e9
    _same(image, template)


def _best_same(image: np.ndarray, template: np.ndarray) -> tuple[int, int, float]:
    """The kernel's best corner and score, asserted equal to OpenCV's minMaxLoc of its map."""
    _, want, _, (wx, wy) = cv2.minMaxLoc(cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED))
    x, y, best = best_ccoeff_normed(image, template)
    assert (x, y) == (wx, wy) and np.float64(best).tobytes() == np.float64(want).tobytes(), (
        image.shape, template.shape, (x, y, best), (wx, wy, want))
    return x, y, best


@pytest.mark.parametrize("seed", range(4))
def test_the_best_corner_is_opencvs_on_random_windows(seed):
    rng = np.random.default_rng(100 + seed)
    for _ in range(60):
        _best_same(*_random_case(rng, 30, 60))


def test_ties_go_to_the_first_corner_in_raster_order():
    rng = np.random.default_rng(8)
    tile = _smooth(rng, 12, 16)
    image = np.tile(tile, (4, 5))  # the template's peak of 1 repeats every 12 rows, 16 columns
    x, y, best = _best_same(image, tile)
    assert best == 1.0 and (x, y) == (0, 0)
    # a tile's corners from (11, 9) on, every 16 columns: some at the clamp to exactly 1,
    # others a float32 below it (OpenCV's raw correlation rounds by position)
    x, y, best = _best_same(image[3:, 5:], tile)
    assert best == 1.0 and y == 9 and x % 16 == 11
    assert _best_same(image, np.full((6, 9), 50, np.uint8)) == (0, 0, 1.0)  # flat template


def test_maps_with_no_positive_score_give_their_first_largest():
    ramp = np.tile(np.arange(0, 240, 4, dtype=np.uint8), (20, 1))  # brighter to the right
    template = ramp[:6, :10][:, ::-1].copy()  # darker to the right: about -1 everywhere
    x, y, best = _best_same(ramp, template)
    assert best < 0
    assert _best_same(np.full((20, 60), 90, np.uint8), template) == (0, 0, 0.0)  # flat: 0


def test_the_best_of_a_template_too_tall_for_int32_sums_is_opencvs():
    rng = np.random.default_rng(9)
    template = rng.integers(0, 256, (40_000, 2), dtype=np.uint8)
    _best_same(rng.integers(250, 256, (40_002, 4), dtype=np.uint8), template)
    with pytest.raises(ValueError, match="larger"):
        best_ccoeff_normed(template[:4], template[:5])


def test_a_corner_barely_above_the_best_of_the_rows_before_is_scored():
    rng = np.random.default_rng(10)
    image = _smooth(rng, 60, 80)
    template = image[30:40, 40:60].copy()  # R = 1 at (40, 30)
    near = template.copy()
    near[4, 7] = near[4, 7] + 1 if near[4, 7] < 255 else 254  # one grey level off: R just below 1
    image[5:15, 10:30] = near
    _, _, first = _best_same(image[:20], template)
    assert 0.9999 < first < 1.0  # the near copy's corner, in row 5
    assert _best_same(image, template) == (40, 30, 1.0)
