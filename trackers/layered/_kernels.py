"""The compiled kernels of the PBM tracker (numba, one core), all in this one file.

Each kernel computes one named equation or rule of the paper ("Tracking People under
Heavy Occlusions by Layered Data Association") and is tested against its plain-numpy
function in ``occbench.trackers.layered.equations`` (or the numpy expression its docstring quotes)
to a tolerance, not bit for bit (``tests/trackers/layered/test_equations.py``, rtol 1e-9):

- part features (PBM 2.1-2.2): the split of a box at its centroid (eqs. 1-2,
  ``_part_rects``; the ratios ``_centroid_ratios``; the inverse under occlusion
  ``_dof_from_head``), area, perimeter, HSV and XYZ histograms, part centroids
  (``part_features``); the foreground centroid of a box (``grid_centroids``);
- the Kalman filters KF1 (eq. 7) and KF2 (eq. 8) and the gate (PBM 3);
- the model update (PBM 4.2): global DOF, centroid ratios and parts;
- layered association (eqs. 11-13) and the best/runner-up rule (PBM 4, step 4);
- per-frame bookkeeping of ``tracker.py`` (gating, occlusion-test pairs, chosen rows,
  life cycle).

They live in one file because numba's cache checks only the file of the function it
compiled: a kernel calling a kernel of another file could be loaded stale after that
file changed. Kernels are compiled on first use and cached on disk (``cache=True``);
none recurses (numba's cache mishandles recursive functions). In the per-sample loops,
indices read from arrays are cast to unsigned (``np.uint64``): numba then drops its
negative-index test.

Grouped arguments are tuples: a feature set is ``(parts, area, perimeter, hsv, xyz,
centroid, height)`` (``PartFeatures``' arrays), the mixture models ``(w, mu, s)``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

if numba.config.DISABLE_JIT:  # plain Python (tests/traced_run.py): numba's intrinsic cannot run

    def trailing_zeros(bits: np.uint64) -> int:
        """Index of the lowest set bit of ``bits`` (> 0), as numba's intrinsic."""
        b = int(bits)
        return (b & -b).bit_length() - 1

else:
    from numba.cpython.unsafe.numbers import trailing_zeros

from occbench.trackers.layered.equations import HEAD_FRACTION


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
    """(M, 3) uint8 BGR pixels to (M, 6) uint8 H, S, V, X, Y, Z (``_hsv_xyz``; the colour
    spaces of PBM 2.2's histograms), for the check against ``cv2.cvtColor``."""
    for m in range(pixels.shape[0]):
        out[m, 0], out[m, 1], out[m, 2], out[m, 3], out[m, 4], out[m, 5] = _hsv_xyz(
            np.int64(pixels[m, 0]), np.int64(pixels[m, 1]), np.int64(pixels[m, 2]))


# ----------------------------------------------------------------------------- eqs. 1-2


@numba.njit(cache=True, inline="always")
def _centroid_ratios(x: float, y: float, w: float, h: float, xc: float, yc: float
                     ) -> tuple[float, float]:
    """Eqs. 1-2 (``equations.centroid_ratios``): alpha = (xc - xtl) / w and
    beta = (yc - ytl - h/7) / (h - h/7) of a centroid in an xywh box, each clipped to
    [0.05, 0.95]."""
    w, h = max(w, 1e-9), max(h, 1e-9)
    alpha = (xc - x) / w                                                      # eq. 1
    beta = (yc - y - HEAD_FRACTION * h) / (h - HEAD_FRACTION * h)             # eq. 2
    return min(max(alpha, 0.05), 0.95), min(max(beta, 0.05), 0.95)


@numba.njit(cache=True, inline="always")
def _part_rects(x: float, y: float, w: float, h: float, alpha: float, beta: float,
                p: np.ndarray) -> None:
    """The five part rectangles (PBM 2.1, Fig. 2; ``equations.part_boxes``) of an xywh box
    split at its centroid xc = x + alpha w (eq. 1), yc = y + h/7 + beta (h - h/7) (eq. 2),
    into p (5, 4) xywh: head, left/right torso-arm, left/right leg."""
    hh = HEAD_FRACTION * h
    xs = x + alpha * w                                                        # eq. 1
    ys = y + hh + beta * (h - hh)                                             # eq. 2
    top, left_w, right_w = y + hh, xs - x, x + w - xs
    torso_h, leg_h = ys - y - hh, y + h - ys
    p[0, 0], p[0, 1], p[0, 2], p[0, 3] = x, y, w, hh
    p[1, 0], p[1, 1], p[1, 2], p[1, 3] = x, top, left_w, torso_h
    p[2, 0], p[2, 1], p[2, 2], p[2, 3] = xs, top, right_w, torso_h
    p[3, 0], p[3, 1], p[3, 2], p[3, 3] = x, ys, left_w, leg_h
    p[4, 0], p[4, 1], p[4, 2], p[4, 3] = xs, ys, right_w, leg_h


@numba.njit(cache=True, inline="always")
def _dof_from_head(hx: float, hy: float, w: float, h: float, alpha: float, beta: float,
                   out: np.ndarray) -> None:
    """The global DOF under occlusion (PBM 2.1; ``equations.dof_from_head``) into out (6,):
    xc, ytl from the head top, xtl from eq. 1 and yc from eq. 2 with the previous
    frame's alpha, beta."""
    out[0] = hx - alpha * w                                                   # eq. 1
    out[1], out[2] = hy, hx
    out[3] = hy + HEAD_FRACTION * h + beta * (h - HEAD_FRACTION * h)          # eq. 2
    out[4], out[5] = w, h


# ----------------------------------------------------------------------------- PBM 2.1-2.2


@numba.njit(cache=True, inline="always")
def _grid_centroid(x: float, y: float, w: float, h: float, on: np.ndarray) -> tuple[float, float]:
    """The foreground centroid (xc, yc) of an xywh box on its sample grid (``_sample_grid``'s
    ``on`` (R, C)): the mean position of the foreground samples, x + w (mean column + 0.5)
    / C and y + h (mean row + 0.5) / R, from exact integer sums of the sample indices (so
    a symmetric foreground gives the exact centre); the box centre when there are none."""
    R, C = on.shape
    n, sc, sr = 0, 0, 0
    for r in range(R):
        k = 0
        for c in range(C):
            if on[r, c]:
                k += 1
                sc += c
        n += k
        sr += k * r
    if n == 0:
        return x + 0.5 * w, y + 0.5 * h
    return x + w * ((sc / n + 0.5) / C), y + h * ((sr / n + 0.5) / R)


@numba.njit(cache=True)
def grid_centroids(boxes: np.ndarray, grid: tuple, image: tuple, out: np.ndarray) -> None:
    """Foreground centroids (PBM 2.1, ``_grid_centroid``) of (N, 4) xywh boxes into out
    (N, 2). ``grid``: (fr (R,), fc (C,)) sample positions in [0, 1]; ``image``: (frame
    (H, W, 3) uint8, fg (H, W) bool, has_fg) as ``part_features``."""
    fr, fc = grid
    frame, fg, has_fg = image
    H, W = frame.shape[0], frame.shape[1]
    R, C = fr.shape[0], fc.shape[0]
    ys, xs = np.empty(R), np.empty(C)
    yi, xi = np.empty(R, np.int64), np.empty(C, np.int64)
    on = np.empty((R, C), np.uint8)
    for i in range(boxes.shape[0]):
        _sample_grid(boxes[i], fr, fc, H, W, fg, has_fg, ys, xs, yi, xi, on)
        out[i, 0], out[i, 1] = _grid_centroid(boxes[i, 0], boxes[i, 1], boxes[i, 2],
                                              boxes[i, 3], on)


