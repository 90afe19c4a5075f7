"""A camera's background learnt from its other footage (occbench.trackers.frontend.footage): people
standing still from a clip's first frame are found with it and missed without it."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from occbench.commands.detect import match_count
from occbench.trackers.frontend.fallback import MedianBackground, RegionDetector
from occbench.trackers.frontend.fallback_params import RegionFilter, RegionGrouping
from occbench.trackers.frontend.footage import CameraBackground, clip_median, pool_clips, start_with

H, W = 120, 160
FLOOR = (140 + np.random.default_rng(7).normal(0, 8, (H, W, 1)) + np.zeros((1, 1, 3))).clip(0, 255)
AREA_250 = RegionGrouping(initial_area=250.0)


def _clip(standing: list[tuple[int, int]], gain: float, length: int, seed: int,
          walker: bool = False) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Frames of the camera at brightness ``gain``: dark people seen from above (ellipses
    24 x 12 px) standing at ``standing`` from the first frame to the last, and optionally one
    walking; a window patch glaring white. Frames (H, W, 3) uint8, per frame (N, 4) xywh gt."""
    rng = np.random.default_rng(seed)
    frames, boxes = [], []
    for k in range(length):
        img = FLOOR * gain + rng.normal(0, 2, (H, W, 3))
        img[90:115, 5:40] = 255  # glare
        img = img.clip(0, 255).astype(np.uint8)
        people = list(standing) + ([(20 + 2 * k, 30)] if walker else [])
        for cx, cy in people:
            cv2.ellipse(img, (cx, cy), (12, 6), 0, 0, 360, (40, 35, 60), -1)
        frames.append(img)
        boxes.append(np.array([[cx - 12, cy - 6, 25, 13] for cx, cy in people], dtype=np.float64))
    return frames, boxes


def _footage() -> CameraBackground:
    """Three other clips of the camera, darker or brighter, people standing elsewhere."""
    clips = [_clip([(40, 70)], 0.9, 30, 1), _clip([(120, 40)], 1.1, 30, 2),
             _clip([(80, 100), (130, 90)], 1.0, 30, 3)]
    return pool_clips([clip_median(f) for f, _ in clips], "three synthetic clips")


def _recall(detector: RegionDetector, frames, boxes) -> tuple[float, float]:
    detector.reset()
    detector.warm_up_sequence(len(frames), lambda k: frames[k - 1])
    tp = nd = ng = 0
    for f, b in zip(frames, boxes):
        d, _ = detector.detect(f)
        tp, nd, ng = tp + match_count(b, d.boxes), nd + len(d), ng + len(b)
    return tp / ng, tp / max(nd, 1)


def test_pooled_background_is_the_empty_floor_at_each_clips_brightness():
    fp = _footage()
    assert fp.clips == 3 and fp.image.shape == (H, W, 3) and fp.spread.shape == (H, W)
    # every spot occupied in one clip is empty floor in the others: the pool shows none
    floor = FLOOR[..., 0] * np.ones((H, W))
    floor[90:115, 5:40] = 255
    assert np.median(np.abs(fp.image.mean(axis=2) - floor)) < 3
    assert np.abs(fp.image.mean(axis=2) - floor)[64:77, 28:53].max() < 20  # clip 1's person


def test_people_standing_still_from_the_first_frame_are_found_only_with_other_footage():
    frames, boxes = _clip([(60, 50), (110, 75)], 1.05, 60, 11)
    without = _recall(RegionDetector(MedianBackground(init_frames=30), grouping=AREA_250),
                      frames, boxes)
    bg = MedianBackground(init_frames=30, footage=_footage())
    with_footage = _recall(RegionDetector(bg, grouping=AREA_250), frames, boxes)
    assert without[0] < 0.1  # the clip's own median holds them
    assert with_footage[0] > 0.9 and with_footage[1] > 0.9
    assert 0 < bg.from_footage < 0.1  # only where they stand
    assert "other footage of this camera (three synthetic clips)" in bg.describe()


def test_a_walker_is_found_either_way_and_the_glare_never():
    frames, boxes = _clip([], 1.0, 50, 12, walker=True)
    bg = MedianBackground(init_frames=30, footage=_footage())
    det = RegionDetector(bg, grouping=AREA_250)
    assert _recall(det, frames, boxes)[0] > 0.9
    assert not det.background.apply(frames[0])[90:115, 5:40].any()


def test_footage_of_another_size_is_refused_naming_it():
    fp = _footage()
    with pytest.raises(ValueError, match=r"three synthetic clips.*160x120.*80x60"):
        start_with(fp, np.zeros((60, 80, 3), np.float32), np.full((60, 80), 20.0), 8.0)
    with pytest.raises(ValueError, match="different sizes"):
        pool_clips([np.zeros((4, 4, 3), np.float32), np.zeros((4, 5, 3), np.float32)], "x")


def test_regions_where_the_footage_disagrees_are_dropped():
    fg = np.zeros((60, 80), dtype=bool)
    fg[5:20, 5:25] = True  # on the unsteady zone (a glaring window in some clips)
    fg[35:50, 40:60] = True  # on steady floor
    zone = np.zeros((60, 80), dtype=bool)
    zone[0:25, 0:30] = True
    for max_unsteady, boxes in ((0.5, [[40, 35, 20, 15]]), (1.0, [[5, 5, 20, 15], [40, 35, 20, 15]])):
        det = RegionDetector(MedianBackground(), RegionFilter(max_unsteady=max_unsteady),
                             RegionGrouping(initial_area=300.0))
        det.background.unsteady = zone  # as MedianBackground.start sets it from the footage
        assert det.detect_on(None, fg).boxes.tolist() == boxes
    with pytest.raises(ValueError, match=r"^fallback\.regions\.max_unsteady "):
        RegionFilter(max_unsteady=1.5)
