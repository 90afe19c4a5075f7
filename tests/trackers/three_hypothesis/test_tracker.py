"""Reta et al. 2015 three-hypothesis tracker: parts (eqs. 1-5, Kalman, graph) and behaviour."""

from __future__ import annotations

import inspect
import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from filterpy.kalman import KalmanFilter
from scipy.optimize import linear_sum_assignment

from occbench.trackers.baseline import BaselineTracker
from occbench.trackers.common.assignment import assign
from occbench.trackers.geometry import intersection_matrix, iou_matrix
from occbench.trackers.histograms import bhattacharyya
from occbench.trackers.records import Detections, TrackState
from occbench.trackers.three_hypothesis import (
    Adaptations,
    Association,
    LifeCycle,
    Occlusion,
    RetaTracker,
)
from occbench.trackers.three_hypothesis.appearance import (EllipseHistogrammer, Histogram, columns,
                                                           snap_boxes)
from occbench.trackers.three_hypothesis.association import _hungarian, _person_costs, associate
from occbench.trackers.three_hypothesis.features import ellipse_histograms, region_similarity
from occbench.trackers.three_hypothesis.graph import TrackingGraph
from occbench.trackers.three_hypothesis.motion import MotionModel, box_measurements, correct, predict
from occbench.trackers.three_hypothesis.occlusion import (
    area_above,
    boxes_meet,
    depth_order,
    occlusion_pairs,
    overlap_ratio,
    region_overlaps,
)
from occbench.trackers.three_hypothesis.rules import AppearanceMargin
from occbench.config.meta import without_meta

ROOT = Path(__file__).resolve().parents[3]


# --------------------------------------------------------------------------- parts


def test_histograms_equal_the_front_end_definition():
    rng = np.random.default_rng(0)
    frame = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    boxes = np.array([[-5.3, 10.2, 30.6, 50.1], [40.0, 30.0, 21.0, 61.0], [150.0, 100.0, 30, 40]])
    fg = rng.random((120, 160)) > 0.3
    h = EllipseHistogrammer()
    for mask in (None, fg):
        ours = h(frame, boxes, mask)
        ref = ellipse_histograms(frame, snap_boxes(boxes), mask)
        np.testing.assert_array_equal(ours, ref)
        np.testing.assert_allclose(ours.sum(axis=1), 1.0)


def test_histogram_uses_foreground_pixels_only_when_enough():
    frame = np.zeros((40, 40, 3), np.uint8)
    frame[:, 20:] = (255, 0, 0)  # right half blue
    box = np.array([[0.0, 0.0, 40.0, 40.0]])
    fg = np.zeros((40, 40), bool)
    fg[:, 20:] = True
    h = EllipseHistogrammer(min_foreground=0.2)
    assert h(frame, box)[0].max() == pytest.approx(0.5, abs=0.02)  # half black, half blue
    assert h(frame, box, fg)[0].max() == 1.0  # only the blue foreground
    tiny = np.zeros((40, 40), bool)
    tiny[0, 20] = True  # 1 pixel of foreground: below min_foreground, whole ellipse used
    np.testing.assert_array_equal(h(frame, box, tiny), h(frame, box))


def test_measure_gives_one_histogram_each_and_their_support():
    rng = np.random.default_rng(4)
    frame = rng.integers(0, 256, (90, 120, 3), dtype=np.uint8) // 64 * 64  # few colours
    boxes = np.array([[10.0, 5.0, 30.0, 60.0], [70.0, 20.0, 40.0, 50.0], [200.0, 0, 10, 10]])
    h = EllipseHistogrammer()
    p, support = h.measure(frame, boxes)
    dense = np.array([row.dense() for row in p])
    assert len(p) == 3 and all(row.size == 4096 for row in p)
    np.testing.assert_array_equal(dense, h(frame, boxes))
    np.testing.assert_array_equal(support, np.flatnonzero(dense.any(axis=0)))
    assert 0 < len(support) <= 4**3 and len(p[2].bins) == 0  # box 3 lies outside the frame
    np.testing.assert_array_equal(columns(p, support), dense[:, support])
    # a person's q occupies bins no measurement does: those are left out
    outside = np.setdiff1d(np.arange(4096), support)[[0, -1]]
    q = Histogram(np.sort(np.append(outside, support[0])), np.array([0.25, 0.5, 0.25]), 4096)
    np.testing.assert_array_equal(columns([q, *p], support),
                                  np.vstack([q.dense(), dense])[:, support])
    np.testing.assert_array_equal(columns([q], support[1:]), q.dense()[None, support[1:]])