@numba.njit(cache=True, inline="always")
def _box_scratch(R: int, C: int, nb: int) -> tuple:
    """The scratch of ``_box_counts`` for an R x C sample grid and nb-bin histograms: the
    grid (ys, xs, yi, xi, on, band, right, coff), the per-part sums (count, edge, sx,
    sy), the joint-bin counts hist (2, 5, nb) int64 (HSV, XYZ; zero between boxes) and
    the occupied bins of each count row as a bit mask (2, 5) uint64 (bin u: bit u; kept
    when nb <= 64)."""
    return (np.empty(R), np.empty(C), np.empty(R, np.int64), np.empty(C, np.int64),
            np.empty((R, C), np.uint8), np.empty(R, np.int64), np.empty(C, np.int64),
            np.empty(C, np.uint64), np.zeros(5, np.int64), np.zeros(5, np.int64), np.zeros(5),
            np.zeros(5), np.zeros((2, 5, nb), np.int64), np.zeros((2, 5), np.uint64))


@numba.njit(cache=True, inline="always")
def _box_counts(boxes: np.ndarray, i: int, alpha: np.ndarray, beta: np.ndarray,
                at_centroids: bool, centres: np.ndarray, grid: tuple, image: tuple, luts: tuple,
                pixel_bins: tuple, s: tuple, p: np.ndarray) -> tuple[int, int, int, int]:
    """The samples of box i (``part_features``' arguments) counted into the scratch ``s``
    (``_box_scratch``) and its part rectangles (eqs. 1-2) into p (5, 4); returns the
    sample rows of the head, torso and leg bands and the sample columns right of the split.

    Part of a sample: the head band above ``y + h / 7``, torso-and-arm rows above the
    centroid row, legs below; left or right of the centroid column (PBM 2.1). A foreground
    sample is on the outline when a 4-neighbour is background or off the grid.
    """
    fr, fc = grid
    frame, fg, has_fg = image
    hsv_lut, xyz_lut = luts
    table, stamp = pixel_bins
    ys, xs, yi, xi, on, band, right, coff, count, edge, sx, sy, hist, occupied = s
    H, W = frame.shape[0], frame.shape[1]
    R, C = fr.shape[0], fc.shape[0]
    pixels = frame.reshape(H * W * 3)
    one, two, three, low = np.uint64(1), np.uint64(2), np.uint64(3), np.uint64(63)
    x, y, w, h = boxes[i, 0], boxes[i, 1], boxes[i, 2], boxes[i, 3]
    _sample_grid(boxes[i], fr, fc, H, W, fg, has_fg, ys, xs, yi, xi, on)
    if at_centroids:
        cx, cy = _grid_centroid(x, y, w, h, on)
        centres[i, 0], centres[i, 1] = cx, cy
        alpha[i], beta[i] = _centroid_ratios(x, y, w, h, cx, cy)            # eqs. 1-2
    _part_rects(x, y, w, h, alpha[i], beta[i], p)                         # eqs. 1-2
    # a sample's band and side: above the head's bottom, the torsos' bottom, left of
    # the left parts' right edge (ties go down and right)
    head_end, torso_end, split = p[0, 1] + p[0, 3], p[1, 1] + p[1, 3], p[1, 0] + p[1, 2]
    for c in range(C):
        coff[c] = np.uint64(xi[c])
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
    sx[:] = 0.0
    sy[:] = 0.0
    occupied[:] = 0
    for r in range(R):
        # the row's left and right parts (the same part in the head band); their
        # sums are carried in registers through the row, each in sample order
        kl = band[r]
        kr = kl + 1 if kl > 0 else 0
        split_row = kr != kl
        yr = ys[r]
        nl, el, sxl, syl = count[kl], edge[kl], sx[kl], sy[kl]
        nr, er, sxr, syr = count[kr], edge[kr], sx[kr], sy[kr]
        hl, xl, hr, xr = occupied[0, kl], occupied[1, kl], occupied[0, kr], occupied[1, kr]
        roff = np.uint64(yi[r] * W)
        for c in range(C):
            if not on[r, c]:
                continue
            q = roff + coff[c]  # the pixel's index (unsigned: no negative-index test)
            packed = table[q]
            if (packed >> 32) != stamp:  # first read this frame: convert it
                o = q * three
                ch, cs, cv, cx, cy, cz = _hsv_xyz(np.int64(pixels[o]), np.int64(pixels[o + one]),
                                                  np.int64(pixels[o + two]))
                packed = ((hsv_lut[0, np.uint64(ch)] + hsv_lut[1, np.uint64(cs)]
                           + hsv_lut[2, np.uint64(cv)]) << 16) | (
                    xyz_lut[0, np.uint64(cx)] + xyz_lut[1, np.uint64(cy)] + xyz_lut[2, np.uint64(cz)]
                ) | (stamp << 32)
                table[q] = packed
            hsv_bin, xyz_bin = np.uint64((packed >> 16) & 0xFFFF), np.uint64(packed & 0xFFFF)
            outline = (r == 0 or c == 0 or r == R - 1 or c == C - 1 or not on[r - 1, c]
                       or not on[r + 1, c] or not on[r, c - 1] or not on[r, c + 1])
            if split_row and right[c]:
                k = kr
                nr += 1
                er += outline
                sxr += xs[c]  # in sample order, as np.bincount(weights=...)
                syr += yr
                hr |= one << (hsv_bin & low)
                xr |= one << (xyz_bin & low)
            else:
                k = kl
                nl += 1
                el += outline
                sxl += xs[c]
                syl += yr
                hl |= one << (hsv_bin & low)
                xl |= one << (xyz_bin & low)
            hist[0, k, hsv_bin] += 1
            hist[1, k, xyz_bin] += 1
        count[kl], edge[kl], sx[kl], sy[kl] = nl, el, sxl, syl
        occupied[0, kl], occupied[1, kl] = hl, xl
        if split_row:
            count[kr], edge[kr], sx[kr], sy[kr] = nr, er, sxr, syr
            occupied[0, kr], occupied[1, kr] = hr, xr
    return rows_head, rows_torso, rows_legs, cols_right


@numba.njit(cache=True, inline="always")
def _box_features(s: tuple, bands: tuple, p: np.ndarray, i: int, out: tuple) -> None:
    """Row i of the features ``out`` (area, perimeter (N, 5), hsv, xyz (N, 5, B),
    centroid (N, 5, 2)) of a box from its counts ``s`` (``_box_counts``, ``bands`` its
    return; the counts are emptied) and part rectangles p (5, 4): per part, the foreground
    fraction of its samples (its band's rows x its side's columns), the outline samples
    over its half perimeter in samples (rows + columns), the histograms normalised by the
    count (an unoccupied bin 0, as 0 / count; with nb <= 64 only the occupied bins are
    divided), and the samples' mean position (the rectangle centre when there are none)."""
    area, perimeter, hsv, xyz, centroid = out
    count, edge, sx, sy, hist, occupied = s[8], s[9], s[10], s[11], s[12], s[13]
    rows_head, rows_torso, rows_legs, cols_right = bands
    C, nb = s[1].shape[0], hist.shape[2]
    for j in range(5):
        rows = rows_head if j == 0 else (rows_torso if j < 3 else rows_legs)
        cols = C if j == 0 else (C - cols_right if j % 2 == 1 else cols_right)
        n = float(count[j])
        area[i, j] = n / max(float(rows * cols), 1.0)
        perimeter[i, j] = edge[j] / max(float(rows + cols), 1.0)
        norm = max(n, 1.0)
        for space, hists in ((0, hsv), (1, xyz)):
            if nb <= 64:
                hists[i, j, :] = 0.0
                bits = occupied[space, j]
                while bits != 0:
                    u = trailing_zeros(bits)
                    hists[i, j, u] = hist[space, j, u] / norm
                    hist[space, j, u] = 0
                    bits &= bits - np.uint64(1)
            else:
                for u in range(nb):
                    hists[i, j, u] = hist[space, j, u] / norm
                    hist[space, j, u] = 0
        if n > 0:
            centroid[i, j, 0] = sx[j] / n
            centroid[i, j, 1] = sy[j] / n
        else:
            centroid[i, j, 0] = p[j, 0] + 0.5 * p[j, 2]
            centroid[i, j, 1] = p[j, 1] + 0.5 * p[j, 3]


