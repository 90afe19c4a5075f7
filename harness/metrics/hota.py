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

The similarities are the nonzero IoUs of ``occbench.metrics.frames.FramePairs``; everything
is kept sparse over the gt/tracker id pairs that ever overlap (potential matches, alignment
scores, match counts per alpha), so memory does not grow with ``#gt ids * #tracker ids``
(TrackEval holds a dense matrix of each, 19 of them for the match counts). The only Python
loops are over frames: a frame's dense similarity for its row and column sums, and one
Hungarian assignment per frame on the same dense score matrix as TrackEval (ties broken
alike); the counts are then taken from the matched entries at once, LocA's similarities
summed in TrackEval's order.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from occbench.metrics.frames import FramePairs

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


def hota_counts(pairs: FramePairs) -> HotaCounts:
    """HOTA counts of one sequence.

    Args:
        pairs: the scored gt and tracker boxes per frame and their IoU, the similarity
            (``occbench.metrics.frames``).
    Returns:
        HotaCounts with TrackEval's per-alpha TP/FN/FP, AssA/AssRe/AssPr and LocA.
    """
    res = HotaCounts()
    if len(pairs.tracker_ids) == 0:
        res.fn[:] = len(pairs.gt_ids)
        return res
    if len(pairs.gt_ids) == 0:
        res.fp[:] = len(pairs.tracker_ids)
        return res
    m = hota_matches(pairs, res)
    association(res, m.pair, m.sim, m.g_count, m.t_count)
    return res


@dataclass
class HotaMatches:
    """Step 2's matches of one sequence (``hota_matches``).

    Attributes:
        pair, sim, frame: (K,) int64 id-pair index, float64 similarity and int64 frame index
            (into ``FramePairs.frames``) of each matched box pair with similarity > 0.
        g_count, t_count: (P,) float64 boxes of the gt id and of the tracker id of each pair.
    """

    pair: np.ndarray
    sim: np.ndarray
    frame: np.ndarray
    g_count: np.ndarray
    t_count: np.ndarray


def hota_matches(pairs: FramePairs, res: HotaCounts) -> HotaMatches:
    """Steps 1 and 2 on a sequence with gt and tracker boxes: the global alignment and the
    per-frame matches; adds TP, FN, FP and LocA to ``res`` (``match_frames``). Read by
    ``hota_counts`` and by the per-frame timeline (``occbench.metrics.timeline``)."""
    # contiguous id indices (TrackEval relabels the same way)
    g_uniq, g_idx = np.unique(pairs.gt_ids, return_inverse=True)
    t_uniq, t_idx = np.unique(pairs.tracker_ids, return_inverse=True)
    g_count = np.bincount(g_idx, minlength=len(g_uniq)).astype(float)  # |g|
    t_count = np.bincount(t_idx, minlength=len(t_uniq)).astype(float)  # |t|
    # one code g * T + t per nonzero similarity entry; the pairs that ever overlap
    codes = g_idx[pairs.row] * len(t_uniq) + t_idx[pairs.col]
    pair_codes, pair_of_entry = np.unique(codes, return_inverse=True)
    pg, pt = np.divmod(pair_codes, len(t_uniq))
    alignment = global_alignment(pairs, pair_of_entry, len(pair_codes), g_count[pg], t_count[pt])
    pair, sim, frame = match_frames(pairs, alignment, pair_of_entry, res)
    return HotaMatches(pair, sim, frame, g_count[pg], t_count[pt])


def global_alignment(pairs: FramePairs, pair_of_entry: np.ndarray, n_pairs: int,
                     g_count: np.ndarray, t_count: np.ndarray) -> np.ndarray:
    """(P,) global alignment score of each overlapping id pair (step 1): the potential
    matches ``S / (rowsum + colsum - S)`` summed over frames, over ``|g| + |t| - potential``.

    The sums run in frame order over the nonzero entries only (a zero entry adds 0 exactly),
    so they equal TrackEval's dense accumulation bit for bit.
    """
    sim_iou = np.zeros(len(pairs.iou))
    for k in range(len(pairs)):
        _, _, s = pairs.frame(k)
        if s.size == 0:
            continue
        r, c, e = pairs.entries(k)
        denom = s.sum(0)[c] + s.sum(1)[r] - pairs.iou[e]
        sim_iou[e] = np.where(denom > 0 + _EPS, pairs.iou[e] / np.maximum(denom, _EPS), 0.0)
    potential = np.bincount(pair_of_entry, weights=sim_iou, minlength=n_pairs)
    return potential / (g_count + t_count - potential)


