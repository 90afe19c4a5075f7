"""Reta's parameter groups and the rules an adaptation switches (occbench.trackers.three_hypothesis
params and rules): hand-derivable cases, the paper's rule beside ours."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from occbench.trackers.common.measured_velocity import FilterPrediction, MeasuredVelocity
from occbench.trackers.three_hypothesis import Adaptations, Appearance, MotionModel, RetaTracker
from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer, Histogram
from occbench.trackers.three_hypothesis.rules import (
    AbsoluteAppearance,
    AllPixels,
    AppearanceAtContact,
    AppearanceMargin,
    BlendVisible,
    EstimateShape,
    FixedGate,
    ForegroundPixels,
    ForegroundPresence,
    ForegroundSupport,
    KalmanGate,
    KeepAppearance,
    NoPresence,
    NoSupport,
    PredictionShape,
    RegionAtContact,
    ReportRule,
    build_rules,
)


def test_paper_mode_picks_the_papers_rule_at_every_step():
    h = EllipseHistogrammer()
    paper = build_rules(Adaptations.paper(), h)
    assert isinstance(paper.pixels, AllPixels) and isinstance(paper.gate, FixedGate)
    assert isinstance(paper.stage1_appearance, AbsoluteAppearance)
    assert isinstance(paper.appearance_behind, KeepAppearance)
    assert isinstance(paper.shape_behind, PredictionShape)
    assert isinstance(paper.support, NoSupport) and isinstance(paper.presence, NoPresence)
    assert paper.report == ReportRule(1_000_000, 0.0)
    assert isinstance(paper.velocity, FilterPrediction)
    ours = build_rules(Adaptations(), h)
    assert isinstance(ours.pixels, ForegroundPixels) and ours.gate == KalmanGate(3.0)
    assert isinstance(ours.stage1_appearance, AppearanceMargin)
    assert isinstance(ours.appearance_behind, BlendVisible)
    assert isinstance(ours.shape_behind, EstimateShape)
    assert ours.support == ForegroundSupport(h) and ours.report == ReportRule(4, 3.0, memory=1.0)
    assert ours.presence == ForegroundPresence(h)
    assert isinstance(ours.velocity, MeasuredVelocity)
    built = RetaTracker(adaptations=Adaptations.paper()).rules
    assert [type(r) for r in built] == [type(r) for r in paper] and built.report == paper.report


def test_gate_radius_is_sigmas_times_the_larger_centre_std():
    P = np.zeros((2, 8, 8))
    P[0, 0, 0], P[0, 1, 1] = 9.0, 16.0  # var xc 9, yc 16: the larger is 16
    P[1, 0, 0], P[1, 1, 1] = 25.0, 4.0
    R = np.array([9.0, 0.0])  # + R[0, 0]: 16 + 9 = 25 -> std 5; 25 + 0 -> std 5
    np.testing.assert_allclose(KalmanGate(3.0).radii(P, R), [15.0, 15.0])
    assert FixedGate().radii(P, R) is None  # mu_g for every node
    assert KalmanGate(3.0).radii(np.zeros((0, 8, 8)), np.zeros(0)) is None


def test_appearance_margin_is_rho_over_the_best_rival_of_row_and_column():
    rho = np.array([[0.9, 0.6, 0.2],
                    [0.7, 0.8, 0.0],
                    [0.0, 0.0, 0.5]])
    admissible = rho > 0
    admissible[0, 2] = False  # not a stage-1 pair: no rival, no evidence
    a = AppearanceMargin().evidence(rho, admissible)
    np.testing.assert_allclose(a, [[0.2, 0.0, 0.0],   # 0.9 - max(0.7 column, 0.6 row)
                                   [0.0, 0.1, 0.0],   # 0.8 - max(0.6, 0.7)
                                   [0.0, 0.0, 0.5]])  # alone in row and column: rho kept
    assert AbsoluteAppearance().evidence(rho, admissible) is rho
    np.testing.assert_allclose(AppearanceMargin().evidence(rho[:1, :1], admissible[:1, :1]),
                               [[0.9]])  # one person, one measurement


@pytest.mark.parametrize("margin", [False, True])
def test_a_merged_measurement_at_a_contact_goes_to_the_region_not_the_colours(margin):
    """Two people in O meet one measurement: person 0's colours fit it better (rho 0.95
    against 0.7), person 1's predicted region better (delta 0.98 against 0.80). The paper
    gives it to person 0; ``contact_region`` to person 1, and to person 0 again when the two
    are not in O."""
    from occbench.trackers.three_hypothesis.association import associate

    sqrt_q = np.array([[0.95, np.sqrt(1 - 0.95**2)], [0.7, np.sqrt(1 - 0.7**2)]])
    sqrt_p = np.array([[1.0, 0.0]])
    boxes = np.array([[100.0, 50, 20, 60], [104.0, 50, 20, 60]])
    delta = np.array([[0.80], [0.98]])
    owners = np.array([0, 1])
    appearance = (AppearanceMargin() if margin else AbsoluteAppearance()).evidence

    def taker(rule, pairs):
        m = associate(boxes, owners, sqrt_q, boxes[1:], sqrt_p, 0.5, 50.0, delta=delta,
                      evidence=rule.evidence(appearance, pairs, owners))
        return m.matches[:, 0].tolist()

    in_o = np.array([[0, 1]])
    assert taker(AppearanceAtContact(), in_o) == [0]
    assert taker(RegionAtContact(), in_o) == [1]
    assert taker(RegionAtContact(), np.zeros((0, 2), dtype=int)) == [0]
    assert isinstance(build_rules(Adaptations.paper(), EllipseHistogrammer()).contact,
                      AppearanceAtContact)
    assert isinstance(build_rules(Adaptations(contact_region=True), EllipseHistogrammer())
                      .contact, RegionAtContact)
    assert "contact_region" in Adaptations(contact_region=True).changed()


def test_appearance_behind_others_kept_or_blended_by_the_visible_share():
    q, p = Histogram.of(np.array([1.0, 0.0])), Histogram.of(np.array([0.0, 1.0]))
    assert KeepAppearance().update(q, p, 0.75) is q
    np.testing.assert_allclose(BlendVisible().update(q, p, 0.25).dense(), [0.75, 0.25])
    np.testing.assert_array_equal(BlendVisible().update(q, p, 1.0).dense(), p.dense())
    assert BlendVisible().update(q, p, 0.0) is q  # fully hidden: as the paper


def test_shape_behind_others_is_the_prediction_or_the_estimate():
    pred = np.array([10.0, 20.0, 30.0, 60.0])
    got = PredictionShape().region([0.0, 0.0, 1.0, 1.0], pred)
    np.testing.assert_array_equal(got, pred)
    assert got is not pred  # a copy: the prediction array stays the frame's
    np.testing.assert_array_equal(EstimateShape().region([1.0, 2.0, 3.0, 4.0], pred), [1, 2, 3, 4])


def test_a_region_with_too_little_foreground_is_seen_empty():
    fg = np.zeros((40, 40), bool)
    fg[:, :20] = True
    boxes = np.array([[0.0, 0.0, 20.0, 40.0], [20.0, 0.0, 20.0, 40.0]])
    support = ForegroundSupport(EllipseHistogrammer(min_foreground=0.2))
    np.testing.assert_array_equal(support.empty(fg, boxes), [False, True])
    assert support.empty(None, boxes) is None  # no mask: nothing is seen empty
    assert NoSupport().empty(fg, boxes) is None
    assert ForegroundPixels().mask(fg) is fg and AllPixels().mask(fg) is None


def test_a_region_on_foreground_is_held_against_a_missing_detection():
    """``foreground_presence`` measures the foreground itself when the support rule is off
    (its ``empty`` None), so a region on bare floor is still contradicted."""
    fg = np.zeros((40, 40), bool)
    fg[:, :20] = True
    boxes = np.array([[0.0, 0.0, 20.0, 40.0], [20.0, 0.0, 20.0, 40.0]])
    presence = ForegroundPresence(EllipseHistogrammer(min_foreground=0.2))
    np.testing.assert_array_equal(presence.held(fg, boxes, None), [True, False])
    np.testing.assert_array_equal(presence.held(fg, boxes, np.array([True, True])),
                                  [False, False])  # the support rule's verdict is reused
    assert presence.held(None, boxes, None) is None  # no mask: every frame counts
    assert NoPresence().held(fg, boxes, None) is None


def test_report_rule_bounds_time_in_plain_view_and_spread():
    P = np.diag([4.0, 4.0] + [1.0] * 6)  # centre std 2 px
    x = np.array([0, 0, 1.0, 2.0, 0, 0, 0, 0])  # 1 px wide: std = 2 widths

    def hyp(covered=True, exposed=0, unseen=False, share=1.0):
        return SimpleNamespace(covered=covered, exposed=exposed, unseen=unseen, share=share,
                               x=x, P=P)

    rule = ReportRule(exposed=4, spread=3.0)
    assert rule.reported(hyp()) and rule.reported(hyp(covered=False, exposed=4))
    assert not rule.reported(hyp(covered=False, exposed=5))
    assert not rule.reported(hyp(unseen=True))
    assert not ReportRule(exposed=4, spread=1.5).reported(hyp())  # 2 widths > 1.5
    assert ReportRule(exposed=4, spread=0.0).reported(hyp())  # 0: however uncertain
    # report_support: the ellipse's foreground share, measured only when asked for
    assert not ReportRule(4, 3.0, 0.4).reported(hyp(share=0.3))
    assert ReportRule(4, 3.0, 0.4).reported(hyp(share=0.4)) and rule.reported(hyp(share=0.0))
    assert rule.shares(None, np.ones((4, 4), bool), np.zeros((1, 4))) is None
    # report_memory: one nobody covers, while misses <= memory x hits (norfair's hit counter)
    young = ReportRule(4, 3.0, memory=0.5)
    assert young.reported(hyp(covered=False), hits=4, misses=2)
    assert not young.reported(hyp(covered=False), hits=4, misses=3)  # 3 > 0.5 x 4
    assert young.reported(hyp(covered=True), hits=4, misses=30)  # behind a visible person
    assert rule.reported(hyp(covered=False), hits=1, misses=4)  # 0: however young


@pytest.mark.parametrize("group,kwargs,name", [
    (Adaptations, {"gate_sigmas": -1.0}, "adaptations.gate_sigmas"),
    (Adaptations, {"report_spread": float("nan")}, "adaptations.report_spread"),
    (Adaptations, {"tentative_misses": -1}, "adaptations.tentative_misses"),
    (Adaptations, {"max_hidden": 0}, "adaptations.max_hidden"),
    (Appearance, {"bins": 15}, "appearance.bins"),
    (Appearance, {"min_foreground": 1.5}, "appearance.min_foreground"),
    (Appearance, {"pixel_stride": 0}, "appearance.pixel_stride"),
    (MotionModel, {"velocity_noise": 0.0}, "motion.velocity_noise"),
])
def test_each_group_names_its_bad_field(group, kwargs, name):
    with pytest.raises(ValueError, match=name.replace(".", r"\.")):
        group(**kwargs)


def test_groups_are_frozen_and_paper_mode_changes_nothing_else():
    a = Adaptations()
    with pytest.raises(AttributeError):
        a.gate_sigmas = 0.0
    assert Adaptations(gate_sigmas=3).gate_sigmas == 3.0 and Adaptations.paper().changed() == []
    assert Adaptations(gate_sigmas=0.0, blend_visible=False).changed() == [
        "shape_estimate", "foreground_histograms", "foreground_support", "report_exposed",
        "report_spread", "tentative_misses", "max_hidden", "appearance_margin",
        "measured_velocity", "foreground_presence", "tentative_stage1_only",
        "inherit_hidden_id", "merge_duplicates", "correct_behind", "filter_size",
        "early_confirm", "report_memory", "merged_appearance", "measured_hypothesis",
        "measured_hypothesis_sigmas", "split_appearance", "split_appearance_margin",
        "split_appearance_parted", "measured_step"]
