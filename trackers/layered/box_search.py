"""PBM 3.1's search boxes (eqs. 9-10), compiled: each box measured as ``part_features``
measures it (PBM 2.1-2.2) and scored by eqs. 11-13 against its target
(``box_scores_kernel``, bit for bit ``part_features`` then ``_pair_scores_kernel``), with a
branch and bound over the boxes of a searched pair (only the first maximum of p counts,
``gating.carved_rows``): upper bounds of p from a table of p(x | theta) (``survival_bounds``,
``_score_bound``) leave unscored the boxes that cannot be that maximum (``_score_group``).

``coarse`` (``adaptations.coarse_search``, ours; off in the paper's mode): a pair's boxes
are searched coarse to fine (``_coarse_group``) instead of all measured: every other width
and height first, then the neighbours of the best of those; the boxes never measured
are left unscored. Not exact: the chosen box is the best of the boxes visited. Its own
kernel (``coarse_box_scores_kernel``), so a run with the switch off never compiles it.

The mixture models are ``(w, mu, s)``; a feature set is ``(parts, area, perimeter, hsv,
xyz, centroid, height)`` (``PartFeatures``' arrays).
"""

from __future__ import annotations

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)
from occbench.trackers.layered.box_groups import _measure, _measure_all
from occbench.trackers.layered.sampling_kernels import _box_scratch
from occbench.trackers.layered.scores import _memo, _score_row, _survival

BOUND_CELLS = 2048
"""Cells per unit of x of ``survival_bounds``' table (a power of two: x * 2048 is exact)."""


BOUND_SLACK = 1e-12
"""Added to each bound: covers erfc's rounding (about 1e-16 on p(x | theta) <= 1)."""


@numba.njit(cache=True)
def survival_bounds(theta: tuple) -> np.ndarray:
    """(6, 5, BOUND_CELLS + 1) upper bounds of p(x | theta_ij) (``_survival``): entry m
    bounds every x in [m, m + 1) / BOUND_CELLS, the last every x >= 1. A survival function
    P(D >= x) does not increase with x, so the value at the cell's left end, plus
    ``BOUND_SLACK``, bounds the cell (``_score_bound``)."""
    w, mu, s = theta
    out = np.empty((w.shape[0], w.shape[1], BOUND_CELLS + 1))
    for i in range(w.shape[0]):
        for j in range(w.shape[1]):
            for c in range(BOUND_CELLS + 1):
                out[i, j, c] = _survival(c / BOUND_CELLS, w, mu, s, i, j) + BOUND_SLACK
    return out


@numba.njit(cache=True, inline="always")
def _score_bound(d: np.ndarray, k: int, spread: float, weights: tuple, table: np.ndarray) -> float:
    """An upper bound of ``_score_row``'s p of differences d[k] (6, 5): the same sums in the
    same order with each p(x | theta_ij) replaced by its bound in ``table``
    (``survival_bounds``); rounding to nearest never decreases a sum or a product by a
    weight >= 0 when an operand grows, so the bound holds for the computed p, bit for bit.
    NaN when a difference is NaN."""
    omega, gamma = weights
    total = 0.0
    for j in range(d.shape[2]):
        acc = 0.0
        for i in range(d.shape[1]):
            x = d[k, i, j] / spread
            if np.isnan(x):
                return np.nan
            v = x * BOUND_CELLS if x > 0.0 else 0.0
            acc += omega[i] * table[i, j, int(v) if v < BOUND_CELLS else BOUND_CELLS]
        total += gamma[j] * acc
    return total


@numba.njit(cache=True, inline="always")
def _score_some(d: np.ndarray, g0: int, qs: np.ndarray, best: float, spread: float,
                weights: tuple, theta: tuple, memo: tuple, table: np.ndarray, pj: np.ndarray,
                p: np.ndarray) -> float:
    """``_score_row`` of the boxes g0 + qs[a] of a group of which only the first maximum of
    p counts (``carved_rows``), ``best`` the highest p already scored in the group (-inf:
    none): scored in order of their bounds (``_score_bound``), highest first; once a bound
    is below the best p scored, that box and the rest cannot reach it and are left
    unscored (p -inf, p_j NaN). Every box is scored when a bound is not finite. The scored
    boxes have their own bits, so the first maximum is the same box. Returns the best p
    scored (NaN when a bound is not finite)."""
    n = qs.shape[0]
    ub = np.empty(n)
    for a in range(n):
        ub[a] = _score_bound(d, g0 + qs[a], spread, weights, table)
    if not np.isfinite(ub).all():
        for a in range(n):
            _score_row(d, g0 + qs[a], spread, weights, theta, memo, pj, p, g0 + qs[a])
        return np.nan
    for a in np.argsort(-ub):
        k = g0 + qs[a]
        if ub[a] < best:
            p[k] = -np.inf
            pj[k, :] = np.nan
            continue
        _score_row(d, k, spread, weights, theta, memo, pj, p, k)
        if p[k] > best:  # noqa: PLR1730 (p is finite here)
            best = p[k]
    return best


