"""Array helpers shared by the metrics."""

from __future__ import annotations

import numpy as np


def distinct(*arrays: np.ndarray) -> np.ndarray:
    """The sorted distinct values of one or more 1-D integer arrays (``np.unique`` of their
    concatenation, ``np.union1d`` of two), found by one sort: numpy 2's ``unique`` without
    ``return_*`` hashes first, many times slower on large arrays."""
    a = np.sort(np.concatenate(arrays) if len(arrays) != 1 else arrays[0], kind="stable")
    return a[np.r_[True, a[1:] != a[:-1]]] if len(a) else a
