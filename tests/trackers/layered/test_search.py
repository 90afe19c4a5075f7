"""The PBM search helpers (trackers/layered/search.py): the compiled ones against
straightforward references (numpy / OpenCV) on seeded random inputs, the numpy ones on
hand-derived cases."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from pbm_scenes import two_heads_blob

from occbench.trackers.geometry import box_slices
from occbench.trackers.layered import search as S

# ---------------------------------------------------------------------- references


def _head_from_band_reference(fg, box):
    x, y, w, h = box
    if fg is not None:
        H, W = fg.shape
        r0, r1 = max(int(y), 0), min(int(np.ceil(y + S.HEAD_FRACTION * h)) + 1, H)
        c0, c1 = max(int(x), 0), min(int(np.ceil(x + w)), W)
        if r1 > r0 and c1 > c0:
            bx, by, bw, _ = cv2.boundingRect(fg[r0:r1, c0:c1].view(np.uint8))
            if bw > 0:
                return np.array([c0 + 0.5 * (2 * bx + bw), r0 + by, max(bw, 1)], dtype=np.float64)
    return np.array([x + 0.5 * w, y, 0.5 * w])


def _exhaustive_match(gray, template, centre, radius):
    """cv2.matchTemplate over the whole window, written out independently."""
    th, tw = template.shape
    H, W = gray.shape
    r = int(np.ceil(radius))
    x0, y0 = round(centre[0]) - r, round(centre[1]) - r
    c0, r0 = max(x0, 0), max(y0, 0)
    c1, r1 = min(x0 + 2 * r + tw, W), min(y0 + 2 * r + th, H)
    if c1 - c0 < tw or r1 - r0 < th:
        return np.asarray(centre, dtype=np.float64), -1.0, None
    res = cv2.matchTemplate(gray[r0:r1, c0:c1], template, cv2.TM_CCOEFF_NORMED)
    _, best, _, loc = cv2.minMaxLoc(res)
    return np.array([c0 + loc[0], r0 + loc[1]], dtype=np.float64), float(best), (res, c0, r0)


def _scene(rng, h=120, w=160):
    """A smooth grey scene (blurred noise) with a few flat-shaded 'heads'."""
    img = cv2.GaussianBlur(rng.integers(0, 256, (h, w)).astype(np.float32), (0, 0), 3.0)
    img = cv2.normalize(img, None, 0, 255, cv2.NORM_MINMAX)
    for _ in range(4):
        cx, cy = rng.integers(10, w - 10), rng.integers(10, h - 10)
        cv2.ellipse(img, (int(cx), int(cy)), (int(rng.integers(4, 9)), int(rng.integers(5, 10))), 0, 0,
                    360, float(rng.integers(0, 256)), -1)
    return img.astype(np.uint8)


# ---------------------------------------------------------------------- template matching


def test_match_head_template_finds_a_planted_head_exactly():
    rng = np.random.default_rng(0)
    for _ in range(30):
        gray = _scene(rng)
        th, tw = int(rng.integers(6, 18)), int(rng.integers(12, 40))
        ty, tx = int(rng.integers(0, 120 - th)), int(rng.integers(0, 160 - tw))
        tpl = gray[ty:ty + th, tx:tx + tw].copy()
        centre = np.array([tx + rng.integers(-12, 13), ty + rng.integers(-12, 13)], dtype=np.float64)
        radius = float(rng.uniform(13, 40))
        tl, corr = S.match_head_template(gray, tpl, centre, radius)
        ref_tl, ref_corr, _ = _exhaustive_match(gray, tpl, centre, radius)
        np.testing.assert_array_equal(tl, ref_tl)
        assert corr == pytest.approx(ref_corr, abs=1e-4)
        assert corr == pytest.approx(1.0, abs=1e-4)  # OpenCV's float32 sums


def test_match_head_template_is_the_exhaustive_maximum():
    rng = np.random.default_rng(1)
    for _ in range(60):
        gray = _scene(rng)
        th, tw = int(rng.integers(6, 16)), int(rng.integers(10, 36))
        ty, tx = int(rng.integers(0, 120 - th)), int(rng.integers(0, 160 - tw))
        # a template from elsewhere, lightly perturbed: no exact copy in the window
        tpl = np.clip(gray[ty:ty + th, tx:tx + tw].astype(np.int16) + rng.integers(-20, 21, (th, tw)),
                      0, 255).astype(np.uint8)
        centre = rng.uniform([0, 0], [160 - tw, 120 - th])
        radius = float(rng.uniform(4, 45))
        tl, corr = S.match_head_template(gray, tpl, centre, radius)
        ref_tl, ref_corr, (res, _, _) = _exhaustive_match(gray, tpl, centre, radius)
        np.testing.assert_array_equal(tl, ref_tl)
        assert corr == ref_corr == res.max()


def test_small_windows_and_no_room_gives_minus_one():
    rng = np.random.default_rng(2)
    for _ in range(40):
        gray = rng.integers(0, 256, (40, 50), dtype=np.uint8)
        tpl = rng.integers(0, 256, (int(rng.integers(3, 9)), int(rng.integers(3, 12))), dtype=np.uint8)
        centre = rng.uniform(0, 30, 2)
        radius = float(rng.uniform(0, 3))  # at most 49 positions: the exhaustive path
        tl, corr = S.match_head_template(gray, tpl, centre, radius)
        ref_tl, ref_corr, _ = _exhaustive_match(gray, tpl, centre, radius)
        np.testing.assert_array_equal(tl, ref_tl)
        assert corr == pytest.approx(ref_corr, abs=1e-4)
    tl, corr = S.match_head_template(gray, np.zeros((60, 5), np.uint8), np.array([3.0, 4.0]), 2.0)
    assert corr == -1.0 and np.array_equal(tl, [3.0, 4.0])


def test_a_flat_template_scores_one_at_the_window_corner_as_opencv():
    gray = np.random.default_rng(3).integers(0, 256, (80, 90), dtype=np.uint8)
    tpl = np.full((10, 20), 77, np.uint8)
    tl, corr = S.match_head_template(gray, tpl, np.array([30.0, 30.0]), 20.0)
    ref_tl, ref_corr, _ = _exhaustive_match(gray, tpl, np.array([30.0, 30.0]), 20.0)
    np.testing.assert_array_equal(tl, ref_tl)
    assert corr == ref_corr == 1.0


# ---------------------------------------------------------------------- candidates


def _random_blob(rng, h, w):
    mask = np.zeros((h, w), dtype=bool)
    for _ in range(int(rng.integers(1, 5))):
        cx, cy = rng.integers(0, w), rng.integers(0, h)
        rx, ry = rng.integers(2, max(3, w // 3)), rng.integers(2, max(3, h // 2))
        cv2.ellipse(mask.view(np.uint8), (int(cx), int(cy)), (int(rx), int(ry)), 0, 0, 360, 1, -1)
    return mask


def test_top_profile_heads_need_prominence_and_separation():
    mask = np.zeros((30, 40), bool)
    mask[10:30] = True  # body, top row 10
    mask[2:10, 15:25] = True  # head, top row 2, centre column 19.5
    mask[9:10, 30:34] = True  # a one-row shoulder, centre column 31.5
    np.testing.assert_array_equal(S.top_profile_heads(mask, 6.0, 3.0), [[19.5, 2.0]])
    np.testing.assert_array_equal(S.top_profile_heads(mask, 6.0, 1.0), [[19.5, 2.0], [31.5, 9.0]])
    np.testing.assert_array_equal(S.top_profile_heads(mask, 20.0, 1.0), [[19.5, 2.0]])  # suppressed
    assert S.top_profile_heads(np.zeros((5, 7), bool), 2.0, 1.0).shape == (0, 2)
    assert S.top_profile_heads(np.zeros((0, 7), bool), 2.0, 1.0).shape == (0, 2)


def test_split_blob_box_cuts_half_way_between_heads_and_bounds_the_foreground():
    mask = two_heads_blob()
    heads_x, offset = np.array([54.5, 19.5]), np.array([100.0, 200.0])
    # cut at round((19.5 + 54.5) / 2) = 37: columns 5..36 rows 5..99, columns 37..74 rows 12..99
    np.testing.assert_array_equal(S.split_blob_box(mask, offset, heads_x, 1), [105.0, 205.0, 32.0, 95.0])
    np.testing.assert_array_equal(S.split_blob_box(mask, offset, heads_x, 0), [137.0, 212.0, 38.0, 88.0])
    empty = np.zeros((10, 20), bool)  # no foreground in the slice: the slice itself
    np.testing.assert_array_equal(S.split_blob_box(empty, offset, np.array([5.0, 15.0]), 1),
                                  [110.0, 200.0, 10.0, 10.0])


def test_blobs_boxes_equal_opencv_statistics():
    rng = np.random.default_rng(6)
    for _ in range(20):
        fg = np.zeros((90, 120), bool)
        for _ in range(int(rng.integers(0, 8))):
            fg |= _random_blob(rng, 90, 120) & (rng.random() < 0.9)
        fg |= rng.random((90, 120)) < 0.01
        min_area = int(rng.integers(1, 40))
        labels, boxes, numbers = S.blobs_boxes(fg, min_area)
        _, ref_labels, stats, _ = cv2.connectedComponentsWithStats(fg.view(np.uint8), connectivity=8,
                                                                  ltype=cv2.CV_16U)
        keep = np.nonzero(stats[1:, cv2.CC_STAT_AREA] >= min_area)[0] + 1
        np.testing.assert_array_equal(labels, ref_labels)
        np.testing.assert_array_equal(numbers, keep)
        np.testing.assert_array_equal(boxes, stats[keep, :4].astype(np.float64))


def test_band_heads_and_residual_foreground_equal_the_references():
    rng = np.random.default_rng(7)
    for _ in range(200):
        H, W = int(rng.integers(10, 90)), int(rng.integers(10, 90))
        fg = rng.random((H, W)) < rng.uniform(0.0, 0.9)
        n = int(rng.integers(0, 7))
        boxes = np.column_stack([rng.uniform(-20, W + 20, n), rng.uniform(-20, H + 20, n),
                                 rng.uniform(0, 50, n), rng.uniform(0, 70, n)])
        ref_heads = np.array([_head_from_band_reference(fg, b) for b in boxes]).reshape(-1, 3)
        for b, ref in zip(boxes, ref_heads):  # the numpy form against OpenCV's boundingRect
            np.testing.assert_array_equal(S.head_from_band(fg, b), ref)
        numpy_heads = np.array([S.head_from_band(fg, b) for b in boxes]).reshape(-1, 3)
        np.testing.assert_array_equal(S.heads_from_bands(fg, boxes), numpy_heads)  # the kernel
        resid = fg.copy()
        for b in boxes:
            rs, cs = box_slices(b, fg.shape)
            resid[rs, cs] = False
        assert S.residual_foreground(fg, boxes) == np.count_nonzero(resid)
    np.testing.assert_array_equal(S.head_from_band(None, np.array([10.0, 5.0, 8.0, 30.0])),
                                  [14.0, 5.0, 4.0])
    fg = np.ones((20, 30), bool)
    boxes = np.array([[0.0, 0.0, 10.0, 10.0], [np.nan, 1.0, 5.0, 5.0], [40.0, 50.0, 5.0, 5.0]])
    assert S.residual_foreground(fg, boxes) == 600 - 100  # the NaN box and the outside one: none
    assert np.isnan(S.heads_from_bands(fg, boxes)[1]).any()


def test_head_fill_and_head_patch_equal_the_references():
    rng = np.random.default_rng(8)
    gray = rng.integers(0, 256, (60, 80), dtype=np.uint8)
    fg = rng.random((60, 80)) < 0.5
    for _ in range(300):
        box = np.concatenate([rng.uniform(-10, 75, 2), rng.uniform(0, 40, 2)])
        x, y, w, h = box
        r0, r1 = max(round(y), 0), min(round(y + S.HEAD_FRACTION * h), 60)
        c0, c1 = max(round(x + 0.25 * w), 0), min(round(x + 0.75 * w), 80)
        fill = 0.0 if r1 <= r0 or c1 <= c0 else float(fg[r0:r1, c0:c1].mean())
        assert S.head_fill(fg, box) == fill
        r0, r1, c0, c1 = round(y), round(y + S.HEAD_FRACTION * h), round(x), round(x + w)
        patch = S.head_patch(gray, box)
        if r0 < 0 or c0 < 0 or r1 > 60 or c1 > 80 or r1 - r0 < 3 or c1 - c0 < 3:
            assert patch is None
        else:
            np.testing.assert_array_equal(patch, gray[r0:r1, c0:c1])
    assert S.head_fill(None, np.array([0.0, 0.0, 5.0, 5.0])) == 1.0


# ---------------------------------------------------------------------- occlusion and search


def _plain_kinds(region, pred, threshold):
    """PBM 3.1's occlusion test as numpy arrays (T, N, 2): the reference of
    ``occlusion_kinds``' kernel."""
    with np.errstate(invalid="ignore"):
        rel = (region[None, :, :] - pred[:, None, :]) / np.maximum(pred, 1.0)[:, None, :]
        larger, smaller = (rel > threshold).any(axis=2), (rel < -threshold).any(axis=2)
    return np.where(larger, 1, np.where(smaller, -1, 0)).astype(np.int64)