@numba.njit(cache=True)
def _coarse_group(g0: int, size: int, measure: tuple, rule: tuple, memo: tuple,
                  table: np.ndarray, pj: np.ndarray, p: np.ndarray) -> None:
    """``adaptations.coarse_search`` on the group of boxes g0 .. g0 + size - 1, a side x
    side grid (box i side + k: width i, height k, ``search_boxes_many``): the boxes of even
    i and k are measured and scored (``_score_some``), then the unmeasured neighbours (i, k
    +-1, the diagonals too) of the first maximum among them; boxes never measured are left
    unscored (p -inf, p_j NaN). When a bound is not finite every box is measured and
    scored (``_score_group``). ``measure``: ``_measure``'s arguments after k and before d,
    then d."""
    boxes, ti, ratios, sampling, m, gap, scratch, d = measure
    spread, weights, theta = rule
    side = int(round(np.sqrt(size)))
    seen = np.zeros(size, np.bool_)
    qs = np.empty(size, np.int64)
    n = 0
    for i in range(0, side, 2):
        for k in range(0, side, 2):
            qs[n] = i * side + k
            n += 1
    stage, best = 0, -np.inf  # 0: the coarse boxes, 1: the best one's neighbours, 2: all
    while n > 0:
        for a in range(n):  # one call site: the measuring is inlined once
            _measure(g0 + qs[a], boxes, ti, ratios, sampling, m, gap, scratch, d)
            seen[qs[a]] = True
        if stage == 2:
            _score_group(d, g0, size, spread, weights, theta, memo, table, pj, p)
            return
        best = _score_some(d, g0, qs[:n], best, spread, weights, theta, memo, table, pj, p)
        if stage == 1:
            break
        stage, top, n0 = 1, qs[0], n
        for a in range(1, n0):
            if p[g0 + qs[a]] > p[g0 + top]:
                top = qs[a]
        ci, ck, n = top // side, top % side, 0
        if np.isnan(best):  # not bounded: measure the rest, score them all
            stage = 2
            for q in range(size):
                if not seen[q]:
                    qs[n] = q
                    n += 1
            continue
        for i in range(max(ci - 1, 0), min(ci + 2, side)):
            for k in range(max(ck - 1, 0), min(ck + 2, side)):
                if not seen[i * side + k]:
                    qs[n] = i * side + k
                    n += 1
    for q in range(size):
        if not seen[q]:
            p[g0 + q] = -np.inf
            pj[g0 + q, :] = np.nan


@numba.njit(cache=True, inline="always")
def _score_group(d: np.ndarray, g0: int, size: int, spread: float, weights: tuple,
                 theta: tuple, memo: tuple, table: np.ndarray, pj: np.ndarray,
                 p: np.ndarray) -> None:
    """``_score_some`` of the whole group g0 .. g0 + size - 1 (the exact search)."""
    _score_some(d, g0, np.arange(size), -np.inf, spread, weights, theta, memo, table, pj, p)


