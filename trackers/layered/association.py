"""Layered data association: feature -> part -> global (PBM 4, 4.1, eqs. 11-13).

Feature layer (eq. 11): d_ij = |f_ij - F_ij| for feature i of part j of a candidate (f)
and of the target's parts model (F). Histograms differ by 1 - rho (Bhattacharyya
coefficient rho = sum_u sqrt(p_u q_u)), overlap by 1 - IoU.
Part layer (eq. 12): p_j = sum_i omega_i p(d_ij | theta_ij), p(. | theta) the match
probability of ``FeatureModels``.
Global layer (eq. 13): p = sum_j gamma_j p_j.

The layers run in small numba kernels over the scored (target, candidate) pairs with no
(pairs, 6, 5, components) temporaries; ``pair_scores`` chains eqs. 11-13 for the
selected pairs in one call (the models indexed, not copied per pair). Every
kernel fixes its floating-point order, the same as the numpy expression quoted in its
docstring (the tests compare them value for value):

- rho: ``np.sqrt(p * q).sum(-1)`` (numpy's pairwise sum, ``_rho``); no BLAS product,
  whose rounding depends on the CPU's kernel;
- p(d | theta): ``scipy.special.ndtr``'s values to 3e-10 (a table, ``_ndtr``);
- eq. 12: ``np.einsum("...ij,i->...j", prob, omega)`` (i = 0..5 left to right from 0);
- eq. 13: sum_j p_j gamma_j, j = 0..4 left to right from 0.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import numba
import numpy as np
from scipy.special import ndtr

from trackers.layered.parts import N_PARTS, PartFeatures

if TYPE_CHECKING:  # annotations only: models.py imports this module
    from trackers.layered.models import FeatureModels

FEATURES: tuple[str, ...] = ("area", "perimeter", "hsv", "xyz", "displacement", "overlap")
"""The Nf = 6 features of every part (PBM 2.2), in the order of every (..., 6) array."""
N_FEATURES = len(FEATURES)

# ----------------------------------------------------------------------------- kernels
# Small numba kernels. The helpers are inlined into the loops that call them
# (``inline="always"``) and index the feature arrays directly, so no array view is built or
# reference-counted per pair. All kernels live in this one file: numba's cache checks only
# the file of the function it compiled, so a kernel calling a kernel of another file could
# be loaded stale after that file changed.

# The standard normal CDF of the survival functions, as a table: values and slopes of
# ``scipy.special.ndtr`` at z = -9 .. 9 in steps of 1/64, interpolated by cubic Hermite
# polynomials (absolute error below 3e-10, ``tests/test_pbm_scoring.py``). About ten times
# faster than calling scipy's ndtr per value; beyond |z| = 9 the CDF is 0 or 1 to 1e-19.
_NDTR_LIMIT = 9.0
_NDTR_PER_UNIT = 64


def _ndtr_table() -> np.ndarray:
    """(N, 2) nodes z_k = -9 + k / 64: ndtr(z_k) and the step times its slope phi(z_k)."""
    z = np.linspace(-_NDTR_LIMIT, _NDTR_LIMIT, int(2 * _NDTR_LIMIT * _NDTR_PER_UNIT) + 1)
    slope = np.exp(-0.5 * z * z) / np.sqrt(2.0 * np.pi)
    return np.ascontiguousarray(np.column_stack([ndtr(z), slope / _NDTR_PER_UNIT]))


_NDTR_TABLE = _ndtr_table()


@numba.njit(cache=True, inline="always")
def _ndtr(z: float) -> float:
    """Standard normal CDF from ``_NDTR_TABLE`` (cubic Hermite); NaN stays NaN."""
    if not z > -_NDTR_LIMIT:
        return z if np.isnan(z) else 0.0
    if z >= _NDTR_LIMIT:
        return 1.0
    u = (z + _NDTR_LIMIT) * _NDTR_PER_UNIT
    k = int(u)
    t = u - k
    t2 = t * t
    t3 = t2 * t
    f0, s0 = _NDTR_TABLE[k, 0], _NDTR_TABLE[k, 1]
    f1, s1 = _NDTR_TABLE[k + 1, 0], _NDTR_TABLE[k + 1, 1]
    return ((2.0 * t3 - 3.0 * t2 + 1.0) * f0 + (t3 - 2.0 * t2 + t) * s0
            + (3.0 * t2 - 2.0 * t3) * f1 + (t3 - t2) * s1)


@numba.njit(cache=True)
def _survival_many(xs: np.ndarray, m: int, w: np.ndarray, mu: np.ndarray, s: np.ndarray,
                   i: int, j: int, out: np.ndarray) -> None:
    """P(D >= x) of model (i, j) of padded (6, 5, K) mixture arrays (``FeatureModels``) for
    the m differences xs[:m], already clipped at 0, into out[:m]:
    ``FeatureModels.match_probability``, the same operations in the same order: per
    component w (ndtr((mu - x) / s) + ndtr((-mu - x) / s)), summed left to right from 0
    (numpy's sum below 8 components); clip to [0, 1]. Zero-weight padding adds exact zeros
    and is skipped; a zero mean needs one ndtr (both terms equal). The ndtr calls run in
    tight loops over the differences, component by component.
    """
    out[:m] = 0.0
    for c in range(w.shape[2]):
        wc, mc, sc = w[i, j, c], mu[i, j, c], s[i, j, c]
        if wc == 0.0:
            continue
        if mc == 0.0:
            for q in range(m):
                a = _ndtr((mc - xs[q]) / sc)
                out[q] += wc * (a + a)
        else:
            for q in range(m):
                out[q] += wc * (_ndtr((mc - xs[q]) / sc)
                                + _ndtr((-mc - xs[q]) / sc))
    for q in range(m):  # NaN stays NaN
        if out[q] < 0.0:
            out[q] = 0.0
        elif out[q] > 1.0:
            out[q] = 1.0


@numba.njit(cache=True)
def survival_kernel(d: np.ndarray, w: np.ndarray, mu: np.ndarray, s: np.ndarray, out: np.ndarray
                    ) -> None:
    """``_survival_many`` of (n, 6, 5) differences into out (n, 6, 5)."""
    n = d.shape[0]
    xs, p = np.empty(n), np.empty(n)
    for i in range(d.shape[1]):
        for j in range(d.shape[2]):
            for k in range(n):
                x = d[k, i, j]
                if x < 0.0:  # np.maximum(x, 0): NaN stays NaN  # noqa: PLR1730
                    x = 0.0
                xs[k] = x
            _survival_many(xs, n, w, mu, s, i, j, p)
            for k in range(n):
                out[k, i, j] = p[k]


@numba.njit(cache=True, inline="always")
def _leaf_sum(v: np.ndarray, lo: int, count: int) -> float:
    """sum of v[lo:lo + count], count <= 128, in the order of numpy's pairwise sum: below 8
    values left to right, else 8 interleaved partial sums added as a tree, then the
    count % 8 last values."""
    if count < 8:
        res = 0.0
        for u in range(lo, lo + count):
            res += v[u]
        return res
    r0, r1, r2, r3 = v[lo], v[lo + 1], v[lo + 2], v[lo + 3]
    r4, r5, r6, r7 = v[lo + 4], v[lo + 5], v[lo + 6], v[lo + 7]
    full = count - count % 8
    for u in range(lo + 8, lo + full, 8):
        r0 += v[u]
        r1 += v[u + 1]
        r2 += v[u + 2]
        r3 += v[u + 3]
        r4 += v[u + 4]
        r5 += v[u + 5]
        r6 += v[u + 6]
        r7 += v[u + 7]
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    for u in range(lo + full, lo + count):
        res += v[u]
    return res


@functools.cache
def _pairwise_plan(n: int) -> tuple[np.ndarray, np.ndarray]:
    """numpy's pairwise-sum tree over n values (ranges above 128 split in halves rounded
    down to a multiple of 8) as leaves (L, 2) of (start, length) and a postfix program: a
    leaf index pushes that leaf's sum, -1 pops two sums and pushes their sum."""
    leaves: list[tuple[int, int]] = []
    program: list[int] = []

    def walk(lo: int, m: int) -> None:
        if m <= 128:
            program.append(len(leaves))
            leaves.append((lo, m))
            return
        m2 = m // 2 - (m // 2) % 8
        walk(lo, m2)
        walk(lo + m2, m - m2)
        program.append(-1)

    walk(0, n)
    return np.array(leaves, dtype=np.intp).reshape(-1, 2), np.array(program, dtype=np.intp)


