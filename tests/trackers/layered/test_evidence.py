"""``adaptations.hidden_evidence`` (``evidence.HiddenEvidence``): with a foreground mask, an
unfound target is shown only while foreground, a nearer found target over it, or its memory
explains it."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered import Adaptations, HiddenEvidence, PBMTracker
from occbench.trackers.layered.evidence import box_foreground, covered_from_front
from occbench.trackers.records import Detections, TrackState


def test_each_piece_of_evidence_alone_shows_a_hidden_target():
    rule = HiddenEvidence(foreground=0.6, cover=0.3, memory=0.2)
    fg = np.zeros((100, 100), dtype=bool)
    fg[0:40, 0:10] = True
    boxes = np.array([[0.0, 0, 10, 40],    # 0: on its own foreground, unfound 4 of 10 hits
                      [50.0, 0, 10, 40],   # 1: found (a nearer person, bottom at 45)
                      [52.0, 0, 10, 30],   # 2: behind 1 (bottom 30 < 45), unfound
                      [52.0, 20, 10, 40],  # 3: in front of 1 (bottom 60), unfound
                      [80.0, 50, 10, 40],  # 4: bare floor, unfound 2 of 10 hits
                      [80.0, 50, 10, 40]])  # 5: the same, unfound 3 of 10 hits
    boxes[1, 3] = 45.0
    hits = np.full(6, 10)
    misses = np.array([4, 0, 4, 4, 2, 3])
    assert rule.shown(boxes, fg, hits, misses).tolist() == [True, True, True, False, True, False]
    # without a mask: no evidence to weigh, every unfound target shown (as the rule off)
    assert rule.shown(boxes, None, hits, misses) is None
    # each piece switched off by a value that never holds
    never = HiddenEvidence(foreground=2.0, cover=2.0, memory=0.0)
    assert never.shown(boxes, fg, hits, misses).tolist() == [False, True, False, False, False,
                                                             False]


def test_geometry_of_the_evidence():
    fg = np.zeros((10, 10), dtype=bool)
    fg[:, :5] = True
    np.testing.assert_allclose(box_foreground(np.array([[0.0, 0, 10, 10], [20.0, 0, 5, 5]]), fg),
                               [0.5, 0.0])
    a = np.array([[0.0, 0, 10, 10]])
    front = np.array([[5.0, 5, 10, 10], [5.0, -5, 10, 10]])  # nearer (bottom 15), farther (5)
    np.testing.assert_allclose(covered_from_front(a, front), [[0.25, 0.0]])


def test_bad_values_are_named():
    with pytest.raises(ValueError, match="hidden_evidence.memory"):
        HiddenEvidence(memory=-1.0)
    with pytest.raises(ValueError, match="report_support and adaptations.hidden_evidence"):
        Adaptations(report_support=0.6, hidden_evidence=HiddenEvidence())
    with pytest.raises(ValueError, match="hidden_evidence must be"):
        Adaptations(hidden_evidence=0.5)
    assert Adaptations.paper().hidden_evidence is None


def _vanish(rule: HiddenEvidence | None, detected: int, mask_after: bool) -> list[int]:
    """A person walking right 3 px a frame, detected for ``detected`` frames, then gone
    from the detections (and from the mask unless ``mask_after``): the frames after at
    which pbm still reports it (hidden, or found by its blob when the mask is left on)."""
    tracker = PBMTracker(adaptations=Adaptations(hidden_evidence=rule))
    background = np.random.default_rng(0).integers(60, 120, (240, 320, 3), dtype=np.uint8)
    shown = []
    for k in range(detected + 6):
        box = np.array([40.0 + 3 * min(k, detected), 60.0, 30.0, 90.0])
        frame = background.copy()
        x, y, w, h = box.astype(int)
        fg = np.zeros((240, 320), dtype=bool)
        if k < detected:
            frame[y:y + h // 7, x:x + w] = (40, 80, 200)
            frame[y + h // 7:y + h, x:x + w] = (200, 60, 40)
        if k < detected or mask_after:
            fg[y:y + h, x:x + w] = True
        dets = Detections(box[None], np.ones(1)) if k < detected else Detections.empty()
        tracks = tracker.update(frame, dets, fg)
        if k >= detected:
            # (with the mask left on, its blob may find it)
            assert mask_after or all(t.state == TrackState.OCCLUDED for t in tracks)
            if tracks:
                shown.append(k - detected + 1)
    return shown


def test_a_briefly_tracked_target_on_bare_floor_is_dropped_from_the_report():
    rule = HiddenEvidence(foreground=0.6, cover=0.3, memory=0.2)
    assert _vanish(None, 12, False) == [1, 2, 3, 4, 5]  # off: reporting.max_misses frames
    assert _vanish(rule, 12, False) == [1, 2]  # 12 matches x 0.2: 2 frames of belief
    assert _vanish(rule, 30, False) == [1, 2, 3, 4, 5]  # tracked long: believed as long
    assert _vanish(rule, 12, True) == [1, 2, 3, 4, 5, 6]  # its foreground is still there
