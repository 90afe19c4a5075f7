"""The Kalman noises estimated from the measurements (trackers.common.noise): the compiled
bank of filters against filterpy, recovery of known noises, and reta's switch."""

from __future__ import annotations

import numpy as np
import pytest

from trackers.common.kalman import box_measurement, constant_velocity_box_filter
from trackers.common.noise import LEVELS, ConfiguredNoise, EstimatedNoise, KalmanNoiseML
from trackers.three_hypothesis import Adaptations, MotionModel, RetaTracker
from trackers.three_hypothesis.appearance import EllipseHistogrammer
from trackers.three_hypothesis.rules import build_rules


def _track(rng, sigmas, frames=120, miss=0.3, height=80.0):
    """(frames, (N, 4) xywh boxes) of one person under the height-scaled constant-velocity
    model with noise stds ``sigmas`` = (sigma_p, sigma_v, sigma_z) per 10 px of height,
    every measurement missed with probability ``miss``."""
    sp, sv, sz = (s * height / 10 for s in sigmas)
    x = np.array([rng.uniform(50, 500), rng.uniform(50, 300), height * 0.4, height])
    v = np.concatenate([rng.normal(0, 2, 2), [0.0, 0.0]])
    kept, boxes = [], []
    for t in range(frames):
        x = x + v + rng.normal(0, sp, 4)
        v = v + rng.normal(0, sv, 4)
        if t == 0 or rng.random() >= miss:
            z = x + rng.normal(0, sz, 4)  # (xc, yc, w, h)
            kept.append(t)
            boxes.append([z[0] - z[2] / 2, z[1] - z[3] / 2, z[2], z[3]])
    return np.array(kept), np.array(boxes)


def _feed(est, tracks):
    """Every track's measurements into ``est``, frame by frame (keys = track index)."""
    for t in range(max(f[-1] for f, _ in tracks) + 1):
        keys = [k for k, (f, _) in enumerate(tracks) if t in f]
        boxes = np.array([b[list(f).index(t)] for f, b in (tracks[k] for k in keys)])
        est.measure(t, keys, boxes.reshape(-1, 4))


def test_bank_likelihood_equals_filterpy():
    """Each candidate's summed innovation log-likelihood is filterpy's, for the track's third
    measurement on, across missed frames (predicted through)."""
    rng = np.random.default_rng(0)
    frames, boxes = _track(rng, (0.3, 0.05, 0.5), frames=40)
    prior = (0.5, 0.05, 0.7)
    est = KalmanNoiseML(prior, levels=(0.3,))
    _feed(est, [(frames, boxes)])
    for sigmas, ll in zip(est.candidates, est.loglik):
        kf = constant_velocity_box_filter(boxes[0], position_noise=sigmas[0],
                                          velocity_noise=sigmas[1], measurement_noise=sigmas[2])
        total, last = 0.0, frames[0]
        for n, (t, b) in enumerate(zip(frames[1:], boxes[1:]), start=1):
            for _ in range(t - last):
                kf.predict()
            kf.update(box_measurement(b))
            last = t
            if n >= 2:
                total += kf.log_likelihood
        # the bank works in units of the first height / 10: log det S differs by 4 log(c^2)
        c2 = (boxes[0, 3] / 10) ** 2
        assert ll == pytest.approx(total + 0.5 * 4 * np.log(c2) * est.innovations, rel=1e-9)
    assert est.innovations == len(frames) - 2


@pytest.mark.parametrize("truth", [(1 / 9, 1 / 27, 1 / 3), (1 / 27, 1 / 81, 3.0)])
def test_recovers_known_noises_small_and_large(truth):
    """Twelve people with known Q and R (on the grid): the estimate is the truth, R exactly,
    Q within one grid step (a small sigma_p under a large R is barely observable); with a
    large R it stays large."""
    rng = np.random.default_rng(1)
    tracks = [_track(rng, truth, height=rng.uniform(60, 160)) for _ in range(12)]
    est = KalmanNoiseML((1.0, 0.1, 1.0))
    _feed(est, tracks)
    sp, sv, sz = est.estimate()
    assert sz == pytest.approx(truth[2])
    for got, true in ((sp, truth[0]), (sv, truth[1])):
        assert true / 3.01 < got < true * 3.01
    if truth[2] < 1:
        assert (sp, sv) == pytest.approx(truth[:2])


def test_the_prior_stands_until_the_data_beat_it():
    """A few measurements do not move the configured noises; the prior is not on the grid."""
    rng = np.random.default_rng(2)
    frames, boxes = _track(rng, (1 / 9, 1 / 27, 1 / 3), frames=6, miss=0.0)
    est = KalmanNoiseML((0.5, 0.1, 0.5))
    _feed(est, [(frames, boxes)])
    assert est.innovations == 4 and est.estimate() == (0.5, 0.1, 0.5)
    assert not any(np.allclose(c, (0.5, 0.1, 0.5)) for c in est.candidates[:-1])
    assert len(est.candidates) == len(LEVELS) ** 3 + 1


def test_forget_frees_a_tracks_bank_and_a_new_track_starts_afresh():
    est = KalmanNoiseML((1.0, 0.1, 1.0))
    box = np.array([[10.0, 10.0, 20.0, 50.0]])
    for t in range(4):
        est.measure(t, [7], box + t)
    assert est.innovations == 2
    est.forget(set())
    est.measure(10, [7], box)  # a first measurement again: nothing counted
    est.measure(11, [8], box)
    assert est.innovations == 2
    with pytest.raises(ValueError, match="frame 11 of track 8"):
        est.measure(11, [8], box)


def test_bad_arguments_name_the_argument():
    with pytest.raises(ValueError, match="prior"):
        KalmanNoiseML((1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="significance"):
        KalmanNoiseML((1.0, 0.1, 1.0), significance=1.0)
    with pytest.raises(ValueError, match="levels"):
        KalmanNoiseML((1.0, 0.1, 1.0), levels=())


def test_reta_switch_estimates_small_noises_from_exact_detections():
    """``adaptations.noise_estimate``: on exact detections of people walking straight, reta's
    M ends with noises far below the configured ones; off (paper), nothing is estimated."""
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).noise, ConfiguredNoise)
    assert isinstance(build_rules(Adaptations(noise_estimate=True), h).noise, EstimatedNoise)
    from trackers.records import Detections

    tracker = RetaTracker(adaptations=Adaptations(noise_estimate=True))
    img = np.full((240, 320, 3), 90, np.uint8)
    for t in range(60):
        boxes = np.array([[20 + 2.0 * t, 40.0, 30.0, 80.0], [250 - 1.5 * t, 120.0, 30.0, 80.0]])
        tracker.update(img, Detections(boxes, np.ones(2)))
    sp, sv, sz = (tracker._motion.position_noise, tracker._motion.velocity_noise,
                  tracker._motion.measurement_noise)
    assert max(sp, sv, sz) < 0.1 and tracker._motion != MotionModel()
    person = tracker._persons[0]
    np.testing.assert_allclose(person.R, np.eye(4) * (sz * person.scale) ** 2)
    tracker.reset()
    assert tracker._motion == MotionModel() and tracker.rules.noise.ml.innovations == 0
