"""The target: global model (PBM 2.1), parts model (2.2), filters (3) and update (4.2).

Global model (GM): six degrees of freedom (xtl, ytl, xc, yc, w, h) and the centroid
ratios alpha (eq. 1) and beta (eq. 2), each a running average over ``ratio_window``
frames, which place the five part rectangles and infer xtl and yc under occlusion.

Update (PBM 4.2):
- global DOF: replaced by the candidate's when unoccluded; under occlusion the mean of the
  last ``occluded_window`` DOF vectors (the new estimate included);
- each part whose score p_j (eq. 12) reaches ``part_match_threshold`` moves its area,
  perimeter and colour histograms towards the candidate's by a running average with weight
  ``update_rate * p_j`` (the better the match, the larger the step); a part below the
  threshold does not match and keeps its model frozen (its rectangle follows the GM).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from trackers.frontend.parts import (
    HEAD_FRACTION,
    N_PARTS,
    PartFeatures,
    part_boxes,
)
from trackers.layered.dynamics import GateFilter, SizeFilter


def dof_from_box(box: np.ndarray, centroid: np.ndarray) -> np.ndarray:
    """(6,) global DOF (xtl, ytl, xc, yc, w, h) of a box and its centroid."""
    x, y, w, h = box
    return np.array([x, y, centroid[0], centroid[1], w, h], dtype=np.float64)


def dof_from_head(head: np.ndarray, w: float, h: float, alpha: float, beta: float) -> np.ndarray:
    """(6,) DOF under occlusion (PBM 2.1): xc, ytl from the head top; xtl (eq. 1) and yc
    (eq. 2) from the previous frame's alpha and beta."""
    xc, ytl = head[0], head[1]
    xtl = xc - alpha * w
    yc = ytl + HEAD_FRACTION * h + beta * (h - HEAD_FRACTION * h)
    return np.array([xtl, ytl, xc, yc, w, h], dtype=np.float64)


