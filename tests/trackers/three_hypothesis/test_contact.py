"""Reta's rules for people in contact (occbench.trackers.three_hypothesis.contact): a
measurement merged over two tracked people, a measurement across people already measured;
hand-derivable cases, the paper's rule beside ours."""

from __future__ import annotations

import cv2
import pytest
import numpy as np
from scipy.sparse import csr_array

from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import Detections
from occbench.trackers.three_hypothesis import Adaptations, RetaTracker
from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer, Histogram
from occbench.trackers.three_hypothesis.contact import (
    AnyCover,
    AnyLeftover,
    AppearanceAtContact,
    AppearanceAtSplit,
    MeasurementAppearance,
    MeasurementMotion,
    MergedAppearance,
    MergedMotion,
    NearerCover,
    RegionAtContact,
    RegionAtSplit,
    SplitParts,
    UnmixedAppearance,
    VisibleRegion,
    WholeRegion,
    own_shares,
)
from occbench.trackers.three_hypothesis.occlusion import union_cover
from occbench.trackers.three_hypothesis.rules import AppearanceMargin, build_rules
from occbench.trackers.three_hypothesis.values import Match

BOX = np.array([[0.0, 0.0, 10.0, 20.0]])


def test_own_share_is_the_measured_region_no_hidden_partner_covers():
    """Person 0 matched to measurement 0 through node 0; node 1 (person 1) in O with it.
    Same sizes: delta 1 (person 1 wholly inside) leaves 0 of the region to person 0, delta
    0.5 half of it; matched, or not in O, person 1 leaves all of it."""
    pred = np.concatenate([BOX, BOX])
    owners, pairs = np.array([0, 1]), np.array([[0, 1]])
    rows = [Match(det=0, node=0, stage=1, rho=1.0)]
    hidden = np.array([False, True])
    for delta, own in ((1.0, 0.0), (0.5, 0.5), (0.0, 1.0)):
        d = csr_array(np.array([[1.0], [delta]]))
        assert own_shares(rows, pairs, owners, hidden, pred, BOX, d) == [own]
    d = csr_array(np.array([[1.0], [1.0]]))
    assert own_shares(rows, pairs, owners, np.array([False, False]), pred, BOX, d) == [1.0]
    assert own_shares(rows, np.zeros((0, 2), dtype=int), owners, hidden, pred, BOX, d) == [1.0]
    # the pair's order in O does not matter
    assert own_shares(rows, np.array([[1, 0]]), owners, hidden, pred, BOX, d) == [0.0]


def test_merged_measurement_moves_q_by_the_own_share_only():
    q, p = Histogram.of(np.array([1.0, 0.0])), Histogram.of(np.array([0.0, 1.0]))
    paper, ours = MeasurementAppearance(), MergedAppearance()
    assert paper.update(q, p, 0.0) is p  # the paper: q = p whoever else is inside
    assert ours.update(q, p, 1.0) is p
    assert ours.update(q, p, 0.0) is q
    assert ours.update(q, p, 0.25).dense().tolist() == [0.75, 0.25]
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).appearance_front, MeasurementAppearance)
    assert isinstance(build_rules(Adaptations(merged_appearance=True), h).appearance_front,
                      MergedAppearance)
    assert "merged_appearance" in Adaptations(merged_appearance=True).changed()


def test_union_cover_counts_the_ellipse_inside_any_other():
    box = np.array([[10.0, 0.0, 10.0, 20.0]])
    assert union_cover(box, box)[0] == 1.0
    assert union_cover(box, np.array([[0.0, -10.0, 30.0, 40.0]]))[0] == 1.0  # wholly inside
    assert union_cover(box, np.array([[40.0, 0.0, 10.0, 20.0]]))[0] == 0.0  # apart
    halves = np.array([[5.0, 0.0, 10.0, 20.0], [15.0, 0.0, 10.0, 20.0]])
    one, both = union_cover(box, halves[:1])[0], union_cover(box, halves)[0]
    assert 0.3 < one < 0.7 and both > one and both == union_cover(box, halves[::-1])[0]


