"""Occlusion relations O (Reta 3.3.1, eq. 2) and depth order pi (eq. 3).

Regions are the ellipses inscribed in (N, 4) float64 xywh boxes (0-based pixels), the
shape S = (xc, yc, 0, w/2, h/2) of ``trackers.geometry.box_ellipses``.
"""

from __future__ import annotations

import math

import numpy as np

from trackers.frontend.features import region_similarity
from trackers.geometry import intersection_matrix


def overlap_ratio(a: np.ndarray, b: np.ndarray, samples: int = 24) -> np.ndarray:
    """Eq. 2's ratio |Si & Sj| / (|Si| + |Sj|) for all pairs of ellipse regions.

    It is half the region similarity delta of eq. 5 (delta = 2 |Si & Sj| / (|Si| + |Sj|)),
    so it lies in [0, 0.5]: 0.5 for identical regions.

    Args:
        a: (N, 4) xywh; b: (M, 4) xywh.
        samples: integration grid per side (``region_similarity``).
    Returns:
        (N, M) float64.
    """
    return 0.5 * region_similarity(a, b, samples=samples)


def occlusion_pairs(boxes: np.ndarray, owners: np.ndarray, lam: float,
                    ratio: np.ndarray | None = None, samples: int = 24) -> np.ndarray:
    """Occlusion relation O of eq. 2 over predicted regions of nodes.

    O = {(n_i, n_j) | id_i != id_j, |S_i & S_j| / (|S_i| + |S_j|) > lambda}.

    Args:
        boxes: (N, 4) xywh predicted regions S^{t|t-1} of the nodes.
        owners: (N,) person key of each node (hypotheses of one person never occlude
            each other).
        lam: overlap threshold lambda in [0, 0.5).
        ratio: optional precomputed (N, N) ``overlap_ratio(boxes, boxes)``; else only
            pairs of different people with intersecting boxes are integrated.
        samples: integration grid per side (``region_similarity``).
    Returns:
        (K, 2) int rows (i, j) with i < j, node indices into ``boxes``.
    """
    n = len(boxes)
    if n < 2:
        return np.zeros((0, 2), dtype=int)
    owners = np.asarray(owners)
    if ratio is None:
        # only pairs of different people whose bounding boxes meet can overlap
        cand = (intersection_matrix(boxes, boxes) > 0) & (owners[:, None] != owners[None, :])
        ci, cj = np.nonzero(np.triu(cand, k=1))
        if len(ci) == 0:
            return np.zeros((0, 2), dtype=int)
        ui, uj = np.unique(ci), np.unique(cj)
        sub = overlap_ratio(boxes[ui], boxes[uj], samples)
        ratio = np.zeros((n, n))
        ratio[np.ix_(ui, uj)] = sub
        ratio *= cand
    mask = (ratio > lam) & (owners[:, None] != owners[None, :])
    i, j = np.nonzero(np.triu(mask, k=1))
    return np.column_stack([i, j]).astype(int)


def area_above(boxes: np.ndarray, y0: np.ndarray) -> np.ndarray:
    """Area of each box's ellipse above the image row y0 (smaller y), exactly.

    With t = (y0 - yc) / ry clipped to [-1, 1], the area is
    rx ry (t sqrt(1 - t^2) + arcsin t + pi / 2).

    Args:
        boxes: (N, 4) xywh; y0: (N,) row coordinates.
    Returns:
        (N,) float64 areas.
    """
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    rx, ry = b[:, 2] / 2, b[:, 3] / 2
    yc = b[:, 1] + ry
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip(np.where(ry > 0, (np.asarray(y0, dtype=np.float64) - yc) / ry, 0.0), -1.0, 1.0)
    return rx * ry * (t * np.sqrt(1.0 - t * t) + np.arcsin(t) + np.pi / 2)


def depth_order(
    visible_i: bool,
    visible_j: bool,
    shape_i: np.ndarray,
    predicted_j: np.ndarray,
    previous: int,
) -> int:
    """Depth order pi_ij of eq. 3: +1 when i occludes j, -1 when j occludes i.

    * i visible and j not: +1; j visible and i not: -1 (the detected one is in front).
    * both visible: compare the areas of j's predicted region up and down the centre of
      i's current region: up_yc(i, S_j) > down_yc(i, S_j) means j stands higher in the
      image, farther from the camera, so i occludes j (+1); smaller gives -1.
    * otherwise (neither visible, or a tie): inherit pi^{t-1}_ij (``previous``).

    Args:
        shape_i: (4,) xywh current region of i (its measurement when visible).
        predicted_j: (4,) xywh predicted region S^{t|t-1}_j.
        previous: pi^{t-1}_ij in {+1, -1, 0} (0 = unknown).
    """
    if visible_i and not visible_j:
        return 1
    if visible_j and not visible_i:
        return -1
    if visible_i and visible_j:
        # scalar form of area_above (this runs once per occlusion pair per frame)
        yc = float(shape_i[1] + shape_i[3] / 2)
        rx, ry = float(predicted_j[2]) / 2, float(predicted_j[3]) / 2
        t = min(max((yc - float(predicted_j[1]) - ry) / ry, -1.0), 1.0) if ry > 0 else 0.0
        up = rx * ry * (t * math.sqrt(1.0 - t * t) + math.asin(t) + math.pi / 2)
        down = math.pi * rx * ry - up
        if up > down:
            return 1
        if up < down:
            return -1
    return previous
