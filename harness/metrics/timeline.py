"""Per-frame counts of one tracker on one sequence: the metrics' own matching, frame by frame.

``frame_counts(gt, res)`` pairs the boxes once (``occbench.metrics.frames.pair_frames``) and
reads the same matchings the sequence's scores come from: CLEAR's (``clear_matches``: misses,
false positives, identity switches), the identity mapping (``identity_pairs``: IDTP) and
HOTA's per-frame matches with their association scores (``hota_matches``). Every count is
additive over frames, and summed over a sequence's frames gives its MOTA, IDF1 and HOTA
exactly (``FrameCounts.total`` and ``scores``): the report's timeline and the paired
bootstrap (``occbench.metrics.paired``) read these, not a looser re-count.

HOTA per frame: at each alpha a, a TP of id pair c adds 1 to TP_a and A_a(c) = |TPA_a(c)| /
(|TPA_a(c)| + |FNA_a(c)| + |FPA_a(c)|) to the association sum, A_a(c) being the pair's
association score over the whole sequence; AssA_a = association sum / TP_a, and HOTA_a =
sqrt(DetA_a AssA_a) (Luiten et al. 2021, eqs. 9-11; combined over sequences as TrackEval).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from occbench.io.mot import MotTable
from occbench.metrics.clear import clear_matches
from occbench.metrics.frames import FramePairs, pair_frames
from occbench.metrics.hota import ALPHAS, HotaCounts, hota_matches, pair_match_counts
from occbench.metrics.identity import identity_pairs

#: the scalar per-frame counts, columns 0..5 of ``FrameCounts.matrix``
SCALARS = ("objects", "predictions", "misses", "false_positives", "switches", "idtp")
NA = len(ALPHAS)


@dataclass
class FrameCounts:
    """Counts of each frame of one tracker on one sequence.

    Attributes:
        frames: (F,) int64 frame numbers (gt or tracker boxes present), ascending.
        objects, predictions: (F,) int64 scored gt boxes and tracker boxes.
        misses, false_positives, switches: (F,) int64 CLEAR's FN, FP and ID switches.
        idtp: (F,) int64 boxes matched under the identity mapping (IDF1's IDTP).
        hota_tp, hota_fn, hota_fp: (F, 19) float64 HOTA's detection counts per alpha.
        hota_ass: (F, 19) float64 sum of the TPs' association scores per alpha.
    """

    frames: np.ndarray
    objects: np.ndarray
    predictions: np.ndarray
    misses: np.ndarray
    false_positives: np.ndarray
    switches: np.ndarray
    idtp: np.ndarray
    hota_tp: np.ndarray
    hota_fn: np.ndarray
    hota_fp: np.ndarray
    hota_ass: np.ndarray

    def matrix(self) -> np.ndarray:
        """(F, 6 + 4 * 19) float64: ``SCALARS``, then HOTA's TP, FN, FP, association sums."""
        cols = [getattr(self, n)[:, None] for n in SCALARS]
        return np.hstack([*cols, self.hota_tp, self.hota_fn, self.hota_fp, self.hota_ass])

    def total(self) -> np.ndarray:
        """(6 + 4 * 19,) the counts summed over the frames (``scores`` reads them)."""
        return self.matrix().sum(0)


def scores(total: np.ndarray) -> dict[str, np.ndarray]:
    """MOTA, IDF1 and HOTA of summed counts (``FrameCounts.total``, or a (B, D) stack of
    them: one row per bootstrap resample): ``ClearCounts.ratios``' MOTA and IDF1, vectorised,
    and ``HotaCounts``' HOTA.

    Returns:
        {"MOTA", "IDF1", "HOTA"}: float64 arrays of shape ``total.shape[:-1]`` (NaN where
        undefined, e.g. MOTA without gt).
    """
    t = np.atleast_2d(np.asarray(total, dtype=np.float64))
    obj, pred, fn, fp, sw, idtp = (t[:, i] for i in range(len(SCALARS)))
    h = [t[:, len(SCALARS) + i * NA: len(SCALARS) + (i + 1) * NA] for i in range(4)]
    hota = HotaCounts(tp=h[0], fn=h[1], fp=h[2], ass_a=h[3] / np.maximum(1.0, h[0]))
    with np.errstate(divide="ignore", invalid="ignore"):  # NaN where undefined, as _ratio
        # vectorised ClearCounts.ratios (tests check they agree): MOTA, and IDF1 with
        # IDFP = predictions - IDTP, IDFN = objects - IDTP
        mota = np.where(obj > 0, 1.0 - (fn + sw + fp) / obj, np.nan)
        den = 2 * idtp + (pred - idtp) + (obj - idtp)
        idf1 = np.where(den > 0, 2 * idtp / den, np.nan)
    out = {"MOTA": mota, "IDF1": idf1, "HOTA": hota.hota.mean(-1)}
    return {k: v.reshape(np.shape(total)[:-1]) for k, v in out.items()}


def frame_counts(gt: MotTable, res: MotTable, iou_threshold: float = 0.5) -> FrameCounts:
    """Per-frame counts of ``res`` against ``gt`` (both as ``score_sequence`` takes them)."""
    return counts_of_pairs(pair_frames(gt, res), iou_threshold)


def counts_of_pairs(pairs: FramePairs, iou_threshold: float = 0.5) -> FrameCounts:
    """``FrameCounts`` of paired boxes (``pair_frames``)."""
    n_f = len(pairs)
    objects = np.diff(pairs.gt_start)
    predictions = np.diff(pairs.tracker_start)

    def per_frame(entries: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
        k = np.searchsorted(pairs.entry_start, entries, side="right") - 1  # entry -> frame
        return np.bincount(k, weights=weights, minlength=n_f)[:n_f].astype(np.int64)

    m = clear_matches(pairs, iou_threshold)
    matched = per_frame(m.matched)
    switches = per_frame(m.matched[m.order], m.switch.astype(float))
    g_ids, t_ids, _ = identity_pairs(pairs, iou_threshold)
    ok = np.flatnonzero(pairs.iou >= iou_threshold)
    chosen = set(zip(g_ids.tolist(), t_ids.tolist()))
    kept = np.array([(g, t) in chosen for g, t in zip(pairs.gt_ids[pairs.row[ok]].tolist(),
                                                     pairs.tracker_ids[pairs.col[ok]].tolist())],
                    dtype=bool)
    idtp = per_frame(ok[kept]) if len(ok) else np.zeros(n_f, np.int64)
    tp, fn, fp, ass = hota_frames(pairs, objects, predictions)
    return FrameCounts(pairs.frames.astype(np.int64), objects, predictions, objects - matched,
                       predictions - matched, switches, idtp, tp, fn, fp, ass)


def hota_frames(pairs: FramePairs, objects: np.ndarray, predictions: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(F, 19) HOTA TP, FN, FP and association sums per frame (module docstring)."""
    n_f = len(pairs)
    tp, ass = np.zeros((n_f, NA)), np.zeros((n_f, NA))
    if len(pairs.gt_ids) and len(pairs.tracker_ids):
        m = hota_matches(pairs, HotaCounts())
        if len(m.pair):
            used, inv, counts = pair_match_counts(m.pair, m.sim)  # (19, P) |TPA| per pair
            score = counts / np.maximum(1.0, m.g_count[used] + m.t_count[used] - counts)
            ok = m.sim[None, :] >= ALPHAS[:, None] - np.finfo(float).eps  # (19, K)
            for a in range(NA):
                tp[:, a] = np.bincount(m.frame, weights=ok[a], minlength=n_f)
                ass[:, a] = np.bincount(m.frame, weights=ok[a] * score[a, inv], minlength=n_f)
    fn = objects[:, None] - tp
    fp = predictions[:, None] - tp
    return tp, fn, fp, ass


def sequence_totals(counts: Mapping[str, FrameCounts]) -> np.ndarray:
    """(D,) the counts of several sequences summed: their COMBINED row's ingredients."""
    return np.sum([c.total() for c in counts.values()], axis=0)
