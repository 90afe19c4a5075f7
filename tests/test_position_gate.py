"""pbm's ``adaptations.position_gate``: a found target kept off candidates beyond a chi-square
probability of its predicted centre, under noises estimated online
(``trackers.common.noise.KalmanNoiseML.predicted``)."""

from __future__ import annotations

import numpy as np
import pytest
from pbm_scenes import Person, Scene, walk

from trackers.common.kalman import box_measurement, constant_velocity_box_filter
from trackers.common.noise import KalmanNoiseML
from trackers.layered import PBMTracker
from trackers.layered.params import Adaptations
from trackers.records import Detections


def test_predicted_centre_and_S_are_the_chosen_filters():
    """``predicted`` gives the centre and S = H P H' + R of the filter run with the noises
    ``estimate`` gives, predicted across a gap; S is inf for a track never measured."""
    rng = np.random.default_rng(2)
    est = KalmanNoiseML((0.5, 0.2, 0.5), levels=(0.05, 0.3))
    box = np.array([100.0, 50.0, 30.0, 90.0])
    frames = [0, 1, 2, 4, 5, 6, 7, 9, 10]
    boxes = [box + np.array([2.0 * t, 0.5 * t, 0, 0]) + rng.normal(0, 0.5, 4) for t in frames]
    for t, b in zip(frames, boxes):
        est.measure(t, [7], b[None])
    sp, sv, sz = est.estimate()
    kf = constant_velocity_box_filter(boxes[0], position_noise=sp, velocity_noise=sv,
                                      measurement_noise=sz)
    # the bank's filter: scale fixed at the first height, P0's velocity variance ivv
    kf.P[4:, 4:] = np.eye(4) * est.ivv * (boxes[0][3] / 10.0) ** 2
    last = frames[0]
    for t, b in zip(frames[1:], boxes[1:]):
        for _ in range(t - last):
            kf.predict()
        kf.update(box_measurement(b))
        last = t
    for _ in range(13 - last):
        kf.predict()
    mean, S = est.predicted(13, [7, 99])
    np.testing.assert_allclose(mean[0], kf.x[:2, 0], rtol=1e-9)
    np.testing.assert_allclose(S[0], kf.P[0, 0] + kf.R[0, 0], rtol=1e-9)
    assert np.isinf(S[1])


def test_position_gate_keeps_a_found_target_off_a_far_candidate():
    """A person walks alone with exact boxes; at frame 25 their detection is replaced by one
    0.4 of their width aside (inside KF1's gate rectangle). Without the gate the target
    takes it; with it (noises learnt from the frames before) the target is unfound that
    frame (the candidate left over may start a tentative target) and takes its own
    detection again afterwards, keeping its one id."""
    scene = Scene(240, 180, [Person(1, walk(32, (40, 40), (2.0, 0.5), (30, 100)),
                                    shirt=(40, 40, 200), pants=(90, 60, 30))], seed=3)
    box = scene.people[0].boxes
    out = {}
    for gate in (0.0, 0.99):
        tracker = PBMTracker(adaptations=Adaptations(position_gate=gate))
        states = []
        for k in range(scene.length):
            img, lab = scene.render(k)
            b = box[k] + (np.array([0.4 * box[k][2], 0, 0, 0]) if k == 25 else 0)
            tracks = tracker.update(img, Detections(b[None], np.ones(1)), lab)
            states.append({t.id: t.state.name for t in tracks})
        out[gate] = states
    assert out[0.0][25] == {1: "CONFIRMED"}
    assert out[0.99][25][1] == "OCCLUDED"
    assert out[0.99][24] == out[0.99][26] == out[0.99][31] == {1: "CONFIRMED"}


def test_position_gate_must_be_a_probability():
    with pytest.raises(ValueError, match="position_gate"):
        Adaptations(position_gate=1.0)
    with pytest.raises(ValueError, match="position_gate"):
        Adaptations(position_gate=-0.1)
