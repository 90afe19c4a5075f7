"""The compiled kernels of the three-hypothesis tracker (numba, one core): eq. 1's colour
histograms of the measurements' ellipses, one call per frame, and eq. 5's region
similarity of the pairs of ellipses that meet (``region_overlap_pairs``, the integration of
``occlusion.region_overlaps``, tested bit for bit against ``features.region_similarity``),
``blend``, the appearance update q <- (1 - v) q + v p of ``rules.BlendVisible`` and
``contact.MergedAppearance`` over histograms kept as their occupied bins (tested bit for bit
against numpy's dense expression), and ``line_misses``, the least-squares lines of
``measured_line.MeasuredLine`` (tested bit for bit against ``measured_line._lines``).

It computes what ``EllipseHistogrammer.measure``'s numpy and ``cv2.calcHist`` path did
(the definition: ``features.ellipse_histograms``), bit for bit: the ellipse of a snapped
box is the set of pixel centres with ys^2 + xs^2 <= 1 (``EllipseHistogrammer._mask``'s
arithmetic), a pixel's joint bin ``(c0 * bins + c1) * bins + c2`` with ``ck = channel_k >>
shift`` (``features.bin_image``), a histogram the counts divided by |S| in float64
(``tests/trackers/three_hypothesis/test_kernels.py``). Compiled on first use, cached on
disk (``cache=True``).
Compiled with numba's ``cache=True``: the cache sits in ``__pycache__`` beside this file, keyed on
the file's time stamp (not on its import name).
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True)
def ellipse_histograms(frame: np.ndarray, snapped: np.ndarray, fg: np.ndarray, has_fg: bool,
                       min_foreground: float, stride: int, bins: int, nonzero: np.ndarray,
                       values: np.ndarray, starts: np.ndarray, occupied: np.ndarray) -> int:
    """Eq. 1 of every box: p_u = |{pixels of S in bin u}| / |S|, each p kept as its nonzero
    bins (every other p_u is +0).

    Args:
        frame: (H, W, 3) uint8 image.
        snapped: (N, 4) int64 boxes snapped to whole pixels (x, y, w, h; w, h >= 1).
        fg: (H, W) foreground (nonzero = foreground; any (1, 1) array when not
            ``has_fg``): with it, S is the ellipse's foreground pixels when they are at
            least ``min_foreground`` of the ellipse's pixels inside the image, else the
            whole ellipse (a person the background model missed keeps a model).
        stride: count every stride-th row and column of the box's crop only.
        bins: bins per channel (a power of 2 up to 256).
        nonzero, values: (N bins**3,) int64 and float64: written, box k's nonzero bins in
            increasing order and their p_u at [starts[k], starts[k + 1]).
        starts: (N + 1,) int64, written.
        occupied: (bins**3,) bool, False on entry: set where some histogram is nonzero.
    Returns:
        starts[N], the entries written.
    """
    H, W = frame.shape[0], frame.shape[1]
    shift = 0
    while (256 >> shift) > bins:
        shift += 1
    size = occupied.shape[0]
    counts = np.zeros(size + (-size) % _BLOCK, np.int32)  # whole blocks of _BLOCK bins
    used = 0
    span = np.empty((H, 2), np.int64)  # per image row of the box: its ellipse's columns [lo, hi)
    for k in range(snapped.shape[0]):
        starts[k] = used
        x, y, w, h = snapped[k, 0], snapped[k, 1], snapped[k, 2], snapped[k, 3]
        r0, r1 = max(y, 0), min(y + h, H)
        c0, c1 = max(x, 0), min(x + w, W)
        if r1 <= r0 or c1 <= c0:
            continue
        _ellipse_spans(x, y, w, h, r0, r1, c0, c1, span)
        # |S| and its foreground pixels, on every pixel (the choice of S precedes the stride)
        total, kept = 0, 0
        for r in range(r0, r1):
            total += span[r, 1] - span[r, 0]
            if has_fg:
                for c in range(span[r, 0], span[r, 1]):
                    kept += fg[r, c] != 0
        use_fg = has_fg and kept >= min_foreground * total
        if shift == 4:  # 16 bins a channel (the paper's): the shifts as constants
            n = _count(frame, fg, use_fg, span, r0, r1, c0, stride, 4, counts)
        else:
            n = _count(frame, fg, use_fg, span, r0, r1, c0, stride, shift, counts)
        if n == 0:
            continue
        for b0 in range(0, size, _BLOCK):  # a block of bins at a time: most are empty
            any_count = 0
            for u in range(b0, b0 + _BLOCK):
                any_count |= counts[u]
            if any_count == 0:
                continue
            for u in range(b0, b0 + _BLOCK):
                if counts[u]:
                    nonzero[used] = u
                    values[used] = counts[u] / float(n)  # eq. 1: / |S|
                    used += 1
                    occupied[u] = True
                    counts[u] = 0
    starts[snapped.shape[0]] = used
    return used


_BLOCK = 16
"""Bins ``ellipse_histograms`` reads at once to skip the empty ones."""


@numba.njit(cache=True, inline="always")
def _count(frame: np.ndarray, fg: np.ndarray, use_fg: bool, span: np.ndarray, r0: int,
           r1: int, c0: int, stride: int, shift: int, counts: np.ndarray) -> int:
    """Each counted pixel of the ellipse's ``span`` rows r0..r1 (every stride-th row and
    column of the box's crop; only foreground ones with ``use_fg``) adds one to its joint bin
    ``(c0 bins + c1) bins + c2``, ck = channel_k >> shift, in ``counts``; returns how many.
    Inlined, so a constant ``shift`` makes constant shifts."""
    sh = np.uint64(shift)
    sb, sb2 = np.uint64(8 - shift), np.uint64(16 - 2 * shift)
    n = 0
    for r in range(r0, r1, stride):
        first = span[r, 0] + (c0 - span[r, 0]) % stride  # the crop's columns c0 + i stride
        row = frame[r]
        for c in range(first, span[r, 1], stride):
            if not use_fg or fg[r, c] != 0:
                px = row[np.uint64(c)]  # unsigned: no negative-index test
                u = (((np.uint64(px[0]) >> sh) << sb2) | ((np.uint64(px[1]) >> sh) << sb)
                     | (np.uint64(px[2]) >> sh))
                counts[u] += 1
                n += 1
    return n


@numba.njit(cache=True, inline="always")
def _inside(c: int, w: int, rx: float, ys2: float) -> bool:
    """Whether the centre of box column c lies in the ellipse on a row of ys^2 = ys2:
    ys^2 + xs^2 <= 1 with xs = (c + 0.5 - w / 2) / rx (``EllipseHistogrammer._mask``)."""
    v = (float(c) + 0.5 - w / 2) / rx
    return ys2 + v * v <= 1.0


@numba.njit(cache=True)
def _ellipse_spans(x: int, y: int, w: int, h: int, r0: int, r1: int, c0: int, c1: int,
                   span: np.ndarray) -> None:
    """span[r] = image columns [lo, hi) of row r (r0 <= r < r1) whose pixel centres lie in
    the ellipse inscribed in the box (x, y, w, h), cut to [c0, c1).

    xs^2 is the same for box columns c and w - 1 - c (c + 0.5 - w / 2 is a half-integer,
    negated exactly) and does not increase towards the centre, and adding ys^2 keeps that
    order: each row's columns are one interval, symmetric in the box, whose left end is
    found by bisection with the very test ``_inside`` applies to each pixel."""
    rx, ry = max(w / 2, 0.5), max(h / 2, 0.5)
    mid = (w - 1) // 2  # the centre-most column of the left half
    for r in range(r0, r1):
        v = (float(r - y) + 0.5 - h / 2) / ry
        ys2 = v * v
        if not _inside(mid, w, rx, ys2):
            span[r, 0], span[r, 1] = c0, c0
            continue
        lo, hi = 0, mid  # the first inside column lies in [lo, hi]
        while lo < hi:
            m = (lo + hi) // 2
            if _inside(m, w, rx, ys2):
                hi = m
            else:
                lo = m + 1
        a, b = max(x + lo, c0), min(x + w - lo, c1)
        span[r, 0], span[r, 1] = a, max(a, b)


@numba.njit(cache=True)
def region_overlap_pairs(a: np.ndarray, b: np.ndarray, ia: np.ndarray, ib: np.ndarray,
                         t: np.ndarray, out: np.ndarray) -> None:
    """Eq. 5, delta = 2 |Sa & Sb| / (|Sa| + |Sb|), of the ellipses inscribed in the xywh
    boxes a[ia[k]] (N, 4) and b[ib[k]] (M, 4) into out[k] (K,), clipped to
    [0, 1]: |Sa & Sb| is the share of the t x t grid over a's box (t (S,) positions in
    [0, 1]) lying in both ellipses times |Sa| = pi/4 w h, with the arithmetic of the
    definition (``features.region_similarity``), operation for operation: the same bits."""
    S = t.shape[0]
    n = a.shape[0]
    ua = np.empty((n, 2, S))  # a's own squared normalised offsets on its grid, x then y
    inside_a = np.zeros((n, S, S), np.bool_)
    count_a = np.zeros(n, np.int64)
    need = np.zeros(n, np.bool_)
    for k in range(ia.shape[0]):
        need[ia[k]] = True
    gx, gy = np.empty((n, S)), np.empty((n, S))
    for i in range(n):
        for s in range(S):
            gx[i, s] = a[i, 0] + a[i, 2] * t[s]
            gy[i, s] = a[i, 1] + a[i, 3] * t[s]
        if not need[i]:
            continue
        rx, ry = max(a[i, 2] / 2, 1e-9), max(a[i, 3] / 2, 1e-9)
        for s in range(S):
            v = (gx[i, s] - a[i, 0] - rx) / rx
            ua[i, 0, s] = v * v
            v = (gy[i, s] - a[i, 1] - ry) / ry
            ua[i, 1, s] = v * v
        c = 0
        for row in range(S):
            for col in range(S):
                if ua[i, 0, col] + ua[i, 1, row] <= 1.0:
                    inside_a[i, row, col] = True
                    c += 1
        count_a[i] = c
    ux, uy = np.empty(S), np.empty(S)
    for k in range(ia.shape[0]):
        i, j = ia[k], ib[k]
        rx, ry = max(b[j, 2] / 2, 1e-9), max(b[j, 3] / 2, 1e-9)
        for s in range(S):
            v = (gx[i, s] - b[j, 0] - rx) / rx
            ux[s] = v * v
            v = (gy[i, s] - b[j, 1] - ry) / ry
            uy[s] = v * v
        both = 0
        for row in range(S):
            for col in range(S):
                if inside_a[i, row, col] and ux[col] + uy[row] <= 1.0:
                    both += 1
        frac = both / max(count_a[i], 1)
        wa, ha = a[i, 2], a[i, 3]
        inter = frac * np.pi / 4 * wa * ha
        total = np.pi / 4 * (wa * ha + b[j, 2] * b[j, 3])  # |Sa| + |Sb|
        delta = 2 * inter / total if total > 0 else 0.0
        if delta < 0.0:
            delta = 0.0
        elif delta > 1.0:
            delta = 1.0
        out[k] = delta


@numba.njit(cache=True)
def blend(q_bins: np.ndarray, q: np.ndarray, p_bins: np.ndarray, p: np.ndarray,
          v: float) -> tuple[np.ndarray, np.ndarray]:
    """q' = (1 - v) q + v p (v > 0 finite) of two histograms kept as their bins (sorted,
    distinct) and values, every other bin +0: q' over the union of the bins, each bin as
    numpy's dense ``(1.0 - v) * q + v * p`` computes it. Where p is +0, v p_u is +0, so
    w q_u + 0.0; where q is, w 0.0 + v p_u (no fast-math: both are kept as written, so a
    -0 product turns +0 as in the dense sum). Returns (bins, values)."""
    w = 1.0 - v
    bins = np.empty(q_bins.shape[0] + p_bins.shape[0], np.int64)
    out = np.empty(bins.shape[0])
    i, j, k = 0, 0, 0
    while i < q_bins.shape[0] or j < p_bins.shape[0]:
        if j == p_bins.shape[0] or (i < q_bins.shape[0] and q_bins[i] < p_bins[j]):
            bins[k], out[k] = q_bins[i], w * q[i] + 0.0
            i += 1
        elif i == q_bins.shape[0] or p_bins[j] < q_bins[i]:
            bins[k], out[k] = p_bins[j], w * 0.0 + v * p[j]
            j += 1
        else:
            bins[k], out[k] = q_bins[i], w * q[i] + v * p[j]
            i += 1
            j += 1
        k += 1
    return bins[:k], out[:k]


@numba.njit(cache=True)
def depth_orders(pairs: np.ndarray, visible: np.ndarray, shapes: np.ndarray, pred: np.ndarray,
                 out: np.ndarray) -> None:
    """Eq. 3's pi_ij of every node pair (i, j) = pairs[k] (K, 2) as far as frame t decides
    it, into out[k] (K,) int64: +1 when i occludes j, -1 when j occludes i, 0 when pi^{t-1}
    must be inherited (neither visible, or the areas tie). ``visible`` (B,) bool per node,
    ``shapes`` (B, 4) xywh current region of each node (its measurement when visible),
    ``pred`` (B, 4) xywh predicted regions. The scalar arithmetic of
    ``occlusion.depth_order`` (the definition), operation for operation: the same verdicts."""
    for k in range(pairs.shape[0]):
        a, b = pairs[k, 0], pairs[k, 1]
        vi, vj = visible[a], visible[b]
        out[k] = 0
        if vi and not vj:
            out[k] = 1
        elif vj and not vi:
            out[k] = -1
        elif vi and vj:
            yc = shapes[a, 1] + shapes[a, 3] / 2
            rx, ry = pred[b, 2] / 2, pred[b, 3] / 2
            t = min(max((yc - pred[b, 1] - ry) / ry, -1.0), 1.0) if ry > 0 else 0.0
            up = rx * ry * (t * math.sqrt(1.0 - t * t) + math.asin(t) + math.pi / 2)
            down = math.pi * rx * ry - up
            if up > down:
                out[k] = 1
            elif up < down:
                out[k] = -1


@numba.njit(cache=True)
def _block_sum(a: np.ndarray, lo: int, n: int) -> float:
    """numpy's ``pairwise_sum`` of a[lo:lo + n] for n <= 128: below 8 terms one by one,
    else eight running sums added as a tree, then the rest one by one."""
    if n < 8:
        res = -0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r = np.empty(8)
    for j in range(8):
        r[j] = a[lo + j]
    i = 8
    while i < n - n % 8:
        for j in range(8):
            r[j] += a[lo + i + j]
        i += 8
    res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@numba.njit(cache=True)
def _pairwise_sum(a: np.ndarray, lo: int, n: int) -> float:
    """numpy's pairwise summation of a[lo:lo + n] (its float64 add loop's
    ``pairwise_sum``): ``_block_sum`` up to 128 terms, beyond it the sum of two halves
    split at a multiple of 8, left + right; the same bits as ``a[lo:lo + n].sum()``. The
    halving runs on an explicit stack (numba's disk cache does not load a recursive
    function)."""
    if n <= 128:
        return _block_sum(a, lo, n)
    seg = np.empty((192, 3), np.int64)  # (start, length, 1: add the two sums above it)
    vals = np.empty(96)
    seg[0, 0], seg[0, 1], seg[0, 2] = lo, n, 0
    top, nv = 1, 0
    while top > 0:
        top -= 1
        s, m, join = seg[top, 0], seg[top, 1], seg[top, 2]
        if join:
            nv -= 1
            vals[nv - 1] = vals[nv - 1] + vals[nv]
        elif m <= 128:
            vals[nv] = _block_sum(a, s, m)
            nv += 1
        else:
            m2 = m // 2
            m2 -= m2 % 8
            seg[top, 0], seg[top, 1], seg[top, 2] = s, m, 1
            seg[top + 1, 0], seg[top + 1, 1], seg[top + 1, 2] = s + m2, m - m2, 0
            seg[top + 2, 0], seg[top + 2, 1], seg[top + 2, 2] = s, m2, 0
            top += 3
    return vals[0]


@numba.njit(cache=True)
def line_misses(hist: np.ndarray, sizes: np.ndarray, frame: float, cx: np.ndarray,
                cy: np.ndarray, out: np.ndarray) -> None:
    """``measured_line._lines`` of K histories at once and their misses at ``frame``: person
    k's n = sizes[k] (frame, xc, yc) rows follow person k - 1's in ``hist`` (sum of sizes,
    3); its least-squares line (t0, x0, y0, vx, vy) through them, and out[:2, k] = (x0 + vx
    (frame - t0) - cx[k], y0 + vy (frame - t0) - cy[k]) (4, K). Each mean and sum as
    ``_lines``' numpy reductions along a row (0 + the pairwise sum, / n): the same bits.
    out[2:, k]: the miss of its last step (``MeasuredLine.step``: the last centre moved on
    by the displacement of the last two per frame), as Python's floats compute it."""
    lo = 0
    w = np.empty((5, sizes.max() if len(sizes) else 0))
    c0 = np.empty(3)
    for k in range(len(sizes)):
        n = sizes[k]
        for i in range(n):
            for c in range(3):
                w[c, i] = hist[lo + i, c]
        for c in range(3):  # t0, x0, y0: the means
            c0[c] = (0.0 + _pairwise_sum(w[c], 0, n)) / n
        for i in range(n):
            w[0, i] = w[0, i] - c0[0]  # t
            w[3, i] = w[0, i] * w[0, i]  # t t
        tt = 0.0 + _pairwise_sum(w[3], 0, n)
        for i in range(n):
            w[4, i] = w[0, i] * (w[1, i] - c0[1])  # t x
            w[3, i] = w[0, i] * (w[2, i] - c0[2])  # t y
        vx = (0.0 + _pairwise_sum(w[4], 0, n)) / tt
        vy = (0.0 + _pairwise_sum(w[3], 0, n)) / tt
        out[0, k] = c0[1] + vx * (frame - c0[0]) - cx[k]
        out[1, k] = c0[2] + vy * (frame - c0[0]) - cy[k]
        f1, x1, y1 = hist[lo + n - 2, 0], hist[lo + n - 2, 1], hist[lo + n - 2, 2]
        f2, x2, y2 = hist[lo + n - 1, 0], hist[lo + n - 1, 1], hist[lo + n - 1, 2]
        gap = f2 - f1
        if 1.0 > gap:  # Python's max(f2 - f1, 1)
            gap = 1.0
        s = (frame - f2) / gap
        out[2, k] = x2 + (x2 - x1) * s - cx[k]
        out[3, k] = y2 + (y2 - y1) * s - cy[k]
        lo += n


