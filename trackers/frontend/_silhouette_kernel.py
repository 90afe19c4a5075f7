"""Compiled greedy search of ``SilhouetteMatcher`` (silhouette.py): the same equations as
``greedy_search`` and ``search_regions`` of silhouette_search.py, in one pass per fit over the
candidates instead of (N, cells) numpy temporaries, and skipping candidates whose template box
holds too little vacant foreground to pass the score test (a bound, so the fits are
unchanged). Tested against the numpy version (tests/trackers/frontend/test_detectors.py): the
same fits on synthetic masks. Compiled with numba's ``cache=True``: the cache sits in
``__pycache__`` beside this file, keyed on the file's time stamp (not on its import name).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _box(I, y0, x0, y1, x1):
    return I[y1, x1] - I[y0, x1] - I[y1, x0] + I[y0, x0]


@numba.njit(cache=True)
def _cells(I, Y, X, ys, xs, coef):
    """Sum over the cells of w_cell x (box sum of the cell), from the cells' corners."""
    acc = 0.0
    for a in range(ys.shape[0]):
        for b in range(xs.shape[0]):
            acc += coef[a, b] * I[Y + ys[a], X + xs[b]]
    return acc


@numba.njit(cache=True)
def _integral(img, I, row0):
    """I[y, x] = sum of img[:y, :x] (int32), recomputed from row ``row0`` of I down."""
    H, W = img.shape
    row0 = max(row0, 1)
    for y in range(row0, H + 1):
        run = 0
        for x in range(W):
            run += img[y - 1, x]
            I[y, x + 1] = I[y - 1, x + 1] + run