@numba.njit(cache=True)
def part_features(boxes: np.ndarray, alpha: np.ndarray, beta: np.ndarray, at_centroids: bool,
                  centres: np.ndarray, grid: tuple, image: tuple, luts: tuple, out: tuple,
                  pixel_bins: tuple) -> None:
    """Part rectangles and features of the five parts of each box (PBM 2.1-2.2):
    ``_box_counts`` then ``_box_features`` per box.

    Args:
        boxes: (N, 4) xywh. alpha, beta: (N,) centroid ratios (eqs. 1-2); out when
            ``at_centroids``: the ratios (``_centroid_ratios``) of the foreground centroids
            (``_grid_centroid``), written to ``centres`` (N, 2).
        grid: (fr (R,), fc (C,)) sample positions in [0, 1] along the height and width.
        image: (frame (H, W, 3) uint8 BGR, fg (H, W) bool mask (any placeholder if not
            has_fg), has_fg).
        luts: (hsv_lut, xyz_lut), each (3, 256) int64: channel c's value q (``_hsv_xyz``)
            adds ``lut[c, q] = min(q * bins // range_c, bins - 1) * bins ** (2 - c)`` to
            the joint bin (``parts._channel_luts``).
        out: (parts (N, 5, 4) (``_part_rects``), area, perimeter (N, 5), hsv, xyz
            (N, 5, B), centroid (N, 5, 2)), written.
        pixel_bins: ((H * W,) int64, stamp): each pixel's joint bins ``stamp << 32 |
            hsv_bin << 16 | xyz_bin`` once a sample of this frame read it: the boxes of a
            frame share most of their pixels (the search's boxes around one head), whose
            colour conversion is then done once per frame; an entry of another stamp (the
            caller's frame count, >= 1) is stale, so nothing is reset between frames.
    """
    parts = out[0]
    s = _box_scratch(grid[0].shape[0], grid[1].shape[0], out[3].shape[2])
    for i in range(boxes.shape[0]):
        bands = _box_counts(boxes, i, alpha, beta, at_centroids, centres, grid, image, luts,
                            pixel_bins, s, parts[i])
        _box_features(s, bands, parts[i], i, out[1:])



# ----------------------------------------------------------------------------- PBM 3, eqs. 7-8


@numba.njit(cache=True)
def cv_predict_inplace(x: np.ndarray, p: np.ndarray, qp: np.ndarray, qv: np.ndarray) -> None:
    """Predict step of KF1 (eq. 7) and KF2 (eq. 8) (``equations.cv_predicted``: x = F x,
    P = F P F' + Q) of every row, in place: x (T, 4) = (a, b, a', b'); P kept per axis i
    as its 2 x 2 block p[:, i] = (A, B, C, D) = (P[a, a], P[a, a'], P[a', a], P[a', a'])
    (diagonal P0, Q and R never couple the axes); qp, qv (T,) the noise variances."""
    for n in range(x.shape[0]):
        for i in range(2):
            x[n, i] = x[n, i] + x[n, i + 2]                                  # x = F x
            A, B, C, D = p[n, i, 0], p[n, i, 1], p[n, i, 2], p[n, i, 3]
            p[n, i, 0] = A + B + C + D + qp[n]                               # P = F P F' + Q
            p[n, i, 1] = B + D
            p[n, i, 2] = C + D
            p[n, i, 3] = D + qv[n]


@numba.njit(cache=True)
def cv_update_inplace(x: np.ndarray, p: np.ndarray, r: np.ndarray, rows: np.ndarray,
                      z: np.ndarray) -> None:
    """Update step of KF1 (eq. 7, z = (xc, yc)) and KF2 (eq. 8, z = (h, w))
    (``equations.cv_updated``) of the filters at ``rows`` with measurements z (M, 2), in
    place (layout as ``cv_predict_inplace``; r (T,) the measurement variance)."""
    for q in range(rows.shape[0]):
        n = rows[q]
        for i in range(2):
            s = p[n, i, 0] + r[n]                                            # S = H P H' + R
            y = z[q, i] - x[n, i]                                            # y = z - H x
            A, B, C, D = p[n, i, 0], p[n, i, 1], p[n, i, 2], p[n, i, 3]
            kp, kv = A / s, C / s                                            # K = P H' S^-1
            x[n, i] += kp * y                                                # x = x + K y
            x[n, i + 2] += kv * y
            p[n, i, 0], p[n, i, 1] = A - kp * A, B - kp * B                  # P = (I - K H) P
            p[n, i, 2], p[n, i, 3] = C - kv * A, D - kv * B


@numba.njit(cache=True)
def gate_boxes(centres: np.ndarray, rates: np.ndarray, size_wh: np.ndarray, misses: np.ndarray,
               rule: tuple, out: np.ndarray) -> None:
    """The gate (PBM 3, Fig. 5; ``dynamics.Gate``) of every row into out (T, 4) xywh:
    centred on ``centres`` (zero-order prediction), half-sizes h = speed_factor |v| +
    min_fraction size (|v| KF1's speed, eq. 7), after m > 0 misses h miss_factor
    growth^(m - 1), capped at max_fraction max(size, 1). ``rule``: (speed_factor,
    min_fraction, miss_factor, growth, max_fraction)."""
    speed_factor, min_fraction, miss_factor, growth, max_fraction = rule
    for n in range(size_wh.shape[0]):
        sp = speed_factor * math.hypot(rates[n, 0], rates[n, 1])
        for i in range(2):
            h = sp + min_fraction * size_wh[n, i]
            if misses[n] > 0:
                h = h * miss_factor * growth ** (misses[n] - 1.0)
            h = min(h, max_fraction * max(size_wh[n, i], 1.0))
            out[n, i] = centres[n, i] - h
            out[n, 2 + i] = 2 * h


# ----------------------------------------------------------------------------- PBM 4.2


@numba.njit(cache=True)
def targets_predict(kf1: tuple, kf2: tuple) -> None:
    """KF1 (eq. 7) and KF2 (eq. 8) predict (``cv_predict_inplace``) of every target; KF2's
    rates are zeroed first where a step would take h or w below 2 pixels. ``kf1``, ``kf2``:
    (x, p, qp, qv) of ``ConstantVelocity2D``."""
    x2 = kf2[0]
    for n in range(x2.shape[0]):
        if x2[n, 0] + x2[n, 2] < 2 or x2[n, 1] + x2[n, 3] < 2:
            x2[n, 2] = 0.0
            x2[n, 3] = 0.0
    cv_predict_inplace(kf1[0], kf1[1], kf1[2], kf1[3])
    cv_predict_inplace(kf2[0], kf2[1], kf2[2], kf2[3])


@numba.njit(cache=True, inline="always")
def _push(window: np.ndarray, count: np.ndarray, n: int, values: np.ndarray) -> np.ndarray:
    """Append ``values`` (K,) as the newest entry of window n of ``window`` (T, L, K) and
    return the mean of its newest ``count[n]`` entries (a sliding temporal window)."""
    L, K = window.shape[1], window.shape[2]
    for j in range(L - 1):
        for k in range(K):
            window[n, j, k] = window[n, j + 1, k]
    for k in range(K):
        window[n, L - 1, k] = values[k]
    c = min(count[n] + 1, L)
    count[n] = c
    mean = np.zeros(K)
    for k in range(K):
        for j in range(L - c, L):
            mean[k] += window[n, j, k]
        mean[k] /= c
    return mean


