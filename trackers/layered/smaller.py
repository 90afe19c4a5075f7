"""PBM 3.1's smaller region, as the paper reads it and as ``lone_shrink`` reads it.

A candidate smaller than a target's prediction (KF2, eq. 8) by more than
``search.occlusion_threshold`` is, in PBM 3.1, the target partly occluded: its
predicted-size box is aligned on the candidate's head. ``LoneShrink`` asks for an occluder
first (``docs/adaptations.md``, ``lone_shrink`` and ``lone_shrink_shape``). Boxes are
(N, 4) float64 xywh pixels; ``kinds`` is ``occlusion_kinds``' (T, N) array (+1 larger,
-1 smaller, 0 neither).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.layered.search import Candidates
from occbench.trackers.layered.targets import Targets


class OccludedSmaller:
    """PBM 3.1 as written: a region smaller than the prediction by more than the occlusion
    threshold is the target partly occluded; its predicted-size box is aligned on the head."""

    def apply(self, kinds: np.ndarray, cand: Candidates, targets: Targets, pred_wh: np.ndarray,
              present: np.ndarray) -> None:
        """Leaves ``kinds`` (T, N) as the size test set them."""


@dataclass(frozen=True)
class LoneShrink:
    """``lone_shrink``: a detection smaller than target t's prediction (kind -1) is t
    partly occluded only when an occluder is there: another ``present`` target whose box
    covers at least ``cover`` of t's predicted-size box aligned on the detection's head;
    without one it is t at its own size (kind 0, taken as measured), the mirror of
    ``lone_growth``. A target whose size grew wrongly (a blob spanning two people taken as
    one) otherwise keeps that size on every later detection of its person. Blobs keep
    PBM 3.1's reading (their foreground may lack a person's legs).

    ``shape`` (``lone_shrink_shape``, 0: any shape): the detection is t at its own size
    only when it has t's shape, its height / width at least ``shape`` x the prediction's
    (KF2's h / w): a whole person seen smaller, not a piece of one (a head-high sliver of
    a person beside t is as wide as it is tall); otherwise PBM 3.1's reading stands."""

    cover: float
    shape: float = 0.0

    def apply(self, kinds: np.ndarray, cand: Candidates, targets: Targets, pred_wh: np.ndarray,
              present: np.ndarray) -> None:
        """Sets kinds[t, n] = 0 in place where the smaller detection n has no occluder of t
        (and, with ``shape``, has t's shape)."""
        ti, n = np.nonzero((kinds < 0) & ~cand.blob[None, :])
        if self.shape > 0 and len(ti):
            region = cand.region[n]
            own = region[:, 3] * pred_wh[ti, 0] >= self.shape * pred_wh[ti, 1] * region[:, 2]
            ti, n = ti[own], n[own]
        if not len(ti):
            return
        w, h = pred_wh[ti, 0], pred_wh[ti, 1]
        head = cand.head[n]
        aligned = np.column_stack([head[:, 0] - targets.alpha[ti] * w, head[:, 1], w, h])
        boxes = targets.dof[:, [0, 1, 4, 5]]
        x0 = np.maximum(aligned[:, None, 0], boxes[None, :, 0])
        x1 = np.minimum(aligned[:, None, 0] + w[:, None], (boxes[:, 0] + boxes[:, 2])[None])
        y0 = np.maximum(aligned[:, None, 1], boxes[None, :, 1])
        y1 = np.minimum(aligned[:, None, 1] + h[:, None], (boxes[:, 1] + boxes[:, 3])[None])
        inter = np.clip(x1 - x0, 0, None) * np.clip(y1 - y0, 0, None)  # (P, T)
        share = inter / np.maximum(w * h, 1e-9)[:, None]
        share[np.arange(len(ti)), ti] = 0.0  # not its own occluder
        share[:, ~present] = 0.0
        lone = share.max(axis=1) < self.cover
        kinds[ti[lone], n[lone]] = 0
