"""The comparators' loss and restart rules (occbench.trackers.comparators.loss) on hand-made colour
scenes: a person hidden behind a grey occluder is declared lost after k frames and the
tracker restarts from a later detection; NeverLost keeps the old single track."""

import numpy as np
import pytest

from occbench.trackers.comparators import (
    AnyDetection,
    ColourParticleFilter,
    ConnectedComponentMeanShiftPF,
    MeanShiftTracker,
    MostSimilar,
    NeverLost,
    ScaleAdaptiveMeanShift,
    SimilarityBelow,
)
from occbench.trackers.records import Detections

W, H = 200, 120
HIDDEN = range(10, 20)  # frames (0-based) on which the red person is behind the occluder


def _scene(n: int = 30):
    """A red 16x32 person walking right on grey noise, hidden behind a grey occluder on
    HIDDEN; frames (BGR), its true boxes, and its detection (None while hidden)."""
    rng = np.random.default_rng(0)
    frames, boxes, dets = [], [], []
    for t in range(n):
        img = rng.integers(90, 110, (H, W, 3), dtype=np.uint8)
        x, y = 20 + 3 * t, 40
        box = np.array([x, y, 16, 32], dtype=np.float64)
        if t not in HIDDEN:
            img[y:y + 32, x:x + 16] = (30, 30, 200)
        frames.append(img)
        boxes.append(box)
        dets.append(None if t in HIDDEN else box)
    return frames, boxes, dets


def _run(tracker, frames, dets, every_detection: bool = True):
    """Ids output per frame: started from the first detection, later detections given
    (``every_detection``) or none."""
    out = []
    for t, (f, d) in enumerate(zip(frames, dets)):
        given = d is not None and (t == 0 or every_detection)
        out.append(tracker.update(f, Detections(d[None], np.ones(1)) if given
                                  else Detections.empty()))
    return out


@pytest.mark.parametrize("make", [MeanShiftTracker, ColourParticleFilter, ScaleAdaptiveMeanShift,
                                  ConnectedComponentMeanShiftPF])
def test_a_hidden_person_is_lost_after_k_frames_and_restarted_under_a_new_id(make):
    frames, _, dets = _scene()
    out = _run(make(max_targets=1, loss=SimilarityBelow(0.8, 3)), frames, dets)
    ids = [[t.id for t in o] for o in out]
    assert ids[:HIDDEN.start + 2] == [[1]] * (HIDDEN.start + 2)  # two misses: still followed
    assert ids[HIDDEN.start + 2:HIDDEN.stop] == [[]] * (len(HIDDEN) - 2)  # the third: lost
    assert ids[HIDDEN.stop:] == [[2]] * (len(frames) - HIDDEN.stop)  # restarted on its return


@pytest.mark.parametrize("make", [MeanShiftTracker, ColourParticleFilter, ScaleAdaptiveMeanShift,
                                  ConnectedComponentMeanShiftPF])
def test_never_lost_keeps_one_track_and_loss_changes_nothing_before_it(make):
    frames, _, dets = _scene()
    kept = _run(make(max_targets=1, loss=NeverLost()), frames, dets)
    assert all([t.id for t in o] == [1] for o in kept)
    lost = _run(make(max_targets=1, loss=SimilarityBelow(0.8, 3)), frames, dets)
    for a, b in zip(kept[:HIDDEN.start + 2], lost[:HIDDEN.start + 2]):
        assert a[0].box.tobytes() == b[0].box.tobytes()  # byte for byte until the loss


def test_most_similar_restarts_only_on_the_lost_colour_and_prefers_it():
    frames, boxes, dets = _scene()
    blue = np.array([150, 70, 16, 32], dtype=np.float64)  # a blue stranger, always visible
    for img in frames:
        img[70:102, 150:166] = (200, 60, 30)
    both = [np.vstack([blue, d]) if d is not None else blue[None] for d in dets]
    for restart, first_after in ((AnyDetection(), blue), (MostSimilar(0.5), boxes[HIDDEN.stop])):
        tracker = MeanShiftTracker(max_targets=1, loss=SimilarityBelow(0.8, 3), restart=restart)
        out = [tracker.update(frames[0], Detections(dets[0][None], np.ones(1)))]
        out += [tracker.update(f, Detections(b, np.ones(len(b))))
                for f, b in zip(frames[1:], both[1:])]
        starts = {}
        for k, o in enumerate(out):
            for t in o:
                starts.setdefault(t.id, (k, t.box))
        (k, box), = [v for i, v in starts.items() if i == 2]
        # AnyDetection: the stranger, on the frame of the loss; MostSimilar: the red person
        # again, once back (the stranger's colour is below the gate meanwhile)
        assert np.array_equal(box, first_after)
        assert k == (HIDDEN.start + 2 if isinstance(restart, AnyDetection) else HIDDEN.stop)


def test_rules_name_their_bad_arguments():
    with pytest.raises(ValueError, match="threshold"):
        SimilarityBelow(threshold=1.5)
    with pytest.raises(ValueError, match="frames"):
        SimilarityBelow(frames=0)
    with pytest.raises(ValueError, match="min_similarity"):
        MostSimilar(min_similarity=-0.1)
