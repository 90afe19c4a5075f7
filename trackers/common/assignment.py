"""Optimal assignment (Hungarian method) with a gate."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment


def assign(
    cost: np.ndarray, max_cost: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Minimum-cost assignment keeping only pairs with cost <= max_cost.

    Args:
        cost: (N, M) float matrix; +inf or NaN marks forbidden pairs.
        max_cost: largest accepted cost.
    Returns:
        matches (K, 2) int rows (i, j), unmatched rows (N - K,), unmatched columns (M - K,).
    """
    cost = np.asarray(cost, dtype=np.float64)
    n, m = cost.shape
    if n == 0 or m == 0:
        return np.zeros((0, 2), dtype=int), np.arange(n), np.arange(m)
    allowed = np.isfinite(cost) & (cost <= max_cost)
    # forbidden pairs cost more than any set of allowed ones: the optimum keeps every
    # allowed pair it can, then the cheapest
    base = max_cost if np.isfinite(max_cost) else 0.0  # max_cost=inf: any finite cost
    big = base + 1.0 + np.abs(np.where(allowed, cost, 0.0)).max() * (n + m)
    rows, cols = linear_sum_assignment(np.where(allowed, cost, big))
    keep = allowed[rows, cols]
    rows, cols = rows[keep], cols[keep]
    free_rows = np.ones(n, dtype=bool)
    free_cols = np.ones(m, dtype=bool)
    free_rows[rows] = False
    free_cols[cols] = False
    return np.column_stack([rows, cols]), np.flatnonzero(free_rows), np.flatnonzero(free_cols)
