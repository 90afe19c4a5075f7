"""The five-part split and per-part features (occbench.trackers.layered.parts, PBM 2.1-2.2)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from occbench.trackers.histograms import colour_histogram
from occbench.trackers.layered.params import FeatureParams
from occbench.trackers.layered.parts import (
    DEFAULT_ALPHA,
    DEFAULT_BETA,
    HEAD_FRACTION,
    N_PARTS,
    PartFeatureExtractor,
    centroid_ratios,
    part_boxes,
    part_displacement,
    part_overlap,
)


def test_part_boxes_hand_case():
    # 70 x 140 box: head = top 20 rows; centroid at the centre -> split at x = 35, y = 70
    p = part_boxes(np.array([[10.0, 5.0, 70.0, 140.0]]))[0]
    np.testing.assert_allclose(p[0], [10, 5, 70, 20])
    np.testing.assert_allclose(p[1], [10, 25, 35, 50])
    np.testing.assert_allclose(p[2], [45, 25, 35, 50])
    np.testing.assert_allclose(p[3], [10, 75, 35, 70])
    np.testing.assert_allclose(p[4], [45, 75, 35, 70])


def test_parts_tile_the_box_for_any_ratios():
    rng = np.random.default_rng(0)
    boxes = np.column_stack([rng.uniform(0, 100, (20, 2)), rng.uniform(5, 80, (20, 2))])
    alpha, beta = rng.uniform(0.1, 0.9, 20), rng.uniform(0.1, 0.9, 20)
    p = part_boxes(boxes, alpha, beta)
    np.testing.assert_allclose((p[:, :, 2] * p[:, :, 3]).sum(1), boxes[:, 2] * boxes[:, 3])
    np.testing.assert_allclose(p[:, 0, 3], HEAD_FRACTION * boxes[:, 3])
    # the split point is the centroid: ratios recovered by centroid_ratios (eqs. 1-2)
    xc = p[:, 1, 0] + p[:, 1, 2]
    yc = p[:, 1, 1] + p[:, 1, 3]
    a, b = centroid_ratios(boxes, np.column_stack([xc, yc]))
    np.testing.assert_allclose(a, alpha)
    np.testing.assert_allclose(b, beta)


def test_centroid_at_centre_gives_default_ratios():
    a, b = centroid_ratios(np.array([[0.0, 0, 40, 70]]), np.array([[20.0, 35.0]]))
    assert a[0] == pytest.approx(DEFAULT_ALPHA) and b[0] == pytest.approx(DEFAULT_BETA)


def _painted(colours, fg_left_only=False):
    """A 70 x 140 box at (20, 10) in a 200 x 200 frame, each part painted one colour."""
    frame = np.zeros((200, 200, 3), np.uint8)
    box = np.array([20.0, 10.0, 70.0, 140.0])
    p = part_boxes(box[None])[0]
    for j, (x, y, w, h) in enumerate(p.astype(int)):
        frame[y:y + h, x:x + w] = colours[j]
    fg = np.zeros((200, 200), bool)
    fg[10:150, 20:55 if fg_left_only else 90] = True
    return frame, fg, box


COLOURS = [(30, 60, 200), (200, 40, 40), (40, 200, 40), (220, 220, 30), (90, 90, 90)]


def test_histograms_equal_colour_histogram_of_the_part_pixels():
    frame, fg, box = _painted(COLOURS)
    ex = PartFeatureExtractor(bins=4)
    ex.start(frame, fg)
    f = ex.extract(box[None])
    for j in range(N_PARTS):
        px = np.array([COLOURS[j]], np.uint8)[None]
        xyz = cv2.cvtColor(px, cv2.COLOR_BGR2XYZ).reshape(-1, 3)
        np.testing.assert_allclose(f.xyz[0, j], colour_histogram(xyz, bins=4))
        hsv = cv2.cvtColor(px, cv2.COLOR_BGR2HSV).reshape(-1, 3).astype(np.float64)
        hsv[:, 0] *= 256.0 / 180.0  # OpenCV hue is 0..179
        np.testing.assert_allclose(f.hsv[0, j], colour_histogram(hsv, bins=4))
    np.testing.assert_allclose(f.area[0], 1.0)


def test_area_centroid_and_outline_follow_the_foreground():
    frame, fg, box = _painted(COLOURS, fg_left_only=True)
    ex = PartFeatureExtractor(bins=4, grid_rows=35, grid_cols=14)
    ex.start(frame, fg)
    f = ex.extract(box[None])
    np.testing.assert_allclose(f.area[0], [0.5, 1.0, 0.0, 1.0, 0.0])
    assert f.hsv[0, 2].sum() == 0 and f.xyz[0, 4].sum() == 0  # no foreground, empty histograms
    # the left torso's foreground centroid is the centre of its rectangle
    p = f.parts[0, 1]
    np.testing.assert_allclose(f.centroid[0, 1], p[:2] + p[2:] / 2, atol=1.0)
    # a full rectangle of foreground: outline samples only along its border
    ex.start(frame, np.ones((200, 200), bool))
    full = ex.extract(box[None])
    assert (full.perimeter[0] > 0).all()
    ex.start(frame, np.zeros((200, 200), bool))
    assert (ex.extract(box[None]).perimeter[0] == 0).all()


def test_extract_is_vectorised_consistently():
    rng = np.random.default_rng(1)
    frame = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    fg = rng.random((120, 160)) < 0.6
    boxes = np.column_stack([rng.uniform(-10, 120, (6, 2)), rng.uniform(10, 60, (6, 2))])
    ex = PartFeatureExtractor(bins=4)
    ex.start(frame, fg)
    together = ex.extract(boxes, 0.4, 0.6)
    for k in range(len(boxes)):
        alone = ex.extract(boxes[k:k + 1], 0.4, 0.6)
        for name in ("area", "perimeter", "hsv", "xyz", "centroid", "parts"):
            np.testing.assert_allclose(getattr(together, name)[k], getattr(alone, name)[0])
    np.testing.assert_allclose(together.hsv.sum(-1)[together.area > 0], 1.0)


def test_samples_outside_the_image_are_background():
    frame = np.full((50, 50, 3), 128, np.uint8)
    ex = PartFeatureExtractor(bins=2)
    ex.start(frame, None)  # no foreground: the whole box counts, but only inside the image
    f = ex.extract(np.array([[25.0, 0.0, 50.0, 49.0]]))
    np.testing.assert_allclose(f.area[0, [1, 3]], 1.0)
    np.testing.assert_allclose(f.area[0, [2, 4]], 0.0)


def test_displacement_and_overlap():
    frame = np.full((100, 100, 3), 100, np.uint8)
    ex = PartFeatureExtractor()
    ex.start(frame, None)
    a = ex.extract(np.array([[10.0, 10, 20, 70]]))
    b = ex.extract(np.array([[10.0, 10, 20, 70], [17.0, 10, 20, 70]]))
    d = part_displacement(b, a)[:, 0]
    np.testing.assert_allclose(d[0], 0.0)
    np.testing.assert_allclose(d[1], 7.0 / 70.0)
    o = part_overlap(a, b)[0]
    np.testing.assert_allclose(o[0], 1.0)
    np.testing.assert_allclose(o[1, 0], 13.0 / 27.0)  # head: 13 of 27 columns shared


def test_bad_input():
    ex = PartFeatureExtractor()
    with pytest.raises(RuntimeError):
        ex.extract(np.zeros((1, 4)))
    with pytest.raises(ValueError, match="uint8"):
        ex.start(np.zeros((10, 10)), None)
    with pytest.raises(ValueError, match="foreground shape"):
        ex.start(np.zeros((10, 10, 3), np.uint8), np.zeros((5, 5), bool))
    with pytest.raises(ValueError, match=r"^features\.histogram_bins must lie in 1\.\.32, got 0$"):
        PartFeatureExtractor(bins=0)  # through common.checks, named by its config key (issue 36)
    with pytest.raises(ValueError, match=r"^features\.grid must be at least 7 x 2 "):
        PartFeatureExtractor(4, 5, 9)
    with pytest.raises(ValueError, match=r"^features\.search_grid must be at least 7 x 2 "):
        FeatureParams(search_grid=(5, 9))  # named by its own key before an extractor is built
    # a grid row is one 64-bit mask in the kernels
    with pytest.raises(ValueError, match=r"^features\.grid .* at most 64 columns, got \[35, 65\]$"):
        PartFeatureExtractor(4, 35, 65)
    with pytest.raises(ValueError, match=r"^features\.search_grid .* at most 64 columns"):
        FeatureParams(search_grid=(21, 65))
    PartFeatureExtractor(4, 7, 64)  # the widest grid


def test_lut_bins_equal_the_joint_index_formula():
    # the cv2.LUT quantisation used by the extractor equals min(v * bins // range, bins - 1)
    from occbench.trackers.layered.parts import HSV_RANGES, XYZ_RANGES, _joint_index, _joint_lut

    img = np.random.default_rng(3).integers(0, 256, (40, 30, 3), dtype=np.uint8)
    for bins in (2, 4, 8):
        for ranges in (HSV_RANGES, XYZ_RANGES):
            q = cv2.LUT(img, _joint_lut(bins, ranges)).astype(np.int64)
            np.testing.assert_array_equal(q.sum(-1), _joint_index(img, bins, ranges))


def test_extract_at_centroids_equals_centroids_then_extract():
    rng = np.random.default_rng(2)
    frame = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    fg = rng.random((120, 160)) < 0.6
    boxes = np.column_stack([rng.uniform(-10, 120, (5, 2)), rng.uniform(10, 60, (5, 2))])
    ex = PartFeatureExtractor(bins=4)
    ex.start(frame, fg)
    c = ex.centroids(boxes)
    ref = ex.extract(boxes, *centroid_ratios(boxes, c))
    c2, got = ex.extract_at_centroids(boxes)
    np.testing.assert_array_equal(c2, c)  # the same kernel helper
    for name in ("area", "perimeter", "hsv", "xyz", "centroid", "parts", "height"):
        np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-9, atol=1e-12)


# --- the compiled extractor against a straightforward per-box reference -------------------

def _reference(frame, fg, boxes, alpha, beta, bins, rows, cols, at_centroids=False):
    """PartFeatures (and centroids) of each box, one box at a time, with the operations
    of the vectorised extractor the kernels replaced (equal to rounding, rtol 1e-9):
    a sample grid, cv2.cvtColor of the foreground samples, np.bincount per part."""
    from occbench.trackers.layered.parts import HSV_RANGES, XYZ_RANGES, PartFeatures, _joint_index

    H, W = frame.shape[:2]
    fr, fc = (np.arange(rows) + 0.5) / rows, (np.arange(cols) + 0.5) / cols
    nb = bins**3
    feats, cents = [], []
    for i, box in enumerate(np.asarray(boxes, dtype=np.float64)):
        x, y, w, h = box
        ys, xs = y + fr * h, x + fc * w
        yi = np.clip(np.floor(ys), 0, H - 1).astype(int)
        xi = np.clip(np.floor(xs), 0, W - 1).astype(int)
        on = ((ys >= 0) & (ys < H))[:, None] & ((xs >= 0) & (xs < W))[None, :]
        if fg is not None:
            on &= fg[yi][:, xi]
        if at_centroids:
            n = on.sum()
            # the mean sample position, from integer sums of the sample indices
            c = (np.array([x + w * ((on.sum(0) @ np.arange(cols) / n + 0.5) / cols),
                           y + h * ((on.sum(1) @ np.arange(rows) / n + 0.5) / rows)]) if n
                 else box[:2] + 0.5 * box[2:])
            cents.append(c)
            a, b = centroid_ratios(box[None], c[None])
        else:
            a = np.broadcast_to(alpha, len(boxes))[i:i + 1]
            b = np.broadcast_to(beta, len(boxes))[i:i + 1]
        p = part_boxes(box[None], a, b)[0]
        band = np.where(ys < p[0, 1] + p[0, 3], 0, np.where(ys < p[1, 1] + p[1, 3], 1, 3))
        right = (xs >= p[1, 0] + p[1, 2]).astype(int)
        key = np.where(band[:, None] > 0, band[:, None] + right[None, :], 0)  # (R, C) part
        pix = frame[yi][:, xi][on][None]  # foreground samples in row-major order
        hsv_j = xyz_j = np.zeros(0, np.int64)
        if pix.size:
            hsv_j = _joint_index(cv2.cvtColor(pix, cv2.COLOR_BGR2HSV)[0], bins, HSV_RANGES)
            xyz_j = _joint_index(cv2.cvtColor(pix, cv2.COLOR_BGR2XYZ)[0], bins, XYZ_RANGES)
        k = key[on]
        count = np.bincount(k, minlength=N_PARTS).astype(float)
        norm = np.maximum(count, 1.0)[:, None]
        hist_hsv = np.bincount(k * nb + hsv_j, minlength=N_PARTS * nb).reshape(N_PARTS, nb) / norm
        hist_xyz = np.bincount(k * nb + xyz_j, minlength=N_PARTS * nb).reshape(N_PARTS, nb) / norm
        sx = np.bincount(k, weights=np.broadcast_to(xs, on.shape)[on], minlength=N_PARTS)
        sy = np.bincount(k, weights=np.broadcast_to(ys[:, None], on.shape)[on], minlength=N_PARTS)
        interior = np.zeros_like(on)
        interior[1:-1, 1:-1] = on[:-2, 1:-1] & on[2:, 1:-1] & on[1:-1, :-2] & on[1:-1, 2:]
        edge = np.bincount(key[on & ~interior], minlength=N_PARTS)
        samples = np.bincount(key.reshape(-1), minlength=N_PARTS)
        band_rows = [(band == v).sum() for v in (0, 1, 1, 3, 3)]
        side_cols = [cols, cols - right.sum(), right.sum(), cols - right.sum(), right.sum()]
        half = np.add(band_rows, side_cols).astype(float)
        centre = p[:, :2] + 0.5 * p[:, 2:]
        centroid = np.where(count[:, None] > 0, np.column_stack([sx, sy]) / norm, centre)
        feats.append(PartFeatures(p[None], (count / np.maximum(samples, 1.0))[None],
                                  (edge / np.maximum(half, 1.0))[None], hist_hsv[None],
                                  hist_xyz[None], centroid[None], box[3:4].copy()))
    out = PartFeatures.concatenate(feats, bins)
    return (np.array(cents).reshape(-1, 2), out) if at_centroids else out


FIELDS = ("parts", "area", "perimeter", "hsv", "xyz", "centroid", "height")


def _assert_same(got, ref):
    for name in FIELDS:
        a, b = getattr(got, name), getattr(ref, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12, err_msg=name)


def _scene(seed, fg_kind):
    """A 90 x 120 noisy frame of flat-coloured people, its foreground (blobs with holes,
    empty, or None) and 12 boxes, some partly or wholly outside the image."""
    rng = np.random.default_rng(seed)
    frame = rng.integers(0, 256, (90, 120, 3), dtype=np.uint8)
    fg = np.zeros((90, 120), bool)
    for _ in range(4):
        x, y = rng.integers(0, 100), rng.integers(0, 60)
        w, h = rng.integers(8, 30), rng.integers(20, 60)
        frame[y:y + h, x:x + w] = rng.integers(0, 256, 3)
        fg[y:y + h, x:x + w] = True
    frame = np.clip(frame + rng.integers(-12, 13, frame.shape), 0, 255).astype(np.uint8)
    fg &= rng.random(fg.shape) < 0.9
    fg = {"mask": fg, "empty": np.zeros_like(fg), "none": None}[fg_kind]
    boxes = np.column_stack([rng.uniform(-40, 130, 12), rng.uniform(-50, 80, 12),
                             rng.uniform(1, 60, 12), rng.uniform(1, 90, 12)])
    boxes[0] = [50.3, 20.7, 0.0, 0.0]  # a degenerate box
    return frame, fg, boxes, rng.uniform(0.05, 0.95, 12), rng.uniform(0.05, 0.95, 12)


@pytest.mark.parametrize("fg_kind", ["mask", "empty", "none"])
@pytest.mark.parametrize(
    "bins, grid", [(4, (35, 15)), (4, (21, 9)), (8, (21, 9)), (3, (14, 5)), (2, (133, 3)), (4, (14, 64))])
def test_extractor_equals_the_reference(fg_kind, bins, grid):
    frame, fg, boxes, alpha, beta = _scene(bins * 100 + grid[0], fg_kind)
    ex = PartFeatureExtractor(bins, *grid)
    ex.start(frame, fg)
    _assert_same(ex.extract(boxes, alpha, beta), _reference(frame, fg, boxes, alpha, beta, bins, *grid))
    _assert_same(ex.extract(boxes, 0.3, DEFAULT_BETA),
                 _reference(frame, fg, boxes, 0.3, DEFAULT_BETA, bins, *grid))
    cents, feats = ex.extract_at_centroids(boxes)
    ref_cents, ref = _reference(frame, fg, boxes, None, None, bins, *grid, at_centroids=True)
    np.testing.assert_allclose(cents, ref_cents, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ex.centroids(boxes), ref_cents, rtol=1e-9, atol=1e-12)
    _assert_same(feats, ref)


def test_colour_conversion_equals_cvtcolor_for_every_colour():
    # the kernels' integer HSV and XYZ formulas against OpenCV on all 2**24 BGR colours,
    # 16 blue values (2**20 colours) at a time
    from occbench.trackers.layered import colour_kernels

    v = np.arange(256, dtype=np.uint8)
    block = np.empty((16, 256, 256, 3), np.uint8)
    block[..., 1], block[..., 2] = v[None, :, None], v[None, None, :]
    got = np.empty((1 << 20, 6), np.uint8)
    for b0 in range(0, 256, 16):
        block[..., 0] = v[b0:b0 + 16, None, None]
        img = block.reshape(1024, 1024, 3)
        colour_kernels.convert(img.reshape(-1, 3), got)
        np.testing.assert_array_equal(got[:, :3], cv2.cvtColor(img, cv2.COLOR_BGR2HSV).reshape(-1, 3))
        np.testing.assert_array_equal(got[:, 3:], cv2.cvtColor(img, cv2.COLOR_BGR2XYZ).reshape(-1, 3))


def test_extractor_accepts_readonly_and_list_inputs():
    frame, fg, boxes, alpha, beta = _scene(5, "mask")
    ex = PartFeatureExtractor()
    ex.start(frame, fg)
    ref = ex.extract(boxes, alpha, beta)
    frame.flags.writeable = False
    boxes.flags.writeable = False
    alpha.flags.writeable = False
    ex.start(frame, fg.astype(np.uint8))
    _assert_same(ex.extract(boxes.tolist(), alpha, list(beta)), ref)
    assert ex.extract(np.zeros((0, 4))).hsv.shape == (0, N_PARTS, 64)
    c, f = ex.extract_at_centroids(np.zeros((0, 4)))
    assert c.shape == (0, 2) and len(f) == 0


def test_boxes_that_are_not_finite_read_nothing_outside_the_image():
    frame, fg = _scene(6, "mask")[:2]
    bad = np.array([[np.nan, 10.0, 20.0, 40.0], [5.0, -np.inf, 20.0, 40.0],
                    [5.0, 10.0, np.inf, 1e300], [-1e300, 1e300, 20.0, 40.0]])
    for foreground in (fg, None):
        ex = PartFeatureExtractor()
        ex.start(frame, foreground)
        f = ex.extract(bad, 0.5, 0.5)
        assert f.hsv.shape == (4, N_PARTS, 64)
        assert (f.area[:2] == 0).all() and (f.hsv[:2] == 0).all()  # no sample is in the image
        assert ex.extract_at_centroids(bad)[0].shape == (4, 2)
    with pytest.raises(ValueError, match="non-empty"):
        ex.start(np.zeros((0, 5, 3), np.uint8), None)
