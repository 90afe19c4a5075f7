"""Hand-derivable cases for the paper metrics (Reta Table 1 after Song et al.; PBM 5.2-5.3)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occbench.io.mot import MotTable
from occbench.metrics.paper import (
    COLUMNS,
    PaperCounts,
    combine,
    match_rows,
    paper_counts,
    paper_metrics,
)


def table(rows: list[tuple[int, int, float, float, float, float]], conf=None) -> MotTable:
    """rows: (frame, id, x, y, w, h), 0-based boxes."""
    a = np.asarray(rows, dtype=np.float64).reshape(-1, 6)
    order = np.lexsort((a[:, 1], a[:, 0]))
    a = a[order]
    n = len(a)
    c = np.ones(n) if conf is None else np.asarray(conf, dtype=np.float64)[order]
    return MotTable(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), a[:, 2:6].copy(), c,
                    np.full(n, -1, np.int64), np.full(n, np.nan))


def person(gid: int, frames, x: float, y: float = 0.0, w: float = 10.0, h: float = 20.0):
    return [(f, gid, x, y, w, h) for f in frames]


def test_perfect_tracking_gives_paper_ideal_values():
    gt = table(person(1, range(1, 11), 0) + person(2, range(1, 11), 50))
    res = table(person(7, range(1, 11), 0) + person(9, range(1, 11), 50))
    m = paper_metrics(gt, res)
    assert set(m) == set(COLUMNS)
    assert m["Song_GT"] == 2 and m["Song_MT%"] == 100 and m["Song_PT%"] == 0
    assert m["Song_ML%"] == 0 and m["Song_Frag"] == 0 and m["Song_IDS"] == 0
    assert m["PBM_MT"] == 2 and m["PBM_MT1"] == 2 and m["PBM_Missed"] == 0
    assert m["PBM_IDs/traj"] == 1 and m["PBM_IDs/frame"] == 1 and m["PBM_IDsw/traj"] == 0
    assert m["PBM_dx%"] == 0 and m["PBM_dh%"] == 0


def test_coverage_thresholds_are_strict_as_in_the_papers():
    # 10-frame trajectories covered 9, 8, 2, 1 and 0 frames: 0.9 -> MT; 0.8 and 0.2 -> PT
    # (Reta: "more than 80%", "between 20% and 80%", "less than 20%"); 0.1, 0 -> ML.
    gt_rows, res_rows = [], []
    for gid, covered in zip(range(1, 6), [9, 8, 2, 1, 0]):
        gt_rows += person(gid, range(1, 11), 100 * gid)
        res_rows += person(gid + 10, range(1, covered + 1), 100 * gid)
    m = paper_metrics(table(gt_rows), table(res_rows))
    assert m["Song_MT%"] == pytest.approx(20)
    assert m["Song_PT%"] == pytest.approx(40)
    assert m["Song_ML%"] == pytest.approx(40)
    # PBM: mostly lost is < 40 %: 0.2, 0.1, 0 -> 3; missed: 1
    assert m["PBM_MT"] == 1 and m["PBM_ML"] == 3 and m["PBM_Missed"] == 1
    # distinct ids per trajectory over the 4 matched trajectories
    assert m["PBM_IDs/traj"] == 1


def test_frag_counts_id_changes_not_gaps():
    # one person tracked as id 5 (frames 1-3), lost (4-5), id 5 again (6-7), id 6 (8-10)
    gt = table(person(1, range(1, 11), 0))
    res = table(person(5, [1, 2, 3, 6, 7], 0) + person(6, [8, 9, 10], 0))
    c = paper_counts(gt, res)
    assert c.frag == 1          # one change of id (5 -> 6); the gap is not a change
    assert c.ids == 0           # neither result trajectory changes its GT
    assert c.over == 1 and c.mt1 == 0 and c.mt80 == 0  # 8/10 covered is not > 80 %
    assert c.swaps == 0         # id 6 was never on another person: no swap
    assert paper_metrics(gt, res)["PBM_IDs/traj"] == 2


def test_identity_swap_counts_in_ids_frag_and_pbm_swaps():
    # two people side by side, the tracker swaps their ids at frame 6
    gt = table(person(1, range(1, 11), 0) + person(2, range(1, 11), 30))
    res = table(person(7, range(1, 6), 0) + person(8, range(1, 6), 30)
                + person(8, range(6, 11), 0) + person(7, range(6, 11), 30))
    c = paper_counts(gt, res)
    assert c.frag == 2      # each GT trajectory changes id once
    assert c.ids == 2       # each result trajectory changes its GT once
    assert c.swaps == 2     # both changes take an id that was on the other person
    m = c.columns()
    assert m["PBM_IDsw/traj"] == 1 and m["PBM_Over"] == 2 and m["PBM_MT1"] == 0
    assert m["Song_MT%"] == 100


def test_a_restart_onto_another_person_is_a_swap_of_its_follower():
    # PBM's single-target protocol: follower 1 (id 1) follows person 1, loses them and
    # restarts as id 3 on person 2, whose own follower (id 2) has lost them.
    gt = table(person(1, range(1, 11), 0) + person(2, range(1, 11), 40))
    res = table(person(1, range(1, 6), 0) + person(2, range(1, 6), 40)
                + person(3, range(6, 11), 40))
    assert paper_counts(gt, res).swaps == 0  # id 3 alone has no past
    c = paper_counts(gt, res, followers={1: 1, 2: 2, 3: 1})
    assert c.swaps == 1 and c.under == 0 and c.over == 1
    # a restart back onto its own person is no swap
    back = table(person(1, range(1, 6), 0) + person(3, range(7, 11), 0))
    assert paper_counts(gt, back, followers={1: 1, 3: 1}).swaps == 0
    with pytest.raises(ValueError, match=r"result ids \[3\] have no follower"):
        paper_counts(gt, res, followers={1: 1, 2: 2})


def test_under_segmented_new_person_inherits_existing_id():
    # person 1 leaves at frame 5; person 2 enters at frame 6 and gets person 1's id 3
    gt = table(person(1, range(1, 6), 0) + person(2, range(6, 11), 40))
    res = table(person(3, range(1, 6), 0) + person(3, range(6, 11), 40))
    c = paper_counts(gt, res)
    assert c.under == 1 and c.over == 0 and c.ids == 1 and c.frag == 0


def test_multiple_responses_count_per_frame_and_in_segmentation_error():
    # one gt box 10x20; the tracker answers with the right box (id 1) and, in frames 1-2,
    # a second small box (id 2) inside the upper half: 2 ids in 2 of 4 frames -> 1.5
    gt = table(person(1, range(1, 5), 0))
    res = table(person(1, range(1, 5), 0) + person(2, [1, 2], 0, 0, 10, 10))
    m = paper_metrics(gt, res)
    assert m["PBM_IDs/frame"] == pytest.approx(6 / 4)
    # segmentation error averaged over 6 responses: the small box has dy = -5/20, dh = -0.5
    assert m["PBM_dy%"] == pytest.approx(100 * 2 * 0.25 / 6)
    assert m["PBM_dh%"] == pytest.approx(100 * 2 * 0.5 / 6)
    assert m["PBM_dx%"] == 0 and m["PBM_dw%"] == 0


def test_relative_errors_are_normalised_by_gt_size():
    gt = table(person(1, [1], 0, 0, 20, 40))
    res = table([(1, 1, 2, 4, 22, 36)])  # centre (13, 22) vs (10, 20); IoU 0.79
    c = paper_counts(gt, res)
    m = c.columns()
    assert m["PBM_dx%"] == pytest.approx(100 * 3 / 20)
    assert m["PBM_dy%"] == pytest.approx(100 * 2 / 40)
    assert m["PBM_dw%"] == pytest.approx(10)
    assert m["PBM_dh%"] == pytest.approx(10)
    assert c.min_dh == pytest.approx(-0.1) and c.max_dw == pytest.approx(0.1)


def test_matching_keeps_previous_pair_and_respects_threshold_and_ignore_rows():
    # frame 2: result 4 fits person 2 best (IoU 1) but still fits person 1 (IoU 0.67),
    # which it matched in frame 1: CLEAR keeps the old pair, person 2 stays unmatched
    gt = table([(1, 1, 0, 0, 10, 10), (2, 1, 0, 0, 10, 10), (2, 2, 2, 0, 10, 10)])
    res = table([(1, 4, 0, 0, 10, 10), (2, 4, 2, 0, 10, 10)])
    m = match_rows(gt, res, 0.5)
    assert m.tolist() == [0, 1, -1]
    # without the history (frame 2 alone) the Hungarian method picks person 2
    alone = match_rows(gt.rows(gt.frames == 2), res.rows(res.frames == 2), 0.5)
    assert alone.tolist() == [-1, 0]
    assert match_rows(gt, res, 0.7).tolist() == [0, -1, 1]
    ignored = table(person(1, range(1, 3), 0), conf=[0, 0])
    assert paper_counts(ignored, table(person(1, [1], 0))).gt == 0
    with pytest.raises(ValueError, match="iou_threshold"):
        match_rows(gt, res, 0.0)


def test_combined_row_sums_counts_not_ratios():
    gt_a = table(person(1, range(1, 11), 0))
    gt_b = table(person(1, range(1, 11), 0) + person(2, range(1, 11), 50)
                 + person(3, range(1, 11), 100))
    res_a = table(person(1, range(1, 11), 0))
    res_b = table(person(1, range(1, 3), 0))
    out = combine({"a": paper_counts(gt_a, res_a), "b": paper_counts(gt_b, res_b)})
    assert out["a"]["Song_MT%"] == 100 and out["b"]["Song_MT%"] == 0
    assert out["COMBINED"]["Song_MT%"] == pytest.approx(25)  # 1 of 4, not mean(100, 0)
    assert out["COMBINED"]["Song_GT"] == 4


def test_empty_inputs_give_zero_counts_and_nan_ratios():
    m = paper_metrics(MotTable.empty(), MotTable.empty())
    assert m["Song_GT"] == 0 and math.isnan(m["Song_MT%"])
    gt = table(person(1, range(1, 4), 0))
    m = paper_metrics(gt, MotTable.empty())
    assert m["PBM_Missed"] == 1 and m["Song_ML%"] == 100 and math.isnan(m["PBM_dx%"])
    assert (PaperCounts() + PaperCounts()).gt == 0
