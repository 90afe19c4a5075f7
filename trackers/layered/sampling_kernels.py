"""PBM 2.1-2.2, compiled: the part features of boxes measured on a fixed grid of samples
(``part_features``; ``reading:sample_grid``) and the foreground centroid of a box
(``grid_centroids``), colours converted as OpenCV converts them (``colour_kernels``). The
extractor that calls them is ``occbench.trackers.layered.parts.PartFeatureExtractor``.

In the per-sample loops, indices read from arrays are cast to unsigned (``np.uint64``):
numba then drops its negative-index test. Grouped arguments are tuples: a feature set is
``(parts, area, perimeter, hsv, xyz, centroid, height)`` (``PartFeatures``' arrays).
"""

from __future__ import annotations

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)
from occbench.trackers.layered.colour_kernels import _pixel_packed
from occbench.trackers.layered.split import _centroid_ratios, _part_rects

if numba.config.DISABLE_JIT:  # plain Python (tests/traced_run.py): numba's intrinsic cannot run

    def trailing_zeros(bits: np.uint64) -> int:
        """Index of the lowest set bit of ``bits`` (> 0), as numba's intrinsic."""
        b = int(bits)
        return (b & -b).bit_length() - 1

else:
    from numba.cpython.unsafe.numbers import trailing_zeros


# ----------------------------------------------------------------------------- the sample grid


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
    """The scratch of ``_box_counts`` for an R x C sample grid (C <= ``MAX_GRID_COLS``) and
    nb-bin histograms: the grid (ys, xs, yi, xi, on, band, right, coff), the per-part sums
    (count, edge, sx, sy), the joint-bin counts hist (2, 5, nb) int64 (HSV, XYZ; zero
    between boxes), the occupied bins of each count row as a bit mask (2, 5) uint64 (bin u:
    bit u; kept when nb <= 64) and the foreground samples of each grid row as a bit mask
    (R,) uint64 (column c: bit c; ``_row_masks``)."""
    return (np.empty(R), np.empty(C), np.empty(R, np.int64), np.empty(C, np.int64),
            np.empty((R, C), np.uint8), np.empty(R, np.int64), np.empty(C, np.int64),
            np.empty(C, np.uint64), np.zeros(5, np.int64), np.zeros(5, np.int64), np.zeros(5),
            np.zeros(5), np.zeros((2, 5, nb), np.int64), np.zeros((2, 5), np.uint64),
            np.empty(R, np.uint64))


@numba.njit(cache=True, inline="always")
def _row_masks(on: np.ndarray, masks: np.ndarray) -> None:
    """The foreground flags ``on`` (R, C) (``_sample_grid``) of each grid row as a bit mask
    into masks (R,) uint64 (column c: bit c; C <= ``MAX_GRID_COLS``)."""
    for r in range(on.shape[0]):
        b = np.uint64(0)
        for c in range(on.shape[1]):
            b |= np.uint64(on[r, c]) << np.uint64(c)
        masks[r] = b


@numba.njit(cache=True, inline="always")
def _bands(ys: np.ndarray, head_end: float, torso_end: float, band: np.ndarray
           ) -> tuple[int, int, int]:
    """The band of each sample row ``ys`` into ``band``: 0 above the head's bottom, 1 above
    the torsos' bottom, 3 below (ties go down); returns the rows of each band."""
    rows_head, rows_torso, rows_legs = 0, 0, 0
    for r in range(ys.shape[0]):
        if ys[r] < head_end:
            band[r] = 0
            rows_head += 1
        elif ys[r] < torso_end:
            band[r] = 1
            rows_torso += 1
        else:
            band[r] = 3
            rows_legs += 1
    return rows_head, rows_torso, rows_legs


@numba.njit(cache=True, inline="always")
def _sides(xs: np.ndarray, split: float, right: np.ndarray) -> tuple[np.uint64, int]:
    """Whether each sample column ``xs`` is right of the split (ties go right) into
    ``right``; returns them as a bit mask (column c: bit c) and their number."""
    right_mask, cols_right = np.uint64(0), 0
    for c in range(xs.shape[0]):
        right[c] = 1 if xs[c] >= split else 0
        cols_right += right[c]
        right_mask |= np.uint64(right[c]) << np.uint64(c)
    return right_mask, cols_right


