"""Layered data association: feature -> part -> global (PBM 4, 4.1, eqs. 11-13).

Feature layer (eq. 11): d_ij = |f_ij - F_ij| for feature i of part j of a candidate (f)
and of the target's parts model (F). Histograms differ by 1 - rho (Bhattacharyya
coefficient rho = sum_u sqrt(p_u q_u)), overlap by 1 - IoU.
Part layer (eq. 12): p_j = sum_i omega_i p(d_ij | theta_ij), p(. | theta) the match
probability of ``FeatureModels``.
Global layer (eq. 13): p = sum_j gamma_j p_j.

The layers run in small numba kernels over the scored (target, candidate) pairs with no
(pairs, 6, 5, components) temporaries; ``pair_scores`` chains eqs. 11-13 for the
selected pairs in one call (the models indexed, not copied per pair). The plain-numpy
equations they compute are ``differences.differences`` (eq. 11),
``scores.part_scores`` (eq. 12) and ``scores.global_score`` (eq. 13); the kernels equal them to
rounding (rtol 1e-9, ``tests/trackers/layered/test_equations.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from occbench.trackers.layered.box_search import (
    box_scores_kernel,
    coarse_box_scores_kernel,
    survival_bounds,
)
from occbench.trackers.layered.differences import _differences_kernel
from occbench.trackers.layered.parts import N_FEATURES, N_PARTS, PartFeatureExtractor, PartFeatures
from occbench.trackers.layered.scores import (
    _ambiguous_kernel,
    _ambiguous_rows_kernel,
    _pair_scores_kernel,
    _scores_kernel,
)

if TYPE_CHECKING:  # annotations only
    from occbench.trackers.layered.feature_models import FeatureModels

# ----------------------------------------------------------------------------- public API


def _theta(models: FeatureModels) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The kernels' mixture parameters: (6, 5, K) weights, means and sigmas."""
    return models._w, models._mu, models._s


def _arrays(f: PartFeatures) -> tuple[np.ndarray, ...]:
    """The kernels' inputs of a feature set (float64 arrays, ``PartFeatures``' contract)."""
    return f.parts, f.area, f.perimeter, f.hsv, f.xyz, f.centroid, f.height


def _gap(misses: np.ndarray | None, n_targets: int, apart: bool) -> tuple[np.ndarray, bool]:
    """The kernels' ``gap``: (T,) float64 misses (zeros when None: the factor 1 / (1 + 0) is
    exactly 1) and ``apart`` (``adaptations.apart_undivided``)."""
    if misses is None:
        return np.zeros(n_targets), bool(apart)
    return np.asarray(misses, dtype=np.float64), bool(apart)


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
                 misses: np.ndarray | None, apart: bool) -> np.ndarray:
    """Eq. 11 of pairs (ti[k], n[k]), indices in [0, T) and [0, N) (IndexError else)."""
    ti, n = _pairs(model, cand, ti, n)
    out = np.empty((len(ti), N_FEATURES, N_PARTS))
    _differences_kernel(_arrays(model), _arrays(cand), ti, n, _gap(misses, len(model), apart),
                        out)
    return out


def feature_differences(model: PartFeatures, cand: PartFeatures, misses: np.ndarray | None = None,
                        apart: bool = False) -> np.ndarray:
    """Eq. 11 for every target/candidate pair.

    Args:
        model: T targets' parts models. cand: N candidates' part features.
        misses: (T,) frames since each target was last found; displacement and overlap
            differences are divided by (1 + misses) so they stay per-frame after a gap.
        apart: the overlap of a pair whose parts all miss the candidate's (every IoU 0) is
            not divided (``adaptations.apart_undivided``).
    Returns:
        (T, N, 6, 5) differences, features in ``FEATURES`` order.
    """
    T, N = len(model), len(cand)
    ti, n = np.divmod(np.arange(T * N, dtype=np.intp), max(N, 1))
    return _differences(model, cand, ti, n, misses, apart).reshape(T, N, N_FEATURES, N_PARTS)


def selected_differences(model: PartFeatures, cand: PartFeatures, ti: np.ndarray, n: np.ndarray,
                         misses: np.ndarray | None = None, apart: bool = False) -> np.ndarray:
    """Eq. 11 for the selected pairs (target ti[k], candidate n[k]) only: (K, 6, 5), equal
    to ``feature_differences(model, cand, misses, apart)[ti, n]`` value for value. The tracker
    scores only the candidates inside a target's gate (PBM 3).
    """
    return _differences(model, cand, ti, n, misses, apart)


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
                   _weights(gamma, N_PARTS, "gamma"), _theta(models), pj, p)
    return pj.reshape(*lead, N_PARTS), p.reshape(lead)


