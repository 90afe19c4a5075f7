"""The feature weights omega of PBM eq. 12, learned by cross-validated grid search (PBM 4.1:
"trained with maximum cross-validation accuracy by a search over interval [0,1] and
normalized to add up to 1"). Samples come from ``occbench.fit.pbm_pairs.collect_pairs``; used
by ``occbench.fit.pbm``.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from occbench.fit.pbm_pairs import PairSamples
from occbench.trackers.layered.feature_models import FeatureModels
from occbench.trackers.layered.parts import FEATURES

log = logging.getLogger(__name__)


@dataclass
class WeightFit:
    """The learned omega of eq. 12 and how it was chosen (PBM 4.1).

    Attributes:
        weights: {feature: omega_i}, sum 1.
        accuracy: mean validation accuracy of ``weights`` over the folds.
        fold_accuracy: (k,) validation accuracy of ``weights`` per fold.
        nested_accuracy: mean over folds of the validation accuracy of the omega chosen on
            the other folds alone (an unbiased estimate of the whole procedure).
        reference_accuracy: mean validation accuracy of ``reference`` weights, if given.
        settings: grid step, grid points, folds, threshold, spread, gamma, sample counts.
    """

    weights: dict[str, float]
    accuracy: float
    fold_accuracy: np.ndarray
    nested_accuracy: float
    reference_accuracy: float | None = None
    settings: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        out = {
            "accuracy": round(float(self.accuracy), 6),
            "fold_accuracy": [round(float(v), 6) for v in self.fold_accuracy],
            "nested_accuracy": round(float(self.nested_accuracy), 6),
        }
        if self.reference_accuracy is not None:
            out["reference_accuracy"] = round(float(self.reference_accuracy), 6)
        out.update(self.settings)
        return out


def weight_grid(step: float) -> np.ndarray:
    """omega on the grid {0, step, ..., 1}^6, normalised to sum 1 (PBM 4.1).

    The all-zero point is skipped and points equal after normalising are kept once.
    Returns:
        (G, 6) float64 weights, rows in lexicographic order of their reduced integer form.
    """
    n = round(1.0 / step)
    if n < 1 or abs(n * step - 1.0) > 1e-9:
        raise ValueError(f"weight step must divide 1 (e.g. 0.1, 0.2, 0.25), got {step}")
    axes = np.meshgrid(*[np.arange(n + 1)] * len(FEATURES), indexing="ij")
    v = np.stack([a.reshape(-1) for a in axes], axis=1)[1:]  # skip all zero
    g = np.gcd.reduce(v, axis=1)
    v = np.unique(v // g[:, None], axis=0)
    return v / v.sum(axis=1, keepdims=True)


def feature_scores(models: FeatureModels, d: np.ndarray, gamma: np.ndarray, spread: float
                   ) -> np.ndarray:
    """q_i = sum_j gamma_j p(d_ij / spread | theta_ij), so that eq. 13 of eq. 12 is q @ omega.

    Args:
        d: (M, 6, 5) differences; gamma: (5,) part weights (normalised here).
    Returns:
        (M, 6) float64.
    """
    gamma = np.asarray(gamma, dtype=np.float64)
    gamma = gamma / gamma.sum()
    prob = models.match_probability(np.asarray(d, dtype=np.float64) / spread)  # (M, 6, 5)
    return prob @ gamma


def block_folds(block: np.ndarray, k: int) -> np.ndarray:
    """Fold of every sample: whole blocks, round-robin over the sorted block ids.

    Args:
        block: (M,) block ids. k: folds.
    Returns:
        (M,) int fold in [0, k).
    """
    ids, inv = np.unique(np.asarray(block), return_inverse=True)
    if len(ids) < k:
        raise ValueError(f"{k}-fold cross-validation needs >= {k} blocks, got {len(ids)}")
    return (np.arange(len(ids)) % k)[inv.reshape(-1)]


def fold_accuracies(q: np.ndarray, positive: np.ndarray, folds: np.ndarray, k: int,
                    grid: np.ndarray, threshold: float, chunk: int = 1024) -> np.ndarray:
    """Balanced accuracy of the match decision p >= threshold per grid point and fold.

    Args:
        q: (M, 6) ``feature_scores``; positive: (M,) bool; folds: (M,) fold ids.
        grid: (G, 6) omega (rows sum to 1); the global score is q @ omega (eqs. 12-13).
    Returns:
        (G, k) accuracy: within a fold, positives and negatives weigh half each (all of it
        when the fold holds one class only).
    """
    positive = np.asarray(positive, dtype=bool)
    wt = np.zeros((len(q), k))
    for f in range(k):
        classes = [positive & (folds == f), ~positive & (folds == f)]
        present = [c for c in classes if c.any()]
        for c in present:
            wt[c, f] = 1.0 / (len(present) * c.sum())
    out = np.empty((len(grid), k))
    for s in range(0, len(grid), chunk):
        p = grid[s:s + chunk] @ q.T  # (c, M) global scores, eq. 13
        correct = (p >= threshold) == positive[None]
        out[s:s + chunk] = correct.astype(np.float64) @ wt
    return out


def pick_best(mean_accuracy: np.ndarray, grid: np.ndarray, tol: float = 1e-12) -> int:
    """Index of the best accuracy; ties: nearest the uniform weights, then first in order."""
    best = np.flatnonzero(mean_accuracy >= mean_accuracy.max() - tol)
    dist = np.linalg.norm(grid[best] - 1.0 / grid.shape[1], axis=1)
    return int(best[np.argmin(dist)])


def search_weights(samples: PairSamples, models: FeatureModels, gamma: np.ndarray,
                   threshold: float, spread: float, step: float = 0.2, k: int = 5,
                   reference: Mapping[str, float] | None = None) -> WeightFit:
    """omega of eq. 12 with the best k-fold cross-validation accuracy (PBM 4.1).

    Args:
        samples: positive and negative pairs (``collect_pairs``).
        models: the fitted difference models theta_ij.
        gamma: (5,) part weights of eq. 13; threshold: the tracker's ``match_threshold``;
            spread: its ``model_spread``.
        step: grid step over [0, 1] per feature. k: folds (whole blocks).
        reference: weights whose accuracy is reported beside (e.g. the hand-set ones).
    Raises:
        ValueError when the samples hold no positive or no negative pair or too few blocks.
    """
    n_pos = int(samples.positive.sum())
    n_neg = len(samples) - n_pos
    if n_pos == 0 or n_neg == 0:
        raise ValueError(f"weight search needs positive and negative pairs, got {n_pos} and {n_neg}")
    grid = weight_grid(step)
    folds = block_folds(samples.block, k)
    log.info("searching omega: %d grid points, %d positive and %d negative pairs, %d folds",
             len(grid), n_pos, n_neg, k)
    q = feature_scores(models, samples.d, gamma, spread)
    acc = fold_accuracies(q, samples.positive, folds, k, grid, threshold)
    mean = acc.mean(axis=1)
    best = pick_best(mean, grid)
    nested = []
    for f in range(k):
        train = np.delete(acc, f, axis=1).mean(axis=1)
        nested.append(acc[pick_best(train, grid), f])
    ref_acc = None
    if reference is not None:
        w = np.array([float(reference[f]) for f in FEATURES])
        ref_acc = float(fold_accuracies(q, samples.positive, folds, k, w[None] / w.sum(),
                                        threshold).mean())
    settings = {
        "grid_step": float(step),
        "grid_points": len(grid),
        "folds": int(k),
        "blocks": len(np.unique(samples.block)),
        "positives": n_pos,
        "negatives": n_neg,
        "match_threshold": float(threshold),
        "model_spread": float(spread),
        "part_weights": [float(g) for g in np.asarray(gamma, dtype=np.float64)],
    }
    weights = {f: round(float(v), 6) for f, v in zip(FEATURES, grid[best], strict=True)}
    log.info("omega %s: mean cross-validation accuracy %.4f (nested %.4f) over %d grid points",
             weights, mean[best], np.mean(nested), len(grid))
    return WeightFit(weights, float(mean[best]), acc[best].copy(), float(np.mean(nested)),
                     ref_acc, settings)
