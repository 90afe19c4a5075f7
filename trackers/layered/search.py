"""Candidates, heads, occlusion test, head-anchored search and alignment (PBM 2.1, 3.1, 4.1).

A *candidate* (a row of ``Candidates``) is one head in one candidate region: a detection box with its
head, or a head found on a foreground blob. Heads come from ``Detections.heads`` when the
source gives them; otherwise from the foreground itself: the peaks of a blob's top
profile (the topmost foreground row of each column), the visible tops of heads that PBM
3.1 relies on ("the tops of the heads are visible most of the time"). A blob holding two
people side by side has two peaks, so each is located by its own head.

Occlusion test (PBM 3.1): a candidate region whose width or height differs from the
target's predicted size by more than ``occlusion_threshold`` (50%) is occluded:
- larger (merged) region: boxes of sizes w (1 + delta i), h (1 + delta i), i = -search_range
  .. search_range (eqs. 9-10; delta is relative to the predicted size) hang from the head
  top inside the region; the best-scoring one is the candidate's global model;
- smaller region: the predicted-size box is aligned on the head; when the head is not
  supported by foreground the candidate is dismissed.

When a target has several close candidates with similar scores, ``match_head_template``
refines the head by normalised cross-correlation of the target's head template in a local
neighbourhood (multiple-response pruning, PBM 4.1).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import cv2
import numpy as np

from occbench.trackers.layered._search_kernels import (
    band_heads,
    covered_count,
    occlusion_kinds_into,
)
from occbench.trackers.layered._template_kernels import best_ccoeff_normed
from occbench.trackers.layered.split import HEAD_FRACTION
from scipy.ndimage import minimum_filter1d


def _floats(v: np.ndarray) -> list[float]:
    """The values of a small array as Python floats (cheaper scalar arithmetic)."""
    return np.asarray(v, dtype=np.float64).tolist()


@dataclass
class Candidates:
    """The frame's candidates, one row each: a head in a region (PBM 2, 3.1).

    Attributes:
        box: (N, 4) xywh own boxes (the detection, the blob, or the blob's slice for the head).
        region: (N, 4) xywh candidate regions the occlusion test compares (detection or blob).
        head: (N, 3) head top-centre x, top y, head width (pixels).
        blob: (N,) bool, the candidate is a head of a foreground blob (else a detection).
        heads_in_region: (N,) int, number of heads found in the region.
        centroid: (N, 2) foreground centroids of the boxes (their centres without
            foreground); None until the tracker measures all candidates at once.
        held: (N,) int, detections lying in a blob's region besides its heads
            (``candidates.HeldDetections``); None: none.
    """

    box: np.ndarray
    region: np.ndarray
    head: np.ndarray
    blob: np.ndarray
    heads_in_region: np.ndarray
    centroid: np.ndarray | None = None
    held: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.box)

    def take(self, rows: np.ndarray) -> Candidates:
        """The candidates at ``rows`` (copies), in that order."""
        return Candidates(*(None if v is None else v[rows] for v in (
            self.box, self.region, self.head, self.blob, self.heads_in_region, self.centroid,
            self.held)))


def blobs_boxes(fg: np.ndarray, min_area: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Connected components of a bool mask (PBM 2).

    Labels are 16-bit when the mask cannot hold 65,535 components (8-connected blobs are
    at least 2 pixels apart): OpenCV's 16-bit path is the same labelling, and faster.

    Returns:
        labels (H, W) uint16 or int32, boxes (K, 4) xywh float64, label numbers (K,) of the
        blobs with at least ``min_area`` pixels.
    """
    h, w = fg.shape
    ltype = cv2.CV_16U if ((h + 1) // 2) * ((w + 1) // 2) < 65535 else cv2.CV_32S
    _, labels, stats, _ = cv2.connectedComponentsWithStats(fg.view(np.uint8), connectivity=8,
                                                           ltype=ltype)
    keep = np.nonzero(stats[1:, cv2.CC_STAT_AREA] >= min_area)[0] + 1
    boxes = stats[keep, :4].astype(np.float64)
    return labels, boxes, keep


def top_profile_heads(mask: np.ndarray, min_separation: float, min_prominence: float) -> np.ndarray:
    """Heads of a blob crop as the peaks of its top profile (PBM 3.1: "the tops of the
    heads are visible most of the time").

    The top profile is the first foreground row of each column; a peak is a run of
    columns equal to the running minimum over 2 max(min_separation // 2, 1) + 1 columns
    (a grey erosion, edges replicated) whose profile drops by ``min_prominence`` rows on
    both sides within ``2 * min_separation`` columns (or reaches the crop edge); without
    any, the highest column. Peaks closer than ``min_separation`` to a higher one are
    suppressed.

    Args:
        mask: (h, w) bool crop of one blob.
        min_separation: smallest horizontal distance between two heads (pixels).
        min_prominence: rows the profile must drop on both sides of a peak (or reach the
            crop edge) within ``2 * min_separation`` columns.
    Returns:
        (K, 2) float64 (column centre, top row) in crop coordinates, highest head first.
    """
    h, w = mask.shape
    has = mask.any(axis=0)
    if not has.any():
        return np.zeros((0, 2))
    top = np.where(has, mask.argmax(axis=0), h).astype(np.float64)  # the top profile
    erosion = minimum_filter1d(top, size=2 * max(int(min_separation // 2), 1) + 1, mode="nearest")
    cols = np.flatnonzero((top == erosion) & has)
    span = int(2 * min_separation)
    peaks = []
    for run in np.split(cols, np.flatnonzero(np.diff(cols) > 1) + 1):  # runs share one top row
        c0, c1 = int(run[0]), int(run[-1])
        t = top[c0]
        left, right = top[max(c0 - span, 0):c0], top[c1 + 1:min(c1 + span + 1, w)]
        ok_left = c0 - span <= 0 or (len(left) > 0 and left.max() - t >= min_prominence)
        ok_right = c1 + span >= w - 1 or (len(right) > 0 and right.max() - t >= min_prominence)
        if ok_left and ok_right:
            peaks.append((0.5 * (c0 + c1), t))
    if not peaks:  # the highest column
        best = int(np.argmin(top))
        peaks = [(float(best), top[best])]
    peaks.sort(key=lambda p: p[1])  # highest first, column order on ties
    kept: list[tuple[float, float]] = []
    for p in peaks:  # non-maximum suppression
        if all(abs(p[0] - q[0]) >= min_separation for q in kept):
            kept.append(p)
    return np.array(kept, dtype=np.float64).reshape(-1, 2)


def head_from_band(fg: np.ndarray | None, box: np.ndarray) -> np.ndarray:
    """(3,) head (x top-centre, y top, width) of a box: the top 1/7 band's foreground
    (PBM 3.1).

    Without foreground (or with none in the band) the band's centre.
    """
    x, y, w, h = _floats(box)
    if fg is not None:
        H, W = fg.shape
        r0, r1 = max(int(y), 0), min(math.ceil(y + HEAD_FRACTION * h) + 1, H)
        c0, c1 = max(int(x), 0), min(math.ceil(x + w), W)
        if r1 > r0 and c1 > c0:
            band = fg[r0:r1, c0:c1]
            cols = np.flatnonzero(band.any(axis=0))  # the band's foreground columns
            if len(cols):
                top = int(np.flatnonzero(band.any(axis=1))[0])
                return np.array([c0 + 0.5 * (cols[0] + cols[-1] + 1), r0 + top,
                                 max(cols[-1] + 1 - cols[0], 1)], dtype=np.float64)
    return np.array([x + 0.5 * w, y, 0.5 * w])


def heads_from_bands(fg: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """``head_from_band`` of N xywh boxes at once (PBM 3.1): (N, 3) float64 heads
    (x top-centre, y top, width); a non-finite box gets its band centre (non-finite).
    Compiled (``_search_kernels.band_heads``, tested against ``head_from_band``).

    Args:
        fg: (H, W) bool foreground. boxes: (N, 4) xywh.
    """
    return band_heads(np.ascontiguousarray(fg, dtype=np.bool_),
                      np.asarray(boxes, dtype=np.float64).reshape(-1, 4), float(HEAD_FRACTION))


def residual_foreground(fg: np.ndarray, boxes: np.ndarray, total: int | None = None) -> int:
    """Number of foreground pixels that no box covers (PBM 2: blobs matter only where the
    detections leave foreground unexplained); a box covers the pixels of
    ``geometry.box_slices`` (floor of its top-left, ceil of its bottom-right, clipped).

    Args:
        fg: (H, W) bool foreground. boxes: (N, 4) xywh (a non-finite box covers nothing).
        total: ``np.count_nonzero(fg)`` when already known.
    """
    fg = np.ascontiguousarray(fg, dtype=np.bool_)
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    if total is None:
        total = np.count_nonzero(fg)
    return total - int(covered_count(fg.view(np.uint8), boxes))


def region_centroid(fg: np.ndarray | None, box: np.ndarray) -> np.ndarray:
    """(2,) foreground centroid inside a box (the box centre without foreground)."""
    x, y, w, h = box
    if fg is not None:
        H, W = fg.shape
        r0, r1 = max(round(y), 0), min(round(y + h), H)
        c0, c1 = max(round(x), 0), min(round(x + w), W)
        if r1 > r0 and c1 > c0:
            crop = fg[r0:r1, c0:c1]
            n = crop.sum()
            if n > 0:
                cy = (crop.sum(axis=1) @ np.arange(r0, r1)) / n + 0.5
                cx = (crop.sum(axis=0) @ np.arange(c0, c1)) / n + 0.5
                return np.array([cx, cy])
    return np.array([x + 0.5 * w, y + 0.5 * h])


def split_blob_box(mask: np.ndarray, offset: np.ndarray, heads_x: np.ndarray, k: int) -> np.ndarray:
    """(4,) xywh slice of a merged blob that belongs to head k (PBM 3.1).

    Columns are split half-way between neighbouring heads; rows run from the head's top to
    the lowest foreground pixel in those columns.
    """
    h, w = mask.shape
    order = sorted(float(v) for v in heads_x)
    xk = float(heads_x[k])
    i = bisect.bisect_left(order, xk)
    lo = 0 if i == 0 else round(0.5 * (order[i - 1] + xk))
    hi = w if i == len(order) - 1 else round(0.5 * (order[i + 1] + xk))
    ox, oy = float(offset[0]), float(offset[1])
    part = mask[:, lo:max(hi, lo)]
    rows = np.flatnonzero(part.any(axis=1))
    if len(rows) == 0:
        return np.array([ox + lo, oy, max(hi - lo, 1), h], dtype=np.float64)
    cols = np.flatnonzero(part.any(axis=0))
    return np.array([ox + lo + cols[0], oy + rows[0], cols[-1] + 1 - cols[0], rows[-1] + 1 - rows[0]],
                    dtype=np.float64)


def occlusion_kind(region_wh: np.ndarray, predicted_wh: np.ndarray, threshold: float) -> int:
    """PBM 3.1 occlusion test of one region against one target (``occlusion_kinds``):
    0 unoccluded, +1 larger region, -1 smaller region."""
    return int(occlusion_kinds(region_wh, predicted_wh, threshold)[0, 0])


def occlusion_kinds(region_wh: np.ndarray, predicted_wh: np.ndarray, threshold: float) -> np.ndarray:
    """PBM 3.1 occlusion test of N candidate regions against T targets: (T, N) int64,
    0 unoccluded, +1 larger region, -1 smaller region.

    Occluded when |w_c - w| / w or |h_c - h| / h exceeds ``threshold`` (w, h floored at
    1 pixel); larger when either dimension grew beyond it, else smaller.

    Args:
        region_wh: (N, 2) candidate region sizes. predicted_wh: (T, 2) KF2 predictions.
    """
    region_wh = np.asarray(region_wh, dtype=np.float64).reshape(-1, 2)
    predicted_wh = np.asarray(predicted_wh, dtype=np.float64).reshape(-1, 2)
    out = np.empty((len(predicted_wh), len(region_wh)), dtype=np.int64)
    occlusion_kinds_into(region_wh, predicted_wh, float(threshold), out)
    return out


def search_boxes(head: np.ndarray, predicted_wh: np.ndarray, alpha: float, step: float,
                 search_range: int) -> np.ndarray:
    """Eqs. 9-10, the head-anchored boxes: ((2 r + 1)^2, 4) xywh, box i (2 r + 1) + k of
    width w_i and height h_k.

    w_i = w (1 + step i), h_k = h (1 + step k), i, k = -r..r (the paper's delta = 0.05 is
    taken relative to the predicted size); each box hangs from the head top (y = head
    top) with its centroid column on the head (x = head x - alpha w_i, eq. 1).
    """
    i = np.arange(-search_range, search_range + 1, dtype=np.float64)
    ws = predicted_wh[0] * (1.0 + step * i)                                  # eq. 9
    hs = predicted_wh[1] * (1.0 + step * i)                                  # eq. 10
    W, Hh = np.meshgrid(ws, hs, indexing="ij")
    W, Hh = W.ravel(), Hh.ravel()
    return np.column_stack([head[0] - alpha * W, np.full_like(W, head[1]), W, Hh])


def search_boxes_many(heads: np.ndarray, predicted_wh: np.ndarray, alpha: np.ndarray,
                      step: float, search_range: int) -> np.ndarray:
    """``search_boxes`` (eqs. 9-10) of S heads: (S, (2 r + 1)^2, 4) xywh, box
    i * (2 r + 1) + k of head s having width w_s (1 + step i) and height h_s (1 + step k).

    Args:
        heads: (S, 3) heads. predicted_wh: (S, 2) KF2 sizes. alpha: (S,) eq. 1 ratios.
    """
    heads = np.asarray(heads, dtype=np.float64).reshape(-1, 3)
    predicted_wh = np.asarray(predicted_wh, dtype=np.float64).reshape(-1, 2)
    alpha = np.asarray(alpha, dtype=np.float64).reshape(-1)
    i = np.arange(-search_range, search_range + 1, dtype=np.float64)
    ws = predicted_wh[:, 0, None] * (1.0 + step * i)                        # eq. 9, (S, m)
    hs = predicted_wh[:, 1, None] * (1.0 + step * i)                        # eq. 10, (S, m)
    S, m = len(heads), len(i)
    out = np.empty((S, m, m, 4))  # [s, i, k]: width w_i, height h_k
    out[..., 0] = (heads[:, 0, None] - alpha[:, None] * ws)[:, :, None]  # centroid on the head (eq. 1)
    out[..., 1] = heads[:, 1, None, None]                                  # hanging from the head top
    out[..., 2] = ws[:, :, None]
    out[..., 3] = hs[:, None, :]
    return out.reshape(S, m * m, 4)


def aligned_box(head: np.ndarray, predicted_wh: np.ndarray, alpha: float) -> np.ndarray:
    """(4,) predicted-size box aligned on a head (PBM 3.1, smaller candidate)."""
    w, h = _floats(predicted_wh)
    hx, hy = _floats(head)[:2]
    return np.array([hx - float(alpha) * w, hy, w, h])


def head_fill(fg: np.ndarray | None, box: np.ndarray) -> float:
    """Foreground fraction of the head rectangle (top 1/7, middle half of the width) of a
    box; 1 without foreground (PBM 3.1: a smaller candidate's head must be supported)."""
    if fg is None:
        return 1.0
    x, y, w, h = _floats(box)
    H, W = fg.shape
    r0, r1 = max(round(y), 0), min(round(y + HEAD_FRACTION * h), H)
    c0, c1 = max(round(x + 0.25 * w), 0), min(round(x + 0.75 * w), W)
    if r1 <= r0 or c1 <= c0:
        return 0.0
    return np.count_nonzero(fg[r0:r1, c0:c1]) / ((r1 - r0) * (c1 - c0))


def grey_region(image: np.ndarray, r0: int, r1: int, c0: int, c1: int) -> np.ndarray:
    """(r1 - r0, c1 - c0) uint8 grey pixels of a region of a grey (H, W) or BGR (H, W, 3)
    image (a copy; a BGR region is converted alone, to the values of the whole frame's
    ``cv2.cvtColor(..., COLOR_BGR2GRAY)``)."""
    region = image[r0:r1, c0:c1]
    if region.ndim == 3:
        return cv2.cvtColor(region, cv2.COLOR_BGR2GRAY)
    return np.array(region, dtype=np.uint8)


def head_patch(image: np.ndarray, box: np.ndarray) -> np.ndarray | None:
    """Head template (PBM 4.1): the top 1/7 of a box (a copy, grey or BGR as ``image``),
    or None when it leaves the image. ``match_head_template`` takes either."""
    return head_patches(image, np.asarray(box, dtype=np.float64).reshape(1, 4))[0]


def head_patches(image: np.ndarray, boxes: np.ndarray) -> list[np.ndarray | None]:
    """``head_patch`` of N xywh boxes (N, 4): rows round(y) .. round(y + h / 7), columns
    round(x) .. round(x + w), None where that leaves the image or is under 3 pixels."""
    H, W = image.shape[:2]
    out: list[np.ndarray | None] = []
    for x, y, w, h in boxes.tolist():
        r0, r1 = round(y), round(y + HEAD_FRACTION * h)
        c0, c1 = round(x), round(x + w)
        if r0 < 0 or c0 < 0 or r1 > H or c1 > W or r1 - r0 < 3 or c1 - c0 < 3:
            out.append(None)
        else:
            out.append(image[r0:r1, c0:c1].copy())
    return out


def match_head_template(image: np.ndarray, template: np.ndarray, centre: np.ndarray,
                        radius: float) -> tuple[np.ndarray, float]:
    """Local template matching (PBM 4.1, multiple-response pruning: "an image template of
    the target's head is exhaustively matched in a local neighborhood").

    The search window holds the top-left positions within ``radius`` (a square) of
    ``centre``, clipped to the image; every position is scored by ``cv2.matchTemplate``
    (TM_CCOEFF_NORMED, zero-mean normalised correlation) and the best one (first in
    raster order on ties, ``cv2.minMaxLoc``) is returned (by
    ``_template_kernels.best_ccoeff_normed``, equal to OpenCV's bit for bit).

    Args:
        image: (H, W) uint8 grey or (H, W, 3) BGR frame (only the window is converted).
            template: (th, tw) grey or (th, tw, 3) BGR uint8 head patch (``head_patch``).
        centre: (2,) expected top-left corner (x, y) of the head patch (array or
            sequence). radius: search radius (pixels).
    Returns:
        best top-left corner (2,) float64 (x, y) and its normalised correlation (-1..1;
        -1 when the window cannot hold the template).
    """
    template = grey_region(template, 0, template.shape[0], 0, template.shape[1])
    window = search_window(image.shape, template.shape, centre, radius)
    if window is None:
        return np.asarray(centre, dtype=np.float64), -1.0
    r0, r1, c0, c1 = window
    bx, by, best = best_ccoeff_normed(grey_region(image, r0, r1, c0, c1), template)  # TM_CCOEFF_NORMED
    return np.array([c0 + bx, r0 + by], dtype=np.float64), float(best)


def search_window(shape: tuple, template_shape: tuple, centre, radius: float
                  ) -> tuple[int, int, int, int] | None:
    """``match_head_template``'s window (r0, r1, c0, c1) in an image of ``shape``: a
    template of ``template_shape`` (th, tw) placed at every top-left corner within
    ``radius`` (a square) of ``centre`` (x, y), clipped to the image; None when the clipped
    window cannot hold the template."""
    th, tw = template_shape[:2]
    H, W = shape[:2]
    r = math.ceil(radius)
    x0, y0 = round(float(centre[0])) - r, round(float(centre[1])) - r
    c0, r0 = max(x0, 0), max(y0, 0)
    c1, r1 = min(x0 + 2 * r + tw, W), min(y0 + 2 * r + th, H)
    if c1 - c0 < tw or r1 - r0 < th:
        return None
    return r0, r1, c0, c1
