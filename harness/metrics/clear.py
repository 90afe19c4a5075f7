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
``occbench.metrics.identity`` (sparse over the id pairs that overlap; equal to TrackEval's
``Identity``). Both read the IoU matrices of ``occbench.metrics.frames``, computed once.

What is kept per sequence are counts (``ClearCounts``), so sequences combine by summing and
recomputing ratios; MOTP is reported as the mean IoU of the matched pairs.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from scipy.optimize import linear_sum_assignment

from occbench.metrics.arrays import distinct
from occbench.metrics.frames import FramePairs
from occbench.metrics.identity import identity_counts

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


def clear_counts(pairs: FramePairs, iou_threshold: float = 0.5) -> ClearCounts:
    """CLEAR counts of one sequence (``clear_matching``) with its identity counts."""
    if not 0.0 < iou_threshold <= 1.0:
        raise ValueError(f"iou_threshold must be in (0, 1], got {iou_threshold!r}")
    counts = clear_matching(pairs, iou_threshold)
    counts.frames = len(pairs)
    counts.idtp, counts.idfp, counts.idfn = identity_counts(pairs, iou_threshold)
    return counts


def clear_matching(pairs: FramePairs, iou_threshold: float = 0.5) -> ClearCounts:
    """CLEAR MOT counts of one sequence, as the MOTChallenge devkit / TrackEval's CLEAR.

    Args:
        pairs: the scored gt and tracker boxes per frame (``occbench.metrics.frames``).
        iou_threshold: smallest IoU of a match.
    Returns:
        ClearCounts with objects, predictions, matches, switches, false_positives, misses,
        fragmentations, mostly_tracked / partially_tracked / mostly_lost, unique_objects and
        iou_sum filled (identity counts and frames left 0).
    """
    m = clear_matches(pairs, iou_threshold)
    matched, g, switch, next_frame = m.matched, m.person, m.switch, m.next_frame
    c = ClearCounts(objects=len(pairs.gt_ids), predictions=len(pairs.tracker_ids))
    ids, g_all = np.unique(pairs.gt_ids, return_inverse=True)  # gt person -> index
    n = len(ids)
    c.switches = int(switch.sum())
    c.matches = len(matched) - c.switches
    c.misses = c.objects - len(matched)
    c.false_positives = c.predictions - len(matched)
    # MOTP's sum frame by frame, as TrackEval adds it
    bounds = np.searchsorted(matched, pairs.entry_start[1:-1])
    c.iou_sum = sum(float(x.sum()) for x in np.split(pairs.iou[matched], bounds))
    # a tracked stretch starts at a match whose person was not matched the frame before
    c.fragmentations = int((~next_frame).sum()) - len(distinct(g))
    ratio = np.bincount(g, minlength=n) / np.maximum(1.0, np.bincount(g_all, minlength=n))
    c.unique_objects = n
    c.mostly_tracked = int(np.sum(ratio > MT_ABOVE))
    c.partially_tracked = int(np.sum(ratio >= ML_BELOW)) - c.mostly_tracked
    c.mostly_lost = n - c.mostly_tracked - c.partially_tracked
    return c


@dataclass
class ClearMatches:
    """The matches of one sequence (``clear_matches``), each person's in time order.

    Attributes:
        matched: (E,) int64 indices into ``pairs.iou`` of the matched entries, ascending.
        person: (E,) int64 gt person index (into the sorted unique gt ids) of each match,
            the matches ordered by person, then time (``order`` maps back).
        order: (E,) int64 ``matched[order]`` is the match at each position of ``person``.
        switch: (E,) bool: the match is an identity switch (its tracker id differs from the
            person's previous match's).
        next_frame: (E,) bool: the person was matched in the previous scored frame too.
    """

    matched: np.ndarray
    person: np.ndarray
    order: np.ndarray
    switch: np.ndarray
    next_frame: np.ndarray


