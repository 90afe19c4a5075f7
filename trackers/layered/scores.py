"""PBM 4, 4.1, eqs. 12-13: the part scores p_j = sum_i omega_i p(d_ij | theta_ij) and the
global score p = sum_j gamma_j p_j, in plain numpy (the definitions: ``match_probability``,
``part_scores``, ``global_score``) and compiled (``_survival``, ``_score_row``,
``_pair_scores_kernel`` with eq. 11's ``differences._differences_kernel``; the search's
boxes measured, bounded and scored in ``box_search``), held equal to rtol 1e-9 by
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
from occbench.trackers.layered.differences import _differences_kernel

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
def _pair_scores_kernel(m: tuple, c: tuple, ti: np.ndarray, n: np.ndarray, gap: tuple,
                        spread: float, omega: np.ndarray, gamma: np.ndarray, theta: tuple
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 11-13 of the pairs (ti[k], n[k]) in one call: ``_differences_kernel`` then
    ``_scores_kernel``; returns p_j (K, 5) and p (K,)."""
    K = ti.shape[0]
    d = np.empty((K, theta[0].shape[0], m[1].shape[1]))
    _differences_kernel(m, c, ti, n, gap, d)
    pj, p = np.empty((K, m[1].shape[1])), np.empty(K)
    _scores_kernel(d, spread, omega, gamma, theta, pj, p)
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