def pair_scores(models: FeatureModels, model: PartFeatures, cand: PartFeatures, ti: np.ndarray,
                n: np.ndarray, misses: np.ndarray | None, omega: np.ndarray, gamma: np.ndarray,
                spread: float = 1.0, apart: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 11-13 in one call for the pairs (target ti[k], candidate n[k]), equal value for
    value to ``layered_scores(models, selected_differences(model, cand, ti, n, misses,
    apart), omega, gamma, spread)``.

    Returns:
        part scores p_j (K, 5) and global scores p (K,).
    """
    ti, n = _pairs(model, cand, ti, n)
    return _pair_scores_kernel(_arrays(model), _arrays(cand), ti, n,
                               _gap(misses, len(model), apart),
                               float(spread), _weights(omega, N_FEATURES, "omega"),
                               _weights(gamma, N_PARTS, "gamma"), _theta(models))


def _bounds(models: FeatureModels) -> np.ndarray | None:
    """``box_search.survival_bounds`` of the models, made once per models object (about
    60,000 values of p(x | theta)); None when a mixture has a sigma <= 0 or a non-finite
    parameter (no bound is then taken)."""
    w, mu, s = _theta(models)
    if not (np.isfinite(w).all() and np.isfinite(mu).all() and np.isfinite(s).all()
            and (s > 0).all()):
        return None
    held = _BOUNDS.get(id(models))
    if held is None or held[0] is not models:
        if len(_BOUNDS) >= 8:
            _BOUNDS.clear()
        held = _BOUNDS[id(models)] = (models, survival_bounds(_theta(models)))
    return held[1]


_BOUNDS: dict[int, tuple] = {}
"""``_bounds``' tables by ``id`` of their models (which they hold, so the id stays theirs)."""


def box_scores(models: FeatureModels, model: PartFeatures, extractor: PartFeatureExtractor,
               boxes: np.ndarray, alpha: np.ndarray, beta: np.ndarray, ti: np.ndarray,
               misses: np.ndarray | None, omega: np.ndarray, gamma: np.ndarray,
               spread: float = 1.0, best_of: int = 0, grouped: int = 0, coarse: bool = False,
               apart: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 11-13 of (K, 4) xywh boxes of the extractor's frame (split at alpha, beta (K,)),
    each against the model of its target ti[k]: equal bit for bit to ``pair_scores(models,
    model, extractor.extract(boxes, alpha, beta), ti, arange(K), ...)``, without making the
    boxes' (K, 5, B) histograms (``box_search.box_scores_kernel``). For the search's boxes
    (PBM 3.1: 25 per searched pair, one kept), whose features are then extracted for the
    kept ones only.

    ``best_of`` > 0: the first ``grouped`` boxes are consecutive groups of ``best_of`` of
    which only the first maximum of p is used (the search's); a box whose upper bound of
    p (``box_search._score_bound``) is below a scored box's p of its group is not scored
    (p -inf, p_j NaN): it cannot be that maximum, and the others keep their bits.
    ``coarse`` (``adaptations.coarse_search``): each group is searched coarse to fine
    (``box_search.coarse_box_scores_kernel``, compiled only when called), not exact.

    Returns:
        part scores p_j (K, 5) and global scores p (K,).
    """
    b, ratios, sampling = extractor.sampling(boxes, alpha, beta)
    ti = np.asarray(ti, dtype=np.intp)
    if ti.shape != (len(b),):
        raise ValueError(f"target indices ti {ti.shape} must be ({len(b)},): one per box")
    if model.hsv.shape[2] != extractor.bins**3 or model.xyz.shape[2] != extractor.bins**3:
        raise ValueError(f"histogram bins differ: model {model.hsv.shape[2]}, "
                         f"extractor {extractor.bins**3}")
    if best_of < 0 or not 0 <= grouped <= len(b) or (best_of and grouped % best_of):
        raise ValueError(f"groups of {best_of} must tile the first {grouped} of {len(b)} boxes")
    table = _bounds(models) if best_of > 0 else None
    groups = (best_of, grouped, table) if table is not None else (0, 0, _NO_TABLE)
    kernel = coarse_box_scores_kernel if coarse and table is not None else box_scores_kernel
    return kernel(b, ti, ratios, sampling, _arrays(model), _gap(misses, len(model), apart),
                  (float(spread), _weights(omega, N_FEATURES, "omega"),
                   _weights(gamma, N_PARTS, "gamma")), _theta(models), groups)


_NO_TABLE = np.zeros((0, 0, 0))
"""``box_scores_kernel``'s table when no box is bounded (never read)."""


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


@dataclass
class LayeredScores:
    """Eqs. 11-13 with one tracker's feature-difference models theta, weights omega and
    gamma (``FeatureParams``), model spread and ``apart`` (``adaptations.apart_undivided``):
    of selected (target, candidate) pairs (``pairs``, as ``pair_scores``) and of boxes
    measured where they lie (``boxes``, as ``box_scores``)."""

    models: FeatureModels
    omega: np.ndarray
    gamma: np.ndarray
    spread: float
    apart: bool = False

    def pairs(self, model: PartFeatures, cand: PartFeatures, ti: np.ndarray, n: np.ndarray,
              misses: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """``pair_scores`` of the pairs (target ti[k], candidate n[k]): p_j (K, 5), p (K,)."""
        return pair_scores(self.models, model, cand, ti, n, misses, self.omega, self.gamma,
                           self.spread, self.apart)

    def boxes(self, model: PartFeatures, extractor: PartFeatureExtractor, boxes: np.ndarray,
              alpha: np.ndarray, beta: np.ndarray, ti: np.ndarray, misses: np.ndarray | None,
              best_of: int = 0, grouped: int = 0, coarse: bool = False
              ) -> tuple[np.ndarray, np.ndarray]:
        """``box_scores`` of (K, 4) boxes against their targets ti (K,): p_j (K, 5), p (K,)."""
        return box_scores(self.models, model, extractor, boxes, alpha, beta, ti, misses,
                          self.omega, self.gamma, self.spread, best_of, grouped, coarse,
                          self.apart)