@numba.njit(cache=True)
def targets_update(state: tuple, kf1: tuple, kf2: tuple, rows: np.ndarray, dof: np.ndarray,
                   flags: tuple, part_scores: np.ndarray, threshold: float, shift: np.ndarray
                   ) -> None:
    """Section 4.2, the global models' update (``equations.update_global``) of the
    targets at ``rows`` from their candidates' DOF (M, 6), then KF1 (eq. 7) with z = (xc,
    yc) and KF2 (eq. 8) with z = (h, w) of the updated DOF (``cv_update_inplace``), then
    p_j, the frozen parts (not p_j >= threshold), the occlusion flag, hits + 1 and misses = 0.

    Per row the DOF enters the occlusion window; an occluded row takes the window's mean,
    an unoccluded one the candidate's DOF; an unoccluded row with a measured centroid
    pushes its ratios (eqs. 1-2, ``_centroid_ratios``) into the ratio window, whose mean
    becomes the target's alpha, beta. ``shift`` (M, 2) gets the centroid moves.

    Args:
        state: ``Targets``' (dof, history, n_history, ratios, n_ratios, alpha, beta,
            part_scores, occluded_parts, occluded, hits, misses), updated.
        kf1, kf2: (x, p, r) of the filters. flags: (measured (M,), occluded (M,)) bool.
    """
    (dof_all, history, n_history, ratios, n_ratios, alpha, beta, part_scores_all,
     occluded_parts, occluded_all, hits, misses) = state
    measured, occluded = flags
    M = rows.shape[0]
    z1, z2 = np.empty((M, 2)), np.empty((M, 2))
    ab = np.empty(2)
    for q in range(M):
        n = rows[q]
        x0, y0 = dof_all[n, 2], dof_all[n, 3]
        mean = _push(history, n_history, n, dof[q])
        for k in range(6):
            dof_all[n, k] = mean[k] if occluded[q] else dof[q, k]            # 4.2
        d = dof_all[n]
        if measured[q] and not occluded[q]:
            ab[0], ab[1] = _centroid_ratios(d[0], d[1], d[4], d[5], d[2], d[3])  # eqs. 1-2
            avg = _push(ratios, n_ratios, n, ab)                             # running average
            alpha[n], beta[n] = avg[0], avg[1]
        shift[q, 0], shift[q, 1] = d[2] - x0, d[3] - y0
        z1[q, 0], z1[q, 1] = d[2], d[3]                                      # eq. 7
        z2[q, 0], z2[q, 1] = d[5], d[4]                                      # eq. 8
    cv_update_inplace(kf1[0], kf1[1], kf1[2], rows, z1)
    cv_update_inplace(kf2[0], kf2[1], kf2[2], rows, z2)
    for q in range(M):
        n = rows[q]
        for j in range(part_scores.shape[1]):
            part_scores_all[n, j] = part_scores[q, j]
            occluded_parts[n, j] = not part_scores[q, j] >= threshold
        occluded_all[n] = occluded[q]
        hits[n] += 1
        misses[n] = 0


@numba.njit(cache=True)
def stale_parts(state: tuple, dof: np.ndarray, misses: np.ndarray, rows: np.ndarray,
                cand: tuple, ks: np.ndarray, part_scores: np.ndarray, rule: tuple,
                relearn: np.ndarray) -> None:
    """Stale parts (our adaptation beyond PBM 4.2; ``model.stale_parts``) in one loop over
    rows x parts x targets; a part's cover is the largest of the fraction outside the
    image and the fractions under each other target's box.

    Args:
        state: (stale (T, 5), occluded_parts (T, 5), model area (T, 5)), updated.
        dof, misses: the targets' (T, 6) DOF and (T,) misses. cand: (parts, area) of the
            candidates. rule: (threshold, occluder_misses, W, H, max_cover, min_fill,
            stale_frames). relearn: (M, 5) bool, written.
    """
    stale, occluded_parts, m_area = state
    c_parts, c_area = cand
    threshold, occluder_misses, W, H, max_cover, min_fill, stale_frames = rule
    T = dof.shape[0]
    for q in range(rows.shape[0]):
        r, k = rows[q], ks[q]
        for j in range(c_parts.shape[1]):
            x0, y0 = c_parts[k, j, 0], c_parts[k, j, 1]
            x1, y1 = x0 + c_parts[k, j, 2], y0 + c_parts[k, j, 3]
            size = max(c_parts[k, j, 2] * c_parts[k, j, 3], 1e-9)
            inside = ((min(max(x1, 0.0), W) - min(max(x0, 0.0), W))
                      * (min(max(y1, 0.0), H) - min(max(y0, 0.0), H)))
            cover = 1.0 - inside / size
            for t in range(T):
                if t == r or misses[t] > occluder_misses:
                    continue
                iw = min(x1, dof[t, 0] + dof[t, 4]) - max(x0, dof[t, 0])
                ih = min(y1, dof[t, 1] + dof[t, 5]) - max(y0, dof[t, 1])
                if iw > 0.0 and ih > 0.0:
                    cover = max(cover, iw * ih / size)
            if part_scores[q, j] >= threshold:
                stale[r, j] = 0
            elif cover <= max_cover and c_area[k, j] >= min_fill * m_area[r, j]:
                stale[r, j] += 1
                if stale[r, j] >= stale_frames:
                    relearn[q, j] = True
                    stale[r, j] = 0
                    occluded_parts[r, j] = False


@numba.njit(cache=True)
def update_parts(m: tuple, rows: np.ndarray, c: tuple, ks: np.ndarray, part_scores: np.ndarray,
                 rule: tuple, shift: np.ndarray, ratios: tuple, boxes: np.ndarray,
                 relearn: np.ndarray) -> None:
    """Section 4.2, the parts models' update (``equations.update_parts``) of the targets
    at ``rows`` of ``m`` from the candidates at ``ks`` of ``c``, in place: a part with
    p_j >= threshold moves area, perimeter and histograms by eta = rate p_j towards the
    candidate's and takes its centroid; a part below keeps them, its centroid moved by
    ``shift``; a ``relearn`` part takes eta = relearn_rate and the candidate's centroid.
    The rectangles follow the updated global model (``boxes`` (M, 4) and ``ratios``
    (alpha, beta), each (M,); ``_part_rects``, eqs. 1-2).

    ``rule``: (threshold, rate, relearn_rate).
    """
    m_parts, m_area, m_perimeter, m_hsv, m_xyz, m_centroid, m_height = m
    _, c_area, c_perimeter, c_hsv, c_xyz, c_centroid, _ = c
    threshold, rate, relearn_rate = rule
    alpha, beta = ratios
    nb = m_hsv.shape[2]
    for q in range(rows.shape[0]):
        r, k = rows[q], ks[q]
        for j in range(m_area.shape[1]):
            p = part_scores[q, j]
            matched = p >= threshold or relearn[q, j]
            eta = relearn_rate if relearn[q, j] else (rate * p if p >= threshold else 0.0)
            m_area[r, j] += eta * (c_area[k, j] - m_area[r, j])              # running average
            m_perimeter[r, j] += eta * (c_perimeter[k, j] - m_perimeter[r, j])
            for u in range(nb):
                m_hsv[r, j, u] += eta * (c_hsv[k, j, u] - m_hsv[r, j, u])
                m_xyz[r, j, u] += eta * (c_xyz[k, j, u] - m_xyz[r, j, u])
            for a in range(2):
                m_centroid[r, j, a] = c_centroid[k, j, a] if matched else m_centroid[r, j, a] + shift[q, a]
        _part_rects(boxes[q, 0], boxes[q, 1], boxes[q, 2], boxes[q, 3], alpha[q], beta[q],
                    m_parts[r])                                              # eqs. 1-2
        m_height[r] = boxes[q, 3]


# ----------------------------------------------------------------------------- PBM 4.1, eqs. 11-13

_SQRT_HALF = math.sqrt(0.5)


@numba.njit(cache=True, inline="always")
def _ndtr(z: float) -> float:
    """Standard normal CDF Phi(z) = erfc(-z / sqrt 2) / 2 (``scipy.special.ndtr``)."""
    return 0.5 * math.erfc(-z * _SQRT_HALF)


