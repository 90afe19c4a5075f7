"""``adaptations.reported_behind`` (``evidence.ReportedBehind``): with a foreground mask, a
confirmed target unfound for longer than ``reporting.max_misses`` frames is still reported
while a found target nearer the camera covers enough of its box; off
(``evidence.MissesBound``), or without a mask, at most ``reporting.max_misses`` frames."""

from __future__ import annotations

import numpy as np

from occbench.config.build import build_tracker, compose_config
from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.evidence import MissesBound, ReportedBehind
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.records import Detections, TrackState

BACK, FRONT, LONE = [50.0, 30, 12, 40], [54.0, 36, 14, 42], [140.0, 30, 12, 40]


def _hidden_frames(cover: float, mask: bool = True) -> dict[int, list[int]]:
    """Three people standing in a 200 x 120 image: one behind another (the front one's box,
    lower in the image, covers 0.57 of his) and one alone; the back one and the lone one are
    detected and drawn until frame 9, then gone for 14 frames (the one behind wholly hidden,
    the lone one left). Per id, the frames it is reported unfound (OCCLUDED)."""
    cfg = compose_config(["tracker=pbm", f"tracker.adaptations.reported_behind={cover}"])
    tracker = build_tracker("pbm", cfg.tracker)
    out: dict[int, list[int]] = {}
    for k in range(24):
        frame = np.full((120, 200, 3), 90, dtype=np.uint8)
        people = ((BACK, (200, 40, 40)), (FRONT, (30, 60, 200)), (LONE, (40, 200, 40)))
        for (x, y, w, h), colour in people if k < 10 else people[1:2]:
            frame[int(y):int(y + h), int(x):int(x + w)] = colour
        boxes = np.array([BACK, FRONT, LONE] if k < 10 else [FRONT])
        fg = (frame != 90).any(axis=2) if mask else None
        for t in tracker.update(frame, Detections(boxes, np.ones(len(boxes))), fg):
            if t.state == TrackState.OCCLUDED:
                out.setdefault(int(t.id), []).append(k)
    return out


def test_a_person_behind_another_is_reported_while_covered():
    off, on = _hidden_frames(0.0), _hidden_frames(0.5)
    max_misses = compose_config(["tracker=pbm"]).tracker.reporting.max_misses
    behind, lone = list(range(10, 10 + max_misses)), [10, 11]  # (hidden_evidence's memory)
    assert sorted(off.values()) == sorted([behind, lone])
    assert sorted(on.values()) == sorted([list(range(10, 24)), lone])  # the one behind: all 14
    assert _hidden_frames(0.5, mask=False) == _hidden_frames(0.0, mask=False)  # stands aside


def test_paper_mode_and_default_bound_the_reports():
    assert isinstance(build_rules(Adaptations.paper()).behind, MissesBound)
    assert isinstance(build_rules(Adaptations()).behind, MissesBound)  # off until measured
    on = Adaptations(reported_behind=0.5)
    assert isinstance(build_rules(on).behind, ReportedBehind)
    assert "reported_behind" in on.changed() and Adaptations.paper().changed() == []
