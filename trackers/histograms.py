"""Colour histograms and their similarity (Reta eqs. 1 and 4; PBM 2.2).

Histograms are float64 and sum to 1 (or are all zero for an empty region).
"""

from __future__ import annotations

import numpy as np


def colour_histogram(pixels: np.ndarray, bins: int = 16, value_range: float = 256.0) -> np.ndarray:
    """Joint 3-channel histogram of (K, 3) pixel values, flattened to (bins**3,).

    Each channel in [0, value_range) is quantised to ``bins`` levels (Reta eq. 1 with
    16x16x16 bins over RGB). Normalised to sum 1; all zero when K == 0.
    """
    p = np.asarray(pixels).reshape(-1, 3)
    hist = np.zeros(bins**3, dtype=np.float64)
    if len(p) == 0:
        return hist
    q = np.clip((p.astype(np.float64) * (bins / value_range)).astype(np.int64), 0, bins - 1)
    idx = (q[:, 0] * bins + q[:, 1]) * bins + q[:, 2]
    hist += np.bincount(idx, minlength=bins**3)
    return hist / len(p)


def masked_histogram(image: np.ndarray, mask: np.ndarray, bins: int = 16) -> np.ndarray:
    """Joint histogram of the (H, W, 3) uint8 ``image`` pixels where (H, W) ``mask`` is true."""
    return colour_histogram(image[mask], bins=bins)


def bhattacharyya(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Bhattacharyya coefficient rho = sum_u sqrt(p_u q_u) (Reta eq. 4).

    Args:
        p: (N, B) or (B,) histograms; q: (M, B) or (B,) histograms, each summing to 1.
    Returns:
        (N, M) matrix (or a scalar for two vectors) in [0, 1]: 1 for identical, 0 for disjoint.
    """
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    if p.ndim == 1 and q.ndim == 1:
        return float(np.sqrt(p * q).sum())
    return np.sqrt(np.atleast_2d(p)) @ np.sqrt(np.atleast_2d(q)).T
