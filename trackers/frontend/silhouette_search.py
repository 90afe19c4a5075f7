"""The greedy search of ``SilhouetteMatcher`` as plain numpy equations (``greedy_search``,
``search_regions``; ``_silhouette_kernel`` compiles them, tested against these) and the
template at every searched height as box-sum rectangles (``_Scales``).

Every sum is a box sum on an integral image, O(1) per placement: the template is scored as
T~, its mean over a grid of cells (the head band, the top 1/7, and ``CELL_ROWS`` - 1 bands
below, by ``CELL_COLS`` columns; ``_Scales``), and the head rule as three rectangles. Each
scale is tried only on the rows its height is allowed at (the height prior); after a fit only
the placements its pixels touch are scored again.
"""

from __future__ import annotations

import cv2
import numpy as np

from occbench.trackers.frontend.silhouette_template import HEAD_FRACTION

CELL_ROWS = 12  # the template's box-sum cells: the head band (top 1/7) and 11 bands below it,
CELL_COLS = 10  # ... by 10 columns


class _Scales:
    """The template at every searched height, as rectangles whose sums an integral image
    gives in O(1) per placement.

    Scale s (template ``templates[s]``, ``size[s]`` = (th, tw) rows and columns):

    * cells: row edges ``ys[s]`` (CELL_ROWS + 1: the head band, the top 1/7, then equal bands)
      and column edges ``xs[s]`` (CELL_COLS + 1, equal); T~ = T's mean over each cell, so
      sum T~ = sum T = ``tsum[s]``. For an image with integral I (I[y, x] = sum of the
      image above and left of (y, x)) and a placement with top-left (Y, X),

          sum T~ img = sum_cells w_cell boxsum(cell) = sum_{a, b} coef[s, a, b] I[Y + ys[a], X + xs[b]]

      (``coef``: each corner's signed share of the cells around it);
    * the head rule's rectangles ``head[s]`` = (kh, h0, h1, l1, r0): rows [0, kh) (the head
      band); the head, columns [h0, h1) where the band's mean T > 0.5; beside it, columns
      [0, l1) and [r0, tw) where it is < 0.1;
    * ``occ[s]``: (th, tw) pixels a fit marks occupied (T > occupy_level), zero-padded to
      the largest scale.
    """

    def __init__(self, templates: list[np.ndarray], occupy_level: float) -> None:
        S = len(templates)
        self.templates = templates
        self.size = np.array([t.shape for t in templates], dtype=np.int64)
        self.tsum = np.array([float(t.sum()) for t in templates])
        self.ys = np.zeros((S, CELL_ROWS + 1), dtype=np.int64)
        self.xs = np.zeros((S, CELL_COLS + 1), dtype=np.int64)
        self.coef = np.zeros((S, CELL_ROWS + 1, CELL_COLS + 1))
        self.head = np.zeros((S, 5), dtype=np.int64)
        hmax, wmax = self.size.max(axis=0)
        self.occ = np.zeros((S, hmax, wmax), dtype=np.uint8)
        for s, t in enumerate(templates):
            th, tw = t.shape
            kh = max(round(th * HEAD_FRACTION), 1)  # PBM 2.1: the head is 1/7 of the height
            ys = np.r_[0, np.round(np.linspace(kh, th, CELL_ROWS)).astype(np.int64)]
            xs = np.round(np.linspace(0, tw, CELL_COLS + 1)).astype(np.int64)
            w = np.zeros((CELL_ROWS + 2, CELL_COLS + 2))  # zero border: corners' neighbours
            for a in range(CELL_ROWS):
                for b in range(CELL_COLS):
                    cell = t[ys[a] : ys[a + 1], xs[b] : xs[b + 1]]
                    w[a + 1, b + 1] = cell.mean() if cell.size else 0.0
            self.coef[s] = w[:-1, :-1] - w[:-1, 1:] - w[1:, :-1] + w[1:, 1:]
            self.ys[s], self.xs[s] = ys, xs
            band = t[:kh].mean(axis=0)
            inside = np.flatnonzero(band > 0.5)
            h0, h1 = (inside[0], inside[-1] + 1) if len(inside) else (np.argmax(band), np.argmax(band) + 1)
            l1 = int(np.argmax(band[:h0] >= 0.1)) if (band[:h0] >= 0.1).any() else int(h0)
            right = band[h1:][::-1]
            r0 = tw - (int(np.argmax(right >= 0.1)) if (right >= 0.1).any() else len(right))
            self.head[s] = (kh, h0, h1, l1, r0)
            self.occ[s, :th, :tw] = t > occupy_level


def _box(I: np.ndarray, y0, x0, y1, x1):
    """Box sums [y0, y1) x [x0, x1) of the image whose integral is I (arrays of boxes)."""
    return I[y1, x1] - I[y0, x1] - I[y1, x0] + I[y0, x0]


def _integral(img: np.ndarray) -> np.ndarray:
    return cv2.integral(img, sdepth=cv2.CV_32S)


