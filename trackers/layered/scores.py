"""PBM 4, 4.1, eqs. 12-13: the part scores p_j = sum_i omega_i p(d_ij | theta_ij) and the
global score p = sum_j gamma_j p_j, in plain numpy (the definitions: ``match_probability``,
``part_scores``, ``global_score``) and compiled (``_survival``, ``_score_row``,
``_pair_scores_kernel`` with eq. 11's ``differences._differences_kernel``; the search's
boxes measured and scored in one pass, ``box_scores_kernel``), held equal to rtol 1e-9 by
``tests/trackers/layered/test_equations.py``; and PBM 4 step 4's best and runner-up
(``_ambiguous_kernel``).

The mixture models are ``(w, mu, s)``; a feature set is ``(parts, area, perimeter, hsv,
xyz, centroid, height)`` (``PartFeatures``' arrays).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numba
import numpy as np
from scipy.special import ndtr

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)
from occbench.trackers.layered.differences import _differences_kernel, _pair_differences
from occbench.trackers.layered.sampling_kernels import _NO_CENTRES, _box_counts, _box_features, _box_scratch

if TYPE_CHECKING:  # annotations only
    from occbench.trackers.layered.feature_models import FeatureModels


# ----------------------------------------------------------------------------- eqs. 12-13, plain numpy


def match_probability(models: FeatureModels, d: np.ndarray) -> np.ndarray:
    """p(d | theta) of eq. 12 as the survival function P(D >= d) of each fitted folded
    normal mixture: sum_c w_c [Phi((mu_c - d) / s_c) + Phi((-mu_c - d) / s_c)], in [0, 1].

    Args:
        d: (..., 6, 5) differences (negative ones count as 0).
    """
    d = np.maximum(np.asarray(d, dtype=np.float64), 0.0)[..., None]
    s = ndtr((models._mu - d) / models._s) + ndtr((-models._mu - d) / models._s)
    return np.clip((models._w * s).sum(-1), 0.0, 1.0)


def part_scores(models: FeatureModels, d: np.ndarray, omega: np.ndarray,
                spread: float = 1.0) -> np.ndarray:
    """Eq. 12, p_j = sum_i omega_i p(d_ij / spread | theta_ij) (omega normalised to sum 1;
    ``spread`` is our ``model_spread``, 1 in the paper): (..., 5) from d (..., 6, 5)."""
    omega = np.asarray(omega, dtype=np.float64)
    prob = match_probability(models, np.asarray(d, dtype=np.float64) / spread)
    return np.einsum("...ij,i->...j", prob, omega / omega.sum())             # eq. 12


def global_score(pj: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """Eq. 13, p = sum_j gamma_j p_j (gamma normalised to sum 1): (...,) from (..., 5)."""
    gamma = np.asarray(gamma, dtype=np.float64)
    return np.asarray(pj) @ (gamma / gamma.sum())                            # eq. 13


# ----------------------------------------------------------------------------- eqs. 12-13, compiled


_SQRT_HALF = math.sqrt(0.5)


@numba.njit(cache=True, inline="always")
def _ndtr(z: float) -> float:
    """Standard normal CDF Phi(z) = erfc(-z / sqrt 2) / 2 (``scipy.special.ndtr``)."""
    return 0.5 * math.erfc(-z * _SQRT_HALF)


@numba.njit(cache=True, inline="always")
def _survival(x: float, w: np.ndarray, mu: np.ndarray, s: np.ndarray, i: int, j: int) -> float:
    """p(d_ij | theta_ij) of eq. 12 (``match_probability``): P(D >= x) of the
    folded normal mixture (i, j) of padded (6, 5, K) arrays, x >= 0:
    sum_c w_c [Phi((mu_c - x) / s_c) + Phi((-mu_c - x) / s_c)], clipped to [0, 1] (NaN stays
    NaN). Zero-weight padding is skipped."""
    tot = 0.0
    for c in range(w.shape[2]):
        wc, mc, sc = w[i, j, c], mu[i, j, c], s[i, j, c]
        if wc == 0.0:
            continue
        a = _ndtr((mc - x) / sc)
        tot += wc * (a + (a if mc == 0.0 else _ndtr((-mc - x) / sc)))
    if tot < 0.0:
        tot = 0.0
    elif tot > 1.0:
        tot = 1.0
    return tot


@numba.njit(cache=True)
def survival_kernel(d: np.ndarray, theta: tuple, out: np.ndarray) -> None:
    """p(d | theta) of eq. 12 (``_survival``) of (n, 6, 5) differences (negative ones count
    as 0) into out (n, 6, 5)."""
    w, mu, s = theta
    for k in range(d.shape[0]):
        for i in range(d.shape[1]):
            for j in range(d.shape[2]):
                x = d[k, i, j]
                out[k, i, j] = _survival(x if not x < 0.0 else 0.0, w, mu, s, i, j)


_MEMO_BITS = 7
"""log2 of the slots of ``_score_row``'s table of p(x | theta_ij) per (i, j)."""