@numba.njit(cache=True, inline="always")
def _rho(a: np.ndarray, b: np.ndarray, t: int, n: int, j: int, leaves: np.ndarray,
         program: np.ndarray, v: np.ndarray, stack: np.ndarray) -> float:
    """Bhattacharyya coefficient of histograms a[t, j] and b[n, j] (B bins), equal to
    ``np.sqrt(a[t, j] * b[n, j]).sum()``: the B square roots into scratch v (B,), then
    summed in numpy's pairwise order (``leaves, program = _pairwise_plan(B)``; scratch
    stack of len(program))."""
    for u in range(v.shape[0]):
        v[u] = np.sqrt(a[t, j, u] * b[n, j, u])
    if program.shape[0] == 1:  # B <= 128 (bins <= 5): one leaf
        return _leaf_sum(v, 0, v.shape[0])
    top = 0
    for op in program:
        if op >= 0:
            stack[top] = _leaf_sum(v, leaves[op, 0], leaves[op, 1])
            top += 1
        else:
            stack[top - 2] = stack[top - 2] + stack[top - 1]
            top -= 1
    return stack[0]


@numba.njit(cache=True, inline="always")
def _pair_differences(m_parts: np.ndarray, m_area: np.ndarray, m_perimeter: np.ndarray,
                      m_hsv: np.ndarray, m_xyz: np.ndarray, m_centroid: np.ndarray,
                      m_height: np.ndarray, c_parts: np.ndarray, c_area: np.ndarray,
                      c_perimeter: np.ndarray, c_hsv: np.ndarray, c_xyz: np.ndarray,
                      c_centroid: np.ndarray, t: int, n: int, g: float,
                      leaves: np.ndarray, program: np.ndarray, v: np.ndarray,
                      stack: np.ndarray, d: np.ndarray, k: int) -> None:
    """Eq. 11 for model t against candidate n into d[k] (6, 5).

    Per part j: |area|, |perimeter|, 1 - rho of HSV and XYZ (1 when the candidate part has
    no foreground), |c_n - C_t| / max(H_t, 1) and 1 - IoU (IoU 0 when union <= 0), the
    last two times g = 1 / (1 + misses); all clipped at 0.
    """
    hgt = max(m_height[t], 1.0)
    for j in range(m_area.shape[1]):
        d[k, 0, j] = abs(m_area[t, j] - c_area[n, j])
        d[k, 1, j] = abs(m_perimeter[t, j] - c_perimeter[n, j])
        if c_area[n, j] <= 0:  # an empty histogram (part without foreground) never matches
            d[k, 2, j] = 1.0
            d[k, 3, j] = 1.0
        else:
            d[k, 2, j] = 1.0 - _rho(m_hsv, c_hsv, t, n, j, leaves, program, v, stack)
            d[k, 3, j] = 1.0 - _rho(m_xyz, c_xyz, t, n, j, leaves, program, v, stack)
        dx = c_centroid[n, j, 0] - m_centroid[t, j, 0]
        dy = c_centroid[n, j, 1] - m_centroid[t, j, 1]
        d[k, 4, j] = np.sqrt(dx * dx + dy * dy) / hgt * g
        ax, ay, aw, ah = m_parts[t, j, 0], m_parts[t, j, 1], m_parts[t, j, 2], m_parts[t, j, 3]
        bx, by, bw, bh = c_parts[n, j, 0], c_parts[n, j, 1], c_parts[n, j, 2], c_parts[n, j, 3]
        iw = max(min(ax + aw, bx + bw) - max(ax, bx), 0.0)
        ih = max(min(ay + ah, by + bh) - max(ay, by), 0.0)
        inter = iw * ih
        union = aw * ah + bw * bh - inter
        iou = inter / union if union > 0 else 0.0
        d[k, 5, j] = (1.0 - iou) * g
        for i in range(d.shape[1]):
            if d[k, i, j] < 0.0:  # np.clip(d, 0, None)  # noqa: PLR1730
                d[k, i, j] = 0.0


