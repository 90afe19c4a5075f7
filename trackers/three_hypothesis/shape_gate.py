"""Which sizes may continue a node (3.3.2): the paper's rule and ours (``adaptations.shape_gate``) against ids handed
across by the front end's boxes (issue 28 (c): the box of the person in front covers a
hidden one, one box covers a group), after BoostTrack's shape similarity;
``rules.build_rules`` picks one; ``docs/adaptations.md`` gives the evidence. Boxes are
(N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np


@dataclass(frozen=True)
class AnyShape:
    """3.3.2 as written: a measurement of any size may continue a person."""

    uses_seen: ClassVar[bool] = False

    def admissible(self, pred: np.ndarray, dets: np.ndarray, owners: np.ndarray,
                   delta: np.ndarray, seen: np.ndarray | None) -> None:
        return None


def shape_similarity(pred: np.ndarray, dets: np.ndarray) -> np.ndarray:
    """(B, D) BoostTrack's shape similarity (Stanojevic et al. 2024; each side normalised by
    its own larger value) of (B, 4) and (D, 4) xywh boxes: S = exp(-(|w_d - w_n| /
    max(w_d, w_n) + |h_d - h_n| / max(h_d, h_n))), 1 for equal sizes."""
    w_n, h_n = pred[:, 2:3], pred[:, 3:4]
    w_d, h_d = dets[None, :, 2], dets[None, :, 3]
    return np.exp(-(np.abs(w_d - w_n) / np.maximum(w_d, w_n)
                    + np.abs(h_d - h_n) / np.maximum(h_d, h_n)))


@dataclass(frozen=True)
class ShapeGate:
    """``shape_gate``: a node may not take a measurement whose size disagrees with its own
    (shape similarity below ``min_similarity``) while another person seen at t-1 meets that
    measurement (eq. 5 delta > 0) with a size that agrees: the box is better explained as
    that other person (the person in front of a hidden one, one box over a group), so it
    does not carry this node's id across; this person is then missed (hidden) instead. A
    size jump nobody else explains (a lone person's foreground jitter), or one only a
    hypothesis explains, is still matched."""

    min_similarity: float
    uses_seen: ClassVar[bool] = True  # the tracker passes its nodes' visible flags

    def admissible(self, pred: np.ndarray, dets: np.ndarray, owners: np.ndarray,
                   delta: np.ndarray, seen: np.ndarray) -> np.ndarray | None:
        """(B, D) bool from (B, 4) xywh predicted regions, (D, 4) xywh measurements, (B,)
        sorted person index of each node, (B, D) region similarity (eq. 5) and (B,) bool
        ``seen``: the node is a person's visible node of t-1 (not a hypothesis)."""
        if not len(pred) or not len(dets):
            return None
        fits = shape_similarity(pred, dets) >= self.min_similarity
        starts = np.searchsorted(owners, np.arange(owners[-1] + 1))
        explains = np.logical_or.reduceat(fits & (delta > 0) & seen[:, None], starts,
                                          axis=0)  # (P, D)
        rival = explains.sum(axis=0)[None, :] - explains[owners] > 0  # another person's
        return fits | ~rival
