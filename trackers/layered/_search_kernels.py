"""Compiled kernels of ``trackers.layered.search`` (numba, one core).

The head-template match of PBM 4.1 (multiple-response pruning) runs coarse to fine:
``coarse_peaks`` scores TM_CCOEFF_NORMED on block sums of the window and template
and keeps the best local maxima; ``ncc_climb`` climbs from each, at full resolution, to
a local maximum of the exact score. ``ncc_all`` scores every position (small windows).
Full-resolution scores use exact integer sums (held in float32 per row and float64
overall; every partial sum is an integer below 2^24 or 2^53) and OpenCV's conventions,
so they equal ``cv2.matchTemplate(..., TM_CCOEFF_NORMED)`` up to its float32 rounding;
being exact, the sums may be formed in any order (eight positions of a row at once).
"""

from __future__ import annotations

import numba
import numpy as np

_CHUNK = 256  # columns per float32 row sum: 256 x 255^2 < 2^24, so the sums stay exact


_LANES = 8  # positions of a row scored together (one vector of float32)


@numba.njit(cache=True, fastmath=True)
def _sums_row(img: np.ndarray, tplf: np.ndarray, x: int, y: int, out: np.ndarray,
              cols: np.ndarray, pre: np.ndarray) -> None:
    """Exact sums of the ``_LANES`` positions (x + q, y), q = 0..7, of a (th, tw)
    template, th and tw <= ``_CHUNK``, into out (3, 8) float64: the cross-correlation
    sum(img[y:y + th, x + q:x + q + tw] tplf), the window sum and its sum of squares.

    ``img``: float32 integers 0..255 with ``_LANES - 1`` columns of padding on the
    right (``_padded``). The cross-correlations sum each template row in float32
    (integers below 2^24: exact in any order, so ``fastmath`` may reorder them), eight
    positions per template value, and the rows in float64. The window sums come from
    column sums (float32, exact) over tw + 7 columns and their float64 prefix sums.
    Scratch: cols (2, tw + 7) float32, pre (2, tw + 8) float64.
    """
    th, tw = tplf.shape
    for r in range(th):
        row = img[y + r, x:]  # indices from 0: no negative-index test
        t = tplf[r]
        c0 = c1 = c2 = c3 = c4 = c5 = c6 = c7 = np.float32(0.0)
        for c in range(tw):
            tv = t[c]
            c0 += row[c] * tv
            c1 += row[c + 1] * tv
            c2 += row[c + 2] * tv
            c3 += row[c + 3] * tv
            c4 += row[c + 4] * tv
            c5 += row[c + 5] * tv
            c6 += row[c + 6] * tv
            c7 += row[c + 7] * tv
        if r == 0:
            out[0, 0], out[0, 1], out[0, 2], out[0, 3] = c0, c1, c2, c3
            out[0, 4], out[0, 5], out[0, 6], out[0, 7] = c4, c5, c6, c7
        else:
            out[0, 0] += c0
            out[0, 1] += c1
            out[0, 2] += c2
            out[0, 3] += c3
            out[0, 4] += c4
            out[0, 5] += c5
            out[0, 6] += c6
            out[0, 7] += c7
    m = tw + _LANES - 1
    cs, cq = cols[0], cols[1]
    cs[:] = 0.0
    cq[:] = 0.0
    for r in range(th):
        row = img[y + r, x:x + m]
        for k in range(m):
            v = row[k]
            cs[k] += v
            cq[k] += v * v
    ps, pq = pre[0], pre[1]
    ps[0] = pq[0] = 0.0
    for k in range(m):
        ps[k + 1] = ps[k] + cs[k]
        pq[k + 1] = pq[k] + cq[k]
    for q in range(_LANES):
        out[1, q] = ps[q + tw] - ps[q]
        out[2, q] = pq[q + tw] - pq[q]


@numba.njit(cache=True)
def _sums_one(img: np.ndarray, tplf: np.ndarray, x: int, y: int) -> tuple[float, float, float]:
    """``_sums_row``'s three sums at one position, in float64 (any template width)."""
    th, tw = tplf.shape
    sc = sw = sw2 = 0.0
    for r in range(th):
        for c in range(tw):
            v = np.float64(img[y + r, x + c])
            sc += v * np.float64(tplf[r, c])
            sw += v
            sw2 += v * v
    return sc, sw, sw2


@numba.njit(cache=True)
def _padded(win: np.ndarray) -> np.ndarray:
    """float32 copy of a uint8 window with ``_LANES - 1`` zero columns on the right."""
    h, w = win.shape
    out = np.zeros((h, w + _LANES - 1), np.float32)
    for y in range(h):
        src, dst = win[y], out[y]
        for x in range(w):
            dst[x] = src[x]
    return out


