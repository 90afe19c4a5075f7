"""Adapter for norfair (tryolabs, https://github.com/tryolabs/norfair), PyPI ``norfair``.

Each detection becomes a norfair ``Detection`` of two points, its top-left and bottom-right
corners, matched with norfair's vectorised ``"iou"`` distance (1 - IoU). norfair returns
every initialised object whose hit counter is still positive, including ones not matched
this frame: those are reported as OCCLUDED (their Kalman estimate), matched ones as
CONFIRMED, which is what a norfair user gets from ``Tracker.update``.

norfair 2.3.0 pins numpy<2 and filterpy<2 in its metadata but runs on numpy 2 (tested
here): install it with ``pip install --no-deps norfair==2.3.0`` next to numpy 2.
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.common import checks
from occbench.trackers.outside._common import IdMap, check_min_score, require, xywh_to_xyxy
from occbench.trackers.records import Detections, Track, TrackState


class NorfairTracker:
    """norfair ``Tracker`` on box corners.

    Args:
        distance_function: norfair distance name; ``"iou"`` (1 - IoU of the corner boxes)
            or ``"iou_opt"`` (same thing), or a point distance such as ``"mean_euclidean"``.
        distance_threshold: largest distance of a match (for ``"iou"``: 1 - smallest IoU).
        hit_counter_max: largest hit counter; an object dies when it falls below 0, so
            this is about the frames an object survives unmatched.
        initialization_delay: matches before an object is reported; None = norfair's
            default hit_counter_max // 2.
        pointwise_hit_counter_max: per-corner hit counter cap.
        detection_threshold: corner scores at or below this are ignored by norfair.
        past_detections_length: detections kept per object (for re-id distances).
        min_score: detections below this score are not given to norfair.
    """

    needs_frames = False  # boxes only (motion-only trackers)

    def __init__(
        self,
        distance_function: str = "iou",
        distance_threshold: float = 0.7,
        hit_counter_max: int = 15,
        initialization_delay: int | None = None,
        pointwise_hit_counter_max: int = 4,
        detection_threshold: float = 0.0,
        past_detections_length: int = 4,
        min_score: float = 0.0,
    ) -> None:
        self._nf = require("norfair", "--no-deps norfair==2.3.0", type(self).__name__)
        checks.require("distance_threshold", distance_threshold > 0, "must be > 0",
                       distance_threshold)
        checks.at_least("", 1, hit_counter_max=hit_counter_max)
        checks.require("initialization_delay", initialization_delay is None
                       or 0 <= initialization_delay < hit_counter_max,
                       f"must lie in [0, hit_counter_max {hit_counter_max}) or be None",
                       initialization_delay)
        self.distance_function = distance_function
        self.distance_threshold = float(distance_threshold)
        self.hit_counter_max = int(hit_counter_max)
        self.initialization_delay = initialization_delay
        self.pointwise_hit_counter_max = int(pointwise_hit_counter_max)
        self.detection_threshold = float(detection_threshold)
        self.past_detections_length = int(past_detections_length)
        self.min_score = check_min_score(min_score)
        self.reset()

    def reset(self) -> None:
        """A fresh norfair Tracker; ids restart at 1."""
        self._tracker = self._nf.Tracker(
            distance_function=self.distance_function,
            distance_threshold=self.distance_threshold,
            hit_counter_max=self.hit_counter_max,
            initialization_delay=self.initialization_delay,
            pointwise_hit_counter_max=self.pointwise_hit_counter_max,
            detection_threshold=self.detection_threshold,
            past_detections_length=self.past_detections_length,
        )
        self._ids = IdMap()

    def update(
        self, frame: np.ndarray | None, detections: Detections, foreground: np.ndarray | None = None
    ) -> list[Track]:
        """Advance one frame; ``frame`` and ``foreground`` are unused."""
        keep = detections.scores >= self.min_score
        corners = xywh_to_xyxy(detections.boxes[keep])
        scores = detections.scores[keep]
        nf_dets = [
            self._nf.Detection(points=c.reshape(2, 2), scores=np.array([s, s]))
            for c, s in zip(corners, scores)
        ]
        this_frame = {id(d) for d in nf_dets}
        out = []
        for obj in self._tracker.update(detections=nf_dets, period=1):
            (x1, y1), (x2, y2) = np.asarray(obj.estimate, dtype=np.float64)
            x1, x2 = min(x1, x2), max(x1, x2)
            y1, y2 = min(y1, y2), max(y1, y2)
            box = np.array([x1, y1, max(x2 - x1, 1.0), max(y2 - y1, 1.0)])
            matched = id(obj.last_detection) in this_frame
            state = TrackState.CONFIRMED if matched else TrackState.OCCLUDED
            out.append(Track(self._ids(obj.id), box, state, score=1.0))
        return out