@numba.njit(cache=True, inline="always")
def _survival(x: float, w: np.ndarray, mu: np.ndarray, s: np.ndarray, i: int, j: int) -> float:
    """p(d_ij | theta_ij) of eq. 12 (``equations.match_probability``): P(D >= x) of the
    folded normal mixture (i, j) of padded (6, 5, K) arrays, x >= 0:
    sum_c w_c [Phi((mu_c - x) / s_c) + Phi((-mu_c - x) / s_c)], clipped to [0, 1] (NaN stays
    NaN). Zero-weight padding is skipped."""
    tot = 0.0
    for c in range(w.shape[2]):
        wc, mc, sc = w[i, j, c], mu[i, j, c], s[i, j, c]
        if wc == 0.0:
            continue
        a = _ndtr((mc - x) / sc)
        tot += wc * (a + (a if mc == 0.0 else _ndtr((-mc - x) / sc)))
    if tot < 0.0:
        tot = 0.0
    elif tot > 1.0:
        tot = 1.0
    return tot


@numba.njit(cache=True)
def survival_kernel(d: np.ndarray, theta: tuple, out: np.ndarray) -> None:
    """p(d | theta) of eq. 12 (``_survival``) of (n, 6, 5) differences (negative ones count
    as 0) into out (n, 6, 5)."""
    w, mu, s = theta
    for k in range(d.shape[0]):
        for i in range(d.shape[1]):
            for j in range(d.shape[2]):
                x = d[k, i, j]
                out[k, i, j] = _survival(x if not x < 0.0 else 0.0, w, mu, s, i, j)


@numba.njit(cache=True, inline="always")
def _rho(a: np.ndarray, b: np.ndarray, t: int, n: int, j: int, idx: np.ndarray) -> float:
    """Bhattacharyya coefficient rho = sum_u sqrt(a[t, j, u] b[n, j, u]) of two histograms
    (eq. 11's colour terms), summed in u order over the bins listed in ``idx`` (scratch, at
    least as long as the histograms): those where b is not 0 or a not finite. A bin where b
    is 0 and a finite adds +-0, which leaves the sum as it was (it starts at +0), so the
    sum has the bits of the sum over every bin (``rho_bins``, tested against it) at the
    cost of the few bins a candidate's part occupies."""
    cnt = 0
    for u in range(b.shape[2]):  # the list, without branches
        idx[cnt] = u
        cnt += (b[n, j, u] != 0.0) | (not abs(a[t, j, u]) < math.inf)
    tot = 0.0
    for q in range(cnt):
        u = idx[q]
        tot += math.sqrt(a[t, j, u] * b[n, j, u])
    return tot