def test_a_box_across_two_measured_people_is_a_part_stage_2_may_not_take():
    """Measurements 0 and 2 are matched in stage 1 (persons 0 and 1); measurement 1 lies
    across both. Person 2, hidden far away with a wide gate, takes it in stage 2 in the
    paper; with ``split_parts`` it is barred (and a measurement apart is not)."""
    from occbench.trackers.three_hypothesis.association import associate

    dets = np.array([[0.0, 0, 10, 20], [5.0, 0, 10, 20], [10.0, 0, 10, 20], [60.0, 0, 10, 20]])
    nodes = np.array([[0.0, 0, 10, 20], [10.0, 0, 10, 20], [40.0, 0, 10, 20]])
    delta = np.zeros((3, 4))
    delta[0, 0] = delta[1, 2] = 1.0
    sqrt_q, sqrt_p = np.ones((3, 1)), np.ones((4, 1))
    rule = SplitParts(0.5)
    assert AnyLeftover().barred(dets, np.array([True, False, True, False])) is None
    assert rule.barred(dets, np.array([True, False, True, False])).tolist() == [
        False, True, False, False]

    def taken(barred, d=dets):
        m = associate(nodes, np.arange(3), sqrt_q, d, sqrt_p[:len(d)], 0.3, 100.0,
                      delta=delta[:, :len(d)],
                      barred=barred)
        return {int(p): int(x) for p, x, _ in m.matches.tolist()}

    assert taken(None, dets[:3])[2] == 1
    assert 2 not in taken(lambda matched: rule.barred(dets[:3], matched), dets[:3])
    assert taken(lambda matched: rule.barred(dets, matched))[2] == 3  # the one apart
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).parts, AnyLeftover)
    assert build_rules(Adaptations(split_parts=True), h).parts == SplitParts(0.5)


def test_merged_measurement_corrects_m_by_its_own_share_only():
    R = np.stack([np.eye(4), 2 * np.eye(4)])
    assert MeasurementMotion().noise(R, np.array([0.5, 0.0])) is R
    out = MergedMotion().noise(R, np.array([0.5, 1.0]))
    assert np.allclose(out, np.stack([2 * np.eye(4), 2 * np.eye(4)]))
    assert MergedMotion().noise(R, np.array([0.0, 1.0]))[0, 0, 0] == 1000.0  # share floored
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).motion_front, MeasurementMotion)
    assert isinstance(build_rules(Adaptations(merged_motion=True), h).motion_front, MergedMotion)


def _walker_past_a_standing_person(merged_motion: bool) -> list[tuple[int, float]]:
    """A red walker P (28 x 80, 2 px/frame right, nearer: lower bottom edge) passes in
    front of a blue person Q standing (24 x 64 at x 100). Both are detected until frame 29;
    Q, covered, is missed from frame 30 on; at frames 32-35 the detector keeps one small
    box on Q's place, all of it inside Q's predicted region and filled with P's red (the
    pair's box); then P is detected again. Returns, per frame 30-41, the id and centre x of
    the reported box nearest P's."""
    tracker = RetaTracker(adaptations=Adaptations(merged_motion=merged_motion))
    q_box = np.array([100.0, 30, 24, 64])
    out = []
    for t in range(42):
        p_box = np.array([40.0 + 2.0 * t, 40, 28, 80])
        img = np.full((140, 200, 3), 90, np.uint8)
        for (x, y, w, h), colour in ((q_box, (200, 60, 40)), (p_box, (60, 60, 200))):
            cv2.ellipse(img, ((int(x + w / 2), int(y + h / 2)), (int(w), int(h)), 0), colour, -1)
        dets = ([p_box, q_box] if t < 30 else [p_box] if t < 32
                else [np.array([106.0, 44, 18, 50])] if t < 36 else [p_box])
        tracks = tracker.update(img, Detections(np.array(dets), np.ones(len(dets))))
        if t >= 30:
            shown = [x for x in tracks if x.state.reported]
            p = shown[int(np.argmax(iou_matrix(p_box[None], np.array([x.box for x in shown]))))]
            out.append((p.id, p.box[0] + p.box[2] / 2))  # the reported box nearest P
    return out


