"""Compiled kernels of ``PartFeatureExtractor`` (trackers.layered.parts, PBM 2.1-2.2).

A kernel call walks the sample grid of every box once and writes straight into the
output arrays, with no (N, R, C) intermediates. The grid, the part split, the outline
test and the order of every floating sum are those of the vectorised numpy version the
kernels replaced, so the features are equal to it bit for bit:

- sample row r of box i is ``ys = y + fr[r] * h`` (column: ``xs = x + fc[c] * w``), the
  pixel under it ``clip(floor(ys), 0, H - 1)``; a sample outside the image is background;
- the foreground centroid of a whole box sums ``count * coordinate`` per column (row) in
  numpy's pairwise order (``_pairwise_sum``, as ``ndarray.sum``);
- per-part centroid sums add the coordinates of the foreground samples one by one in
  row-major order (as ``np.bincount(weights=...)``);
- colour bins come from OpenCV's own 8-bit integer formulas for BGR -> HSV (hue 0..179)
  and BGR -> XYZ (``_hsv_xyz``), equal to ``cv2.cvtColor`` for all 2**24 colours (checked
  by tests/test_parts.py and, on a sample, once per process by the extractor).

Kernels are compiled on first use and cached on disk (``cache=True``); none recurses
(numba's cache mishandles recursive functions). In the per-sample loops, indices read
from arrays are cast to unsigned (``np.uint64``): numba then drops its negative-index
test, about a fifth of ``part_features``' time.
"""

from __future__ import annotations

import numba
import numpy as np

HEAD_FRACTION = 1.0 / 7.0
"""The head occupies one seventh of the person height (PBM 2.1; ``parts.HEAD_FRACTION``)."""


@numba.njit(cache=True, inline="always")
def _clip_index(v: float, n: int) -> int:
    """``clip(floor(v), 0, n - 1)`` as an index, for any float (NaN gives 0): the kernels
    never read outside the image, whatever the box."""
    if not v >= 0.0:  # negative or NaN
        return 0
    if v >= n - 1.0:  # also +inf and values beyond int64
        return n - 1
    return int(v)  # 0 <= v < n - 1: truncation is floor


@numba.njit(cache=True)
def _sample_grid(
    box: np.ndarray, fr: np.ndarray, fc: np.ndarray, H: int, W: int, fg: np.ndarray,
    has_fg: bool, ys: np.ndarray, xs: np.ndarray, yi: np.ndarray, xi: np.ndarray, on: np.ndarray,
) -> None:
    """Sample rows ``ys`` (R,) and columns ``xs`` (C,) of one xywh box, the pixel row
    ``yi`` / column ``xi`` under each (clipped into the image) and the foreground flag
    ``on`` (R, C) uint8 of each sample in an H x W image (outside = background; without
    a mask, ``has_fg`` false, every sample inside is foreground)."""
    R, C = fr.shape[0], fc.shape[0]
    for r in range(R):
        ys[r] = box[1] + fr[r] * box[3]
        yi[r] = _clip_index(ys[r], H)
    for c in range(C):
        xs[c] = box[0] + fc[c] * box[2]
        xi[c] = _clip_index(xs[c], W)
    for r in range(R):
        row_in = ys[r] >= 0.0 and ys[r] < H
        mrow = fg[np.uint64(yi[r])] if has_fg else fg[0]
        for c in range(C):
            inside = row_in and xs[c] >= 0.0 and xs[c] < W
            if inside and has_fg:
                inside = mrow[np.uint64(xi[c])]  # unsigned: no negative-index test
            on[r, c] = inside


HSV_SHIFT = 12
"""Fixed-point bits of OpenCV's 8-bit HSV and XYZ conversions (``hsv_shift``, ``xyz_shift``)."""
_S_DIV = np.concatenate([[0], np.rint((255 << HSV_SHIFT) / np.arange(1.0, 256.0))]).astype(np.int64)
"""``sdiv_table`` of OpenCV's RGB2HSV_b: round(255 * 2**12 / v) (saturate_cast rounds to even)."""
_H_DIV = np.concatenate([[0], np.rint((180 << HSV_SHIFT) / (6.0 * np.arange(1.0, 256.0)))]).astype(np.int64)
"""``hdiv_table180`` of RGB2HSV_b: round(180 * 2**12 / (6 * diff))."""
_XYZ = np.array([[739, 1465, 1689], [296, 2929, 871], [3892, 488, 79]], dtype=np.int64)
"""Rows X, Y, Z, columns B, G, R: OpenCV's ``sRGB2XYZ_D65_i`` (RGB2XYZ_i<uchar>), in BGR order."""