@numba.njit(cache=True)
def rho_bins(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """``_rho`` of every pair of rows a[t, j] and b[t, j] of two (T, J, U) arrays into
    out (T, J), for its test against the plain sum over every bin."""
    idx = np.empty(b.shape[2], np.int64)
    for t in range(a.shape[0]):
        for j in range(a.shape[1]):
            out[t, j] = _rho(a, b, t, t, j, idx)


@numba.njit(cache=True, inline="always")
def _rho_listed(a: np.ndarray, b: np.ndarray, t: int, n: int, j: int, bits: np.uint64) -> float:
    """``_rho`` when a[t, j] is finite and the bins where b[n, j] is not 0 are the set bits
    of ``bits`` (bin u: bit u): the same terms in the same (u) order, without the scan."""
    tot = 0.0
    while bits != 0:
        u = trailing_zeros(bits)
        tot += math.sqrt(a[t, j, u] * b[n, j, u])
        bits &= bits - np.uint64(1)
    return tot


@numba.njit(cache=True, inline="always")
def _pair_differences(m: tuple, c: tuple, t: int, n: int, g: float, d: np.ndarray, k: int,
                      idx: np.ndarray, listed: tuple) -> None:
    """Eq. 11, d_ij = |f_ij - F_ij| (``equations.differences``), of model t of ``m`` against
    candidate n of ``c`` into d[k] (6, 5) (``idx``: ``_rho``'s scratch).

    Per part j: |area|, |perimeter|, 1 - rho of HSV and XYZ (1 when the candidate part has
    no foreground), |c_n - C_t| / max(H_t, 1) and 1 - IoU (IoU 0 when union <= 0), the
    last two times g = 1 / (1 + misses); all clipped at 0.

    ``listed``: (use, occupied (2, 5) uint64, finite (T, 2, 5) bool): when ``use``, rho of a
    model histogram that is finite (``finite[t]``) is summed over the candidate's occupied
    bins (``_rho_listed``; ``occupied`` as ``_box_scratch``'s) instead of ``_rho``'s scan.
    """
    m_parts, m_area, m_perimeter, m_hsv, m_xyz, m_centroid, m_height = m
    c_parts, c_area, c_perimeter, c_hsv, c_xyz, c_centroid, _ = c
    use_lists, occupied, finite = listed
    hgt = max(m_height[t], 1.0)
    for j in range(m_area.shape[1]):
        d[k, 0, j] = abs(m_area[t, j] - c_area[n, j])
        d[k, 1, j] = abs(m_perimeter[t, j] - c_perimeter[n, j])
        if c_area[n, j] <= 0:  # an empty histogram (part without foreground) never matches
            d[k, 2, j] = 1.0
            d[k, 3, j] = 1.0
        elif use_lists and finite[t, 0, j] and finite[t, 1, j]:
            d[k, 2, j] = 1.0 - _rho_listed(m_hsv, c_hsv, t, n, j, occupied[0, j])
            d[k, 3, j] = 1.0 - _rho_listed(m_xyz, c_xyz, t, n, j, occupied[1, j])
        else:
            d[k, 2, j] = 1.0 - _rho(m_hsv, c_hsv, t, n, j, idx)
            d[k, 3, j] = 1.0 - _rho(m_xyz, c_xyz, t, n, j, idx)
        dx = c_centroid[n, j, 0] - m_centroid[t, j, 0]
        dy = c_centroid[n, j, 1] - m_centroid[t, j, 1]
        d[k, 4, j] = math.sqrt(dx * dx + dy * dy) / hgt * g
        ax, ay, aw, ah = m_parts[t, j, 0], m_parts[t, j, 1], m_parts[t, j, 2], m_parts[t, j, 3]
        bx, by, bw, bh = c_parts[n, j, 0], c_parts[n, j, 1], c_parts[n, j, 2], c_parts[n, j, 3]
        iw = max(min(ax + aw, bx + bw) - max(ax, bx), 0.0)
        ih = max(min(ay + ah, by + bh) - max(ay, by), 0.0)
        inter = iw * ih
        union = aw * ah + bw * bh - inter
        iou = inter / union if union > 0 else 0.0
        d[k, 5, j] = (1.0 - iou) * g
        for i in range(d.shape[1]):
            if d[k, i, j] < 0.0:  # np.clip(d, 0, None)  # noqa: PLR1730
                d[k, i, j] = 0.0


_NO_LISTS = (False, np.zeros((2, 5), np.uint64), np.zeros((1, 2, 5), np.bool_))
"""``_pair_differences``' ``listed`` when the candidates' occupied bins are not known."""


@numba.njit(cache=True)
def _differences_kernel(m: tuple, c: tuple, ti: np.ndarray, n: np.ndarray, misses: np.ndarray,
                        out: np.ndarray) -> None:
    """Eq. 11 (``_pair_differences``) of the pairs (ti[k], n[k]) into out (K, 6, 5);
    misses (T,) float64 per target, g = 1 / (1 + misses)."""
    for k in range(ti.shape[0]):
        if not (0 <= ti[k] < m[1].shape[0] and 0 <= n[k] < c[1].shape[0]):
            raise IndexError("selected pair index out of range")
    idx = np.empty(max(m[3].shape[2], m[4].shape[2]), np.int64)
    for k in range(ti.shape[0]):
        _pair_differences(m, c, ti[k], n[k], 1.0 / (1.0 + misses[ti[k]]), out, k, idx, _NO_LISTS)


_MEMO_BITS = 7
"""log2 of the slots of ``_score_row``'s table of p(x | theta_ij) per (i, j)."""
_HASH_MUL, _HASH_SHIFT, _SLOT_SHIFT = (np.uint64(0x9E3779B97F4A7C15), np.uint64(29),
                                       np.uint64(64 - _MEMO_BITS))


@numba.njit(cache=True, inline="always")
def _memo(n_i: int, n_j: int) -> tuple:
    """An empty table of p(x | theta_ij) per (i, j) for ``_score_row``: (filled, keys,
    values) (n_i, n_j, slots) and the (buffer, its bits) a key is read through."""
    buf = np.empty(1)
    return (np.zeros((n_i, n_j, 1 << _MEMO_BITS), np.bool_),
            np.empty((n_i, n_j, 1 << _MEMO_BITS), np.uint64),
            np.empty((n_i, n_j, 1 << _MEMO_BITS)), buf, buf.view(np.uint64))


@numba.njit(cache=True, inline="always")
def _score_row(d: np.ndarray, k: int, spread: float, weights: tuple, theta: tuple, memo: tuple,
               pj: np.ndarray, p: np.ndarray, row: int) -> None:
    """Eqs. 12-13 of differences d[k] (6, 5) into pj[row] (5,) and p[row], with the
    normalised weights (omega, gamma) (``_scores_kernel``); ``memo`` (``_memo``) recalls
    p(x | theta_ij) of an x seen before, bit for bit as ``_survival`` computes it."""
    w, mu, s = theta
    omega, gamma = weights
    filled, keys, values, buf, bits = memo
    total = 0.0
    for j in range(d.shape[2]):
        acc = 0.0
        for i in range(d.shape[1]):
            x = d[k, i, j] / spread
            buf[0] = x if not x < 0.0 else 0.0
            key = bits[0]
            slot = ((key ^ (key >> _HASH_SHIFT)) * _HASH_MUL) >> _SLOT_SHIFT
            if filled[i, j, slot] and keys[i, j, slot] == key:
                sv = values[i, j, slot]
            else:
                sv = _survival(buf[0], w, mu, s, i, j)
                filled[i, j, slot], keys[i, j, slot], values[i, j, slot] = True, key, sv
            acc += omega[i] * sv                                                       # eq. 12
        pj[row, j] = acc
        total += gamma[j] * acc                                                        # eq. 13
    p[row] = total


@numba.njit(cache=True)
def _scores_kernel(d: np.ndarray, spread: float, omega: np.ndarray, gamma: np.ndarray,
                   theta: tuple, pj: np.ndarray, p: np.ndarray) -> None:
    """Eq. 12, p_j = sum_i omega_i p(d_ij / spread | theta_ij), into pj (K, 5) and eq. 13,
    p = sum_j gamma_j p_j, into p (K,), of (K, 6, 5) differences (``equations.part_scores``,
    ``equations.global_score``); omega and gamma are normalised to sum 1 here.

    p(x | theta_ij) (``_survival``) is a function of x alone for each (i, j), and x repeats
    (area and perimeter take few values, an empty part's colour terms are 1): a value is
    recalled from a small table per (i, j), keyed by the bits of x, instead of computed
    again (``_score_row``); the sums are those of ``_survival`` on every term, bit for bit."""
    weights = (omega / omega.sum(), gamma / gamma.sum())
    memo = _memo(d.shape[1], d.shape[2])
    for k in range(d.shape[0]):
        _score_row(d, k, spread, weights, theta, memo, pj, p, k)


@numba.njit(cache=True)
def _pair_scores_kernel(m: tuple, c: tuple, ti: np.ndarray, n: np.ndarray, misses: np.ndarray,
                        spread: float, omega: np.ndarray, gamma: np.ndarray, theta: tuple
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 11-13 of the pairs (ti[k], n[k]) in one call: ``_differences_kernel`` then
    ``_scores_kernel``; returns p_j (K, 5) and p (K,)."""
    K = ti.shape[0]
    d = np.empty((K, theta[0].shape[0], m[1].shape[1]))
    _differences_kernel(m, c, ti, n, misses, d)
    pj, p = np.empty((K, m[1].shape[1])), np.empty(K)
    _scores_kernel(d, spread, omega, gamma, theta, pj, p)
    return pj, p


_NO_CENTRES = np.zeros((0, 2))
"""``_box_counts``' centroid output when it is given the ratios (never written)."""


BOUND_CELLS = 2048
"""Cells per unit of x of ``survival_bounds``' table (a power of two: x * 2048 is exact)."""
BOUND_SLACK = 1e-12
"""Added to each bound: covers erfc's rounding (about 1e-16 on p(x | theta) <= 1)."""


@numba.njit(cache=True)
def survival_bounds(theta: tuple) -> np.ndarray:
    """(6, 5, BOUND_CELLS + 1) upper bounds of p(x | theta_ij) (``_survival``): entry m
    bounds every x in [m, m + 1) / BOUND_CELLS, the last every x >= 1. A survival function
    P(D >= x) does not increase with x, so the value at the cell's left end, plus
    ``BOUND_SLACK``, bounds the cell (``_score_bound``)."""
    w, mu, s = theta
    out = np.empty((w.shape[0], w.shape[1], BOUND_CELLS + 1))
    for i in range(w.shape[0]):
        for j in range(w.shape[1]):
            for c in range(BOUND_CELLS + 1):
                out[i, j, c] = _survival(c / BOUND_CELLS, w, mu, s, i, j) + BOUND_SLACK
    return out


@numba.njit(cache=True, inline="always")
def _score_bound(d: np.ndarray, k: int, spread: float, weights: tuple, table: np.ndarray) -> float:
    """An upper bound of ``_score_row``'s p of differences d[k] (6, 5): the same sums in the
    same order with each p(x | theta_ij) replaced by its bound in ``table``
    (``survival_bounds``); rounding to nearest never decreases a sum or a product by a
    weight >= 0 when an operand grows, so the bound holds for the computed p, bit for bit.
    NaN when a difference is NaN."""
    omega, gamma = weights
    total = 0.0
    for j in range(d.shape[2]):
        acc = 0.0
        for i in range(d.shape[1]):
            x = d[k, i, j] / spread
            if np.isnan(x):
                return np.nan
            v = x * BOUND_CELLS if x > 0.0 else 0.0
            acc += omega[i] * table[i, j, int(v) if v < BOUND_CELLS else BOUND_CELLS]
        total += gamma[j] * acc
    return total


@numba.njit(cache=True, inline="always")
def _score_group(d: np.ndarray, g0: int, size: int, spread: float, weights: tuple,
                 theta: tuple, memo: tuple, table: np.ndarray, pj: np.ndarray,
                 p: np.ndarray) -> None:
    """``_score_row`` of the boxes g0 .. g0 + size - 1 of which only the first maximum of p
    counts (``carved_rows``): scored in order of their bounds (``_score_bound``), highest
    first; once a bound is below the best p scored, that box and the rest cannot reach
    it and are left unscored (p -inf, p_j NaN). Every box is scored when a bound is not
    finite. The scored boxes have their own bits, so the first maximum is the same box."""
    ub = np.empty(size)
    for q in range(size):
        ub[q] = _score_bound(d, g0 + q, spread, weights, table)
    if not np.isfinite(ub).all():
        for q in range(size):
            _score_row(d, g0 + q, spread, weights, theta, memo, pj, p, g0 + q)
        return
    best = -np.inf
    for q in np.argsort(-ub):
        k = g0 + q
        if ub[q] < best:
            p[k] = -np.inf
            pj[k, :] = np.nan
            continue
        _score_row(d, k, spread, weights, theta, memo, pj, p, k)
        if p[k] > best:  # noqa: PLR1730 (p is finite here)
            best = p[k]


@numba.njit(cache=True)
def box_scores_kernel(boxes: np.ndarray, ti: np.ndarray, ratios: tuple, sampling: tuple, m: tuple,
               misses: np.ndarray, rule: tuple, theta: tuple, groups: tuple
               ) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 11-13 of K boxes of the frame, each measured as ``part_features`` measures it
    (PBM 2.1-2.2), against the model of target ti[k]: p_j (K, 5) and p (K,), bit for bit
    ``part_features`` then ``_pair_scores_kernel(m, features, ti, arange(K), ...)``, with
    no (K, 5, B) histograms: each box's features are made in a one-row scratch, compared
    and dropped, and rho sums the occupied bins only (``_rho_listed``) where the model's
    histogram is finite. The search's boxes (PBM 3.1, eqs. 9-10): 25 per searched pair, of
    which the tracker keeps one.

    Args:
        boxes: (K, 4) xywh. ti: (K,) target rows (IndexError when out of range).
        ratios: (alpha, beta), each (K,), of the boxes' split (eqs. 1-2).
        sampling: (grid, image, luts, pixel_bins) as ``part_features``'.
        m: the targets' models (a feature set). misses: (T,) float64, g = 1 / (1 + misses).
        rule: (spread, omega (6,), gamma (5,)) as ``_pair_scores_kernel``'s.
        groups: (size, grouped, table): boxes 0 .. grouped - 1 are consecutive groups of
            ``size`` of which only the first maximum of p counts, scored by
            ``_score_group`` (``table``: ``survival_bounds(theta)``); size 0: none.
    """
    grid, image, luts, pixel_bins = sampling
    spread, omega, gamma = rule
    K, T, nb = boxes.shape[0], m[1].shape[0], m[3].shape[2]
    for k in range(K):
        if not 0 <= ti[k] < T:
            raise IndexError("selected pair index out of range")
    finite = np.empty((T, 2, 5), np.bool_)
    for t in range(T):
        for j in range(5):
            finite[t, 0, j] = np.isfinite(m[3][t, j]).all()
            finite[t, 1, j] = np.isfinite(m[4][t, j]).all()
    s = _box_scratch(grid[0].shape[0], grid[1].shape[0], nb)
    one = (np.empty((1, 5, 4)), np.empty((1, 5)), np.empty((1, 5)), np.empty((1, 5, nb)),
           np.empty((1, 5, nb)), np.empty((1, 5, 2)), np.empty(1))
    listed = (nb <= 64, s[13], finite)
    weights = (omega / omega.sum(), gamma / gamma.sum())
    memo = _memo(theta[0].shape[0], m[1].shape[1])
    d = np.empty((K, theta[0].shape[0], m[1].shape[1]))
    idx = np.empty(max(nb, m[4].shape[2]), np.int64)
    for k in range(K):
        bands = _box_counts(boxes, k, ratios[0], ratios[1], False, _NO_CENTRES, grid, image,
                            luts, pixel_bins, s, one[0][0])
        _box_features(s, bands, one[0][0], 0, one[1:6])
        one[6][0] = boxes[k, 3]
        t = ti[k]
        _pair_differences(m, one, t, 0, 1.0 / (1.0 + misses[t]), d, k, idx, listed)  # eq. 11
    pj, p = np.empty((K, m[1].shape[1])), np.empty(K)
    size, grouped, table = groups
    first = 0
    if size > 0:
        for g0 in range(0, grouped, size):
            _score_group(d, g0, size, spread, weights, theta, memo, table, pj, p)
        first = grouped
    for k in range(first, K):
        _score_row(d, k, spread, weights, theta, memo, pj, p, k)                      # eqs. 12-13
    return pj, p


@numba.njit(cache=True)
def _ambiguous_kernel(scores: np.ndarray, threshold: float, margin: float
                      ) -> tuple[int, int, bool]:
    """PBM 4, step 4 (``association.ambiguous``): the candidate with the highest global
    score (eq. 13), above ``threshold``, and whether the runner-up is within ``margin``;
    the best and runner-up are the first and second entries of a stable descending sort
    (ties: lower index first; NaN last)."""
    best, runner = -1, -1
    for k in range(scores.shape[0]):
        v = scores[k]
        if np.isnan(v):  # NaN sorts last
            continue
        if best < 0 or v > scores[best]:
            runner, best = best, k
        elif runner < 0 or v > scores[runner]:
            runner = k
    if best < 0 or not np.isfinite(scores[best]) or scores[best] < threshold:
        return -1, -1, False
    if runner >= 0 and not np.isfinite(scores[runner]):
        runner = -1
    amb = runner >= 0 and scores[runner] >= threshold and scores[best] < margin * scores[runner]
    return best, runner, amb


@numba.njit(cache=True)
def _ambiguous_rows_kernel(scores: np.ndarray, threshold: float, margin: float,
                           best: np.ndarray, runner: np.ndarray, amb: np.ndarray) -> None:
    """``_ambiguous_kernel`` of every row of (T, N) scores into best, runner, amb (T,)."""
    for t in range(scores.shape[0]):
        best[t], runner[t], amb[t] = _ambiguous_kernel(scores[t], threshold, margin)


# ----------------------------------------------------------------------------- tracker.py


@numba.njit(cache=True)
def _held(dof: np.ndarray, t: int, region: np.ndarray, ratio: float) -> bool:  # pragma: no cover
    """At least ``ratio`` of target t's box (dof columns 0, 1, 4, 5) lies inside ``region``
    (``geometry.overlap_ratio_matrix``)."""
    area = dof[t, 4] * dof[t, 5]
    w = min(dof[t, 0] + dof[t, 4], region[0] + region[2]) - max(dof[t, 0], region[0])
    h = min(dof[t, 1] + dof[t, 5], region[1] + region[3]) - max(dof[t, 1], region[1])
    inter = max(w, 0.0) * max(h, 0.0)
    return (inter / area if area > 0 else 0.0) >= ratio


@numba.njit(cache=True)
def _lone_growth(kinds: np.ndarray, regions: np.ndarray, heads_in_region: np.ndarray,
                 dof: np.ndarray, present: np.ndarray, ratio: float) -> None:  # pragma: no cover
    """``gated_pairs``' lone growth, in place on ``kinds``."""
    T, N = kinds.shape
    for n in range(N):
        if heads_in_region[n] > 1:
            continue
        owner, holders = -1, 0
        for t in range(T):
            if present[t] and _held(dof, t, regions[n], ratio):
                owner, holders = t, holders + 1
        if holders == 1 and kinds[owner, n] > 0:
            kinds[owner, n] = 0


@numba.njit(cache=True)
def gated_pairs(boxes: np.ndarray, regions: np.ndarray, heads: np.ndarray,
                heads_in_region: np.ndarray, grown_heads: np.ndarray, gates: np.ndarray,
                pred_wh: np.ndarray, kinds: np.ndarray, dof: np.ndarray, misses: np.ndarray,
                search_overlap: float, present: np.ndarray,
                several_heads_merge: bool) -> tuple:  # pragma: no cover (compiled)
    """Gating (PBM 3) and the occlusion test's pairs (PBM 3.1) of T targets and N candidates.

    A candidate is in target t's gate (xywh ``gates[t]``) when its box centre
    ``box[:2] + 0.5 box[2:]`` lies in it (borders included). ``kinds`` (T, N) (0, +1
    larger, -1 smaller; ``search.occlusion_kinds``) is set to +1 in place where it is 0
    and the candidate's region holds several heads (a merge) when ``several_heads_merge``
    (an adaptation; the paper's occlusion test is by size alone, PBM 3.1). The occluded pairs keep only
    those whose carved candidate lies in the gate too (head x, head y + 0.5 KF2 height)
    and, when ``search_overlap`` > 0, whose larger region holds the target: a smaller
    region, a target missed last frame, or ``geometry.overlap_ratio_matrix(boxes of dof,
    regions)[t, n] >= search_overlap``.

    Lone growth (adaptation): a region larger only by size (one head by ``grown_heads``,
    which may count more than ``heads_in_region``: ``candidates.HeldDetections``) that
    holds target t and no other ``present`` target (both by ``search_overlap`` of their
    boxes) is t itself, grown (entering through a border or a doorway, coming closer), not
    a merge: the pair is unoccluded (kind 0). ``present`` all False: never.

    Args:
        boxes, regions: (N, 4) xywh candidate boxes and regions. heads: (N, 3) heads.
        heads_in_region: (N,) int. grown_heads: (N,) int, the heads lone growth counts.
        gates: (T, 4) xywh. pred_wh: (T, 2) KF2 (w, h).
        dof: (T, 6) the targets' global models (xtl, ytl, xc, yc, w, h). misses: (T,) int.
        present: (T,) bool, the targets whose boxes can hold a region (found or recently
            missed).
    Returns:
        (ti, n) of the unoccluded pairs in the gates, then (ti, n, kind) of the occluded
        pairs to search or align, each in row-major order (as ``np.nonzero``).
    """
    T, N = kinds.shape
    if search_overlap > 0:
        _lone_growth(kinds, regions, grown_heads, dof, present, search_overlap)
    inside = np.zeros((T, N), np.bool_)
    n_in, n_occ = 0, 0
    for t in range(T):
        gx0, gy0 = gates[t, 0], gates[t, 1]
        gx1, gy1 = gx0 + gates[t, 2], gates[t, 3] + gy0
        for n in range(N):
            if several_heads_merge and kinds[t, n] == 0 and heads_in_region[n] > 1:
                kinds[t, n] = 1
            cx = boxes[n, 0] + 0.5 * boxes[n, 2]
            cy = boxes[n, 1] + 0.5 * boxes[n, 3]
            if gx0 <= cx <= gx1 and gy0 <= cy <= gy1:
                inside[t, n] = True
                if kinds[t, n] == 0:
                    n_in += 1
                else:
                    n_occ += 1
    ti_in, n_in_ = np.empty(n_in, np.intp), np.empty(n_in, np.intp)
    ti_s, n_s, kind_s = np.empty(n_occ, np.intp), np.empty(n_occ, np.intp), np.empty(n_occ, np.int64)
    a, b = 0, 0
    for t in range(T):
        gx0, gy0 = gates[t, 0], gates[t, 1]
        gx1, gy1 = gx0 + gates[t, 2], gates[t, 1] + gates[t, 3]
        for n in range(N):
            if not inside[t, n]:
                continue
            kind = kinds[t, n]
            if kind == 0:
                ti_in[a], n_in_[a] = t, n
                a += 1
                continue
            hx, hy = heads[n, 0], heads[n, 1] + 0.5 * pred_wh[t, 1]
            if not (gx0 <= hx <= gx1 and gy0 <= hy <= gy1):
                continue
            if (search_overlap > 0 and kind > 0 and misses[t] <= 0
                    and not _held(dof, t, regions[n], search_overlap)):
                continue
            ti_s[b], n_s[b], kind_s[b] = t, n, kind
            b += 1
    return ti_in, n_in_, ti_s[:b], n_s[:b], kind_s[:b]


@numba.njit(cache=True)
def matched_rows(mt: np.ndarray, mn: np.ndarray, hyp: np.ndarray, boxes: np.ndarray,
                 centroid: np.ndarray, blob: np.ndarray, pred_wh: np.ndarray, alpha: np.ndarray,
                 pj_all: np.ndarray, dof_h: np.ndarray, pj_h: np.ndarray, k_h: np.ndarray
                 ) -> tuple:  # pragma: no cover (compiled)
    """The chosen candidates of M matched (target mt, candidate mn) pairs, as the model
    update (PBM 4.2) takes them: (dof (M, 6), p_j (M, 5), occluded (M,) bool, index (M,)
    in the features the candidate was measured in).

    An occluded pair (``hyp[t, n]`` >= 0, a row of the search's ``dof_h``, ``pj_h``,
    ``k_h``) takes the carved box's; an unoccluded one its own box and centroid
    (xtl, ytl, xc, yc, w, h) and ``pj_all[t, n]``, except that a blob keeps KF2's width
    (its span follows the swinging limbs, PBM 3): w = ``pred_wh[t, 0]``, xtl = xc - alpha w
    (eq. 1).
    """
    M = mt.shape[0]
    dof = np.empty((M, 6))
    pj = np.empty((M, pj_all.shape[2]))
    occluded = np.empty(M, np.bool_)
    ks = np.empty(M, np.int64)
    for q in range(M):
        t, n = mt[q], mn[q]
        h = hyp[t, n]
        occluded[q] = h >= 0
        if h >= 0:
            dof[q] = dof_h[h]
            pj[q] = pj_h[h]
            ks[q] = k_h[h]
            continue
        dof[q, 0], dof[q, 1], dof[q, 4], dof[q, 5] = boxes[n, 0], boxes[n, 1], boxes[n, 2], boxes[n, 3]
        dof[q, 2], dof[q, 3] = centroid[n, 0], centroid[n, 1]
        if blob[n]:
            w = pred_wh[t, 0]
            dof[q, 0] = centroid[n, 0] - alpha[t] * w
            dof[q, 4] = w
        pj[q] = pj_all[t, n]
        ks[q] = n
    return dof, pj, occluded, ks


@numba.njit(cache=True)
def alive_rows(dof: np.ndarray, shift: np.ndarray, misses: np.ndarray, confirmed: np.ndarray,
               width: int, height: int, margin: float, max_misses: int, exit_misses: int
               ) -> np.ndarray:  # pragma: no cover (compiled)
    """(T,) bool: the targets kept after this frame (the tracker's life cycle): found, or
    confirmed and unfound for at most ``max_misses`` frames, unless unfound for
    ``exit_misses`` frames with the box (dof columns 0, 1, 4, 5) moved by ``shift`` (T, 2)
    (KF1's prediction since it was last found) more than ``margin`` beyond an image border
    (it left; a person standing at the border is not leaving)."""
    T = misses.shape[0]
    alive = np.empty(T, np.bool_)
    for t in range(T):
        x, y = dof[t, 0] + shift[t, 0], dof[t, 1] + shift[t, 1]
        x1, y1 = x + dof[t, 4], y + dof[t, 5]
        gone = x < -margin or y < -margin or x1 > width + margin or y1 > height + margin
        alive[t] = misses[t] == 0 or (confirmed[t] and misses[t] <= max_misses
                                      and not (gone and misses[t] >= exit_misses))
    return alive


@numba.njit(cache=True)
def carved_rows(p: np.ndarray, pj: np.ndarray, boxes: np.ndarray, heads: np.ndarray,
                ti: np.ndarray, alpha: np.ndarray, beta: np.ndarray, search_q: np.ndarray,
                align_q: np.ndarray, m: int) -> tuple:  # pragma: no cover (compiled)
    """The occluded candidates of P (target ti, head) pairs (PBM 3.1) from the scores of
    the carved boxes: searched pair ``search_q[s]`` owns boxes s m .. s m + m - 1 (eqs.
    9-10) and keeps the best (``np.argmax``: the first maximum); aligned pair
    ``align_q[a]`` owns box len(search_q) m + a. Pairs in neither are dismissed.

    Returns:
        kept (P,) bool, p (P,), p_j (P, 5), box index k (P,) and the DOF under occlusion
        (P, 6) (``_dof_from_head``, eqs. 1-2, of the head with the box's w, h and the
        target's alpha, beta).
    """
    P = ti.shape[0]
    kept = np.zeros(P, np.bool_)
    k = np.zeros(P, np.int64)
    for s in range(search_q.shape[0]):
        b = s * m
        if not np.isnan(p[b]):
            for j in range(s * m + 1, s * m + m):
                if np.isnan(p[j]):
                    b = j
                    break
                if p[j] > p[b]:
                    b = j
        kept[search_q[s]] = True
        k[search_q[s]] = b
    for a in range(align_q.shape[0]):
        kept[align_q[a]] = True
        k[align_q[a]] = search_q.shape[0] * m + a
    p_out = np.zeros(P)
    pj_out = np.zeros((P, pj.shape[1]))
    dof = np.zeros((P, 6))
    for q in range(P):
        if not kept[q]:
            continue
        b, t = k[q], ti[q]
        p_out[q] = p[b]
        pj_out[q] = pj[b]
        _dof_from_head(heads[q, 0], heads[q, 1], boxes[b, 2], boxes[b, 3], alpha[t], beta[t],
                       dof[q])                                               # eqs. 1-2
    return kept, p_out, pj_out, k, dof
