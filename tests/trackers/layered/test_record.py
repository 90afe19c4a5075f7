"""``adaptations.reported_by_record`` (``trackers.layered.record``): a confirmed target unfound
for longer than ``reporting.max_misses`` frames is still reported while the sequence's
resolved runs of as many misses ended found again where reported at least half the time."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.config.build import build_tracker, compose_config
from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.evidence import MissesBound
from occbench.trackers.layered.record import ReportedByRecord
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.records import Detections, TrackState

MISSED = set(range(10, 20)) | set(range(21, 33))  # two long runs of misses


def _hidden_frames(on: bool) -> list[int]:
    """A person (a 12 x 40 box of colour in a 200 x 120 image) standing still, detected but
    at frames 10-19 and 21-32; the frames of pbm's hidden (OCCLUDED) reports."""
    cfg = compose_config(["tracker=pbm", f"tracker.adaptations.reported_by_record={on}"])
    tracker = build_tracker("pbm", cfg.tracker)
    hidden = []
    for k in range(33):
        frame = np.full((120, 200, 3), 90, dtype=np.uint8)
        frame[40:80, 60:72] = (30, 60, 200)
        box = np.zeros((0, 4)) if k in MISSED else np.array([[60.0, 40, 12, 40]])
        out = tracker.update(frame, Detections(box, np.ones(len(box))))
        hidden += [k for t in out if t.state == TrackState.OCCLUDED]
    return hidden


def test_a_camera_whose_long_runs_end_where_reported_reports_them_longer():
    off, on = _hidden_frames(False), _hidden_frames(True)
    assert off == [10, 11, 12, 13, 14, 21, 22, 23, 24, 25]  # reporting.max_misses 5
    # the first run (10 frames, found again where reported) supports runs of up to 10
    assert on == [10, 11, 12, 13, 14, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30]


def test_a_run_that_ended_with_the_target_dropped_counts_against():
    rule = ReportedByRecord()
    rule._resolve(8, True)
    rule._resolve(7, False)
    rule._resolve(7, False)
    assert (rule.successes[6], rule.episodes[6]) == (1, 3)  # runs of >= 6: one of three
    assert (rule.successes[8], rule.episodes[8]) == (1, 1)
    rule.reset()
    assert rule.episodes == {} and rule.successes == {}


def test_paper_mode_and_default_report_for_max_misses():
    assert isinstance(build_rules(Adaptations.paper()).behind, MissesBound)
    assert isinstance(build_rules(Adaptations()).behind, MissesBound)  # off until earned
    on = Adaptations(reported_by_record=True)
    assert isinstance(build_rules(on).behind, ReportedByRecord)
    assert "reported_by_record" in on.changed() and Adaptations.paper().changed() == []
    with pytest.raises(ValueError, match="reported_by_record"):
        Adaptations(reported_by_record=True, reported_behind=0.8)
