"""Pairs of boxes that meet and the blocks an assignment splits into
(``occbench.trackers.common.spatial``), against the dense definitions."""

from __future__ import annotations

import numpy as np

from occbench.trackers.common.assignment import assign, assign_in_blocks, assign_min_cost
from occbench.trackers.common.spatial import blocks, meeting_pairs
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.three_hypothesis.occlusion import boxes_meet


def _boxes(rng, n):
    return np.column_stack([rng.uniform(0, 100, (n, 2)), rng.uniform(0, 30, (n, 2))])


def test_meeting_pairs_are_the_dense_pairs_in_row_major_order():
    rng = np.random.default_rng(1)
    for trial in range(200):
        a, b = _boxes(rng, rng.integers(0, 40)), _boxes(rng, rng.integers(0, 40))
        if trial % 5 == 0 and len(a):
            a[0] = [np.nan, 1, 2, 3]  # never meets
        if trial % 3 == 0 and len(a) > 1 and len(b) > 1:  # a NaN anywhere: never meets
            a[-1, trial % 4] = np.nan
            b[-1, (trial // 3) % 4] = np.nan
        if trial % 7 == 0 and len(b):
            b[0, 2] = np.inf  # meets everything on its rows
        ia, ib = meeting_pairs(a, b)
        ra, rb = np.nonzero(boxes_meet(a, b))
        assert ia.tolist() == ra.tolist() and ib.tolist() == rb.tolist()
    a, b = np.array([[0.0, 0, 10, 10]]), np.array([[12.0, 0, 5, 5]])
    assert len(meeting_pairs(a, b)[0]) == 0 and len(meeting_pairs(a, b, pad=2.5)[0]) == 1


def test_blocks_cover_everything_once_and_no_pair_crosses_them():
    rng = np.random.default_rng(2)
    for _ in range(100):
        n, m = rng.integers(0, 40, 2)
        ia, ib = meeting_pairs(_boxes(rng, n), _boxes(rng, m))
        parts = blocks(n, m, lambda: (ia, ib), limit=10)
        block_of_row = {int(i): k for k, (r, _) in enumerate(parts) for i in r}
        block_of_col = {int(j): k for k, (_, c) in enumerate(parts) for j in c}
        assert sorted(block_of_row) == list(range(n)) and sorted(block_of_col) == list(range(m))
        assert sum(len(r) for r, _ in parts) == n and sum(len(c) for _, c in parts) == m
        assert all(block_of_row[i] == block_of_col[j] for i, j in zip(ia.tolist(), ib.tolist()))
    assert len(blocks(3, 4, lambda: 1 / 0)) == 1  # small: one block, pairs never asked


def test_assignment_block_by_block_is_the_whole_matrix_assignment():
    rng = np.random.default_rng(3)
    for _ in range(60):
        a, b = _boxes(rng, rng.integers(0, 30)), _boxes(rng, rng.integers(0, 30))
        cost = 1.0 - iou_matrix(a, b)
        parts = blocks(len(a), len(b), lambda: meeting_pairs(a, b), limit=4)
        for solve in (assign, assign_min_cost):
            whole = solve(cost, 0.9)
            split = assign_in_blocks(parts, lambda r, c: cost[np.ix_(r, c)], 0.9, solve)
            for w, s in zip(whole, split):
                assert w.tolist() == s.tolist()
