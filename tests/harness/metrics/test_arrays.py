"""occbench.metrics.arrays.distinct equals numpy's unique / union1d."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.metrics.arrays import distinct


@pytest.mark.parametrize("n", [0, 1, 7, 1000])
def test_distinct_equals_unique_and_union(n):
    rng = np.random.default_rng(n)
    a, b = rng.integers(-5, 50, n), rng.integers(0, 80, n // 2 + 1)
    for got, want in ((distinct(a), np.unique(a)), (distinct(a, b), np.union1d(a, b))):
        assert got.dtype == want.dtype and got.tolist() == want.tolist()
