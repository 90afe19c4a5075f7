"""``adaptations.measured_velocity`` (``trackers.common.measured_velocity``, reta's rule, in
pbm's reporting): an unfound target stands at its last found box moved by the displacement
of its last two found boxes per frame when that has predicted its found boxes better than
KF1's velocity so far; off, where KF1 predicts (``report_predicted``)."""

from __future__ import annotations

import numpy as np

from occbench.trackers.common.measured_velocity import FilterPrediction, MeasuredVelocity
from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.rules import build_rules
from pbm_scenes import pace_change_hidden


def _hidden_boxes(on: bool) -> tuple[list[float], list[float]]:
    """A person walking right at 1, then 5 px a frame, missed at frames 20-21
    (``pbm_scenes.pace_change_hidden``); pbm's hidden x and where the person is."""
    return pace_change_hidden([f"tracker.adaptations.measured_velocity={on}"], {20, 21})


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