@numba.njit(cache=True)
def stage1_costs(rho: np.ndarray, owners: np.ndarray, starts: np.ndarray, mu_rho: np.ndarray,
                 admissible: np.ndarray, has_admissible: bool, delta: np.ndarray,
                 margin: bool, cost: np.ndarray, best: np.ndarray, pairs: np.ndarray) -> int:
    """Stage 1 of MaxSimilarity (3.3.2 steps 1-4) up to the Hungarian step, in one pass:
    ``association._stage1``'s (P, D) person costs into ``cost`` (min over each person's
    nodes of (1 - rho) + (1 - delta) (eqs. 4-5) where delta > 0, rho >= mu_rho and the pair
    is ``admissible``, else +inf) and the first node attaining each into ``best``; with
    ``margin``, ``association.appearance_margin``'s term in place of rho (cost + (rho -
    margin)). rho (P, D) clipped to [0, 1]; owners (B,) sorted person of each node; starts
    (P,) each person's first node; mu_rho (P,); admissible (B, D) bool, read when
    ``has_admissible``; delta (B, D). The operations of the numpy definition, one by one:
    the same bits. Returns the number of allowed pairs (cost <= 2) written to ``pairs``
    (row-major, as ``np.argwhere``) when no two of them share a person or a measurement
    (``association._hungarian``'s immediate assignment), else -1."""
    P, D = rho.shape
    for i in range(P):
        for j in range(D):
            cost[i, j] = np.inf
            best[i, j] = starts[i]
    for b in range(owners.shape[0]):
        i = owners[b]
        for j in range(D):
            r = rho[i, j]
            if delta[b, j] > 0 and r >= mu_rho[i] and (not has_admissible or admissible[b, j]):
                c = (1.0 - r) + (1.0 - delta[b, j])
                if c < cost[i, j]:  # the first node attaining the minimum keeps it
                    cost[i, j] = c
                    best[i, j] = b
    if margin:
        _margin_costs(rho, cost)
    k = 0
    per_col = np.zeros(D, np.int64)
    for i in range(P):
        in_row = 0
        for j in range(D):
            if cost[i, j] <= 2.0:  # finite and <= 2
                in_row += 1
                per_col[j] += 1
                if in_row > 1 or per_col[j] > 1:
                    return -1
                pairs[k, 0], pairs[k, 1] = i, j
                k += 1
    return k


