"""PBM 3.1's search boxes measured (PBM 2.1-2.2) and compared with their target (eq. 11),
compiled, for ``box_search``: one box as ``part_features`` measures it (``_measure``), or a
grid of boxes together (``_measure_grid``, the same bits): the boxes of a searched pair
are a grid of widths and heights hanging from one head (``search.search_boxes_many``), so
each height's sample rows, each width's sample columns and each (width, pixel row)'s
foreground samples are made once for the pair instead of once per box.
"""

from __future__ import annotations

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)
from occbench.trackers.layered.differences import _pair_differences
from occbench.trackers.layered.sampling_kernels import (_NO_CENTRES, _bands, _box_counts, _box_features,
                                                       _clip_index, _count_rows, _sides)
from occbench.trackers.layered.split import _part_rects


@numba.njit(cache=True, inline="always")
def _measure(k: int, boxes: np.ndarray, ti: np.ndarray, ratios: tuple, sampling: tuple,
             m: tuple, gap: tuple, scratch: tuple, d: np.ndarray) -> None:
    """Box k measured as ``part_features`` measures it (``_box_counts``, ``_box_features``
    into the one-row feature set of ``scratch``) and eq. 11 of it against target ti[k]
    into d[k]. ``scratch``: (``_box_scratch``, the one-row features, ``_rho``'s index
    scratch, ``listed`` of ``_pair_differences``)."""
    grid, image, luts, pixel_bins = sampling
    s, one, idx, listed = scratch
    bands = _box_counts(boxes, k, ratios[0], ratios[1], False, _NO_CENTRES, grid, image,
                        luts, pixel_bins, s, one[0][0])
    _box_features(s, bands, one[0][0], 0, one[1:6])
    one[6][0] = boxes[k, 3]
    t = ti[k]
    _pair_differences(m, one, t, 0, gap, d, k, idx, listed)  # eq. 11


@numba.njit(cache=True, inline="always")
def _same(a: float, b: float) -> bool:
    """a and b the same float bit for bit (NaN never: a group holding one is measured box by box)."""
    return a == b and (a != 0.0 or np.copysign(1.0, a) == np.copysign(1.0, b))


@numba.njit(cache=True)
def _is_grid(boxes: np.ndarray, alpha: np.ndarray, beta: np.ndarray, g0: int, side: int) -> bool:
    """Whether the boxes g0 + i side + k (i, k < side) share their top and beta, box (i, k)
    its height with (0, k) and its left edge, width and alpha with (i, 0), bit for bit (the
    search's boxes, ``search_boxes_many``): the samples of box (i, k) are then rows k's and
    columns i's."""
    for i in range(side):
        a = g0 + i * side
        for k in range(side):
            q = a + k
            if not (_same(boxes[q, 1], boxes[g0, 1]) and _same(beta[q], beta[g0])
                    and _same(boxes[q, 3], boxes[g0 + k, 3]) and _same(boxes[q, 0], boxes[a, 0])
                    and _same(boxes[q, 2], boxes[a, 2]) and _same(alpha[q], alpha[a])):
                return False
    return True


@numba.njit(cache=True, inline="always")
def _group_axes(g0: int, side: int, boxes: np.ndarray, ratios: tuple, grid: tuple, H: int,
                W: int, axes: tuple, p: np.ndarray) -> None:
    """The sample rows of each height k (``ys``, ``yi``, their bands and band sizes) and the
    sample columns of each width i (``xs``, their pixel columns, sides, right mask and
    size) of a grid of boxes (``_is_grid``), as ``_box_counts`` makes them per box."""
    fr, fc = grid
    alpha, beta = ratios
    ys, yi, band, rows, xs, coff, right, rmask, ncols = axes[:9]
    for k in range(side):
        b = g0 + k
        _part_rects(boxes[b, 0], boxes[b, 1], boxes[b, 2], boxes[b, 3], alpha[b], beta[b], p)
        for r in range(fr.shape[0]):
            ys[k, r] = boxes[b, 1] + fr[r] * boxes[b, 3]
            yi[k, r] = _clip_index(ys[k, r], H)
        rows[k, 0], rows[k, 1], rows[k, 2] = _bands(ys[k], p[0, 1] + p[0, 3], p[1, 1] + p[1, 3],
                                                    band[k])
    for i in range(side):
        b = g0 + i * side
        _part_rects(boxes[b, 0], boxes[b, 1], boxes[b, 2], boxes[b, 3], alpha[b], beta[b], p)
        for c in range(fc.shape[0]):
            xs[i, c] = boxes[b, 0] + fc[c] * boxes[b, 2]
            coff[i, c] = np.uint64(_clip_index(xs[i, c], W))
        rmask[i], ncols[i] = _sides(xs[i], p[1, 0] + p[1, 2], right[i])


