"""HOTA (Luiten et al., IJCV 2021), following TrackEval's ``HOTA.eval_sequence`` exactly.

Per sequence, for the localisation thresholds alpha = 0.05, 0.10, ..., 0.95:

1. Global alignment score between every gt id g and tracker id t: the similarity-weighted
   potential matches, summed over frames (per frame, ``S / (rowsum + colsum - S)``), divided
   by ``|g| + |t| - potential``.
2. One Hungarian assignment per frame maximising ``alignment score * similarity``; a matched
   pair counts as a true positive for each alpha with ``similarity >= alpha`` (the assignment
   does not depend on alpha, as in TrackEval).
3. DetA = TP / (TP + FN + FP); AssA = sum over TP of ``|TPA| / (|TPA| + |FNA| + |FPA|)``
   divided by TP; LocA = mean similarity of the TPs (1 when TP = 0, as TrackEval);
   HOTA = sqrt(DetA * AssA). Reported figures are the means over the 19 alphas.

Sequences are combined as TrackEval's ``combine_sequences``: TP, FN, FP summed per alpha;
AssA, AssRe, AssPr and LocA averaged with the per-sequence TP counts as weights.

Everything is vectorised over pairs and alphas; the only Python loop is over frames (one
Hungarian per frame). Association counts are kept sparse (one entry per gt/tracker id pair
that ever co-occurs), so memory does not grow with ``#gt ids * #tracker ids``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

ALPHAS: np.ndarray = np.arange(0.05, 0.99, 0.05)  # the 19 thresholds, exactly TrackEval's
_EPS = np.finfo(float).eps


@dataclass
class HotaCounts:
    """Per-alpha HOTA counts of one sequence (or of combined sequences).

    All arrays are (19,) float64, one entry per value of ``ALPHAS``.

    Attributes:
        tp, fn, fp: HOTA_TP, HOTA_FN, HOTA_FP detection counts.
        ass_a, ass_re, ass_pr: association accuracy, recall and precision.
        loc_a: localisation accuracy (mean similarity of the TPs; 1 when there are none).
    """

    tp: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    fn: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    fp: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    ass_a: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    ass_re: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    ass_pr: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    loc_a: np.ndarray = field(default_factory=lambda: np.ones(len(ALPHAS)))

    @property
    def det_re(self) -> np.ndarray:
        return self.tp / np.maximum(1.0, self.tp + self.fn)

    @property
    def det_pr(self) -> np.ndarray:
        return self.tp / np.maximum(1.0, self.tp + self.fp)

    @property
    def det_a(self) -> np.ndarray:
        """(19,) DetA per alpha."""
        return self.tp / np.maximum(1.0, self.tp + self.fn + self.fp)

    @property
    def hota(self) -> np.ndarray:
        """(19,) HOTA per alpha."""
        return np.sqrt(self.det_a * self.ass_a)

    def summary(self) -> dict[str, float]:
        """HOTA, DetA, AssA, LocA (and DetRe, DetPr, AssRe, AssPr) averaged over alpha."""
        return {
            "HOTA": float(self.hota.mean()),
            "DetA": float(self.det_a.mean()),
            "AssA": float(self.ass_a.mean()),
            "LocA": float(self.loc_a.mean()),
            "DetRe": float(self.det_re.mean()),
            "DetPr": float(self.det_pr.mean()),
            "AssRe": float(self.ass_re.mean()),
            "AssPr": float(self.ass_pr.mean()),
        }


def hota_counts(
    gt_ids: Sequence[np.ndarray],
    tracker_ids: Sequence[np.ndarray],
    similarity: Sequence[np.ndarray],
) -> HotaCounts:
    """HOTA counts of one sequence.

    Args:
        gt_ids: per frame, (N_t,) int ids of the scored gt boxes (unique within a frame).
        tracker_ids: per frame, (M_t,) int ids of the tracker boxes (unique within a frame).
        similarity: per frame, (N_t, M_t) float64 similarity in [0, 1] (IoU for boxes).
    Returns:
        HotaCounts with TrackEval's per-alpha TP/FN/FP, AssA/AssRe/AssPr and LocA.
    """
    if not len(gt_ids) == len(tracker_ids) == len(similarity):
        raise ValueError(
            f"gt_ids, tracker_ids and similarity must have one entry per frame, got "
            f"{len(gt_ids)}, {len(tracker_ids)}, {len(similarity)}"
        )
    n_alpha = len(ALPHAS)
    res = HotaCounts()
    n_gt_dets = sum(len(g) for g in gt_ids)
    n_tr_dets = sum(len(t) for t in tracker_ids)
    if n_tr_dets == 0:
        res.fn[:] = n_gt_dets
        return res
    if n_gt_dets == 0:
        res.fp[:] = n_tr_dets
        return res

    # contiguous id indices (TrackEval relabels the same way)
    all_g = np.concatenate([np.asarray(g, dtype=np.int64) for g in gt_ids])
    all_t = np.concatenate([np.asarray(t, dtype=np.int64) for t in tracker_ids])
    g_uniq, g_idx = np.unique(all_g, return_inverse=True)
    t_uniq, t_idx = np.unique(all_t, return_inverse=True)
    n_t_ids = len(t_uniq)
    gt_id_count = np.bincount(g_idx, minlength=len(g_uniq)).astype(float)  # |g|
    tr_id_count = np.bincount(t_idx, minlength=n_t_ids).astype(float)  # |t|

    # 1. potential matches, one flat key g * n_t_ids + t per co-occurring pair
    g_off = np.cumsum([0] + [len(g) for g in gt_ids])
    t_off = np.cumsum([0] + [len(t) for t in tracker_ids])
    keys: list[np.ndarray] = []
    sim_ious: list[np.ndarray] = []
    frames: list[tuple[np.ndarray, np.ndarray, np.ndarray, int]] = []
    n_pairs = 0
    for f, s in enumerate(similarity):
        gi = g_idx[g_off[f] : g_off[f + 1]]
        ti = t_idx[t_off[f] : t_off[f + 1]]
        n, m = len(gi), len(ti)
        if n == 0 or m == 0:
            frames.append((gi, ti, np.zeros((n, m)), -1))
            continue
        s = np.asarray(s, dtype=np.float64).reshape(n, m)
        denom = s.sum(0)[None, :] + s.sum(1)[:, None] - s
        sim_iou = np.zeros_like(s)
        ok = denom > 0 + _EPS
        sim_iou[ok] = s[ok] / denom[ok]
        keys.append((gi[:, None] * n_t_ids + ti[None, :]).ravel())
        sim_ious.append(sim_iou.ravel())
        frames.append((gi, ti, s, n_pairs))
        n_pairs += n * m
    pair_keys, pair_inv = np.unique(np.concatenate(keys), return_inverse=True)
    potential = np.bincount(pair_inv, weights=np.concatenate(sim_ious), minlength=len(pair_keys))
    pg, pt = np.divmod(pair_keys, n_t_ids)
    alignment = potential / (gt_id_count[pg] + tr_id_count[pt] - potential)

    # 2. per-frame Hungarian on alignment * similarity, thresholded per alpha
    loc_sum = np.zeros(n_alpha)
    match_key: list[np.ndarray] = []
    match_sim: list[np.ndarray] = []
    for gi, ti, s, start in frames:
        n, m = s.shape
        if n == 0 or m == 0:
            res.fp += m
            res.fn += n
            continue
        inv = pair_inv[start : start + n * m]
        score = alignment[inv].reshape(n, m) * s
        rows, cols = linear_sum_assignment(-score)
        sims = s[rows, cols]
        matched = sims[None, :] >= ALPHAS[:, None] - _EPS  # (19, K)
        n_match = matched.sum(1)
        res.tp += n_match
        res.fn += n - n_match
        res.fp += m - n_match
        loc_sum += (matched * sims[None, :]).sum(1)
        match_key.append(inv.reshape(n, m)[rows, cols])
        match_sim.append(sims)

    # 3. association scores from the per-pair match counts (sparse over pairs)
    if match_key:
        mk = np.concatenate(match_key)
        ms = np.concatenate(match_sim)
        used, mk_inv = np.unique(mk, return_inverse=True)
        ug, ut = pg[used], pt[used]
        ok = ms[None, :] >= ALPHAS[:, None] - _EPS  # (19, K_total)
        counts = np.stack(
            [np.bincount(mk_inv, weights=ok[a], minlength=len(used)) for a in range(n_alpha)]
        )  # (19, P) matches per (g, t) pair and alpha
        tp = np.maximum(1.0, res.tp)
        g_c, t_c = gt_id_count[ug][None, :], tr_id_count[ut][None, :]
        res.ass_a = (counts * counts / np.maximum(1.0, g_c + t_c - counts)).sum(1) / tp
        res.ass_re = (counts * counts / np.maximum(1.0, g_c)).sum(1) / tp
        res.ass_pr = (counts * counts / np.maximum(1.0, t_c)).sum(1) / tp
    res.loc_a = np.maximum(1e-10, loc_sum) / np.maximum(1e-10, res.tp)
    return res


def combine_hota(parts: Sequence[HotaCounts]) -> HotaCounts:
    """Combine sequences as TrackEval: sum TP/FN/FP; TP-weighted AssA, AssRe, AssPr, LocA."""
    out = HotaCounts()
    if not parts:
        return out
    out.tp = np.sum([p.tp for p in parts], axis=0)
    out.fn = np.sum([p.fn for p in parts], axis=0)
    out.fp = np.sum([p.fp for p in parts], axis=0)
    w = np.maximum(1.0, out.tp)
    out.ass_a = np.sum([p.ass_a * p.tp for p in parts], axis=0) / w
    out.ass_re = np.sum([p.ass_re * p.tp for p in parts], axis=0) / w
    out.ass_pr = np.sum([p.ass_pr * p.tp for p in parts], axis=0) / w
    loc = np.sum([p.loc_a * p.tp for p in parts], axis=0)
    out.loc_a = np.maximum(1e-10, loc) / np.maximum(1e-10, out.tp)
    return out
