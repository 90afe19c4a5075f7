"""Mean shift (Comaniciu, Ramesh and Meer 2003), PBM's "MS" comparator, with OpenCV; fixed
size, and with Comaniciu et al.'s scale adaptation.

Comaniciu et al.'s iteration around each target's last box: every pixel i of colour bin u
is weighted by w_i = sqrt(q_u / p_u(y)), q the target's colour model and p(y) the
candidate box's (eq. 10), and ``cv2.meanShift`` moves the box, at fixed size, to the
weighted mean of its pixels (eq. 13, with the Epanechnikov profile's flat derivative);
repeated until the box moves less than a pixel. ``ScaleAdaptiveMeanShift`` runs that
iteration at the previous size h and at h -/+ 10 %, keeps the size whose converged box has
the largest Bhattacharyya coefficient (h_opt) and smooths it,
h_new = gamma h_opt + (1 - gamma) h_prev, with Delta h = 0.1 h_prev and gamma = 0.1
(Comaniciu, Ramesh and Meer, "Real-time tracking of non-rigid objects using mean shift",
CVPR 2000, its bandwidth adaptation; the same test in their 2003 "Kernel-based object
tracking"). Life cycle and colour model:
``occbench.trackers.comparators.appearance``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from occbench.trackers.common.checks import (
    at_least,
    coerce,
    parameter_group,
    refuse_moved,
    require,
)
from occbench.trackers.comparators.appearance import (
    ColourTarget,
    ColourTrackerBase,
    Loss,
    Restart,
    clip_box,
    colour_model,
)


def mean_shift(q: np.ndarray, box: np.ndarray, bins: np.ndarray, search: float,
               max_iterations: int) -> np.ndarray:
    """Comaniciu et al.'s mean-shift iteration (eqs. 10, 13) from ``box`` at its size.

    Args:
        q: (MODEL_BINS,) the target's colour model.
        box: xywh start box; its size is kept.
        bins: (H, W) colour bin of every pixel (``colour_bins``).
        search: half-width of the region searched around ``box``, in box sizes.
        max_iterations: iterations at most (stops earlier once a step is under a pixel).
    Returns:
        The converged xywh box (``box`` itself when the region is empty).
    """
    height, width = bins.shape
    x, y, w, h = box
    roi = clip_box(np.array([x - search * w, y - search * h,
                             w * (1 + 2 * search), h * (1 + 2 * search)]), width, height)
    if roi is None:
        return box
    x0, y0, x1, y1 = roi
    u = bins[y0:y1, x0:x1]  # bin u of every pixel
    wx, wy = x - x0, y - y0
    ww, wh = max(int(round(w)), 1), max(int(round(h)), 1)
    criteria = (cv2.TERM_CRITERIA_COUNT, 1, 0)
    for _ in range(max_iterations):
        r = clip_box(np.array([wx, wy, w, h]), x1 - x0, y1 - y0)
        if r is None:
            break
        p = np.bincount(u[r[1]:r[3], r[0]:r[2]].ravel(), minlength=len(q))
        p = p / p.sum()  # the candidate's colour model p(y)
        ratio = np.sqrt(np.divide(q, p, out=np.zeros_like(p), where=p > 0))
        weight = ratio[u].astype(np.float32)  # w_i = sqrt(q_u / p_u(y)) (eq. 10)
        _, (nx, ny, _, _) = cv2.meanShift(weight, (int(round(wx)), int(round(wy)), ww, wh),
                                          criteria)  # y1 = sum x_i w_i / sum w_i (eq. 13)
        step = np.hypot(nx - round(wx), ny - round(wy))
        wx, wy = wx + nx - round(wx), wy + ny - round(wy)
        if step < 1:
            break
    return np.array([wx + x0, wy + y0, w, h])


def similarity(q: np.ndarray, bins: np.ndarray, box: np.ndarray) -> float:
    """rho(q, p(box)), the Bhattacharyya coefficient (Comaniciu et al.'s eq. 17)."""
    return float(np.sqrt(q * colour_model(bins, box)).sum())


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
        at_least("", 1, max_iterations=max_iterations)
        require("search", search > 0, "must be > 0", search)
        self.max_iterations = max_iterations
        self.search = search
        super().__init__(birth_iou, loss, restart, max_targets)

    def _follow(self, target: ColourTarget, bins: np.ndarray) -> float:
        target.box = mean_shift(target.q, target.box, bins, self.search, self.max_iterations)
        return similarity(target.q, bins, target.box)


@dataclass(frozen=True)
class ScaleTest:
    """Comaniciu, Ramesh and Meer's scale test (CVPR 2000).

    Args:
        step: the relative size change tested (Delta h / h_prev), in (0, 1) (the paper's
            0.1).
        gamma: the smoothing weight of h_opt, in [0, 1] (0 keeps the size fixed; the
            paper's 0.1).
    """

    step: float = 0.1
    gamma: float = 0.1

    def __post_init__(self) -> None:
        require("scale.step", 0.0 < self.step < 1.0, "must lie in (0, 1)", self.step)
        require("scale.gamma", 0.0 <= self.gamma <= 1.0, "must lie in [0, 1]", self.gamma)
        coerce(self, {"step": float, "gamma": float})


class ScaleAdaptiveMeanShift(MeanShiftTracker):
    """Mean shift with Comaniciu, Ramesh and Meer's scale test: the box's size adapts.

    Each frame the fixed-size iteration runs three times, from the last box at its size h_prev
    and at (1 -/+ ``step``) h_prev about the same centre; the size whose converged box has
    the largest rho is h_opt, and the box takes h_new = gamma h_opt + (1 - gamma) h_prev
    (CVPR 2000: step 0.1, gamma 0.1) at h_opt's converged centre. Width and
    height scale together (the box's aspect is the starting box's).

    Args:
        scale: the sizes tested and the smoothing of the chosen one (``ScaleTest``; None:
            the paper's).
        max_iterations, search, birth_iou, loss, restart, max_targets: as for
            ``MeanShiftTracker``; ``loss`` judges rho of the box at h_new.
        A key of the flat arguments before the groups is refused with a TypeError naming
        its group.
    """

    def __init__(self, scale: ScaleTest | None = None, max_iterations: int = 10,
                 search: float = 1.0, birth_iou: float = 0.3, loss: Loss | None = None,
                 restart: Restart | None = None, max_targets: int | None = None,
                 **moved: object) -> None:
        refuse_moved("tracker", moved, {"scale": ScaleTest})
        self.scale = parameter_group("scale", scale, ScaleTest)
        super().__init__(max_iterations, search, birth_iou, loss, restart, max_targets)

    def _follow(self, target: ColourTarget, bins: np.ndarray) -> float:
        x, y, w, h = target.box
        cx, cy = x + w / 2, y + h / 2
        best, best_rho, best_f = target.box, -1.0, 1.0
        step, gamma = self.scale.step, self.scale.gamma
        for f in (1.0, 1.0 - step, 1.0 + step):  # h_prev, h_prev -/+ Delta h
            start = np.array([cx - f * w / 2, cy - f * h / 2, f * w, f * h])
            box = mean_shift(target.q, start, bins, self.search, self.max_iterations)
            rho = similarity(target.q, bins, box)
            if rho > best_rho:  # ties keep the earlier: h_prev first
                best, best_rho, best_f = box, rho, f
        s = gamma * best_f + (1.0 - gamma)  # h_new = gamma h_opt + (1 - gamma) h_prev
        bx, by = best[0] + best[2] / 2, best[1] + best[3] / 2
        target.box = np.array([bx - s * w / 2, by - s * h / 2, s * w, s * h])
        return similarity(target.q, bins, target.box)
