"""Hand-made MOT tables for the evaluation tests."""

from __future__ import annotations

import numpy as np

from occbench.io.mot import MotTable


def table(rows, conf=None, classes=None) -> MotTable:
    """MotTable from (frame, id, x, y, w, h) rows (0-based boxes); conf 1 and no class unless given."""
    if not rows:
        return MotTable.empty()
    a = np.asarray(rows, dtype=np.float64)
    n = len(a)
    return MotTable(
        a[:, 0].astype(np.int64),
        a[:, 1].astype(np.int64),
        a[:, 2:6].copy(),
        np.ones(n) if conf is None else np.asarray(conf, dtype=np.float64),
        np.full(n, -1, dtype=np.int64) if classes is None else np.asarray(classes, np.int64),
        np.full(n, np.nan),
    )
