"""Compiled kernels of ``trackers.layered.search`` (numba, one core).

The head-template match of PBM 4.1 (multiple-response pruning) runs coarse to fine:
``coarse_peaks`` scores TM_CCOEFF_NORMED on 2 x 2 block sums of the window and template
and keeps the best local maxima; ``ncc_climb`` climbs from each, at full resolution, to
a local maximum of the exact score. ``ncc_all`` scores every position (small windows).
Full-resolution scores use exact integer sums (held in float32 per row and float64
overall; every partial sum is an integer below 2^24 or 2^53) and OpenCV's conventions,
so they equal ``cv2.matchTemplate(..., TM_CCOEFF_NORMED)`` up to its float32 rounding.
"""

from __future__ import annotations

import numba
import numpy as np

_MARGIN = 3  # ncc_climb: climbing steps prepared around each start
_CHUNK = 256  # columns per float32 row sum: 256 x 255^2 < 2^24, so the sums stay exact


@numba.njit(cache=True, fastmath=True)
def _cross(reg: np.ndarray, tplf: np.ndarray, x: int, y: int) -> float:
    """sum(reg[y:y + th, x:x + tw] tplf) of float32 integers 0..255, exactly.

    Templates up to ``_CHUNK`` wide sum each row in float32 (every partial sum is an
    integer below 2^24: exact in any order, so ``fastmath`` may vectorise it) and the
    rows in float64; wider ones sum in float64 (exact below 2^53).
    """
    th, tw = tplf.shape
    total = 0.0
    for r in range(th):
        a = reg[y + r, x:x + tw]
        b = tplf[r]
        if tw <= _CHUNK:
            acc = np.float32(0.0)
            for c in range(tw):
                acc += a[c] * b[c]
            total += acc
        else:
            acc64 = 0.0
            for c in range(tw):
                acc64 += np.float64(a[c]) * np.float64(b[c])
            total += acc64
    return total


