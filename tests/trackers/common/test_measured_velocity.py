"""Where reta reports a hidden person (``adaptations.measured_velocity``): its last measured
box moved by its measured velocity when that velocity has predicted its measurements better
than the tracker's filter, else the filter's prediction."""

from __future__ import annotations

import numpy as np
import pbm_scenes as S

from occbench.trackers.common.measured_velocity import MeasuredVelocity
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import TrackState
from occbench.trackers.three_hypothesis import Adaptations as RetaAdaptations
from occbench.trackers.three_hypothesis import RetaTracker


def test_the_predictor_with_the_smaller_error_places_the_hidden_box():
    rule = MeasuredVelocity()
    # steady walk at 6 px/frame, a filter lagging at 2 px/frame: the measured velocity wins
    for k in range(1, 5):
        rule.found(k, [1], np.array([[6.0 * k, 0, 20, 50]]), np.array([[2.0, 0.0]]))
    box = np.array([[24.0, 0, 20, 50]])
    rule.place(6, [1], box)
    np.testing.assert_allclose(box, [[36.0, 0, 20, 50]])
    # a person standing still with jittering boxes, a filter at rest: the filter's box stays
    for k in range(1, 6):
        rule.found(k, [2], np.array([[100.0 + (8 if k % 2 else -8), 0, 20, 50]]),
                   np.zeros((1, 2)))
    box = np.array([[100.0, 0, 20, 50]])
    rule.place(7, [2], box)
    np.testing.assert_allclose(box, [[100.0, 0, 20, 50]])
    rule.forget({2})
    box = np.array([[0.0, 0, 20, 50]])
    rule.place(6, [1], box)  # forgotten: nothing to place it by
    np.testing.assert_allclose(box, [[0.0, 0, 20, 50]])


def _hidden_iou(tracker) -> list[float]:
    """A person walks at 2 px/frame, then at 7 from frame 12 (exact boxes, no foreground),
    its detection missed on frames 20-23: IoU with the truth of each box the tracker
    reports for it while hidden (its filter still lags behind the new speed)."""
    slow = S.walk(12, (20, 60), (2.0, 0.0), (30, 105))
    fast = S.walk(14, (slow[-1][0] + 7, 60), (7.0, 0.0), (30, 105))
    scene = S.Scene(320, 240, [S.Person(1, np.vstack([slow, fast]), shirt=(40, 40, 200),
                                        pants=(90, 60, 30))], seed=3)
    ious = []
    for k in range(scene.length):
        img, lab = scene.render(k)
        det = scene.detections(k, lab, hidden={1} if 20 <= k <= 23 else None)
        for t in tracker.update(img, det, None):
            if t.state == TrackState.OCCLUDED:
                ious.append(float(iou_matrix(t.box[None], scene.gt(k)[1][None])[0, 0]))
    return ious


def test_reta_reports_a_hidden_walker_closer_to_the_truth_with_its_measured_velocity():
    # measured_step off in both: with it, hypothesis 1 itself takes the walker's last step
    # and the filter's box is already the truth's (the two rules meet the same lag)
    off = _hidden_iou(RetaTracker(adaptations=RetaAdaptations(measured_velocity=False,
                                                             measured_step=False)))
    on = _hidden_iou(RetaTracker(adaptations=RetaAdaptations(measured_step=False)))
    assert len(on) == len(off) >= 3
    assert np.mean(on) > np.mean(off) + 0.02
    assert min(on) > 0.9  # exact boxes, steady new speed: the measured velocity is the truth's
