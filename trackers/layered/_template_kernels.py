"""Compiled normalisation of PBM 4.1's head-template match (``search.match_head_template``),
kept because ``benchmarks/bench_pbm.py`` shows the match is the largest cost of the pruning:
``ccoeff_normed`` is ``cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED)`` for 8-bit
grey images, bit for bit (tested against it), made from OpenCV's own raw correlation
(``cv2.TM_CCORR``) and template statistics (``cv2.meanStdDev``) by OpenCV's normalisation
(``common_matchTemplate`` of ``modules/imgproc/src/templmatch.cpp``, one channel), the same
double operations in the same order, with its loop vectorised. The tracker takes only the
best corner (``best_ccoeff_normed``: ``cv2.minMaxLoc`` of that map, bit for bit), and scores
only the corners that may beat the best of the rows before (a bound on R^2 without its
square root and division). None calls a kernel of another file.

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

_BOUND_MARGIN = 1.0 - 1e-6
"""``_best_ccoeff_normed``'s margin on a corner's squared R: a corner is left unscored only when
its R lies below the best by far more than the products' and float32's rounding (< 1e-7)."""

_INT32_ROWS = np.iinfo(np.int32).max // 255**2
"""The tallest template whose window columns' sums of I^2 (at most 255^2 th) ``_ccoeff_normed``
holds in int32; a taller one is left to OpenCV."""


@numba.njit(cache=True, inline="always", error_model="numpy")
def _coefficient(raw: float, t: float, w2: float, mean: float, inv_area: float,
                 norm: float) -> np.float32:
    """R at one corner: ``raw`` its float32 cross-correlation, ``t`` and ``w2`` the window's
    sums of I and I^2 (exact integers), OpenCV's operations and clamps (module docstring)."""
    num = np.float64(raw) - t * mean
    diff2 = w2 - (t * t) * inv_area
    diff2 = diff2 if diff2 >= 0.0 else 0.0
    floor = _FLT_EPSILON_10 * w2
    floor = floor if floor < 0.5 else 0.5
    den = math.sqrt(diff2) * norm
    den = 0.0 if diff2 <= floor else den
    a = abs(num)
    clamp = (1.0 if num > 0 else -1.0) if a < den * 1.125 else 0.0
    return np.float32(num / den if a < den else clamp)


@numba.njit(cache=True, inline="always", error_model="numpy")
def _normalise_row(raw: np.ndarray, ps: np.ndarray, pq: np.ndarray, tw: int, mean: float,
                   inv_area: float, norm: float) -> None:
    """One result row of ``_ccoeff_normed`` in place: ``raw`` (C',) float32 cross-correlations,
    ``ps``, ``pq`` (C + 1,) the row's prefix sums of the window columns' sums of I and I^2.
    numpy's error model: no test of a zero divisor, so the loop is vectorised (a 0 divisor's
    quotient is never kept)."""
    for j in range(raw.shape[0]):
        raw[j] = _coefficient(raw[j], ps[j + tw] - ps[j], pq[j + tw] - pq[j], mean, inv_area, norm)


@numba.njit(cache=True, inline="always")
def _norm(th: int, tw: int, sdv: float) -> tuple[float, float]:
    """(1 / n, s_T sqrt(n)) of a (th, tw) template of standard deviation ``sdv``, as OpenCV
    computes them; the second is 0 for a flat template (variance below DBL_EPSILON)."""
    inv_area = 1.0 / (float(th) * float(tw))
    norm = sdv * sdv
    if norm < _DBL_EPSILON:
        return inv_area, 0.0
    norm = math.sqrt(norm)
    norm /= math.sqrt(inv_area)
    return inv_area, norm


@numba.njit(cache=True, inline="always")
def _first_rows(image: np.ndarray, th: int, cs: np.ndarray, cq: np.ndarray) -> None:
    """The window columns' sums of I and I^2 over the first th rows into ``cs``, ``cq`` (C,)
    int32 (at most 255^2 th)."""
    for y in range(th):
        for x in range(image.shape[1]):
            v = np.int32(image[y, x])
            cs[x] += v
            cq[x] += v * v


@numba.njit(cache=True, inline="always")
def _next_row(image: np.ndarray, i: int, th: int, cs: np.ndarray, cq: np.ndarray,
              ps: np.ndarray, pq: np.ndarray) -> None:
    """Result row i's sums: the columns' sums slid down to rows i .. i + th - 1 (i > 0), then
    their prefix sums along the row into ``ps``, ``pq`` (C + 1,) (int64 sums, exact)."""
    if i > 0:
        for x in range(image.shape[1]):
            a, b = np.int32(image[i - 1, x]), np.int32(image[i + th - 1, x])
            cs[x] += b - a
            cq[x] += b * b - a * a
    s, q = np.int64(0), np.int64(0)
    for x in range(image.shape[1]):
        s += cs[x]
        q += cq[x]
        ps[x + 1] = s
        pq[x + 1] = q


