"""``adaptations.camera_placement`` (``trackers.layered.placement``): an unfound target is
reported by whichever predictor (the tracker's KF1 box, its last found box moved by its
measured velocity, or unmoved) has placed the sequence's re-found targets best so far."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.common.measured_velocity import FilterPrediction
from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.placement import FILTER, MEASURED, STILL, CameraPlacement
from occbench.trackers.layered.rules import build_rules
from pbm_scenes import pace_change_hidden


def _hidden_boxes(on: bool) -> tuple[list[float], list[float]]:
    """A person walking right at 1, then 5 px a frame (``pbm_scenes.pace_change_hidden``),
    missed at frame 17 and at frames 20-21; pbm's hidden x at 20-21 and where he is."""
    return pace_change_hidden([f"tracker.adaptations.camera_placement={on}"], {17, 20, 21}, 20)


def test_the_cameras_record_places_a_hidden_person():
    on, truth = _hidden_boxes(True)
    off, _ = _hidden_boxes(False)
    assert len(on) == len(off) == 2
    assert np.allclose(on, truth)  # the re-find at 18 showed the measured pace placing best
    assert (np.abs(np.array(off) - truth) > 0.5).all()  # KF1's velocity lags the new pace


def _refind(rule: CameraPlacement, tid: int, xs: list[float], hidden_x: float,
            velocity: float, start: int) -> None:
    """Target ``tid`` found at x = xs[0], xs[1] (frames start, start + 1), hidden at
    start + 2 (the tracker's box at ``hidden_x``, KF1's velocity ``velocity``), found again
    at xs[2] (start + 3)."""
    for i, x in enumerate(xs[:2]):
        rule.found(start + i, [tid], np.array([[x, 0.0, 10, 30]]), np.zeros((1, 2)))
    rule.place(start + 2, [tid], np.array([[hidden_x, 0.0, 10, 30]]), np.array([[velocity, 0]]))
    rule.found(start + 3, [tid], np.array([[xs[2], 0.0, 10, 30]]), np.zeros((1, 2)))


def test_jittering_boxes_choose_the_last_box_unmoved():
    rule = CameraPlacement()
    assert rule.choice() == FILTER  # no record: the tracker's own box
    _refind(rule, 1, [50.0, 54.0, 50.0], 58.0, 4.0, 0)  # a standing person's jittering box
    assert rule.choice() == STILL and rule.refinds == 1
    boxes = np.array([[70.0, 0, 10, 30]])  # another target's KF1 box, drifting
    rule.found(10, [2], np.array([[60.0, 0, 10, 30]]), np.zeros((1, 2)))
    rule.place(12, [2], boxes, np.array([[5.0, 0]]))
    assert boxes[0].tolist() == [60.0, 0, 10, 30]  # reported at its last found box


def test_a_steady_walker_chooses_the_measured_velocity():
    rule = CameraPlacement()
    _refind(rule, 1, [50.0, 55.0, 65.0], 57.0, 2.0, 0)  # KF1 lags at 2 px a frame
    assert rule.choice() == MEASURED
    rule.reset()
    assert rule.choice() == FILTER and rule.refinds == 0


def test_paper_mode_and_default_keep_kf1():
    assert isinstance(build_rules(Adaptations.paper()).velocity, FilterPrediction)
    assert isinstance(build_rules(Adaptations()).velocity, FilterPrediction)  # off until earned
    on = Adaptations(camera_placement=True)
    assert isinstance(build_rules(on).velocity, CameraPlacement)
    assert "camera_placement" in on.changed() and Adaptations.paper().changed() == []
    with pytest.raises(ValueError, match="camera_placement"):
        Adaptations(camera_placement=True, measured_velocity=True)
