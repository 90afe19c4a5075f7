"""HOTA: hand-derived cases, TrackEval's figures for the TUD test files, and equivalence with
a plain loop transcription of TrackEval's ``HOTA.eval_sequence`` on random scenes."""

from __future__ import annotations

import os

import motmetrics
import numpy as np
import pytest
from metric_references import reference_hota
from mot_tables import table

from occbench.io.mot import MotTable, read_mot
from occbench.metrics import score_sequence
from occbench.metrics.frames import FramePairs
from occbench.metrics.hota import ALPHAS, combine_hota, hota_counts
from occbench.trackers.geometry import iou_matrix

MM_DATA = os.path.join(os.path.dirname(motmetrics.__file__), "data")


def hota_of(gt: MotTable, res: MotTable) -> dict[str, float]:
    return score_sequence(gt, res).hota.summary()


def test_alphas_are_trackeval_grid():
    assert len(ALPHAS) == 19
    np.testing.assert_allclose(ALPHAS, np.linspace(0.05, 0.95, 19))


def test_single_box_iou_06_matches_for_12_of_19_alphas():
    # IoU = 60 / 100 exactly: a TP for alpha = 0.05 .. 0.60 (12 values), else FN + FP
    gt = table([(1, 1, 0, 0, 10, 10)])
    res = table([(1, 7, 0, 0, 6, 10)])
    s = score_sequence(gt, res).hota
    assert s.tp.tolist() == [1.0] * 12 + [0.0] * 7
    assert s.fn.tolist() == [0.0] * 12 + [1.0] * 7
    assert s.fp.tolist() == [0.0] * 12 + [1.0] * 7
    h = s.summary()
    assert h["HOTA"] == pytest.approx(12 / 19)
    assert h["DetA"] == pytest.approx(12 / 19)
    assert h["AssA"] == pytest.approx(12 / 19)
    # LocA is 0.6 where matched and 1 (TrackEval's convention) where TP = 0
    assert h["LocA"] == pytest.approx((12 * 0.6 + 7 * 1.0) / 19)


def test_perfect_tracker_scores_one_whatever_its_ids():
    rng = np.random.default_rng(3)
    rows = [
        (f, i, *rng.uniform(0, 500, 2), 30, 80)
        for f in range(1, 31)
        for i in range(1, 6)
        if rng.random() > 0.2
    ]
    gt = table(rows)
    res = table([(f, 100 + 3 * i, x, y, w, h) for f, i, x, y, w, h in rows])
    h = hota_of(gt, res)
    for key in ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr"):
        assert h[key] == pytest.approx(1.0), key


def test_empty_tracker_and_empty_gt_score_zero():
    gt = table([(1, 1, 0, 0, 10, 10), (2, 1, 1, 0, 10, 10)])
    s = score_sequence(gt, table([])).hota
    assert s.summary()["HOTA"] == 0.0
    assert s.fn.tolist() == [2.0] * 19 and s.tp.sum() == 0
    s = score_sequence(table([]), gt).hota
    assert s.summary()["HOTA"] == 0.0
    assert s.fp.tolist() == [2.0] * 19


def test_identity_switch_halves_association():
    # one person over 4 frames, tracked perfectly but as id 1 then id 2:
    # |TPA(g,1)| = |TPA(g,2)| = 2, |FNA| = 2, |FPA| = 0 -> A = 2 / 4 for every TP
    gt = table([(f, 1, 10 * f, 0, 10, 20) for f in range(1, 5)])
    res = table([(f, 1 if f <= 2 else 2, 10 * f, 0, 10, 20) for f in range(1, 5)])
    h = hota_of(gt, res)
    assert h["DetA"] == pytest.approx(1.0)
    assert h["AssA"] == pytest.approx(0.5)
    assert h["AssRe"] == pytest.approx(0.5)
    assert h["AssPr"] == pytest.approx(1.0)
    assert h["HOTA"] == pytest.approx(np.sqrt(0.5))


def test_alignment_score_overrides_a_better_single_frame_iou():
    # gt 1 in frames 1-3; tracker 1 follows it at IoU 0.72 throughout; in frame 3 a
    # tracker 2 appears at IoU 0.83. TrackEval's score (alignment * IoU) keeps tracker 1
    # (0.70 * 0.72 vs 0.15 * 0.83), so alphas <= 0.70 (14 of 19) give TP 3, FP 1 and AssA 1,
    # and alphas >= 0.75 give no TP at all (tracker 2 is not re-matched per alpha).
    gt = table([(f, 1, 0, 0, 10, 10) for f in (1, 2, 3)])
    res = table([(f, 1, 0, 0, 7.2, 10) for f in (1, 2, 3)] + [(3, 2, 0, 0, 8.3, 10)])
    s = score_sequence(gt, res).hota
    assert s.tp.tolist() == [3.0] * 14 + [0.0] * 5
    assert s.fp.tolist() == [1.0] * 14 + [4.0] * 5
    h = s.summary()
    assert h["DetA"] == pytest.approx(14 / 19 * 3 / 4)
    assert h["AssA"] == pytest.approx(14 / 19)
    assert h["HOTA"] == pytest.approx(14 / 19 * np.sqrt(3 / 4))
    assert h["LocA"] == pytest.approx((14 * 0.72 + 5) / 19)