@numba.njit(cache=True, inline="always")
def _top_two(x: np.ndarray) -> tuple[float, float]:
    """The last two of ``np.sort(x)`` (2 entries at least): the largest and the next."""
    first, second = -np.inf, -np.inf
    for v in x:
        if v > first:
            first, second = v, first
        elif v > second:
            second = v
    return first, second


@numba.njit(cache=True)
def _margin_costs(rho: np.ndarray, cost: np.ndarray) -> None:
    """cost += rho - a with a = ``association.appearance_margin``(rho, cost finite): r =
    rho where the person cost is finite, else 0; a = clip(r - max(rival along the column,
    rival along the row), 0, 1), a rival the largest other entry (0 alone), as numpy's
    sorted second-to-last: the same bits."""
    P, D = rho.shape
    r = np.empty((P, D))
    for i in range(P):
        for j in range(D):
            r[i, j] = rho[i, j] if cost[i, j] < np.inf else 0.0
    rival = np.zeros((P, D))
    if P >= 2:
        for j in range(D):
            first, second = _top_two(r[:, j])
            for i in range(P):
                rival[i, j] = second if r[i, j] >= first else first
    if D >= 2:
        for i in range(P):
            first, second = _top_two(r[i])
            for j in range(D):
                v = second if r[i, j] >= first else first
                if not rival[i, j] >= v:  # np.maximum
                    rival[i, j] = v
    for i in range(P):
        for j in range(D):
            a = r[i, j] - rival[i, j]
            if a == a:  # np.clip: NaN kept, else max with 0 (a > 0 ? a : 0), then min with 1
                a = a if a > 0.0 else 0.0
                a = a if a < 1.0 else 1.0
            cost[i, j] = cost[i, j] + (rho[i, j] - a)
