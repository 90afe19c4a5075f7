"""Which boxes can be paired, without an (N, M) matrix: the pairs of boxes that meet, and
the independent blocks an assignment over those pairs splits into.

A frame with thousands of detections would need gigabytes for dense (N, M) matrices; the
pairs a tracker can match are those whose boxes meet (or lie within a gate), so memory
grows with the pairs. ``blocks`` keeps one dense block of everything while N x M is at
most ``DENSE_LIMIT`` (every ordinary frame: the dense code runs as it always did).
Boxes are (N, 4) float64 xywh, 0-based pixels.

Compiled with numba's ``cache=True`` (the cache sits in ``__pycache__`` beside this file).
"""

from __future__ import annotations

from collections.abc import Callable

import numba
import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

DENSE_LIMIT = 1 << 18  # largest N x M solved as one dense block (2 MB of float64)


def meeting_pairs(a: np.ndarray, b: np.ndarray, pad: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (i, j) of xywh boxes a (N, 4) and b (M, 4) that share a positive area once
    every box of a is grown by ``pad`` pixels on each side; ``pad`` 0 gives exactly
    ``np.nonzero(occlusion.boxes_meet(a, b))``, in that order (row-major). Memory and time
    grow with N + M + the pairs (boxes are swept along x; the test of each candidate is
    boxes_meet's arithmetic), never with N x M unless every box meets every other.

    Returns:
        ia (K,), ib (K,) int64, sorted by ia then ib.
    """
    a = np.ascontiguousarray(a, dtype=np.float64).reshape(-1, 4)
    b = np.ascontiguousarray(b, dtype=np.float64).reshape(-1, 4)
    if pad:
        a = a + np.array([-pad, -pad, 2 * pad, 2 * pad])
    if len(a) == 0 or len(b) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    a, b = _meeting_nothing(a), _meeting_nothing(b)
    order = np.argsort(b[:, 0], kind="stable")
    bs = b[order]
    widest = float(bs[:, 2].max())
    counts = np.zeros(len(a), np.int64)
    _sweep(a, bs, order, widest, counts, np.zeros(0, np.int64))
    ib = np.empty(int(counts.sum()), np.int64)
    _sweep(a, bs, order, widest, counts, ib)
    ia = np.repeat(np.arange(len(a), dtype=np.int64), counts)
    return ia, ib  # each row's columns in ascending order (``_sweep`` sorts them)


def _meeting_nothing(boxes: np.ndarray) -> np.ndarray:
    """``boxes`` with every box holding a NaN made (0, 0, -1, -1), which meets nothing: in
    ``boxes_meet`` a NaN makes the pair's width or height NaN, so it meets nothing, while
    the sweep's scalar min and max would drop a NaN of the second box."""
    bad = np.isnan(boxes).any(axis=1)
    if not bad.any():
        return boxes
    boxes = boxes.copy()
    boxes[bad] = (0.0, 0.0, -1.0, -1.0)
    return boxes


@numba.njit(cache=True)
def _sweep(a, bs, order, widest, counts, out):  # pragma: no cover (compiled)
    """Per box of a, the boxes of bs (sorted by x, ``order`` their original rows) that meet
    it: counted into ``counts`` when ``out`` is empty, else written to ``out`` (original
    rows, row by row, each row's ascending). A box of bs meeting a[i] starts left of a[i]'s
    right edge and right of its left edge minus the widest box (the candidates; each is
    then tested)."""
    m = bs.shape[0]
    fill = out.shape[0] > 0
    k = 0
    for i in range(a.shape[0]):
        ax1, ay1 = a[i, 0], a[i, 1]
        ax2, ay2 = ax1 + a[i, 2], ay1 + a[i, 3]
        lo_x = ax1 - widest - 1.0
        lo, hi = 0, m  # first bs with x >= lo_x
        while lo < hi:
            mid = (lo + hi) // 2
            if bs[mid, 0] < lo_x:
                lo = mid + 1
            else:
                hi = mid
        c = 0
        start = k
        for q in range(lo, m):
            bx1 = bs[q, 0]
            if not bx1 < ax2:
                break
            by1 = bs[q, 1]
            w = min(ax2, bx1 + bs[q, 2]) - max(ax1, bx1)
            h = min(ay2, by1 + bs[q, 3]) - max(ay1, by1)
            if w > 0 and h > 0:
                if fill:
                    j = k  # insertion into the row's ascending run out[start:k]
                    while j > start and out[j - 1] > order[q]:
                        out[j] = out[j - 1]
                        j -= 1
                    out[j] = order[q]
                    k += 1
                c += 1
        if not fill:
            counts[i] = c


def blocks(n_rows: int, n_cols: int, pairs: Callable[[], tuple[np.ndarray, np.ndarray]],
           limit: float = DENSE_LIMIT) -> list[tuple[np.ndarray, np.ndarray]]:
    """Split rows 0..n_rows-1 and columns 0..n_cols-1 into blocks no pair (ia[k], ib[k])
    of ``pairs()`` (called only when needed) crosses: the connected components of the pairs, gathered in order into blocks of at
    most ``limit`` rows x columns (a larger component is a block of its own). One block
    holding everything when n_rows x n_cols <= ``limit``. An assignment whose allowed pairs
    are among the given ones has the same optimum solved block by block.

    Returns:
        [(rows, cols)] sorted int64 index arrays, every row and column in exactly one block.
    """
    if n_rows * n_cols <= limit:
        return [(np.arange(n_rows), np.arange(n_cols))]
    ia, ib = pairs()
    n = n_rows + n_cols
    graph = coo_array((np.ones(len(ia), np.int8), (ia, n_rows + ib)), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    members = np.argsort(label, kind="stable")
    bounds = np.flatnonzero(np.diff(label[members])) + 1
    out, rows, cols = [], [], []
    n_r = n_c = 0
    for part in np.split(members, bounds):
        r, c = part[part < n_rows], part[part >= n_rows] - n_rows
        if (n_r + len(r)) * (n_c + len(c)) > limit and (n_r or n_c):
            out.append((np.sort(np.concatenate(rows)), np.sort(np.concatenate(cols))))
            rows, cols, n_r, n_c = [], [], 0, 0
        rows.append(r)
        cols.append(c)
        n_r, n_c = n_r + len(r), n_c + len(c)
    if n_r or n_c:
        out.append((np.sort(np.concatenate(rows)), np.sort(np.concatenate(cols))))
    return out
