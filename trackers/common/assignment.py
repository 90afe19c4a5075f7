"""Optimal assignment (Hungarian method) with a gate.

Compiled with numba's ``cache=True``: the cache sits in ``__pycache__`` beside this file, keyed on
the file's time stamp (not on its import name).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numba
import numpy as np
from scipy.optimize import linear_sum_assignment


def assign(
    cost: np.ndarray, max_cost: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Minimum-cost assignment keeping only pairs with cost <= max_cost.

    Forbidden pairs cost more than any set of allowed ones: the optimum keeps every
    allowed pair it can, then the cheapest. The gating before and after the Hungarian
    method (scipy's ``linear_sum_assignment``) is compiled (two small loops).

    Args:
        cost: (N, M) float matrix; +inf or NaN marks forbidden pairs.
        max_cost: largest accepted cost.
    Returns:
        matches (K, 2) int rows (i, j), unmatched rows (N - K,), unmatched columns (M - K,).
    """
    cost = np.ascontiguousarray(cost, dtype=np.float64)
    n, m = cost.shape
    if n == 0 or m == 0:
        return np.zeros((0, 2), dtype=int), np.arange(n), np.arange(m)
    max_cost = float(max_cost)
    base = max_cost if math.isfinite(max_cost) else 0.0  # max_cost=inf: any finite cost
    allowed, gated = _gate(cost, max_cost, base)
    rows, cols = linear_sum_assignment(gated)
    return _split(allowed, rows, cols)


@numba.njit(cache=True)
def _gate(cost: np.ndarray, max_cost: float, base: float) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover (compiled)
    """allowed = isfinite(cost) & (cost <= max_cost), and the cost matrix with every
    forbidden pair at base + 1 + max|allowed cost| (N + M)."""
    n, m = cost.shape
    allowed = np.empty((n, m), np.bool_)
    largest = 0.0
    for i in range(n):
        for j in range(m):
            c = cost[i, j]
            allowed[i, j] = np.isfinite(c) and c <= max_cost
            if allowed[i, j] and abs(c) > largest:
                largest = abs(c)
    big = base + 1.0 + largest * (n + m)
    gated = np.empty((n, m))
    for i in range(n):
        for j in range(m):
            gated[i, j] = cost[i, j] if allowed[i, j] else big
    return allowed, gated


@numba.njit(cache=True)
def _split(allowed: np.ndarray, rows: np.ndarray, cols: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover (compiled)
    """The assigned pairs (K, 2) that are allowed, and the rows and columns left free."""
    n, m = allowed.shape
    free_rows, free_cols = np.ones(n, np.bool_), np.ones(m, np.bool_)
    matches = np.empty((rows.shape[0], 2), np.int64)
    k = 0
    for q in range(rows.shape[0]):
        i, j = rows[q], cols[q]
        if allowed[i, j]:
            matches[k, 0], matches[k, 1] = i, j
            free_rows[i], free_cols[j] = False, False
            k += 1
    return matches[:k].copy(), np.flatnonzero(free_rows), np.flatnonzero(free_cols)


def assign_min_cost(
    cost: np.ndarray, max_cost: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Minimum-cost assignment where leaving a row unmatched costs ``max_cost``, the
    largest cost an accepted pair can have.

    Unlike ``assign``, which keeps as many allowed pairs as it can and only then the
    cheapest, a pair is taken only when it lowers the total: one pair of cost c and a
    row left over (c + max_cost) beat two pairs c1 + c2 when they cost less. Row i stays
    unmatched through its own dummy column M + i of cost ``max_cost``.

    Args:
        cost: (N, M) float matrix; +inf or NaN marks forbidden pairs.
        max_cost: largest accepted cost and the cost of an unmatched row (finite).
    Returns:
        matches (K, 2) int rows (i, j), unmatched rows (N - K,), unmatched columns (M - K,).
    Raises:
        ValueError: ``max_cost`` is not finite.
    """
    cost = np.ascontiguousarray(cost, dtype=np.float64)
    n, m = cost.shape
    max_cost = float(max_cost)
    if not math.isfinite(max_cost):
        raise ValueError(f"assign_min_cost: max_cost must be finite, got {max_cost}")
    if n == 0 or m == 0:
        return np.zeros((0, 2), dtype=int), np.arange(n), np.arange(m)
    allowed, _ = _gate(cost, max_cost, max_cost)
    # a forbidden entry costs more than any assignment without one (e.g. every row left
    # over, n max_cost)
    largest = max(float(np.abs(cost[allowed]).max()) if allowed.any() else 0.0, abs(max_cost))
    big = max_cost + 1.0 + largest * (2 * n + m)
    full = np.full((n, m + n), big)  # dummy columns: only row i's own is allowed
    np.copyto(full[:, :m], cost, where=allowed)
    full[np.arange(n), m + np.arange(n)] = max_cost
    rows, cols = linear_sum_assignment(full)
    keep = cols < m
    return _split(allowed, rows[keep], cols[keep])


def assign_in_blocks(
    parts: list[tuple[np.ndarray, np.ndarray]],
    block_cost: Callable[[np.ndarray, np.ndarray], np.ndarray],
    max_cost: float,
    solve: Callable = assign,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``solve`` (``assign`` or ``assign_min_cost``) block by block over ``parts`` (rows,
    cols) from ``spatial.blocks``, whose allowed pairs never cross a block: the optimum
    of the whole matrix, without building it. ``block_cost(rows, cols)`` gives a block's
    dense cost matrix. Returns what ``solve`` returns, in global indices (matches sorted
    by row, unmatched rows and columns ascending)."""
    matches, free_rows, free_cols = [np.zeros((0, 2), dtype=np.int64)], [], []
    for rows, cols in parts:
        m, fr, fc = solve(block_cost(rows, cols), max_cost)
        matches.append(np.column_stack([rows[m[:, 0]], cols[m[:, 1]]]))
        free_rows.append(rows[fr])
        free_cols.append(cols[fc])
    out = np.concatenate(matches)
    out = out[np.argsort(out[:, 0], kind="stable")]
    return (out, np.sort(np.concatenate(free_rows + [np.zeros(0, np.int64)])),
            np.sort(np.concatenate(free_cols + [np.zeros(0, np.int64)])))
