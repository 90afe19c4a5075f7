"""``adaptations.measured_velocity`` (``trackers.common.measured_velocity``, reta's rule, in
pbm's reporting): an unfound target stands at its last found box moved by the displacement
of its last two found boxes per frame when that has predicted its found boxes better than
KF1's velocity so far; off, where KF1 predicts (``report_predicted``)."""

from __future__ import annotations

import numpy as np

from occbench.config.build import build_tracker, compose_config
from occbench.trackers.common.measured_velocity import FilterPrediction, MeasuredVelocity
from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.records import Detections, TrackState


def _hidden_boxes(on: bool) -> tuple[list[float], list[float]]:
    """A person (a 12 x 40 box of colour in a 200 x 120 image) walking right at 1 px a frame
    for 14 frames, then at 5 px a frame, detected until frame 20 and missed for 2 frames;
    the x of pbm's hidden (OCCLUDED) reports and where the person is."""
    cfg = compose_config(["tracker=pbm", f"tracker.adaptations.measured_velocity={on}"])
    tracker = build_tracker("pbm", cfg.tracker)
    x, hidden, truth = 20.0, [], []
    for k in range(22):
        x += 1.0 if k < 14 else 5.0
        frame = np.full((120, 200, 3), 90, dtype=np.uint8)
        frame[40:80, int(x):int(x) + 12] = (30, 60, 200)
        box = np.array([[x, 40.0, 12, 40]]) if k < 20 else np.zeros((0, 4))
        out = tracker.update(frame, Detections(box, np.ones(len(box))))
        hidden += [t.box[0] for t in out if t.state == TrackState.OCCLUDED]
        truth += [x] if k >= 20 else []
    return hidden, truth


def test_a_hidden_person_stands_where_its_own_last_steps_put_it():
    on, truth = _hidden_boxes(True)
    off, _ = _hidden_boxes(False)
    assert len(on) == len(off) == 2  # both frames of the miss reported
    assert np.allclose(on, truth)  # 5 px a frame from the last found box
    assert (np.abs(np.array(off) - truth) > 0.5).all()  # KF1's velocity still lags the new pace


def test_paper_mode_and_default_keep_kf1():
    assert isinstance(build_rules(Adaptations.paper()).velocity, FilterPrediction)
    assert isinstance(build_rules(Adaptations()).velocity, FilterPrediction)  # off until measured
    on = Adaptations(measured_velocity=True)
    assert isinstance(build_rules(on).velocity, MeasuredVelocity)
    assert "measured_velocity" in on.changed() and Adaptations.paper().changed() == []