def greedy_search(vp, op, py, px, H, W, ids, bands, ys, xs, coef, size, tsum, head, occ,
                  alpha, beta, threshold, min_visible, head_contrast, fits) -> int:
    """The greedy fits of one region (the plain-numpy equations; ``_silhouette_kernel``
    compiles them).

    Args:
        vp, op: (H + 2 py, W + 2 px) uint8 0/1 vacant and occupied foreground of the region's
            crop, zero-padded by (py, px) (occupied = 1 beyond a frame border: unknown);
            updated in place as fits occupy pixels.
        ids, bands: the scales searched, and for each the centre rows [b0, b1) of the crop
            it is tried at (its height allowed there); every column is tried.
        ys .. occ: the ``_Scales`` arrays.
        fits: (max_people, 9) float64 output, one row per fit in greedy order: scale, top,
            left (crop pixels), E, score E / M, and the box [x0, y0, x1) x [y0, y1) of the
            foreground it explained (-1 when none).
    Returns:
        the number of fits.
    """
    if not len(ids):
        return 0
    s_, r_, c_ = [], [], []
    for s, (b0, b1) in zip(ids, bands):
        r, c = np.mgrid[b0:b1, 0:W]
        s_.append(np.full(r.size, s))
        r_.append(r.ravel())
        c_.append(c.ravel())
    s = np.concatenate(s_)
    th, tw = size[s, 0], size[s, 1]
    Y = np.concatenate(r_) - th // 2 + py  # a kernel is anchored at its centre
    X = np.concatenate(c_) - tw // 2 + px
    rows, cols = Y[:, None, None] + ys[s][:, :, None], X[:, None, None] + xs[s][:, None, :]

    def cells(I):  # sum of T~ over the image of integral I at every placement
        return (coef[s] * I[rows, cols]).sum(axis=(1, 2))

    ts = tsum[s]
    head_ok = np.ones(len(s), dtype=bool)
    if head_contrast > -1.0:  # on the region's foreground before any fit (unknown = fg)
        K, V0 = _integral(vp + op), _integral(vp)
        kh, h0, h1, l1, r0 = head[s].T
        hin = np.minimum(_box(K, Y, X + h0, Y + kh, X + h1), kh * (h1 - h0))
        hout = _box(V0, Y, X, Y + kh, X + l1) + _box(V0, Y, X + r0, Y + kh, X + tw)
        head_ok = (hin / np.maximum(kh * (h1 - h0), 1e-6)
                   - hout / np.maximum(kh * (l1 + tw - r0), 1e-6)) >= head_contrast
    n = 0
    for _ in range(len(fits)):
        IV, IO = _integral(vp), _integral(op)
        tv, bx = cells(IV), _box(IV, Y, X, Y + th, X + tw)
        visible = ts - cells(IO)
        # explained mass E = sum T V - alpha sum T (1 - V) - beta sum (1 - T) V
        e = tv - alpha * (visible - tv) - beta * (bx - tv)
        ok = (head_ok & (e >= threshold * np.maximum(visible, 1e-6))
              & (visible >= min_visible * ts) & (e > 0))
        if not ok.any():
            break
        j = int(np.argmax(np.where(ok, e, -np.inf)))
        k, y, x = s[j], Y[j], X[j]
        sil = occ[k, : th[j], : tw[j]] > 0
        win_v, win_o = vp[y : y + th[j], x : x + tw[j]], op[y : y + th[j], x : x + tw[j]]
        claimed = sil & (win_v > 0)  # the foreground this fit explains
        win_o[claimed] = 1
        win_v[sil] = 0
        fits[n, :5] = k, y - py, x - px, e[j], e[j] / max(visible[j], 1e-6)
        fits[n, 5:] = -1.0
        if claimed.any():
            rr, cc = np.flatnonzero(claimed.any(axis=1)), np.flatnonzero(claimed.any(axis=0))
            fits[n, 5:] = x - px + cc[0], y - py + rr[0], x - px + cc[-1] + 1, y - py + rr[-1] + 1
        n += 1
    return n


def region_arrays(small: np.ndarray, lab: np.ndarray, region: np.ndarray,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The zero-padded vacant and occupied arrays of one region (``search_regions``)."""
    label, x0, y0, x1, y1, py, px, top, bottom, left, right = (int(v) for v in region)
    H, W = y1 - y0, x1 - x0
    vp = np.zeros((H + 2 * py, W + 2 * px), dtype=np.uint8)
    op = np.zeros_like(vp)
    # only this region's pixels (others are found from their own)
    vp[py : py + H, px : px + W] = (lab[y0:y1, x0:x1] == label) & (small[y0:y1, x0:x1] > 0)
    if top:  # beyond the frame's border: unknown, counted as occupied
        op[:py] = 1
    if bottom:
        op[py + H :] = 1
    if left:
        op[:, :px] = 1
    if right:
        op[:, px + W :] = 1
    return vp, op


def search_regions(small, lab, regions, bands, ys, xs, coef, size, tsum, head, occ, alpha, beta,
                   threshold, min_visible, head_contrast, fits, counts) -> None:
    """``greedy_search`` on every region of a frame (compiled: ``_silhouette_kernel``).

    Args:
        small: (h, w) uint8 0/1 foreground at working resolution; lab: its (h, w) int32
            component labels.
        regions: (n, 11) int64 rows: label, crop x0, y0, x1, y1 (working pixels), padding
            py, px, and whether the crop's top, bottom, left, right side is the frame border.
        bands: (n, n_scales, 2) int64 centre rows [b0, b1) of the crop each scale is tried
            at (b0 = b1: not tried).
        fits: (n, max_people, 9) float64 output (``greedy_search``'s rows); counts: (n,)
            int64 output, fits per region.
    """
    for i, region in enumerate(regions):
        vp, op = region_arrays(small, lab, region)
        ids = np.flatnonzero(bands[i, :, 1] > bands[i, :, 0])
        counts[i] = greedy_search(vp, op, int(region[5]), int(region[6]), int(region[4] - region[2]),
                                  int(region[3] - region[1]), ids, bands[i, ids], ys, xs, coef,
                                  size, tsum, head, occ, alpha, beta, threshold, min_visible,
                                  head_contrast, fits[i])

