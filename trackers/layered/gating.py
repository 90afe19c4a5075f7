"""PBM 3 and 3.1: which (target, candidate) pairs a frame scores (the KF1 gate and the
occlusion test's pairs: ``pairs_in_gates``, compiled ``gated_pairs``) and the search of the
occluded ones (``OcclusionSearch``: the head-anchored boxes of eqs. 9-10 or the aligned box,
scored by eqs. 11-13; the carved candidates, compiled ``carved_rows``, with the DOF of eqs.
1-2 under occlusion, ``split.dof_from_head``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)
from occbench.trackers.layered.search import head_fill, search_boxes_many
from occbench.trackers.layered.split import _dof_from_head

if TYPE_CHECKING:  # annotations only
    from occbench.trackers.layered.association import LayeredScores
    from occbench.trackers.layered.params import SearchParams
    from occbench.trackers.layered.parts import PartFeatureExtractor, PartFeatures
    from occbench.trackers.layered.search import Candidates
    from occbench.trackers.layered.targets import Targets

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
def in_gates(boxes: np.ndarray, gates: np.ndarray) -> np.ndarray:  # pragma: no cover (compiled)
    """PBM 3's gate: (T, N) bool, candidate n (xywh ``boxes`` (N, 4)) in target t's gate
    (xywh ``gates`` (T, 4)): its box centre ``box[:2] + 0.5 box[2:]`` lies in it, borders
    included (False where a gate is NaN)."""
    T, N = gates.shape[0], boxes.shape[0]
    inside = np.zeros((T, N), np.bool_)
    for t in range(T):
        gx0, gy0 = gates[t, 0], gates[t, 1]
        gx1, gy1 = gx0 + gates[t, 2], gates[t, 3] + gy0
        for n in range(N):
            cx = boxes[n, 0] + 0.5 * boxes[n, 2]
            cy = boxes[n, 1] + 0.5 * boxes[n, 3]
            if gx0 <= cx <= gx1 and gy0 <= cy <= gy1:
                inside[t, n] = True
    return inside


@numba.njit(cache=True)
def gated_pairs(boxes: np.ndarray, regions: np.ndarray, heads: np.ndarray,
                heads_in_region: np.ndarray, grown_heads: np.ndarray, gates: np.ndarray,
                pred_wh: np.ndarray, kinds: np.ndarray, dof: np.ndarray, misses: np.ndarray,
                search_overlap: float, present: np.ndarray,
                several_heads_merge: bool) -> tuple:  # pragma: no cover (compiled)
    """Gating (PBM 3) and the occlusion test's pairs (PBM 3.1) of T targets and N candidates.

    A candidate is in target t's gate (xywh ``gates[t]``) when its box centre
    ``box[:2] + 0.5 box[2:]`` lies in it (borders included; ``in_gates``). ``kinds`` (T, N) (0, +1
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
    inside = in_gates(boxes, gates)
    n_in, n_occ = 0, 0
    for t in range(T):
        for n in range(N):
            if several_heads_merge and kinds[t, n] == 0 and heads_in_region[n] > 1:
                kinds[t, n] = 1
            if inside[t, n]:
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


# ----------------------------------------------------------------------------- the tracker's steps


class Gated(NamedTuple):
    """The pairs (target, candidate) of a frame (PBM 3): ``ti``, ``n`` unoccluded, scored
    as measured; ``search_ti``, ``search_n``, ``kind`` occluded (PBM 3.1; kind +1 larger,
    -1 smaller region), searched or aligned. Each in row-major order."""

    ti: np.ndarray
    n: np.ndarray
    search_ti: np.ndarray
    search_n: np.ndarray
    kind: np.ndarray


def pairs_in_gates(targets: Targets, cand: Candidates, gates: np.ndarray, pred_wh: np.ndarray,
                   kinds: np.ndarray, present: np.ndarray, overlap: float,
                   several_heads_merge: bool) -> Gated:
    """``gated_pairs`` of the frame's targets (their KF1 ``gates`` and KF2 ``pred_wh``) and
    candidates, ``kinds`` (T, N) the occlusion test's (changed in place); lone growth counts
    a blob's held detections among its heads."""
    grown_heads = cand.heads_in_region if cand.held is None else cand.heads_in_region + cand.held
    return Gated(*gated_pairs(cand.box, cand.region, cand.head, cand.heads_in_region, grown_heads,
                              gates, pred_wh, kinds, targets.dof, targets.misses, overlap, present,
                              several_heads_merge))


class Carved(NamedTuple):
    """The occluded candidates of P searched pairs (``OcclusionSearch``): ``kept`` (P,) bool
    (False: dismissed), score ``p`` (P,), part scores ``pj`` (P, 5), the features ``feats``
    of each pair's best box (row q: pair q's, ``k`` = arange(P)), and its ``dof`` (P, 6)."""

    kept: np.ndarray
    p: np.ndarray
    pj: np.ndarray
    feats: PartFeatures
    k: np.ndarray
    dof: np.ndarray


class OcclusionSearch:
    """Head-anchored search (larger region) or alignment (smaller) of PBM 3.1 for the
    occluded pairs of a frame, all boxes scored in one call (``LayeredScores.boxes``): the
    (2 r + 1)^2 boxes of eqs. 9-10 of every searched pair, then the aligned box (the
    predicted size on the head, ``search.aligned_box``) of every smaller candidate whose
    head is supported by foreground (``search.head_min_fill``; else dismissed).

    Args:
        search: the occlusion test's and the search's settings. scores: eqs. 11-13.
        extractor: the features of the search's boxes (its grid), started on the frame.
        coarse: each pair's boxes searched coarse to fine (``adaptations.coarse_search``).
    """

    def __init__(self, search: SearchParams, scores: LayeredScores,
                 extractor: PartFeatureExtractor, coarse: bool = False) -> None:
        self.search = search
        self.scores = scores
        self.extractor = extractor
        self.coarse = coarse

    def __call__(self, targets: Targets, cand: Candidates, pairs: Gated, fg: np.ndarray | None,
                 pred_wh: np.ndarray, model: PartFeatures, misses: np.ndarray | None
                 ) -> Carved | None:
        """The carved candidates of ``pairs``' occluded ones against the targets' parts
        ``model`` (eq. 11's ``misses``), or None when every pair is dismissed."""
        ti, n, kind = pairs.search_ti, pairs.search_n, pairs.kind
        alpha_t, beta_t = targets.alpha, targets.beta
        heads = cand.head[n]
        search_q = (kind > 0).nonzero()[0]
        align_q = (kind <= 0).nonzero()[0]
        if len(align_q):
            # the predicted-size box aligned on the head (``search.aligned_box``)
            at = ti[align_q]
            w, h = pred_wh[at, 0], pred_wh[at, 1]
            ha = heads[align_q]
            align_boxes = np.column_stack([ha[:, 0] - alpha_t[at] * w, ha[:, 1], w, h])
            if fg is not None:
                fill = np.array([head_fill(fg, b) for b in align_boxes])
                supported = fill >= self.search.head_min_fill
                align_q, align_boxes = align_q[supported], align_boxes[supported]
        if not len(search_q) and not len(align_q):
            return None
        m, sti = (2 * self.search.range + 1) ** 2, ti[search_q]  # boxes per searched pair
        B = np.concatenate([search_boxes_many(heads[search_q], pred_wh[sti], alpha_t[sti],
                                              self.search.step, self.search.range).reshape(-1, 4),
                            align_boxes if len(align_q) else np.zeros((0, 4))])
        tis = np.concatenate([sti.repeat(m), ti[align_q]])
        ex = self.extractor  # eqs. 11-13 of box k against target tis[k], best of m
        pj, p = self.scores.boxes(model, ex, B, alpha_t[tis], beta_t[tis], tis, misses, m,
                                  len(search_q) * m, self.coarse)
        kept, p_h, pj_h, k, dof = carved_rows(p, pj, B, heads, ti, alpha_t, beta_t, search_q,
                                              align_q, m)
        feats = ex.extract(B[k], alpha_t[tis[k]], beta_t[tis[k]])
        return Carved(kept, p_h, pj_h, feats, np.arange(len(k)), dof)
