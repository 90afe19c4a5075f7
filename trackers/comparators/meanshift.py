"""Mean shift (Comaniciu, Ramesh and Meer 2003), PBM's "MS" comparator, with OpenCV.

The hue-saturation part of each target's colour model q is back-projected on the frame (every pixel gets
q of its colour bin) around the target's last box, and ``cv2.meanShift`` moves the box, at
fixed size, to the mode of that likelihood. Life cycle and colour model:
``trackers.comparators.appearance``.
"""

from __future__ import annotations

import cv2
import numpy as np

from trackers.comparators.appearance import (
    HUE_BINS, SAT_BINS, ColourTarget, ColourTrackerBase, clip_box, hs_histogram,
)

_RANGES = [0, 180, 0, 256]


class MeanShiftTracker(ColourTrackerBase):
    """Mean shift over the back-projected colour model, one box of fixed size per target.

    Args:
        max_iterations: mean-shift iterations per frame (OpenCV's term criteria).
        search: half-width of the region searched around the last box, in box sizes.
        birth_iou, min_similarity, max_misses: life cycle (``ColourTrackerBase``).
    """

    def __init__(self, max_iterations: int = 10, search: float = 1.0, birth_iou: float = 0.3,
                 min_similarity: float = 0.5, max_misses: int = 10) -> None:
        if max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")
        if search <= 0:
            raise ValueError(f"search must be > 0, got {search}")
        self.max_iterations = max_iterations
        self.search = search
        super().__init__(birth_iou, min_similarity, max_misses)

    def _follow(self, target: ColourTarget, hsv: np.ndarray, mask: np.ndarray) -> float:
        height, width = hsv.shape[:2]
        x, y, w, h = target.box
        roi = clip_box(np.array([x - self.search * w, y - self.search * h,
                                 w * (1 + 2 * self.search), h * (1 + 2 * self.search)]),
                       width, height)
        if roi is None:
            return 0.0
        x0, y0, x1, y1 = roi
        hs = target.q[:HUE_BINS * SAT_BINS].reshape(HUE_BINS, SAT_BINS)
        model = hs * 255.0 / max(hs.max(), 1e-12)
        back = cv2.calcBackProject([hsv[y0:y1, x0:x1]], [0, 1], model.astype(np.float32),
                                   _RANGES, 1)
        back &= mask[y0:y1, x0:x1]
        window = (int(round(x)) - x0, int(round(y)) - y0, max(int(round(w)), 1),
                  max(int(round(h)), 1))
        criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, self.max_iterations, 1)
        _, (wx, wy, _, _) = cv2.meanShift(back, window, criteria)
        target.box = np.array([wx + x0 + (x - round(x)), wy + y0 + (y - round(y)), w, h])
        return float(np.sqrt(target.q * hs_histogram(hsv, mask, target.box)).sum())