def test_occlusion_kinds_equal_the_numpy_arrays_on_random_ties_empty_and_nan():
    rng = np.random.default_rng(11)
    for T, N in ((0, 4), (3, 0), (1, 1), (30, 40)):
        region, pred = rng.uniform(0.2, 120, (N, 2)), rng.uniform(0.2, 100, (T, 2))
        if T > 10:
            pred[0] = (0.5, 0.25)  # floored at 1 pixel
            region[1] = pred[2] * 1.5  # ties: exactly at +-threshold 0.5
            region[2] = pred[3] * 0.5
            region[3, 0], pred[4, 1] = np.nan, np.nan
            region[4] = (np.inf, 10.0)
        for threshold in (0.0, 0.5):
            got = S.occlusion_kinds(region, pred, threshold)
            assert got.dtype == np.int64 and got.tolist() == _plain_kinds(region, pred, threshold).tolist()


def test_occlusion_kinds_shape_and_search_boxes_equal_the_one_at_a_time_versions():
    rng = np.random.default_rng(9)
    for _ in range(50):
        T, N = int(rng.integers(0, 6)), int(rng.integers(0, 8))
        region = rng.uniform(0.5, 120, (N, 2))
        pred = rng.uniform(0.5, 100, (T, 2))
        assert S.occlusion_kinds(region, pred, 0.5).shape == (T, N)
        heads = rng.uniform(0, 200, (T, 3))
        alpha = rng.uniform(0.3, 0.7, T)
        r = int(rng.integers(0, 4))
        many = S.search_boxes_many(heads, pred, alpha, 0.05, r)
        assert many.shape == (T, (2 * r + 1) ** 2, 4)
        for s in range(T):
            np.testing.assert_array_equal(many[s], S.search_boxes(heads[s], pred[s], alpha[s], 0.05, r))
            np.testing.assert_array_equal(S.aligned_box(heads[s], pred[s], alpha[s]),
                                          [heads[s, 0] - alpha[s] * pred[s, 0], heads[s, 1], *pred[s]])