@numba.njit(cache=True, error_model="numpy")
def _ccoeff_normed(image: np.ndarray, th: int, tw: int, raw: np.ndarray, mean: float,
                   sdv: float) -> None:
    """TM_CCOEFF_NORMED into ``raw`` (R', C') float32, which holds the raw cross-correlation
    of ``image`` (R, C) uint8 with a (th, tw) template of mean ``mean`` and standard deviation
    ``sdv`` (``cv2.meanStdDev``). The windows' sums: column sums over th rows (int32: at
    most 255^2 th), slid down a row at a time, and their prefix sums along the row (int64),
    exact integers as OpenCV's integral images hold them."""
    C = image.shape[1]
    inv_area, norm = _norm(th, tw, sdv)
    if norm == 0.0:
        raw[:, :] = 1.0
        return
    cs, cq = np.zeros(C, np.int32), np.zeros(C, np.int32)
    ps, pq = np.zeros(C + 1), np.zeros(C + 1)
    _first_rows(image, th, cs, cq)
    for i in range(raw.shape[0]):
        _next_row(image, i, th, cs, cq, ps, pq)
        _normalise_row(raw[i], ps, pq, tw, mean, inv_area, norm)


@numba.njit(cache=True, error_model="numpy")
def _best_ccoeff_normed(image: np.ndarray, th: int, tw: int, raw: np.ndarray, mean: float,
                        sdv: float) -> tuple[int, int, float]:
    """The best corner (x, y) of ``_ccoeff_normed``'s result and its R (the first in raster
    order on ties, as ``cv2.minMaxLoc``), with R computed only where it may beat the best
    of the rows before: once that best b is above 0, a corner with num <= 0 has R <= 0, and
    one with num^2 < b^2 s_T^2 n (1 - 1e-6) (sum I^2 - (sum I)^2 / n) has R below b by
    more than float32's rounding (the squares need no square root nor division; module
    docstring's R). ``raw`` is left as the raw cross-correlation."""
    C = image.shape[1]
    inv_area, norm = _norm(th, tw, sdv)
    if norm == 0.0:
        return 0, 0, 1.0  # R = 1 everywhere
    cs, cq = np.zeros(C, np.int32), np.zeros(C, np.int32)
    ps, pq = np.zeros(C + 1), np.zeros(C + 1)
    may = np.zeros(raw.shape[1], np.bool_)
    _first_rows(image, th, cs, cq)
    best, bx, by = -np.inf, 0, 0
    for i in range(raw.shape[0]):
        _next_row(image, i, th, cs, cq, ps, pq)
        row = raw[i]
        if best > 0.0:  # the corners that may beat it, in a vectorised pass
            bound = best * best * (norm * norm) * _BOUND_MARGIN
            n = 0
            for j in range(row.shape[0]):
                t = ps[j + tw] - ps[j]
                num = np.float64(row[j]) - t * mean
                diff2 = (pq[j + tw] - pq[j]) - (t * t) * inv_area
                m = (num > 0.0) & (num * num >= bound * diff2)
                may[j] = m
                n += m
            if n == 0:
                continue
        else:
            may[:] = True
        for j in range(row.shape[0]):
            if may[j]:
                r = np.float64(_coefficient(row[j], ps[j + tw] - ps[j], pq[j + tw] - pq[j],
                                            mean, inv_area, norm))
                if r > best:
                    best, bx, by = r, j, i
        if best >= 1.0:  # R is at most 1: no later corner is above it
            break
    return bx, by, best


def _checked(image: np.ndarray, template: np.ndarray, name: str) -> None:
    """Raise ValueError unless ``image`` (R, C) and ``template`` (th, tw) are uint8 grey
    images with th <= R, tw <= C."""
    if image.ndim != 2 or template.ndim != 2 or image.dtype != np.uint8 or template.dtype != np.uint8:
        raise ValueError(f"{name}: (R, C) and (th, tw) uint8 images expected, got "
                         f"{image.dtype} {image.shape} and {template.dtype} {template.shape}")
    if template.shape[0] > image.shape[0] or template.shape[1] > image.shape[1]:
        raise ValueError(f"{name}: template {template.shape} larger than image {image.shape}")


def ccoeff_normed(image: np.ndarray, template: np.ndarray) -> np.ndarray:
    """``cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED)`` of a (R, C) uint8 grey
    image and a (th, tw) uint8 grey template (th <= R, tw <= C), bit for bit: (R - th + 1,
    C - tw + 1) float32 (every corner's R; the tracker takes only the best,
    ``best_ccoeff_normed``)."""
    _checked(image, template, "ccoeff_normed")
    th, tw = template.shape
    if th > _INT32_ROWS:
        return cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED)
    raw = cv2.matchTemplate(image, template, cv2.TM_CCORR)
    mean, sdv = cv2.meanStdDev(template)
    _ccoeff_normed(image, th, tw, raw, float(mean[0, 0]), float(sdv[0, 0]))
    return raw


def best_ccoeff_normed(image: np.ndarray, template: np.ndarray) -> tuple[int, int, float]:
    """``cv2.minMaxLoc(cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED))``'s best
    corner (x, y) and its score (the float32 as a float), bit for bit, for a (R, C) uint8
    grey image and a (th, tw) uint8 grey template (th <= R, tw <= C); only the corners
    that may beat the best so far are scored (``_best_ccoeff_normed``)."""
    _checked(image, template, "best_ccoeff_normed")
    th, tw = template.shape
    if th > _INT32_ROWS:
        _, best, _, (x, y) = cv2.minMaxLoc(cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED))
        return x, y, best
    raw = cv2.matchTemplate(image, template, cv2.TM_CCORR)
    mean, sdv = cv2.meanStdDev(template)
    return _best_ccoeff_normed(image, th, tw, raw, float(mean[0, 0]), float(sdv[0, 0]))
