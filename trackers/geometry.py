"""Boxes and ellipses, vectorised. All boxes are (N, 4) float64 xywh, 0-based pixels."""

from __future__ import annotations

import numpy as np


def xywh_to_xyxy(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) xywh -> (N, 4) x1 y1 x2 y2."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return np.concatenate([b[:, :2], b[:, :2] + b[:, 2:]], axis=1)


def xyxy_to_xywh(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) x1 y1 x2 y2 -> (N, 4) xywh."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return np.concatenate([b[:, :2], b[:, 2:] - b[:, :2]], axis=1)


def centres(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) xywh -> (N, 2) box centres (x, y)."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return b[:, :2] + 0.5 * b[:, 2:]


def intersection_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, M) intersection areas of xywh boxes ``a`` (N, 4) and ``b`` (M, 4)."""
    A, B = xywh_to_xyxy(a), xywh_to_xyxy(b)
    w = np.minimum(A[:, None, 2], B[None, :, 2]) - np.maximum(A[:, None, 0], B[None, :, 0])
    h = np.minimum(A[:, None, 3], B[None, :, 3]) - np.maximum(A[:, None, 1], B[None, :, 1])
    return np.clip(w, 0.0, None) * np.clip(h, 0.0, None)


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, M) intersection over union of xywh boxes; 0 where a union is empty."""
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 4)
    inter = intersection_matrix(a, b)
    area_a = a[:, 2] * a[:, 3]
    area_b = b[:, 2] * b[:, 3]
    union = area_a[:, None] + area_b[None, :] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        iou = np.where(union > 0, inter / union, 0.0)
    return iou


def overlap_ratio_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, M) fraction of each box of ``a`` covered by each box of ``b``: |a & b| / |a|."""
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4)
    inter = intersection_matrix(a, b)
    area_a = a[:, 2] * a[:, 3]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(area_a[:, None] > 0, inter / area_a[:, None], 0.0)


def centre_distance_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, M) Euclidean distances between the centres of xywh boxes."""
    ca, cb = centres(a), centres(b)
    return np.linalg.norm(ca[:, None, :] - cb[None, :, :], axis=2)


def clip_boxes(boxes: np.ndarray, width: int, height: int) -> np.ndarray:
    """Clip xywh boxes to the image [0, width) x [0, height); sizes may become 0."""
    b = xywh_to_xyxy(boxes)
    b[:, [0, 2]] = np.clip(b[:, [0, 2]], 0, width)
    b[:, [1, 3]] = np.clip(b[:, [1, 3]], 0, height)
    return xyxy_to_xywh(b)


def valid_boxes(boxes: np.ndarray) -> np.ndarray:
    """(N,) bool: finite coordinates and positive width and height."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return np.isfinite(b).all(axis=1) & (b[:, 2] > 0) & (b[:, 3] > 0)


def box_ellipses(boxes: np.ndarray) -> np.ndarray:
    """Ellipse shape S = (xc, yc, phi, rx, ry) inscribed in each box (Reta 3.2).

    Args:
        boxes: (N, 4) xywh.
    Returns:
        (N, 5) float64: centre, orientation phi (radians, 0 = axis-aligned), semi-axes.
    """
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    c = centres(b)
    return np.column_stack([c, np.zeros(len(b)), 0.5 * b[:, 2], 0.5 * b[:, 3]])


def ellipse_boxes(ellipses: np.ndarray) -> np.ndarray:
    """(N, 5) ellipses (xc, yc, phi, rx, ry) -> (N, 4) xywh bounding boxes."""
    e = np.asarray(ellipses, dtype=np.float64).reshape(-1, 5)
    cos, sin = np.cos(e[:, 2]), np.sin(e[:, 2])
    hw = np.sqrt((e[:, 3] * cos) ** 2 + (e[:, 4] * sin) ** 2)
    hh = np.sqrt((e[:, 3] * sin) ** 2 + (e[:, 4] * cos) ** 2)
    return np.column_stack([e[:, 0] - hw, e[:, 1] - hh, 2 * hw, 2 * hh])


def ellipse_mask(ellipse: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Boolean (H, W) mask of the pixels inside one ellipse (xc, yc, phi, rx, ry).

    Pixel (r, c) is inside when its centre (c + 0.5, r + 0.5) lies in the ellipse. Only
    the ellipse's bounding box is evaluated.
    """
    xc, yc, phi, rx, ry = (float(v) for v in ellipse)
    h, w = shape
    mask = np.zeros((h, w), dtype=bool)
    rx, ry = max(rx, 0.5), max(ry, 0.5)
    x0, y0, bw, bh = ellipse_boxes(np.array([[xc, yc, phi, rx, ry]]))[0]
    c0, c1 = max(int(np.floor(x0)), 0), min(int(np.ceil(x0 + bw)), w)
    r0, r1 = max(int(np.floor(y0)), 0), min(int(np.ceil(y0 + bh)), h)
    if c1 <= c0 or r1 <= r0:
        return mask
    xs = np.arange(c0, c1) + 0.5 - xc
    ys = np.arange(r0, r1) + 0.5 - yc
    cos, sin = np.cos(phi), np.sin(phi)
    u = xs[None, :] * cos + ys[:, None] * sin
    v = -xs[None, :] * sin + ys[:, None] * cos
    mask[r0:r1, c0:c1] = (u / rx) ** 2 + (v / ry) ** 2 <= 1.0
    return mask


def box_slices(box: np.ndarray, shape: tuple[int, int]) -> tuple[slice, slice]:
    """Row and column slices of the pixels a xywh box covers, clipped to an (H, W) image."""
    h, w = shape
    x, y, bw, bh = (float(v) for v in box)
    c0, c1 = max(int(np.floor(x)), 0), min(int(np.ceil(x + bw)), w)
    r0, r1 = max(int(np.floor(y)), 0), min(int(np.ceil(y + bh)), h)
    return slice(r0, max(r1, r0)), slice(c0, max(c1, c0))
