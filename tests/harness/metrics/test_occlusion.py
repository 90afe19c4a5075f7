"""Hand cases for the visibility-binned metrics and re-identification after total occlusion."""

from __future__ import annotations

import math

import numpy as np
import pytest

from occbench.datasets.base import GroundTruth
from occbench.io.mot import MotTable
from occbench.metrics.occlusion import (
    COLUMNS,
    OcclusionCounts,
    combine,
    identity_mapping,
    occlusion_counts,
    occlusion_metrics,
    row_visibility,
)


def table(rows, vis=None) -> MotTable:
    """rows: (frame, id, x, y, w, h); vis: per row visibility (same order) or None."""
    a = np.asarray(rows, dtype=np.float64).reshape(-1, 6)
    v = np.full(len(a), np.nan) if vis is None else np.asarray(vis, dtype=np.float64)
    order = np.lexsort((a[:, 1], a[:, 0]))
    a, v = a[order], v[order]
    n = len(a)
    return MotTable(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), a[:, 2:6].copy(),
                    np.ones(n), np.full(n, -1, np.int64), v)


def walk(gid, frames, x=0.0):
    return [(f, gid, x, 0.0, 10.0, 20.0) for f in frames]


def test_columns_are_the_documented_flat_names():
    m = occlusion_metrics(table(walk(1, [1])), table(walk(1, [1])))
    assert list(m) == COLUMNS
    assert COLUMNS[:3] == ["Recall_v0-25", "IDP_v0-25", "IDs_v0-25"]
    assert COLUMNS[-3:] == ["ReID", "ReID_frames", "ReID_n"]


def test_recall_per_visibility_bin():
    # 8 frames, visibility 1,1,.6,.6,.3,.3,0,0; the tracker finds the person while vis >= .5
    vis = [1, 1, .6, .6, .3, .3, 0, 0]
    gt = table(walk(1, range(1, 9)), vis)
    res = table(walk(4, range(1, 5)))
    m = occlusion_metrics(gt, res)
    assert m["Recall_v75-100"] == 1 and m["Recall_v50-75"] == 1
    assert m["Recall_v25-50"] == 0 and m["Recall_v0-25"] == 0
    assert math.isnan(m["IDP_v0-25"])  # nothing matched in that bin
    # bin edges: 0.25 belongs to the upper bin, 1.0 to the top bin
    c = occlusion_counts(table(walk(1, [1, 2, 3]), [0.25, 0.75, 1.0]), MotTable.empty())
    assert c.rows.tolist() == [0, 1, 0, 2]


def test_id_precision_and_switches_land_in_the_bin_of_the_switch():
    # person 1 tracked as id 4 for 4 frames (visible), then as id 5 for 2 frames at vis .1
    vis = [1, 1, 1, 1, .1, .1]
    gt = table(walk(1, range(1, 7)), vis)
    res = table(walk(4, range(1, 5)) + walk(5, [5, 6]))
    m = occlusion_metrics(gt, res)
    assert m["IDP_v75-100"] == 1        # id 4 is the mapped id (4 frames vs 2)
    assert m["IDP_v0-25"] == 0
    assert m["IDs_v0-25"] == 1 and m["IDs_v75-100"] == 0
    assert identity_mapping(gt, res) == {1: 4}


def test_reid_after_total_occlusion_same_id_and_frames_to_recovery():
    # visible 1-3 (id 4), hidden 4-6, visible 7-10; tracker finds id 4 again from frame 9
    vis = [1, 1, 1, 0, 0, 0, 1, 1, 1, 1]
    gt = table(walk(1, range(1, 11)), vis)
    res = table(walk(4, [1, 2, 3, 9, 10]))
    m = occlusion_metrics(gt, res)
    assert m["ReID_n"] == 1 and m["ReID"] == 1 and m["ReID_frames"] == 2
    # a new id after the occlusion is a failed re-identification
    res_new = table(walk(4, [1, 2, 3]) + walk(8, [7, 8, 9, 10]))
    m = occlusion_metrics(gt, res_new)
    assert m["ReID_n"] == 1 and m["ReID"] == 0 and math.isnan(m["ReID_frames"])
    # a tracker coasting through the occlusion with the same id recovers at once
    res_coast = table(walk(4, range(1, 11)))
    assert occlusion_metrics(gt, res_coast)["ReID_frames"] == 0


def test_episodes_not_scored_when_never_tracked_before_or_never_seen_again():
    vis = [1, 0, 0, 1]
    gt = table(walk(1, range(1, 5)), vis)
    assert occlusion_counts(gt, table(walk(3, [4]))).episodes == 0  # untracked before
    gt_leaves = table(walk(1, range(1, 4)), [1, 0, 0])
    assert occlusion_counts(gt_leaves, table(walk(3, [1]))).episodes == 0
    # two episodes of one person are scored separately
    gt2 = table(walk(1, range(1, 8)), [1, 0, 1, 1, 0, 0, 1])
    c = occlusion_counts(gt2, table(walk(3, [1, 3, 4, 7])))
    assert c.episodes == 2 and c.recovered == 2 and c.recovery_frames == 0


def test_caviar_occluded_labels_stand_in_for_missing_visibility():
    gt_table = table(walk(1, range(1, 7)))  # visibility NaN
    occluded = np.array([False, False, True, True, False, False])
    vis = row_visibility(gt_table, occluded)
    assert vis.tolist() == [1, 1, 0, 0, 1, 1]
    c = occlusion_counts(GroundTruth(gt_table, occluded=occluded), table(walk(2, [1, 2, 5, 6])))
    assert c.rows.tolist() == [2, 0, 0, 4] and c.episodes == 1 and c.recovered == 1
    # without labels and visibility no row is binned
    assert occlusion_counts(gt_table, table(walk(2, [1]))).rows.sum() == 0
    with pytest.raises(ValueError, match="occluded"):
        row_visibility(gt_table, occluded[:3])


def test_combined_sums_counts():
    gt = table(walk(1, range(1, 5)), [1, 1, 1, 1])
    a = occlusion_counts(gt, table(walk(1, range(1, 5))))
    b = occlusion_counts(gt, MotTable.empty())
    out = combine({"a": a, "b": b})
    assert out["COMBINED"]["Recall_v75-100"] == 0.5
    assert (OcclusionCounts() + a).rows.tolist() == a.rows.tolist()


def test_extra_rows_for_metrics_csv_have_sequence_and_combined_rows():
    from occbench.metrics.occlusion import EXTRA_COLUMNS, extra_rows, extra_score

    gt = table(walk(1, range(1, 5)), [1, 1, 0, 1])
    good = extra_score(gt, table(walk(1, range(1, 5))))
    none = extra_score(GroundTruth(gt), MotTable.empty())
    rows = extra_rows({"t": {"a": good, "b": none}, "u": {}})
    assert list(rows.columns) == ["tracker", "sequence", *EXTRA_COLUMNS]
    assert rows["sequence"].tolist() == ["a", "b", "COMBINED"]
    combined = rows.iloc[2]
    assert combined["Song_GT"] == 2 and combined["Song_MT%"] == 50
    assert combined["Recall_v75-100"] == 0.5 and combined["ReID_n"] == 1