def test_a_box_on_a_hidden_partner_does_not_drag_the_walker_and_its_id():
    """``merged_motion``: the walker matched at frame 32 to a box its hidden partner's
    region holds (own share near 0) keeps M's motion, so the box goes to the partner from
    frame 33 on and the walker's own box, back at frame 36, to the walker's id; the paper's
    correction drags the walker's M onto the box, it keeps the box for 4 frames, and its
    own box goes to the partner's id: the two ids are exchanged."""
    paper, ours = (_walker_past_a_standing_person(m) for m in (False, True))
    p_id = ours[0][0]
    assert p_id > 0 and paper[0][0] == p_id
    assert [i for i, _ in paper[3:6]] == [p_id] * 3  # the paper: P keeps the box
    assert p_id not in [i for i, _ in ours[3:6]]  # ours: the box is the partner's
    assert [i for i, _ in ours[6:]] == [p_id] * 6
    assert p_id not in [i for i, _ in paper[6:]]  # the paper's exchange at frame 36


def test_region_term_of_a_node_behind_is_scaled_by_its_visible_share():
    """Two nodes of one size in O; eq. 2's ratio 0.25 means half of either region lies in
    the other. The node behind keeps half of its region term, the node in front all of it;
    wholly covered (ratio 0.5), the node behind has none; the paper keeps both whole."""
    pred = np.array([[0.0, 0, 10, 20], [5.0, 0, 10, 20]])
    delta = np.array([[0.8, 0.2], [0.6, 0.4]])
    pairs = np.array([[0, 1]])
    assert WholeRegion().delta(delta, pairs, np.array([0.25]), np.array([True]), pred) is delta
    rule = VisibleRegion()
    assert np.allclose(rule.delta(delta, pairs, np.array([0.25]), np.array([True]), pred),
                       [[0.8, 0.2], [0.3, 0.2]])
    assert np.allclose(rule.delta(delta, pairs, np.array([0.25]), np.array([False]), pred),
                       [[0.4, 0.1], [0.6, 0.4]])
    assert np.allclose(rule.delta(delta, pairs, np.array([0.5]), np.array([True]), pred)[1], 0)
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).region, WholeRegion)
    assert isinstance(build_rules(Adaptations(visible_region=True), h).region, VisibleRegion)


def test_own_shares_equal_the_per_row_definition_bit_for_bit():
    """Random frames: each row's share, 1 - max over its hidden partners in O of
    |S_m & S_d| / |S_d|, computed row by row over the dense delta, equals own_shares's
    whole-frame arrays bit for bit (ties, rows with no partner, no hidden partner)."""
    rng = np.random.default_rng(5)
    for _ in range(50):
        nodes, dets, people = rng.integers(2, 12), rng.integers(1, 6), rng.integers(2, 8)
        owners = np.sort(rng.integers(0, people, nodes))
        pred = rng.uniform(1, 40, (nodes, 4))
        boxes = rng.uniform(1, 40, (dets, 4))
        dense = np.where(rng.random((nodes, dets)) < 0.5,
                         rng.choice([0.25, 0.5, 0.7], (nodes, dets)), 0.0)
        pairs = rng.integers(0, nodes, (rng.integers(0, 15), 2))
        hidden = rng.random(people) < 0.5
        matched = rng.permutation(nodes)[: rng.integers(1, nodes)]
        matches = [Match(det=int(rng.integers(dets)), node=int(n), stage=1, rho=1.0)
                   for n in matched]
        want = []
        for match in matches:
            area = boxes[match.det, 2] * boxes[match.det, 3]
            inter = [dense[m, match.det] * (pred[m, 2] * pred[m, 3] + area) / 2
                     for a, b in pairs.tolist() for n, m in ((a, b), (b, a))
                     if n == match.node and hidden[owners[m]]]
            share = 1.0 - max(inter) / max(area, 1e-9) if inter else 1.0
            want.append(float(np.clip(share, 0.0, 1.0)))
        got = own_shares(matches, pairs, owners, hidden, pred, boxes, csr_array(dense))
        assert got.tolist() == want


