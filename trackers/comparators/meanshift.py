"""Mean shift (Comaniciu, Ramesh and Meer 2003), PBM's "MS" comparator, with OpenCV.

Comaniciu et al.'s iteration around each target's last box: every pixel i of colour bin u
is weighted by w_i = sqrt(q_u / p_u(y)), q the target's colour model and p(y) the
candidate box's (eq. 10), and ``cv2.meanShift`` moves the box, at fixed size, to the
weighted mean of its pixels (eq. 13, with the Epanechnikov profile's flat derivative);
repeated until the box moves less than a pixel. Life cycle and colour model:
``occbench.trackers.comparators.appearance``.
"""

from __future__ import annotations

import cv2
import numpy as np

from occbench.trackers.comparators.appearance import (
    ColourTarget,
    ColourTrackerBase,
    Loss,
    Restart,
    clip_box,
    colour_model,
)


class MeanShiftTracker(ColourTrackerBase):
    """Mean shift on the colour model (Comaniciu et al. 2003), one box of fixed size per target.

    Args:
        max_iterations: mean-shift iterations per frame (OpenCV's term criteria).
        search: half-width of the region searched around the last box, in box sizes.
        birth_iou, loss, restart, max_targets: life cycle (``ColourTrackerBase``); the
            evidence ``loss`` judges is rho at convergence (Comaniciu et al.'s eq. 17).
    """

    def __init__(self, max_iterations: int = 10, search: float = 1.0, birth_iou: float = 0.3,
                 loss: Loss | None = None, restart: Restart | None = None,
                 max_targets: int | None = None) -> None:
        if max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")
        if search <= 0:
            raise ValueError(f"search must be > 0, got {search}")
        self.max_iterations = max_iterations
        self.search = search
        super().__init__(birth_iou, loss, restart, max_targets)

    def _follow(self, target: ColourTarget, bins: np.ndarray) -> float:
        height, width = bins.shape
        x, y, w, h = target.box
        roi = clip_box(np.array([x - self.search * w, y - self.search * h,
                                 w * (1 + 2 * self.search), h * (1 + 2 * self.search)]),
                       width, height)
        if roi is None:
            return 0.0
        x0, y0, x1, y1 = roi
        u = bins[y0:y1, x0:x1]  # bin u of every pixel
        wx, wy = x - x0, y - y0
        ww, wh = max(int(round(w)), 1), max(int(round(h)), 1)
        criteria = (cv2.TERM_CRITERIA_COUNT, 1, 0)
        for _ in range(self.max_iterations):
            r = clip_box(np.array([wx, wy, w, h]), x1 - x0, y1 - y0)
            if r is None:
                break
            p = np.bincount(u[r[1]:r[3], r[0]:r[2]].ravel(), minlength=len(target.q))
            p = p / p.sum()  # the candidate's colour model p(y)
            ratio = np.sqrt(np.divide(target.q, p, out=np.zeros_like(p), where=p > 0))
            weight = ratio[u].astype(np.float32)  # w_i = sqrt(q_u / p_u(y)) (eq. 10)
            _, (nx, ny, _, _) = cv2.meanShift(weight, (int(round(wx)), int(round(wy)), ww, wh),
                                              criteria)  # y1 = sum x_i w_i / sum w_i (eq. 13)
            step = np.hypot(nx - round(wx), ny - round(wy))
            wx, wy = wx + nx - round(wx), wy + ny - round(wy)
            if step < 1:
                break
        target.box = np.array([wx + x0, wy + y0, w, h])
        return float(np.sqrt(target.q * colour_model(bins, target.box)).sum())