def test_region_overlaps_equal_the_front_end_definition_exactly():
    rng = np.random.default_rng(2)
    for k in range(60):
        n, m = rng.integers(0, 9, 2)
        a = np.column_stack([rng.uniform(-40, 200, (n, 2)), rng.uniform(0.5, 90, (n, 2))])
        b = np.column_stack([rng.uniform(-40, 200, (m, 2)), rng.uniform(0.5, 90, (m, 2))])
        if k % 2:  # pixel-aligned boxes: edges that touch exactly
            a, b = a.round(), np.maximum(b.round(), 1.0)
        if n and m:
            b[0] = a[0]
        samples = (12, 24)[k % 2]
        np.testing.assert_array_equal(region_overlaps(a, b, samples),
                                      region_similarity(a, b, samples=samples))
        np.testing.assert_array_equal(boxes_meet(a, b), intersection_matrix(a, b) > 0)
        # integrating only some pairs gives those pairs' values and 0 elsewhere
        near = boxes_meet(a, b) & (rng.random((n, m)) < 0.5)
        np.testing.assert_array_equal(region_overlaps(a, b, samples, near),
                                      np.where(near, region_similarity(a, b, samples=samples), 0))


def test_hungarian_with_unmatched_cost_equals_the_padded_assignment():
    rng = np.random.default_rng(6)
    for _ in range(200):
        n, m = rng.integers(1, 7, 2)
        cost = np.where(rng.random((n, m)) < 0.5, rng.uniform(0, 2.5, (n, m)), np.inf)
        dummy = np.full((n, n), np.inf)
        np.fill_diagonal(dummy, 2.0)
        ref, _, _ = assign(np.hstack([cost, dummy]), 2.0)  # the former formulation
        ref = ref[ref[:, 1] < m]
        np.testing.assert_array_equal(_hungarian(cost, 2.0), ref)


def test_person_costs_take_each_persons_best_node():
    rng = np.random.default_rng(7)
    owners = np.array([0, 0, 1, 2, 2, 2, 3])
    starts = np.array([0, 2, 3, 6])
    cost = np.where(rng.random((7, 5)) < 0.6, rng.integers(0, 4, (7, 5)).astype(float), np.inf)
    person, best = _person_costs(cost, starts, owners)
    for k, (a, b) in enumerate(zip(starts, [*starts[1:], 7])):
        np.testing.assert_array_equal(person[k], cost[a:b].min(axis=0))
        np.testing.assert_array_equal(best[k], a + np.argmin(cost[a:b], axis=0))  # first on ties