@numba.njit(cache=True)
def _differences_kernel(m_parts: np.ndarray, m_area: np.ndarray, m_perimeter: np.ndarray,
                        m_hsv: np.ndarray, m_xyz: np.ndarray, m_centroid: np.ndarray,
                        m_height: np.ndarray, c_parts: np.ndarray, c_area: np.ndarray,
                        c_perimeter: np.ndarray, c_hsv: np.ndarray, c_xyz: np.ndarray,
                        c_centroid: np.ndarray, ti: np.ndarray, n: np.ndarray, misses: np.ndarray,
                        leaves: np.ndarray, program: np.ndarray,
                        out: np.ndarray) -> None:
    """``_pair_differences`` of pairs (ti[k], n[k]) into out (K, 6, 5); misses (T,) float64
    per target, g = 1 / (1 + misses)."""
    for k in range(ti.shape[0]):
        if not (0 <= ti[k] < m_area.shape[0] and 0 <= n[k] < c_area.shape[0]):
            raise IndexError("selected pair index out of range")
    v, stack = np.empty(m_hsv.shape[2]), np.empty(program.shape[0])
    for k in range(ti.shape[0]):
        _pair_differences(m_parts, m_area, m_perimeter, m_hsv, m_xyz, m_centroid, m_height,
                          c_parts, c_area, c_perimeter, c_hsv, c_xyz, c_centroid,
                          ti[k], n[k], 1.0 / (1.0 + misses[ti[k]]), leaves, program,
                          v, stack, out, k)