def _split_takers(rule, merged: list[bool], hidden: list[bool], stage: int = 1,
                  delta: list | None = None, rho_10: float = 0.7,
                  region: list | None = None) -> list[int]:
    """pets1-400 sil frame 166 in miniature: persons 0 and 1 in O, two measurements meet
    both. Colours: person 0 rho 0.6 for both, person 1 0.7 for measurement 0 and 0.5 for 1;
    regions: person 0 delta 0.49 / 0.76, person 1 0.24 / 0.83 (person 0's M dragged by the
    merged box, person 1's hypothesis lagging). Stage 1 (the paper's cost) gives each the
    other's measurement; returns the measurement each person takes after ``rule``
    (``rho_10``: person 1's rho for measurement 0; ``region``: person 0's at t - 1, person
    1's is measurement 1's box)."""
    from types import SimpleNamespace

    from occbench.trackers.three_hypothesis.association import associate

    sqrt_q = np.array([[0.6, 0.6, np.sqrt(0.28)],
                       [rho_10, 0.5, np.sqrt(max(1.0 - rho_10 ** 2 - 0.25, 0.0))]])
    sqrt_p = np.eye(3)[:2]  # rho = sqrt_q's first two columns
    boxes = np.array([[100.0, 50, 20, 60], [104.0, 50, 20, 60]])
    owners, pairs = np.array([0, 1]), np.array([[0, 1]])
    delta = np.array([[0.49, 0.76], [0.24, 0.83]] if delta is None else delta)
    m = associate(boxes, owners, sqrt_q, boxes, sqrt_p, 0.3, 50.0, delta=delta)
    assert m.matches[:, :2].tolist() == [[0, 0], [1, 1]]  # the regions' pairs

    def rho(i, d):
        return float(sqrt_q[i] @ sqrt_p[d])

    shapes = [np.array(boxes[0] if region is None else region, dtype=float), boxes[1]]
    persons = [SimpleNamespace(shape=s) for s in shapes]
    rows = rule.matches(m.matches, np.full(2, stage), rho, pairs, owners, csr_array(delta),
                        np.array(merged), np.array(hidden), 0.3, (persons, boxes))
    return rows[np.argsort(rows[:, 0]), 1].tolist()


def test_where_a_merged_pair_parts_the_colours_say_who_is_whose():
    """``split_appearance``: person 0's last measurement held person 1, hidden; stage 1
    gave the pair each other's measurement by the regions, the rule exchanges them because
    the colours fit the exchange better (0.6 + 0.7 against 0.6 + 0.5). The paper keeps stage
    1's; so does the rule when person 0 was not merged, person 1 not hidden, the matches
    came from stage 2, or a person's nodes do not meet the other measurement."""
    paper, ours = RegionAtSplit(), AppearanceAtSplit()
    assert _split_takers(paper, [True, False], [False, True]) == [0, 1]
    assert _split_takers(ours, [True, False], [False, True]) == [1, 0]
    assert _split_takers(ours, [False, True], [True, False]) == [1, 0]  # either way round
    assert _split_takers(ours, [False, False], [False, True]) == [0, 1]
    assert _split_takers(ours, [True, False], [False, False]) == [0, 1]
    assert _split_takers(ours, [True, False], [False, True], stage=2) == [0, 1]
    assert _split_takers(ours, [True, False], [False, True],
                         delta=[[0.49, 0.76], [0.0, 0.83]]) == [0, 1]
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).split, RegionAtSplit)
    assert isinstance(build_rules(Adaptations(split_appearance=True), h).split,
                      AppearanceAtSplit)
    assert "split_appearance" not in Adaptations.paper().changed()
    assert "split_appearance" in Adaptations().changed()  # on since the fifteenth round