@numba.njit(cache=True)
def _region(win: np.ndarray, x0: int, y0: int, x1: int, y1: int, th: int, tw: int
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pixels under the top-left positions [x0, x1) x [y0, y1) of a (th, tw)
    template: float32 copy and exact float64 integral images of it and its square."""
    hr, wr = y1 - y0 + th - 1, x1 - x0 + tw - 1
    reg = np.empty((hr, wr), np.float32)
    s1 = np.zeros((hr + 1, wr + 1))
    s2 = np.zeros((hr + 1, wr + 1))
    for y in range(hr):
        a1 = 0.0
        a2 = 0.0
        for x in range(wr):
            v = win[y0 + y, x0 + x]
            reg[y, x] = v
            a1 += v
            a2 += np.float64(v) * v
            s1[y + 1, x + 1] = s1[y, x + 1] + a1
            s2[y + 1, x + 1] = s2[y, x + 1] + a2
    return reg, s1, s2


@numba.njit(cache=True)
def _score_in(reg: np.ndarray, s1: np.ndarray, s2: np.ndarray, ox: int, oy: int,
              tplf: np.ndarray, xa: int, ya: int, xb: int, yb: int, st: float, tnorm: float,
              seen: np.ndarray, score: np.ndarray) -> None:
    """TM_CCOEFF_NORMED at the window positions [xa, xb) x [ya, yb) not yet ``seen``,
    from a ``_region`` whose first position is (ox, oy); written into ``score``.

    OpenCV's conventions: |num| >= denominator gives 0, within 12.5% of it +-1.
    ``st``: template sum; ``tnorm``: sqrt of its sum of squared deviations.
    """
    th, tw = tplf.shape
    n = th * tw
    for yy in range(ya, yb):
        for xx in range(xa, xb):
            if seen[yy, xx]:
                continue
            x, y = xx - ox, yy - oy
            sc = _cross(reg, tplf, x, y)
            sw = s1[y + th, x + tw] - s1[y, x + tw] - s1[y + th, x] + s1[y, x]
            sw2 = s2[y + th, x + tw] - s2[y, x + tw] - s2[y + th, x] + s2[y, x]
            num = sc - sw * st / n
            d = np.sqrt(max(sw2 - sw * (sw / n), 0.0)) * tnorm
            if abs(num) < d:
                v = num / d
            elif abs(num) < d * 1.125:
                v = 1.0 if num > 0 else -1.0
            else:
                v = 0.0
            score[yy, xx] = v
            seen[yy, xx] = 1


@numba.njit(cache=True)
def _template_stats(tpl: np.ndarray) -> tuple[float, float]:
    """(sum, sqrt of the sum of squared deviations) of a uint8 template (exact sums)."""
    st = 0.0
    st2 = 0.0
    for r in range(tpl.shape[0]):
        for c in range(tpl.shape[1]):
            v = np.float64(tpl[r, c])
            st += v
            st2 += v * v
    return st, np.sqrt(max(st2 - st * (st / tpl.size), 0.0))


@numba.njit(cache=True)
def _block_sums(img: np.ndarray, f: int, h: int, w: int) -> np.ndarray:
    """(h, w) float32 sums of the f x f blocks (f = 2 or 3) of a C-contiguous uint8
    image (its top-left h f x w f)."""
    out = np.empty((h, w), np.float32)
    for y in range(h):
        a = img[f * y]
        b = img[f * y + 1]
        o = out[y]
        if f == 2:
            for x in range(w):
                o[x] = ((np.float32(a[2 * x]) + np.float32(a[2 * x + 1]))
                        + (np.float32(b[2 * x]) + np.float32(b[2 * x + 1])))
        else:
            c = img[f * y + 2]
            for x in range(w):
                o[x] = ((np.float32(a[3 * x]) + np.float32(a[3 * x + 1]) + np.float32(a[3 * x + 2]))
                        + (np.float32(b[3 * x]) + np.float32(b[3 * x + 1]) + np.float32(b[3 * x + 2]))
                        + (np.float32(c[3 * x]) + np.float32(c[3 * x + 1]) + np.float32(c[3 * x + 2])))
    return out


@numba.njit(cache=True)
def _correlate_rows(img: np.ndarray, tpl: np.ndarray, ny: int, nx: int) -> np.ndarray:
    """Cross-correlation of a float32 (h, w) image with a float32 template at the
    (ny, nx) valid top-left positions, returned flat: position (y, x) at y w + x.

    On the flattened image each template cell is one long vectorised pass (columns
    x >= nx are computed and not used); four cells per pass save loads and stores.
    """
    h, w = img.shape
    th, tw = tpl.shape
    flat = img.reshape(h * w)
    size = (ny - 1) * w + nx
    num = np.zeros(size, np.float32)
    for r in range(th):
        c = 0
        while c + 4 <= tw:
            off = r * w + c
            t0, t1, t2, t3 = tpl[r, c], tpl[r, c + 1], tpl[r, c + 2], tpl[r, c + 3]
            s0, s1 = flat[off:off + size], flat[off + 1:off + 1 + size]
            s2, s3 = flat[off + 2:off + 2 + size], flat[off + 3:off + 3 + size]
            for i in range(size):
                num[i] += s0[i] * t0 + s1[i] * t1 + s2[i] * t2 + s3[i] * t3
            c += 4
        while c < tw:
            off = r * w + c
            t0 = tpl[r, c]
            s0 = flat[off:off + size]
            for i in range(size):
                num[i] += s0[i] * t0
            c += 1
    return num


@numba.njit(cache=True)
def coarse_peaks(win: np.ndarray, tpl: np.ndarray, f: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` best local maxima of TM_CCOEFF_NORMED on 2 x 2 block sums.

    Window and template are summed over 2 x 2 blocks (a last odd row or column is left
    out); the zero-mean cross-correlation of the block images (float32) over the window
    deviation (exact float64 integral images) ranks the positions (by the signed square
    of the normalised correlation, which orders them alike); the 3 x 3 local maxima
    (>= every neighbour) are kept, best first, ties in raster order.

    Args:
        win: (H, W) uint8 window. tpl: (th, tw) uint8 template, 2 <= th <= H,
            2 <= tw <= W.
    Returns:
        columns and rows (int64, full-resolution top-left positions, even), at most k.
    """
    th2, tw2 = tpl.shape[0] // f, tpl.shape[1] // f
    ch, cw = win.shape[0] // f, win.shape[1] // f
    small = _block_sums(win, f, ch, cw)
    tz = _block_sums(tpl, f, th2, tw2)
    n = th2 * tw2
    mean = tz.sum() / n
    t2 = 0.0
    for r in range(th2):
        for c in range(tw2):
            tz[r, c] -= mean
            t2 += np.float64(tz[r, c]) * np.float64(tz[r, c])
    # integral images of the block image and its square (exact integers in float64)
    s1 = np.zeros((ch + 1, cw + 1))
    s2 = np.zeros((ch + 1, cw + 1))
    for y in range(ch):
        a1 = 0.0
        a2 = 0.0
        for x in range(cw):
            v = np.float64(small[y, x])
            a1 += v
            a2 += v * v
            s1[y + 1, x + 1] = s1[y, x + 1] + a1
            s2[y + 1, x + 1] = s2[y, x + 1] + a2
    ny, nx = ch - th2 + 1, cw - tw2 + 1
    num = _correlate_rows(small, tz, ny, nx)
    score = np.empty((ny, nx))  # sign(ncc) ncc^2
    inv = 1.0 / n
    for y in range(ny):
        for x in range(nx):
            sw = s1[y + th2, x + tw2] - s1[y, x + tw2] - s1[y + th2, x] + s1[y, x]
            sw2 = s2[y + th2, x + tw2] - s2[y, x + tw2] - s2[y + th2, x] + s2[y, x]
            var = max(sw2 - sw * sw * inv, 1e-9) * t2
            v = np.float64(num[y * cw + x])
            score[y, x] = v * abs(v) / var
    # the k best 3 x 3 local maxima, kept sorted (best first, earlier raster on ties)
    bv = np.full(k, -np.inf)
    bx = np.zeros(k, np.int64)
    by = np.zeros(k, np.int64)
    m = 0
    for y in range(ny):
        for x in range(nx):
            v = score[y, x]
            if m == k and v <= bv[k - 1]:
                continue
            peak = True
            for yy in range(max(y - 1, 0), min(y + 2, ny)):
                for xx in range(max(x - 1, 0), min(x + 2, nx)):
                    if score[yy, xx] > v:
                        peak = False
            if not peak:
                continue
            j = min(m, k - 1)
            while j > 0 and bv[j - 1] < v:
                bv[j], bx[j], by[j] = bv[j - 1], bx[j - 1], by[j - 1]
                j -= 1
            bv[j], bx[j], by[j] = v, f * x, f * y
            m = min(m + 1, k)
    return bx[:m], by[:m]


@numba.njit(cache=True)
def ncc_climb(win: np.ndarray, tpl: np.ndarray, xs: np.ndarray, ys: np.ndarray, pad: int
              ) -> tuple[int, int, float]:
    """Best TM_CCOEFF_NORMED position reached from a few starts (PBM 4.1 refinement).

    From each start (xs[i], ys[i]) the (2 pad + 1)^2 positions around it are scored, then
    the best one climbs to a maximum of its 8-neighbourhood. Ties go to the first
    position in raster order (as ``cv2.minMaxLoc``). A flat template scores 1 everywhere
    (as OpenCV).

    Args:
        win: (H, W) uint8 search window. tpl: (th, tw) uint8 template, th <= H, tw <= W.
        xs, ys: (K,) int64 start columns and rows (top-left positions in ``win``).
        pad: half-size of the first neighbourhood.
    Returns:
        best column, best row (in ``win``) and its score.
    """
    th, tw = tpl.shape
    ny, nx = win.shape[0] - th + 1, win.shape[1] - tw + 1
    st, tnorm = _template_stats(tpl)
    if tnorm <= 0:
        return 0, 0, 1.0
    tplf = tpl.astype(np.float32)
    seen = np.zeros((ny, nx), np.uint8)
    score = np.empty((ny, nx))
    bx, by, best = -1, -1, -np.inf
    for i in range(len(xs)):
        cx, cy = xs[i], ys[i]
        half = pad
        # pixels for the first neighbourhood and a few climbing steps, prepared once
        rx0, ry0 = max(cx - pad - _MARGIN, 0), max(cy - pad - _MARGIN, 0)
        rx1, ry1 = min(cx + pad + _MARGIN + 1, nx), min(cy + pad + _MARGIN + 1, ny)
        reg, s1, s2 = _region(win, rx0, ry0, rx1, ry1, th, tw)
        while True:
            xa, xb = max(cx - half, 0), min(cx + half + 1, nx)
            ya, yb = max(cy - half, 0), min(cy + half + 1, ny)
            if xa < rx0 or ya < ry0 or xb > rx1 or yb > ry1:
                rx0, ry0 = max(cx - _MARGIN, 0), max(cy - _MARGIN, 0)
                rx1, ry1 = min(cx + _MARGIN + 1, nx), min(cy + _MARGIN + 1, ny)
                reg, s1, s2 = _region(win, rx0, ry0, rx1, ry1, th, tw)
            _score_in(reg, s1, s2, rx0, ry0, tplf, xa, ya, xb, yb, st, tnorm, seen, score)
            mx, my, mv = -1, -1, -np.inf
            for y in range(ya, yb):
                for x in range(xa, xb):
                    if score[y, x] > mv:
                        mx, my, mv = x, y, score[y, x]
            if mx < 0 or (mx == cx and my == cy):
                break
            cx, cy, half = mx, my, 1
        if mv > best or (mv == best and (my < by or (my == by and mx < bx))):
            bx, by, best = mx, my, mv
    return bx, by, best


@numba.njit(cache=True)
def ncc_all(win: np.ndarray, tpl: np.ndarray) -> tuple[int, int, float]:
    """Exhaustive TM_CCOEFF_NORMED maximum (first in raster order), for small windows."""
    th, tw = tpl.shape
    ny, nx = win.shape[0] - th + 1, win.shape[1] - tw + 1
    st, tnorm = _template_stats(tpl)
    if tnorm <= 0:
        return 0, 0, 1.0
    seen = np.zeros((ny, nx), np.uint8)
    score = np.empty((ny, nx))
    reg, s1, s2 = _region(win, 0, 0, nx, ny, th, tw)
    _score_in(reg, s1, s2, 0, 0, tpl.astype(np.float32), 0, 0, nx, ny, st, tnorm, seen, score)
    bx, by, best = 0, 0, -np.inf
    for y in range(ny):
        for x in range(nx):
            if score[y, x] > best:
                bx, by, best = x, y, score[y, x]
    return bx, by, best
