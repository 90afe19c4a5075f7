"""CLEAR MOT (Bernardin and Stiefelhagen 2008) and identity (Ristani et al. 2016) metrics.

CLEAR counts (matches, FP, FN, ID switches, Frag, MT/PT/ML, MOTP) follow the MOTChallenge
devkit as TrackEval implements it (``trackeval.metrics.CLEAR.eval_sequence``), so that
TrackEval re-scores a run folder to the same figures (``clear_counts``):

* a gt person matched to a tracker id in the previous scored frame keeps it while their
  IoU is at least the threshold (the pair gets a bonus of 1000 in the Hungarian step);
  the rest is matched by maximum IoU. A person missed in the previous frame has no such
  claim (py-motmetrics keeps the last match over any gap, and counts fewer switches);
* an ID switch is a matched person whose tracker id differs from their last matched one
  (any number of frames before);
* Frag: per gt person, the number of times they are matched again after a scored frame in
  which they were not matched (missed, or not annotated at all), i.e. tracked stretches
  minus one; a frame without any tracker box does not end a stretch (motmetrics'
  ``num_fragmentations`` counts the misses between the first and last match instead);
* MT / ML: matched in more than 80 % / fewer than 20 % of their annotated frames.

Identity metrics (IDF1, IDP, IDR: a global one-to-one assignment of ids) come from
py-motmetrics' ``MOTAccumulator``, fed with our own distances: per frame ``1 - IoU`` from
``trackers.geometry.iou_matrix``, with pairs below the IoU threshold set to NaN (not
pairable); they equal TrackEval's ``Identity``. motmetrics' own ``iou_matrix`` and
``compare_to_groundtruth`` call ``np.asfarray`` and fail on numpy 2; note also that its
``max_iou`` / ``distth`` arguments are *distance* thresholds (1 - IoU), not IoU.

What is kept per sequence are counts (``ClearCounts``), so sequences combine by summing and
recomputing ratios; MOTP is reported as the mean IoU of the matched pairs.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import motmetrics as mm
import numpy as np
from scipy.optimize import linear_sum_assignment

from harness.metrics.frames import FramePairs

# motmetrics metric name -> ClearCounts field (identity metrics only)
_MM_COUNTS = {
    "num_frames": "frames",
    "idtp": "idtp",
    "idfp": "idfp",
    "idfn": "idfn",
}
MT_ABOVE = 0.8  # mostly tracked: matched in more than 80 % of the annotated frames
ML_BELOW = 0.2  # mostly lost: matched in fewer than 20 %


def _ratio(num: float, den: float) -> float:
    """num / den, NaN when den is 0 (an undefined ratio, never an error)."""
    return float(num) / float(den) if den else float("nan")


@dataclass
class ClearCounts:
    """Additive CLEAR/ID counts of one sequence, or of several summed.

    ``matches`` counts matched pairs that are not ID switches; a switch is also a matched
    pair, so matched pairs (TrackEval's CLR_TP) are ``matches + switches``.
    ``iou_sum`` is the sum of IoU over all matched pairs.
    """

    frames: int = 0
    objects: int = 0
    predictions: int = 0
    matches: int = 0
    switches: int = 0
    false_positives: int = 0
    misses: int = 0
    fragmentations: int = 0
    mostly_tracked: int = 0
    partially_tracked: int = 0
    mostly_lost: int = 0
    unique_objects: int = 0
    idtp: int = 0
    idfp: int = 0
    idfn: int = 0
    iou_sum: float = 0.0

    def __add__(self, other: ClearCounts) -> ClearCounts:
        return ClearCounts(
            **{f.name: getattr(self, f.name) + getattr(other, f.name) for f in fields(self)}
        )

    @property
    def detections(self) -> int:
        """Matched gt/tracker pairs (MATCH + SWITCH events)."""
        return self.matches + self.switches

    def ratios(self) -> dict[str, float]:
        """MOTA, MOTP (mean IoU), IDF1, IDP, IDR, Recall, Precision as fractions."""
        return {
            "MOTA": 1.0 - _ratio(self.misses + self.switches + self.false_positives, self.objects),
            "MOTP": _ratio(self.iou_sum, self.detections),
            "IDF1": _ratio(2 * self.idtp, 2 * self.idtp + self.idfp + self.idfn),
            "IDP": _ratio(self.idtp, self.idtp + self.idfp),
            "IDR": _ratio(self.idtp, self.idtp + self.idfn),
            "Recall": _ratio(self.detections, self.objects),
            "Precision": _ratio(self.detections, self.detections + self.false_positives),
        }


def accumulate(pairs: FramePairs, iou_threshold: float = 0.5) -> mm.MOTAccumulator:
    """A motmetrics accumulator fed with ``1 - IoU`` distances (NaN below the threshold)."""
    if not 0.0 < iou_threshold <= 1.0:
        raise ValueError(f"iou_threshold must be in (0, 1], got {iou_threshold!r}")
    acc = mm.MOTAccumulator(auto_id=False)
    for f, g, t, iou in zip(pairs.frames.tolist(), pairs.gt_ids, pairs.tracker_ids, pairs.iou):
        dist = 1.0 - iou
        dist[iou < iou_threshold] = np.nan
        acc.update(g, t, dist, frameid=f)
    return acc


def clear_counts(acc: mm.MOTAccumulator, pairs: FramePairs,
                 iou_threshold: float = 0.5) -> ClearCounts:
    """CLEAR counts of one sequence (``clear_matching``) with the identity counts of ``acc``
    (the motmetrics accumulator of the same ``pairs``)."""
    counts = clear_matching(pairs, iou_threshold)
    if len(acc.mot_events) == 0:
        counts.frames = len(acc.events.index.unique(level="FrameId"))
        return counts
    mh = mm.metrics.create()
    values = mh.compute(acc, metrics=list(_MM_COUNTS), return_dataframe=False)
    for key, name in _MM_COUNTS.items():
        setattr(counts, name, int(values[key]))
    return counts


def clear_matching(pairs: FramePairs, iou_threshold: float = 0.5) -> ClearCounts:
    """CLEAR MOT counts of one sequence, as the MOTChallenge devkit / TrackEval's CLEAR.

    Args:
        pairs: the scored gt and tracker boxes per frame (``harness.metrics.frames``).
        iou_threshold: smallest IoU of a match.
    Returns:
        ClearCounts with objects, predictions, matches, switches, false_positives, misses,
        fragmentations, mostly_tracked / partially_tracked / mostly_lost, unique_objects and
        iou_sum filled (identity counts and frames left 0).
    """
    eps = np.finfo(float).eps
    c = ClearCounts()
    gt_all = np.concatenate([np.zeros(0, np.int64), *pairs.gt_ids])
    ids = np.unique(gt_all)  # gt person -> index
    n = len(ids)
    annotated = np.zeros(n)  # frames each gt person is scored in
    matched = np.zeros(n)  # ... and matched in
    stretches = np.zeros(n)  # tracked stretches (Frag = stretches - 1)
    last_id = np.full(n, np.nan)  # last matched tracker id, any frame before (switches)
    prev_id = np.full(n, np.nan)  # tracker id matched in the previous scored frame
    for g_ids, t_ids, iou in zip(pairs.gt_ids, pairs.tracker_ids, pairs.iou):
        c.objects += len(g_ids)
        c.predictions += len(t_ids)
        if len(g_ids) == 0:
            c.false_positives += len(t_ids)
            continue
        g = np.searchsorted(ids, g_ids)
        annotated[g] += 1
        if len(t_ids) == 0:
            c.misses += len(g_ids)
            continue
        # continuing the previous frame's pairs first (+1000), then the largest IoU
        score = 1000.0 * (t_ids[None, :] == prev_id[g][:, None]) + iou
        score[iou < iou_threshold - eps] = 0.0
        rows, cols = linear_sum_assignment(-score)
        keep = score[rows, cols] > eps
        rows, cols = rows[keep], cols[keep]
        gm, tm = g[rows], t_ids[cols].astype(float)
        switch = ~np.isnan(last_id[gm]) & (tm != last_id[gm])
        was_tracked = ~np.isnan(prev_id)
        last_id[gm] = tm
        prev_id[:] = np.nan
        prev_id[gm] = tm
        stretches += ~was_tracked & ~np.isnan(prev_id)
        matched[gm] += 1
        c.switches += int(switch.sum())
        c.matches += int(len(rows) - switch.sum())
        c.misses += len(g_ids) - len(rows)
        c.false_positives += len(t_ids) - len(rows)
        c.iou_sum += float(iou[rows, cols].sum())
    ratio = matched / np.maximum(1.0, annotated)
    c.unique_objects = n
    c.mostly_tracked = int(np.sum(ratio > MT_ABOVE))
    c.partially_tracked = int(np.sum(ratio >= ML_BELOW)) - c.mostly_tracked
    c.mostly_lost = n - c.mostly_tracked - c.partially_tracked
    c.fragmentations = int(np.sum(stretches[stretches > 0] - 1))
    return c