def test_where_a_merged_pair_parts_colours_that_win_by_little_decide_nothing():
    """``split_appearance_margin``: the same parting with person 1's rho for measurement 0
    at 0.55: the exchange fits the colours better by 0.05 (0.6 + 0.55 against 0.6 + 0.5),
    taken at margin 0, not at 0.1; at 0.7 (by 0.2) taken at both."""
    assert _split_takers(AppearanceAtSplit(), [True, False], [False, True], rho_10=0.55) == [1, 0]
    assert _split_takers(AppearanceAtSplit(0.1), [True, False], [False, True],
                         rho_10=0.55) == [0, 1]
    assert _split_takers(AppearanceAtSplit(0.1), [True, False], [False, True]) == [1, 0]
    h = EllipseHistogrammer()
    assert build_rules(Adaptations(), h).split == AppearanceAtSplit(0.1, 0.5)
    assert build_rules(Adaptations(split_appearance_parted=0.0), h).split == AppearanceAtSplit(0.1)
    assert Adaptations.paper().split_appearance_margin == 0.0


def test_where_a_merged_pair_parts_only_a_measurement_that_does_not_continue_it():
    """``split_appearance_parted``: person 0's region at t - 1 was its measurement 0 of now
    (IoU 1: a person's own box continued): no exchange at 0.5. A region 10 px to the right
    of it (IoU 0.33 with measurement 0: a box over two that parted) is exchanged as before;
    at 0 (off) either is."""
    parted = AppearanceAtSplit(0.1, 0.5)
    assert _split_takers(parted, [True, False], [False, True]) == [0, 1]
    assert _split_takers(parted, [True, False], [False, True], region=[110, 50, 20, 60]) == [1, 0]
    assert _split_takers(AppearanceAtSplit(0.1), [True, False], [False, True]) == [1, 0]
    h = EllipseHistogrammer()
    assert build_rules(Adaptations(split_appearance=True, split_appearance_parted=0.5),
                       h).split == parted
    assert "split_appearance_parted" in Adaptations().changed()
    assert "split_appearance_parted" not in Adaptations.paper().changed()
    with pytest.raises(ValueError, match=r"adaptations\.split_appearance_parted"):
        Adaptations(split_appearance_parted=50.0)  # an IoU, not a percentage


def test_merged_measurement_unmixed_takes_out_the_hidden_partners_colours():
    """``merged_unmixed``: a measurement half covered by a hidden partner (own 0.5) holds
    red (the person's) and green (the partner's, q_j) half and half. The paper takes p, the
    merged form moves q halfway to p (a quarter green), the unmixed form takes the partner's
    half out and keeps q red; with no partner or own 1 it is the merged form."""
    q, q_j = Histogram.of(np.array([0.8, 0.0, 0.2])), Histogram.of(np.array([0.0, 1.0, 0.0]))
    p = Histogram.of(np.array([0.5, 0.5, 0.0]))
    assert MeasurementAppearance().update(q, p, 0.5, q_j) is p
    assert np.allclose(MergedAppearance().update(q, p, 0.5, q_j).dense(), [0.65, 0.25, 0.1])
    assert np.allclose(UnmixedAppearance().update(q, p, 0.5, q_j).dense(), [0.9, 0.0, 0.1])
    assert np.array_equal(UnmixedAppearance().update(q, p, 0.5, None).dense(),
                          MergedAppearance().update(q, p, 0.5).dense())
    assert UnmixedAppearance().update(q, p, 1.0, q_j) is p
    assert UnmixedAppearance().update(q, p, 0.0, q_j) is q  # wholly the partner's: kept
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations(merged_unmixed=True), h).appearance_front,
                      UnmixedAppearance)
    assert type(build_rules(Adaptations(), h).appearance_front) is MergedAppearance
    assert isinstance(build_rules(Adaptations(merged_appearance=False, merged_unmixed=True),
                                  h).appearance_front, MeasurementAppearance)
    assert "merged_unmixed" not in Adaptations().changed() + Adaptations.paper().changed()


