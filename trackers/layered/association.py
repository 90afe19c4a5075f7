"""Layered data association: feature -> part -> global (PBM 4, 4.1, eqs. 11-13).

Feature layer (eq. 11): d_ij = |f_ij - F_ij| for feature i of part j of a candidate (f)
and of the target's parts model (F). Histograms differ by 1 - rho (Bhattacharyya
coefficient, ``trackers.histograms.bhattacharyya``), overlap by 1 - IoU.
Part layer (eq. 12): p_j = sum_i omega_i p(d_ij | theta_ij), p(. | theta) the match
probability of ``FeatureModels``.
Global layer (eq. 13): p = sum_j gamma_j p_j.

Everything is vectorised over T targets x N candidates.
"""

from __future__ import annotations

import numpy as np

from trackers.frontend.parts import N_PARTS, PartFeatures, part_displacement, part_overlap
from trackers.histograms import bhattacharyya
from trackers.layered.models import FEATURES, FeatureModels


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
    d = np.empty((T, N, len(FEATURES), N_PARTS))
    d[:, :, 0] = np.abs(model.area[:, None] - cand.area[None])
    d[:, :, 1] = np.abs(model.perimeter[:, None] - cand.perimeter[None])
    for i, name in ((2, "hsv"), (3, "xyz")):
        a, b = getattr(model, name), getattr(cand, name)
        for j in range(N_PARTS):
            d[:, :, i, j] = 1.0 - bhattacharyya(a[:, j], b[:, j]).reshape(T, N)
    d[:, :, 4] = part_displacement(cand, model).transpose(1, 0, 2)
    d[:, :, 5] = 1.0 - part_overlap(model, cand)
    # an empty histogram (part without foreground) never matches
    empty = (cand.area <= 0)[None, :, :]
    d[:, :, 2] = np.where(empty, 1.0, d[:, :, 2])
    d[:, :, 3] = np.where(empty, 1.0, d[:, :, 3])
    if misses is not None:
        g = 1.0 / (1.0 + np.asarray(misses, dtype=np.float64))[:, None, None]
        d[:, :, 4] *= g
        d[:, :, 5] *= g
    return np.clip(d, 0.0, None)


def selected_differences(model: PartFeatures, cand: PartFeatures, ti: np.ndarray, n: np.ndarray,
                         misses: np.ndarray | None = None) -> np.ndarray:
    """Eq. 11 for the selected pairs (target ti[k], candidate n[k]) only: (K, 6, 5), equal
    to ``feature_differences(model, cand, misses)[ti, n]`` value for value (the same
    operations; the histogram terms take the same T x N Bhattacharyya products). The
    tracker scores only the candidates inside a target's gate (PBM 3).
    """
    ti = np.asarray(ti, dtype=np.intp)
    n = np.asarray(n, dtype=np.intp)
    d = np.empty((len(ti), len(FEATURES), N_PARTS))
    d[:, 0] = np.abs(model.area[ti] - cand.area[n])
    d[:, 1] = np.abs(model.perimeter[ti] - cand.perimeter[n])
    for i, name in ((2, "hsv"), (3, "xyz")):
        # rho of every part of every (target, candidate): the products of ``bhattacharyya``
        # (sqrt(p) @ sqrt(q)'), one (T, B) @ (B, N) matrix product per part, stacked
        a = np.sqrt(np.ascontiguousarray(getattr(model, name).transpose(1, 0, 2)))  # (5, T, B)
        b = np.sqrt(np.ascontiguousarray(getattr(cand, name).transpose(1, 0, 2)))  # (5, N, B)
        d[:, i] = 1.0 - (a @ b.transpose(0, 2, 1))[:, ti, n].T
    # part_displacement(cand, model): |c_n - C_t| / max(H_t, 1)
    d[:, 4] = (np.linalg.norm(cand.centroid[n] - model.centroid[ti], axis=2)
               / np.maximum(model.height, 1.0)[ti, None])
    # part_overlap(model, cand): IoU as ``trackers.geometry.iou_matrix`` computes it
    a, b = model.parts[ti], cand.parts[n]
    iw = np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2]) - np.maximum(a[..., 0], b[..., 0])
    ih = np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3]) - np.maximum(a[..., 1], b[..., 1])
    inter = np.clip(iw, 0.0, None) * np.clip(ih, 0.0, None)
    union = a[..., 2] * a[..., 3] + b[..., 2] * b[..., 3] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        d[:, 5] = 1.0 - np.where(union > 0, inter / union, 0.0)
    empty = cand.area[n] <= 0
    d[:, 2] = np.where(empty, 1.0, d[:, 2])
    d[:, 3] = np.where(empty, 1.0, d[:, 3])
    if misses is not None:
        g = 1.0 / (1.0 + np.asarray(misses, dtype=np.float64))[ti, None]
        d[:, 4] *= g
        d[:, 5] *= g
    return np.clip(d, 0.0, None)