@numba.njit(cache=True, inline="always")
def _hsv_xyz(b: int, g: int, r: int) -> tuple[int, int, int, int, int, int]:
    """OpenCV's 8-bit HSV (hue 0..179) and XYZ of one BGR pixel, as ``cv2.cvtColor`` with
    COLOR_BGR2HSV (RGB2HSV_b: integer division by tables) and COLOR_BGR2XYZ (RGB2XYZ_i)."""
    v, vmin = max(b, g, r), min(b, g, r)
    diff = v - vmin
    half = 1 << (HSV_SHIFT - 1)
    s = (diff * _S_DIV[np.uint64(v)] + half) >> HSV_SHIFT  # unsigned: no negative-index test
    # the hue sector without branches (colours are noisy): OpenCV's vr, vg masks
    vr, vg = -np.int64(v == r), -np.int64(v == g)
    h = (vr & (g - b)) + (~vr & ((vg & (b - r + 2 * diff)) + (~vg & (r - g + 4 * diff))))
    h = (h * _H_DIV[np.uint64(diff)] + half) >> HSV_SHIFT
    h = min(h + (180 & -np.int64(h < 0)), 255)
    x = min((b * _XYZ[0, 0] + g * _XYZ[0, 1] + r * _XYZ[0, 2] + half) >> HSV_SHIFT, 255)
    y = min((b * _XYZ[1, 0] + g * _XYZ[1, 1] + r * _XYZ[1, 2] + half) >> HSV_SHIFT, 255)
    z = min((b * _XYZ[2, 0] + g * _XYZ[2, 1] + r * _XYZ[2, 2] + half) >> HSV_SHIFT, 255)
    return h, s, v, x, y, z


@numba.njit(cache=True)
def convert(pixels: np.ndarray, out: np.ndarray) -> None:
    """(M, 3) uint8 BGR pixels to (M, 6) uint8 H, S, V, X, Y, Z (``_hsv_xyz``)."""
    for m in range(pixels.shape[0]):
        out[m, 0], out[m, 1], out[m, 2], out[m, 3], out[m, 4], out[m, 5] = _hsv_xyz(
            np.int64(pixels[m, 0]), np.int64(pixels[m, 1]), np.int64(pixels[m, 2]))


PAIRWISE_BLOCK = 128
"""numpy sums up to this many items with 8 running sums; ``_pairwise_sum`` covers them."""


@numba.njit(cache=True)
def _pairwise_sum(a: np.ndarray, n: int) -> float:
    """Sum of ``a[:n]``, ``n <= PAIRWISE_BLOCK``, in numpy's order (``pairwise_sum`` of
    numpy/_core/src/umath/loops_utils.h): a plain loop below 8 items, else 8 running
    sums over whole blocks of 8, combined as a tree, then the rest added in turn."""
    if n < 8:
        s = 0.0
        for i in range(n):
            s += a[i]
        return s
    r0, r1, r2, r3, r4, r5, r6, r7 = a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]
    whole = n - n % 8
    for i in range(8, whole, 8):
        r0 += a[i]
        r1 += a[i + 1]
        r2 += a[i + 2]
        r3 += a[i + 3]
        r4 += a[i + 4]
        r5 += a[i + 5]
        r6 += a[i + 6]
        r7 += a[i + 7]
    s = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    for i in range(whole, n):
        s += a[i]
    return s


@numba.njit(cache=True)
def grid_centroid_terms(
    boxes: np.ndarray, fr: np.ndarray, fc: np.ndarray, H: int, W: int, fg: np.ndarray,
    has_fg: bool, count: np.ndarray, col_terms: np.ndarray, row_terms: np.ndarray,
) -> None:
    """Terms of the foreground centroid of each (N, 4) xywh box on its sample grid (PBM
    2.1): ``count`` (N,) foreground samples, ``col_terms`` (N, C) foreground samples of a
    column times its x, ``row_terms`` (N, R) those of a row times its y. The centroid is
    ``(col_terms.sum(1), row_terms.sum(1)) / count``, summed by numpy (pairwise order).

    ``fg`` is the (H, W) bool mask of the H x W frame (any placeholder when ``has_fg`` is
    false).
    """
    R, C = fr.shape[0], fc.shape[0]
    ys, xs = np.empty(R), np.empty(C)
    yi, xi = np.empty(R, np.int64), np.empty(C, np.int64)
    on = np.empty((R, C), np.uint8)
    for i in range(boxes.shape[0]):
        _sample_grid(boxes[i], fr, fc, H, W, fg, has_fg, ys, xs, yi, xi, on)
        n = 0
        col_terms[i, :] = 0.0
        for r in range(R):
            k = 0
            for c in range(C):
                if on[r, c]:
                    k += 1
                    col_terms[i, c] += 1.0
            n += k
            row_terms[i, r] = k * ys[r]
        for c in range(C):
            col_terms[i, c] *= xs[c]
        count[i] = n