def test_own_shares_name_the_partner_covering_most():
    """Person 0 matched to a measurement two hidden partners (persons 1 and 2) overlap,
    person 2 by more: the partner is 2; an unmatched row and a row with no partner: -1."""
    boxes = np.array([[0.0, 0, 10, 20], [6.0, 0, 10, 20], [2.0, 0, 10, 20], [50.0, 0, 10, 20]])
    dense = np.zeros((4, 2))
    dense[:3, 0] = [1.0, 0.4, 0.8]
    dense[3, 1] = 1.0
    pairs = np.array([[0, 1], [0, 2], [1, 2]])
    owners, hidden = np.arange(4), np.array([False, True, True, False])
    matches = [Match(0, 0, 1, 1.0), Match(1, 3, 1, 1.0)]
    partners = np.full(2, -1)
    own = own_shares(matches, pairs, owners, hidden, boxes, boxes[[0, 3]], csr_array(dense),
                     partners)
    assert partners.tolist() == [2, -1]
    assert own[0] < 1.0 and own[1] == 1.0
    assert own.tolist() == own_shares(matches, pairs, owners, hidden, boxes, boxes[[0, 3]],
                                      csr_array(dense)).tolist()


def test_unmixed_evidence_unmixes_only_a_measurement_whose_colours_hold_both():
    """``merged_unmixed_evidence``: q red, the hidden partner's q_j mostly green, own 0.5. A
    measurement half q, half q_j fits the mixture (rho 1) better than either alone: the
    partner's half is taken out as ``merged_unmixed`` does. A measurement that is the person's
    red alone fits q better than the mixture: q moves towards p by own, as
    ``merged_appearance`` does."""
    q, q_j = Histogram.of(np.array([1.0, 0.0, 0.0])), Histogram.of(np.array([0.2, 0.8, 0.0]))
    both, alone = Histogram.of(np.array([0.6, 0.4, 0.0])), Histogram.of(np.array([0.9, 0.0, 0.1]))
    rule = UnmixedAppearance(evidence=True)
    assert np.array_equal(rule.update(q, both, 0.5, q_j).dense(),
                          UnmixedAppearance().update(q, both, 0.5, q_j).dense())
    assert np.array_equal(rule.update(q, alone, 0.5, q_j).dense(),
                          MergedAppearance().update(q, alone, 0.5).dense())
    assert not np.array_equal(UnmixedAppearance().update(q, alone, 0.5, q_j).dense(),
                              MergedAppearance().update(q, alone, 0.5).dense())
    h = EllipseHistogrammer()
    assert build_rules(Adaptations(merged_unmixed=True, merged_unmixed_evidence=True),
                       h).appearance_front == UnmixedAppearance(True)
    assert build_rules(Adaptations(merged_unmixed=True), h).appearance_front == \
        UnmixedAppearance(False)
    assert "merged_unmixed_evidence" not in (Adaptations().changed()
                                             + Adaptations.paper().changed())