@numba.njit(cache=True, inline="always")
def _normalised(weights: np.ndarray) -> np.ndarray:
    """weights / sum(weights), the sum left to right from 0 (numpy's sum below 8 values)."""
    total = 0.0
    for x in weights:
        total += x
    return weights / total


@numba.njit(cache=True)
def _scores_kernel(d: np.ndarray, spread: float, omega: np.ndarray, gamma: np.ndarray,
                   w: np.ndarray, mu: np.ndarray, s: np.ndarray, pj: np.ndarray, p: np.ndarray
                   ) -> None:
    """Eqs. 12 and 13 for (K, 6, 5) differences into pj (K, 5), p (K,);
    omega and gamma are normalised here.

    The probabilities P(D_ij >= d_ij / spread) are computed model by model over all pairs
    first (``_survival_many``; an argument repeated by consecutive pairs is computed
    once), then eqs. 12-13 pair by pair.
    """
    omega, gamma = _normalised(omega), _normalised(gamma)
    K, NF, NP = d.shape
    prob = np.empty((NF, NP, K))
    xs, tot = np.empty(K), np.empty(K)  # the distinct arguments (clipped at 0), their sums
    slot = np.empty(K, np.intp)  # pair -> its argument in xs
    for i in range(NF):
        for j in range(NP):
            m, last = 0, np.nan
            for k in range(K):
                x = d[k, i, j] / spread
                if x != last:  # a new argument (NaN never repeats)
                    last = x
                    if x < 0.0:  # np.maximum(x, 0): NaN stays NaN  # noqa: PLR1730
                        x = 0.0
                    xs[m] = x
                    m += 1
                slot[k] = m - 1
            _survival_many(xs, m, w, mu, s, i, j, tot)
            row = prob[i, j]
            for k in range(K):
                row[k] = tot[slot[k]]
    for k in range(K):
        total = 0.0
        for j in range(NP):
            acc = 0.0
            for i in range(NF):
                acc += prob[i, j, k] * omega[i]
            pj[k, j] = acc
            total += acc * gamma[j]
        p[k] = total


