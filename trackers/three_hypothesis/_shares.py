"""The compiled shares of a region that other people's regions cover, from eq. 5's delta
(|S_m & S_d| = delta (|S_m| + |S_d|) / 2) of the frame's pairs (numba, one core): step 6's
own share of each matched measurement (``contact.own_shares``), the share of a region the
visible people cover (``occlusion.covered_fraction``: step 6's v of a person behind, step
8's spawned hypotheses), step 8's hidden share of each continued hypothesis
(``steps_hypotheses._hidden_share``), and the measurements another person's region meets
(``tentative.clear_measurements``). Each is the numpy expression it replaced, pair by pair in
the same order with the same operations (numpy's NaN rules of maximum and minimum kept): the
same bits (``tests/trackers/three_hypothesis/test_shares.py`` against per-row definitions).

Compiled with numba's ``cache=True``: the cache sits in ``__pycache__`` beside this file, keyed on
the file's time stamp (not on its import name).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.sparse import csr_array

from occbench.trackers.three_hypothesis._kernels import region_overlap_pairs


def csr(delta: csr_array) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The (B + 1,) indptr, (E,) indices (int64) and (E,) data (float64) of a sparse (B, D)
    delta as CSR, the kernels' form of it."""
    delta = delta.tocsr()  # no copy where they already have these types (O.delta: _csr)
    return (delta.indptr.astype(np.int64, copy=False), delta.indices.astype(np.int64, copy=False),
            delta.data.astype(np.float64, copy=False))


@numba.njit(cache=True, inline="always")
def _maximum(a: float, b: float) -> float:
    """numpy's ``np.maximum(a, b)`` of two float64: a NaN of either wins, a tie keeps a."""
    return a if (a >= b or math.isnan(a)) else b


@numba.njit(cache=True, inline="always")
def _delta(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, row: int, col: int
           ) -> float:
    """The stored delta[row, col] of a CSR matrix (the last entry of a repeat), else 0."""
    out = 0.0
    for e in range(indptr[row], indptr[row + 1]):
        if indices[e] == col:
            out = data[e]
    return out


@numba.njit(cache=True)
def own_shares(pairs: np.ndarray, owners: np.ndarray, hidden: np.ndarray, row: np.ndarray,
               det: np.ndarray, area_n: np.ndarray, area_d: np.ndarray, indptr: np.ndarray,
               indices: np.ndarray, data: np.ndarray, own: np.ndarray,
               partners: np.ndarray, want_partners: bool) -> None:  # pragma: no cover
    """``contact.own_shares``: per matched row r (measurement det[r]), own[r] = clip(1 - max
    |S_m & S_d| / max(|S_d|, 1e-9), 0, 1) over O's pairs (n, m) both ways whose node n is
    row r's (``row``: node -> matched row, -1) and whose m's person is ``hidden``; ``own``
    is left where a row has none. ``partners[r]``: the person of the largest cover (the
    last of a tie in the pairs' order, a NaN largest), when ``want_partners``."""
    biggest = np.full(own.shape[0], -np.inf)
    best = np.full(own.shape[0], -np.inf)
    seen = np.zeros(own.shape[0], np.bool_)
    for side in range(2):  # (a, b) of every pair, then (b, a)
        for q in range(pairs.shape[0]):
            n, m = pairs[q, side], pairs[q, 1 - side]
            r = row[n]
            if not hidden[owners[m]] or r < 0:
                continue
            inter = _delta(indptr, indices, data, m, det[r]) * (area_n[m] + area_d[r]) / 2
            biggest[r] = _maximum(biggest[r], inter)
            if want_partners and (not seen[r] or math.isnan(inter)
                                  or (not math.isnan(best[r]) and inter >= best[r])):
                best[r], partners[r] = inter, owners[m]
            seen[r] = True
    for r in range(own.shape[0]):
        if seen[r]:
            share = 1.0 - biggest[r] / _maximum(area_d[r], 1e-9)
            own[r] = 0.0 if share < 0.0 else (1.0 if share > 1.0 else share)