_HASH_MUL, _HASH_SHIFT, _SLOT_SHIFT = (np.uint64(0x9E3779B97F4A7C15), np.uint64(29),
                                       np.uint64(64 - _MEMO_BITS))


@numba.njit(cache=True, inline="always")
def _memo(n_i: int, n_j: int) -> tuple:
    """An empty table of p(x | theta_ij) per (i, j) for ``_score_row``: (filled, keys,
    values) (n_i, n_j, slots) and the (buffer, its bits) a key is read through."""
    buf = np.empty(1)
    return (np.zeros((n_i, n_j, 1 << _MEMO_BITS), np.bool_),
            np.empty((n_i, n_j, 1 << _MEMO_BITS), np.uint64),
            np.empty((n_i, n_j, 1 << _MEMO_BITS)), buf, buf.view(np.uint64))


@numba.njit(cache=True, inline="always")
def _score_row(d: np.ndarray, k: int, spread: float, weights: tuple, theta: tuple, memo: tuple,
               pj: np.ndarray, p: np.ndarray, row: int) -> None:
    """Eqs. 12-13 of differences d[k] (6, 5) into pj[row] (5,) and p[row], with the
    normalised weights (omega, gamma) (``_scores_kernel``); ``memo`` (``_memo``) recalls
    p(x | theta_ij) of an x seen before, bit for bit as ``_survival`` computes it."""
    w, mu, s = theta
    omega, gamma = weights
    filled, keys, values, buf, bits = memo
    total = 0.0
    for j in range(d.shape[2]):
        acc = 0.0
        for i in range(d.shape[1]):
            x = d[k, i, j] / spread
            buf[0] = x if not x < 0.0 else 0.0
            key = bits[0]
            slot = ((key ^ (key >> _HASH_SHIFT)) * _HASH_MUL) >> _SLOT_SHIFT
            if filled[i, j, slot] and keys[i, j, slot] == key:
                sv = values[i, j, slot]
            else:
                sv = _survival(buf[0], w, mu, s, i, j)
                filled[i, j, slot], keys[i, j, slot], values[i, j, slot] = True, key, sv
            acc += omega[i] * sv                                                       # eq. 12
        pj[row, j] = acc
        total += gamma[j] * acc                                                        # eq. 13
    p[row] = total


@numba.njit(cache=True)
def _scores_kernel(d: np.ndarray, spread: float, omega: np.ndarray, gamma: np.ndarray,
                   theta: tuple, pj: np.ndarray, p: np.ndarray) -> None:
    """Eq. 12, p_j = sum_i omega_i p(d_ij / spread | theta_ij), into pj (K, 5) and eq. 13,
    p = sum_j gamma_j p_j, into p (K,), of (K, 6, 5) differences (``part_scores``,
    ``global_score``); omega and gamma are normalised to sum 1 here.

    p(x | theta_ij) (``_survival``) is a function of x alone for each (i, j), and x repeats
    (area and perimeter take few values, an empty part's colour terms are 1): a value is
    recalled from a small table per (i, j), keyed by the bits of x, instead of computed
    again (``_score_row``); the sums are those of ``_survival`` on every term, bit for bit."""
    weights = (omega / omega.sum(), gamma / gamma.sum())
    memo = _memo(d.shape[1], d.shape[2])
    for k in range(d.shape[0]):
        _score_row(d, k, spread, weights, theta, memo, pj, p, k)