@pytest.mark.parametrize("seq, expected", [("TUD-Campus", 0.3914), ("TUD-Stadtmitte", 0.3978)])
def test_trackeval_figures_for_tud(seq: str, expected: float):
    gt = read_mot(os.path.join(MM_DATA, seq, "gt.txt"), gt=True)
    res = read_mot(os.path.join(MM_DATA, seq, "test.txt"))
    assert round(hota_of(gt, res)["HOTA"], 4) == expected


def random_scene(rng: np.random.Generator, frames: int = 40, people: int = 6):
    """Per-frame gt ids, tracker ids and IoU matrices of a jittery, switching tracker."""
    gt_ids, tr_ids, sims = [], [], []
    pos = rng.uniform(0, 200, (people, 2))
    for _ in range(frames):
        pos += rng.normal(0, 3, pos.shape)
        g = np.flatnonzero(rng.random(people) > 0.15)
        boxes = np.column_stack([pos[g], np.full((len(g), 2), [20.0, 50.0])])
        keep = rng.random(len(g)) > 0.2
        tb = boxes[keep] + rng.normal(0, 4, (keep.sum(), 4)) * [1, 1, 0.3, 0.3]
        t = g[keep] + 10 * rng.integers(0, 2, keep.sum())  # occasional id swaps
        n_fp = rng.integers(0, 3)
        tb = np.vstack(
            [
                tb,
                np.column_stack([rng.uniform(0, 200, (n_fp, 2)), np.full((n_fp, 2), [20.0, 50.0])]),
            ]
        )
        t = np.concatenate([t, 100 + rng.integers(0, 5, n_fp)])
        t, first = np.unique(t, return_index=True)
        tb = tb[first]
        gt_ids.append(g)
        tr_ids.append(t)
        sims.append(iou_matrix(boxes, tb))
    return gt_ids, tr_ids, sims


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_vectorised_equals_trackeval_loops(seed: int):
    gt_ids, tr_ids, sims = random_scene(np.random.default_rng(seed))
    got = hota_counts(FramePairs.from_dense(gt_ids, tr_ids, sims))
    ref = reference_hota(gt_ids, tr_ids, sims)
    for name in ("tp", "fn", "fp", "ass_a", "ass_re", "ass_pr", "loc_a"):
        np.testing.assert_allclose(
            getattr(got, name), getattr(ref, name), rtol=1e-12, atol=1e-12, err_msg=name
        )
    assert 0.2 < got.summary()["HOTA"] < 0.95  # a non-trivial scene


def test_combined_equals_scoring_disjoint_sequences_together():
    # two sequences with disjoint ids and frames: the alignment scores cannot mix, so
    # TrackEval's combination (sums, TP-weighted AssA/LocA) equals scoring them as one
    a = random_scene(np.random.default_rng(10), frames=20)
    b = random_scene(np.random.default_rng(11), frames=25)
    b = ([g + 1000 for g in b[0]], [t + 1000 for t in b[1]], b[2])
    ha, hb = hota_counts(FramePairs.from_dense(*a)), hota_counts(FramePairs.from_dense(*b))
    both = hota_counts(FramePairs.from_dense(a[0] + b[0], a[1] + b[1], a[2] + b[2]))
    comb = combine_hota([ha, hb])
    for name in ("tp", "fn", "fp", "ass_a", "ass_re", "ass_pr", "loc_a"):
        np.testing.assert_allclose(
            getattr(comb, name), getattr(both, name), rtol=1e-12, err_msg=name
        )
    np.testing.assert_array_equal(comb.tp, ha.tp + hb.tp)
    # and it is not the plain mean of the two sequences' HOTA
    mean = (ha.summary()["HOTA"] + hb.summary()["HOTA"]) / 2
    assert comb.summary()["HOTA"] == pytest.approx(both.summary()["HOTA"])
    assert comb.summary()["HOTA"] != pytest.approx(mean, abs=1e-6)


def test_frame_count_mismatch_is_an_error():
    with pytest.raises(ValueError, match="one entry per frame"):
        FramePairs.from_dense([np.array([1])], [], [])
