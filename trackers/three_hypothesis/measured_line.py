"""Hypothesis 1's velocity (Reta 3.3.3, case 1: a missing person keeps its velocity and
direction): M's, or the line through the person's last measured centres; the paper's rule
and ours (``adaptations.measured_hypothesis``), ``rules.build_rules`` picks one. Issue 35: on
PETS a person who turns or speeds up keeps a Kalman velocity a third of its own for ten
frames (M's position noise takes up the motion), and its hypothesis is left behind at the
next contact. ``docs/adaptations.md`` gives the evidence. States are (8,) Kalman vectors
(xc, yc, w, h, vx, vy, vw, vh); boxes (4,) xywh pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np


@dataclass(frozen=True)
class FilterVelocity:
    """3.3.3 as written: hypothesis 1 continues M's prediction (M's velocity)."""

    records: ClassVar[bool] = False

    def record(self, person, frame: int, box: np.ndarray, predicted: np.ndarray) -> None:
        return None

    def start(self, person, x_prev: np.ndarray, x_pred: np.ndarray) -> np.ndarray:
        return x_pred


def _line(centres: list[tuple[float, float, float]]) -> tuple[float, float, float, float, float]:
    """Least-squares line (t0, x0, y0, vx, vy) through (frame, xc, yc) rows: the centre at
    the mean frame t0 and the velocity."""
    return _fit(centres)[:5]


def _fit(centres: list[tuple[float, float, float]]) -> tuple[float, ...]:
    """``_line``'s (t0, x0, y0, vx, vy) and the standard errors (se_x, se_y) of the two
    slopes: sqrt(sum of squared residuals / (n - 2) / sum (t - t0)^2) (n >= 3 rows)."""
    c = np.asarray(centres, dtype=np.float64)
    t = c[:, 0] - c[:, 0].mean()
    tt = float((t * t).sum())
    x, y = c[:, 1] - c[:, 1].mean(), c[:, 2] - c[:, 2].mean()
    vx, vy = float((t * x).sum()) / tt, float((t * y).sum()) / tt
    dof = max(len(c) - 2, 1)
    se_x = float(np.sqrt(((x - vx * t) ** 2).sum() / dof / tt))
    se_y = float(np.sqrt(((y - vy * t) ** 2).sum() / dof / tt))
    return (float(c[:, 0].mean()), float(c[:, 1].mean()), float(c[:, 2].mean()), vx, vy,
            se_x, se_y)


@dataclass(frozen=True)
class MeasuredLine:
    """``measured_hypothesis``: hypothesis 1 of a person just missed moves with the velocity
    of the least-squares line through its last ``window`` measured centres (Alg. 1's m), from
    its last estimate, when that line has predicted the person's measurements better than M
    so far (summed squared errors in box heights, each measurement predicted from the ones
    before it: the person's own track record chooses); else M's, as the paper. With
    ``sigmas`` > 0 the line is taken only where it is measured to differ from M's velocity,
    by more than ``sigmas`` standard errors of its slope in x or in y (a standing person's
    jitter draws a line that predicts as well as M by chance)."""

    window: int
    sigmas: float = 0.0
    records: ClassVar[bool] = True

    def record(self, person, frame: int, box: np.ndarray, predicted: np.ndarray) -> None:
        """Score both predictors on this measured (4,) xywh ``box`` (M's: ``predicted``
        (8,) state), then keep its centre."""
        cx, cy = box[0] + box[2] / 2, box[1] + box[3] / 2
        centres = person.centres
        if len(centres) >= 3:
            t0, x0, y0, vx, vy = _line(centres)
            h2 = max(float(box[3]), 1.0) ** 2
            person.line_errors[0] += ((predicted[0] - cx) ** 2 + (predicted[1] - cy) ** 2) / h2
            person.line_errors[1] += ((x0 + vx * (frame - t0) - cx) ** 2
                                      + (y0 + vy * (frame - t0) - cy) ** 2) / h2
        centres.append((frame, cx, cy))
        del centres[:-self.window]

    def start(self, person, x_prev: np.ndarray, x_pred: np.ndarray) -> np.ndarray:
        """(8,) state of hypothesis 1 at a person's first miss, from its last estimate
        ``x_prev`` and M's prediction ``x_pred``."""
        errors = person.line_errors
        if len(person.centres) < 3 or errors[1] >= errors[0]:
            return x_pred
        _, _, _, vx, vy, se_x, se_y = _fit(person.centres)
        if self.sigmas > 0 and (abs(vx - x_pred[4]) <= self.sigmas * se_x
                                and abs(vy - x_pred[5]) <= self.sigmas * se_y):
            return x_pred  # the line's velocity is M's within its own error
        x = x_pred.copy()
        x[0], x[1], x[4], x[5] = x_prev[0] + vx, x_prev[1] + vy, vx, vy
        return x
