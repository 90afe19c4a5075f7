"""Where a hidden person is reported: the filter's prediction, or its last measured box moved
by its measured velocity, whichever has predicted that person's measurements better.

Both paper trackers report a found person at its measured box but a hidden one where their
Kalman filter predicts it. A filter whose noise model is wider than the detector's real noise
lags behind the measurements (its velocity is too small); one whose model fits follows them.
``MeasuredVelocity`` keeps, per track id, two one-step predictors of each new measurement
from the last one: the filter's velocity and the measured velocity (the displacement between
the last two measured boxes per frame), and the summed squared error of each (in box
heights). A hidden person whose measured velocity has the smaller error so far is reported
at its last measured box moved by that velocity times the frames since; otherwise the
tracker's own box stands. No parameter: the person's own track record chooses.
Boxes are (N, 4) float64 xywh, 0-based pixels; velocities (N, 2) pixels per frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def _squared_miss(last: np.ndarray, velocity: np.ndarray, frames: int, centre: np.ndarray,
                  height: float) -> float:
    """Squared distance, in box heights^2, of ``centre`` from ``last`` + frames x velocity."""
    return float(((last + frames * velocity - centre) ** 2).sum()) / max(height, 1.0) ** 2


@dataclass
class _Record:
    frame: int  # frame of the last measured box
    box: np.ndarray  # (4,) last measured box
    filter_velocity: np.ndarray  # (2,) the filter's velocity after that measurement
    measured_velocity: np.ndarray | None = None  # (2,) displacement per frame, last two boxes
    filter_error: float = 0.0  # summed squared error / h^2 of the filter's predictions
    measured_error: float = 0.0  # ... of the measured velocity's predictions


@dataclass
class MeasuredVelocity:
    """``report_velocity: measured`` (both trackers): per-id records of the two predictors."""

    _records: dict[int, _Record] = field(default_factory=dict)

    def reset(self) -> None:
        self._records.clear()

    def found(self, frame: int, ids: list[int], boxes: np.ndarray,
              filter_velocity: np.ndarray) -> None:
        """Record the measured boxes (N, 4) of the found ``ids`` at ``frame`` with their
        filters' velocities (N, 2) after the update; score both predictors of each box."""
        for tid, box, v in zip(ids, np.asarray(boxes, dtype=np.float64),
                               np.asarray(filter_velocity, dtype=np.float64)):
            rec = self._records.get(tid)
            centre = box[:2] + box[2:] / 2
            if rec is None:
                self._records[tid] = _Record(frame, box.copy(), v.copy())
                continue
            n = frame - rec.frame
            last = rec.box[:2] + rec.box[2:] / 2
            if rec.measured_velocity is not None:
                h = rec.box[3]
                rec.filter_error += _squared_miss(last, rec.filter_velocity, n, centre, h)
                rec.measured_error += _squared_miss(last, rec.measured_velocity, n, centre, h)
            rec.measured_velocity = (centre - last) / max(n, 1)
            rec.frame, rec.box, rec.filter_velocity = frame, box.copy(), v.copy()

    def place(self, frame: int, ids: list[int], boxes: np.ndarray) -> None:
        """Move, in place, the boxes (N, 4) of hidden ``ids`` whose measured velocity has
        predicted better: their last measured box moved by it times the frames since."""
        for r, tid in enumerate(ids):
            rec = self._records.get(tid)
            if rec is None or rec.measured_velocity is None:
                continue
            if rec.measured_error < rec.filter_error:
                boxes[r] = rec.box
                boxes[r, :2] += (frame - rec.frame) * rec.measured_velocity

    def forget(self, alive: set[int]) -> None:
        """Drop the records of ids no longer tracked."""
        for tid in [t for t in self._records if t not in alive]:
            del self._records[tid]


@dataclass(frozen=True)
class FilterPrediction:
    """The paper's trackers as they are: a hidden person is where the filter predicts it."""

    def reset(self) -> None:
        pass

    def found(self, frame: int, ids: list[int], boxes: np.ndarray,
              filter_velocity: np.ndarray) -> None:
        pass

    def place(self, frame: int, ids: list[int], boxes: np.ndarray) -> None:
        pass

    def forget(self, alive: set[int]) -> None:
        pass