@numba.njit(cache=True)
def part_features(
    boxes: np.ndarray, alpha: np.ndarray, beta: np.ndarray, at_centroids: bool,
    centres: np.ndarray, fr: np.ndarray, fc: np.ndarray,
    frame: np.ndarray, H: int, W: int, fg: np.ndarray, has_fg: bool,
    hsv_lut: np.ndarray, xyz_lut: np.ndarray,
    parts: np.ndarray, area: np.ndarray, perimeter: np.ndarray, hsv: np.ndarray,
    xyz: np.ndarray, centroid: np.ndarray,
) -> None:
    """Part rectangles and features of the five parts of each box (PBM 2.1-2.2).

    Args:
        boxes: (N, 4) xywh. alpha, beta: (N,) centroid ratios (eqs. 1-2); out when
            ``at_centroids``: the ratios (``centroid_ratios``) of the foreground centroids,
            written to ``centres`` (N, 2) (as ``PartFeatureExtractor.centroids``; needs
            R, C <= PAIRWISE_BLOCK).
        fr, fc: (R,), (C,) sample positions in [0, 1] along the height and width.
        frame: (H, W, 3) uint8 BGR. fg: (H, W) bool mask (any placeholder if not ``has_fg``).
        hsv_lut, xyz_lut: (3, 256) int64: channel c's value q (``_hsv_xyz``) adds
            ``lut[c, q] = min(q * bins // range_c, bins - 1) * bins ** (2 - c)`` to the
            joint bin (``parts._channel_luts``).
        parts: (N, 5, 4) out: ``part_boxes(boxes, alpha, beta)``, the same float operations.
        area, perimeter: (N, 5) out. hsv, xyz: (N, 5, B) out. centroid: (N, 5, 2) out.

    Part of a sample: the head band above ``y + h / 7``, torso-and-arm rows above the
    centroid row, legs below; left or right of the centroid column (PBM 2.1). A foreground
    sample is on the outline when a 4-neighbour is background or off the grid.
    """
    R, C = fr.shape[0], fc.shape[0]
    nb = hsv.shape[2]
    ys, xs = np.empty(R), np.empty(C)
    yi, xi = np.empty(R, np.int64), np.empty(C, np.int64)
    on = np.empty((R, C), np.uint8)
    col_terms, row_terms = np.empty(C), np.empty(R)
    sink = np.empty(1, np.int64)
    band = np.empty(R, np.int64)  # part of a sample of the row: 0 head, 1 torso, 3 legs (+1 right)
    right = np.empty(C, np.int64)  # 1 if the column is right of the split
    count, edge = np.zeros(5, np.int64), np.zeros(5, np.int64)
    coff = np.empty(C, np.uint64)  # byte offset of a sample column's pixel in its row
    pixels = frame.reshape(H * W * 3)
    one, two = np.uint64(1), np.uint64(2)
    sx, sy = np.zeros(5), np.zeros(5)
    count_hsv, count_xyz = np.zeros((5, nb), np.int64), np.zeros((5, nb), np.int64)
    for i in range(boxes.shape[0]):
        x, y, w, h = boxes[i, 0], boxes[i, 1], boxes[i, 2], boxes[i, 3]
        _sample_grid(boxes[i], fr, fc, H, W, fg, has_fg, ys, xs, yi, xi, on)
        if at_centroids:  # centroids (np.where(n > 0, sums / n, centre)) and their ratios
            n_fg = 0
            col_terms[:] = 0.0
            for r in range(R):
                k = 0
                for c in range(C):
                    k += on[r, c]
                    col_terms[c] += on[r, c]
                n_fg += k
                row_terms[r] = k * ys[r]
            for c in range(C):
                col_terms[c] *= xs[c]
            if n_fg > 0:
                cx, cy = _pairwise_sum(col_terms, C) / n_fg, _pairwise_sum(row_terms, R) / n_fg
            else:
                cx, cy = x + 0.5 * w, y + 0.5 * h
            centres[i, 0], centres[i, 1] = cx, cy
            w_pos, h_pos = max(w, 1e-9), max(h, 1e-9)
            alpha[i] = min(max((cx - x) / w_pos, 0.05), 0.95)
            beta[i] = min(max((cy - y - HEAD_FRACTION * h_pos) / (h_pos - HEAD_FRACTION * h_pos),
                              0.05), 0.95)
        # the five rectangles (part_boxes): split at the centroid (xsplit, ysplit), eqs. 1-2
        hh = HEAD_FRACTION * h
        xsplit = x + alpha[i] * w
        ysplit = y + hh + beta[i] * (h - hh)
        top, left_w, right_w = y + hh, xsplit - x, x + w - xsplit
        torso_h, leg_h = ysplit - y - hh, y + h - ysplit
        p = parts[i]
        p[0, 0], p[0, 1], p[0, 2], p[0, 3] = x, y, w, hh
        p[1, 0], p[1, 1], p[1, 2], p[1, 3] = x, top, left_w, torso_h
        p[2, 0], p[2, 1], p[2, 2], p[2, 3] = xsplit, top, right_w, torso_h
        p[3, 0], p[3, 1], p[3, 2], p[3, 3] = x, ysplit, left_w, leg_h
        p[4, 0], p[4, 1], p[4, 2], p[4, 3] = xsplit, ysplit, right_w, leg_h
        head_end, torso_end, split = y + hh, top + torso_h, x + left_w
        # read every sample's pixel once in a loop without branches: the frame's cache
        # misses then overlap instead of stalling the conversion below sample by sample;
        # the sum only keeps the loads
        for c in range(C):
            coff[c] = np.uint64(xi[c] * 3)
        warm = 0
        for r in range(R):
            roff = np.uint64(yi[r] * (W * 3))
            for c in range(C):
                warm += pixels[roff + coff[c]]
        sink[0] = warm
        rows_head, rows_torso, rows_legs, cols_right = 0, 0, 0, 0
        for r in range(R):
            if ys[r] < head_end:
                band[r] = 0
                rows_head += 1
            elif ys[r] < torso_end:
                band[r] = 1
                rows_torso += 1
            else:
                band[r] = 3
                rows_legs += 1
        for c in range(C):
            right[c] = 1 if xs[c] >= split else 0
            cols_right += right[c]
        count[:] = 0
        edge[:] = 0
        count_hsv[:] = 0
        count_xyz[:] = 0
        sx[:] = 0.0
        sy[:] = 0.0
        for r in range(R):
            # the row's left and right parts (the same part in the head band); their
            # sums are carried in registers through the row, each in sample order
            kl = band[r]
            kr = kl + 1 if kl > 0 else 0
            split_row = kr != kl
            yr = ys[r]
            nl, el, sxl, syl = count[kl], edge[kl], sx[kl], sy[kl]
            nr, er, sxr, syr = count[kr], edge[kr], sx[kr], sy[kr]
            roff = np.uint64(yi[r] * (W * 3))
            for c in range(C):
                if not on[r, c]:
                    continue
                o = roff + coff[c]  # unsigned: no negative-index test
                ch, cs, cv, cx, cy, cz = _hsv_xyz(np.int64(pixels[o]), np.int64(pixels[o + one]),
                                                  np.int64(pixels[o + two]))
                hsv_bin = hsv_lut[0, np.uint64(ch)] + hsv_lut[1, np.uint64(cs)] + hsv_lut[2, np.uint64(cv)]
                xyz_bin = xyz_lut[0, np.uint64(cx)] + xyz_lut[1, np.uint64(cy)] + xyz_lut[2, np.uint64(cz)]
                outline = (r == 0 or c == 0 or r == R - 1 or c == C - 1 or not on[r - 1, c]
                           or not on[r + 1, c] or not on[r, c - 1] or not on[r, c + 1])
                if split_row and right[c]:
                    k = kr
                    nr += 1
                    er += outline
                    sxr += xs[c]  # in sample order, as np.bincount(weights=...)
                    syr += yr
                else:
                    k = kl
                    nl += 1
                    el += outline
                    sxl += xs[c]
                    syl += yr
                count_hsv[k, np.uint64(hsv_bin)] += 1
                count_xyz[k, np.uint64(xyz_bin)] += 1
            count[kl], edge[kl], sx[kl], sy[kl] = nl, el, sxl, syl
            if split_row:
                count[kr], edge[kr], sx[kr], sy[kr] = nr, er, sxr, syr
        # samples of each part (rows of its band x columns of its side) and its half
        # perimeter in samples (rows + columns); histograms normalised by the count
        for j in range(5):
            rows = rows_head if j == 0 else (rows_torso if j < 3 else rows_legs)
            cols = C if j == 0 else (C - cols_right if j % 2 == 1 else cols_right)
            n = float(count[j])
            area[i, j] = n / max(float(rows * cols), 1.0)
            perimeter[i, j] = edge[j] / max(float(rows + cols), 1.0)
            norm = max(n, 1.0)
            for b in range(nb):
                hsv[i, j, b] = count_hsv[j, b] / norm
                xyz[i, j, b] = count_xyz[j, b] / norm
            if n > 0:
                centroid[i, j, 0] = sx[j] / n
                centroid[i, j, 1] = sy[j] / n
            else:
                centroid[i, j, 0] = p[j, 0] + 0.5 * p[j, 2]
                centroid[i, j, 1] = p[j, 1] + 0.5 * p[j, 3]
