"""PBM's comparators (mean shift, colour particle filter) on hand-made colour scenes."""

import numpy as np
import pytest

from occbench.trackers.comparators import (
    ColourParticleFilter,
    ConnectedComponentMeanShiftPF,
    MeanShiftTracker,
    ScaleAdaptiveMeanShift,
    SimilarityBelow,
)
from occbench.trackers.comparators.particle_filter import ParticleSampling
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import Detections

W, H = 200, 120


def _scene(n: int = 40) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """A red 16x32 block walking right on grey noise: frames (BGR) and its true boxes."""
    rng = np.random.default_rng(0)
    frames, boxes = [], []
    for t in range(n):
        img = rng.integers(90, 110, (H, W, 3), dtype=np.uint8)
        x, y = 20 + 3 * t, 40 + (t % 5)
        img[y:y + 32, x:x + 16] = (30, 30, 200)
        frames.append(img)
        boxes.append(np.array([x, y, 16, 32], dtype=np.float64))
    return frames, boxes


def _follow(tracker, frames, boxes):
    out = [tracker.update(frames[0], Detections(boxes[0][None], np.ones(1)))]
    out += [tracker.update(f, Detections.empty()) for f in frames[1:]]
    return out


@pytest.mark.parametrize("make", [MeanShiftTracker, ColourParticleFilter, ScaleAdaptiveMeanShift,
                                  ConnectedComponentMeanShiftPF])
def test_follows_a_coloured_person_from_its_first_box(make):
    frames, boxes = _scene()
    out = _follow(make(), frames, boxes)
    assert all(len(o) == 1 and o[0].id == 1 for o in out)
    iou = [iou_matrix(o[0].box[None], b[None])[0, 0] for o, b in zip(out, boxes)]
    assert min(iou) > 0.5


@pytest.mark.parametrize("make", [MeanShiftTracker, ColourParticleFilter, ScaleAdaptiveMeanShift,
                                  ConnectedComponentMeanShiftPF])
def test_target_ends_when_its_colour_is_gone(make):
    frames, boxes = _scene(10)
    grey = [np.full((H, W, 3), 100, np.uint8)] * 15
    out = _follow(make(loss=SimilarityBelow(0.5, 4)), frames + grey, boxes + boxes[-1:] * 15)
    assert len(out[9]) == 1 and out[-1] == []


@pytest.mark.parametrize("make", [MeanShiftTracker, ColourParticleFilter, ScaleAdaptiveMeanShift,
                                  ConnectedComponentMeanShiftPF])
def test_a_detection_where_a_target_stands_starts_nothing(make):
    frames, boxes = _scene(5)
    tracker = make()
    ids = [{t.id for t in tracker.update(f, Detections(b[None], np.ones(1)))}
           for f, b in zip(frames, boxes)]
    assert ids == [{1}] * 5


@pytest.mark.parametrize("make", [MeanShiftTracker, ColourParticleFilter, ScaleAdaptiveMeanShift,
                                  ConnectedComponentMeanShiftPF])
def test_a_single_target_tracker_starts_nothing_more(make):
    frames, boxes = _scene(3)
    far = np.array([[150, 10, 16, 32]])
    tracker = make(max_targets=1)
    out = [tracker.update(f, Detections(np.vstack([b[None], far]), np.ones(2)))
           for f, b in zip(frames, boxes)]
    assert [[t.id for t in o] for o in out] == [[1]] * 3
    assert len(make().update(frames[0], Detections(np.vstack([boxes[0][None], far]),
                                                   np.ones(2)))) == 2


def test_particle_filter_is_seeded():
    frames, boxes = _scene(15)
    a = _follow(ColourParticleFilter(ParticleSampling(seed=3)), frames, boxes)
    b = _follow(ColourParticleFilter(ParticleSampling(seed=3)), frames, boxes)
    assert all(np.array_equal(x[0].box, y[0].box) for x, y in zip(a, b))


def test_frames_are_required_and_arguments_named():
    with pytest.raises(ValueError, match="needs frames"):
        MeanShiftTracker().update(None, Detections.empty())
    with pytest.raises(ValueError, match=r"^sampling\.particles "):
        ParticleSampling(particles=0)
    with pytest.raises(TypeError, match=r"tracker.particles: moved to tracker.sampling"):
        ColourParticleFilter(particles=50)  # a flat key before the groups (issue 36)
    with pytest.raises(ValueError, match="threshold"):
        SimilarityBelow(threshold=2)
