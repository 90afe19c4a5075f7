"""OpenCV's 8-bit BGR to HSV and XYZ conversions, compiled (``_hsv_xyz``, ``convert``), and
the pixel-bin table entry made from them (``_pixel_packed``): the colours of PBM 2.2's
histograms, for ``sampling_kernels``. ``parts._check_colour_formulas`` checks them against
``cv2.cvtColor``.
"""

from __future__ import annotations

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)

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


@numba.njit(cache=True)
def _pixel_packed(q: np.uint64, table: np.ndarray, colours: tuple) -> np.uint64:
    """Entry q of the pixel-bin table (``part_features``' ``pixel_bins``) made from its
    pixel's colour (``_hsv_xyz``, the luts) and written. ``colours``: (the frame's BGR bytes
    flat, luts, stamp, shift), the last two ``np.uint64``."""
    pixels, luts, st, sh = colours
    hsv_lut, xyz_lut = luts
    o = q * np.uint64(3)
    ch, cs, cv, cx, cy, cz = _hsv_xyz(np.int64(pixels[o]), np.int64(pixels[o + np.uint64(1)]),
                                      np.int64(pixels[o + np.uint64(2)]))
    packed = (st << (sh + sh)) | (np.uint64(
        hsv_lut[0, np.uint64(ch)] + hsv_lut[1, np.uint64(cs)] + hsv_lut[2, np.uint64(cv)]
    ) << sh) | np.uint64(
        xyz_lut[0, np.uint64(cx)] + xyz_lut[1, np.uint64(cy)] + xyz_lut[2, np.uint64(cz)])
    table[q] = np.uint32(packed)
    return packed
