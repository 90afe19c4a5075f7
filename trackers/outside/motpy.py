"""Adapter for motpy (https://github.com/wmuron/motpy), PyPI ``motpy``.

motpy's ``MultiObjectTracker`` keeps one Kalman filter per object (position of order
``order_pos``, size of order ``order_size``), matches by IoU with the Hungarian method and
returns the "active" tracks: alive at least ``min_steps_alive`` steps and not staler than
``active_max_staleness``. Its track ids are ``uuid4`` strings; they are renumbered here.
Active tracks are reported as CONFIRMED (motpy does not say which were matched this frame).
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.common import checks
from occbench.trackers.outside._common import IdMap, check_min_score, require, xywh_to_xyxy, xyxy_to_xywh
from occbench.trackers.records import Detections, Track, TrackState


class MotpyTracker:
    """motpy ``MultiObjectTracker`` on xyxy boxes.

    Args:
        dt: time step of the motion model, frames.
        order_pos: 1 = constant-velocity position, 2 = constant acceleration, 0 = static.
        order_size: 0 = static box size, 1 = constant size rate.
        q_var_pos, q_var_size: process noise variances of position / size.
        r_var_pos, r_var_size: measurement noise variances of position / size.
        p_cov_p0: initial state covariance.
        min_iou: smallest IoU of a match.
        multi_match_min_iou: IoU above which one detection may update several tracks
            (> 1 disables it).
        max_staleness: staleness at which a track is deleted (stale() adds 1 per miss,
            a match subtracts 2).
        smooth_score_gamma: score exponential smoothing factor.
        min_steps_alive: steps before a track is reported.
        active_max_staleness: a track staler than this is not reported.
        min_score: detections below this score are not given to motpy.
    """

    needs_frames = False  # boxes only (motion-only trackers)

    def __init__(
        self,
        dt: float = 1.0,
        order_pos: int = 1,
        order_size: int = 0,
        q_var_pos: float = 70.0,
        q_var_size: float = 10.0,
        r_var_pos: float = 1.0,
        r_var_size: float = 1.0,
        p_cov_p0: float = 1000.0,
        min_iou: float = 0.25,
        multi_match_min_iou: float = 0.93,
        max_staleness: float = 12.0,
        smooth_score_gamma: float = 0.8,
        min_steps_alive: int = 3,
        active_max_staleness: float = 3.0,
        min_score: float = 0.0,
    ) -> None:
        self._mp = require("motpy", "motpy==0.0.10", type(self).__name__)
        checks.require("dt", dt > 0, "must be > 0", dt)
        checks.unit("", min_iou=min_iou)
        for key, order in (("order_pos", order_pos), ("order_size", order_size)):
            checks.require(key, order in (0, 1, 2), "must be 0, 1 or 2", order)
        self.dt = float(dt)
        self.model_spec = {
            "order_pos": int(order_pos),
            "dim_pos": 2,
            "order_size": int(order_size),
            "dim_size": 2,
            "q_var_pos": float(q_var_pos),
            "q_var_size": float(q_var_size),
            "r_var_pos": float(r_var_pos),
            "r_var_size": float(r_var_size),
            "p_cov_p0": float(p_cov_p0),
        }
        self.matching = {
            "min_iou": float(min_iou),
            "multi_match_min_iou": float(multi_match_min_iou),
        }
        self.track_kwargs = {
            "max_staleness": float(max_staleness),
            "smooth_score_gamma": float(smooth_score_gamma),
        }
        self.active = {
            "min_steps_alive": int(min_steps_alive),
            "max_staleness": float(active_max_staleness),
        }
        self.min_score = check_min_score(min_score)
        self.reset()

    def reset(self) -> None:
        """A fresh MultiObjectTracker; ids restart at 1."""
        self._tracker = self._mp.MultiObjectTracker(
            dt=self.dt,
            model_spec=dict(self.model_spec),
            tracker_kwargs=dict(self.track_kwargs),
            matching_fn_kwargs=dict(self.matching),
            active_tracks_kwargs=dict(self.active),
        )
        self._ids = IdMap()

    def update(
        self, frame: np.ndarray | None, detections: Detections, foreground: np.ndarray | None = None
    ) -> list[Track]:
        """Advance one frame; ``frame`` and ``foreground`` are unused."""
        keep = detections.scores >= self.min_score
        corners = xywh_to_xyxy(detections.boxes[keep])
        mp_dets = [
            self._mp.Detection(box=c, score=float(s))
            for c, s in zip(corners, detections.scores[keep])
        ]
        out = []
        for t in self._tracker.step(detections=mp_dets):
            box = xyxy_to_xywh(t.box)
            box[2:] = np.maximum(box[2:], 1.0)
            score = float(np.clip(t.score, 0.0, 1.0)) if t.score is not None else 1.0
            out.append(Track(self._ids(t.id), box, TrackState.CONFIRMED, score=score))
        return out
