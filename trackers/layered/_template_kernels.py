"""Compiled normalisation of PBM 4.1's head-template match (``search.match_head_template``),
kept because ``benchmarks/bench_pbm.py`` shows the match is the largest cost of the pruning:
``ccoeff_normed`` is ``cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED)`` for 8-bit
grey images, bit for bit (tested against it), made from OpenCV's own raw correlation
(``cv2.TM_CCORR``) and template statistics (``cv2.meanStdDev``) by OpenCV's normalisation
(``common_matchTemplate`` of ``modules/imgproc/src/templmatch.cpp``, one channel), the same
double operations in the same order, with its loop vectorised. None calls a kernel of
another file.

TM_CCOEFF_NORMED at a top-left corner (x, y), with T the template (n = th tw pixels, mean
m_T, standard deviation s_T) and I the image window under it:

    R = (sum T I - m_T sum I) / (sqrt(sum I^2 - (sum I)^2 / n) * s_T sqrt(n))

where OpenCV takes sum T I from its cross-correlation, sum I and sum I^2 from integral
images (exact integers here, as in its doubles), and clamps: a window of nearly no variance
(``sum I^2 - (sum I)^2 / n <= min(0.5, 10 FLT_EPSILON sum I^2)``) has a denominator 0; a
numerator not below the denominator gives +-1 when within 1.125 of it, else 0; a template
of variance below DBL_EPSILON gives 1 everywhere.
"""

from __future__ import annotations

import math

import cv2
import numba
import numpy as np

_FLT_EPSILON_10 = float(np.float32(10) * np.finfo(np.float32).eps)
"""C++'s ``10 * FLT_EPSILON``, a float product (OpenCV's window-variance floor)."""

_DBL_EPSILON = float(np.finfo(np.float64).eps)

_INT32_ROWS = np.iinfo(np.int32).max // 255**2
"""The tallest template whose window columns' sums of I^2 (at most 255^2 th) ``_ccoeff_normed``
holds in int32; a taller one is left to OpenCV."""


@numba.njit(cache=True, inline="always", error_model="numpy")
def _normalise_row(raw: np.ndarray, ps: np.ndarray, pq: np.ndarray, tw: int, mean: float,
                   inv_area: float, norm: float) -> None:
    """One result row of ``_ccoeff_normed`` in place: ``raw`` (C',) float32 cross-correlations,
    ``ps``, ``pq`` (C + 1,) the row's prefix sums of the window columns' sums of I and I^2.
    numpy's error model: no test of a zero divisor, so the loop is vectorised (a 0 divisor's
    quotient is never kept)."""
    for j in range(raw.shape[0]):
        t = ps[j + tw] - ps[j]                       # sum I (exact)
        w2 = pq[j + tw] - pq[j]                      # sum I^2 (exact)
        num = np.float64(raw[j]) - t * mean
        diff2 = w2 - (t * t) * inv_area
        diff2 = diff2 if diff2 >= 0.0 else 0.0
        floor = _FLT_EPSILON_10 * w2
        floor = floor if floor < 0.5 else 0.5
        den = math.sqrt(diff2) * norm
        den = 0.0 if diff2 <= floor else den
        a = abs(num)
        clamp = (1.0 if num > 0 else -1.0) if a < den * 1.125 else 0.0
        raw[j] = np.float32(num / den if a < den else clamp)


@numba.njit(cache=True, error_model="numpy")
def _ccoeff_normed(image: np.ndarray, th: int, tw: int, raw: np.ndarray, mean: float,
                   sdv: float) -> None:
    """TM_CCOEFF_NORMED into ``raw`` (R', C') float32, which holds the raw cross-correlation
    of ``image`` (R, C) uint8 with a (th, tw) template of mean ``mean`` and standard deviation
    ``sdv`` (``cv2.meanStdDev``). The windows' sums: column sums over th rows (int32: at
    most 255^2 th), slid down a row at a time, and their prefix sums along the row (int64),
    exact integers as OpenCV's integral images hold them."""
    C = image.shape[1]
    inv_area = 1.0 / (float(th) * float(tw))
    norm = sdv * sdv
    if norm < _DBL_EPSILON:
        raw[:, :] = 1.0
        return
    norm = math.sqrt(norm)
    norm /= math.sqrt(inv_area)
    cs, cq = np.zeros(C, np.int32), np.zeros(C, np.int32)
    ps, pq = np.zeros(C + 1), np.zeros(C + 1)
    for y in range(th):
        for x in range(C):
            v = np.int32(image[y, x])
            cs[x] += v
            cq[x] += v * v
    for i in range(raw.shape[0]):
        if i > 0:
            for x in range(C):
                a, b = np.int32(image[i - 1, x]), np.int32(image[i + th - 1, x])
                cs[x] += b - a
                cq[x] += b * b - a * a
        s, q = np.int64(0), np.int64(0)
        for x in range(C):
            s += cs[x]
            q += cq[x]
            ps[x + 1] = s
            pq[x + 1] = q
        _normalise_row(raw[i], ps, pq, tw, mean, inv_area, norm)


def ccoeff_normed(image: np.ndarray, template: np.ndarray) -> np.ndarray:
    """``cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED)`` of a (R, C) uint8 grey
    image and a (th, tw) uint8 grey template (th <= R, tw <= C), bit for bit: (R - th + 1,
    C - tw + 1) float32."""
    if image.ndim != 2 or template.ndim != 2 or image.dtype != np.uint8 or template.dtype != np.uint8:
        raise ValueError(f"ccoeff_normed: (R, C) and (th, tw) uint8 images expected, got "
                         f"{image.dtype} {image.shape} and {template.dtype} {template.shape}")
    th, tw = template.shape
    if th > image.shape[0] or tw > image.shape[1]:
        raise ValueError(f"ccoeff_normed: template {template.shape} larger than image {image.shape}")
    if th > _INT32_ROWS:
        return cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED)
    raw = cv2.matchTemplate(image, template, cv2.TM_CCORR)
    mean, sdv = cv2.meanStdDev(template)
    _ccoeff_normed(image, th, tw, raw, float(mean[0, 0]), float(sdv[0, 0]))
    return raw