def test_batched_kalman_equals_filterpy():
    model = MotionModel()
    rng = np.random.default_rng(1)
    boxes = rng.uniform(10, 100, (3, 4))
    states = [model.init(b) for b in boxes]
    kfs = []
    for b, (x, P, F, H, Q, R) in zip(boxes, states):
        kf = KalmanFilter(dim_x=8, dim_z=4)
        kf.x, kf.P, kf.F, kf.H, kf.Q, kf.R = x[:, None].copy(), P.copy(), F, H, Q, R
        kfs.append(kf)
    X = np.array([s[0] for s in states])
    Ps = np.array([s[1] for s in states])
    F, H = states[0][2], states[0][3]
    Qs = np.array([s[4] for s in states])
    Rs = np.array([s[5] for s in states])
    for _ in range(4):
        z = box_measurements(boxes + rng.normal(0, 2, boxes.shape))
        X, Ps = predict(X, Ps, F, Qs)
        X, Ps = correct(X, Ps, z, H, Rs)
        for kf, zi in zip(kfs, z):
            kf.predict()
            kf.update(zi[:, None])
    np.testing.assert_allclose(X, np.array([kf.x[:, 0] for kf in kfs]), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(Ps, np.array([kf.P for kf in kfs]), rtol=1e-9, atol=1e-9)


def test_eq2_overlap_ratio_and_occlusion_pairs():
    a = np.array([[0.0, 0.0, 40.0, 80.0]])
    assert overlap_ratio(a, a)[0, 0] == pytest.approx(0.5, abs=0.01)  # identical: 1/2
    assert overlap_ratio(a, a + [100, 0, 0, 0])[0, 0] == 0.0
    small = np.array([[10.0, 20.0, 20.0, 40.0]])  # inside a, a quarter of its area
    assert overlap_ratio(small, a)[0, 0] == pytest.approx(0.25 / 1.25, abs=0.01)
    boxes = np.vstack([a, a + [5, 0, 0, 0], a + [200, 0, 0, 0]])
    # the first two overlap; the same person's hypotheses never occlude each other
    np.testing.assert_array_equal(occlusion_pairs(boxes, np.array([0, 1, 2]), 0.1), [[0, 1]])
    assert len(occlusion_pairs(boxes, np.array([0, 0, 1]), 0.1)) == 0


def test_area_above_is_exact_and_depth_order_follows_eq3():
    box = np.array([[0.0, 0.0, 20.0, 40.0]])  # centre y 20, area 200 pi
    full = np.pi * 10 * 20
    assert area_above(box, np.array([20.0]))[0] == pytest.approx(full / 2)
    assert area_above(box, np.array([40.0]))[0] == pytest.approx(full)
    assert area_above(box, np.array([-1.0]))[0] == 0.0
    near = np.array([0.0, 100.0, 40.0, 100.0])  # lower in the image: nearer
    far = np.array([10.0, 60.0, 20.0, 50.0])
    assert depth_order(True, False, near, far, 0) == 1  # visible one in front
    assert depth_order(False, True, near, far, 0) == -1
    assert depth_order(True, True, near, far, 0) == 1  # far's region lies above near's centre
    assert depth_order(True, True, far, near, 0) == -1
    assert depth_order(False, False, near, far, -1) == -1  # inherited
    assert depth_order(False, False, near, far, 1) == 1


def _hist(colour_index: int, bins: int = 4096) -> np.ndarray:
    h = np.zeros(bins)
    h[colour_index] = 1.0
    return h


def test_association_stage1_appearance_decides_between_intersecting_pairs():
    # two predictions at the same place; the measurements' colours tell them apart
    node_boxes = np.array([[100.0, 100, 30, 80], [102.0, 100, 30, 80]])
    q = np.array([_hist(1), _hist(2)])
    meas = np.array([[101.0, 100, 30, 80], [101.0, 101, 30, 80]])
    p = np.array([_hist(2), _hist(1)])
    a = associate(node_boxes, np.array([0, 1]), np.sqrt(q), meas, np.sqrt(p), mu_rho=0.5, mu_g=50)
    assert sorted(map(tuple, a.matches[:, :2])) == [(0, 1), (1, 0)]
    assert set(a.stages) == {1}
    # nobody looks like anybody: every pair rejected by mu_rho
    a = associate(node_boxes, np.array([0, 1]), np.sqrt(q), meas,
                  np.sqrt(np.array([_hist(3), _hist(4)])), 0.5, 50)
    assert len(a.matches) == 0 and len(a.unmatched_measurements) == 2


def test_association_stage2_gate_and_best_hypothesis():
    # person 0 owns two hypotheses, neither intersecting the measurement
    node_boxes = np.array([[0.0, 0, 20, 40], [200.0, 0, 20, 40]])
    meas = np.array([[240.0, 0, 20, 40]])
    q, p = np.array([_hist(1)]), np.array([_hist(1)])
    a = associate(node_boxes, np.array([0, 0]), np.sqrt(q), meas, np.sqrt(p), mu_rho=0.5, mu_g=50)
    np.testing.assert_array_equal(a.matches, [[0, 0, 1]])  # matched through node 1
    assert a.stages[0] == 2
    a = associate(node_boxes, np.array([0, 0]), np.sqrt(q), meas, np.sqrt(p), mu_rho=0.5, mu_g=30)
    assert len(a.matches) == 0  # outside the gate


def test_associate_rho_is_the_bhattacharyya_coefficient():
    """Eq. 4 as the tracker runs it: ``associate`` takes square-rooted histograms restricted
    to the bins some measurement occupies (``steps_occlusion.max_similarity``); the rho of
    each match equals ``bhattacharyya`` (the definition) of the whole histograms."""
    rng = np.random.default_rng(11)
    for _ in range(20):
        n_p, n_d = rng.integers(1, 6, 2)
        q = rng.random((n_p, 4096)) * (rng.random((n_p, 4096)) < 0.05)
        p = rng.random((n_d, 4096)) * (rng.random((n_d, 4096)) < 0.05)
        q /= q.sum(axis=1, keepdims=True)
        p /= p.sum(axis=1, keepdims=True)
        support = np.flatnonzero(p.any(axis=0))
        boxes = np.tile([50.0, 50.0, 30.0, 80.0], (max(n_p, n_d), 1))  # everyone intersects
        m = associate(boxes[:n_p], np.arange(n_p), np.sqrt(q[:, support]), boxes[:n_d],
                      np.sqrt(p[:, support]), mu_rho=0.0, mu_g=50.0)
        assert len(m.matches) == min(n_p, n_d)
        want = bhattacharyya(q, p)[m.matches[:, 0], m.matches[:, 1]]
        np.testing.assert_allclose(m.rho, want, rtol=1e-12, atol=1e-15)


def test_association_keeps_one_good_pair_rather_than_two_poor_ones():
    # person 0 fits measurement 0 perfectly; person 1 only weakly fits measurement 0 and
    # person 0 weakly fits measurement 1: the good pair must win
    node_boxes = np.array([[100.0, 100, 40, 100], [130.0, 100, 40, 100]])
    meas = np.array([[100.0, 100, 40, 100], [300.0, 100, 40, 100]])
    base = np.full(4096, 1 / 4096)
    q = np.array([_hist(1), 0.5 * _hist(1) + 0.5 * base])
    p = np.array([_hist(1), 0.6 * _hist(1) + 0.4 * base])
    a = associate(node_boxes, np.array([0, 1]), np.sqrt(q), meas, np.sqrt(p), mu_rho=0.3, mu_g=10)
    assert (0, 0) in set(map(tuple, a.matches[:, :2]))


def test_stage1_matches_every_acceptable_pair_even_by_exchanging_a_good_one():
    # person 0 fits measurement 0 well (cost 0.2); person 1 (its own detection missed) and
    # person 0 each fit the other measurement poorly (cost 1 - 0.707 + 1 - 0.6 = 0.69).
    # Leaving a person over costs 2 (the paper's Hungarian step), so the exchange is cheaper
    # (1.39 < 0.2 + 2): person 1 takes person 0's detection and pushes person 0 onto the
    # other one (docs/adaptations.md: leaving such pairs over was tried and not taken).
    node_boxes = np.array([[100.0, 100, 40, 100], [130.0, 100, 40, 100]])
    meas = np.array([[100.0, 100, 40, 100], [300.0, 100, 40, 100]])
    q = np.array([_hist(1), 0.5 * _hist(1) + 0.5 * _hist(2)])
    p = np.array([_hist(1), 0.5 * _hist(1) + 0.5 * _hist(3)])
    delta = np.array([[0.8, 0.6], [0.6, 0.0]])
    kw = dict(mu_rho=0.3, mu_g=50.0, delta=delta)
    paper = associate(node_boxes, np.array([0, 1]), np.sqrt(q), meas, np.sqrt(p), **kw)
    assert sorted(map(tuple, paper.matches[:, :2])) == [(0, 1), (1, 0)]
    assert list(paper.stages) == [1, 1]


def test_stage1_appearance_margin_lets_the_regions_decide_among_look_alikes():
    # everyone looks alike (rho = 1 for every pair). Person 1's detection is missed; it
    # overlaps person 0's detection (delta 0.4) as person 0 overlaps a newcomer's (0.4).
    # rho itself: the exchange costs 0.6 + 0.6 < 0 + 2 (person 1 left over), so person 1
    # takes person 0's detection. Margins: rho says nothing here (every margin 0), each
    # pair costs 1 + (1 - delta): the exchange 3.2 > 1 + 2, person 0 keeps its own.
    node_boxes = np.array([[100.0, 100, 40, 100], [130.0, 100, 40, 100]])
    meas = np.array([[100.0, 100, 40, 100], [70.0, 100, 40, 100]])
    q, p = np.array([_hist(1), _hist(1)]), np.array([_hist(1), _hist(1)])
    kw = {"mu_rho": 0.3, "mu_g": 10.0, "delta": np.array([[1.0, 0.4], [0.4, 0.0]])}
    paper = associate(node_boxes, np.array([0, 1]), np.sqrt(q), meas, np.sqrt(p), **kw)
    assert sorted(map(tuple, paper.matches[:, :2])) == [(0, 1), (1, 0)]
    ours = associate(node_boxes, np.array([0, 1]), np.sqrt(q), meas, np.sqrt(p), **kw,
                     evidence=AppearanceMargin().evidence)
    assert sorted(map(tuple, ours.matches[:, :2])) == [(0, 0)]
    assert list(ours.unmatched_persons) == [1] and list(ours.unmatched_measurements) == [1]


def test_bad_input_raises_clear_errors():
    with pytest.raises(ValueError, match="frame"):
        RetaTracker().update(None, Detections.empty())
    with pytest.raises(ValueError, match=r"association\.mu_rho"):
        Association(mu_rho=1.5)
    with pytest.raises(ValueError, match=r"occlusion\.lam"):
        Occlusion(lam=0.5)
    with pytest.raises(ValueError, match=r"life_cycle\.m must"):
        LifeCycle(m=0)
    with pytest.raises(ValueError, match=r"^appearance\.bins must divide 256, got 7$"):
        EllipseHistogrammer(bins=7)  # through common.checks, named by its config key (issue 36)
    with pytest.raises(ValueError, match=r"^the graph's window \(life_cycle\.m \+ 1\) must"):
        TrackingGraph(window=0)
    with pytest.raises(TypeError, match="association: expected a Association"):
        RetaTracker(association={"mu_rho": 0.3})


def test_config_maps_onto_the_constructor():
    from hydra.utils import instantiate
    from omegaconf import OmegaConf

    cfg = without_meta(OmegaConf.load(ROOT / "conf" / "tracker" / "reta.yaml"))
    params = set(inspect.signature(RetaTracker.__init__).parameters) - {"self"}
    assert set(cfg.keys()) - {"_target_"} == params
    assert len(params) <= 12
    tracker = instantiate(cfg)
    assert isinstance(tracker, RetaTracker)
    for group in params - {"min_score"}:  # every group's keys are its fields, all set
        node = cfg[group]
        fields = set(inspect.signature(type(getattr(tracker, group))).parameters)
        assert set(node.keys()) - {"_target_"} == fields, group
        assert {k: getattr(getattr(tracker, group), k) for k in fields} == {
            k: node[k] for k in fields}, group
    assert tracker.adaptations == Adaptations()  # the YAML defaults are the code's


def test_paper_mode_turns_every_adaptation_off():
    from occbench.config.build import build_tracker, compose_config

    paper = build_tracker("reta_paper", compose_config(["tracker=reta_paper"]).tracker)
    ours = build_tracker("reta", compose_config(["tracker=reta"]).tracker)
    assert paper.adaptations == Adaptations.paper() and paper.adaptations.changed() == []
    assert set(ours.adaptations.changed()) == {
        "gate_sigmas", "blend_visible", "shape_estimate", "foreground_histograms",
        "foreground_support", "report_exposed", "report_spread", "tentative_misses",
        "max_hidden", "measured_velocity", "appearance_margin", "foreground_presence",
        "tentative_stage1_only", "inherit_hidden_id", "merge_duplicates", "correct_behind",
        "filter_size", "early_confirm", "report_memory", "merged_appearance",
        "measured_hypothesis", "measured_hypothesis_sigmas", "split_appearance",
        "split_appearance_margin", "split_appearance_parted", "measured_step"}
    for group in ("association", "occlusion", "appearance", "motion", "life_cycle"):
        assert getattr(paper, group) == getattr(ours, group), group


# --------------------------------------------------------------------------- small scenes

W, H = 320, 240


def _scene(paths, colours, seed=0, fps=None):
    """Frames of people drawn as two-colour ellipses (far to near) and their exact detections
    (people at least 30 % visible); ``fps``: frame -> list of false-positive boxes."""
    rng = np.random.default_rng(seed)
    fps = fps or {}
    out = []
    for t in range(len(paths[0])):
        img = np.full((H, W, 3), 90, np.uint8)
        img += rng.integers(0, 6, img.shape, dtype=np.uint8)
        label = np.zeros((H, W), np.int32)
        boxes = np.array([[p[t][0] - 15, p[t][1] - 80, 30, 80] for p in paths])
        for k in np.argsort(boxes[:, 1]):
            x, y, w, h = boxes[k]
            c = (int(x + w / 2), int(y + h / 2))
            cv2.ellipse(img, (c, (int(w), int(h)), 0), colours[k][1], -1)
            cv2.ellipse(img, ((c[0], int(y + h * 0.3)), (int(w * 0.9), int(h * 0.55)), 0),
                        colours[k][0], -1)
            cv2.ellipse(label, (c, (int(w), int(h)), 0), int(k + 1), -1)
        area = np.pi * 15 * 40
        vis = np.bincount(label.ravel(), minlength=len(paths) + 1)[1:] / area
        det = boxes[vis >= 0.3]
        extra = np.array(fps.get(t, []), dtype=float).reshape(-1, 4)
        det = np.vstack([det, extra])
        out.append((img, label, Detections(det, np.ones(len(det))), boxes))
    return out


RED = ((40, 40, 200), (60, 60, 120))
BLUE = ((200, 60, 40), (120, 50, 30))


def _line(p0, v, n):
    return np.array(p0, float) + np.outer(np.arange(n), v)


def _identities(frames, tracker):
    """gt index -> list of reported ids matched by IoU >= 0.5, and reported boxes on no gt."""
    tracker.reset()
    ids: dict[int, list[int]] = {}
    unmatched = 0
    for img, label, dets, gt in frames:
        rep = [t for t in tracker.update(img, dets, label > 0) if t.state.reported]
        if not rep:
            continue
        iou = iou_matrix(gt, np.array([t.box for t in rep]))
        r, c = linear_sum_assignment(-iou)
        good = {(i, j) for i, j in zip(r, c) if iou[i, j] >= 0.5}
        for i, j in good:
            ids.setdefault(int(i), []).append(rep[j].id)
        unmatched += len(rep) - len(good)
    return ids, unmatched


def test_small_crossing_keeps_both_ids_baseline_fragments():
    frames = _scene([_line((50, 150), (1.5, 0), 150), _line((270, 152), (-1.5, 0), 150)],
                    [RED, BLUE])
    assert min(len(f[2]) for f in frames) == 1  # somebody really disappears
    ids, _ = _identities(frames, RetaTracker())
    assert {k: len(set(v)) for k, v in ids.items()} == {0: 1, 1: 1}
    assert ids[0][0] != ids[1][0]
    base, _ = _identities(frames, BaselineTracker())
    assert max(len(set(v)) for v in base.values()) > 1


def test_isolated_false_positives_never_become_confirmed_tracks():
    # one false positive every 4 frames, anywhere: isolated in time (beyond
    # tentative_misses) though they all look alike (background)
    rng = np.random.default_rng(3)
    fps = {t: [[rng.uniform(0, W - 30), rng.uniform(0, H - 80), 30, 80]] for t in range(0, 60, 4)}
    frames = _scene([_line((40, 150), (2, 0), 60)], [RED], fps=fps)
    tracker = RetaTracker()
    confirmed_ids = set()
    tentative_seen = 0
    for img, label, dets, gt in frames:
        for t in tracker.update(img, dets, label > 0):
            if t.state == TrackState.CONFIRMED:
                confirmed_ids.add(t.id)
                assert iou_matrix(t.box[None], gt)[0, 0] > 0.5
            tentative_seen += t.state == TrackState.TENTATIVE
    assert confirmed_ids == {1}
    assert tentative_seen > 0  # false positives did start tentative tracks
    # the baseline reports unconfirmed tracks during its warm-up: the false positive of frame 0
    _, base_fp = _identities(frames, BaselineTracker())
    _, reta_fp = _identities(frames, RetaTracker())
    assert base_fp > 0 and reta_fp == 0


def _by_id(tracks, track_id):
    return [t for t in tracks if t.id == track_id]


def test_person_detected_half_behind_another_keeps_its_measured_size():
    # A stands still; its detected width shrinks 0.5 px a frame (a size rate) until B, nearer
    # the camera, walks half in front of it; from then on A is measured at a constant 30 px.
    # A person behind another once took its size from the bare prediction, whose size rate
    # nothing corrected: A kept shrinking under a constant measurement.
    n = 42  # A is detected (at least 30 % visible) in every frame
    frames = _scene([_line((150, 150), (0, 0), n), _line((70, 153), (1.8, 0), n)], [RED, BLUE])
    tracker = RetaTracker()
    behind, widths = 0, []
    for t, (img, label, dets, gt) in enumerate(frames):
        boxes = dets.boxes.copy()
        a = int(np.argmin(np.abs(boxes[:, 0] - 135) + np.abs(boxes[:, 1] - 70)))
        w = 30 + 0.5 * max(0, 31 - t)
        boxes[a] = [150 - w / 2, 70, w, 80]
        out = tracker.update(img, Detections(boxes, dets.scores), label > 0)
        if t < 5:
            continue
        if t == 5:
            (mine,) = [x for x in out if iou_matrix(x.box[None], boxes[a][None])[0, 0] > 0.5]
            a_id = mine.id
        (mine,) = _by_id(out, a_id)
        assert mine.state == TrackState.CONFIRMED
        if t > 31:
            behind += mine.extra["depth"] > 0
            widths.append(mine.box[2])
    assert behind >= 5  # A really was matched behind B
    assert max(abs(np.array(widths) - 30)) < 2.0, widths


def test_hypothesis_in_plain_view_is_reported_briefly_then_only_drawn_and_keeps_the_id():
    # a lone walker's detections stop at frame 20 (it stepped behind the scenery) and come
    # back at frame 27: no visible person covers its hypotheses, so after report_exposed
    # frames they are contradicted (only drawn); the person keeps its id when found again.
    # (The scene's mask still holds the walker, which foreground_presence would take as the
    # person being there, undetected: off here, as behind real scenery.)
    frames = _scene([_line((40, 150), (2, 0), 40)], [RED])
    tracker = RetaTracker(life_cycle=LifeCycle(m=8),
                          adaptations=Adaptations(report_exposed=2, foreground_presence=False))
    states = []
    for t, (img, label, dets, gt) in enumerate(frames):
        if 20 <= t < 27:
            dets = Detections(np.zeros((0, 4)), np.zeros(0))
        out = tracker.update(img, dets, label > 0)
        assert {x.id for x in out} == {1} or t < 2
        states.append([x.state for x in out])
    hidden = states[20:27]
    assert [TrackState.OCCLUDED in s for s in hidden] == [True, True] + [False] * 5
    assert all(TrackState.HYPOTHESIS in s for s in hidden[2:])  # still in the graph
    assert states[27] == [TrackState.CONFIRMED]  # re-found with its id (1)
    with pytest.raises(ValueError, match="report_exposed"):
        Adaptations(report_exposed=-1)


def test_a_hidden_person_is_reported_only_on_enough_foreground():
    # the same walker undetected in frames 20-23, its mask kept at half its height there
    # (the legs only): report_support 0.4 reports its hypothesis (ellipse about half
    # foreground), 0.7 does not; both keep the id (1) when it is found again
    frames = _scene([_line((40, 150), (2, 0), 30)], [RED])

    def hidden_reports(support: float) -> list[bool]:
        tracker = RetaTracker(adaptations=Adaptations(report_support=support))
        out_states = []
        for t, (img, label, dets, gt) in enumerate(frames):
            fg = label > 0
            if 20 <= t < 24:
                dets = Detections(np.zeros((0, 4)), np.zeros(0))
                rows = np.flatnonzero(fg.any(axis=1))
                fg[rows[: len(rows) // 2]] = False  # the upper half gone
            out = tracker.update(img, dets, fg)
            assert {x.id for x in out} == {1} or t < 2
            if 20 <= t < 24:
                out_states.append(any(x.state == TrackState.OCCLUDED for x in out))
        return out_states

    assert hidden_reports(0.4) == [True] * 4
    assert hidden_reports(0.7) == [False] * 4
    with pytest.raises(ValueError, match="report_support"):
        Adaptations(report_support=1.5)


# --------------------------------------------------------------------------- synthetic suite


def _suite_run(name: str, tracker):
    from occbench.datasets.synthetic import load_scenario
    from occbench.sources.annotations import NoisyGroundTruth

    seq = load_scenario(name)
    src = NoisyGroundTruth(seed=0)
    src.start(seq)
    ids: dict[int, set[int]] = {}
    winners: list[str] = []
    previous: dict[int, dict] = {}
    for k in range(1, seq.info.length + 1):
        frame = seq.frame(k)
        dets, _ = src.detect(k, frame)
        out = [t for t in tracker.update(frame, dets, seq.foreground(k)) if t.state.reported]
        if hasattr(tracker, "graph_snapshot"):
            snap = tracker.graph_snapshot()
            for n in snap["nodes"]:  # which hypothesis a re-found person came back through
                parent = previous.get(n["parent"])
                if n["kind"] == "visible" and parent is not None and parent["hypothesis"]:
                    winners.append(parent["hypothesis"])
            previous = {n["node"]: n for n in snap["nodes"]}
        rows = seq.gt.rows_of(k)
        if not len(rows) or not out:
            continue
        iou = iou_matrix(seq.gt.table.boxes[rows], np.array([t.box for t in out]))
        r, c = linear_sum_assignment(-iou)
        for i, j in zip(r, c):
            if iou[i, j] >= 0.5:
                ids.setdefault(int(seq.gt.table.ids[rows[i]]), set()).add(out[j].id)
    return ids, winners


@pytest.mark.parametrize(
    "scenario, hypothesis",
    [("crossing", None), ("stop_behind", "still"), ("follow_occluder", "occluder")],
)
def test_suite_scenarios_keep_ids_through_the_right_hypothesis(scenario, hypothesis):
    ids, winners = _suite_run(scenario, RetaTracker())
    assert len(ids) == 2
    assert all(len(v) == 1 for v in ids.values()), ids  # no fragment, no switch
    assert len(set.union(*ids.values())) == 2
    if hypothesis is not None:
        assert hypothesis in winners, winners
    else:
        assert set(winners) <= {"velocity"}
    base, _ = _suite_run(scenario, BaselineTracker())
    assert any(len(v) > 1 for v in base.values()), base  # the baseline loses someone


# --------------------------------------------------------------------------- graph output


def test_graph_snapshot_export_and_drawing(tmp_path):
    from occbench.report.graph import GraphRecorder, draw_graph, read_graph_csv

    frames = _scene([_line((50, 150), (1.5, 0), 110), _line((270, 152), (-1.5, 0), 110)],
                    [RED, BLUE])
    tracker = RetaTracker(adaptations=Adaptations(early_confirm=0))  # tentative nodes too
    rec = GraphRecorder("crossing")
    kinds = set()
    hyp_snapshot = None
    for k, (img, label, dets, gt) in enumerate(frames, start=1):
        tracker.update(img, dets)
        snap = tracker.graph_snapshot()
        rec.add(snap, frame=k)
        kinds |= {n["kind"] for n in snap["nodes"]}
        if any(n["kind"] == "hypothesis" for n in snap["nodes"]):
            hyp_snapshot = (img, snap)
        node_keys = {n["node"] for n in snap["nodes"]}
        assert all(e["target"] in node_keys for e in snap["edges"])
    assert kinds == {"visible", "tentative", "hypothesis"}
    files = rec.write(tmp_path / "crossing.csv")
    nodes, edges = read_graph_csv(tmp_path / "crossing.csv")
    assert [f.name for f in files] == ["crossing_nodes.csv", "crossing_edges.csv"]
    assert len(nodes) == len(rec.nodes) and len(edges) == len(rec.edges)
    assert {"frame", "id", "kind", "hypothesis", "xc", "yc", "rx", "ry", "occluder"} <= set(nodes[0])
    rec.write(tmp_path / "crossing.json")
    doc = json.loads((tmp_path / "crossing.json").read_text())
    assert len(doc["nodes"]) == len(nodes)
    img, snap = hyp_snapshot
    drawn = draw_graph(img, snap)
    assert drawn.shape == img.shape and (drawn != img).any()
    # a hypothesis is dashed: it paints fewer pixels than the same node drawn solid
    node = next(n for n in snap["nodes"] if n["kind"] == "hypothesis")
    blank = np.zeros_like(img)
    dashed = (draw_graph(blank, {"nodes": [{**node, "id": 1}]}) != 0).any(axis=2).sum()
    solid = (draw_graph(blank, {"nodes": [{**node, "id": 1, "kind": "visible",
                                           "hypothesis": ""}]}) != 0).any(axis=2).sum()
    assert dashed < solid
    with pytest.raises(ValueError, match="suffix"):
        rec.write(tmp_path / "x.txt")


def test_memory_stays_flat_over_a_long_run():
    """10,000 frames of people entering, crossing and leaving plus false positives."""
    w, h = 96, 64
    rng = np.random.default_rng(5)
    frame = np.full((h, w, 3), 80, np.uint8)
    frame[:, ::2] = 120
    tracker = RetaTracker(Association(mu_g=20.0))
    most_nodes = most_persons = 0
    for t in range(10_000):
        phase = t % 100
        boxes = []
        if phase < 40:
            boxes.append([2.5 * phase - 10, 10, 8, 20])  # walks left to right and leaves
            boxes.append([w - 2.5 * phase, 30, 8, 20])  # walks right to left and leaves
        if rng.random() < 0.05:
            boxes.append([rng.uniform(0, w - 8), rng.uniform(0, h - 20), 8, 20])
        dets = Detections(np.array(boxes, float).reshape(-1, 4), np.ones(len(boxes)))
        tracker.update(frame, dets)
        most_nodes = max(most_nodes, tracker.graph.node_count)
        most_persons = max(most_persons, len(tracker.memory.persons))
    assert most_persons <= 12
    assert most_nodes <= (tracker.life_cycle.m + 1) * 3 * most_persons
    assert len(tracker.memory.pi) <= 4 * most_persons**2 + 16


def test_record_sequence_writes_graph_beside_tracks_and_draws_frames(tmp_path):
    from occbench.datasets.base import Sequence
    from occbench.replay.graph import record_sequence
    from occbench.trackers.records import SequenceInfo

    frames = _scene([_line((50, 150), (1.5, 0), 40), _line((120, 152), (-1.5, 0), 40)],
                    [RED, BLUE])

    class Tiny(Sequence):
        info = SequenceInfo("tiny", W, H, 25.0, len(frames))

        def frame(self, index):
            return frames[index - 1][0]

    class Exact:
        def start(self, sequence):
            pass

        def detect(self, index, frame):
            return frames[index - 1][2], frames[index - 1][1] > 0

    files = record_sequence(RetaTracker(), Tiny(), Exact(), tmp_path / "tracks" / "tiny_graph.json",
                            frames_dir=tmp_path / "frames", every=10)
    assert files[0].name == "tiny_graph.json"
    assert [f.name for f in files[1:]] == ["000001.png", "000011.png", "000021.png", "000031.png"]
    doc = json.loads(files[0].read_text())
    assert {n["frame"] for n in doc["nodes"]} == set(range(1, 41))
    with pytest.raises(TypeError, match="graph"):
        record_sequence(BaselineTracker(), Tiny(), Exact(), tmp_path / "x.json")


GREEN = ((40, 180, 40), (30, 110, 30))
YELLOW = ((40, 200, 220), (30, 120, 140))


def test_crowd_crossing_keeps_every_id_where_the_baseline_switches():
    """Two pairs walking in opposite directions cross in the middle of the scene, each
    person hidden or half hidden for several frames by the ones in front: reta keeps one id
    per person (its hypotheses carry the hidden ones through), the baseline does not."""
    n = 120
    paths = [_line((30, 140), (2.0, 0), n), _line((10, 165), (2.0, 0), n),
             _line((290, 150), (-2.0, 0), n), _line((310, 175), (-2.0, 0), n)]
    frames = _scene(paths, [RED, BLUE, GREEN, YELLOW])
    assert min(len(f[2]) for f in frames) < 4  # people really disappear in the crossing
    ids, unmatched = _identities(frames, RetaTracker())
    assert {k: len(set(v)) for k, v in ids.items()} == {0: 1, 1: 1, 2: 1, 3: 1}
    assert len({v[0] for v in ids.values()}) == 4
    base, _ = _identities(frames, BaselineTracker())
    assert max(len(set(v)) for v in base.values()) > 1
