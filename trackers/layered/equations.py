"""PBM's equations in plain numpy: the source of truth the compiled kernels are tested
against (``tests/test_pbm_equations.py``, to rtol 1e-9).

Each function computes one equation of the paper ("Tracking People under Heavy Occlusions
by Layered Data Association"), its number beside the line. Arrays: a parts model or a
candidate is a ``PartFeatures`` (five parts: head, left/right torso-arm, left/right leg);
boxes are xywh, 0-based, top-left corner.

- eqs. 1-2, the centroid ratios alpha and beta: ``trackers.layered.parts.centroid_ratios``
  (plain numpy, re-exported here);
- eqs. 9-10, the head-anchored search boxes: ``trackers.layered.search.search_boxes``
  (plain numpy, re-exported here); the tracker runs the compiled ``search_boxes_many``;
- eq. 11, feature differences: ``differences`` (compiled: ``association.selected_differences``);
- eq. 12, part scores: ``part_scores``; eq. 13, global score: ``global_score``
  (compiled together with eq. 11: ``association.pair_scores``).
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr

from trackers.layered.parts import N_PARTS, PartFeatures, centroid_ratios
from trackers.layered.models import FEATURES, FeatureModels
from trackers.layered.search import search_boxes

__all__ = [
    "centroid_ratios",
    "differences",
    "global_score",
    "match_probability",
    "part_scores",
    "search_boxes",
]


def differences(model: PartFeatures, cand: PartFeatures, ti: np.ndarray, n: np.ndarray,
                misses: np.ndarray | None = None) -> np.ndarray:
    """Eq. 11, d_ij = |f_ij - F_ij|, for the pairs (target ti[k], candidate n[k]).

    Features i in ``FEATURES`` order: area and perimeter (absolute differences), HSV and
    XYZ histograms (1 - Bhattacharyya coefficient; 1 when the candidate's part has no
    foreground), displacement of the part centroid over the target's height, and 1 - IoU
    of the part rectangles. After a gap of ``misses`` frames the last two are divided by
    1 + misses (our adaptation).

    Returns:
        (K, 6, 5) differences, >= 0.
    """
    ti, n = np.asarray(ti, dtype=np.intp), np.asarray(n, dtype=np.intp)
    d = np.empty((len(ti), len(FEATURES), N_PARTS))
    d[:, 0] = np.abs(model.area[ti] - cand.area[n])                          # area
    d[:, 1] = np.abs(model.perimeter[ti] - cand.perimeter[n])                # perimeter
    empty = cand.area[n] <= 0
    for i, name in ((2, "hsv"), (3, "xyz")):
        rho = np.sqrt(getattr(model, name)[ti] * getattr(cand, name)[n]).sum(-1)
        d[:, i] = np.where(empty, 1.0, 1.0 - rho)                            # 1 - rho
    d[:, 4] = (np.linalg.norm(cand.centroid[n] - model.centroid[ti], axis=2)
               / np.maximum(model.height[ti], 1.0)[:, None])                 # |c - C| / H
    a, b = model.parts[ti], cand.parts[n]
    iw = np.clip(np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2])
                 - np.maximum(a[..., 0], b[..., 0]), 0.0, None)
    ih = np.clip(np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3])
                 - np.maximum(a[..., 1], b[..., 1]), 0.0, None)
    inter = iw * ih
    union = a[..., 2] * a[..., 3] + b[..., 2] * b[..., 3] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        d[:, 5] = 1.0 - np.where(union > 0, inter / union, 0.0)               # 1 - IoU
    if misses is not None:
        g = 1.0 / (1.0 + np.asarray(misses, dtype=np.float64)[ti])
        d[:, 4:6] *= g[:, None, None]
    return np.clip(d, 0.0, None)


def match_probability(models: FeatureModels, d: np.ndarray) -> np.ndarray:
    """p(d | theta_ij) of eq. 12 as the survival function P(D >= d) of each fitted folded
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
