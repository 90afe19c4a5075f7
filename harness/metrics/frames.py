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
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from occbench.io.mot import MotTable, scored_gt_mask
from occbench.metrics.arrays import distinct
from occbench.metrics.overlaps import sparse_iou
from occbench.trackers.geometry import iou_matrix

log = logging.getLogger(__name__)

DISTRACTOR_CLASSES = (2, 7, 8, 12)
DISTRACTOR_IOU = 0.5  # fixed by the devkit, independent of the scoring threshold
_EPS = np.finfo(float).eps


@dataclass
class FramePairs:
    """Scored gt and tracker boxes of one sequence and their overlaps, frame by frame.

    The IoU matrix of each frame is computed once (``pair_frames``) and kept sparse: only
    its nonzero entries, as COO arrays over the whole sequence, so memory grows with the
    overlapping box pairs, not with gt boxes x tracker boxes. ``frame(k)`` gives frame k's
    dense (N_k, M_k) matrix again, bit for bit, for the metrics that read it whole (the
    Hungarian steps of CLEAR and HOTA, HOTA's row and column sums).

    Attributes:
        frames: (F,) int64 frame numbers present in gt or results, ascending.
        gt_ids: (N,) int64 ids of the scored gt boxes, frame by frame.
        tracker_ids: (M,) int64 ids of the kept tracker boxes, frame by frame.
        gt_start, tracker_start: (F + 1,) int64 offsets: frame k's boxes are
            ``gt_ids[gt_start[k]:gt_start[k + 1]]`` (and likewise for the tracker).
        row, col: (K,) int64 gt and tracker box indices (into ``gt_ids``, ``tracker_ids``)
            of every nonzero IoU, frame by frame, row-major within a frame.
        iou: (K,) float64 those IoUs, in (0, 1].
        entry_start: (F + 1,) int64 offsets of each frame's entries in row, col, iou.
        ignored_gt: number of gt rows not scored (conf 0 or non-pedestrian class).
        removed_tracker: number of tracker rows removed for matching a distractor.
        gt_rows, tracker_rows: (N,) and (M,) int64 rows of the gt and tracker tables the
            boxes come from (``frame_pairs``; None from ``from_dense``).
    """

    frames: np.ndarray
    gt_ids: np.ndarray
    tracker_ids: np.ndarray
    gt_start: np.ndarray
    tracker_start: np.ndarray
    row: np.ndarray
    col: np.ndarray
    iou: np.ndarray
    entry_start: np.ndarray
    ignored_gt: int = 0
    removed_tracker: int = 0
    gt_rows: np.ndarray | None = None
    tracker_rows: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.frames)

    def ids(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Frame k's (N_k,) gt ids and (M_k,) tracker ids."""
        return (self.gt_ids[self.gt_start[k] : self.gt_start[k + 1]],
                self.tracker_ids[self.tracker_start[k] : self.tracker_start[k + 1]])

    def entries(self, k: int) -> tuple[np.ndarray, np.ndarray, slice]:
        """Frame k's nonzero entries: (E,) rows and columns within the frame, and the slice
        of them in ``row``, ``col``, ``iou``."""
        e = slice(int(self.entry_start[k]), int(self.entry_start[k + 1]))
        return self.row[e] - self.gt_start[k], self.col[e] - self.tracker_start[k], e

    def frame(self, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Frame k's gt ids (N_k,), tracker ids (M_k,) and dense IoU (N_k, M_k) float64."""
        g, t = self.ids(k)
        r, c, e = self.entries(k)
        iou = np.zeros((len(g), len(t)))
        iou[r, c] = self.iou[e]
        return g, t, iou

    def __iter__(self) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """(gt ids, tracker ids, dense IoU) of each frame in turn (see ``frame``)."""
        return (self.frame(k) for k in range(len(self.frames)))

    @classmethod
    def from_dense(cls, gt_ids: Sequence[np.ndarray], tracker_ids: Sequence[np.ndarray],
                   iou: Sequence[np.ndarray]) -> FramePairs:
        """From per-frame (N_t,) gt ids, (M_t,) tracker ids and (N_t, M_t) IoU matrices
        (frames numbered 1, 2, ...); the reference form the tests compare against."""
        if not len(gt_ids) == len(tracker_ids) == len(iou):
            raise ValueError(
                f"gt_ids, tracker_ids and iou must have one entry per frame, got "
                f"{len(gt_ids)}, {len(tracker_ids)}, {len(iou)}"
            )
        n = np.cumsum([0, *map(len, gt_ids)], dtype=np.int64)
        m = np.cumsum([0, *map(len, tracker_ids)], dtype=np.int64)
        rows, cols, vals = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)], [np.zeros(0)]
        for k, s in enumerate(iou):
            s = np.asarray(s, dtype=np.float64).reshape(n[k + 1] - n[k], m[k + 1] - m[k])
            r, c = np.nonzero(s)
            rows.append(r + n[k])
            cols.append(c + m[k])
            vals.append(s[r, c])
        ids = [np.concatenate([np.zeros(0, np.int64), *x]).astype(np.int64)
               for x in (gt_ids, tracker_ids)]
        return cls(np.arange(1, len(iou) + 1), *ids, n, m, np.concatenate(rows),
                   np.concatenate(cols), np.concatenate(vals),
                   np.cumsum([0, *map(len, vals[1:])], dtype=np.int64))


