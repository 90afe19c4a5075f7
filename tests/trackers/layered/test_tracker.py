"""PBM tracker (occbench.trackers.layered): models, layers, dynamics, search and behaviour on scenes."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pbm_scenes as S
import pytest
import yaml
from hydra.utils import instantiate

from occbench.config.meta import without_meta
from occbench.trackers.baseline import BaselineTracker
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.layered import (
    Adaptations,
    CandidateParams,
    FeatureModels,
    FeatureParams,
    HiddenEvidence,
    LifeCycleParams,
    MatchParams,
    PBMTracker,
    PruneParams,
    StaleParts,
    load_feature_models,
)
from occbench.trackers.layered.association import ambiguous, layered_scores
from occbench.trackers.layered.dynamics import Gate
from occbench.trackers.layered.feature_models import (
    FoldedMixture,
    fit_difference_model,
    fit_half_normal,
    save_feature_models,
)
from occbench.trackers.layered.parts import FEATURES, N_PARTS, PartFeatureExtractor
from occbench.trackers.layered.search import (
    occlusion_kind,
    search_boxes,
    search_boxes_many,
    top_profile_heads,
)
from occbench.trackers.layered.targets import Targets
from occbench.trackers.records import Detections, TrackState
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[3]


def run(tracker, scene, hidden=None, use_fg=True, min_visible=0.5):
    """Per gt id: the list of reported track ids matched with IoU >= 0.5, per frame."""
    matched: dict[int, list[int]] = {}
    outputs = []
    for k in range(scene.length):
        img, lab = scene.render(k)
        det = scene.detections(k, lab, min_visible, hidden(k) if hidden else None)
        tracks = tracker.update(img, det, lab if use_fg else None)
        outputs.append(tracks)
        rep = [t for t in tracks if t.state.reported]
        for gid, gb in scene.gt(k).items():
            if not rep:
                continue
            iou = iou_matrix(gb[None], np.array([t.box for t in rep]))[0]
            j = int(np.argmax(iou))
            if iou[j] >= 0.5:
                matched.setdefault(gid, []).append(rep[j].id)
    return matched, outputs


# ---------------------------------------------------------------- configuration, input


def test_imports_from_this_repository():
    import occbench.trackers.layered

    assert Path(occbench.trackers.layered.__file__).resolve().is_relative_to(ROOT)


def test_config_instantiates_with_shipped_models_and_is_in_all():
    cfg = without_meta(OmegaConf.load(ROOT / "conf" / "tracker" / "pbm.yaml"))
    tracker = instantiate(cfg)
    assert isinstance(tracker, PBMTracker)
    assert "synthetic" in tracker.features.models.description
    all_cfg = yaml.safe_load((ROOT / "conf" / "tracker" / "all.yaml").read_text())
    assert "pbm@pbm" in all_cfg["defaults"]


def test_shipped_models_header_says_synthetic():
    text = (ROOT / "trackers" / "layered" / "data" / "default_models.yaml").read_text()
    assert text.startswith("#") and "synthetic" in text.splitlines()[1]


def test_bad_input_raises_clear_errors():
    t = PBMTracker()
    with pytest.raises(ValueError, match="frame is None"):
        t.update(None, Detections.empty())
    with pytest.raises(ValueError, match="foreground shape"):
        t.update(np.zeros((20, 30, 3), np.uint8), Detections.empty(), np.zeros((5, 5), bool))
    with pytest.raises(ValueError, match="matching.margin_ratio"):
        PBMTracker(matching=MatchParams(margin_ratio=0.5))
    with pytest.raises(ValueError, match=r"^matching\.weak_threshold must be <= matching\.match"):
        MatchParams(weak_threshold=0.3, match_threshold=0.2)
    with pytest.raises(ValueError, match="features.part_weights"):
        PBMTracker(features=FeatureParams(part_weights=[1, 1, 1, 1]))
    with pytest.raises(ValueError, match="unknown features"):
        PBMTracker(features=FeatureParams(feature_weights={"colour": 1.0}))
    with pytest.raises(ValueError, match="adaptations.stale.frames"):
        Adaptations(stale=StaleParts(frames=0))
    with pytest.raises(TypeError, match="matching: expected a MatchParams"):
        PBMTracker(matching={"margin_ratio": 1.2})


def test_models_roundtrip_and_malformed_file(tmp_path):
    m = FeatureModels.default()
    path = tmp_path / "m.yaml"
    save_feature_models(m, path, "header line")
    back = load_feature_models(path)
    d = np.random.default_rng(0).uniform(0, 0.5, (3, len(FEATURES), N_PARTS))
    np.testing.assert_allclose(back.match_probability(d), m.match_probability(d), atol=1e-5)
    data = yaml.safe_load(path.read_text())
    del data["models"]["hsv"]["left_leg"]
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ValueError, match=r"m\.yaml: models\.hsv\.left_leg missing"):
        load_feature_models(path)
    with pytest.raises(ValueError, match="cannot read"):
        load_feature_models(tmp_path / "absent.yaml")


# ---------------------------------------------------------------- difference models (2.2)


def test_half_normal_fit_and_survival():
    rng = np.random.default_rng(0)
    d = np.abs(rng.normal(0, 0.2, 20000))
    m = fit_half_normal(d)
    assert m.sigmas[0] == pytest.approx(0.2, rel=0.03)
    assert m.survival(np.array(0.0)) == pytest.approx(1.0)
    # P(|X| >= sigma) = erfc(1 / sqrt 2)
    assert m.survival(np.array(0.2)) == pytest.approx(math.erfc(1 / math.sqrt(2)), rel=0.05)
    assert fit_difference_model(d).kind == "half_normal"


def test_mixture_chosen_where_differences_are_not_unimodal():
    rng = np.random.default_rng(1)
    d = np.abs(np.concatenate([rng.normal(0, 0.02, 3000), rng.normal(0.5, 0.05, 3000)]))
    m = fit_difference_model(d)
    assert m.kind == "mixture"
    np.testing.assert_allclose(np.sort(m.means), [0.0, 0.5], atol=0.03)
    np.testing.assert_allclose(m.weights, [0.5, 0.5], atol=0.05)
    x = np.linspace(0, 2, 4001)
    assert np.trapezoid(m.pdf(x), x) == pytest.approx(1.0, abs=1e-3)


def test_layered_scores_hand_case():
    unit = [FoldedMixture([1.0], [0.0], [1.0])] * N_PARTS
    models = FeatureModels({f: unit for f in FEATURES})
    omega = np.array([1, 1, 2, 2, 1, 3], float)  # normalised inside: sum 10
    gamma = np.array([3, 2, 2, 1, 2], float)  # sum 10
    d = np.zeros((len(FEATURES), N_PARTS))
    pj, p = layered_scores(models, d, omega, gamma)
    np.testing.assert_allclose(pj, 1.0)
    assert p == pytest.approx(1.0)
    d[5, 0] = 1e3  # the overlap of the head fails completely
    pj, p = layered_scores(models, d, omega, gamma)
    assert pj[0] == pytest.approx(1 - 0.3)  # eq. 12: 1 - omega_overlap
    assert p == pytest.approx(1 - 0.3 * 0.3)  # eq. 13: 1 - gamma_head * 0.3


def test_best_candidate_needs_threshold_and_margin():
    assert ambiguous(np.array([0.9, 0.3, -np.inf]), 0.5, 1.2) == (0, 1, False)
    assert ambiguous(np.array([0.6, 0.55]), 0.5, 1.2)[2] is True
    assert ambiguous(np.array([0.4, 0.3]), 0.5, 1.2) == (-1, -1, False)


# ---------------------------------------------------------------- dynamics and search (3, 3.1)


def test_gate_is_zero_order_and_doubles_after_a_miss():
    gate = Gate(speed_factor=3.0, min_fraction=0.5, miss_factor=2.0, growth=1.5, max_fraction=100.0)
    tg = Targets(gate, (0.5, 0.2, 0.5), (0.2, 0.02, 0.5), 4, 3, 4)
    ex = PartFeatureExtractor()
    ex.start(np.zeros((200, 300, 3), np.uint8), None)
    for k, x0 in enumerate((90.0, 150.0)):  # a moving target and a still one
        tg.add(k + 1, [x0 - 10, 0, x0, 50, 20, 100], 0.5, 0.5, ex.extract(np.array([[x0 - 10, 0, 20, 100]])), None)
    for x in (4.0, 8.0, 12.0, 16.0):
        tg.predict()
        tg.update(np.array([0]), [[90 + x - 10, 0, 90 + x, 50, 20, 100]], [True], [False], np.ones((1, 5)), 0.4)
    tg.predict()
    box = tg.gate_boxes()
    assert box[0, 0] + box[0, 2] / 2 == pytest.approx(106.0)  # centred on the last position
    assert box[1, 0] + box[1, 2] / 2 == pytest.approx(150.0)
    wh = np.array([[20.0, 100.0]])
    h0 = gate.half_sizes(tg.kf1.x[:1, 2:], wh, np.array([0]))[0]
    assert h0[0] > 10.0 + 3 * 3.0  # grows with the speed (about 4 px / frame)
    assert box[1, 2] / 2 == pytest.approx(10.0)  # the still target: min_fraction * w only
    np.testing.assert_allclose(gate.half_sizes(tg.kf1.x[:1, 2:], wh, np.array([1]))[0], 2 * h0)
    np.testing.assert_allclose(gate.half_sizes(tg.kf1.x[:1, 2:], wh, np.array([3]))[0], 2 * 1.5**2 * h0)
    tg.mark_missed(np.array([1]))
    assert tg.occluded_parts[1].all() and tg.misses[1] == 1
    tg.take([1])
    assert list(tg.id) == [2] and len(tg.kf1) == len(tg.parts) == len(tg.head_template) == 1


def test_occlusion_rule_and_search_sizes():
    wh = np.array([40.0, 100.0])
    assert occlusion_kind(np.array([55.0, 120.0]), wh, 0.5) == 0
    assert occlusion_kind(np.array([70.0, 100.0]), wh, 0.5) == 1
    assert occlusion_kind(np.array([40.0, 45.0]), wh, 0.5) == -1
    boxes = search_boxes(np.array([200.0, 30.0, 10.0]), wh, 0.5, 0.05, 2)
    assert len(boxes) == 25
    np.testing.assert_allclose(np.unique(boxes[:, 2]), 40 * (1 + 0.05 * np.arange(-2, 3)))
    np.testing.assert_allclose(np.unique(boxes[:, 3]), 100 * (1 + 0.05 * np.arange(-2, 3)))
    np.testing.assert_allclose(boxes[:, 1], 30.0)  # hanging from the head top
    np.testing.assert_allclose(boxes[:, 0] + 0.5 * boxes[:, 2], 200.0)  # xc on the head (eq. 1)


def test_batched_search_boxes_equal_the_single_ones():
    rng = np.random.default_rng(4)
    heads = rng.uniform(0, 300, (6, 3))
    wh = rng.uniform(10, 100, (6, 2))
    alpha = rng.uniform(0.1, 0.9, 6)
    many = search_boxes_many(heads, wh, alpha, 0.05, 2)
    for s in range(6):
        np.testing.assert_array_equal(many[s], search_boxes(heads[s], wh[s], alpha[s], 0.05, 2))


def test_two_heads_in_one_blob():
    mask = S.two_heads_blob()
    heads = top_profile_heads(mask, 12.0, 5.0)
    np.testing.assert_allclose(heads, [[19.5, 5.0], [54.5, 12.0]])
    single = np.zeros((60, 30), bool)
    single[10:60, :] = True
    single[0:10, 10:20] = True
    assert len(top_profile_heads(single, 7.0, 3.0)) == 1


# ---------------------------------------------------------------- behaviour on scenes


def test_uturn_behind_keeps_the_id_and_baseline_does_not():
    scene, (uturner,) = S.uturn_behind()[0], tuple(S.uturn_behind()[1])
    pbm, _ = run(PBMTracker(), scene)
    base, _ = run(BaselineTracker(), scene)
    assert set(pbm[uturner]) == {pbm[uturner][0]}  # one id before and after the u-turn
    assert len(pbm[uturner]) >= 55  # found before and after the occlusion
    assert len(set(pbm[2])) == 1
    assert len(set(base[uturner])) > 1  # the constant-velocity baseline fragments


def test_uturn_without_foreground_uses_detection_boxes():
    scene, _ = S.uturn_behind()
    pbm, _ = run(PBMTracker(), scene, use_fg=False)
    assert len(set(pbm[1])) == 1 and len(set(pbm[2])) == 1


def test_two_people_in_one_blob_are_kept_by_their_heads():
    scene = S.merge_pair()
    merged = range(25, 56)

    def hidden(k: int) -> set[int]:
        return {1, 2} if k in merged else set()  # no detections at all while merged

    lab = scene.render(40)[1]
    n, _ = cv2.connectedComponents((lab != 0).astype(np.uint8))
    assert n == 2  # background + one blob holding both people
    pbm, _ = run(PBMTracker(), scene, hidden)
    base, _ = run(BaselineTracker(), scene, hidden)
    for gid in (1, 2):
        assert len(set(pbm[gid])) == 1
        assert len(pbm[gid]) == scene.length  # located in every frame, merged ones included
    assert pbm[1][0] != pbm[2][0]
    assert len(set(base[1])) > 1 or len(base[1]) < scene.length - 20


def test_a_hidden_part_is_frozen_while_hidden():
    scene, (h0, h1) = S.legs_behind_wall()
    tracker = PBMTracker()
    snap = {}
    legs_flag = []
    for k in range(scene.length):
        img, lab = scene.render(k)
        out = tracker.update(img, scene.detections(k, lab, 0.0), lab)
        m = tracker.targets.parts  # row 0: the only target
        assert len(m) == len(tracker.targets)  # one parts model per target
        if k in (h0 + 2, h1 - 2):
            snap[k] = (m.hsv[0].copy(), m.xyz[0].copy(), m.area[0].copy())
        if h0 + 2 <= k <= h1 - 2:
            legs_flag.append(out[0].extra["occluded_parts"].copy())
    assert out[0].extra["parts"].shape == (5, 4)
    a, b = snap[h0 + 2], snap[h1 - 2]
    for arr_a, arr_b in zip(a, b):
        np.testing.assert_array_equal(arr_a[3:], arr_b[3:])  # both legs frozen
    assert np.abs(a[0][:3] - b[0][:3]).sum() > 0  # head and torso kept updating
    legs_flag = np.array(legs_flag)
    assert legs_flag[:, 3:].all() and not legs_flag[:, :3].any()


def test_deterministic():
    scene, _ = S.uturn_behind(40)
    outs = []
    for _ in range(2):
        _, o = run(PBMTracker(), scene)
        outs.append([(t.id, t.state, tuple(np.round(t.box, 9))) for f in o for t in f])
    assert outs[0] == outs[1]


def test_tentative_before_confirmation():
    scene, _ = S.uturn_behind(12)
    tracker = PBMTracker(life_cycle=LifeCycleParams(min_hits=3), adaptations=Adaptations(early_confirm=2))
    states = []
    for k in range(8):
        img, lab = scene.render(k)
        if k < 4:  # nobody visible at first: the tracker starts after the sequence start
            img, lab = scene.background(), np.zeros_like(lab)
            det = Detections.empty()
        else:
            det = scene.detections(k, lab)
        states.append({t.state for t in tracker.update(img, det, lab)})
    assert states[4] == {TrackState.TENTATIVE} and states[6] == {TrackState.CONFIRMED}
    # adaptations.early_confirm 1: the lone newcomers are reported from their first frame
    born = PBMTracker(life_cycle=LifeCycleParams(min_hits=3), adaptations=Adaptations(early_confirm=1))
    for k in range(5):
        img, lab = scene.render(k)
        if k < 4:
            img, lab, det = scene.background(), np.zeros_like(lab), Detections.empty()
        else:
            det = scene.detections(k, lab)
        first = {t.state for t in born.update(img, det, lab)}
    assert first == {TrackState.CONFIRMED}


def test_synthetic_uturn_behind_beats_baseline():
    synthetic = pytest.importorskip("occbench.datasets.synthetic")
    from occbench.pipeline.loop import run_sequence
    from occbench.pipeline.record import score
    from occbench.sources.annotations import NoisyGroundTruth

    seq = synthetic.load_scenario("uturn_behind", seed=0, length=150)
    out = run_sequence({"pbm": PBMTracker(), "baseline": BaselineTracker()}, seq,
                       NoisyGroundTruth(seed=0))
    s_pbm = score(seq.gt, out["pbm"].table).row()
    s_base = score(seq.gt, out["baseline"].table).row()
    assert s_pbm["IDs"] == 0 and s_base["IDs"] + s_base["Frag"] > 0
    assert s_pbm["IDF1"] > s_base["IDF1"]


def test_drawing_parts_marks_frozen_parts():
    from occbench.report.draw import draw_tracks
    from occbench.report.parts import draw_parts
    from occbench.trackers.records import Track

    img = np.zeros((100, 100, 3), np.uint8)
    parts = np.array([[40, 10, 20, 10], [40, 20, 10, 30], [50, 20, 10, 30], [40, 50, 10, 40],
                      [50, 50, 10, 40]], float)
    t = Track(3, np.array([40.0, 10, 20, 80]), extra={
        "parts": parts, "occluded_parts": np.array([0, 0, 0, 1, 1], bool)})
    out = draw_parts(img.copy(), [t], tint=0.0)
    assert out[10, 45:56].any() and out[20, 40:60].any()  # solid head and torso edges
    legs_edge = out[90, 40:61].any(axis=1)  # bottom edge of the frozen legs: dashed
    assert 0 < legs_edge.sum() < 21
    via = draw_tracks(img, [t], "parts")
    assert via.shape == img.shape and via.any()


def test_fit_command_writes_models_and_plot(tmp_path):
    pytest.importorskip("occbench.datasets.synthetic")
    from occbench.commands.fit import main

    out, png = tmp_path / "m.yaml", tmp_path / "m.png"
    assert main(["pbm", "--synthetic", "crossing", "--length", "12", "--out", str(out),
                 "--plot", str(png)]) == 0
    models = load_feature_models(out)
    assert "crossing" in models.description and png.stat().st_size > 1000
    assert out.read_text().startswith("# PBM feature-difference models")


def test_detection_heads_are_used_when_given():
    t = PBMTracker()
    boxes = np.array([[10.0, 20, 30, 90], [60.0, 20, 30, 90]])
    heads = np.array([[18.0, 22, 12, 12], [np.nan] * 4])
    fg = np.zeros((150, 120), bool)
    fg[25:110, 68:82] = True  # second person: its top 1/7 band has foreground from row 25
    anchors = t._finder.find(fg, Detections(boxes, np.ones(2), heads=heads))
    np.testing.assert_allclose(anchors.head[0], [24.0, 22.0, 12.0])  # from Detections.heads
    assert anchors.head[1, 1] == 25 and anchors.head[1, 0] == pytest.approx(75.0)
    assert len(anchors) == 2 and not anchors.blob.any()


def test_head_detector_fills_missing_heads():
    class Fixed:
        def detect(self, frame, foreground, boxes):
            return np.array([[12.0, 21, 10, 10]] * len(boxes))

    t = PBMTracker(candidates=CandidateParams(head_detector=Fixed()))
    anchors = t._finder.find(None, Detections(np.array([[10.0, 20, 30, 90]]), np.ones(1)),
                         np.zeros((150, 120, 3), np.uint8))
    np.testing.assert_allclose(anchors.head[0], [17.0, 21.0, 10.0])
    with pytest.raises(ValueError, match="candidates.head_detector"):
        CandidateParams(head_detector=object())


def test_blobs_equal_opencv_default_labelling():
    from occbench.trackers.layered.search import blobs_boxes

    rng = np.random.default_rng(5)
    fg = cv2.dilate((rng.random((120, 160)) < 0.02).astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    labels, boxes, numbers = blobs_boxes(fg, 10)
    _, ref_labels, stats, _ = cv2.connectedComponentsWithStats(fg.view(np.uint8), connectivity=8)
    np.testing.assert_array_equal(labels, ref_labels)
    keep = np.nonzero(stats[1:, cv2.CC_STAT_AREA] >= 10)[0] + 1
    assert len(keep) > 3
    np.testing.assert_array_equal(numbers, keep)
    np.testing.assert_array_equal(boxes, stats[keep, :4])


def test_constant_velocity_filter_equals_matrix_form_and_filterpy():
    from filterpy.kalman import KalmanFilter
    from occbench.trackers.layered.dynamics import ConstantVelocity2D

    rng = np.random.default_rng(6)
    kf = ConstantVelocity2D(0.5, 0.2, 0.5)
    kf.add(np.array([7.0, -3.0]), 30.0)  # a second filter, never updated: rows stay apart
    kf.add(np.array([50.0, 80.0]), 12.0)
    F = np.array([[1.0, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1]])
    H = np.eye(2, 4)
    x, P = kf.state(1)
    Q = np.diag([0.5**2] * 2 + [0.2**2] * 2) * 144.0
    R = np.eye(2) * 0.5**2 * 144.0
    fp = KalmanFilter(dim_x=4, dim_z=2)
    fp.F, fp.H, fp.Q, fp.R = F, H, Q, R
    fp.x, fp.P = x.reshape(4, 1).copy(), P.copy()
    for _ in range(40):
        # the matrix form: equal to rounding
        kf.predict()
        x, P = F @ x, F @ P @ F.T + Q
        fp.predict()
        np.testing.assert_allclose(kf.state(1)[0], x, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(kf.state(1)[1], P, rtol=1e-12, atol=1e-12)
        z = x[:2] + rng.normal(0, 5, 2)
        kf.update(np.array([1]), z[None])
        S = P[:2, :2] + R
        det = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
        K = P[:, :2] @ (np.array([[S[1, 1], -S[0, 1]], [-S[1, 0], S[0, 0]]]) / det)
        x, P = x + K @ (z - x[:2]), P - K @ P[:2, :]
        fp.update(z.reshape(2, 1))
        np.testing.assert_allclose(kf.state(1)[0], x, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(kf.state(1)[1], P, rtol=1e-12, atol=1e-12)
        # filterpy (Joseph-form covariance update): equal up to rounding
        np.testing.assert_allclose(kf.state(1)[0], fp.x[:, 0], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(kf.state(1)[1], fp.P, rtol=1e-9, atol=1e-9)
    assert abs(kf.x[1, 2]) + abs(kf.x[1, 3]) > 0  # the rates moved
    np.testing.assert_array_equal(kf.x[0], [7.0, -3.0, 0.0, 0.0])  # predicted only: still


def test_selected_differences_equal_the_all_pairs_ones():
    from occbench.trackers.layered.association import feature_differences, selected_differences
    from occbench.trackers.layered.parts import PartFeatureExtractor

    rng = np.random.default_rng(8)
    frame = rng.integers(0, 256, (200, 300, 3), dtype=np.uint8)
    ex = PartFeatureExtractor()
    ex.start(frame, rng.random((200, 300)) < 0.6)
    model = ex.extract(np.column_stack([rng.uniform(0, 250, (6, 2)), rng.uniform(10, 80, (6, 2))]), 0.4, 0.5)
    cand = ex.extract(np.column_stack([rng.uniform(0, 250, (7, 2)), rng.uniform(10, 80, (7, 2))]), 0.5, 0.6)
    misses = rng.integers(0, 3, 6)
    ti, n = np.nonzero(rng.random((6, 7)) < 0.4)
    np.testing.assert_array_equal(selected_differences(model, cand, ti, n, misses),
                                  feature_differences(model, cand, misses)[ti, n])


def test_bool_and_label_foreground_give_the_same_tracks():
    # a bool mask is used as is (made contiguous); a label image is compared with 0
    scene = S.merge_pair()
    a, b = PBMTracker(), PBMTracker()
    for k in range(25):
        img, lab = scene.render(k)
        det = scene.detections(k, lab, 0.5)
        ta = a.update(img, det, lab)
        tb = b.update(img, det, np.asfortranarray(lab != 0))
        assert [(t.id, tuple(t.box), t.state) for t in ta] == [(t.id, tuple(t.box), t.state) for t in tb]


def test_update_parts_equals_the_numpy_running_averages():
    from occbench.trackers.layered.parts import part_boxes
    from occbench.trackers.layered.targets import PartMatches, PartRates, update_parts

    rng = np.random.default_rng(11)
    ex = PartFeatureExtractor()
    ex.start(rng.integers(0, 255, (120, 160, 3), dtype=np.uint8), rng.random((120, 160)) < 0.6)
    boxes = np.column_stack([rng.uniform(-10, 120, 9), rng.uniform(-10, 60, 9), rng.uniform(8, 40, 9),
                             rng.uniform(20, 80, 9)])
    model, cand = ex.extract(boxes[:6], 0.5, 0.4), ex.extract(boxes, 0.45, 0.5)
    rows, ks = np.array([4, 0, 2]), np.array([8, 1, 3])
    pj = rng.random((3, 5))
    shift, new_boxes = rng.normal(0, 3, (3, 2)), boxes[[2, 5, 7]] + 1.5
    alpha, beta = rng.uniform(0.2, 0.8, 3), rng.uniform(0.2, 0.8, 3)
    ref = model.copy()
    matched = pj >= 0.4
    eta = np.where(matched, 0.3 * pj, 0.0)
    for name in ("area", "perimeter", "hsv", "xyz"):
        m, c = getattr(ref, name), getattr(cand, name)
        e = eta if m.ndim == 2 else eta[:, :, None]
        m[rows] += e * (c[ks] - m[rows])
    ref.centroid[rows] = np.where(matched[:, :, None], cand.centroid[ks], ref.centroid[rows] + shift[:, None])
    ref.parts[rows] = part_boxes(new_boxes, alpha, beta)
    ref.height[rows] = new_boxes[:, 3]
    update_parts(model, cand, PartMatches(rows, ks, pj, shift, new_boxes, alpha, beta),
                 PartRates(0.4, 0.3))
    for name in ("parts", "area", "perimeter", "hsv", "xyz", "centroid", "height"):
        np.testing.assert_array_equal(getattr(model, name), getattr(ref, name), err_msg=name)
    assert (matched.any() and (~matched).any())  # both branches ran


def test_occluded_update_averages_the_window_and_keeps_the_ratios():
    gate = Gate(3.0, 0.5, 2.0, 1.15, 4.0)
    tg = Targets(gate, (0.5, 0.2, 0.5), (0.2, 0.02, 0.5), 4, 3, 4)
    ex = PartFeatureExtractor()
    ex.start(np.zeros((200, 300, 3), np.uint8), None)
    dofs = [np.array([10.0 + 3 * k, 5, 30.0 + 3 * k, 60, 40, 120]) for k in range(4)]
    dofs[3][2] += 10.0  # alpha 0.75 if it were measured
    tg.add(1, dofs[0], 0.5, 0.5, ex.extract(np.array([[10, 5, 40, 120]])), None)
    for d in dofs[1:3]:
        tg.predict()
        tg.update([0], [d], [True], [False], np.ones((1, 5)), 0.4)
    alpha = tg.alpha[0]
    tg.predict()
    tg.update([0], [dofs[3]], [True], [True], np.ones((1, 5)), 0.4)
    np.testing.assert_allclose(tg.dof[0], np.mean(dofs[1:], axis=0))  # window of 3 (PBM 4.2)
    assert tg.alpha[0] == alpha and tg.occluded[0] and tg.hits[0] == 4


def test_row_norms_and_occluded_dofs_equal_their_scalar_forms_bit_for_bit():
    from occbench.trackers.layered.selection import _norms
    from occbench.trackers.layered.targets import dof_from_head, dofs_from_heads

    rng = np.random.default_rng(3)
    v = rng.normal(size=(500, 2)) * rng.uniform(0.1, 300.0, size=(500, 1))
    np.testing.assert_array_equal(_norms(v), [np.linalg.norm(r) for r in v])
    assert _norms(np.zeros((0, 2))).shape == (0,)
    heads = rng.uniform(0, 500, size=(50, 3))
    w, h, a, b = rng.uniform(5, 200, 50), rng.uniform(5, 400, 50), rng.random(50), rng.random(50)
    many = dofs_from_heads(heads, w, h, a, b)
    for k in range(50):
        hx, hy = heads[k, 0], heads[k, 1]
        hh = (1.0 / 7.0) * h[k]  # HEAD_FRACTION h (eq. 2)
        yc = hy + hh + b[k] * (h[k] - hh)
        np.testing.assert_array_equal(many[k], [hx - a[k] * w[k], hy, hx, yc, w[k], h[k]])
        np.testing.assert_array_equal(dof_from_head(heads[k], w[k], h[k], a[k], b[k]), many[k])


def test_gated_pairs_equal_the_numpy_gating():
    """The compiled gating (PBM 3), occlusion-test pairs (PBM 3.1) and lone growth against
    numpy expressions, on random scenes with many boundary cases."""
    from occbench.trackers.geometry import overlap_ratio_matrix
    from occbench.trackers.layered.gating import gated_pairs
    from occbench.trackers.layered.search import occlusion_kinds

    rng = np.random.default_rng(11)
    n_lone = 0
    for trial in range(40):
        T, N = int(rng.integers(0, 7)), int(rng.integers(0, 9))
        boxes = np.round(rng.uniform(0, 60, (N, 4)) * 2) / 2 + [0, 0, 5, 10]
        regions = np.where(rng.random((N, 1)) < 0.5, boxes, boxes * [1, 1, 2, 1.6])
        heads = np.column_stack([boxes[:, 0] + 0.5 * boxes[:, 2], boxes[:, 1], 0.3 * boxes[:, 2]])
        nh = rng.integers(1, 3, N)
        grown = nh + rng.integers(0, 2, N)  # candidates.HeldDetections' detections in the blob
        gates = np.round(rng.uniform(0, 60, (T, 4)) * 2) / 2 + [0, 0, 10, 20]
        pred = rng.uniform(5, 60, (T, 2))
        tboxes = np.round(rng.uniform(0, 60, (T, 4)) * 2) / 2 + [0, 0, 0, 5]
        tboxes[:1, 2] = 0.0  # an empty target box
        misses = rng.integers(0, 2, T)
        so = 0.0 if trial % 5 == 0 else 0.5
        kinds = occlusion_kinds(regions[:, 2:], pred, 0.5)
        dof = np.column_stack([tboxes[:, :2], tboxes[:, :2] + 0.5 * tboxes[:, 2:], tboxes[:, 2:]])
        present = rng.random(T) < (0.0 if trial % 4 == 0 else 0.8)
        merge_heads = trial % 3 != 1  # adaptations.several_heads_merge
        got = gated_pairs(boxes, regions, heads, nh, grown, gates, pred, kinds.copy(), dof, misses, so,
                          present, merge_heads)
        # the numpy reference
        if so > 0:  # lone growth: the one present target holding a one-head larger region
            holds = (overlap_ratio_matrix(tboxes, regions) >= so) & present[:, None]
            lone = holds & (holds.sum(0) == 1) & (grown == 1) & (kinds > 0)
            n_lone += lone.sum()
            kinds[lone] = 0
        c = boxes[:, :2] + 0.5 * boxes[:, 2:]
        g = gates[:, None]
        inside = ((c[:, 0] >= g[..., 0]) & (c[:, 0] <= g[..., 0] + g[..., 2])
                  & (c[:, 1] >= g[..., 1]) & (c[:, 1] <= g[..., 3] + g[..., 1]))
        merged = (nh > 1) & merge_heads
        kinds[:, merged] = np.where(kinds[:, merged] == 0, 1, kinds[:, merged])
        ti_in, n_in = np.nonzero(inside & (kinds == 0))
        hx, hy = heads[:, 0], heads[:, 1] + 0.5 * pred[:, 1, None]
        carved = ((g[..., 0] <= hx) & (hx <= g[..., 0] + g[..., 2])
                  & (g[..., 1] <= hy) & (hy <= g[..., 1] + g[..., 3]))
        ti_s, n_s = np.nonzero(inside & (kinds != 0) & carved)
        if so > 0 and len(ti_s):
            ratio = overlap_ratio_matrix(tboxes, regions)[ti_s, n_s]
            held = (kinds[ti_s, n_s] <= 0) | (misses[ti_s] > 0) | (ratio >= so)
            ti_s, n_s = ti_s[held], n_s[held]
        for a, b in zip(got, (ti_in, n_in, ti_s, n_s, kinds[ti_s, n_s])):
            np.testing.assert_array_equal(a, b)
    assert n_lone > 0


def test_assign_equals_the_numpy_gated_hungarian():
    """``assign``'s compiled gating against the numpy form it replaces (PBM's one-to-one
    step), on random matrices with ties, +-inf, NaN and every kind of gate."""
    from occbench.trackers.common.assignment import assign
    from scipy.optimize import linear_sum_assignment

    def reference(cost, max_cost):
        n, m = cost.shape
        if n == 0 or m == 0:
            return np.zeros((0, 2), dtype=int), np.arange(n), np.arange(m)
        allowed = np.isfinite(cost) & (cost <= max_cost)
        base = max_cost if np.isfinite(max_cost) else 0.0
        big = base + 1.0 + np.abs(np.where(allowed, cost, 0.0)).max() * (n + m)
        rows, cols = linear_sum_assignment(np.where(allowed, cost, big))
        keep = allowed[rows, cols]
        rows, cols = rows[keep], cols[keep]
        return (np.column_stack([rows, cols]), np.setdiff1d(np.arange(n), rows),
                np.setdiff1d(np.arange(m), cols))

    rng = np.random.default_rng(2)
    for t in range(400):
        n, m = (int(v) for v in rng.integers(0, 8, 2))
        cost = np.round(rng.random((n, m)) * 4) / 4 * rng.choice([1.0, -1.0, 100.0])
        for value, rate in ((np.inf, 0.3), (-np.inf, 0.05), (np.nan, 0.05)):
            cost[rng.random((n, m)) < rate] = value
        max_cost = [0.5, 0.75, np.inf, 0.0, 100.0][t % 5]
        for got, want in zip(assign(cost, max_cost), reference(cost, max_cost)):
            assert got.shape == want.shape
            np.testing.assert_array_equal(got, want)


def test_prune_equals_the_numpy_centre_radius_and_nearest_head():
    """``MultipleResponsePruning.match_template``'s scalar arithmetic (few heads) and numpy
    path (many) against the numpy form: mean centre, largest norm as radius, nearest head to the refined one."""
    from occbench.trackers.layered.search import head_patch, match_head_template

    rng = np.random.default_rng(4)
    frame = cv2.GaussianBlur(rng.integers(0, 256, (120, 160, 3), dtype=np.uint8), (5, 5), 0)
    t = PBMTracker(pruning=PruneParams(template_threshold=-1.0))  # every match counts: the refined head is used
    for K in [1, 2, 3, 5, 7, 8, 9, 12] * 3:
        heads = rng.uniform(20, 100, (K, 2))
        cands = rng.permutation(40)[:K]
        template = head_patch(frame, np.array([*rng.uniform(30, 90, 2), 18.0, 70.0]))
        tw = template.shape[1]
        centre = heads.mean(axis=0)
        radius = float(np.max(np.linalg.norm(heads - centre, axis=1))) + 0.5 * tw + 2
        tl, _ = match_head_template(frame, template, np.array([centre[0] - 0.5 * tw, centre[1]]), radius)
        refined = np.array([tl[0] + 0.5 * tw, tl[1]])
        nearest = cands[int(np.argmin(np.linalg.norm(heads - refined, axis=1)))]
        chosen, got = t._pruning.match_template(template, cands, heads, frame)
        assert chosen == nearest
        np.testing.assert_array_equal(got, refined)
    assert t._pruning.match_template(None, cands, heads, frame) == (-1, None)


def test_the_tracker_accepts_every_foreground_dtype():
    rng = np.random.default_rng(6)
    labels = rng.integers(0, 4, (30, 40)) * (rng.random((30, 40)) < 0.5)
    frame = rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)
    dets = Detections(np.array([[5.0, 2, 12, 26]]), np.ones(1))
    runs = []
    for fg in (labels != 0, labels.astype(np.int32), labels.astype(">i4"), labels * 0.5,
               np.asfortranarray(labels.astype(np.uint8)), (labels != 0)[:, ::-1][:, ::-1]):
        t = PBMTracker()
        runs.append([(tr.id, tuple(tr.box)) for _ in range(3) for tr in t.update(frame, dets, fg)])
    assert runs[0] and all(r == runs[0] for r in runs)


def test_matched_rows_and_alive_rows_equal_the_numpy_forms():
    from occbench.trackers.layered.model_update import alive_rows, matched_rows

    rng = np.random.default_rng(9)
    T, N, P = 6, 8, 5
    boxes, cents = rng.uniform(0, 200, (N, 4)), rng.uniform(0, 200, (N, 2))
    blob, pred, alpha = rng.random(N) < 0.5, rng.uniform(10, 80, (T, 2)), rng.random(T)
    pj_all = rng.random((T, N, N_PARTS))
    dof_h, pj_h, k_h = rng.uniform(0, 200, (P, 6)), rng.random((P, N_PARTS)), rng.integers(0, 50, P)
    hyp = np.full((T, N), -1, dtype=np.intp)
    hyp[rng.integers(0, T, P), rng.integers(0, N, P)] = np.arange(P)
    mt, mn = rng.permutation(T)[:5], rng.permutation(N)[:5]
    hyp[mt[0], mn[0]] = 2  # at least one occluded match
    dof, pj, occl, ks = matched_rows(mt, mn, hyp, boxes, cents, blob, pred, alpha, pj_all, dof_h, pj_h, k_h)
    q = hyp[mt, mn]
    want = np.column_stack([boxes[mn, :2], cents[mn], boxes[mn, 2:]])
    b = blob[mn] & (q < 0)
    want[b, 0] = cents[mn[b], 0] - alpha[mt[b]] * pred[mt[b], 0]
    want[b, 4] = pred[mt[b], 0]
    want[q >= 0] = dof_h[q[q >= 0]]
    np.testing.assert_array_equal(occl, q >= 0)
    np.testing.assert_array_equal(dof, want)
    np.testing.assert_array_equal(pj, np.where((q >= 0)[:, None], pj_h[q], pj_all[mt, mn]))
    np.testing.assert_array_equal(ks, np.where(q >= 0, k_h[q], mn))

    dof = rng.uniform(-20, 660, (40, 6))
    shift = rng.normal(0.0, 10.0, (40, 2))
    misses, confirmed = rng.integers(0, 5, 40), rng.random(40) < 0.6
    x, y, w, h = dof[:, 0] + shift[:, 0], dof[:, 1] + shift[:, 1], dof[:, 4], dof[:, 5]
    gone = (x < -8.0) | (y < -8.0) | (x + w > 640 + 8.0) | (y + h > 480 + 8.0)
    want = (misses == 0) | (confirmed & (misses <= 3) & ~(gone & (misses >= 2)))
    np.testing.assert_array_equal(alive_rows(dof, shift, misses, confirmed, 640, 480, 8.0, 3, 2), want)
    assert 0 < (confirmed & (misses >= 2) & gone).sum() and 0 < (confirmed & (misses >= 2) & ~gone).sum()


def test_carved_rows_equal_the_numpy_selection_of_searched_and_aligned_boxes():
    from occbench.trackers.layered.gating import carved_rows
    from occbench.trackers.layered.targets import dofs_from_heads

    rng = np.random.default_rng(12)
    m, P, T = 25, 7, 4
    search_q, align_q = np.array([0, 2, 3, 6]), np.array([1, 5])  # pair 4 dismissed
    K = len(search_q) * m + len(align_q)
    p = np.round(rng.random(K) * 8) / 8  # ties: the first maximum wins
    pj, boxes = rng.random((K, N_PARTS)), rng.uniform(5, 200, (K, 4))
    heads, ti = rng.uniform(0, 300, (P, 3)), rng.integers(0, T, P)
    alpha, beta = rng.random(T), rng.random(T)
    kept, p_h, pj_h, k, dof = carved_rows(p, pj, boxes, heads, ti, alpha, beta, search_q, align_q, m)
    ns = len(search_q)
    best = np.concatenate([np.argmax(p[:ns * m].reshape(ns, m), axis=1) + m * np.arange(ns),
                           ns * m + np.arange(len(align_q))])
    qs = np.concatenate([search_q, align_q])
    np.testing.assert_array_equal(kept, np.isin(np.arange(P), qs))
    np.testing.assert_array_equal(k[qs], best)
    np.testing.assert_array_equal(p_h[qs], p[best])
    np.testing.assert_array_equal(pj_h[qs], pj[best])
    np.testing.assert_array_equal(dof[qs], dofs_from_heads(heads[qs], boxes[best, 2], boxes[best, 3],
                                                           alpha[ti[qs]], beta[ti[qs]]))


def test_a_flickering_false_alarm_over_background_is_never_reported():
    """A detection box over empty background, present two frames of every three from the
    first frame on, beside one walking person: with foreground, pbm never reports it
    (it holds no foreground, PBM 2), and keeps the person; without the support rule
    (``min_support=0``) the same input starts and reports a false track."""
    scene = S.Scene(320, 240, [S.Person(1, S.walk(40, (40, 60), (2.0, 0.0), (30, 105)),
                                        shirt=(40, 40, 200), pants=(90, 60, 30))], seed=4)
    alarm = np.array([220.0, 40.0, 30.0, 100.0])

    def reported_alarm(tracker) -> tuple[int, set[int]]:
        hits, person_ids = 0, set()
        for k in range(scene.length):
            img, lab = scene.render(k)
            det = scene.detections(k, lab)
            if k % 3 != 2:
                det = Detections(np.vstack([det.boxes, alarm]), np.ones(len(det) + 1))
            for t in tracker.update(img, det, lab):
                if not t.state.reported:
                    continue
                if iou_matrix(t.box[None], alarm[None])[0, 0] > 0.3:
                    hits += 1
                if iou_matrix(t.box[None], scene.gt(k)[1][None])[0, 0] >= 0.5:
                    person_ids.add(t.id)
        return hits, person_ids

    hits, ids = reported_alarm(PBMTracker())
    assert hits == 0
    assert len(ids) == 1
    assert reported_alarm(PBMTracker(adaptations=Adaptations(min_support=0.0)))[0] > 0


def test_identities_kept_through_a_crowd_crossing_where_the_baseline_switches():
    """Two people walk side by side (the nearer one's detection missed every fourth
    frame) while a third crosses them: pbm keeps one id per person, found in every
    frame; the SORT-like baseline gives the farther walker a second id."""
    L = 60
    people = [
        S.Person(1, S.walk(L, (40, 60), (2.0, 0.0), (40, 120)), shirt=(40, 40, 200),
                 pants=(90, 60, 30), depth=1.0),
        S.Person(2, S.walk(L, (58, 56), (2.0, 0.0), (36, 110)), shirt=(40, 170, 40),
                 pants=(50, 50, 50), hair=(30, 90, 150), depth=2.0),
        S.Person(3, S.walk(L, (300, 60), (-2.0, 0.0), (38, 116)), shirt=(200, 120, 40),
                 pants=(40, 40, 90), depth=1.5),
    ]
    scene = S.Scene(360, 220, people, seed=6)

    def hidden(k: int) -> set[int]:
        return {1} if k % 4 == 3 else set()

    pbm, _ = run(PBMTracker(), scene, hidden=hidden, min_visible=0.3)
    base, _ = run(BaselineTracker(), scene, hidden=hidden, min_visible=0.3)
    for gid in (1, 2, 3):
        assert len(pbm[gid]) == L and len(set(pbm[gid])) == 1
    assert len({pbm[g][0] for g in (1, 2, 3)}) == 3
    assert len(set(base[2])) > 1


def test_paper_mode_turns_every_adaptation_off():
    """``tracker=pbm_paper`` composes pbm.yaml with each adaptation at the paper's value."""
    from occbench.config.build import compose_config
    from occbench.trackers.frontend.heads import HeadDetector

    paper = instantiate(without_meta(compose_config(["tracker=pbm_paper"]).tracker))
    ours = instantiate(without_meta(compose_config(["tracker=pbm"]).tracker))
    assert isinstance(paper, PBMTracker) and isinstance(paper.candidates.head_detector, HeadDetector)
    assert ours.candidates.head_detector is None
    a = paper.adaptations
    assert (a.model_spread, a.stale, a.min_support, a.relative_match) == (1.0, None, 0.0, 0.0)
    assert a.report_support == 0.0
    assert not (a.motion_compensation or a.report_predicted or a.lone_growth)
    assert a.prune_max_misses >= 10**6 and a.duplicate_radius < 0
    assert a.gate_max_fraction >= 10**6 and a.exit_margin >= 10**6
    assert a == Adaptations.paper() and a.changed() == []
    assert not (a.gap_division or a.hold_size or a.blob_box_ratio or a.several_heads_merge
                or a.profile_heads or a.one_to_one)
    assert ours.adaptations == Adaptations() and ours.adaptations != a
    # what the paper leaves open: ours
    for group in ("gate", "noise", "search", "matching", "pruning", "model_update", "life_cycle",
                  "reporting"):
        assert getattr(paper, group) == getattr(ours, group), group