@numba.njit(cache=True)
def _kernel_state(boxes: np.ndarray, ti: np.ndarray, sampling: tuple, m: tuple, rule: tuple,
                  theta: tuple) -> tuple:
    """The checks and scratch of ``box_scores_kernel`` and ``coarse_box_scores_kernel``:
    ((``_box_scratch``, the one-row features, ``_rho``'s index scratch, ``listed``),
    the normalised (omega, gamma), ``_memo``, d (K, 6, 5), p_j (K, 5), p (K,))."""
    grid = sampling[0]
    omega, gamma = rule[1], rule[2]
    K, T, nb = boxes.shape[0], m[1].shape[0], m[3].shape[2]
    for k in range(K):
        if not 0 <= ti[k] < T:
            raise IndexError("selected pair index out of range")
    finite = np.empty((T, 2, 5), np.bool_)
    for t in range(T):
        for j in range(5):
            finite[t, 0, j] = np.isfinite(m[3][t, j]).all()
            finite[t, 1, j] = np.isfinite(m[4][t, j]).all()
    s = _box_scratch(grid[0].shape[0], grid[1].shape[0], nb)
    one = (np.empty((1, 5, 4)), np.empty((1, 5)), np.empty((1, 5)), np.empty((1, 5, nb)),
           np.empty((1, 5, nb)), np.empty((1, 5, 2)), np.empty(1))
    idx = np.empty(max(nb, m[4].shape[2]), np.int64)
    scratch = (s, one, idx, (nb <= 64, s[13], finite))
    weights = (omega / omega.sum(), gamma / gamma.sum())
    memo = _memo(theta[0].shape[0], m[1].shape[1])
    d = np.empty((K, theta[0].shape[0], m[1].shape[1]))
    return scratch, weights, memo, d, np.empty((K, m[1].shape[1])), np.empty(K)


@numba.njit(cache=True)
def box_scores_kernel(boxes: np.ndarray, ti: np.ndarray, ratios: tuple, sampling: tuple, m: tuple,
               gap: tuple, rule: tuple, theta: tuple, groups: tuple
               ) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 11-13 of K boxes of the frame, each measured as ``part_features`` measures it
    (PBM 2.1-2.2), against the model of target ti[k]: p_j (K, 5) and p (K,), bit for bit
    ``part_features`` then ``_pair_scores_kernel(m, features, ti, arange(K), ...)``, with
    no (K, 5, B) histograms: each box's features are made in a one-row scratch, compared
    and dropped, and rho sums the occupied bins only (``_rho_listed``) where the model's
    histogram is finite. The search's boxes (PBM 3.1, eqs. 9-10): 25 per searched pair, of
    which the tracker keeps one.

    Args:
        boxes: (K, 4) xywh. ti: (K,) target rows (IndexError when out of range).
        ratios: (alpha, beta), each (K,), of the boxes' split (eqs. 1-2).
        sampling: (grid, image, luts, pixel_bins) as ``part_features``'.
        m: the targets' models (a feature set). gap: (misses (T,) float64, apart) as
            ``differences._pair_differences``'.
        rule: (spread, omega (6,), gamma (5,)) as ``_pair_scores_kernel``'s.
        groups: (size, grouped, table): boxes 0 .. grouped - 1 are consecutive groups of
            ``size`` of which only the first maximum of p counts, scored by
            ``_score_group`` (``table``: ``survival_bounds(theta)``); size 0: none.
    """
    scratch, weights, memo, d, pj, p = _kernel_state(boxes, ti, sampling, m, rule, theta)
    spread = rule[0]
    size, grouped, table = groups
    _measure_all(boxes, ti, ratios, sampling, m, gap, scratch, size, grouped, d)
    first = 0
    if size > 0:
        for g0 in range(0, grouped, size):
            _score_group(d, g0, size, spread, weights, theta, memo, table, pj, p)
        first = grouped
    for k in range(first, boxes.shape[0]):
        _score_row(d, k, spread, weights, theta, memo, pj, p, k)                      # eqs. 12-13
    return pj, p


@numba.njit(cache=True)
def coarse_box_scores_kernel(boxes: np.ndarray, ti: np.ndarray, ratios: tuple, sampling: tuple,
                             m: tuple, gap: tuple, rule: tuple, theta: tuple,
                             groups: tuple) -> tuple[np.ndarray, np.ndarray]:
    """``box_scores_kernel`` with each group of ``groups`` (size > 0) searched coarse to fine
    (``_coarse_group``, ``adaptations.coarse_search``); the boxes past the groups are
    measured and scored as there. Its own kernel: a run with the switch off never compiles
    it."""
    scratch, weights, memo, d, pj, p = _kernel_state(boxes, ti, sampling, m, rule, theta)
    spread = rule[0]
    size, grouped, table = groups
    measure = (boxes, ti, ratios, sampling, m, gap, scratch, d)
    for g0 in range(0, grouped, size):
        _coarse_group(g0, size, measure, (spread, weights, theta), memo, table, pj, p)
    for k in range(grouped, boxes.shape[0]):
        _measure(k, boxes, ti, ratios, sampling, m, gap, scratch, d)
        _score_row(d, k, spread, weights, theta, memo, pj, p, k)                      # eqs. 12-13
    return pj, p