def _walker_colours_after_passing(unmixed: bool, evidence: bool = False) -> tuple[float, float]:
    """A red walker P (28 x 80, 2 px/frame right) passes in front of a blue person Q
    standing (24 x 64 at x 100); from frame 22 to 33 the detector gives one box over both
    (their union) and misses Q. Returns rho of P's and of Q's q (eq. 4) with P's own
    measurement histogram at frame 34, where P is measured alone again."""
    tracker = RetaTracker(adaptations=Adaptations(merged_unmixed=unmixed,
                                                  merged_unmixed_evidence=evidence))
    q_box = np.array([100.0, 30, 24, 64])
    for t in range(35):
        p_box = np.array([40.0 + 2.0 * t, 40, 28, 80])
        img = np.full((140, 220, 3), 90, np.uint8)
        for (x, y, w, h), colour in ((q_box, (200, 60, 40)), (p_box, (60, 60, 200))):
            cv2.ellipse(img, ((int(x + w / 2), int(y + h / 2)), (int(w), int(h)), 0), colour, -1)
        x0, y0 = np.minimum(p_box[:2], q_box[:2])
        x1, y1 = np.maximum(p_box[:2] + p_box[2:], q_box[:2] + q_box[2:])
        union = np.array([x0, y0, x1 - x0, y1 - y0])
        dets = [p_box, q_box] if t < 22 else [union] if t < 34 else [p_box]
        if t == 34:
            before = {p.id: p.q.dense() for p in tracker.memory.persons if p.confirmed}
        tracker.update(img, Detections(np.array(dets), np.ones(len(dets))))
    own_p = tracker.histograms(img, p_box[None])[0]
    rho = {i: float(np.sqrt(q) @ np.sqrt(own_p)) for i, q in before.items()}
    return rho[1], rho[2]


def test_a_walker_in_front_keeps_its_colours_through_a_merged_box():
    """``merged_unmixed``: through twelve frames of the pair's box, the walker's q absorbs
    the standing person's blue with the merged form (it moves towards the pair's histogram
    by its own share each frame); unmixed, the partner's share is taken out and the walker's
    q stays nearer its own red when it is measured alone again."""
    merged, unmixed = (_walker_colours_after_passing(u) for u in (False, True))
    assert unmixed[0] > merged[0] + 0.03  # 0.94 against 0.89
    assert unmixed[0] > unmixed[1]
    # merged_unmixed_evidence: the union's histogram (both people and the floor between
    # them) fits the walker's q better than the mixture in most of the twelve frames, so
    # it unmixes in a few: between the two
    evidence = _walker_colours_after_passing(True, True)
    assert merged[0] < evidence[0] < unmixed[0]  # 0.8919 < 0.8927 < 0.938


def test_coincident_people_seen_at_t_minus_1_share_their_appearance_term():
    """``contact_coincident``: persons 0 and 1, both seen at t - 1, predicted 20 x 60 and
    20 x 56 at the same place (each region holds more than half of the larger), meet one
    measurement: person 0's colours fit it better (rho 0.95 against 0.7, the q's of two
    people measured over the same pixels), person 1's region better (delta 0.98 against
    0.80). The paper gives it to person 0; the rule to person 1. Moved 12 px apart (the
    common part below half of the larger), or with person 1 hidden at t - 1, the pair keeps
    its appearance terms and person 0 takes it again."""
    from occbench.trackers.three_hypothesis.association import associate
    from occbench.trackers.three_hypothesis.occlusion import region_overlap_values

    sqrt_q = np.array([[0.95, np.sqrt(1 - 0.95**2)], [0.7, np.sqrt(1 - 0.7**2)]])
    sqrt_p = np.array([[1.0, 0.0]])
    delta = np.array([[0.80], [0.98]])
    owners, pairs = np.array([0, 1]), np.array([[0, 1]])
    rule = RegionAtContact(0.5)

    def taker(pred, seen):
        ratio = 0.5 * region_overlap_values(pred, pred, np.array([0]), np.array([1]), 12)
        kept = rule.pairs(pairs, ratio, pred, seen)
        m = associate(pred, owners, sqrt_q, pred[1:], sqrt_p, 0.5, 50.0, delta=delta,
                      evidence=rule.evidence(AppearanceMargin().evidence, kept, owners))
        return len(kept), m.matches[:, 0].tolist()

    together = np.array([[100.0, 50, 20, 60], [100.0, 52, 20, 56]])
    apart = np.array([[100.0, 50, 20, 60], [112.0, 52, 20, 56]])
    both, one = np.array([True, True]), np.array([True, False])
    assert taker(together, both) == (1, [1])
    assert taker(apart, both) == (0, [0])  # they overlap (in O) but do not coincide
    assert taker(together, one) == (0, [0])  # person 1's q is its own, kept while hidden
    assert len(RegionAtContact().pairs(pairs, np.array([0.1]), apart, None)) == 1  # every pair
    assert AppearanceAtContact().pairs(pairs, np.array([0.1]), apart, None) is pairs
    h = EllipseHistogrammer()
    assert build_rules(Adaptations(contact_coincident=True), h).contact == RegionAtContact(0.5)
    assert build_rules(Adaptations(), h).contact == AppearanceAtContact()
    assert "contact_coincident" in Adaptations(contact_coincident=True).changed()
    assert "contact_coincident" not in Adaptations().changed() + Adaptations.paper().changed()