@numba.njit(cache=True, inline="always")
def _count_rows(masks: np.ndarray, band: np.ndarray, yi: np.ndarray, W: int, coff: np.ndarray,
                right_mask: np.uint64, xs: np.ndarray, ys: np.ndarray, table: np.ndarray,
                colours: tuple, s: tuple) -> None:
    """The foreground samples of a box's grid rows (``masks`` (R,), ``_row_masks``) counted
    into the scratch ``s`` (``_box_scratch``): row r in part ``band[r]`` (0 head, 1 torso,
    3 legs; the right half one more where ``right_mask`` is set), sample (r, c) at
    ``(xs[c], ys[r])`` on pixel ``yi[r] W + coff[c]`` of the bin ``table``
    (``_pixel_packed``). A row's foreground samples left of the split, then those right of
    it (the two parts' sums are separate, each in sample order, as
    ``np.bincount(weights=...)``); the outline samples are those whose row's and neighbour
    rows' masks are not all set around them."""
    count, edge, sx, sy, hist, occupied = s[8], s[9], s[10], s[11], s[12], s[13]
    st, sh = colours[2], colours[3]
    sh2 = sh + sh
    bin_mask = (np.uint64(1) << sh) - np.uint64(1)
    zero, one, low = np.uint64(0), np.uint64(1), np.uint64(63)
    R = masks.shape[0]
    count[:] = 0
    edge[:] = 0
    sx[:] = 0.0
    sy[:] = 0.0
    occupied[:] = 0
    for r in range(R):
        row = masks[r]
        up = masks[r - 1] if r > 0 else zero
        down = masks[r + 1] if r < R - 1 else zero
        outline = row & ~(up & down & (row << one) & (row >> one))  # bits 0, C - 1: always
        kl = band[r]
        kr = kl + 1 if kl > 0 else 0  # the same part in the head band
        roff = np.uint64(yi[r] * W)
        for side in range(2):
            if kr == kl:
                if side == 1:
                    break
                bits, k = row, kl
            elif side == 0:
                bits, k = row & ~right_mask, kl
            else:
                bits, k = row & right_mask, kr
            # the part's sums carried in registers through the row, in sample order
            n, e, sxk, syk = count[k], edge[k], sx[k], sy[k]
            hk, xk = occupied[0, k], occupied[1, k]
            while bits != zero:
                c = trailing_zeros(bits)
                bits &= bits - one
                # the pixel's bins (its index unsigned: no negative-index test)
                q = roff + coff[c]
                packed = np.uint64(table[q])
                if (packed >> sh2) != st:  # first read this frame: convert it
                    packed = _pixel_packed(q, table, colours)
                hsv_bin, xyz_bin = (packed >> sh) & bin_mask, packed & bin_mask
                n += 1
                e += np.int64((outline >> np.uint64(c)) & one)
                sxk += xs[c]  # in sample order, as np.bincount(weights=...)
                syk += ys[r]
                hk |= one << (hsv_bin & low)
                xk |= one << (xyz_bin & low)
                hist[0, k, hsv_bin] += 1
                hist[1, k, xyz_bin] += 1
            count[k], edge[k], sx[k], sy[k] = n, e, sxk, syk
            occupied[0, k], occupied[1, k] = hk, xk


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

    A grid row is walked as a bit mask (``_row_masks``, ``_count_rows``).
    """
    fr, fc = grid
    frame, fg, has_fg = image
    table, stamp, shift = pixel_bins
    sh, st = np.uint64(shift), np.uint64(stamp)
    ys, xs, yi, xi, on, band, right, coff, masks = s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[14]
    H, W = frame.shape[0], frame.shape[1]
    R, C = fr.shape[0], fc.shape[0]
    pixels = frame.reshape(H * W * 3)
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
    rows_head, rows_torso, rows_legs = _bands(ys, head_end, torso_end, band)
    right_mask, cols_right = _sides(xs, split, right)
    _row_masks(on, masks)
    _count_rows(masks, band, yi, W, coff, right_mask, xs, ys, table, (pixels, luts, st, sh), s)
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
        pixel_bins: ((H * W,) uint32, stamp, shift) (``parts.PixelBins``): each pixel's
            joint bins ``stamp << 2 shift | hsv_bin << shift | xyz_bin`` once a sample of
            this frame read it (shift: the bits of a joint bin): the boxes of a frame share
            most of their pixels (the search's boxes around one head), whose colour
            conversion is then done once per frame; an entry of another stamp (>= 1, the
            caller's count of frames, the table zeroed when it wraps) is stale, so nothing
            is reset between frames.
    """
    parts = out[0]
    s = _box_scratch(grid[0].shape[0], grid[1].shape[0], out[3].shape[2])
    for i in range(boxes.shape[0]):
        bands = _box_counts(boxes, i, alpha, beta, at_centroids, centres, grid, image, luts,
                            pixel_bins, s, parts[i])
        _box_features(s, bands, parts[i], i, out[1:])


_NO_CENTRES = np.zeros((0, 2))
"""``_box_counts``' centroid output when it is given the ratios (never written)."""