def test_templates_too_small_for_blocks_are_matched_by_opencv_exhaustively():
    rng = np.random.default_rng(10)
    gray = _scene(rng)
    for th, tw in ((3, 3), (3, 20), (12, 3)):
        tpl = rng.integers(0, 256, (th, tw), dtype=np.uint8)
        tl, corr = S.match_head_template(gray, tpl, np.array([70.0, 50.0]), 30.0)
        ref_tl, ref_corr, _ = _exhaustive_match(gray, tpl, np.array([70.0, 50.0]), 30.0)
        np.testing.assert_array_equal(tl, ref_tl)
        assert corr == ref_corr


def test_bgr_frames_give_the_grey_frames_results():
    rng = np.random.default_rng(21)
    frame = rng.integers(0, 256, (90, 120, 3), dtype=np.uint8)
    frame[20:40, 30:60] = (40, 90, 200)  # a head-like blob to match
    gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    box = np.array([28.0, 18.0, 34.0, 150.0])
    tpl, tpl_grey = S.head_patch(frame, box), S.head_patch(gray, box)  # BGR and grey crops
    np.testing.assert_array_equal(cv2.cvtColor(tpl, cv2.COLOR_BGR2GRAY), tpl_grey)
    for centre, radius in ((np.array([26.0, 15.0]), 9.0), (np.array([60.0, 40.0]), 30.0)):
        a = S.match_head_template(frame, tpl, centre, radius)
        b = S.match_head_template(gray, tpl_grey, centre, radius)
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1] == b[1]
