"""Scale in PBM's comparators: Comaniciu et al.'s +/-10 % test in ScaleAdaptiveMeanShift and
the connected-component cue of the CCMSPF, on a red person changing size on grey noise."""

from dataclasses import replace

import numpy as np
import pytest

from occbench.trackers.comparators import (
    ConnectedComponentMeanShiftPF,
    MeanShiftTracker,
    ScaleAdaptiveMeanShift,
)
from occbench.trackers.comparators.ccmspf import CCMSPF_SAMPLING, Cues, component_dice, components
from occbench.trackers.comparators.meanshift import ScaleTest
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import Detections

W, H = 200, 160


def _scene(start: float, end: float, n: int = 50, speed: int = 2):
    """A red person of width start -> end (height twice that) walking right at ``speed``
    pixels a frame: frames (BGR),
    true boxes and foreground masks."""
    rng = np.random.default_rng(0)
    frames, boxes, masks = [], [], []
    for t in range(n):
        w = int(round(start + (end - start) * t / (n - 1)))
        x, y = 30 + speed * t, 80 - w
        img = rng.integers(90, 110, (H, W, 3), dtype=np.uint8)
        img[y:y + 2 * w, x:x + w] = (30, 30, 200)
        mask = np.zeros((H, W), bool)
        mask[y:y + 2 * w, x:x + w] = True
        frames.append(img)
        boxes.append(np.array([x, y, w, 2 * w], dtype=np.float64))
        masks.append(mask)
    return frames, boxes, masks


def _final_box(tracker, frames, boxes, masks=None):
    masks = masks or [None] * len(frames)
    out = tracker.update(frames[0], Detections(boxes[0][None], np.ones(1)), masks[0])
    for f, m in zip(frames[1:], masks[1:]):
        out = tracker.update(f, Detections.empty(), m)
    (track,) = out
    assert track.id == 1  # followed throughout, never lost
    return track.box


def _iou(a, b) -> float:
    return float(iou_matrix(a[None], b[None])[0, 0])


def test_scale_adaptive_mean_shift_shrinks_with_a_receding_person():
    frames, boxes, _ = _scene(24, 12)
    fixed = _final_box(MeanShiftTracker(), frames, boxes)
    scaled = _final_box(ScaleAdaptiveMeanShift(), frames, boxes)
    assert fixed[2] == 24 and _iou(fixed, boxes[-1]) < 0.3
    assert scaled[2] < 18 and _iou(scaled, boxes[-1]) > 0.5


def test_the_scale_test_keeps_the_size_on_a_tie():
    # inside a uniformly red person every size has rho = 1: h_prev wins the tie (the test
    # cannot grow a box inside a uniform target, a known limit of the method)
    frames, boxes, _ = _scene(30, 30, n=10, speed=0)
    inner = boxes[0] + [5, 10, -10, -20]
    box = _final_box(ScaleAdaptiveMeanShift(), frames, [inner] + boxes[1:])
    assert box[2:].tolist() == inner[2:].tolist()


def test_smoothing_weight_zero_is_fixed_size_mean_shift():
    frames, boxes, _ = _scene(24, 12, n=20)
    a = _final_box(ScaleAdaptiveMeanShift(ScaleTest(gamma=0.0)), frames, boxes)
    b = _final_box(MeanShiftTracker(), frames, boxes)
    assert a.tolist() == b.tolist()


def test_ccmspf_sizes_its_box_on_the_connected_component():
    frames, boxes, masks = _scene(12, 24)
    with_components = _final_box(ConnectedComponentMeanShiftPF(cues=Cues(component_lambda=10.0)),
                                  frames, boxes, masks)
    colour_alone = _final_box(ConnectedComponentMeanShiftPF(cues=Cues(component_lambda=0.0)),
                              frames, boxes, masks)
    assert _iou(with_components, boxes[-1]) > 0.6
    assert _iou(colour_alone, boxes[-1]) < _iou(with_components, boxes[-1]) - 0.2


def test_component_dice_counts_every_fragment_a_box_touches():
    mask = np.zeros((40, 30), bool)
    mask[2:12, 10:20] = True   # a head-and-body fragment
    mask[14:30, 10:20] = True  # legs, a second component
    mask[35:40, 0:5] = True    # a speck elsewhere
    labels, areas = components(mask)
    boxes = np.array([[10, 2, 10, 28], [10, 2, 10, 10], [5, 0, 20, 40], [25, 0, 5, 5]], float)
    dice = component_dice(boxes, labels, areas)
    assert dice[0] == pytest.approx(2 * 260 / (280 + 260))  # both fragments, whole
    assert dice[1] == pytest.approx(2 * 100 / (100 + 100))  # the head fragment alone: 1
    assert dice[2] == pytest.approx(2 * 260 / (800 + 260))  # grown past them
    assert dice[3] == 0.0 and components(None) is None


def test_ccmspf_is_seeded_and_names_bad_arguments():
    frames, boxes, masks = _scene(12, 24, n=10)
    seeded = replace(CCMSPF_SAMPLING, seed=4)
    a = _final_box(ConnectedComponentMeanShiftPF(seeded), frames, boxes, masks)
    b = _final_box(ConnectedComponentMeanShiftPF(seeded), frames, boxes, masks)
    assert a.tobytes() == b.tobytes()
    with pytest.raises(ValueError, match=r"^cues\.component_lambda "):
        Cues(component_lambda=-1)
    with pytest.raises(ValueError, match=r"^scale\.step "):
        ScaleTest(step=1.5)
    with pytest.raises(TypeError, match=r"tracker.component_lambda: moved to tracker.cues"):
        ConnectedComponentMeanShiftPF(component_lambda=1.0)  # a flat key before the groups
    with pytest.raises(TypeError, match=r"tracker.gamma: moved to tracker.scale.gamma"):
        ScaleAdaptiveMeanShift(gamma=0.0)
