"""ByteTrack's BYTE association: OUR re-implementation (not the authors' code).

Zhang, Sun, Jiang, Yu, Weng, Yuan, Luo, Liu, Wang, "ByteTrack: Multi-Object Tracking by
Associating Every Detection Box", ECCV 2022 (Algorithm 1), following the control flow of
the authors' ``yolox/tracker/byte_tracker.py``. No installable package implements it
without torch (``bytetracker``, ``boxmot``) or a second OpenCV (``supervision<0.27``), so it
is written here on the project's Kalman set-up (``occbench.trackers.common.kalman``: constant
velocity on centre and size, noise scaled by the box height, instead of the authors' xyah
filter) and gated Hungarian assignment (``occbench.trackers.common.assignment``, in place of
``lap.lapjv`` with ``cost_limit``).

Per frame t (Algorithm 1):
  1. split detections: D_high (score > track_thresh), D_low (low_thresh < score <= track_thresh);
  2. predict every tracked and lost track (lost tracks with their size rate zeroed);
  3. first association: tracked + lost tracks vs D_high, cost 1 - IoU (times the detection
     score when ``fuse_score``), gate ``match_thresh``; a matched lost track is re-found;
  4. second association: the still unmatched *tracked* tracks vs D_low, cost 1 - IoU, gate
     ``second_match_thresh``; tracked tracks left unmatched become lost;
  5. unconfirmed (one-frame) tracks vs the D_high left, gate ``unconfirmed_match_thresh``;
     matched ones are confirmed, unmatched ones removed;
  6. every D_high left scoring above ``new_track_thresh`` starts an unconfirmed track
     (confirmed at once in the first frame);
  7. lost tracks unmatched for more than ``track_buffer`` frames are removed; tracked and
     lost tracks overlapping with 1 - IoU < 0.15 keep only the longer-lived one.
Reported: confirmed tracks matched this frame (CONFIRMED), and, when ``report_lost``, lost
tracks' predictions for ``report_lost`` frames (OCCLUDED).
"""

from __future__ import annotations

from enum import Enum

import numpy as np

from occbench.trackers.common.assignment import assign
from occbench.trackers.common.checks import at_least, require, unit
from occbench.trackers.common.kalman import box_measurement, constant_velocity_box_filter, state_box
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import Detections, Track, TrackState

DUPLICATE_IOU_DISTANCE = 0.15  # remove_duplicate_stracks in the authors' code


class _State(Enum):
    TRACKED = 1
    LOST = 2
    REMOVED = 3


class _STrack:
    """One BYTE track: Kalman filter, state, activation flag, first and last frames."""

    def __init__(self, key: int, box: np.ndarray, score: float, frame: int, noise: dict) -> None:
        self.key = key
        self.kf = constant_velocity_box_filter(box, **noise)
        self.score = score
        self.state = _State.TRACKED
        self.activated = frame == 1
        self.start_frame = frame
        self.end_frame = frame

    def predict(self) -> None:
        if self.state != _State.TRACKED:
            self.kf.x[6:, 0] = 0.0  # the authors zero the height rate of lost tracks
        if self.kf.x[2, 0] + self.kf.x[6, 0] <= 1 or self.kf.x[3, 0] + self.kf.x[7, 0] <= 1:
            self.kf.x[6:, 0] = 0.0  # never let a size shrink through zero
        self.kf.predict()  # x = F x, P = F P F' + Q

    def correct(self, box: np.ndarray, score: float, frame: int) -> None:
        self.kf.update(box_measurement(box))  # K = P H' (H P H' + R)^-1, x = x + K (z - H x)
        self.score = score
        self.state = _State.TRACKED
        self.activated = True
        self.end_frame = frame

    @property
    def box(self) -> np.ndarray:
        return state_box(self.kf)


def _boxes(tracks: list[_STrack]) -> np.ndarray:
    return np.array([t.box for t in tracks]).reshape(-1, 4)


