"""PBM stale parts (an adaptation beyond PBM 4.2): a part that is visible (no other
target's box over it, inside the image, its foreground present) yet keeps failing to match
is re-learned; a hidden part stays frozen as the paper asks (the wall case is
``test_pbm.test_a_hidden_part_is_frozen_while_hidden``, run with the defaults)."""

from __future__ import annotations

import numpy as np
import pbm_scenes as S

from occbench.trackers.layered import Adaptations, PBMTracker
from occbench.trackers.layered.dynamics import Gate
from occbench.trackers.layered.parts import PartFeatureExtractor
from occbench.trackers.layered.targets import Targets, stale_parts


def _targets() -> Targets:
    return Targets(Gate(3.0, 0.5, 2.0, 1.15, 4.0), (0.5, 0.2, 0.5), (0.2, 0.02, 0.5), 4, 3, 4)


def test_only_visible_failing_parts_count_and_are_relearned():
    frame = np.full((200, 200, 3), 90, np.uint8)
    box = np.array([[50.0, 40.0, 30.0, 90.0]])
    full = np.zeros((200, 200), bool)
    full[40:130, 50:80] = True
    ex = PartFeatureExtractor(4, 35, 15)
    ex.start(frame, full)
    model = ex.extract(box, np.array([0.5]), np.array([0.5]))
    seen = full.copy()
    seen[92:130, 50:65] = False  # the left leg behind a wall: no foreground
    ex.start(frame, seen)
    cand = ex.extract(box, np.array([0.5]), np.array([0.5]))
    tg = _targets()
    tg.add(1, np.array([50.0, 40.0, 65.0, 85.0, 30.0, 90.0]), 0.5, 0.5, model, None)
    # target 2's box lies over target 1's right torso-arm (and 6% of its right leg)
    tg.add(2, np.array([66.0, 54.0, 86.0, 74.0, 40.0, 40.0]), 0.5, 0.5, model, None)
    failing = np.full((1, 5), 0.1)
    args = (0.4, 5, (200, 200), 0.1, 0.75, 3)
    for _ in range(2):
        assert not stale_parts(tg, np.array([0]), cand, np.array([0]), failing, *args).any()
    assert tg.stale[0].tolist() == [2, 2, 0, 0, 2]
    relearn = stale_parts(tg, np.array([0]), cand, np.array([0]), failing, *args)
    # head, left torso-arm and right leg visible; right torso-arm covered; left leg hidden
    assert relearn[0].tolist() == [True, True, False, False, True]
    assert tg.stale[0].tolist() == [0, 0, 0, 0, 0]
    # a matching part resets its count; the image border hides a part too
    stale_parts(tg, np.array([0]), cand, np.array([0]), failing, *args)
    stale_parts(tg, np.array([0]), cand, np.array([0]), np.array([[0.9, 0.1, 0.1, 0.1, 0.1]]),
                0.4, 5, (200, 100), 0.1, 0.75, 3)
    assert tg.stale[0].tolist() == [0, 2, 0, 0, 1]  # the right leg (y > 100) left the image


def _walk_with_a_stale_torso(tracker: PBMTracker) -> tuple[np.ndarray, list, list, np.ndarray]:
    """One person walks alone; at frame 10 the left torso-arm model is spoiled (the head's
    colours, wrong area and perimeter: a model gone stale in a crowd)."""
    a = S.walk(40, (20, 60), (3.0, 0.0), (30, 105))
    scene = S.Scene(260, 200, [S.Person(1, a, shirt=(50, 50, 200), pants=(140, 90, 20))], seed=3)
    flags, scores = [], []
    for k in range(scene.length):
        img, lab = scene.render(k)
        out = tracker.update(img, scene.detections(k, lab), lab)
        if k == 10:
            m = tracker.targets.parts
            m.hsv[0, 1], m.xyz[0, 1] = m.hsv[0, 0], m.xyz[0, 0]
            m.area[0, 1], m.perimeter[0, 1] = 0.2, m.perimeter[0, 1] + 1.0
            spoiled = m.hsv[0, 1].copy()
        elif k > 10:
            flags.append(bool(out[0].extra["occluded_parts"][1]))
            scores.append(float(out[0].extra["part_scores"][1]))
    return spoiled, flags, scores, tracker.targets.parts.hsv[0, 1]


def test_a_stale_visible_part_is_relearned():
    # the paper's rule: the spoiled part never matches again, so it is never updated again
    spoiled, flags, scores, hsv = _walk_with_a_stale_torso(PBMTracker(adaptations=Adaptations(stale=None)))
    assert all(flags) and max(scores) < 0.4
    np.testing.assert_array_equal(hsv, spoiled)
    # stale parts: re-learned after 3 visible failures, then it matches every frame
    spoiled, flags, scores, hsv = _walk_with_a_stale_torso(PBMTracker())
    assert flags[:2] == [True, True] and not any(flags[3:])
    assert min(scores[3:]) >= 0.4
    assert np.abs(hsv - spoiled).sum() > 0.5
