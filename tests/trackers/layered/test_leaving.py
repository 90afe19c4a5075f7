"""``adaptations.leaving_unreported`` (``exits.LeavingUnreported``): an unfound target
walking out at an image border is not reported; off (``exits.ReportAnywhere``), the other
reporting rules alone decide."""

from __future__ import annotations

import numpy as np

from occbench.config.build import build_tracker, compose_config
from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.exits import LeavingUnreported, ReportAnywhere
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.records import Detections, TrackState


def test_near_a_border_and_moving_out_is_unreported():
    # 480 x 360 (PETS): unfound boxes at the right edge moving right, at the right edge
    # moving left (coming in), 5 px from the left edge moving left (a quarter of its width),
    # in the middle moving left; and a found box at the right edge moving right
    boxes = np.array([[461.0, 149, 20, 57], [461, 149, 20, 57], [5, 108, 20, 42],
                      [200, 100, 20, 50], [461, 149, 20, 57]])
    v = np.array([[2.0, 0], [-2, 0], [-2, 0], [-2, 0], [2, 0]])
    found = np.array([False, False, False, False, True])
    assert LeavingUnreported(0.0).shown(boxes, v, found, 480, 360, None).tolist() == [
        False, True, True, True, True]
    assert LeavingUnreported(0.5).shown(boxes, v, found, 480, 360, None).tolist() == [
        False, True, False, True, True]
    keep = np.array([True, True, False, True, True])  # another reporting rule's choice stays
    assert LeavingUnreported(0.5).shown(boxes, v, found, 480, 360, keep).tolist() == [
        False, True, False, True, True]
    assert ReportAnywhere().shown(boxes, v, found, 480, 360, None) is None


def _walk_out(leaving: float) -> list[tuple[int, TrackState]]:
    """A person (a 12 x 40 box of colour) walking right at 4 px per frame and detected
    until its box touches the right edge of a 160 x 120 image; pbm's reports per frame."""
    cfg = compose_config(["tracker=pbm", f"tracker.adaptations.leaving_unreported={leaving}"])
    tracker = build_tracker("pbm", cfg.tracker)
    out = []
    for k in range(40):
        x = 100 + 4 * k
        frame = np.full((120, 160, 3), 90, dtype=np.uint8)
        frame[40:80, max(x, 0):min(x + 12, 160)] = (30, 60, 200)
        box = np.array([[x, 40.0, 12, 40]]) if x + 12 <= 160 else np.zeros((0, 4))
        dets = Detections(box, np.ones(len(box)))
        out += [(k, t.state) for t in tracker.update(frame, dets) if t.state.reported]
    return out


def test_a_person_walking_out_is_not_reported_after_the_last_detection():
    off, on = _walk_out(-1.0), _walk_out(0.0)
    last = max(k for k, s in off if s != TrackState.OCCLUDED)  # the last found frame
    assert [k for k, s in off if k > last]  # off: reported hidden past the edge
    assert [k for k, _ in on if k > last] == []
    assert [x for x in on if x[0] <= last] == [x for x in off if x[0] <= last]


def test_paper_mode_reports_anywhere():
    assert isinstance(build_rules(Adaptations.paper()).leaving, ReportAnywhere)
    assert isinstance(build_rules(Adaptations()).leaving, ReportAnywhere)  # off until measured
    on = Adaptations(leaving_unreported=0.5)
    assert isinstance(build_rules(on).leaving, LeavingUnreported)
    assert "leaving_unreported" in on.changed() and Adaptations.paper().changed() == []