class ByteTrackTracker:
    """BYTE (ByteTrack's association) on the project's Kalman filter.

    Args:
        track_thresh: tau of Algorithm 1: detections above it are "high" (first
            association), the rest above ``low_thresh`` are "low" (second association).
        low_thresh: detections at or below it are dropped (0.1 in the authors' code).
        new_track_thresh: a high detection left over starts a track only above this
            (track_thresh + 0.1 in the authors' code).
        match_thresh: largest cost (1 - IoU, score-fused) of a first-round match.
        second_match_thresh: largest cost (1 - IoU) of a second-round (low-score) match.
        unconfirmed_match_thresh: largest cost of a match of a one-frame track.
        track_buffer: frames a lost track is kept for re-finding (30 at 30 fps).
        fuse_score: multiply the IoU by the detection score in the first round and for
            unconfirmed tracks (the authors do so except on MOT20).
        report_lost: frames a lost track's prediction is reported as OCCLUDED (0 = never,
            as in the authors' output).
        position_noise, velocity_noise, measurement_noise, initial_velocity_variance:
            Kalman noise std per 10 px of box height (``constant_velocity_box_filter``).
    """

    needs_frames = False  # boxes only

    def __init__(
        self,
        track_thresh: float = 0.5,
        low_thresh: float = 0.1,
        new_track_thresh: float = 0.6,
        match_thresh: float = 0.8,
        second_match_thresh: float = 0.5,
        unconfirmed_match_thresh: float = 0.7,
        track_buffer: int = 30,
        fuse_score: bool = True,
        report_lost: int = 0,
        position_noise: float = 1.0,
        velocity_noise: float = 0.1,
        measurement_noise: float = 1.0,
        initial_velocity_variance: float = 100.0,
    ) -> None:
        unit("", track_thresh=track_thresh, low_thresh=low_thresh,
             new_track_thresh=new_track_thresh, match_thresh=match_thresh,
             second_match_thresh=second_match_thresh,
             unconfirmed_match_thresh=unconfirmed_match_thresh)
        require("low_thresh", low_thresh <= track_thresh,
                f"must not exceed track_thresh {track_thresh}", low_thresh)
        at_least("", 0, track_buffer=track_buffer, report_lost=report_lost)
        self.track_thresh = float(track_thresh)
        self.low_thresh = float(low_thresh)
        self.new_track_thresh = float(new_track_thresh)
        self.match_thresh = float(match_thresh)
        self.second_match_thresh = float(second_match_thresh)
        self.unconfirmed_match_thresh = float(unconfirmed_match_thresh)
        self.track_buffer = int(track_buffer)
        self.fuse_score = bool(fuse_score)
        self.report_lost = int(report_lost)
        self.noise = {
            "position_noise": float(position_noise),
            "velocity_noise": float(velocity_noise),
            "measurement_noise": float(measurement_noise),
            "initial_velocity_variance": float(initial_velocity_variance),
        }
        self.reset()

    def reset(self) -> None:
        """Forget every track; ids restart at 1."""
        self._tracked: list[_STrack] = []
        self._lost: list[_STrack] = []
        self._frame = 0
        self._next_key = 1
        self._ids: dict[int, int] = {}

    def _cost(self, tracks: list[_STrack], boxes: np.ndarray, scores: np.ndarray, fuse: bool):
        cost = 1.0 - iou_matrix(_boxes(tracks), boxes)  # iou_distance
        if fuse and self.fuse_score:
            cost = 1.0 - (1.0 - cost) * scores[None, :]  # fuse_score
        return cost

    def update(
        self, frame: np.ndarray | None, detections: Detections, foreground: np.ndarray | None = None
    ) -> list[Track]:
        """Advance one frame (Algorithm 1); ``frame`` and ``foreground`` are unused."""
        self._frame += 1
        t = self._frame
        s = detections.scores
        high = s > self.track_thresh
        low = (s > self.low_thresh) & ~high
        hb, hs = detections.boxes[high], s[high]
        lb, ls = detections.boxes[low], s[low]

        unconfirmed = [k for k in self._tracked if not k.activated]
        tracked = [k for k in self._tracked if k.activated]
        pool = tracked + self._lost
        for k in pool:
            k.predict()

        # first association: all tracks vs high-score detections
        matches, u_track, u_det = assign(self._cost(pool, hb, hs, True), self.match_thresh)
        for i, j in matches:
            pool[i].correct(hb[j], hs[j], t)
        # second association: remaining tracked tracks vs low-score detections
        rest = [pool[i] for i in u_track if pool[i].state == _State.TRACKED]
        matches2, u_rest, _ = assign(self._cost(rest, lb, ls, False), self.second_match_thresh)
        for i, j in matches2:
            rest[i].correct(lb[j], ls[j], t)
        for i in u_rest:
            rest[i].state = _State.LOST
        # unconfirmed tracks vs remaining high-score detections
        hb, hs = hb[u_det], hs[u_det]
        matches3, u_unconf, u_det = assign(
            self._cost(unconfirmed, hb, hs, True), self.unconfirmed_match_thresh
        )
        for i, j in matches3:
            unconfirmed[i].correct(hb[j], hs[j], t)
        for i in u_unconf:
            unconfirmed[i].state = _State.REMOVED
        # new tracks
        born = []
        for j in u_det:
            if hs[j] >= self.new_track_thresh:
                born.append(_STrack(self._next_key, hb[j], float(hs[j]), t, self.noise))
                self._next_key += 1
        # lost tracks too old are removed
        everyone = tracked + self._lost + unconfirmed + born
        for k in everyone:
            if k.state == _State.LOST and t - k.end_frame > self.track_buffer:
                k.state = _State.REMOVED
        self._tracked = [k for k in everyone if k.state == _State.TRACKED]
        self._lost = [k for k in everyone if k.state == _State.LOST]
        self._remove_duplicates()
        self._tracked.sort(key=lambda k: k.key)
        self._lost.sort(key=lambda k: k.key)

        out = []
        for k in self._tracked:
            if k.activated:
                out.append(Track(self._id(k.key), k.box, TrackState.CONFIRMED, float(k.score)))
        if self.report_lost:
            for k in self._lost:
                if t - k.end_frame <= self.report_lost:
                    out.append(Track(self._id(k.key), k.box, TrackState.OCCLUDED, float(k.score)))
        return out

    def _id(self, key: int) -> int:
        if key not in self._ids:
            self._ids[key] = len(self._ids) + 1
        return self._ids[key]

    def _remove_duplicates(self) -> None:
        """remove_duplicate_stracks: a tracked/lost pair closer than 0.15 in IoU distance
        keeps only the track followed for longer."""
        if not self._tracked or not self._lost:
            return
        dist = 1.0 - iou_matrix(_boxes(self._tracked), _boxes(self._lost))
        drop_a, drop_b = set(), set()
        for p, q in zip(*np.nonzero(dist < DUPLICATE_IOU_DISTANCE)):
            a, b = self._tracked[p], self._lost[q]
            if _t_len(a) > _t_len(b):
                drop_b.add(q)
            else:
                drop_a.add(p)
        self._tracked = [k for i, k in enumerate(self._tracked) if i not in drop_a]
        self._lost = [k for i, k in enumerate(self._lost) if i not in drop_b]


def _t_len(track: _STrack) -> int:
    """Frames a track has been followed (end_frame - start_frame, as the authors compute)."""
    return track.end_frame - track.start_frame
