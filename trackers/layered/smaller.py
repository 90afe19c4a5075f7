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

import numba
import numpy as np

from occbench.trackers.layered.search import Candidates
from occbench.trackers.layered.targets import Targets


class OccludedSmaller:
    """PBM 3.1 as written: a region smaller than the prediction by more than the occlusion
    threshold is the target partly occluded; its predicted-size box is aligned on the head."""

    def apply(self, kinds: np.ndarray, cand: Candidates, targets: Targets, pred_wh: np.ndarray,
              present: np.ndarray, inside: np.ndarray | None = None) -> None:
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
    a person beside t is as wide as it is tall); otherwise PBM 3.1's reading stands.

    ``narrow`` (``lone_shrink_narrow``): with ``shape``, the detection's height / width must
    also be at most 1 / ``shape`` x the prediction's: a person cut by a vertical edge (a
    doorway's frame, a pillar) leaves a sliver taller than his shape, and taking it as the
    whole person shrinks the target to it (ecp1-180 gt frames 38-54: 3 x 61, then 3 x 27,
    against 18 x 82; its gate never reaches him again)."""

    cover: float
    shape: float = 0.0
    narrow: bool = False

    def apply(self, kinds: np.ndarray, cand: Candidates, targets: Targets, pred_wh: np.ndarray,
              present: np.ndarray, inside: np.ndarray | None = None) -> None:
        """Sets kinds[t, n] = 0 in place where the smaller detection n has no occluder of t
        (and, with ``shape``, has t's shape), for the pairs ``inside`` (T, N) bool marks
        (the targets' gates, ``gating.in_gates``: no later step reads a kind outside them;
        None: every pair)."""
        smaller = (kinds < 0) & ~cand.blob[None, :]
        ti, n = np.nonzero(smaller if inside is None else smaller & inside)
        if self.shape > 0 and len(ti):
            region = cand.region[n]
            own = region[:, 3] * pred_wh[ti, 0] >= self.shape * pred_wh[ti, 1] * region[:, 2]
            if self.narrow:
                own &= self.shape * region[:, 3] * pred_wh[ti, 0] <= pred_wh[ti, 1] * region[:, 2]
            ti, n = ti[own], n[own]
        # the kernel is called when no pair is smaller too: a warm-up loads it (test_warmup)
        w, h = pred_wh[ti, 0], pred_wh[ti, 1]
        head = cand.head[n]
        aligned = np.column_stack([head[:, 0] - targets.alpha[ti] * w, head[:, 1], w, h])
        lone = np.empty(len(ti), dtype=bool)
        lone_rows(aligned, targets.dof[:, [0, 1, 4, 5]], ti, present, self.cover, lone)
        kinds[ti[lone], n[lone]] = 0


@numba.njit(cache=True, inline="always")
def _maximum(a: float, b: float) -> float:
    """``np.maximum`` of two floats (NaN when either is)."""
    return a if (a >= b or a != a) else b


@numba.njit(cache=True, inline="always")
def _minimum(a: float, b: float) -> float:
    """``np.minimum`` of two floats (NaN when either is)."""
    return a if (a <= b or a != a) else b


@numba.njit(cache=True)
def lone_rows(aligned: np.ndarray, boxes: np.ndarray, ti: np.ndarray, present: np.ndarray,
              cover: float, out: np.ndarray) -> None:
    """``LoneShrink``'s test of P aligned xywh boxes (P, 4) against T target boxes (T, 4)
    into out (P,) bool: no ``present`` target but ti[p] covers ``cover`` or more of box p,
    its share inter / max(w h, 1e-9) in the same operations as numpy's elementwise arrays
    (False when a share is NaN, as numpy's max of the row is then)."""
    for p in range(aligned.shape[0]):
        x, y, w, h = aligned[p, 0], aligned[p, 1], aligned[p, 2], aligned[p, 3]
        area = _maximum(w * h, 1e-9)
        top, nan = -np.inf, False
        for t in range(boxes.shape[0]):
            share = 0.0  # not its own occluder, nor an absent target
            if t != ti[p] and present[t]:
                x0, x1 = _maximum(x, boxes[t, 0]), _minimum(x + w, boxes[t, 0] + boxes[t, 2])
                y0, y1 = _maximum(y, boxes[t, 1]), _minimum(y + h, boxes[t, 1] + boxes[t, 3])
                share = _maximum(x1 - x0, 0.0) * _maximum(y1 - y0, 0.0) / area
            if share != share:
                nan = True
            elif share > top:
                top = share
        out[p] = not nan and top < cover