@numba.njit(cache=True)
def _integrals(img: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Integral images (h + 1, w + 1) of an (h, w) image of integers and of its square,
    in float64 (exact: the sums are integers below 2**53)."""
    h, w = img.shape
    s1 = np.zeros((h + 1, w + 1))
    s2 = np.zeros((h + 1, w + 1))
    for y in range(h):
        a1 = 0.0
        a2 = 0.0
        for x in range(w):
            v = np.float64(img[y, x])
            a1 += v
            a2 += v * v
            s1[y + 1, x + 1] = s1[y, x + 1] + a1
            s2[y + 1, x + 1] = s2[y, x + 1] + a2
    return s1, s2


@numba.njit(cache=True)
def _score_in(img: np.ndarray, tplf: np.ndarray, xa: int, ya: int, xb: int, yb: int,
              st: float, tnorm: float, seen: np.ndarray, score: np.ndarray) -> None:
    """TM_CCOEFF_NORMED at the positions [xa, xb) x [ya, yb) not yet ``seen`` of a
    ``_padded`` window, written into ``score``.

    OpenCV's conventions: |num| >= denominator gives 0, within 12.5% of it +-1.
    ``st``: template sum; ``tnorm``: sqrt of its sum of squared deviations.
    """
    th, tw = tplf.shape
    n = th * tw
    rows = tw <= _CHUNK and th <= _CHUNK  # eight positions at once (exact float32 sums)
    sums = np.empty((3, _LANES))
    cols = np.empty((2, tw + _LANES - 1), np.float32)
    pre = np.empty((2, tw + _LANES))
    for yy in range(ya, yb):
        first = -_LANES  # sums[:, q] hold position (first + q, yy)
        for xx in range(xa, xb):
            if seen[yy, xx]:
                continue
            if rows:
                if xx >= first + _LANES:  # this position and the next seven
                    _sums_row(img, tplf, xx, yy, sums, cols, pre)
                    first = xx
                q = xx - first
                sc, sw, sw2 = sums[0, q], sums[1, q], sums[2, q]
            else:
                sc, sw, sw2 = _sums_one(img, tplf, xx, yy)
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
def _block_sums(img: np.ndarray, fy: int, fx: int, h: int, w: int) -> np.ndarray:
    """(h, w) float32 sums of the fy x fx blocks (fy >= 1; fx = 2 or 3) of a uint8 image
    (its top-left h fy x w fx)."""
    out = np.empty((h, w), np.float32)
    tmp = np.empty(w * fx, np.float32)
    for y in range(h):
        a = img[fy * y, :w * fx]
        for x in range(w * fx):
            tmp[x] = np.float32(a[x])
        for dy in range(1, fy):
            b = img[fy * y + dy, :w * fx]
            for x in range(w * fx):
                tmp[x] += np.float32(b[x])
        o = out[y]
        if fx == 2:
            for x in range(w):
                o[x] = tmp[2 * x] + tmp[2 * x + 1]
        else:
            for x in range(w):
                o[x] = tmp[3 * x] + tmp[3 * x + 1] + tmp[3 * x + 2]
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
def coarse_peaks(win: np.ndarray, tpl: np.ndarray, fy: int, fx: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` best local maxima of TM_CCOEFF_NORMED on fy x fx block sums.

    Window and template are summed over blocks of fy rows and fx columns (fx = 2 or 3;
    rows and columns that do not fill a block are left out); the zero-mean
    cross-correlation of the block images (float32) over the window deviation (exact
    float64 integral images) ranks the positions (by the signed square of the normalised
    correlation, which orders them alike); the 3 x 3 local maxima (>= every neighbour)
    are kept, best first, ties in raster order.

    Args:
        win: (H, W) C-contiguous uint8 window. tpl: (th, tw) C-contiguous uint8 template,
            2 fy <= th <= H, 2 fx <= tw <= W.
    Returns:
        columns and rows (int64, full-resolution top-left positions on the block grid),
        at most k; none when the block template is flat.
    """
    th2, tw2 = tpl.shape[0] // fy, tpl.shape[1] // fx
    ch, cw = win.shape[0] // fy, win.shape[1] // fx
    small = _block_sums(win, fy, fx, ch, cw)
    tz = _block_sums(tpl, fy, fx, th2, tw2)
    n = th2 * tw2
    mean = tz.sum() / n
    t2 = 0.0
    for r in range(th2):
        for c in range(tw2):
            tz[r, c] -= mean
            t2 += np.float64(tz[r, c]) * np.float64(tz[r, c])
    if t2 <= 0:  # flat at the coarse level: no ranking (the caller scores exhaustively)
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    s1, s2 = _integrals(small)  # of the block image and its square
    ny, nx = ch - th2 + 1, cw - tw2 + 1
    num = _correlate_rows(small, tz, ny, nx)
    score = np.empty((ny, nx))  # sign(ncc) ncc^2
    inv = 1.0 / n
    for y in range(ny):
        top1, bot1, top2, bot2 = s1[y], s1[y + th2], s2[y], s2[y + th2]
        nrow, srow = num[y * cw:], score[y]
        for x in range(nx):
            xe = np.uint64(x + tw2)  # unsigned: no negative-index test
            sw = bot1[xe] - top1[xe] - bot1[x] + top1[x]
            sw2 = bot2[xe] - top2[xe] - bot2[x] + top2[x]
            var = max(sw2 - sw * sw * inv, 1e-9) * t2
            v = np.float64(nrow[x])
            srow[x] = v * abs(v) / var
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
                    if score[np.uint64(yy), np.uint64(xx)] > v:
                        peak = False
            if not peak:
                continue
            j = min(m, k - 1)
            while j > 0 and bv[j - 1] < v:
                bv[j], bx[j], by[j] = bv[j - 1], bx[j - 1], by[j - 1]
                j -= 1
            bv[j], bx[j], by[j] = v, fx * x, fy * y
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
    img = _padded(win)
    seen = np.zeros((ny, nx), np.uint8)
    score = np.empty((ny, nx))
    bx, by, best = -1, -1, -np.inf
    for i in range(len(xs)):
        cx, cy = xs[i], ys[i]
        half = pad
        while True:
            xa, xb = max(cx - half, 0), min(cx + half + 1, nx)
            ya, yb = max(cy - half, 0), min(cy + half + 1, ny)
            _score_in(img, tplf, xa, ya, xb, yb, st, tnorm, seen, score)
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
    _score_in(_padded(win), tpl.astype(np.float32), 0, 0, nx, ny, st, tnorm, seen, score)
    bx, by, best = 0, 0, -np.inf
    for y in range(ny):
        for x in range(nx):
            if score[y, x] > best:
                bx, by, best = x, y, score[y, x]
    return bx, by, best


@numba.njit(cache=True)
def profile_peaks(mask: np.ndarray, min_separation: float, min_prominence: float) -> np.ndarray:
    """``search.top_profile_heads`` compiled: (K, 2) float64 (column centre, top row) of
    the peaks of a bool blob crop's top profile, highest first (PBM 3.1 heads)."""
    h, w = mask.shape
    top = np.full(w, np.float64(h))
    left_to_find = w
    for r in range(h):  # the first foreground row of each column
        if left_to_find == 0:
            break
        row = mask[r]
        for c in range(w):
            if row[c] and top[c] == h:
                top[c] = r
                left_to_find -= 1
    if left_to_find == w:
        return np.zeros((0, 2))
    rad = max(int(min_separation // 2), 1)
    span = int(2 * min_separation)
    # plateau runs of columns equal to the running minimum over 2 rad + 1 columns (edges
    # replicated) and holding foreground; a run's columns share one top row
    cand = np.empty((w, 2))
    nc = 0
    c = 0
    while c < w:
        if top[c] == h or top[c] != np.min(top[max(c - rad, 0):min(c + rad + 1, w)]):
            c += 1
            continue
        g0 = c
        g1 = c
        while (g1 + 1 < w and top[g1 + 1] != h
               and top[g1 + 1] == np.min(top[max(g1 + 1 - rad, 0):min(g1 + rad + 2, w)])):
            g1 += 1
        t = top[g0]
        ok_left = g0 - span <= 0
        if not ok_left and g0 > max(g0 - span, 0):
            ok_left = np.max(top[max(g0 - span, 0):g0]) - t >= min_prominence
        ok_right = g1 + span >= w - 1
        if not ok_right and min(g1 + span + 1, w) > g1 + 1:
            ok_right = np.max(top[g1 + 1:min(g1 + span + 1, w)]) - t >= min_prominence
        if ok_left and ok_right:
            # insertion by top row, stable: the highest first, column order on ties
            j = nc
            while j > 0 and cand[j - 1, 1] > t:
                cand[j, 0], cand[j, 1] = cand[j - 1, 0], cand[j - 1, 1]
                j -= 1
            cand[j, 0], cand[j, 1] = 0.5 * (g0 + g1), t
            nc += 1
        c = g1 + 1
    if nc == 0:
        best = int(np.argmin(top))
        cand[0, 0], cand[0, 1] = float(best), top[best]
        nc = 1
    kept = np.empty((nc, 2))
    nk = 0
    for i in range(nc):  # non-maximum suppression, highest first
        ok = True
        for j in range(nk):
            if abs(cand[i, 0] - kept[j, 0]) < min_separation:
                ok = False
                break
        if ok:
            kept[nk, 0], kept[nk, 1] = cand[i, 0], cand[i, 1]
            nk += 1
    return kept[:nk].copy()


@numba.njit(cache=True)
def mask_span(mask: np.ndarray, lo: int, hi: int) -> tuple[int, int, int, int]:
    """First and last+1 row, first and last+1 column (relative to ``lo``) of the True
    pixels of ``mask[:, lo:hi]``; (0, 0, 0, 0) when there are none."""
    r0, r1, c0, c1 = -1, -1, hi - lo, -1
    for r in range(mask.shape[0]):
        row = mask[r]
        for c in range(lo, hi):
            if row[c]:
                if r0 < 0:
                    r0 = r
                r1 = r
                c0 = min(c0, c - lo)
                c1 = max(c1, c - lo)
    if r0 < 0:
        return 0, 0, 0, 0
    return r0, r1 + 1, c0, c1 + 1


@numba.njit(cache=True)
def kinds_matrix(region_wh: np.ndarray, predicted_wh: np.ndarray, threshold: float) -> np.ndarray:
    """``search.occlusion_kinds`` compiled: (T, N) int64 of 0, +1 (larger), -1 (smaller)."""
    T, N = predicted_wh.shape[0], region_wh.shape[0]
    out = np.zeros((T, N), np.int64)
    for t in range(T):
        pw, ph = predicted_wh[t, 0], predicted_wh[t, 1]
        dw, dh = max(pw, 1.0), max(ph, 1.0)
        for n in range(N):
            rw = (region_wh[n, 0] - pw) / dw
            rh = (region_wh[n, 1] - ph) / dh
            if rw > threshold or rh > threshold:
                out[t, n] = 1
            elif rw < -threshold or rh < -threshold:
                out[t, n] = -1
    return out


@numba.njit(cache=True)
def head_boxes(heads: np.ndarray, predicted_wh: np.ndarray, alpha: np.ndarray, step: float,
               search_range: int) -> np.ndarray:
    """``search.search_boxes_many`` compiled: (S, (2 r + 1)^2, 4) xywh (eqs. 9-10)."""
    S = heads.shape[0]
    m = 2 * search_range + 1
    out = np.empty((S, m * m, 4))
    for s in range(S):
        for i in range(m):
            w = predicted_wh[s, 0] * (1.0 + step * np.float64(i - search_range))
            x = heads[s, 0] - alpha[s] * w
            for k in range(m):
                b = i * m + k
                out[s, b, 0] = x
                out[s, b, 1] = heads[s, 1]
                out[s, b, 2] = w
                out[s, b, 3] = predicted_wh[s, 1] * (1.0 + step * np.float64(k - search_range))
    return out


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
def label_stats(labels: np.ndarray, n: int) -> np.ndarray:
    """(n, 5) int64 left, top, width, height, area of labels 0..n-1 of a label image, as
    ``cv2.connectedComponentsWithStats``, except label 0 (the background): all zeros."""
    x0 = np.full(n, labels.shape[1], np.int64)
    y0 = np.full(n, labels.shape[0], np.int64)
    x1 = np.full(n, -1, np.int64)
    y1 = np.full(n, -1, np.int64)
    area = np.zeros(n, np.int64)
    for y in range(labels.shape[0]):
        row = labels[y]
        for x in range(labels.shape[1]):
            lab = row[x]
            if lab == 0:
                continue
            area[lab] += 1
            x0[lab] = min(x0[lab], x)
            x1[lab] = max(x1[lab], x)
            y0[lab] = min(y0[lab], y)
            y1[lab] = max(y1[lab], y)
    out = np.zeros((n, 5), np.int64)
    for i in range(1, n):
        out[i, 0], out[i, 1] = x0[i], y0[i]
        out[i, 2], out[i, 3], out[i, 4] = x1[i] + 1 - x0[i], y1[i] + 1 - y0[i], area[i]
    return out


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
def foreground_counts(values: np.ndarray, boxes: np.ndarray) -> tuple:  # pragma: no cover (compiled)
    """The foreground (PBM 2) of an (H, W) label image or mask in one pass: (H, W) bool
    ``values != 0``, its number of True pixels (``np.count_nonzero``) and the number of
    them inside the union of the xywh boxes (``covered_count``), each row counted while
    it is still in cache."""
    H, W = values.shape
    mask = np.empty((H, W), np.bool_)
    spans = _box_spans(boxes, H, W)
    starts, ends = np.empty(boxes.shape[0], np.int64), np.empty(boxes.shape[0], np.int64)
    rmin, rmax = _span_rows(spans, H)
    count, covered = 0, 0
    for r in range(H):
        src, dst = values[r], mask[r]
        for c in range(W):
            v = src[c] != 0
            dst[c] = v
            count += v
        if rmin <= r < rmax:
            covered += _covered_in_row(dst, r, spans, starts, ends)
    return mask, count, covered