@numba.njit(cache=True)
def hidden_shares(src: np.ndarray, area_n: np.ndarray, indptr: np.ndarray, indices: np.ndarray,
                  data: np.ndarray, column: np.ndarray, area_v: np.ndarray,
                  fraction: np.ndarray) -> None:  # pragma: no cover (compiled)
    """``steps_hypotheses._hidden_share`` of the hypotheses continuing node src[k] >= 0:
    fraction[k] = max(0, max |S_n & S_v| / max(|S_n|, 1e-9)) over the stored delta[n, d]
    (CSR) of the measurements d of a person visible at t (``column``: d -> its row of the
    visible regions, whose areas are ``area_v``; -1: none). ``area_n``: every node's area."""
    for k in range(src.shape[0]):
        n = src[k]
        if n < 0:
            continue
        h = 0.0
        for e in range(indptr[n], indptr[n + 1]):
            v = column[indices[e]]
            if v >= 0:
                cover = data[e] * (area_n[n] + area_v[v]) / 2
                h = _maximum(h, cover / _maximum(area_n[n], 1e-9))
        fraction[k] = h


@numba.njit(cache=True)
def crowded_by_others(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray,
                      owners: np.ndarray, column: np.ndarray, row_owners: np.ndarray,
                      crowded: np.ndarray) -> None:  # pragma: no cover (compiled)
    """``tentative.clear_measurements``' second test: crowded[r] = True where the stored
    delta[n, d] > 0 (CSR, every node n) of a measurement d of row r = column[d] >= 0 comes
    from a node of another person than row r's (``row_owners``)."""
    for n in range(indptr.shape[0] - 1):
        for e in range(indptr[n], indptr[n + 1]):
            r = column[indices[e]]
            if r >= 0 and data[e] > 0 and owners[n] != row_owners[r]:
                crowded[r] = True


@numba.njit(cache=True, inline="always")
def _minimum(a: float, b: float) -> float:
    """numpy's ``np.minimum(a, b)`` of two float64: a NaN of either wins, a tie keeps a."""
    return a if (a <= b or math.isnan(a)) else b


@numba.njit(cache=True)
def covered(boxes: np.ndarray, visible: np.ndarray, ia: np.ndarray, ib: np.ndarray,
            test_meet: bool, grid: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """``occlusion.covered_fraction`` of the pairs (boxes[ia[k]], visible[ib[k]]) (only
    those whose boxes meet, ``occlusion.boxes_meet``'s arithmetic, when ``test_meet``): out[i] =
    max(out[i], delta (|S_i| + |S_v|) / 2 / max(|S_i|, 1e-9)) pair by pair, eq. 5's delta
    from ``_kernels.region_overlap_pairs`` on ``grid``, |S| = pi / 4 w h."""
    keep = np.ones(ia.shape[0], np.bool_)
    if test_meet:
        for k in range(ia.shape[0]):
            a, b = boxes[ia[k]], visible[ib[k]]
            w = _minimum(a[0] + a[2], b[0] + b[2]) - _maximum(a[0], b[0])
            h = _minimum(a[1] + a[3], b[1] + b[3]) - _maximum(a[1], b[1])
            keep[k] = w > 0 and h > 0
    ja, jb = ia[keep], ib[keep]
    delta = np.zeros(ja.shape[0])
    if ja.shape[0]:
        region_overlap_pairs(boxes, visible, ja, jb, grid, delta)
    for k in range(ja.shape[0]):
        i, v = ja[k], jb[k]
        area_i = math.pi / 4 * boxes[i, 2] * boxes[i, 3]
        area_v = math.pi / 4 * visible[v, 2] * visible[v, 3]
        inter = 0.5 * delta[k] * (area_i + area_v)
        out[i] = _maximum(out[i], inter / _maximum(area_i, 1e-9))
