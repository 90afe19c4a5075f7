"""Compiled per-frame bookkeeping of ``trackers.layered.tracker`` (numba, one core).

Small loops over the (target, candidate) pairs of a frame that numpy would spell as a
few dozen (T, N) temporaries. Every value is computed by the same floating-point
operations, in the same order, as the numpy expressions quoted in the docstrings, so the
tracker's outputs do not change.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def gated_pairs(boxes: np.ndarray, regions: np.ndarray, heads: np.ndarray,
                heads_in_region: np.ndarray, gates: np.ndarray, pred_wh: np.ndarray,
                kinds: np.ndarray, dof: np.ndarray, misses: np.ndarray,
                search_overlap: float) -> tuple:  # pragma: no cover (compiled)
    """Gating (PBM 3) and the occlusion test's pairs (PBM 3.1) of T targets and N candidates.

    A candidate is in target t's gate (xywh ``gates[t]``) when its box centre
    ``box[:2] + 0.5 box[2:]`` lies in it (borders included). ``kinds`` (T, N) (0, +1
    larger, -1 smaller; ``search.occlusion_kinds``) is set to +1 in place where it is 0
    and the candidate's region holds several heads (a merge). The occluded pairs keep only
    those whose carved candidate lies in the gate too (head x, head y + 0.5 KF2 height)
    and, when ``search_overlap`` > 0, whose larger region holds the target: a smaller
    region, a target missed last frame, or ``geometry.overlap_ratio_matrix(boxes of dof,
    regions)[t, n] >= search_overlap``.

    Args:
        boxes, regions: (N, 4) xywh candidate boxes and regions. heads: (N, 3) heads.
        heads_in_region: (N,) int. gates: (T, 4) xywh. pred_wh: (T, 2) KF2 (w, h).
        dof: (T, 6) the targets' global models (xtl, ytl, xc, yc, w, h). misses: (T,) int.
    Returns:
        (ti, n) of the unoccluded pairs in the gates, then (ti, n, kind) of the occluded
        pairs to search or align, each in row-major order (as ``np.nonzero``).
    """
    T, N = kinds.shape
    inside = np.zeros((T, N), np.bool_)
    n_in, n_occ = 0, 0
    for t in range(T):
        gx0, gy0 = gates[t, 0], gates[t, 1]
        gx1, gy1 = gx0 + gates[t, 2], gates[t, 3] + gy0
        for n in range(N):
            if kinds[t, n] == 0 and heads_in_region[n] > 1:
                kinds[t, n] = 1
            cx = boxes[n, 0] + 0.5 * boxes[n, 2]
            cy = boxes[n, 1] + 0.5 * boxes[n, 3]
            if gx0 <= cx <= gx1 and gy0 <= cy <= gy1:
                inside[t, n] = True
                if kinds[t, n] == 0:
                    n_in += 1
                else:
                    n_occ += 1
    ti_in, n_in_ = np.empty(n_in, np.intp), np.empty(n_in, np.intp)
    ti_s, n_s, kind_s = np.empty(n_occ, np.intp), np.empty(n_occ, np.intp), np.empty(n_occ, np.int64)
    a, b = 0, 0
    for t in range(T):
        gx0, gy0 = gates[t, 0], gates[t, 1]
        gx1, gy1 = gx0 + gates[t, 2], gates[t, 1] + gates[t, 3]
        # target t's box as x1 y1 x2 y2 and area (``overlap_ratio_matrix``)
        ax0, ay0 = dof[t, 0], dof[t, 1]
        ax1, ay1 = ax0 + dof[t, 4], ay0 + dof[t, 5]
        area = dof[t, 4] * dof[t, 5]
        for n in range(N):
            if not inside[t, n]:
                continue
            kind = kinds[t, n]
            if kind == 0:
                ti_in[a], n_in_[a] = t, n
                a += 1
                continue
            hx, hy = heads[n, 0], heads[n, 1] + 0.5 * pred_wh[t, 1]
            if not (gx0 <= hx <= gx1 and gy0 <= hy <= gy1):
                continue
            if search_overlap > 0 and kind > 0 and misses[t] <= 0:
                bx0, by0 = regions[n, 0], regions[n, 1]
                bx1, by1 = bx0 + regions[n, 2], by0 + regions[n, 3]
                w = min(ax1, bx1) - max(ax0, bx0)
                h = min(ay1, by1) - max(ay0, by0)
                inter = max(w, 0.0) * max(h, 0.0)
                ratio = inter / area if area > 0 else 0.0
                if not ratio >= search_overlap:
                    continue
            ti_s[b], n_s[b], kind_s[b] = t, n, kind
            b += 1
    return ti_in, n_in_, ti_s[:b], n_s[:b], kind_s[:b]


@numba.njit(cache=True)
def nonzero_mask(values: np.ndarray) -> tuple:  # pragma: no cover (compiled)
    """The foreground (PBM 2) of an (H, W) label image or mask in one pass: (H, W) bool
    ``values != 0`` and its number of True pixels (``np.count_nonzero``)."""
    H, W = values.shape
    mask = np.empty((H, W), np.bool_)
    count = 0
    for r in range(H):
        for c in range(W):
            v = values[r, c] != 0
            mask[r, c] = v
            count += v
    return mask, count
