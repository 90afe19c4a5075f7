"""Appearance and shape similarity of detections (Reta 3.2 eq. 1, 3.3.2 eqs. 4 and 5).

All boxes are (N, 4) float64 xywh in 0-based pixels. The person region S of a box is the
ellipse inscribed in it (``occbench.trackers.geometry.box_ellipses``).
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.geometry import box_slices, intersection_matrix
from occbench.trackers.histograms import bhattacharyya

__all__ = ["bhattacharyya", "bin_image", "ellipse_histograms", "region_similarity"]


def bin_image(frame: np.ndarray, bins: int = 16) -> np.ndarray:
    """(H, W) int32 joint-bin index of every pixel of an (H, W, 3) uint8 frame.

    The index is ``(c0 * bins + c1) * bins + c2`` with ``ck = channel_k * bins // 256``, the
    same order as ``occbench.trackers.histograms.colour_histogram`` (for a BGR frame: B major). The
    bins partition the RGB cube, so the channel order does not change rho.
    """
    if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
        raise ValueError(f"bin_image: expected (H, W, 3) uint8, got {frame.shape} {frame.dtype}")
    if 256 % bins:
        raise ValueError(f"bin_image: bins must divide 256, got {bins}")
    q = (frame // np.uint8(256 // bins)).astype(np.int32)
    return (q[..., 0] * bins + q[..., 1]) * bins + q[..., 2]


def _ellipse_in_box(box: np.ndarray, rows: slice, cols: slice) -> np.ndarray:
    """Bool mask over the pixels ``[rows, cols]`` whose centres lie in the box's ellipse."""
    x, y, w, h = box
    xc, yc, rx, ry = x + w / 2, y + h / 2, max(w / 2, 0.5), max(h / 2, 0.5)
    xs = (np.arange(cols.start, cols.stop) + 0.5 - xc) / rx
    ys = (np.arange(rows.start, rows.stop) + 0.5 - yc) / ry
    return ys[:, None] ** 2 + xs[None, :] ** 2 <= 1.0


def ellipse_histograms(
    frame: np.ndarray,
    boxes: np.ndarray,
    mask: np.ndarray | None = None,
    bins: int = 16,
    binned: np.ndarray | None = None,
) -> np.ndarray:
    """Colour histograms over the ellipse of each box (Reta eq. 1: 16x16x16 RGB bins).

    Args:
        frame: (H, W, 3) uint8 image.
        boxes: (N, 4) xywh.
        mask: optional (H, W) bool mask or label image (nonzero = counted): only the
            ellipse pixels that are also foreground are counted.
        bins: bins per channel.
        binned: optional precomputed ``bin_image(frame, bins)`` (reuse it across calls).
    Returns:
        (N, bins**3) float64, each row summing to 1 (all zero where no pixel is counted).
    """
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    idx = bin_image(frame, bins) if binned is None else binned
    out = np.zeros((len(boxes), bins**3), dtype=np.float64)
    shape = idx.shape
    for i, box in enumerate(boxes):  # loop over detections, not pixels
        rows, cols = box_slices(box, shape)
        if rows.stop <= rows.start or cols.stop <= cols.start:
            continue
        inside = _ellipse_in_box(box, rows, cols)
        if mask is not None:
            inside &= np.asarray(mask[rows, cols]) != 0
        counts = np.bincount(idx[rows, cols][inside], minlength=bins**3)
        n = counts.sum()
        if n:
            out[i] = counts / n
    return out


def region_similarity(
    a: np.ndarray, b: np.ndarray, region: str = "ellipse", samples: int = 24
) -> np.ndarray:
    """Region similarity delta (Reta eq. 5) of every pair of regions.

    delta(Sp, Sq) = 1 - (|Sp & ~Sq| + |Sq & ~Sp|) / (|Sp| + |Sq|) = 2 |Sp & Sq| / (|Sp| + |Sq|):
    1 for identical regions, 0 for disjoint ones.

    Args:
        a: (N, 4) xywh; b: (M, 4) xywh.
        region: "ellipse" (the inscribed ellipse, Reta 3.2) or "box".
        samples: grid points per side used to integrate ellipse intersections (the error
            of |Sp & Sq| is about one grid cell of the smaller ellipse per boundary cell).
    Returns:
        (N, M) float64 in [0, 1].
    """
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 4)
    if region not in ("ellipse", "box"):
        raise ValueError(f"region must be 'ellipse' or 'box', got {region!r}")
    if region == "box":
        inter = intersection_matrix(a, b)
        total = (a[:, 2] * a[:, 3])[:, None] + (b[:, 2] * b[:, 3])[None, :]
    else:
        inter = np.zeros((len(a), len(b)))
        total = np.pi / 4 * ((a[:, 2] * a[:, 3])[:, None] + (b[:, 2] * b[:, 3])[None, :])
        near = intersection_matrix(a, b) > 0
        if near.any():
            # integrate over a grid on each a-ellipse's bounding box: (N, S*S) points
            t = (np.arange(samples) + 0.5) / samples
            gx = a[:, 0, None, None] + a[:, 2, None, None] * t[None, None, :]
            gy = a[:, 1, None, None] + a[:, 3, None, None] * t[None, :, None]
            gx = np.broadcast_to(gx, (len(a), samples, samples)).reshape(len(a), -1)
            gy = np.broadcast_to(gy, (len(a), samples, samples)).reshape(len(a), -1)

            def inside(px, py, boxes):  # px, py (K, P), boxes (K, 4) -> (K, P)
                rx = np.maximum(boxes[:, 2:3] / 2, 1e-9)
                ry = np.maximum(boxes[:, 3:4] / 2, 1e-9)
                u = (px - boxes[:, 0:1] - rx) / rx
                v = (py - boxes[:, 1:2] - ry) / ry
                return u**2 + v**2 <= 1.0

            ia, ib = np.nonzero(near)
            in_a = inside(gx[ia], gy[ia], a[ia])  # (K, P)
            in_b = inside(gx[ia], gy[ia], b[ib])
            # fraction of Sa's grid points inside Sb, times the exact |Sa| = pi/4 w h
            frac = (in_a & in_b).sum(axis=1) / np.maximum(in_a.sum(axis=1), 1)
            inter[ia, ib] = frac * np.pi / 4 * a[ia, 2] * a[ia, 3]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.clip(np.where(total > 0, 2 * inter / total, 0.0), 0.0, 1.0)