@numba.njit(cache=True)
def _pair_scores_kernel(m: tuple, c: tuple, ti: np.ndarray, n: np.ndarray, misses: np.ndarray,
                        spread: float, omega: np.ndarray, gamma: np.ndarray, theta: tuple
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 11-13 of the pairs (ti[k], n[k]) in one call: ``_differences_kernel`` then
    ``_scores_kernel``; returns p_j (K, 5) and p (K,)."""
    K = ti.shape[0]
    d = np.empty((K, theta[0].shape[0], m[1].shape[1]))
    _differences_kernel(m, c, ti, n, misses, d)
    pj, p = np.empty((K, m[1].shape[1])), np.empty(K)
    _scores_kernel(d, spread, omega, gamma, theta, pj, p)
    return pj, p


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
def _score_group(d: np.ndarray, g0: int, size: int, spread: float, weights: tuple,
                 theta: tuple, memo: tuple, table: np.ndarray, pj: np.ndarray,
                 p: np.ndarray) -> None:
    """``_score_row`` of the boxes g0 .. g0 + size - 1 of which only the first maximum of p
    counts (``carved_rows``): scored in order of their bounds (``_score_bound``), highest
    first; once a bound is below the best p scored, that box and the rest cannot reach
    it and are left unscored (p -inf, p_j NaN). Every box is scored when a bound is not
    finite. The scored boxes have their own bits, so the first maximum is the same box."""
    ub = np.empty(size)
    for q in range(size):
        ub[q] = _score_bound(d, g0 + q, spread, weights, table)
    if not np.isfinite(ub).all():
        for q in range(size):
            _score_row(d, g0 + q, spread, weights, theta, memo, pj, p, g0 + q)
        return
    best = -np.inf
    for q in np.argsort(-ub):
        k = g0 + q
        if ub[q] < best:
            p[k] = -np.inf
            pj[k, :] = np.nan
            continue
        _score_row(d, k, spread, weights, theta, memo, pj, p, k)
        if p[k] > best:  # noqa: PLR1730 (p is finite here)
            best = p[k]


@numba.njit(cache=True)
def box_scores_kernel(boxes: np.ndarray, ti: np.ndarray, ratios: tuple, sampling: tuple, m: tuple,
               misses: np.ndarray, rule: tuple, theta: tuple, groups: tuple
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
        m: the targets' models (a feature set). misses: (T,) float64, g = 1 / (1 + misses).
        rule: (spread, omega (6,), gamma (5,)) as ``_pair_scores_kernel``'s.
        groups: (size, grouped, table): boxes 0 .. grouped - 1 are consecutive groups of
            ``size`` of which only the first maximum of p counts, scored by
            ``_score_group`` (``table``: ``survival_bounds(theta)``); size 0: none.
    """
    grid, image, luts, pixel_bins = sampling
    spread, omega, gamma = rule
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
    listed = (nb <= 64, s[13], finite)
    weights = (omega / omega.sum(), gamma / gamma.sum())
    memo = _memo(theta[0].shape[0], m[1].shape[1])
    d = np.empty((K, theta[0].shape[0], m[1].shape[1]))
    idx = np.empty(max(nb, m[4].shape[2]), np.int64)
    for k in range(K):
        bands = _box_counts(boxes, k, ratios[0], ratios[1], False, _NO_CENTRES, grid, image,
                            luts, pixel_bins, s, one[0][0])
        _box_features(s, bands, one[0][0], 0, one[1:6])
        one[6][0] = boxes[k, 3]
        t = ti[k]
        _pair_differences(m, one, t, 0, 1.0 / (1.0 + misses[t]), d, k, idx, listed)  # eq. 11
    pj, p = np.empty((K, m[1].shape[1])), np.empty(K)
    size, grouped, table = groups
    first = 0
    if size > 0:
        for g0 in range(0, grouped, size):
            _score_group(d, g0, size, spread, weights, theta, memo, table, pj, p)
        first = grouped
    for k in range(first, K):
        _score_row(d, k, spread, weights, theta, memo, pj, p, k)                      # eqs. 12-13
    return pj, p


# ----------------------------------------------------------------------------- PBM 4, step 4


@numba.njit(cache=True)
def _ambiguous_kernel(scores: np.ndarray, threshold: float, margin: float
                      ) -> tuple[int, int, bool]:
    """PBM 4, step 4 (``association.ambiguous``): the candidate with the highest global
    score (eq. 13), above ``threshold``, and whether the runner-up is within ``margin``;
    the best and runner-up are the first and second entries of a stable descending sort
    (ties: lower index first; NaN last)."""
    best, runner = -1, -1
    for k in range(scores.shape[0]):
        v = scores[k]
        if np.isnan(v):  # NaN sorts last
            continue
        if best < 0 or v > scores[best]:
            runner, best = best, k
        elif runner < 0 or v > scores[runner]:
            runner = k
    if best < 0 or not np.isfinite(scores[best]) or scores[best] < threshold:
        return -1, -1, False
    if runner >= 0 and not np.isfinite(scores[runner]):
        runner = -1
    amb = runner >= 0 and scores[runner] >= threshold and scores[best] < margin * scores[runner]
    return best, runner, amb


@numba.njit(cache=True)
def _ambiguous_rows_kernel(scores: np.ndarray, threshold: float, margin: float,
                           best: np.ndarray, runner: np.ndarray, amb: np.ndarray) -> None:
    """``_ambiguous_kernel`` of every row of (T, N) scores into best, runner, amb (T,)."""
    for t in range(scores.shape[0]):
        best[t], runner[t], amb[t] = _ambiguous_kernel(scores[t], threshold, margin)
