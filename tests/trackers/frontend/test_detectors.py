"""Person detectors on frames with known people: foreground blobs, silhouette, HOG."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from occbench.trackers.frontend.background import BackgroundModel
from occbench.trackers.frontend.background_params import MaskCleanup, PixelModel
from occbench.trackers.frontend.detectors import SilhouetteDetector
from occbench.trackers.frontend.foreground import Blobs, ForegroundDetector
from occbench.trackers.frontend.heads import HeadDetector
from occbench.trackers.frontend.hog import Boxes, Crops, HogDetector, Scan, nms
from occbench.trackers.frontend.silhouette import SilhouetteMatcher, fit_height_model
from occbench.trackers.frontend.silhouette_params import (
    MOVED,
    Heights,
    Person,
    Report,
    Score,
    Search,
)
from occbench.trackers.frontend.silhouette_search import _integral
from occbench.trackers.frontend.silhouette_template import (
    analytic_template,
    fit_template,
    load_template,
)
from occbench.trackers.geometry import iou_matrix


GROUPS = {"person": Person, "heights": Heights, "score": Score, "search": Search,
          "report": Report}


def _matcher(**flat) -> SilhouetteMatcher:
    """A matcher from flat keys, each put in its group (``silhouette_params.MOVED``)."""
    groups: dict[str, dict] = {}
    for key, value in flat.items():
        groups.setdefault(MOVED[key], {})[key] = value
    return SilhouetteMatcher(**{g: GROUPS[g](**kw) for g, kw in groups.items()})


def _person_mask(shape, box):
    """Paint the shipped template (thresholded) into a (H, W) mask at xywh ``box``."""
    m = np.zeros(shape, dtype=np.uint8)
    x, y, w, h = box
    m[y : y + h, x : x + w] = cv2.resize(load_template(), (w, h)) > 0.5
    return m


def test_silhouette_finds_one_person_at_its_place():
    box = (50, 100, 34, 84)
    boxes, scores = _matcher(min_height=40, max_height=120, n_scales=10,
                                      downscale=1).fit(_person_mask((288, 384), box))
    assert len(boxes) == 1
    assert iou_matrix(boxes, np.array([box]))[0, 0] > 0.8 and scores[0] > 0.5


def test_silhouette_separates_two_touching_people():
    a, b = (100, 60, 34, 84), (116, 66, 31, 78)  # side by side, masks touching
    mask = _person_mask((240, 320), a) | _person_mask((240, 320), b)
    n, _ = cv2.connectedComponents(mask)
    assert n - 1 == 1  # one blob
    boxes, _ = _matcher(min_height=40, max_height=120, n_scales=10, downscale=1).fit(mask)
    assert len(boxes) == 2
    iou = iou_matrix(np.array([a, b]), boxes)
    assert (iou.max(axis=1) > 0.6).all()


def test_silhouette_ignores_specks_and_empty_masks():
    m = _matcher(min_height=40, max_height=120)
    mask = np.zeros((200, 200), dtype=np.uint8)
    assert len(m.fit(mask)[0]) == 0
    mask[10:13, 10:13] = 1
    assert len(m.fit(mask)[0]) == 0


def test_height_prior_restricts_scales():
    m = _matcher(min_height=30, max_height=120, n_scales=10, downscale=1)
    mask = _person_mask((288, 384), (50, 100, 34, 84))
    m.set_height_model((0.0, 40.0))  # people here are 40 pixels high
    boxes, _ = m.fit(mask)
    assert len(boxes) and (boxes[:, 3] <= 40 * 1.4 + 1).all()


def test_fit_template_and_height_model():
    masks = [np.ones((40, 16), bool), np.zeros((80, 32), bool), np.ones((80, 32), bool)]
    t = fit_template(masks, height=20)
    assert t.shape == (20, 8) and np.allclose(t, 1.0)  # the empty mask is skipped
    assert 0.0 <= analytic_template().min() and analytic_template().max() <= 1.0
    rng = np.random.default_rng(0)
    feet = rng.uniform(50, 280, 100)
    heights = 0.2 * feet + 20 + rng.normal(0, 1, 100)
    heights[:10] *= 2.5  # outliers (a person with its reflection)
    a, b = fit_height_model(feet, heights)
    assert a == pytest.approx(0.2, abs=0.02) and b == pytest.approx(20, abs=3)
    assert fit_height_model(feet[:5], heights[:5]) is None


def _scene(people: list[tuple[int, int, int, int]], seed: int = 0):
    """Textured background and a frame with filled person shapes at xywh boxes."""
    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.integers(60, 200, (240, 320, 3), dtype=np.uint8), (5, 5), 0)
    frame = bg.copy()
    for x, y, w, h in people:
        m = _person_mask(bg.shape[:2], (x, y, w, h)).astype(bool)
        frame[m] = (40, 40, 170)
    return bg, frame


def test_foreground_detector_boxes_of_moving_people():
    people = [(40, 50, 30, 80), (200, 100, 40, 100)]
    bg, frame = _scene(people)
    det = ForegroundDetector(BackgroundModel(model=PixelModel(history=50),
                                             cleanup=MaskCleanup(open_kernel=3, close_kernel=5)))
    for _ in range(20):
        det.detect(bg)
    dets, fg = det.detect(frame)
    assert fg.dtype == bool and fg.shape == frame.shape[:2]
    assert len(dets) == 2
    tight = []  # the painted shapes' own boxes
    for box in people:
        ys, xs = np.nonzero(_person_mask(fg.shape, box))
        tight.append([xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1])
    assert (iou_matrix(np.array(tight, float), dets.boxes).max(axis=1) > 0.85).all()
    assert dets.labels is not None and set(np.unique(dets.labels)) == {0, 1, 2}


def test_foreground_detector_splits_a_group_at_its_heads():
    img = np.full((200, 300, 3), (90, 110, 100), dtype=np.uint8)
    fg = np.zeros((200, 300), dtype=np.uint8)
    for cx in (120, 160):  # two people side by side: one blob
        h, top = 140, 40
        hh = h / 7
        cv2.rectangle(img, (int(cx - 0.14 * h), int(top + hh)), (int(cx + 0.14 * h), top + h), (150, 40, 40), -1)
        cv2.rectangle(fg, (int(cx - 0.14 * h), int(top + hh)), (int(cx + 0.14 * h), top + h), 1, -1)
        cv2.ellipse(img, (cx, int(top + hh / 2)), (int(hh * 0.4), int(hh / 2)), 0, 0, 360, (130, 160, 210), -1)
        cv2.ellipse(fg, (cx, int(top + hh / 2)), (int(hh * 0.4), int(hh / 2)), 0, 0, 360, 1, -1)
    det = ForegroundDetector(blobs=Blobs(max_aspect=0.5), heads=HeadDetector(), report_heads=True)
    dets = det.detect_on(img, fg.astype(bool))
    assert len(dets) == 2
    centres = np.sort(dets.boxes[:, 0] + dets.boxes[:, 2] / 2)
    np.testing.assert_allclose(centres, [120, 160], atol=6)
    assert np.isfinite(dets.heads).all()
    whole = ForegroundDetector(blobs=Blobs(max_aspect=0.5)).detect_on(img, fg.astype(bool))
    assert len(whole) == 1
    # split_heads off (PBM 2: a blob is one candidate): one box, the head still reported
    unsplit = ForegroundDetector(blobs=Blobs(max_aspect=0.5), heads=HeadDetector(), report_heads=True,
                                 split_heads=False).detect_on(img, fg.astype(bool))
    assert len(unsplit) == 1 and np.isfinite(unsplit.heads).all()
    np.testing.assert_allclose(unsplit.boxes[0], whole.boxes[0])


def test_silhouette_detector_end_to_end():
    people = [(40, 50, 30, 80), (200, 100, 40, 100)]
    bg, frame = _scene(people, seed=1)
    det = SilhouetteDetector(BackgroundModel(model=PixelModel(history=50)),
                             _matcher(min_height=50, max_height=130, downscale=1))
    for _ in range(20):
        det.detect(bg)
    dets, _ = det.detect(frame)
    assert len(dets) == 2
    assert (iou_matrix(np.array(people, float), dets.boxes).max(axis=1) > 0.6).all()
    assert ((dets.scores >= 0) & (dets.scores <= 1)).all()


def test_nms_keeps_best_of_overlapping():
    boxes = np.array([[0, 0, 10, 10], [1, 1, 10, 10], [50, 50, 10, 10]], float)
    np.testing.assert_array_equal(nms(boxes, np.array([0.5, 0.9, 0.1]), 0.3), [1, 2])


def test_hog_runs_and_returns_frame_coordinates():
    synthetic = pytest.importorskip("occbench.datasets.synthetic")
    seq = synthetic.load_scenario("crossing", length=10)
    frame, labels = seq.frame(5), seq.foreground(5)
    gt = seq.gt.table.boxes[seq.gt.rows_of(5)]
    big = gt[np.argmax(gt[:, 3])]
    full = HogDetector(crops=Crops(full_frame=True)).detect(frame)[0]
    crop = HogDetector(crops=Crops(target_height=128)).detect_on(frame, labels > 0)
    assert len(full) >= 1 and len(crop) >= 1
    # the person is found in the crop path at the same frame position as in the full frame
    assert iou_matrix(big[None], crop.boxes).max() > 0.4
    assert iou_matrix(full.boxes, crop.boxes).max() > 0.6
    assert ((crop.scores > 0) & (crop.scores < 1)).all()
    shrunk = HogDetector(crops=Crops(target_height=128),
                         boxes=Boxes(box_scale=(0.5, 0.5))).detect_on(frame, labels > 0)
    np.testing.assert_allclose(shrunk.boxes[0, 2:], crop.boxes[0, 2:] * 0.5)


def test_detector_arguments_validated():
    with pytest.raises(ValueError, match="blobs.max_aspect"):
        Blobs(min_aspect=0.9, max_aspect=0.5)
    with pytest.raises(ValueError, match="scan.scale"):
        Scan(scale=1.0)
    with pytest.raises(ValueError, match="boxes.box_scale"):
        Boxes(box_scale=(1.0,))
    with pytest.raises(TypeError, match="crops: expected a Crops"):
        HogDetector(crops={"full_frame": True})
    with pytest.raises(ValueError, match="detector.calibration_frames"):
        SilhouetteDetector(calibration_frames=-1)
    with pytest.raises(ValueError, match="detector.calibration_evidence"):
        SilhouetteDetector(calibration_evidence="boxes")
    with pytest.raises(ValueError, match="heights.max_height"):
        Heights(min_height=100, max_height=50)


@pytest.mark.parametrize(("kind", "field"), [
    (Person, "aspect"), (Person, "occupy_level"), (Heights, "min_height"),
    (Heights, "max_height"), (Heights, "n_scales"), (Heights, "height_tolerance"),
    (Score, "min_visible"), (Score, "head_contrast"), (Search, "downscale"),
    (Search, "group_gap"), (Report, "max_overlap"), (Blobs, "min_area"), (Blobs, "min_height"),
    (Blobs, "min_aspect"), (Blobs, "max_aspect"), (Crops, "target_height"),
    (Crops, "max_upscale"), (Crops, "min_scale"), (Scan, "scale")])
def test_detector_groups_refuse_nan(kind, field):
    """Every checked number refuses NaN (through ``trackers.common.checks``); before the
    groups ``height_tolerance``, ``group_gap``, ``min_height`` (of blobs), ``target_height``,
    ``max_upscale`` and ``scale`` (written ``x < 1``, ``x <= 0``, ...) let it in."""
    with pytest.raises(ValueError, match=f"{field} .*got nan"):
        kind(**{field: float("nan")})


def test_matcher_names_the_group_of_a_flat_key():
    with pytest.raises(TypeError, match=r"matcher.min_height: moved to matcher.heights.min_height"):
        SilhouetteMatcher(min_height=40)
    with pytest.raises(TypeError, match="heights: expected a Heights"):
        SilhouetteMatcher(heights={"min_height": 40})


def test_template_cells_sum_like_the_piecewise_constant_template():
    """sum_{a,b} coef I[Y + ys[a], X + xs[b]] (the cells' corners on an integral image) is the
    correlation of the image with T~, the template averaged over each cell; sum T~ = sum T."""
    m = _matcher(min_height=12, max_height=90, n_scales=5, downscale=1)
    sc = m._kernels_for(200)
    rng = np.random.default_rng(3)
    img = (rng.random((120, 100)) < 0.5).astype(np.uint8)
    I = _integral(img)
    for s, t in enumerate(sc.templates):
        th, tw = t.shape
        tt = np.zeros_like(t, dtype=np.float64)  # T~ drawn cell by cell
        ys, xs = sc.ys[s], sc.xs[s]
        for a in range(len(ys) - 1):
            for b in range(len(xs) - 1):
                if ys[a + 1] > ys[a] and xs[b + 1] > xs[b]:
                    tt[ys[a] : ys[a + 1], xs[b] : xs[b + 1]] = t[ys[a] : ys[a + 1], xs[b] : xs[b + 1]].mean()
        assert tt.sum() == pytest.approx(sc.tsum[s], rel=1e-5)
        for Y, X in rng.integers(0, [120 - th, 100 - tw], size=(5, 2)):
            want = (tt * img[Y : Y + th, X : X + tw]).sum()
            got = (sc.coef[s] * I[Y + ys[:, None], X + xs[None, :]]).sum()
            assert got == pytest.approx(want, rel=1e-9, abs=1e-9)
        kh, h0, h1, l1, r0 = sc.head[s]  # the head rule's rectangles
        assert kh == max(round(th / 7), 1) and 0 <= l1 <= h0 < h1 <= r0 <= tw


def test_compiled_greedy_search_equals_the_numpy_equations():
    rng = np.random.default_rng(5)
    mask = np.zeros((120, 160), dtype=np.uint8)
    for _ in range(5):  # a cluster of overlapping people and a few specks
        h = int(rng.integers(40, 80))
        x, y = int(rng.integers(10, 110)), int(rng.integers(5, 120 - h))
        mask[y : y + h, x : x + int(0.4 * h)] |= _person_mask((h, int(0.4 * h)), (0, 0, int(0.4 * h), h))
    mask[rng.random(mask.shape) < 0.01] = 1
    mask[70:, 120:152] |= _person_mask((80, 32), (0, 0, 32, 80))[:50]  # cut by the bottom edge
    got = {}
    cases = [(-1.0, None), (0.2, None), (0.2, (0.5, 10.0))]  # head rule, height model
    for compiled in (True, False):
        for head, model in cases:
            m = _matcher(min_height=30, max_height=100, n_scales=6, downscale=1,
                                  max_overlap=1.0, head_contrast=head, frame_border=True,
                                  height_model=model, compiled=compiled)
            got[compiled, head, model] = m.candidates(mask.copy())
    for key in cases:
        fast, ref = got[(True, *key)], got[(False, *key)]
        assert len(ref) >= 2
        np.testing.assert_array_equal(fast.boxes, ref.boxes)  # template boxes
        np.testing.assert_array_equal(fast.tight, ref.tight)  # explained foreground
        np.testing.assert_array_equal(fast.region, ref.region)
        np.testing.assert_allclose(fast.scores, ref.scores, rtol=1e-9)
    assert len(got[True, 0.2, None]) <= len(got[True, -1.0, None])


def test_frame_border_finds_a_person_cut_by_the_bottom_edge():
    # a person 100 rows high whose legs are outside a 240-row frame (only 60 rows visible)
    full = _person_mask((340, 320), (140, 180, 40, 100))
    mask = full[:240]
    kw = {"min_height": 60, "max_height": 120, "n_scales": 12, "downscale": 1}
    plain = _matcher(**kw).fit(mask)[0]
    cut = _matcher(**kw, frame_border=True).fit(mask)[0]
    visible = np.array([[140, 180, 40, 60]], float)  # the annotation convention: clipped box
    assert len(cut) == 1
    assert (cut[:, 1] + cut[:, 3] <= 240).all()  # clipped to the frame
    assert iou_matrix(visible, cut)[0, 0] > 0.9
    # without it, the missing legs count against every tall fit: a smaller, shifted box
    assert len(plain) == 0 or iou_matrix(visible, plain).max() < 0.8


def test_box_scale_aspect_and_fixed_height_model():
    box = (50, 100, 34, 84)
    mask = _person_mask((288, 384), box)
    kw = {"min_height": 40, "max_height": 120, "n_scales": 10, "downscale": 1}
    ref = _matcher(**kw).fit(mask)[0]
    scaled = _matcher(**kw, box_scale=(0.8, 0.9)).fit(mask)[0]
    assert len(ref) == 1 and len(scaled) == 1
    np.testing.assert_allclose(scaled[0, 2:], ref[0, 2:] * [0.8, 0.9])
    np.testing.assert_allclose(scaled[0, 0] + scaled[0, 2] / 2, ref[0, 0] + ref[0, 2] / 2)  # same centre
    assert scaled[0, 1] == ref[0, 1]  # same top
    narrow = _matcher(**kw, aspect=0.3)
    narrow._kernels_for(288)
    assert all(abs(t.shape[1] / t.shape[0] - 0.3) < 0.1 for t in narrow._cache[0].templates)
    # a fixed prior (camera calibration) survives set_height_model(None), e.g. a detector reset
    fixed = _matcher(**kw, height_model=(0.0, 40.0))
    fixed.set_height_model(None)
    assert fixed.height_model == (0.0, 40.0)
    b = fixed.fit(mask)[0]
    assert len(b) and (b[:, 3] <= 40 * 1.4 + 1).all()
    fixed.set_height_model((0.0, 84.0))  # a learnt prior overrides it
    assert fixed.height_model == (0.0, 84.0)
    with pytest.raises(ValueError, match="report.box_scale"):
        Report(box_scale=(0.0, 1.0))
    with pytest.raises(ValueError, match="person.aspect"):
        Person(aspect=5.0)
    with pytest.raises(ValueError, match="heights.height_model"):
        Heights(height_model=(1.0,))