def test_a_measurement_mostly_covered_by_a_nearer_one_is_a_person_behind():
    """``covered_appearance``: measurement 0 (20 x 60, foot line 110) lies for 0.71 of its
    ellipse inside measurement 1's (24 x 70, foot line 126: nearer the camera); measurement
    1 is covered by 0 too, but 0 stands farther; measurement 2 meets nobody. Only 0 is a
    person behind. At cover 0.75 none is."""
    boxes = np.array([[100.0, 50, 20, 60], [104.0, 56, 24, 70], [300.0, 50, 20, 60]])
    rows = np.array([0, 1, 2])
    assert NearerCover(0.5).behind(rows, boxes, 12).tolist() == [True, False, False]
    assert NearerCover(0.75).behind(rows, boxes, 12).tolist() == [False, False, False]
    assert NearerCover(0.5).behind(rows[1:], boxes, 12).tolist() == [False, False]
    assert not AnyCover.covers and NearerCover.covers  # the paper reads no measurement as covered
    h = EllipseHistogrammer()
    assert build_rules(Adaptations(covered_appearance=True), h).covered == NearerCover(0.5)
    assert build_rules(Adaptations(), h).covered == AnyCover()
    assert "covered_appearance" in Adaptations(covered_appearance=True).changed()
    assert "covered_appearance" not in Adaptations().changed() + Adaptations.paper().changed()


def _red_person_q_after_a_green_one_steps_in_front(covered: bool) -> float:
    """A red person (20 x 60 at x 100) measured alone for five frames; at frame 5 a green
    newcomer stands in front of it (24 x 70, foot line 16 px lower), drawn over most of the
    red ellipse, and both are measured. Returns rho (eq. 4) of the red person's q after
    frame 5 with its q of frame 4."""
    tracker = RetaTracker(adaptations=Adaptations(covered_appearance=covered))
    red, green = np.array([100.0, 50, 20, 60]), np.array([104.0, 56, 24, 70])
    for t in range(6):
        img = np.full((160, 240, 3), 90, np.uint8)
        boxes = [red] if t < 5 else [red, green]
        for (x, y, w, h), colour in zip(boxes, ((40, 40, 200), (40, 200, 40))):
            cv2.ellipse(img, ((int(x + w / 2), int(y + h / 2)), (int(w), int(h)), 0), colour, -1)
        if t == 5:
            (person,) = [p for p in tracker.memory.persons if p.confirmed]
            before = person.q.dense()
        tracker.update(img, Detections(np.array(boxes), np.ones(len(boxes))))
    return float(np.sqrt(person.q.dense()) @ np.sqrt(before))


def test_a_person_whose_measurement_a_nearer_one_covers_keeps_its_colours():
    """``covered_appearance``: the paper's red person takes its measurement's histogram,
    green for the most part (rho 0.55 with its q of frame 4); with the rule its measurement
    is a person behind's and its q is kept (rho 1)."""
    assert _red_person_q_after_a_green_one_steps_in_front(False) < 0.9
    assert _red_person_q_after_a_green_one_steps_in_front(True) == pytest.approx(1.0)