@numba.njit(cache=True)
def _pair_scores_kernel(m_parts: np.ndarray, m_area: np.ndarray, m_perimeter: np.ndarray,
                        m_hsv: np.ndarray, m_xyz: np.ndarray, m_centroid: np.ndarray,
                        m_height: np.ndarray, c_parts: np.ndarray, c_area: np.ndarray,
                        c_perimeter: np.ndarray, c_hsv: np.ndarray, c_xyz: np.ndarray,
                        c_centroid: np.ndarray, ti: np.ndarray, n: np.ndarray, misses: np.ndarray,
                        leaves: np.ndarray, program: np.ndarray, spread: float,
                        omega: np.ndarray, gamma: np.ndarray, w: np.ndarray, mu: np.ndarray,
                        s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 11-13 of the pairs (ti[k], n[k]) in one call: ``_differences_kernel`` then
    ``_scores_kernel``; returns p_j (K, 5) and p (K,)."""
    K = ti.shape[0]
    d = np.empty((K, w.shape[0], m_area.shape[1]))
    _differences_kernel(m_parts, m_area, m_perimeter, m_hsv, m_xyz, m_centroid, m_height,
                        c_parts, c_area, c_perimeter, c_hsv, c_xyz, c_centroid, ti, n, misses,
                        leaves, program, d)
    pj, p = np.empty((K, m_area.shape[1])), np.empty(K)
    _scores_kernel(d, spread, omega, gamma, w, mu, s, pj, p)
    return pj, p


@numba.njit(cache=True)
def _ambiguous_kernel(scores: np.ndarray, threshold: float, margin: float
                      ) -> tuple[int, int, bool]:
    """``ambiguous`` in one pass: the best and runner-up are the first and second entries
    of a stable descending sort (ties: lower index first; NaN last)."""
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


# ----------------------------------------------------------------------------- public API


def _arrays(f: PartFeatures) -> tuple[np.ndarray, ...]:
    """The kernels' inputs of a feature set (float64 arrays, ``PartFeatures``' contract)."""
    return f.parts, f.area, f.perimeter, f.hsv, f.xyz, f.centroid, f.height


def _misses(misses: np.ndarray | None, n_targets: int) -> np.ndarray:
    """(T,) float64 misses (zeros when None: the factor 1 / (1 + 0) is exactly 1)."""
    if misses is None:
        return np.zeros(n_targets)
    return np.asarray(misses, dtype=np.float64)


def _pairs(model: PartFeatures, cand: PartFeatures, ti: np.ndarray, n: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    """The pair indices ti, n as (K,) intp arrays, after checking their shapes and that
    model and candidates have histograms of the same bins (ValueError else)."""
    ti = np.asarray(ti, dtype=np.intp)
    n = np.asarray(n, dtype=np.intp)
    if ti.shape != n.shape or ti.ndim != 1:
        raise ValueError(f"pair indices ti {ti.shape} and n {n.shape} must be equal-length 1-D")
    if model.hsv.shape[2] != cand.hsv.shape[2] or model.xyz.shape[2] != cand.xyz.shape[2]:
        raise ValueError(f"histogram bins differ: model {model.hsv.shape[2]}, "
                         f"candidates {cand.hsv.shape[2]}")
    return ti, n


def _differences(model: PartFeatures, cand: PartFeatures, ti: np.ndarray, n: np.ndarray,
                 misses: np.ndarray | None) -> np.ndarray:
    """Eq. 11 of pairs (ti[k], n[k]), indices in [0, T) and [0, N) (IndexError else)."""
    ti, n = _pairs(model, cand, ti, n)
    out = np.empty((len(ti), N_FEATURES, N_PARTS))
    _differences_kernel(*_arrays(model), *_arrays(cand)[:6], ti, n, _misses(misses, len(model)),
                        *_pairwise_plan(model.hsv.shape[2]), out)
    return out


def feature_differences(model: PartFeatures, cand: PartFeatures, misses: np.ndarray | None = None
                        ) -> np.ndarray:
    """Eq. 11 for every target/candidate pair.

    Args:
        model: T targets' parts models. cand: N candidates' part features.
        misses: (T,) frames since each target was last found; displacement and overlap
            differences are divided by (1 + misses) so they stay per-frame after a gap.
    Returns:
        (T, N, 6, 5) differences, features in ``FEATURES`` order.
    """
    T, N = len(model), len(cand)
    ti, n = np.divmod(np.arange(T * N, dtype=np.intp), max(N, 1))
    return _differences(model, cand, ti, n, misses).reshape(T, N, N_FEATURES, N_PARTS)


def selected_differences(model: PartFeatures, cand: PartFeatures, ti: np.ndarray, n: np.ndarray,
                         misses: np.ndarray | None = None) -> np.ndarray:
    """Eq. 11 for the selected pairs (target ti[k], candidate n[k]) only: (K, 6, 5), equal
    to ``feature_differences(model, cand, misses)[ti, n]`` value for value. The tracker
    scores only the candidates inside a target's gate (PBM 3).
    """
    return _differences(model, cand, ti, n, misses)


def _weights(w: np.ndarray, size: int, name: str) -> np.ndarray:
    """A (size,) float64 weight vector (the kernels normalise it to sum 1)."""
    w = np.asarray(w, dtype=np.float64)
    if w.shape != (size,):
        raise ValueError(f"{name} must have shape ({size},), got {w.shape}")
    return w


def layered_scores(models: FeatureModels, d: np.ndarray, omega: np.ndarray, gamma: np.ndarray,
                   spread: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 12-13.

    Args:
        d: (..., 6, 5) differences. omega: (6,) feature weights; gamma: (5,) part weights
            (both normalised to sum 1 here).
        spread: the models are applied to d / spread, i.e. stretched by ``spread``: tracking
            sees larger differences than the clean annotated pairs the models were fitted on
            (detection noise, partial overlaps by other people).
    Returns:
        part scores p_j (..., 5) and global scores p (...,), all in [0, 1].
    """
    return _scores(models, d, omega, gamma, spread)


