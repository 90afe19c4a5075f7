"""Occlusion relations O (Reta 3.3.1, eq. 2) and depth order pi (eq. 3).

Regions are the ellipses inscribed in (N, 4) float64 xywh boxes (0-based pixels), the
shape S = (xc, yc, 0, w/2, h/2) of ``occbench.trackers.geometry.box_ellipses``.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from occbench.trackers.common.spatial import meeting_pairs
from occbench.trackers.three_hypothesis._kernels import region_overlap_pairs
from occbench.trackers.three_hypothesis import _shares as shares


def region_overlaps(
    a: np.ndarray, b: np.ndarray, samples: int = 24, near: np.ndarray | None = None
) -> np.ndarray:
    """Region similarity delta of eq. 5 for ellipse regions, integrated only where needed.

    delta(Sp, Sq) = 2 |Sp & Sq| / (|Sp| + |Sq|). The values are exactly those of
    ``occbench.trackers.three_hypothesis.features.region_similarity(a, b, "ellipse", samples)`` (the
    definition; ``tests/trackers/three_hypothesis/test_tracker.py`` checks equality):
    |Sa & Sb| is the share of a ``samples`` x ``samples`` grid over a's box lying in both
    ellipses, times |Sa| = pi/4 w h.
    Three things make it cheaper per frame: the grid is separable, so each ellipse test is
    a sum of a row term and a column term, and a's own ellipse test is done once per box
    instead of once per pair; ``near`` restricts the integration to the pairs the caller
    needs (pairs outside it get delta 0); and the loops are compiled
    (``_kernels.region_overlap_pairs``).

    Args:
        a: (N, 4) xywh; b: (M, 4) xywh.
        samples: grid points per side.
        near: optional (N, M) bool pairs to integrate; default ``boxes_meet(a, b)``
            (the only pairs that can overlap). Pairs outside ``near`` get 0: they must
            not overlap or not be wanted.
    Returns:
        (N, M) float64 in [0, 1].
    """
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 4)
    out = np.zeros((len(a), len(b)))
    ia, ib = meeting_pairs(a, b) if near is None else np.nonzero(near)
    out[ia, ib] = region_overlap_values(a, b, ia, ib, samples)
    return out


def region_overlap_values(a: np.ndarray, b: np.ndarray, ia: np.ndarray, ib: np.ndarray,
                          samples: int = 24) -> np.ndarray:
    """(K,) ``region_overlaps`` of the K pairs (a[ia[k]], b[ib[k]]) alone, the same bits,
    without an (N, M) matrix (pairs whose boxes do not meet must not be asked: 0)."""
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 4)
    out = np.zeros(len(ia))
    if len(ia):
        region_overlap_pairs(a, b, np.asarray(ia), np.asarray(ib), _grid(samples), out)
    return out


@functools.cache
def _grid(samples: int) -> np.ndarray:
    """(samples,) read-only positions (k + 1/2) / samples of the integration grid in [0, 1]."""
    t = (np.arange(samples) + 0.5) / samples
    t.flags.writeable = False
    return t


def boxes_meet(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, M) bool: xywh boxes a (N, 4) and b (M, 4) share a positive area (the pairs whose
    ``occbench.trackers.geometry.intersection_matrix`` is positive)."""
    ax1, ay1 = a[:, 0:1], a[:, 1:2]
    bx1, by1 = b[:, 0], b[:, 1]
    w = np.minimum(ax1 + a[:, 2:3], bx1 + b[:, 2]) - np.maximum(ax1, bx1)
    h = np.minimum(ay1 + a[:, 3:4], by1 + b[:, 3]) - np.maximum(ay1, by1)
    return (w > 0) & (h > 0)


def overlap_ratio(a: np.ndarray, b: np.ndarray, samples: int = 24) -> np.ndarray:
    """Eq. 2's ratio |Si & Sj| / (|Si| + |Sj|) for all pairs of ellipse regions.

    It is half the region similarity delta of eq. 5 (delta = 2 |Si & Sj| / (|Si| + |Sj|)),
    so it lies in [0, 0.5]: 0.5 for identical regions.

    Args:
        a: (N, 4) xywh; b: (M, 4) xywh.
        samples: integration grid per side (``region_overlaps``).
    Returns:
        (N, M) float64.
    """
    return 0.5 * region_overlaps(a, b, samples=samples)