@numba.njit(cache=True)
def greedy_kernel(vp, op, py, px, H, W, ids, bands, ys, xs, coef, size, tsum, head, occ,
                  alpha, beta, threshold, min_visible, head_contrast, fits):
    """See ``silhouette_search.greedy_search`` (same arguments); returns the number of fits.

    Every placement is scored once; after a fit only the placements whose box meets the
    fit's box are scored again (the others' sums did not change)."""
    Hp, Wp = vp.shape
    IV = np.zeros((Hp + 1, Wp + 1), dtype=np.int32)
    IO = np.zeros((Hp + 1, Wp + 1), dtype=np.int32)
    _integral(vp, IV, 1)
    _integral(op, IO, 1)
    IK, IV0 = IV, IV  # the head rule's sums, on the region before any fit
    if head_contrast > -1.0:
        IK = np.zeros((Hp + 1, Wp + 1), dtype=np.int32)
        _integral(vp + op, IK, 1)
        IV0 = IV.copy()
    # a placement passes only if (1 + alpha + beta) tv >= (alpha + threshold) M + beta bx with
    # M >= min_visible sum T and tv <= bx: so bx >= bound sum T
    bound = (alpha + threshold) * min_visible / (1.0 + alpha)
    nk = ids.shape[0]
    start = np.zeros(nk + 1, dtype=np.int64)  # placements of scale k: start[k] .. start[k+1]
    for k in range(nk):
        start[k + 1] = start[k] + (bands[k, 1] - bands[k, 0]) * W
    E = np.full(start[nk], -np.inf)
    alive = np.ones(start[nk], dtype=np.uint8)  # placements that may still pass
    first = True
    score = np.zeros(start[nk])
    rowmax = np.full(start[nk] // W, -np.inf)  # the largest E of each row of W placements
    # the window whose placements are (re)scored: first the vacant pixels' box (a placement
    # outside it has no foreground, E <= 0), then after each fit the pixels it changed
    y0, y1, x0, x1 = Hp, 0, Wp, 0
    for y in range(Hp):
        for x in range(Wp):
            if vp[y, x]:
                y0, y1, x0, x1 = min(y0, y), max(y1, y + 1), min(x0, x), max(x1, x + 1)
    n = 0
    for _ in range(fits.shape[0]):
        for k in range(nk):
            s = ids[k]
            th, tw = size[s, 0], size[s, 1]
            b0 = bands[k, 0]
            ys_s, xs_s, coef_s, hd = ys[s], xs[s], coef[s], head[s]
            # centre rows r whose box [r - th // 2 + py, + th) meets [y0, y1), same for columns
            r_lo, r_hi = max(b0, y0 - py + th // 2 - th + 1), min(bands[k, 1], y1 - py + th // 2)
            c_lo, c_hi = max(0, x0 - px + tw // 2 - tw + 1), min(W, x1 - px + tw // 2)
            ts = tsum[s]
            kh, h0, h1, l1, r0 = hd[0], hd[1], hd[2], hd[3], hd[4]
            h_area, b_area = max(kh * (h1 - h0), 1e-6), max(kh * (l1 + tw - r0), 1e-6)
            for r in range(r_lo, r_hi):
                Y = r - th // 2 + py
                row = start[k] + (r - b0) * W
                for c in range(c_lo, c_hi):
                    if not alive[row + c]:
                        continue
                    X = c - tw // 2 + px
                    E[row + c] = -np.inf
                    bx = _box(IV, Y, X, Y + th, X + tw)
                    if bx < bound * ts - 1e-9:  # too little vacant foreground (tv <= bx), for
                        alive[row + c] = 0  # good: vacant foreground only shrinks
                        continue
                    if head_contrast > -1.0 and first:
                        hin = min(_box(IK, Y, X + h0, Y + kh, X + h1), kh * (h1 - h0))
                        hout = _box(IV0, Y, X, Y + kh, X + l1) + _box(IV0, Y, X + r0, Y + kh, X + tw)
                        if hin / h_area - hout / b_area < head_contrast:
                            alive[row + c] = 0  # for good: the head rule is fixed
                            continue
                    tv = _cells(IV, Y, X, ys_s, xs_s, coef_s)
                    to = _cells(IO, Y, X, ys_s, xs_s, coef_s) if _box(IO, Y, X, Y + th, X + tw) > 0 else 0.0
                    visible = ts - to
                    # explained mass E = sum T V - alpha sum T (1 - V) - beta sum (1 - T) V
                    e = tv - alpha * (visible - tv) - beta * (bx - tv)
                    if e >= threshold * max(visible, 1e-6) and visible >= min_visible * ts:
                        E[row + c] = e
                        score[row + c] = e / max(visible, 1e-6)
                rowmax[row // W] = E[row : row + W].max()
        first = False
        best = 0.0
        j = -1
        for q in range(rowmax.shape[0]):  # the first largest E > 0, in scale, row, column order
            if rowmax[q] > best:
                best, j = rowmax[q], q
        if j < 0:
            break
        j *= W
        while E[j] < best:
            j += 1
        k = np.searchsorted(start, j, side="right") - 1
        s = ids[k]
        th, tw = size[s, 0], size[s, 1]
        r, c = divmod(j - start[k], W)
        best_y, best_x = r + bands[k, 0] - th // 2 + py, c - tw // 2 + px
        cy0, cx0, cy1, cx1 = Hp, Wp, -1, -1
        for i in range(th):
            for jj in range(tw):
                if occ[s, i, jj]:
                    y, x = best_y + i, best_x + jj
                    if vp[y, x]:
                        op[y, x] = 1
                        vp[y, x] = 0
                        cy0, cx0 = min(cy0, y), min(cx0, x)
                        cy1, cx1 = max(cy1, y + 1), max(cx1, x + 1)
        _integral(vp, IV, best_y + 1)
        _integral(op, IO, best_y + 1)
        if cy1 < 0:  # nothing changed: no placement to score again
            cy0, cy1, cx0, cx1 = 0, 0, 0, 0
        y0, y1, x0, x1 = cy0, cy1, cx0, cx1  # the pixels whose sums changed
        fits[n, 0] = s
        fits[n, 1] = best_y - py
        fits[n, 2] = best_x - px
        fits[n, 3] = best
        fits[n, 4] = score[j]
        if cy1 >= 0:
            fits[n, 5], fits[n, 6] = cx0 - px, cy0 - py
            fits[n, 7], fits[n, 8] = cx1 - px, cy1 - py
        else:
            fits[n, 5:9] = -1.0
        n += 1
    return n


@numba.njit(cache=True)
def search_regions_kernel(small, lab, regions, bands, ys, xs, coef, size, tsum, head, occ,
                          alpha, beta, threshold, min_visible, head_contrast, fits, counts):
    """See ``silhouette_search.search_regions`` (same arguments): every region of a frame in one call."""
    for i in range(regions.shape[0]):
        label, x0, y0, x1, y1 = regions[i, 0], regions[i, 1], regions[i, 2], regions[i, 3], regions[i, 4]
        py, px = regions[i, 5], regions[i, 6]
        H, W = y1 - y0, x1 - x0
        vp = np.zeros((H + 2 * py, W + 2 * px), dtype=np.uint8)
        op = np.zeros_like(vp)
        for r in range(H):
            for c in range(W):
                if lab[y0 + r, x0 + c] == label and small[y0 + r, x0 + c] > 0:
                    vp[py + r, px + c] = 1
        if regions[i, 7]:
            op[:py] = 1
        if regions[i, 8]:
            op[py + H :] = 1
        if regions[i, 9]:
            op[:, :px] = 1
        if regions[i, 10]:
            op[:, px + W :] = 1
        n = 0
        for k in range(bands.shape[1]):
            n += bands[i, k, 1] > bands[i, k, 0]
        ids = np.empty(n, dtype=np.int64)
        b = np.empty((n, 2), dtype=np.int64)
        n = 0
        for k in range(bands.shape[1]):
            if bands[i, k, 1] > bands[i, k, 0]:
                ids[n], b[n, 0], b[n, 1] = k, bands[i, k, 0], bands[i, k, 1]
                n += 1
        counts[i] = greedy_kernel(vp, op, py, px, H, W, ids, b, ys, xs, coef, size, tsum, head,
                                  occ, alpha, beta, threshold, min_visible, head_contrast, fits[i])
