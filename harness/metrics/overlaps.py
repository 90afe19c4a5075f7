"""The nonzero IoUs of every frame at once, without the dense matrices (``sparse_iou``).

Per frame, ``occbench.trackers.geometry.iou_matrix`` of N gt boxes against M tracker boxes holds
N x M entries, about 1 % of them nonzero at MOT20 density (100 people in a frame). Here the
tracker boxes are sorted by frame and left edge, and each gt box is paired only with the
tracker boxes of its frame whose left edge lies within (its left edge - the widest tracker
box, its right edge): every box pair apart along x is left out, its IoU being 0. The IoU of
each remaining pair is then computed elementwise with the operations of ``iou_matrix`` in
the same order, so every value is bit-equal to it
(``tests/harness/metrics/test_matching.py``). Plain numpy: a compiled kernel was no faster
once its start-up (about a second per process) is counted.
"""

from __future__ import annotations

import numpy as np


def sparse_iou(gt: np.ndarray, gt_start: np.ndarray, res: np.ndarray, res_start: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Nonzero IoUs of gt x tracker boxes, frame by frame.

    Args:
        gt: (N, 4) float64 xywh gt boxes, grouped by frame; frame k's are
            ``gt[gt_start[k]:gt_start[k + 1]]``.
        gt_start: (F + 1,) int64 offsets.
        res: (M, 4) float64 xywh tracker boxes, grouped by the same frames.
        res_start: (F + 1,) int64 offsets.
    Returns:
        row (K,) int64 gt index, col (K,) int64 tracker index, iou (K,) float64 nonzero,
        row-major within each frame, and entry_start (F + 1,) int64 offsets of each frame's
        entries.
    """
    n_frames = len(gt_start) - 1
    g, j = _candidates(gt, gt_start, res, res_start)
    ga, ra = gt[:, 2] * gt[:, 3], res[:, 2] * res[:, 3]  # areas, then x2 = x + w, y2 = y + h
    gx, gy, gx2, gy2 = gt[:, 0], gt[:, 1], gt[:, 0] + gt[:, 2], gt[:, 1] + gt[:, 3]
    rx, ry, rx2, ry2 = res[:, 0], res[:, 1], res[:, 0] + res[:, 2], res[:, 1] + res[:, 3]
    w = np.minimum(gx2[g], rx2[j]) - np.maximum(gx[g], rx[j])
    g, j, w = g[w > 0], j[w > 0], w[w > 0]  # elsewhere the intersection is 0
    h = np.minimum(gy2[g], ry2[j]) - np.maximum(gy[g], ry[j])
    g, j, w, h = g[h > 0], j[h > 0], w[h > 0], h[h > 0]
    inter = w * h
    union = ga[g] + ra[j] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        iou = np.where(union > 0, inter / union, 0.0)
    keep = iou != 0
    g, j, iou = g[keep], j[keep], iou[keep]
    order = np.argsort(g * len(res) + j, kind="stable")  # row-major (gt rows by frame already)
    g, j, iou = g[order], j[order], iou[order]
    frame = np.searchsorted(gt_start, g, side="right") - 1
    entry_start = np.searchsorted(frame, np.arange(n_frames + 1)).astype(np.int64)
    return g.astype(np.int64), j.astype(np.int64), iou, entry_start


def _candidates(gt: np.ndarray, gt_start: np.ndarray, res: np.ndarray, res_start: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """(C,) gt and (C,) tracker indices of the box pairs of one frame that may overlap along
    x: every pair with a nonzero IoU, and few others."""
    n_frames = len(gt_start) - 1
    if len(gt) == 0 or len(res) == 0:
        z = np.zeros(0, np.int64)
        return z, z
    g_frame = np.repeat(np.arange(n_frames), np.diff(gt_start))
    r_frame = np.repeat(np.arange(n_frames), np.diff(res_start))
    lo_x = min(gt[:, 0].min(), res[:, 0].min())
    span = max((gt[:, 0] + gt[:, 2]).max(), (res[:, 0] + res[:, 2]).max()) - lo_x + 2
    span += res[:, 2].max()
    margin = 1.0 + span * n_frames * 1e-12  # for the rounding of the keys below
    key = r_frame * span + (res[:, 0] - lo_x)  # frame, then left edge
    by_key = np.argsort(key, kind="stable")
    key = key[by_key]
    base = g_frame * span - lo_x
    first = np.searchsorted(key, base + gt[:, 0] - res[:, 2].max() - margin, side="left")
    last = np.searchsorted(key, base + gt[:, 0] + gt[:, 2] + margin, side="right")
    count = np.maximum(last - first, 0)
    g = np.repeat(np.arange(len(gt)), count)
    j = by_key[np.arange(count.sum()) - np.repeat(np.cumsum(count) - count - first, count)]
    same = r_frame[j] == g_frame[g]  # the margins may reach into the next frame
    return g[same], j[same]
