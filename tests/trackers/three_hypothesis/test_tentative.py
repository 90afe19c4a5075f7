"""Reta's early confirmation (occbench.trackers.three_hypothesis.tentative) beside the paper's
reading: a hand-derivable case of which measurements are clear, and constructed scenes where a
lone person is confirmed at once and two people whose boxes meet wait ``confirm_frames``."""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_array
import pytest
from reta_scenes import RED, ellipse_frame

from occbench.trackers.records import Detections
from occbench.trackers.three_hypothesis import Adaptations, RetaTracker
from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer
from occbench.trackers.three_hypothesis.rules import build_rules
from occbench.trackers.three_hypothesis.tentative import AfterMatches, ClearEarly, clear_measurements

W, H = 240, 120


BLUE = ((200, 60, 40), (120, 60, 60))


def _states(tracker, boxes, scores=None, frames=4):
    """Per frame, the states of the tracker's outputs, people standing at ``boxes``."""
    s = np.ones(len(boxes)) if scores is None else np.asarray(scores, float)
    dets = Detections(np.array(boxes, float).reshape(-1, 4), s)
    return [sorted(t.state.name for t in tracker.update(ellipse_frame(boxes, [RED, BLUE][:len(boxes)], (W, H)), dets, None))
            for _ in range(frames)]


def test_paper_mode_confirms_after_confirm_frames():
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).confirm, AfterMatches)
    assert build_rules(Adaptations(early_confirm=1, early_confirm_score=0.5), h).confirm == \
        ClearEarly(1, 0.5)
    assert not AfterMatches().confirms(2, 3, True, 1.0) and AfterMatches().confirms(3, 3, False, 0)
    with pytest.raises(ValueError, match="adaptations.early_confirm_score"):
        Adaptations(early_confirm_score=1.5)


def test_clear_early_needs_a_clear_confident_measurement():
    rule = ClearEarly(matches=2, min_score=0.5)
    assert rule.confirms(2, 3, True, 0.9)
    assert not rule.confirms(1, 3, True, 0.9)  # too few matches
    assert not rule.confirms(2, 3, False, 0.9)  # ambiguous
    assert not rule.confirms(2, 3, True, 0.4)  # not confident
    assert rule.confirms(3, 3, False, 0.1)  # the full count always confirms


def test_clear_measurements_by_hand():
    # three boxes: 0 alone, 1 and 2 overlap each other
    dets = np.array([[0.0, 0, 10, 30], [50, 0, 10, 30], [55, 0, 10, 30]])
    # two nodes: node 0 of person 0 meets box 0; node 1 of person 1 meets nothing
    delta = csr_array(np.array([[0.7, 0.0, 0.0], [0.0, 0.0, 0.0]]))
    owners = np.array([0, 1])
    rows = np.array([0, 1])
    # row 0 is person 0's own measurement: its own node does not make it ambiguous
    assert clear_measurements(dets, rows, delta, owners, np.array([0, 1])).tolist() \
        == [True, False]
    # as a new track's measurement (every person another), box 0 meets person 0's node
    assert clear_measurements(dets, rows, delta, owners, np.array([-1, -1])).tolist() \
        == [False, False]


def test_a_lone_person_is_confirmed_at_once_with_the_rule_and_after_three_without():
    person = [[100.0, 20.0, 20.0, 60.0]]
    paper = RetaTracker(adaptations=Adaptations(early_confirm=0))
    assert _states(paper, person) == [["TENTATIVE"], ["TENTATIVE"], ["CONFIRMED"], ["CONFIRMED"]]
    early = RetaTracker()  # early_confirm 1, the default
    assert _states(early, person) == [["CONFIRMED"]] * 4
    # a detection below the score waits the full count
    unsure = RetaTracker(adaptations=Adaptations(early_confirm=1, early_confirm_score=0.8))
    assert _states(unsure, person, scores=[0.6])[:2] == [["TENTATIVE"], ["TENTATIVE"]]


def test_two_people_whose_boxes_meet_wait_the_full_count():
    pair = [[100.0, 20.0, 20.0, 60.0], [112.0, 25.0, 20.0, 60.0]]
    early = RetaTracker(adaptations=Adaptations(early_confirm=1))
    assert _states(early, pair) == [["TENTATIVE"] * 2, ["TENTATIVE"] * 2, ["CONFIRMED"] * 2,
                                    ["CONFIRMED"] * 2]