def occlusion_pairs(boxes: np.ndarray, owners: np.ndarray, lam: float,
                    ratio: np.ndarray | None = None, samples: int = 24) -> np.ndarray:
    """Occlusion relation O of eq. 2 over predicted regions of nodes.

    O = {(n_i, n_j) | id_i != id_j, |S_i & S_j| / (|S_i| + |S_j|) > lambda}.

    Args:
        boxes: (N, 4) xywh predicted regions S^{t|t-1} of the nodes.
        owners: (N,) person key of each node (hypotheses of one person never occlude
            each other).
        lam: overlap threshold lambda in [0, 0.5).
        ratio: optional precomputed (N, N) ``overlap_ratio(boxes, boxes)`` (only its
            entries i < j are read); else only pairs of different people with
            intersecting boxes are integrated.
        samples: integration grid per side (``region_overlaps``).
    Returns:
        (K, 2) int rows (i, j) with i < j, node indices into ``boxes``.
    """
    n = len(boxes)
    if n < 2:
        return np.zeros((0, 2), dtype=int)
    owners = np.asarray(owners)
    k = np.arange(n)
    cand = (owners[:, None] != owners[None, :]) & (k[:, None] < k[None, :])
    if ratio is None:
        # only pairs of different people whose bounding boxes meet can overlap
        cand &= boxes_meet(boxes, boxes)
        ratio = 0.5 * region_overlaps(boxes, boxes, samples, near=cand)
    i, j = np.nonzero((ratio > lam) & cand)
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


def covered_fraction(boxes: np.ndarray, visible: np.ndarray, samples: int = 24,
                     pairs: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """(N,) largest fraction |S_i & S_v| / |S_i| of each region S_i hidden by one visible
    region S_v (from eq. 5: |S_i & S_v| = delta (|S_i| + |S_v|) / 2), integrated over the
    pairs whose boxes meet only (memory grows with them).

    Args:
        boxes: (N, 4) xywh regions S_i; visible: (M, 4) xywh regions S_v.
        samples: integration grid per side (``region_overlaps``).
        pairs: optional (ia, ib) index arrays restricting the visible regions each S_i is
            compared with (default: all).
    """
    out = np.zeros(len(boxes))
    if len(boxes) == 0 or len(visible) == 0:
        return out
    if pairs is None:
        ia, ib = meeting_pairs(boxes, visible)
    else:
        ia, ib = (np.asarray(k, dtype=np.int64) for k in pairs)
    shares.covered(np.ascontiguousarray(boxes, dtype=np.float64),
                   np.ascontiguousarray(visible, dtype=np.float64), ia, ib, pairs is not None,
                   _grid(samples), out)  # the pairs whose boxes meet, compiled
    return out


def union_cover(boxes: np.ndarray, others: np.ndarray, samples: int = 12) -> np.ndarray:
    """(N,) share of each box's inscribed ellipse lying inside the union of the ellipses of
    (M, 4) xywh ``others``, integrated on a ``samples`` x ``samples`` grid over the box."""
    t = (np.arange(samples) + 0.5) / samples
    out = np.zeros(len(boxes))
    for k, (x, y, w, h) in enumerate(np.asarray(boxes, dtype=np.float64).tolist()):
        px, py = np.meshgrid(x + t * w, y + t * h)
        inside = ((px - x - w / 2) / (w / 2)) ** 2 + ((py - y - h / 2) / (h / 2)) ** 2 <= 1.0
        px, py = px[inside], py[inside]
        hit = np.zeros(len(px), dtype=bool)
        for ox, oy, ow, oh in np.asarray(others, dtype=np.float64).tolist():
            if ox >= x + w or ox + ow <= x or oy >= y + h or oy + oh <= y:
                continue
            hit |= ((px - ox - ow / 2) / (ow / 2)) ** 2 + ((py - oy - oh / 2) / (oh / 2)) ** 2 <= 1.0
        out[k] = hit.mean() if len(hit) else 0.0
    return out
