"""The front end's camera-fit check and its fallback (occbench.trackers.frontend.fallback): an
overhead scene the upright-person model does not fit is noticed, said in one line, and its
people found by foreground regions; a scene it fits (synthetic, and the shipped CAVIAR
corridor sample) is left to the silhouette detector."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from hydra.utils import instantiate

from occbench.commands.detect import fallback_note, match_count
from occbench.config.build import compose_config
from occbench.trackers.frontend.fallback import (
    CameraFitCheck,
    FitEvidence,
    MedianBackground,
    RegionDetector,
)
from occbench.trackers.frontend.fallback_params import (
    DifferenceThreshold,
    MaskMorphology,
    RegionFilter,
    RegionGrouping,
    UpdateRates,
)

H, W, LENGTH = 288, 384, 90


def _overhead(seed: int = 0) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """A camera looking straight down: a textured floor, three people seen from above (dark
    ellipses twice as wide as tall, 44 x 22 px) walking from frame 1 on, and a window whose glare
    flickers to white. Frames (H, W, 3) uint8 and per frame the (N, 4) xywh gt boxes."""
    import cv2

    rng = np.random.default_rng(seed)
    floor = (150 + rng.normal(0, 6, (H, W, 1)) + np.zeros((1, 1, 3))).clip(0, 255)
    starts = np.array([[60.0, 60.0], [300.0, 90.0], [120.0, 220.0]])
    steps = np.array([[2.0, 0.8], [-2.2, 1.0], [2.4, -0.6]])
    colours = [(40, 40, 90), (70, 50, 30), (30, 30, 30)]
    frames, boxes = [], []
    for k in range(LENGTH):
        img = floor.copy()
        if rng.random() < 0.5:  # glare: a saturated window patch, on half the frames
            img[200:260, 10:70] = 255
        img += rng.normal(0, 2, img.shape)
        img = img.clip(0, 255).astype(np.uint8)
        bk = []
        for (x, y), (dx, dy), c in zip(starts, steps, colours):
            cx, cy = int(x + dx * k), int(y + dy * k)
            cv2.ellipse(img, (cx, cy), (22, 11), 0, 0, 360, c, -1)
            bk.append([cx - 22, cy - 11, 45, 23])
        frames.append(img)
        boxes.append(np.array(bk, dtype=np.float64))
    return frames, boxes


def _silhouette():
    return instantiate(compose_config(["detector=silhouette"], config_name="detect").detector).detector


def test_misfit_is_noticed_said_in_one_line_and_the_fallback_finds_the_people(caplog):
    frames, boxes = _overhead()
    det = _silhouette()
    det.reset()
    with caplog.at_level(logging.INFO, logger="occbench.trackers.frontend.detectors"):
        det.warm_up_sequence(LENGTH, lambda k: frames[k - 1])
    assert det.fallback_reason is not None and "does not fit" in det.fallback_reason
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(said) == 1 and "\n" not in said[0]
    assert "RegionDetector" in said[0] and "explain" in said[0]
    assert det.evidence.explained_share < 0.5
    note = fallback_note(det)  # what `occbench detect` prints and writes to front_end.txt
    assert note.startswith("detected with foreground regions") and det.fallback_reason in note
    tp = nd = ng = 0
    for k, f in enumerate(frames, 1):
        dets, fg = det.detect(f)
        assert fg.shape == (H, W) and fg.dtype == bool
        assert not fg[200:260, 10:70].any()  # the glare is never foreground
        tp += match_count(boxes[k - 1], dets.boxes)
        nd, ng = nd + len(dets), ng + len(boxes[k - 1])
    assert tp / ng > 0.9 and tp / nd > 0.9


def test_a_scene_the_model_fits_is_left_to_the_silhouette_detector():
    from occbench.datasets.synthetic import load_scenario

    seq = load_scenario("crowd", seed=0, width=W, height=H, length=40, camera_height=2.5,
                        horizon=0.1, people=8)
    det = _silhouette()
    det.reset()
    for k in range(1, seq.info.length + 1):
        det._collect(seq.foreground(k) > 0)
    assert det.evidence.explained_share > 0.8
    assert det.fit_check.misfit(True, det.evidence) is None


def test_the_shipped_corridor_sample_does_not_fall_back():
    from occbench.config.build import dataset_sequences as load_sequences

    seq = load_sequences(["dataset=caviar", "dataset.frames=[1,40]"])[0]
    source = instantiate(compose_config(["detector=silhouette"], config_name="detect").detector)
    source.start(seq)
    det = source.detector
    assert det.fallback_reason is None
    assert det.evidence.busy_frames >= 10 and det.evidence.explained_share > 0.8


def test_fit_evidence_counts_the_foreground_inside_boxes():
    fg = np.zeros((50, 50), dtype=bool)
    fg[10:20, 10:20] = True  # 100 px, inside the box
    fg[30:40, 30:40] = True  # 100 px, outside
    fg[0:2, 45:47] = True  # 4 px: below min_area, not counted
    ev = FitEvidence(min_area=10)
    ev.add(fg, np.array([[5.0, 5.0, 20.0, 20.0]]))
    assert (ev.frames, ev.busy_frames, ev.foreground, ev.explained) == (1, 1, 200, 100)
    assert ev.explained_share == 0.5
    ev.add(np.zeros((50, 50), dtype=bool), np.zeros((0, 4)))
    assert ev.busy_frames == 1
    check = CameraFitCheck(min_explained=0.6, min_busy_frames=1)
    assert "50%" in check.misfit(False, ev) and "no consistent upright" in check.misfit(False, ev)
    assert CameraFitCheck(min_explained=0.5, min_busy_frames=1).misfit(True, ev) is None
    assert CameraFitCheck(min_explained=0.6, min_busy_frames=2).misfit(True, ev) is None


def test_median_background_starts_with_people_in_view_and_ignores_saturation():
    rng = np.random.default_rng(3)
    base = (120 + rng.normal(0, 3, (40, 60, 3))).clip(0, 255).astype(np.uint8)
    frames = []
    for k in range(30):  # a dark square walking right, in view from the first frame
        f = base.copy()
        f[10:20, 2 * k: 2 * k + 8] = 20
        frames.append(f)
    bg = MedianBackground(init_frames=30)
    bg.start(frames)
    np.testing.assert_allclose(bg.background, MedianBackground(init_frames=30)._smooth(base),
                               atol=6)
    probe = base.copy()
    probe[25:35, 10:20] = 20  # a person
    probe[0:8, 40:60] = 255  # glare
    fg = bg.apply(probe)
    assert fg[27:33, 12:18].all() and not fg[0:8, 40:60].any()


def test_region_detector_merges_fragments_and_splits_when_asked():
    fg = np.zeros((100, 100), dtype=bool)
    fg[10:30, 10:20] = True
    fg[10:30, 22:30] = True  # a fragment 2 px away: one person
    d = RegionDetector(grouping=RegionGrouping(initial_area=400.0)).detect_on(None, fg)
    assert len(d) == 1 and d.boxes[0].tolist() == [10, 10, 20, 20]
    big = np.zeros((100, 100), dtype=bool)
    big[40:60, 10:90] = True  # 1600 px: four typical people side by side
    split = RegionGrouping(initial_area=400.0, split_ratio=2.5)
    d = RegionDetector(grouping=split).detect_on(None, big)
    assert len(d) == 4 and np.allclose(np.sort(d.boxes[:, 2]), 20, atol=3)
    assert len(RegionDetector(grouping=RegionGrouping(initial_area=400.0)).detect_on(None, big)) == 1


def test_fallback_arguments_are_validated():
    with pytest.raises(ValueError, match=r"^fit_check\.min_explained "):
        CameraFitCheck(min_explained=0.0)
    with pytest.raises(ValueError, match=r"^fallback\.background\.rates\.slow_rate "):
        UpdateRates(fast_rate=0.01, slow_rate=0.1)
    with pytest.raises(ValueError, match=r"^fallback\.background\.steady_spread .*nan"):
        MedianBackground(steady_spread=float("nan"))  # let in before
    with pytest.raises(ValueError, match=r"^fallback\.background\.morphology\.open_kernel "):
        MaskMorphology(open_kernel=-1)
    with pytest.raises(ValueError, match=r"^fallback\.background\.threshold\.blur "):
        DifferenceThreshold(blur=4)
    with pytest.raises(TypeError, match=r"background.k_sigma: moved to fallback.background.thr"):
        MedianBackground(k_sigma=3.0)  # a flat key before the groups (issue 36)
    with pytest.raises(ValueError, match=r"^fallback\.grouping\.split_ratio "):
        RegionGrouping(split_ratio=1.0)
    with pytest.raises(ValueError, match=r"^fallback\.regions\.min_area "):
        RegionFilter(min_area=0)
    with pytest.raises(TypeError, match=r"fallback.split_ratio: moved to fallback.grouping"):
        RegionDetector(split_ratio=2.0)  # a flat key before the groups (issue 36)