def match_frames(pairs: FramePairs, alignment: np.ndarray, pair_of_entry: np.ndarray,
                 res: HotaCounts) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 2: per frame, the Hungarian assignment maximising ``alignment * similarity``
    (``frame_assignments``); adds TP, FN, FP and LocA's sums per alpha to ``res``.

    Returns:
        (K,) pair index, (K,) similarity and (K,) frame index of the matched boxes with
        similarity > 0, by frame, then gt box.
    """
    score = alignment[pair_of_entry] * pairs.iou
    taken = np.flatnonzero(frame_assignments(pairs, score))
    sim = pairs.iou[taken]
    frame = np.searchsorted(pairs.entry_start, taken, side="right") - 1
    matched = sim[None, :] >= ALPHAS[:, None] - _EPS  # (19, K)
    n_match = matched.sum(1)
    res.tp += n_match
    res.fn += len(pairs.gt_ids) - n_match
    res.fp += len(pairs.tracker_ids) - n_match
    # LocA's sums added as TrackEval adds them: a frame's similarities in turn, then frames
    per_frame = np.stack([np.bincount(frame, weights=np.where(ok, sim, 0.0),
                                      minlength=len(pairs)) for ok in matched])
    loc_sum = np.cumsum(per_frame, axis=1)[:, -1] if len(pairs) else np.zeros(len(ALPHAS))
    res.loc_a = np.maximum(1e-10, loc_sum) / np.maximum(1e-10, res.tp)
    return pair_of_entry[taken], sim, frame.astype(np.int64)


def frame_assignments(pairs: FramePairs, score: np.ndarray) -> np.ndarray:
    """(E,) bool: the entries taken by one maximising Hungarian assignment on each frame's
    dense (N_k, M_k) matrix of ``score`` ((E,) float64, one per entry; 0 where a box pair
    has none), as TrackEval's ``linear_sum_assignment(-score)``."""
    taken = np.zeros(len(score), dtype=bool)
    for k in range(len(pairs)):
        r, c, e = pairs.entries(k)
        if e.start == e.stop:
            continue  # nothing to take
        n, m = (int(pairs.gt_start[k + 1] - pairs.gt_start[k]),
                int(pairs.tracker_start[k + 1] - pairs.tracker_start[k]))
        dense = np.zeros((n, m))
        dense[r, c] = score[e]
        index = np.full((n, m), -1)
        index[r, c] = np.arange(e.start, e.stop)
        rows, cols = linear_sum_assignment(-dense)
        hit = index[rows, cols]
        taken[hit[hit >= 0]] = True
    return taken


def association(res: HotaCounts, matched_pair: np.ndarray, matched_sim: np.ndarray,
                g_count: np.ndarray, t_count: np.ndarray) -> None:
    """Step 3: AssA, AssRe, AssPr per alpha from the matches of each id pair (sparse over
    the pairs ever matched), written into ``res``."""
    if len(matched_pair) == 0:
        return
    used, _, counts = pair_match_counts(matched_pair, matched_sim)
    tp = np.maximum(1.0, res.tp)
    g_c, t_c = g_count[used][None, :], t_count[used][None, :]
    res.ass_a = (counts * counts / np.maximum(1.0, g_c + t_c - counts)).sum(1) / tp
    res.ass_re = (counts * counts / np.maximum(1.0, g_c)).sum(1) / tp
    res.ass_pr = (counts * counts / np.maximum(1.0, t_c)).sum(1) / tp


def pair_match_counts(matched_pair: np.ndarray, matched_sim: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The id pairs ever matched: (P,) pair indices, (K,) each match's position among them,
    and (19, P) float64 matches per pair and alpha (|TPA| of step 3)."""
    used, inv = np.unique(matched_pair, return_inverse=True)
    ok = matched_sim[None, :] >= ALPHAS[:, None] - _EPS  # (19, K)
    counts = np.stack(
        [np.bincount(inv, weights=ok[a], minlength=len(used)) for a in range(len(ALPHAS))]
    )  # (19, P) matches per (g, t) pair and alpha
    return used, inv, counts


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