class Target:
    """One tracked person.

    Attributes:
        id: track id. dof: (6,) global model. alpha, beta: averaged centroid ratios.
        (The parts models of all targets are stacked in one PartFeatures by the tracker,
        row i for target i, and updated together by ``update_parts``.)
        hits, misses, age: life-cycle counters; confirmed: passed ``min_hits``.
        occluded_parts: (5,) bool, parts frozen at the last update.
        occluded: the last match was an occluded candidate.
        head_template: grey head patch for multiple-response pruning, or None.
    """

    def __init__(self, track_id: int, dof: np.ndarray, alpha: float, beta: float,
                 gate_args: dict, size_args: dict, ratio_window: int, occluded_window: int) -> None:
        self.id = track_id
        self.dof = np.asarray(dof, dtype=np.float64).copy()
        self._alphas: deque[float] = deque([alpha], maxlen=ratio_window)
        self._betas: deque[float] = deque([beta], maxlen=ratio_window)
        self._alpha, self._beta = float(alpha), float(beta)
        self._history: deque[np.ndarray] = deque([self.dof.copy()], maxlen=occluded_window)
        xc, yc, w, h = self.dof[2], self.dof[3], self.dof[4], self.dof[5]
        self.gate = GateFilter(np.array([xc, yc]), h, **gate_args)
        self.size = SizeFilter(w, h, **size_args)
        self.hits = 1
        self.misses = 0
        self.age = 1
        self.confirmed = False
        self.occluded = False
        self.occluded_parts = np.zeros(N_PARTS, dtype=bool)
        self.part_scores = np.ones(N_PARTS)
        self.head_template: np.ndarray | None = None
        self.score = 0.0
        self.last_gate: np.ndarray | None = None

    @property
    def alpha(self) -> float:
        """Running average of eq. 1 over ``ratio_window`` frames."""
        return self._alpha

    @property
    def beta(self) -> float:
        """Running average of eq. 2 over ``ratio_window`` frames."""
        return self._beta

    @property
    def box(self) -> np.ndarray:
        """(4,) xywh of the global model."""
        return self.dof[[0, 1, 4, 5]]  # fancy indexing: a copy

    @property
    def head(self) -> np.ndarray:
        """(3,) head top-centre x, top y, head width of the global model."""
        return np.array([self.dof[2], self.dof[1], self.dof[4] * 0.5])

    def predict(self) -> np.ndarray:
        """Advance KF1 and KF2 one frame; returns the predicted (w, h) (KF2)."""
        self.gate.predict()
        self.age += 1
        return self.size.predict()

    def gate_box(self) -> np.ndarray:
        return self.gate.gate(self.size.predicted, self.misses)

    def mark_missed(self) -> None:
        self.misses += 1
        self.occluded_parts = np.ones(N_PARTS, dtype=bool)  # replaced, never modified in place

    def update(self, dof: np.ndarray, centroid_measured: bool, occluded: bool,
               part_scores: np.ndarray, part_match_threshold: float) -> np.ndarray:
        """PBM 4.2 update of the global model and the filters from the chosen candidate
        (the parts model, stacked over all targets, is updated by ``update_parts``).

        Args:
            dof: (6,) the candidate's global model. centroid_measured: xc, yc come from the
                candidate's own foreground (then alpha, beta are re-measured, eqs. 1-2).
            occluded: the candidate was occluded (window-average the DOF).
            part_scores: (5,) p_j (eq. 12); a part below ``part_match_threshold`` is frozen.
        Returns:
            (2,) shift of the centroid (xc, yc), which frozen parts' centroids follow.
        """
        old_centre = self.dof[2:4].copy()
        self._history.append(np.asarray(dof, dtype=np.float64).copy())
        if occluded:
            self.dof = np.mean(np.stack(self._history), axis=0)
        else:
            self.dof = np.asarray(dof, dtype=np.float64).copy()
            if centroid_measured:  # eqs. 1-2 (as ``centroid_ratios``, scalar)
                x, y, xc, yc, w, h = (float(v) for v in self.dof)
                hh = HEAD_FRACTION * h
                a = min(max((xc - x) / max(w, 1e-9), 0.05), 0.95)
                b = min(max((yc - y - hh) / max(h - hh, 1e-9), 0.05), 0.95)
                self._alphas.append(a)
                self._betas.append(b)
                self._alpha = sum(self._alphas) / len(self._alphas)
                self._beta = sum(self._betas) / len(self._betas)
        self.gate.correct(self.dof[2:4])
        self.size.correct(self.dof[4], self.dof[5])
        self.part_scores = np.asarray(part_scores, dtype=np.float64).copy()
        self.occluded_parts = ~(self.part_scores >= part_match_threshold)
        self.occluded = occluded
        self.hits += 1
        self.misses = 0
        return self.dof[2:4] - old_centre


def update_parts(model: PartFeatures, rows: np.ndarray, cand: PartFeatures, ks: np.ndarray,
                 part_scores: np.ndarray, part_match_threshold: float, update_rate: float,
                 shift: np.ndarray, boxes: np.ndarray, alpha: np.ndarray, beta: np.ndarray) -> None:
    """PBM 4.2 parts-model update of several targets at once, in place.

    Each part whose score p_j reaches ``part_match_threshold`` moves its area, perimeter
    and colour histograms towards the candidate's by a running average with weight
    ``update_rate * p_j``, and takes the candidate's centroid; a part below it keeps its
    model frozen, its centroid following the global model's ``shift``. The rectangles
    follow the (updated) global model.

    Args:
        model: the parts models of all targets. rows: (M,) the updated targets' rows.
        cand: features holding the chosen candidates at ``ks`` (M,) (no copy).
        part_scores: (M, 5) p_j (eq. 12). shift: (M, 2) centroid shifts (``Target.update``).
        boxes: (M, 4) xywh, alpha, beta: (M,) the updated global models.
    """
    matched = part_scores >= part_match_threshold
    eta = np.where(matched, update_rate * part_scores, 0.0)
    model.area[rows] += eta * (cand.area[ks] - model.area[rows])
    model.perimeter[rows] += eta * (cand.perimeter[ks] - model.perimeter[rows])
    model.hsv[rows] += eta[:, :, None] * (cand.hsv[ks] - model.hsv[rows])
    model.xyz[rows] += eta[:, :, None] * (cand.xyz[ks] - model.xyz[rows])
    model.centroid[rows] = np.where(matched[:, :, None], cand.centroid[ks],
                                    model.centroid[rows] + shift[:, None, :])
    model.parts[rows] = part_boxes(boxes, alpha, beta)
    model.height[rows] = boxes[:, 3]