def _scores(models: FeatureModels, d: np.ndarray, omega: np.ndarray, gamma: np.ndarray,
            spread: float) -> tuple[np.ndarray, np.ndarray]:
    d = np.asarray(d, dtype=np.float64)
    if d.shape[-2:] != (N_FEATURES, N_PARTS):
        raise ValueError(f"expected (..., {N_FEATURES}, {N_PARTS}) differences, got {d.shape}")
    lead = d.shape[:-2]
    flat = np.ascontiguousarray(d).reshape(-1, N_FEATURES, N_PARTS)
    pj = np.empty((len(flat), N_PARTS))
    p = np.empty(len(flat))
    _scores_kernel(flat, float(spread), _weights(omega, N_FEATURES, "omega"),
                   _weights(gamma, N_PARTS, "gamma"), models._w, models._mu, models._s,
                   pj, p)
    return pj.reshape(*lead, N_PARTS), p.reshape(lead)


def pair_scores(models: FeatureModels, model: PartFeatures, cand: PartFeatures, ti: np.ndarray,
                n: np.ndarray, misses: np.ndarray | None, omega: np.ndarray, gamma: np.ndarray,
                spread: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 11-13 in one call for the pairs (target ti[k], candidate n[k]), equal value for
    value to ``layered_scores(models, selected_differences(model, cand, ti, n, misses),
    omega, gamma, spread)``.

    Returns:
        part scores p_j (K, 5) and global scores p (K,).
    """
    ti, n = _pairs(model, cand, ti, n)
    return _pair_scores_kernel(*_arrays(model), *_arrays(cand)[:6], ti, n,
                               _misses(misses, len(model)), *_pairwise_plan(model.hsv.shape[2]),
                               float(spread), _weights(omega, N_FEATURES, "omega"),
                               _weights(gamma, N_PARTS, "gamma"), models._w, models._mu, models._s)


def ambiguous(scores: np.ndarray, threshold: float, margin: float) -> tuple[int, int, bool]:
    """The best candidate of one target and whether the decision is ambiguous (PBM 4, step 4).

    Args:
        scores: (N,) global scores, -inf outside the gate.
    Returns:
        (best index or -1, runner-up index or -1, ambiguous) where ambiguous means the best
        does not exceed ``margin`` times the runner-up while both pass ``threshold``.
    """
    scores = np.asarray(scores, dtype=np.float64)
    if scores.ndim != 1:
        raise ValueError(f"ambiguous: expected (N,) scores, got {scores.shape}")
    return _ambiguous_kernel(scores, threshold, margin)


def ambiguous_rows(scores: np.ndarray, threshold: float, margin: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``ambiguous`` of every row of (T, N) scores in one call.

    Returns:
        best (T,) and runner-up (T,) indices (-1 when none), ambiguous (T,) bool; row t
        equals ``ambiguous(scores[t], threshold, margin)``.
    """
    scores = np.asarray(scores, dtype=np.float64)
    if scores.ndim != 2:
        raise ValueError(f"ambiguous_rows: expected (T, N) scores, got {scores.shape}")
    T = scores.shape[0]
    best, runner, amb = np.empty(T, dtype=np.intp), np.empty(T, dtype=np.intp), np.empty(T, bool)
    _ambiguous_rows_kernel(scores, threshold, margin, best, runner, amb)
    return best, runner, amb
