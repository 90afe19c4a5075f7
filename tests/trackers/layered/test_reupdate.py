"""``adaptations.reupdate`` (``reupdate.ReUpdate``, OC-SORT's observation-centric re-update):
a target found again after a gap has KF1 and KF2 re-run over the line from its last
observation to the new one; off (``AfterPrediction``), one update after the gap's
predictions (PBM 3, eqs. 7-8)."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered import Adaptations
from occbench.trackers.layered.dynamics import Gate, cv_predicted, cv_updated
from occbench.trackers.layered.parts import PartFeatureExtractor
from occbench.trackers.layered.reupdate import AfterPrediction, ReUpdate
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.layered.targets import Targets

GAP = 5  # frames unfound


def _dof(xc: float, h: float = 90.0) -> np.ndarray:
    return np.array([[xc - 15.0, 50.0, xc, 95.0, h / 3, h]])


def _walk(rule, kf1_noise=(0.5, 0.2, 0.5), before=4.0, after=1.0, seen=None
          ) -> tuple[Targets, float]:
    """A target walks right by ``before`` px a frame for 10 frames, is unfound for GAP
    frames and found again (GAP + 1) ``after`` px per frame further on, grown by 1 px a
    frame meanwhile. Returns the targets and the observed displacement / frames; ``seen``
    (a list) gets KF1's and KF2's (x, P, z) of the last observation before the gap."""
    tg = Targets(Gate(3.0, 0.5, 2.0, 1.15, 6.0), kf1_noise, (0.2, 0.02, 0.5), 4, 3, 4)
    ex = PartFeatureExtractor(4, 14, 6)
    ex.start(np.full((240, 320, 3), 90, np.uint8), None)
    parts = ex.extract(np.array([[100.0, 50.0, 30.0, 90.0]]), np.array([0.5]), np.array([0.5]))
    xc = 115.0
    tg.add(1, _dof(xc)[0], 0.5, 0.5, parts, None)
    one = (np.ones(1, bool), np.zeros(1, bool), np.ones((1, 5)), 0.4)
    for _ in range(10):
        tg.predict()
        xc += before
        rule.update(tg, np.array([0]), _dof(xc), *one)
    for _ in range(GAP):
        tg.predict()
        build_rules(Adaptations()).unfound_size.missed(tg, np.array([0]))  # KF2 held
    tg.predict()
    if seen is not None:
        seen += [(kf.seen_x[0].copy(), _block_p(kf.seen_p[0]), kf.seen_z[0].copy())
                 for kf in (tg.kf1, tg.kf2)]
    rule.update(tg, np.array([0]), _dof(xc + after * (GAP + 1), 90.0 + GAP + 1), *one)
    return tg, after


@pytest.mark.parametrize(("before", "after"), [(4.0, 1.0), (0.0, 3.0), (-3.0, 3.0)])
def test_refound_velocity_is_the_observed_one(before, after):
    # KF1 trusting its measurements (no position noise, R ~ 0): rewound and re-run over the
    # virtual trajectory, the rate is the observed displacement / frames; one update after
    # GAP blind predictions over-corrects (the velocity's variance grew with each)
    noise = (0.0, 0.2, 0.001)
    on, seen = _walk(ReUpdate(2), noise, before, after)
    off, _ = _walk(AfterPrediction(), noise, before, after)
    assert on.kf1.x[0, 2] == pytest.approx(seen, abs=1e-3)
    assert abs(off.kf1.x[0, 2] - seen) > 0.5
    assert on.misses[0] == off.misses[0] == 0 and on.hits[0] == off.hits[0] == 12


def _block_p(p: np.ndarray) -> np.ndarray:
    """(4, 4) covariance of one filter's (2, 4) per-axis blocks (``ConstantVelocity2D``)."""
    P = np.zeros((4, 4))
    for axis, (A, B, C, D) in enumerate(p):
        P[axis, axis], P[axis, axis + 2], P[axis + 2, axis], P[axis + 2, axis + 2] = A, B, C, D
    return P


def test_re_run_is_the_filter_observed_along_the_line():
    # pbm's noise: the state after the re-find equals KF1 / KF2 rewound to just after the
    # last observation z1 and updated at each of the GAP + 1 frames with the interpolated
    # measurement (OC-SORT 3.2, eqs. 7-8 in plain numpy)
    seen = []
    on, _ = _walk(ReUpdate(1), seen=seen)
    off, _ = _walk(AfterPrediction())
    (kf1_seen, kf2_seen) = seen
    for kf, (x, P, z1), z2 in ((on.kf1, kf1_seen, np.array([161.0, 95.0])),
                               (on.kf2, kf2_seen, np.array([96.0, 32.0]))):
        g = GAP + 1
        for i in range(1, g + 1):
            x, P = cv_predicted(x, P, kf.qp[0], kf.qv[0])
            x, P = cv_updated(x, P, z1 + i / g * (z2 - z1), kf.r[0])
        np.testing.assert_allclose(kf.x[0], x, rtol=1e-9)
        np.testing.assert_allclose(_block_p(kf.p[0]), P, rtol=1e-9, atol=1e-12)
    assert not np.allclose(on.kf1.x[0], off.kf1.x[0])  # one update after the gap differs
    assert not np.allclose(on.kf2.x[0], off.kf2.x[0])


def test_a_short_gap_or_the_paper_takes_one_update():
    # a gap below min_gap is not re-run: ReUpdate(GAP + 1) equals the paper's filters
    on, _ = _walk(ReUpdate(GAP + 1))
    off, _ = _walk(AfterPrediction())
    assert np.array_equal(on.kf1.x, off.kf1.x) and np.array_equal(on.kf2.p, off.kf2.p)
    # ... and every match is remembered as the last observation (KF2's z = (h, w))
    assert on.kf2.seen_z[0].tolist() == pytest.approx([96.0, 32.0])


def test_reupdate_is_off_by_default_and_in_paper_mode_and_checked():
    assert isinstance(build_rules(Adaptations()).reupdate, AfterPrediction)
    assert isinstance(build_rules(Adaptations(reupdate=2)).reupdate, ReUpdate)
    assert build_rules(Adaptations(reupdate=2)).reupdate.min_gap == 2
    assert Adaptations.paper().reupdate == 0
    with pytest.raises(ValueError, match="reupdate"):
        Adaptations(reupdate=-1)
