"""CLEAR MOT (Bernardin and Stiefelhagen 2008) and identity (Ristani et al. 2016) metrics.

Events come from py-motmetrics' ``MOTAccumulator``, fed with our own distances: per frame
``1 - IoU`` from ``trackers.geometry.iou_matrix``, with pairs below the IoU threshold set to
NaN (not pairable). motmetrics' own ``iou_matrix`` and ``compare_to_groundtruth`` call
``np.asfarray`` and fail on numpy 2; note also that its ``max_iou`` / ``distth`` arguments
are *distance* thresholds (1 - IoU), not IoU.

What is kept per sequence are counts (``ClearCounts``), so sequences combine by summing and
recomputing ratios; MOTP is reported as the mean IoU of the matched pairs (1 minus
motmetrics' distance MOTP).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import motmetrics as mm
import numpy as np

from harness.metrics.frames import FramePairs

# motmetrics metric name -> ClearCounts field
_MM_COUNTS = {
    "num_frames": "frames",
    "num_objects": "objects",
    "num_predictions": "predictions",
    "num_matches": "matches",
    "num_switches": "switches",
    "num_false_positives": "false_positives",
    "num_misses": "misses",
    "num_fragmentations": "fragmentations",
    "mostly_tracked": "mostly_tracked",
    "partially_tracked": "partially_tracked",
    "mostly_lost": "mostly_lost",
    "num_unique_objects": "unique_objects",
    "idtp": "idtp",
    "idfp": "idfp",
    "idfn": "idfn",
}


def _ratio(num: float, den: float) -> float:
    """num / den, NaN when den is 0 (an undefined ratio, never an error)."""
    return float(num) / float(den) if den else float("nan")


@dataclass
class ClearCounts:
    """Additive CLEAR/ID counts of one sequence, or of several summed.

    ``matches`` counts motmetrics MATCH events only; a SWITCH event is also a matched pair,
    so matched pairs (motmetrics' ``num_detections``) are ``matches + switches``.
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


def clear_counts(acc: mm.MOTAccumulator) -> ClearCounts:
    """CLEAR/ID counts of one accumulator (one sequence)."""
    events = acc.mot_events
    if len(events) == 0:
        return ClearCounts(frames=len(acc.events.index.unique(level="FrameId")))
    mh = mm.metrics.create()
    values = mh.compute(acc, metrics=list(_MM_COUNTS), return_dataframe=False)
    counts = ClearCounts(**{name: int(values[key]) for key, name in _MM_COUNTS.items()})
    matched = events["Type"].isin(["MATCH", "SWITCH"]).to_numpy()
    dist = events["D"].to_numpy(dtype=np.float64)[matched]
    counts.iou_sum = float(np.sum(1.0 - dist))
    return counts
