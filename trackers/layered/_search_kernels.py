"""Compiled kernels of ``occbench.trackers.layered.search`` (numba, one core), kept where
``benchmarks/bench_pbm.py`` shows their numpy forms cost the tracker's speed: the head
bands of the detection boxes (``band_heads``, PBM 3.1, tested against
``cv2.boundingRect`` of each band) and the foreground the detection boxes cover
(``covered_count``, PBM 2, tested against ``geometry.box_slices``) and the occlusion test
of every (target, candidate) pair (``occlusion_kinds_into``, PBM 3.1, tested against its
numpy arrays). None calls a kernel of another file.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def band_bounds(fg: np.ndarray, r0: int, r1: int, c0: int, c1: int) -> tuple[int, int, int]:
    """Bounding rectangle of the True pixels of ``fg[r0:r1, c0:c1]`` as (first column,
    first row, width), relative to (c0, r0); width 0 when there are none
    (``cv2.boundingRect``'s x, y, w). Each row is scanned only outside the columns
    already known to hold foreground."""
    first_r, lo, hi = -1, c1, c0 - 1
    for r in range(r0, r1):
        row = fg[r]
        c = c0
        while c < lo and not row[c]:
            c += 1
        if c < lo:
            lo = c
            if first_r < 0:
                first_r = r - r0
        c = c1 - 1
        while c > hi and not row[c]:
            c -= 1
        hi = max(hi, c)
    if first_r < 0:
        return 0, 0, 0
    return lo - c0, first_r, hi + 1 - lo


@numba.njit(cache=True)
def band_heads(fg: np.ndarray, boxes: np.ndarray, fraction: float) -> np.ndarray:
    """``search.head_from_band`` of N xywh boxes at once: (N, 3) float64 heads."""
    H, W = fg.shape
    out = np.empty((boxes.shape[0], 3))
    for i in range(boxes.shape[0]):
        x, y, w, h = boxes[i, 0], boxes[i, 1], boxes[i, 2], boxes[i, 3]
        out[i, 0], out[i, 1], out[i, 2] = x + 0.5 * w, y, 0.5 * w
        if not (np.isfinite(x) and np.isfinite(y) and np.isfinite(w) and np.isfinite(h)):
            continue
        r0, r1 = max(int(y), 0), min(int(np.ceil(y + fraction * h)) + 1, H)
        c0, c1 = max(int(x), 0), min(int(np.ceil(x + w)), W)
        if r1 > r0 and c1 > c0:
            bx, by, bw = band_bounds(fg, r0, r1, c0, c1)
            if bw > 0:
                out[i, 0], out[i, 1], out[i, 2] = c0 + 0.5 * (2 * bx + bw), r0 + by, max(bw, 1)
    return out


@numba.njit(cache=True, inline="always")
def _box_spans(boxes: np.ndarray, H: int, W: int) -> np.ndarray:
    """(N, 4) int64 (r0, r1, c0, c1) half-open pixel spans of N xywh boxes in an H x W
    image (``geometry.box_slices``: floor of the top-left, ceil of the bottom-right,
    clipped); a non-finite box gets an empty span."""
    n = boxes.shape[0]
    spans = np.zeros((n, 4), np.int64)
    for k in range(n):
        x, y, w, h = boxes[k, 0], boxes[k, 1], boxes[k, 2], boxes[k, 3]
        if not (np.isfinite(x) and np.isfinite(y) and np.isfinite(x + w) and np.isfinite(y + h)):
            continue  # covers nothing
        c0, c1 = min(max(np.floor(x), 0.0), W), min(np.ceil(x + w), W)
        r0, r1 = min(max(np.floor(y), 0.0), H), min(np.ceil(y + h), H)
        spans[k, 0], spans[k, 1] = int(r0), int(max(r1, r0))
        spans[k, 2], spans[k, 3] = int(c0), int(max(c1, c0))
    return spans


@numba.njit(cache=True, inline="always")
def _covered_in_row(row: np.ndarray, r: int, spans: np.ndarray, starts: np.ndarray,
                    ends: np.ndarray) -> int:
    """Nonzero entries of image row ``row`` (row r) inside the union of the ``spans``
    (``_box_spans``); scratch starts, ends (N,)."""
    # column intervals of the spans covering row r, sorted by start, then merged
    m = 0
    for k in range(spans.shape[0]):
        if spans[k, 0] <= r < spans[k, 1] and spans[k, 3] > spans[k, 2]:
            j = m
            while j > 0 and starts[j - 1] > spans[k, 2]:
                starts[j], ends[j] = starts[j - 1], ends[j - 1]
                j -= 1
            starts[j], ends[j] = spans[k, 2], spans[k, 3]
            m += 1
    total = 0
    k = 0
    while k < m:
        a, b = starts[k], ends[k]
        k += 1
        while k < m and starts[k] <= b:
            b = max(b, ends[k])
            k += 1
        seg = row[a:b]
        for c in range(b - a):
            total += np.int64(seg[c] != 0)
    return total


@numba.njit(cache=True, inline="always")
def _span_rows(spans: np.ndarray, H: int) -> tuple[int, int]:
    """The rows [rmin, rmax) that the non-empty spans cover (rmin >= rmax: none)."""
    rmin, rmax = H, 0
    for k in range(spans.shape[0]):
        if spans[k, 3] > spans[k, 2]:
            rmin, rmax = min(rmin, spans[k, 0]), max(rmax, spans[k, 1])
    return rmin, rmax


@numba.njit(cache=True)
def covered_count(fg: np.ndarray, boxes: np.ndarray) -> int:
    """Number of nonzero pixels of a uint8 mask inside the union of N xywh boxes, each
    covering the pixels of ``geometry.box_slices`` (floor of the top-left, ceil of the
    bottom-right, clipped to the image); a non-finite box covers nothing."""
    H, W = fg.shape
    spans = _box_spans(boxes, H, W)
    starts, ends = np.empty(boxes.shape[0], np.int64), np.empty(boxes.shape[0], np.int64)
    rmin, rmax = _span_rows(spans, H)
    total = 0
    for r in range(rmin, rmax):
        total += _covered_in_row(fg[r], r, spans, starts, ends)
    return total


@numba.njit(cache=True)
def occlusion_kinds_into(region_wh: np.ndarray, predicted_wh: np.ndarray, threshold: float,
                         out: np.ndarray) -> None:
    """PBM 3.1's occlusion test (``search.occlusion_kinds``) of N regions (N, 2) against T
    predictions (T, 2) into out (T, N) int64: +1 when (region - prediction) / max(prediction,
    1) of the width or the height is above ``threshold``, else -1 when one is below
    -threshold, else 0 (the same operations as numpy's elementwise arrays; a NaN is 0)."""
    for t in range(predicted_wh.shape[0]):
        w, h = predicted_wh[t, 0], predicted_wh[t, 1]
        nw = w if (w >= 1.0 or w != w) else 1.0  # np.maximum(w, 1.0)
        nh = h if (h >= 1.0 or h != h) else 1.0
        for n in range(region_wh.shape[0]):
            dw, dh = (region_wh[n, 0] - w) / nw, (region_wh[n, 1] - h) / nh
            if dw > threshold or dh > threshold:
                out[t, n] = 1
            elif dw < -threshold or dh < -threshold:
                out[t, n] = -1
            else:
                out[t, n] = 0
