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


@dataclass(slots=True)
class _Record:
    """One id's last measurement and its two predictors' track record, as Python floats
    (a handful of 2-vectors per person and frame: numpy's per-call cost would dominate)."""

    frame: int  # frame of the last measured box
    box: tuple[float, float, float, float]  # last measured box, xywh
    filter_velocity: tuple[float, float]  # the filter's velocity after that measurement
    measured_velocity: tuple[float, float] | None = None  # displacement per frame, last two boxes
    filter_error: float = 0.0  # summed squared error / h^2 of the filter's predictions
    measured_error: float = 0.0  # ... of the measured velocity's predictions


@dataclass
class MeasuredVelocity:
    """Reta's ``adaptations.measured_velocity``: per-id records of the two predictors."""

    _records: dict[int, _Record] = field(default_factory=dict)

    def reset(self) -> None:
        self._records.clear()

    def found(self, frame: int, ids: list[int], boxes: np.ndarray,
              filter_velocity: np.ndarray) -> None:
        """Record the measured boxes (N, 4) of the found ``ids`` at ``frame`` with their
        filters' velocities (N, 2) after the update; score both predictors of each box."""
        records = self._records
        for tid, box, v in zip(ids, np.asarray(boxes, dtype=np.float64).tolist(),
                               np.asarray(filter_velocity, dtype=np.float64).tolist()):
            rec = records.get(tid)
            if rec is None:
                records[tid] = _Record(frame, tuple(box), tuple(v))
                continue
            cx, cy = box[0] + box[2] / 2, box[1] + box[3] / 2
            n = frame - rec.frame
            x, y, w, h = rec.box
            lx, ly = x + w / 2, y + h / 2
            mv = rec.measured_velocity
            if mv is not None:  # each predictor's squared miss |last + n v - centre|^2 / h^2
                h2 = max(h, 1.0) ** 2
                fv = rec.filter_velocity
                dx, dy = lx + n * fv[0] - cx, ly + n * fv[1] - cy
                rec.filter_error += (dx * dx + dy * dy) / h2
                dx, dy = lx + n * mv[0] - cx, ly + n * mv[1] - cy
                rec.measured_error += (dx * dx + dy * dy) / h2
            k = max(n, 1)
            rec.measured_velocity = ((cx - lx) / k, (cy - ly) / k)
            rec.frame, rec.box, rec.filter_velocity = frame, tuple(box), tuple(v)

    def place(self, frame: int, ids: list[int], boxes: np.ndarray,
              velocity: np.ndarray | None = None) -> None:
        """Move, in place, the boxes (N, 4) of hidden ``ids`` whose measured velocity has
        predicted better: their last measured box moved by it times the frames since."""
        for r, tid in enumerate(ids):
            rec = self._records.get(tid)
            if rec is None or rec.measured_velocity is None:
                continue
            if rec.measured_error < rec.filter_error:
                k = frame - rec.frame
                x, y, w, h = rec.box
                boxes[r] = (x + k * rec.measured_velocity[0], y + k * rec.measured_velocity[1], w, h)

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

    def place(self, frame: int, ids: list[int], boxes: np.ndarray,
              velocity: np.ndarray | None = None) -> None:
        pass

    def forget(self, alive: set[int]) -> None:
        pass