def check_unique_ids(table: MotTable, what: str) -> None:
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


def pair_frames(gt: MotTable, res: MotTable) -> FramePairs:
    """Apply the ignore rules and compute one IoU matrix per frame, kept sparse
    (``occbench.metrics.overlaps.sparse_iou``), read by CLEAR, IDF1 and HOTA alike.

    Args:
        gt: ground truth read with ``read_mot(path, gt=True)`` (boxes xywh, 0-based).
        res: tracker results (boxes xywh, 0-based), every row scored.
    Raises:
        ValueError: an id occurs twice in one frame of gt or results (names the file).
    """
    check_unique_ids(gt, "gt")
    check_unique_ids(res, "tracker")
    scored = scored_gt_mask(gt)
    kept = np.flatnonzero(~distractor_matches(gt, res))
    out = frame_pairs(gt, np.flatnonzero(scored), res, kept)
    out.ignored_gt, out.removed_tracker = int((~scored).sum()), len(res) - len(kept)
    if out.removed_tracker:
        log.info("%s: %d tracker boxes on distractors removed", res.path, out.removed_tracker)
    return out


def frame_pairs(gt: MotTable, gt_rows: np.ndarray, res: MotTable,
                res_rows: np.ndarray) -> FramePairs:
    """``FramePairs`` of some rows of ``gt`` against some rows of ``res`` (ascending (K,) int
    index arrays), over every frame of either table, with the nonzero IoUs of each frame."""
    frames = distinct(gt.frames, res.frames).astype(np.int64)
    g = gt_rows[np.argsort(gt.frames[gt_rows], kind="stable")]  # by frame, in table order
    r = res_rows[np.argsort(res.frames[res_rows], kind="stable")]
    g_start = np.r_[np.searchsorted(gt.frames[g], frames), len(g)].astype(np.int64)
    r_start = np.r_[np.searchsorted(res.frames[r], frames), len(r)].astype(np.int64)
    row, col, iou, entry_start = sparse_iou(gt.boxes[g], g_start, res.boxes[r], r_start)
    return FramePairs(frames, gt.ids[g], res.ids[r], g_start, r_start, row, col, iou,
                      entry_start, gt_rows=g, tracker_rows=r)


def distractor_matches(gt: MotTable, res: MotTable) -> np.ndarray:
    """(M,) bool: tracker rows matched to a distractor-class gt box (removed before scoring).

    In each frame holding a distractor, all its gt and tracker boxes are matched by a
    Hungarian assignment on IoU (pairs below ``DISTRACTOR_IOU`` not allowed).
    """
    hit_rows = np.zeros(len(res), dtype=bool)
    distractor = np.isin(gt.classes, DISTRACTOR_CLASSES)
    if not distractor.any() or len(res) == 0:
        return hit_rows
    g_index, r_index = gt.frame_index(), res.frame_index()
    for f in distinct(gt.frames[distractor]).tolist():
        g, r = g_index[f], r_index.get(f)
        if r is None:
            continue
        iou = iou_matrix(gt.boxes[g], res.boxes[r])
        m = np.where(iou < DISTRACTOR_IOU - _EPS, 0.0, iou)
        rows, cols = linear_sum_assignment(-m)
        hit = (m[rows, cols] > 0 + _EPS) & distractor[g[rows]]
        hit_rows[r[cols[hit]]] = True
    return hit_rows
