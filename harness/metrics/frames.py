"""Frame-by-frame pairing of gt and tracker boxes, with the MOTChallenge ignore rules.

This is the one place that decides which gt rows are scored and which tracker rows are
dropped; CLEAR/ID (``clear.py``) and HOTA (``hota.py``) both score the result.

Ignore rules (MOTChallenge devkit, as implemented by TrackEval's ``MotChallenge2DBox``):

* gt rows with ``conf == 0`` (column 7) are never scored;
* gt rows with a class (column 8, MOT16+ gt) are scored only when the class is 1
  (pedestrian); rows without a class (MOT15-style gt: columns 8-10 are -1, e.g. TUD,
  CAVIAR) count as pedestrians, so MOT15 gt is scored on ``conf != 0`` alone;
* in frames that hold a gt box of a distractor class (2 person on vehicle, 7 static person,
  8 distractor, 12 reflection), tracker and all gt boxes of the frame are matched by a
  Hungarian assignment on IoU (pairs below IoU 0.5 not allowed), and tracker boxes matched
  to a distractor are removed before scoring. Any other tracker box is scored (a box on an
  unscored gt row of another class is a false positive, as in the devkit).

Tracker rows are never filtered on their confidence column.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from harness.io.mot import MotTable
from trackers.geometry import iou_matrix

log = logging.getLogger(__name__)

PEDESTRIAN_CLASS = 1
NO_CLASS = -1  # MOT15-style gt without a class column
DISTRACTOR_CLASSES = (2, 7, 8, 12)
DISTRACTOR_IOU = 0.5  # fixed by the devkit, independent of the scoring threshold
_EPS = np.finfo(float).eps


@dataclass
class FramePairs:
    """Scored gt and tracker boxes of one sequence, frame by frame.

    Attributes:
        frames: (F,) int64 frame numbers present in gt or results, ascending.
        gt_ids: F arrays (N_t,) int64, ids of the scored gt boxes.
        tracker_ids: F arrays (M_t,) int64, ids of the kept tracker boxes.
        iou: F arrays (N_t, M_t) float64 IoU of scored gt x kept tracker boxes.
        ignored_gt: number of gt rows not scored (conf 0 or non-pedestrian class).
        removed_tracker: number of tracker rows removed for matching a distractor.
    """

    frames: np.ndarray
    gt_ids: list[np.ndarray]
    tracker_ids: list[np.ndarray]
    iou: list[np.ndarray]
    ignored_gt: int = 0
    removed_tracker: int = 0


def _check_unique_ids(table: MotTable, what: str) -> None:
    """Raise ValueError naming file, frame and id when an id occurs twice in a frame."""
    if len(table) < 2:
        return
    order = np.lexsort((table.ids, table.frames))
    f, i = table.frames[order], table.ids[order]
    dup = (f[1:] == f[:-1]) & (i[1:] == i[:-1])
    if dup.any():
        k = int(np.flatnonzero(dup)[0])
        raise ValueError(
            f"{table.path}: {what} id {int(i[k])} occurs more than once in frame {int(f[k])}"
        )


def scored_gt_mask(gt: MotTable) -> np.ndarray:
    """(N,) bool: gt rows that are scored (conf != 0 and class pedestrian or no class)."""
    return (gt.conf != 0) & np.isin(gt.classes, (PEDESTRIAN_CLASS, NO_CLASS))


def pair_frames(gt: MotTable, res: MotTable) -> FramePairs:
    """Apply the ignore rules and compute one IoU matrix per frame.

    Args:
        gt: ground truth read with ``read_mot(path, gt=True)`` (boxes xywh, 0-based).
        res: tracker results (boxes xywh, 0-based), every row scored.
    Raises:
        ValueError: an id occurs twice in one frame of gt or results (names the file).
    """
    _check_unique_ids(gt, "gt")
    _check_unique_ids(res, "tracker")
    scored = scored_gt_mask(gt)
    distractor = np.isin(gt.classes, DISTRACTOR_CLASSES)
    g_index, r_index = gt.frame_index(), res.frame_index()
    frames = np.array(sorted(set(g_index) | set(r_index)), dtype=np.int64)
    empty = np.zeros(0, dtype=np.int64)
    out = FramePairs(frames, [], [], [], ignored_gt=int((~scored).sum()))
    for f in frames.tolist():
        g = g_index.get(f, empty)
        r = r_index.get(f, empty)
        iou = iou_matrix(gt.boxes[g], res.boxes[r])
        keep_r = np.ones(len(r), dtype=bool)
        if len(r) and distractor[g].any():
            m = np.where(iou < DISTRACTOR_IOU - _EPS, 0.0, iou)
            rows, cols = linear_sum_assignment(-m)
            hit = (m[rows, cols] > 0 + _EPS) & distractor[g[rows]]
            keep_r[cols[hit]] = False
            out.removed_tracker += int(hit.sum())
        keep_g = scored[g]
        out.gt_ids.append(gt.ids[g[keep_g]])
        out.tracker_ids.append(res.ids[r[keep_r]])
        out.iou.append(iou[np.ix_(keep_g, keep_r)])
    if out.removed_tracker:
        log.info("%s: %d tracker boxes on distractors removed", res.path, out.removed_tracker)
    return out
