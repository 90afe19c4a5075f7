"""SORT-like reference tracker: constant-velocity Kalman filter plus IoU Hungarian matching.

Bewley et al., "Simple Online and Realtime Tracking", 2016. It keeps no appearance model
and no occlusion reasoning: the reference row every occlusion-aware tracker must beat.
"""

from __future__ import annotations

import math

import numpy as np

from occbench.trackers.common.assignment import assign_in_blocks
from occbench.trackers.common.checks import at_least, unit
from occbench.trackers.common.spatial import DENSE_LIMIT, blocks, meeting_pairs
from occbench.trackers.common.kalman import box_measurement, constant_velocity_box_filter, state_box
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import Detections, Track, TrackState


class _BoxTrack:
    """One SORT track: a Kalman filter and its life-cycle counters."""

    def __init__(self, track_id: int, box: np.ndarray) -> None:
        self.id = track_id
        self.kf = constant_velocity_box_filter(box)
        self.hits = 1
        self.misses = 0

    def predict(self) -> np.ndarray:
        if self.kf.x[2, 0] + self.kf.x[6, 0] <= 1 or self.kf.x[3, 0] + self.kf.x[7, 0] <= 1:
            self.kf.x[6:, 0] = 0.0  # never let a size shrink through zero
        self.kf.predict()
        return state_box(self.kf)

    def correct(self, box: np.ndarray) -> None:
        self.kf.update(box_measurement(box))
        self.hits += 1
        self.misses = 0


class BaselineTracker:
    """SORT: predict, match by IoU with the Hungarian method, confirm after ``min_hits``.

    Args:
        iou_threshold: smallest IoU accepted for a prediction/detection pair.
        min_hits: matched frames before a track is reported.
        max_age: frames a track survives without a match (coasting, reported as OCCLUDED
            when ``report_coasting``).
        min_score: detections below this score are ignored.
        report_coasting: write coasting tracks' predicted boxes to the output.
    """

    needs_frames = False  # boxes only

    def __init__(
        self,
        iou_threshold: float = 0.3,
        min_hits: int = 3,
        max_age: int = 3,
        min_score: float = 0.0,
        report_coasting: bool = False,
    ) -> None:
        unit("", iou_threshold=iou_threshold)
        at_least("", 1, min_hits=min_hits)
        at_least("", 0, max_age=max_age)
        self.iou_threshold = iou_threshold
        self.min_hits = min_hits
        self.max_age = max_age
        self.min_score = min_score
        self.report_coasting = report_coasting
        self.reset()

    def reset(self) -> None:
        """Forget every track and restart ids at 1."""
        self._tracks: list[_BoxTrack] = []
        self._next_id = 1
        self._frame = 0

    def _match(self, predicted: np.ndarray, dets: np.ndarray) -> tuple:
        """``assign`` over cost 1 - IoU, block by block over the pairs that meet (with
        ``iou_threshold`` > 0 no other pair is allowed): memory grows with the pairs, not
        predictions x detections; one block, the whole matrix, in ordinary frames."""
        limit = DENSE_LIMIT if self.iou_threshold > 0 else math.inf
        parts = blocks(len(predicted), len(dets), lambda: meeting_pairs(predicted, dets),
                       limit=limit)
        return assign_in_blocks(parts, lambda r, c: 1.0 - iou_matrix(predicted[r], dets[c]),
                                1.0 - self.iou_threshold)

    def update(
        self, frame: np.ndarray | None, detections: Detections, foreground: np.ndarray | None = None
    ) -> list[Track]:
        """Advance one frame; ``frame`` and ``foreground`` are unused (no appearance)."""
        self._frame += 1
        dets = detections.boxes[detections.scores >= self.min_score]
        predicted = np.array([t.predict() for t in self._tracks]).reshape(-1, 4)
        matches, lost, new = self._match(predicted, dets)
        for i, j in matches:
            self._tracks[i].correct(dets[j])
        for i in lost:
            self._tracks[i].misses += 1
        for j in new:
            self._tracks.append(_BoxTrack(self._next_id, dets[j]))
            self._next_id += 1
        self._tracks = [t for t in self._tracks if t.misses <= self.max_age]
        out = []
        for t in self._tracks:
            if t.hits >= self.min_hits or (self._frame <= self.min_hits and t.misses == 0):
                if t.misses == 0:
                    out.append(Track(t.id, state_box(t.kf), TrackState.CONFIRMED))
                elif self.report_coasting:
                    out.append(Track(t.id, state_box(t.kf), TrackState.OCCLUDED))
            elif t.misses == 0:
                out.append(Track(t.id, state_box(t.kf), TrackState.TENTATIVE))
        return out
