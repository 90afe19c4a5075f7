"""GT rows matched to result rows frame by frame, the CLEAR MOT way (Bernardin &
Stiefelhagen 2008), for the paper and occlusion metrics (``occbench.metrics.paper``,
``occbench.metrics.occlusion``): a pair matched in the last frame the person was matched is
kept while its IoU stays >= the threshold, the remaining rows are matched by the Hungarian
method on IoU (pairs below the threshold are forbidden). GT rows with ``conf == 0`` (MOT16
"ignore") or a class other than pedestrian are left out (``considered_mask``).

The IoUs come from ``occbench.metrics.frames.frame_pairs`` (nonzero entries of each frame,
computed once); ``row_matching`` keeps them with the matching for every metric that reads
either (``tests/harness/metrics/test_matching.py``: equal to the loop over frames and rows).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.io.mot import MotTable, scored_gt_mask
from occbench.metrics.arrays import distinct
from occbench.metrics.frames import FramePairs, check_unique_ids, frame_pairs
from occbench.trackers.common.assignment import assign


def considered_mask(gt: MotTable) -> np.ndarray:
    """(N,) bool: GT rows that are scored, by the MOTChallenge rule
    (``occbench.io.mot.scored_gt_mask``): ``conf != 0`` and class pedestrian (1) or none."""
    return scored_gt_mask(gt)


def considered(gt: MotTable) -> MotTable:
    """The GT rows that are scored (see ``considered_mask``)."""
    return gt.rows(considered_mask(gt))


@dataclass
class RowMatching:
    """The considered GT rows matched to result rows once (``row_matching``): what the paper
    and occlusion metrics of a sequence read.

    Attributes:
        gt: the considered GT rows (``considered``).
        res: the result rows.
        pairs: nonzero IoUs of every frame, GT rows x result rows (``frame_pairs``).
        match: (len(gt),) int64 matched result row of each GT row, -1 where none.
    """

    gt: MotTable
    res: MotTable
    pairs: FramePairs
    match: np.ndarray


def row_matching(gt: MotTable, res: MotTable, iou_threshold: float = 0.5) -> RowMatching:
    """``match_rows`` of the considered rows of ``gt`` against ``res``, with their IoUs."""
    gt = considered(gt)
    pairs = frame_pairs(gt, np.arange(len(gt)), res, np.arange(len(res)))
    return RowMatching(gt, res, pairs, match_rows(gt, res, iou_threshold, pairs))


def match_rows(gt: MotTable, res: MotTable, iou_threshold: float = 0.5,
               pairs: FramePairs | None = None) -> np.ndarray:
    """Match GT rows to result rows frame by frame, keeping last frame's pairs (CLEAR MOT).

    Args:
        gt: ground-truth rows (all are matched; filter with ``considered`` first).
        res: result rows.
        iou_threshold: smallest IoU of a match.
        pairs: ``frame_pairs`` of all rows of ``gt`` and ``res`` when already computed.
    Returns:
        (len(gt),) int64 index of the matched row of ``res`` for each GT row, -1 where none.
    Raises:
        ValueError: bad threshold, or an id repeated within a frame (names the file).
    """
    if not 0.0 < iou_threshold <= 1.0:
        raise ValueError(f"iou_threshold must be in (0, 1], got {iou_threshold}")
    out = np.full(len(gt), -1, dtype=np.int64)
    if len(gt) == 0 or len(res) == 0:
        return out
    check_unique_ids(gt, "gt")
    check_unique_ids(res, "tracker")
    if pairs is None:
        pairs = frame_pairs(gt, np.arange(len(gt)), res, np.arange(len(res)))
    ok = np.flatnonzero(pairs.iou >= iou_threshold)
    frame = np.searchsorted(pairs.entry_start, ok, side="right") - 1
    starts = np.searchsorted(frame, np.arange(len(pairs) + 1))
    person = np.unique(gt.ids, return_inverse=True)[1]
    last = np.zeros(len(person), dtype=np.int64)  # person -> result id matched last ...
    seen = np.zeros(len(person), dtype=bool)  # ... if any
    t_start = pairs.tracker_start
    by_id = np.lexsort((res.ids[pairs.tracker_rows],  # each frame's result boxes by id
                        np.repeat(np.arange(len(pairs)), np.diff(t_start))))
    for k in distinct(frame).tolist():
        e = ok[starts[k] : starts[k + 1]]
        g = pairs.gt_rows[pairs.gt_start[k] : pairs.gt_start[k + 1]]
        r = pairs.tracker_rows[t_start[k] : t_start[k + 1]]
        iou = np.zeros((len(g), len(r)))  # IoU where >= the threshold, else 0
        iou[pairs.row[e] - pairs.gt_start[k], pairs.col[e] - t_start[k]] = pairs.iou[e]
        j = _match_frame(iou, last[person[g]], seen[person[g]], res.ids[r], iou_threshold,
                         by_id[t_start[k] : t_start[k + 1]] - t_start[k])
        hit = j >= 0
        out[g[hit]] = r[j[hit]]
        last[person[g[hit]]], seen[person[g[hit]]] = res.ids[r[j[hit]]], True
    return out


def _match_frame(iou: np.ndarray, before: np.ndarray, known: np.ndarray, ids: np.ndarray,
                 iou_threshold: float, by_id: np.ndarray) -> np.ndarray:
    """One frame of ``match_rows``: (N,) result box (column) of each GT box, -1 where none.

    Args:
        iou: (N, M) IoU of GT x result boxes where >= the threshold, else 0.
        before: (N,) int64 each GT person's last matched result id, where ``known``.
        known: (N,) bool the person was matched before.
        ids: (M,) int64 result ids (unique).
        by_id: (M,) int64 ``argsort(ids)``.
    A person whose last matched result id is in the frame keeps it while their IoU passes
    (in GT row order, a box taken once); the rest by the Hungarian method on 1 - IoU.
    """
    n, m = iou.shape
    out = np.full(n, -1, dtype=np.int64)
    wanted = np.flatnonzero(known)
    want = before[wanted]
    j = by_id[np.minimum(np.searchsorted(ids[by_id], want), m - 1)]
    keep = (ids[j] == want) & (iou[wanted, j] > 0)
    i, j = wanted[keep], j[keep]
    order = np.argsort(j, kind="stable")  # a box is taken by the first row wanting it
    first = order[np.concatenate(([True], j[order][1:] != j[order][:-1]))] if len(j) else order
    out[i[first]] = j[first]
    free = np.ones(m, dtype=bool)
    free[j] = False
    free_g, free_r = np.flatnonzero(out < 0), np.flatnonzero(free)
    sub = iou[free_g][:, free_r]
    if (sub > 0).any():
        cost = 1.0 - sub
        cost[sub <= 0] = np.inf
        pairs, _, _ = assign(cost, 1.0 - iou_threshold + 1e-12)
        out[free_g[pairs[:, 0]]] = free_r[pairs[:, 1]]
    return out