def clear_matches(pairs: FramePairs, iou_threshold: float = 0.5) -> ClearMatches:
    """CLEAR's matching of one sequence (``matched_entries``) and its switches: the one
    place both the counts (``clear_matching``) and the per-frame timeline
    (``occbench.metrics.timeline``) read."""
    eps = np.finfo(float).eps
    pairable = np.flatnonzero(pairs.iou >= iou_threshold - eps)  # entries a match may take
    matched = pairable[matched_entries(pairs, pairable)]
    _, g_all = np.unique(pairs.gt_ids, return_inverse=True)  # gt person -> index
    g, t = g_all[pairs.row[matched]], pairs.tracker_ids[pairs.col[matched]]
    active = np.cumsum((np.diff(pairs.gt_start) > 0) & (np.diff(pairs.tracker_start) > 0))
    when = active[np.searchsorted(pairs.entry_start, matched, side="right") - 1]
    order = np.argsort(g, kind="stable")  # each person's matches in time order
    g, t, when = g[order], t[order], when[order]
    same, switch, next_frame = (np.zeros(len(g), dtype=bool) for _ in range(3))
    same[1:] = g[1:] == g[:-1]  # the person's previous match is the one before
    switch[1:] = same[1:] & (t[1:] != t[:-1])
    next_frame[1:] = same[1:] & (when[1:] - when[:-1] == 1)
    return ClearMatches(matched, g, order, switch, next_frame)


def matched_entries(pairs: FramePairs, pairable: np.ndarray) -> np.ndarray:
    """(E,) bool: which of the ``pairable`` entries (indices into ``pairs.iou``, IoU at least
    the threshold) CLEAR matches.

    Frame by frame, a gt person matched to a tracker id in the previous frame with both gt
    and tracker boxes keeps it (the pair scores 1000 + IoU), the rest goes by the largest
    IoU: one Hungarian assignment per frame. Where no gt box and no tracker box of a frame
    has two pairable entries, every optimal assignment takes them all, whatever the frame
    before: only the other frames are solved, in order.
    """
    take = np.ones(len(pairable), dtype=bool)
    if len(pairable) == 0:
        return take
    frame = np.searchsorted(pairs.entry_start, pairable, side="right") - 1
    row, col = pairs.row[pairable], pairs.col[pairable]
    shared = (np.bincount(row)[row] > 1) | (np.bincount(col)[col] > 1)
    both = np.flatnonzero((np.diff(pairs.gt_start) > 0) & (np.diff(pairs.tracker_start) > 0))
    starts = np.searchsorted(frame, np.arange(len(pairs) + 1))
    _, person = np.unique(pairs.gt_ids, return_inverse=True)
    person, tracker = person[row], pairs.tracker_ids[col]  # of each pairable entry
    none = np.iinfo(np.int64).min  # no tracker id
    last = np.full(int(person.max()) + 1, none)  # person -> tracker id matched the frame before
    for k in distinct(frame[shared]).tolist():
        before = both[np.searchsorted(both, k) - 1] if k > both[0] else -1
        e = np.arange(starts[before], starts[before + 1]) if before >= 0 else np.zeros(0, int)
        e = e[take[e]]
        last[person[e]] = tracker[e]
        here = slice(starts[k], starts[k + 1])
        kept = last[person[here]] == tracker[here]
        last[person[e]] = none
        r, cc = row[here] - pairs.gt_start[k], col[here] - pairs.tracker_start[k]
        score = np.zeros((int(pairs.gt_start[k + 1] - pairs.gt_start[k]),
                          int(pairs.tracker_start[k + 1] - pairs.tracker_start[k])))
        score[r, cc] = 1000.0 * kept + pairs.iou[pairable[here]]
        index = np.full(score.shape, -1)
        index[r, cc] = np.arange(here.start, here.stop)
        rows, cols = linear_sum_assignment(-score)
        take[here] = False
        take[index[rows, cols][index[rows, cols] >= 0]] = True
    return take
