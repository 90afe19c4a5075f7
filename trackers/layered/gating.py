"""PBM 3 and 3.1, compiled: which (target, candidate) pairs a frame scores (the KF1 gate
and the occlusion test's pairs, ``gated_pairs``) and the occluded candidates the search
carves (``carved_rows``; the DOF of eqs. 1-2 under occlusion, ``split.dof_from_head``).
"""

from __future__ import annotations

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)
from occbench.trackers.layered.split import _dof_from_head

# ----------------------------------------------------------------------------- PBM 3, 3.1


@numba.njit(cache=True)
def _held(dof: np.ndarray, t: int, region: np.ndarray, ratio: float) -> bool:  # pragma: no cover
    """At least ``ratio`` of target t's box (dof columns 0, 1, 4, 5) lies inside ``region``
    (``geometry.overlap_ratio_matrix``)."""
    area = dof[t, 4] * dof[t, 5]
    w = min(dof[t, 0] + dof[t, 4], region[0] + region[2]) - max(dof[t, 0], region[0])
    h = min(dof[t, 1] + dof[t, 5], region[1] + region[3]) - max(dof[t, 1], region[1])
    inter = max(w, 0.0) * max(h, 0.0)
    return (inter / area if area > 0 else 0.0) >= ratio


@numba.njit(cache=True)
def _lone_growth(kinds: np.ndarray, regions: np.ndarray, heads_in_region: np.ndarray,
                 dof: np.ndarray, present: np.ndarray, ratio: float) -> None:  # pragma: no cover
    """``gated_pairs``' lone growth, in place on ``kinds``."""
    T, N = kinds.shape
    for n in range(N):
        if heads_in_region[n] > 1:
            continue
        owner, holders = -1, 0
        for t in range(T):
            if present[t] and _held(dof, t, regions[n], ratio):
                owner, holders = t, holders + 1
        if holders == 1 and kinds[owner, n] > 0:
            kinds[owner, n] = 0


@numba.njit(cache=True)
def gated_pairs(boxes: np.ndarray, regions: np.ndarray, heads: np.ndarray,
                heads_in_region: np.ndarray, grown_heads: np.ndarray, gates: np.ndarray,
                pred_wh: np.ndarray, kinds: np.ndarray, dof: np.ndarray, misses: np.ndarray,
                search_overlap: float, present: np.ndarray,
                several_heads_merge: bool) -> tuple:  # pragma: no cover (compiled)
    """Gating (PBM 3) and the occlusion test's pairs (PBM 3.1) of T targets and N candidates.

    A candidate is in target t's gate (xywh ``gates[t]``) when its box centre
    ``box[:2] + 0.5 box[2:]`` lies in it (borders included). ``kinds`` (T, N) (0, +1
    larger, -1 smaller; ``search.occlusion_kinds``) is set to +1 in place where it is 0
    and the candidate's region holds several heads (a merge) when ``several_heads_merge``
    (an adaptation; the paper's occlusion test is by size alone, PBM 3.1). The occluded pairs keep only
    those whose carved candidate lies in the gate too (head x, head y + 0.5 KF2 height)
    and, when ``search_overlap`` > 0, whose larger region holds the target: a smaller
    region, a target missed last frame, or ``geometry.overlap_ratio_matrix(boxes of dof,
    regions)[t, n] >= search_overlap``.

    Lone growth (adaptation): a region larger only by size (one head by ``grown_heads``,
    which may count more than ``heads_in_region``: ``candidates.HeldDetections``) that
    holds target t and no other ``present`` target (both by ``search_overlap`` of their
    boxes) is t itself, grown (entering through a border or a doorway, coming closer), not
    a merge: the pair is unoccluded (kind 0). ``present`` all False: never.

    Args:
        boxes, regions: (N, 4) xywh candidate boxes and regions. heads: (N, 3) heads.
        heads_in_region: (N,) int. grown_heads: (N,) int, the heads lone growth counts.
        gates: (T, 4) xywh. pred_wh: (T, 2) KF2 (w, h).
        dof: (T, 6) the targets' global models (xtl, ytl, xc, yc, w, h). misses: (T,) int.
        present: (T,) bool, the targets whose boxes can hold a region (found or recently
            missed).
    Returns:
        (ti, n) of the unoccluded pairs in the gates, then (ti, n, kind) of the occluded
        pairs to search or align, each in row-major order (as ``np.nonzero``).
    """
    T, N = kinds.shape
    if search_overlap > 0:
        _lone_growth(kinds, regions, grown_heads, dof, present, search_overlap)
    inside = np.zeros((T, N), np.bool_)
    n_in, n_occ = 0, 0
    for t in range(T):
        gx0, gy0 = gates[t, 0], gates[t, 1]
        gx1, gy1 = gx0 + gates[t, 2], gates[t, 3] + gy0
        for n in range(N):
            if several_heads_merge and kinds[t, n] == 0 and heads_in_region[n] > 1:
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
            if (search_overlap > 0 and kind > 0 and misses[t] <= 0
                    and not _held(dof, t, regions[n], search_overlap)):
                continue
            ti_s[b], n_s[b], kind_s[b] = t, n, kind
            b += 1
    return ti_in, n_in_, ti_s[:b], n_s[:b], kind_s[:b]


@numba.njit(cache=True)
def carved_rows(p: np.ndarray, pj: np.ndarray, boxes: np.ndarray, heads: np.ndarray,
                ti: np.ndarray, alpha: np.ndarray, beta: np.ndarray, search_q: np.ndarray,
                align_q: np.ndarray, m: int) -> tuple:  # pragma: no cover (compiled)
    """The occluded candidates of P (target ti, head) pairs (PBM 3.1) from the scores of
    the carved boxes: searched pair ``search_q[s]`` owns boxes s m .. s m + m - 1 (eqs.
    9-10) and keeps the best (``np.argmax``: the first maximum); aligned pair
    ``align_q[a]`` owns box len(search_q) m + a. Pairs in neither are dismissed.

    Returns:
        kept (P,) bool, p (P,), p_j (P, 5), box index k (P,) and the DOF under occlusion
        (P, 6) (``_dof_from_head``, eqs. 1-2, of the head with the box's w, h and the
        target's alpha, beta).
    """
    P = ti.shape[0]
    kept = np.zeros(P, np.bool_)
    k = np.zeros(P, np.int64)
    for s in range(search_q.shape[0]):
        b = s * m
        if not np.isnan(p[b]):
            for j in range(s * m + 1, s * m + m):
                if np.isnan(p[j]):
                    b = j
                    break
                if p[j] > p[b]:
                    b = j
        kept[search_q[s]] = True
        k[search_q[s]] = b
    for a in range(align_q.shape[0]):
        kept[align_q[a]] = True
        k[align_q[a]] = search_q.shape[0] * m + a
    p_out = np.zeros(P)
    pj_out = np.zeros((P, pj.shape[1]))
    dof = np.zeros((P, 6))
    for q in range(P):
        if not kept[q]:
            continue
        b, t = k[q], ti[q]
        p_out[q] = p[b]
        pj_out[q] = pj[b]
        _dof_from_head(heads[q, 0], heads[q, 1], boxes[b, 2], boxes[b, 3], alpha[t], beta[t],
                       dof[q])                                               # eqs. 1-2
    return kept, p_out, pj_out, k, dof