@numba.njit(cache=True, inline="always")
def _group_masks(i: int, k: int, H: int, W: int, image: tuple, axes: tuple, masks: np.ndarray
                 ) -> None:
    """The foreground samples of box (i, k) of a grid (``_group_axes``) as row bit masks
    (``_row_masks``), each (width, pixel row) made once per group (``cache``, ``stamp``)."""
    frame, fg, has_fg = image
    ys, yi, xs, coff = axes[0], axes[1], axes[4], axes[5]
    cache, stamp, gid = axes[9], axes[10], axes[11][0]
    for r in range(ys.shape[1]):
        if not (ys[k, r] >= 0.0 and ys[k, r] < H):
            masks[r] = np.uint64(0)
            continue
        y = yi[k, r]
        if stamp[i, y] != gid:
            bits = np.uint64(0)
            for c in range(xs.shape[1]):
                inside = xs[i, c] >= 0.0 and xs[i, c] < W
                if inside and has_fg:
                    inside = fg[y, coff[i, c]]
                bits |= np.uint64(inside) << np.uint64(c)
            cache[i, y], stamp[i, y] = bits, gid
        masks[r] = cache[i, y]


@numba.njit(cache=True)
def _measure_grid(g0: int, side: int, boxes: np.ndarray, ti: np.ndarray, ratios: tuple,
                  sampling: tuple, m: tuple, gap: tuple, scratch: tuple, axes: tuple,
                  d: np.ndarray) -> None:
    """``_measure`` of the boxes g0 .. g0 + side^2 - 1, a grid (``_is_grid``; any one box is a
    grid of side 1), the same bits: each height's rows and each width's columns made once
    (``_group_axes``), each (width, pixel row)'s foreground mask once (``_group_masks``).
    ``axes``: ``_group_scratch``. Not inlined: the kernels call it at several places and
    compile it once."""
    grid, image, luts, pixel_bins = sampling
    s, one, idx, listed = scratch
    frame = image[0]
    H, W = frame.shape[0], frame.shape[1]
    table, stamp, shift = pixel_bins
    colours = (frame.reshape(H * W * 3), luts, np.uint64(stamp), np.uint64(shift))
    p = one[0][0]
    axes[11][0] += 1
    _group_axes(g0, side, boxes, ratios, grid, H, W, axes, p)
    ys, yi, band, rows, xs, coff, right, rmask, ncols = axes[:9]
    for i in range(side):
        for k in range(side):
            q = g0 + i * side + k
            _group_masks(i, k, H, W, image, axes, s[14])
            _part_rects(boxes[q, 0], boxes[q, 1], boxes[q, 2], boxes[q, 3], ratios[0][q],
                        ratios[1][q], p)
            _count_rows(s[14], band[k], yi[k], W, coff[i], rmask[i], xs[i], ys[k], table,
                        colours, s)
            _box_features(s, (rows[k, 0], rows[k, 1], rows[k, 2], ncols[i]), p, 0, one[1:6])
            one[6][0] = boxes[q, 3]
            t = ti[q]
            _pair_differences(m, one, t, 0, gap, d, q, idx, listed)  # eq. 11


@numba.njit(cache=True, inline="always")
def _measure_all(boxes: np.ndarray, ti: np.ndarray, ratios: tuple, sampling: tuple, m: tuple,
                 gap: tuple, scratch: tuple, size: int, grouped: int, d: np.ndarray
                 ) -> None:
    """``_measure`` of every box into d: the groups of ``size`` boxes 0 .. grouped - 1 that
    are grids (``_is_grid``) together, every other box alone (``_measure_grid``)."""
    side = int(round(np.sqrt(size))) if size > 0 else 0
    axes = _group_scratch(max(side, 1), sampling[0][0].shape[0], sampling[0][1].shape[0],
                          sampling[1][0].shape[0])
    first = 0
    if side > 0 and side * side == size:
        for g0 in range(0, grouped, size):
            if _is_grid(boxes, ratios[0], ratios[1], g0, side):
                _measure_grid(g0, side, boxes, ti, ratios, sampling, m, gap, scratch, axes, d)
            else:
                for q in range(g0, g0 + size):
                    _measure_grid(q, 1, boxes, ti, ratios, sampling, m, gap, scratch, axes, d)
        first = grouped
    for q in range(first, boxes.shape[0]):
        _measure_grid(q, 1, boxes, ti, ratios, sampling, m, gap, scratch, axes, d)


@numba.njit(cache=True)
def _group_scratch(side: int, R: int, C: int, H: int) -> tuple:
    """``_measure_grid``'s scratch: per height (ys, yi, band (side, R), band sizes (side,
    3)), per width (xs, pixel columns, sides (side, C), right mask, right size (side,)),
    the (width, pixel row) masks and their group stamps (side, H) and the group count (1,)."""
    return (np.empty((side, R)), np.empty((side, R), np.int64), np.empty((side, R), np.int64),
            np.empty((side, 3), np.int64), np.empty((side, C)), np.empty((side, C), np.uint64),
            np.empty((side, C), np.int64), np.empty(side, np.uint64), np.empty(side, np.int64),
            np.empty((side, H), np.uint64), np.zeros((side, H), np.int64), np.zeros(1, np.int64))