def paired_differences(model: PartFeatures, cand: PartFeatures, misses: np.ndarray | None = None
                       ) -> np.ndarray:
    """Eq. 11 for M aligned pairs (model k against candidate k): (M, 6, 5).

    Same definitions as ``feature_differences``, without the all-pairs product (the
    head-anchored search scores each target against its own carved boxes only).
    """
    M = len(model)
    d = np.empty((M, len(FEATURES), N_PARTS))
    d[:, 0] = np.abs(model.area - cand.area)
    d[:, 1] = np.abs(model.perimeter - cand.perimeter)
    for i, name in ((2, "hsv"), (3, "xyz")):  # 1 - rho (Bhattacharyya), in place
        prod = getattr(model, name) * getattr(cand, name)
        d[:, i] = 1.0 - np.sqrt(prod, out=prod).sum(-1)
    d[:, 4] = np.linalg.norm(cand.centroid - model.centroid, axis=2) / np.maximum(
        model.height, 1.0)[:, None]
    a, b = model.parts, cand.parts
    iw = np.clip(np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2])
                 - np.maximum(a[..., 0], b[..., 0]), 0, None)
    ih = np.clip(np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3])
                 - np.maximum(a[..., 1], b[..., 1]), 0, None)
    inter = iw * ih
    union = a[..., 2] * a[..., 3] + b[..., 2] * b[..., 3] - inter
    d[:, 5] = 1.0 - np.where(union > 0, inter / np.maximum(union, 1e-12), 0.0)
    empty = cand.area <= 0
    d[:, 2] = np.where(empty, 1.0, d[:, 2])
    d[:, 3] = np.where(empty, 1.0, d[:, 3])
    if misses is not None:
        g = 1.0 / (1.0 + np.asarray(misses, dtype=np.float64))[:, None]
        d[:, 4] *= g
        d[:, 5] *= g
    return np.clip(d, 0.0, None)


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
    p_parts = part_scores(models, d, omega, spread)
    return p_parts, global_scores(p_parts, gamma)


def part_scores(models: FeatureModels, d: np.ndarray, omega: np.ndarray, spread: float = 1.0
                ) -> np.ndarray:
    """Eq. 12 alone (see ``layered_scores``): (..., 6, 5) differences -> (..., 5) p_j."""
    prob = models.match_probability(np.asarray(d) / spread)  # p(d_ij | theta_ij)
    w = np.asarray(omega, dtype=np.float64) / np.sum(omega)
    return np.einsum("...ij,i->...j", prob, w)  # eq. 12


def global_scores(p_parts: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """Eq. 13 alone (see ``layered_scores``): (..., 5) p_j -> (...,) p."""
    g = np.asarray(gamma, dtype=np.float64) / np.sum(gamma)
    return p_parts @ g  # eq. 13


def ambiguous(scores: np.ndarray, threshold: float, margin: float) -> tuple[int, int, bool]:
    """The best candidate of one target and whether the decision is ambiguous (PBM 4, step 4).

    Args:
        scores: (N,) global scores, -inf outside the gate.
    Returns:
        (best index or -1, runner-up index or -1, ambiguous) where ambiguous means the best
        does not exceed ``margin`` times the runner-up while both pass ``threshold``.
    """
    if len(scores) == 0:
        return -1, -1, False
    order = np.argsort(-scores, kind="stable")
    best = int(order[0])
    if not np.isfinite(scores[best]) or scores[best] < threshold:
        return -1, -1, False
    runner = int(order[1]) if len(order) > 1 and np.isfinite(scores[order[1]]) else -1
    amb = runner >= 0 and scores[runner] >= threshold and scores[best] < margin * scores[runner]
    return best, runner, bool(amb)
