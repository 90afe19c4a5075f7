"""Background subtraction, shadow removal, morphology and blobs on frames with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.frontend.background import BackgroundModel
from occbench.trackers.frontend.background_params import FrameInput, MaskCleanup, PixelModel, WarmUp
from occbench.trackers.frontend.blobs import blob_boxes, blobs_from_mask

RAW = MaskCleanup(open_kernel=0, close_kernel=0)  # the model's mask, no morphology


def test_blobs_of_known_mask():
    m = np.zeros((50, 60), dtype=bool)
    m[5:15, 10:20] = True  # 10x10 square
    m[30:32, 40:43] = True  # 3x2 rectangle
    m[40, 0] = True  # single pixel: below min_area
    blobs = blobs_from_mask(m, min_area=2)
    assert len(blobs) == 2
    big, small = blobs
    np.testing.assert_array_equal(big.box, [10, 5, 10, 10])
    np.testing.assert_allclose(big.centroid, [15.0, 10.0])
    assert big.area == 100 and small.area == 6
    assert big.perimeter == pytest.approx(36.0)  # contour through pixel centres: 4 * 9
    assert big.mask.sum() == 100 and big.mask[5:15, 10:20].all()
    assert small.crop_mask().shape == (2, 3) and small.crop_mask().all()
    np.testing.assert_array_equal(blob_boxes(blobs)[1], [40, 30, 3, 2])
    assert blobs[0].labels.max() == 2 and blobs[0].labels[40, 0] == 0


def test_label_image_nonzero_is_foreground():
    lab = np.zeros((20, 20), dtype=np.int32)
    lab[2:8, 2:8] = 3
    lab[2:8, 8:12] = 7  # touches label 3: one component
    blobs = blobs_from_mask(lab, min_area=1)
    assert len(blobs) == 1 and blobs[0].area == 6 * 10


def test_blobs_reject_bad_shape():
    with pytest.raises(ValueError, match="2-D"):
        blobs_from_mask(np.zeros((4, 4, 3)), min_area=1)


def _scene(person_value: int, shadow: bool) -> tuple[np.ndarray, np.ndarray]:
    bg = np.full((60, 80, 3), 120, dtype=np.uint8)
    f = bg.copy()
    f[10:40, 20:30] = person_value
    if shadow:
        f[40:50, 20:45] = 70  # same hue, darker: a cast shadow
    return bg, f


def test_shadow_pixels_removed_and_person_kept():
    model = BackgroundModel(method="mog2", model=PixelModel(history=50), cleanup=RAW)
    bg, f = _scene(230, shadow=True)
    for _ in range(40):
        model.apply(bg)
    raw = model.raw(f)
    assert (raw[42:48, 22:43] == 127).mean() > 0.9  # the model labels the shadow
    mask = model.clean(raw) > 0
    assert mask[12:38, 22:28].all()
    assert not mask[42:48, 22:43].any()
    blobs = blobs_from_mask(mask, min_area=20)
    assert len(blobs) == 1
    np.testing.assert_array_equal(blobs[0].box, [20, 10, 10, 30])


def test_opening_removes_specks_and_closing_fills_holes():
    model = BackgroundModel(cleanup=MaskCleanup(open_kernel=3, close_kernel=5))
    raw = np.zeros((60, 60), dtype=np.uint8)
    raw[10:40, 10:30] = 255
    raw[20, 20] = 0  # hole
    raw[50, 50] = 255  # speck
    out = model.clean(raw) > 0
    assert out[20, 20] and not out[50, 50]


def test_warm_up_learns_background_behind_standing_person():
    rng = np.random.default_rng(0)
    bg = rng.integers(80, 160, size=(40, 50, 3), dtype=np.uint8)
    frames = []
    for k in range(20):
        f = bg.copy()
        x = 2 + 2 * k
        f[5:30, x : x + 6] = 250  # a person walking across the view
        frames.append(f)
    model = BackgroundModel(model=PixelModel(history=100), start=WarmUp(warmup_frames=10),
                            cleanup=RAW)
    model.warm_up_sequence(len(frames), lambda k: frames[k - 1])
    mask = model.apply(frames[0])
    assert mask[6:29, 3:7].mean() > 0.9  # the person at the start is foreground
    assert mask[:, 20:].mean() < 0.02  # the rest is background
    cold = BackgroundModel(model=PixelModel(history=100), cleanup=RAW)
    assert cold.apply(frames[0]).sum() == 0  # without warm-up the first frame is background


def test_work_scale_gives_full_size_mask():
    model = BackgroundModel(model=PixelModel(history=50), cleanup=RAW,
                            frames=FrameInput(work_scale=0.5))
    bg, f = _scene(230, shadow=False)
    for _ in range(30):
        model.apply(bg)
    mask = model.apply(f)
    assert mask.shape == f.shape[:2]
    assert mask[12:38, 22:28].all() and mask.sum() < 1.3 * 300
    with pytest.raises(ValueError, match="work_scale"):
        BackgroundModel(frames=FrameInput(work_scale=0))


def test_empty_mask_has_no_blobs():
    assert blobs_from_mask(np.zeros((5, 5), bool)) == []


def test_inpainted_estimate_removes_a_person_who_never_leaves():
    from occbench.trackers.frontend.background import background_estimate

    yy, xx = np.mgrid[0:80, 0:100]
    bg = np.dstack([100 + xx // 2, 120 + yy // 4, np.full_like(xx, 140)]).astype(np.uint8)
    frames = []
    for k in range(30):  # a dark person swaying in place, present in every frame
        f = bg.copy()
        x = 40 + round(4 * np.sin(k / 3))
        y = 20 + round(3 * np.cos(k / 2))
        f[y : y + 40, x : x + 14] = 30
        frames.append(f)
    median = background_estimate(frames, inpaint=False)
    assert np.abs(median[30:50, 45:50].astype(int) - bg[30:50, 45:50]).max() > 50  # the person
    est = background_estimate(frames, inpaint=True, spread_threshold=12, spread_quantile=0.75)
    assert np.abs(est[30:50, 45:50].astype(int) - bg[30:50, 45:50]).max() < 15
    assert np.abs(est[:, :20].astype(int) - bg[:, :20]).max() <= 1  # elsewhere: the median


@pytest.mark.parametrize("compensate", [True, False])
def test_gain_compensation_ignores_global_brightening(compensate):
    rng = np.random.default_rng(2)
    bg = rng.integers(50, 150, size=(60, 80, 3), dtype=np.uint8)
    model = BackgroundModel(model=PixelModel(history=50), cleanup=RAW,
                            frames=FrameInput(gain_compensation=compensate))
    for _ in range(30):
        model.apply(bg)
    bright = (bg * 1.4).astype(np.uint8)  # (a darker scene would pass as shadow)
    bright[10:40, 20:30] = 10  # a person in the brighter scene
    mask = model.apply(bright)
    assert mask[12:38, 22:28].all()
    if compensate:
        np.testing.assert_allclose(model.last_gain, 1.4, atol=0.02)
        assert mask.mean() < 0.1
    else:
        assert mask.mean() > 0.5