def test_apart_undivided_reaches_the_trackers_scores_and_needs_gap_division():
    """``adaptations.apart_undivided``: off by default and in paper mode, passed to eq.
    11's kernels through the tracker's ``LayeredScores``; on only with ``gap_division``."""
    assert not PBMTracker()._scores.apart
    assert PBMTracker(adaptations=Adaptations(apart_undivided=True))._scores.apart
    assert "apart_undivided" not in Adaptations.paper().changed()
    assert "apart_undivided" not in Adaptations().changed()
    with pytest.raises(ValueError, match="apart_undivided"):
        Adaptations(gap_division=False, apart_undivided=True)


def test_adaptations_pick_the_papers_rule_when_off_and_ours_when_on():
    """``rules.build_rules``: paper mode's values select the paper's rule for each step."""
    from occbench.config.build import compose_config
    from occbench.trackers.layered import rules as R
    from occbench.trackers.layered.reupdate import AfterPrediction

    ours = R.build_rules(Adaptations())
    paper = R.build_rules(instantiate(without_meta(compose_config(["tracker=pbm_paper"]).tracker)).adaptations)
    assert [type(r) for r in ours] == [R.PredictedModels, R.RelativeMatch, R.ForegroundSupport,
                                       R.PredictedBox, R.PerFrame, R.HeldSize, R.OneToOne,
                                       HiddenEvidence, R.IsolatedEarly,
                                       AfterPrediction, R.NoContest, R.LoneShrink, R.FoundElsewhere,
                                       R.BorderExit, R.ReportAnywhere, R.KeepStacked,
                                       R.FilterPrediction, R.MissesBound, R.AllAtOnce,
                                       R.AsMatched, R.SizeOcclusion]
    # report_support, reupdate, contested_template, leaving_unreported, fold_twins,
    # measured_velocity, reported_behind, reported_first and contact_frozen off
    assert [type(r) for r in paper] == [R.LastModels, R.AnyAboveThreshold, R.AnyCandidate,
                                        R.LastBox, R.AsMeasured, R.PredictedSize, R.Alone,
                                        R.ReportUnfound, R.InARow, AfterPrediction, R.NoContest,
                                        R.OccludedSmaller, R.AllHolders, R.PredictedExit,
                                        R.ReportAnywhere,
                                        R.KeepStacked, R.FilterPrediction, R.MissesBound,
                                        R.AllAtOnce, R.AsMatched, R.SizeOcclusion]
    # relative match: target 0 matched at 0.8 last frame takes no 0.3 (< 0.5 x 0.8)
    tg = Targets(Gate(3.0, 0.5, 2.0, 1.15, 6.0), (0.5, 0.2, 0.5), (0.2, 0.02, 0.5), 4, 3, 4)
    tg.misses, tg.score = np.array([0, 3]), np.array([0.8, 0.9])
    S = np.array([[0.3, 0.7], [0.3, -np.inf]])
    withheld = ours.match.withhold(S, tg, 0.25)
    assert S[0, 0] == -np.inf and S[0, 1] == 0.7 and S[1, 0] == 0.3  # target 1 was unfound
    assert withheld.tolist() == [True, False]
    assert paper.match.withhold(S, tg, 0.25) is None
    # report support: a box 60% foreground is reported, 50% not; without a mask, any
    fg = np.zeros((20, 20), dtype=bool)
    fg[:, :6] = True  # columns 0-5
    boxes = np.array([[0.0, 0, 10, 10], [1.0, 0, 10, 10], [30.0, 30, 5, 5]])
    shown = R.build_rules(Adaptations(report_support=0.6, hidden_evidence=None)).report_shown
    hits, misses = np.full(3, 20), np.ones(3, dtype=int)
    assert shown.shown(boxes, fg, hits, misses).tolist() == [True, False, False]
    assert shown.shown(boxes, None, hits, misses) is None
    assert paper.report_shown.shown(boxes, fg, hits, misses) is None
    # ours (hidden_evidence): tracked 20 frames and unfound 1, memory shows all three
    assert ours.report_shown.shown(boxes, fg, hits, misses).tolist() == [True, True, True]
    # birth support: a part with 0.3 foreground or more
    assert not ours.birth.supported(np.full(5, 0.1), True)
    assert ours.birth.supported(np.full(5, 0.1), False)
    assert paper.birth.supported(np.zeros(5), True)


def test_a_free_candidate_overlapping_a_target_or_an_earlier_birth_starts_none():
    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, (240, 320, 3), dtype=np.uint8)
    boxes = np.array([[50.0, 50.0, 30.0, 80.0], [52.0, 51.0, 30.0, 80.0],  # IoU 0.89
                      [150.0, 50.0, 30.0, 80.0], [240.0, 60.0, 30.0, 80.0]])
    assert iou_matrix(boxes[1:2], boxes[:1])[0, 0] > LifeCycleParams().new_track_iou
    tracker = PBMTracker()
    # the second box overlaps the target the first started this frame: it starts none
    first = tracker.update(img, Detections(boxes[:3], np.ones(3)), None)
    assert sorted(t.id for t in first) == [1, 2]
    # the first box twice: one is target 1's, the other is left free over it and starts
    # none; the far box (after them) starts target 3
    second = tracker.update(img, Detections(boxes[[0, 0, 3]], np.ones(3)), None)
    ids = {t.id: t.box for t in second}
    assert max(ids) == 3 and ids[3][0] == 240.0
