"""occbench.report.html.charts: the specs carry every row of their data."""

from __future__ import annotations

import numpy as np

from occbench.metrics.timeline import FrameCounts
from occbench.report.html import charts


def _counts(frames: int, seed: int) -> FrameCounts:
    rng = np.random.default_rng(seed)
    f = np.arange(1, frames + 1)
    n = rng.integers(0, 3, size=(3, frames))  # misses, false positives, switches
    zeros = np.zeros(frames, np.int64)
    hota = np.zeros((frames, 19))
    return FrameCounts(f, zeros + 2, zeros + 2, n[0], n[1], n[2], zeros, hota, hota, hota,
                       hota)


def test_segments_join_runs_of_equal_counts() -> None:
    frames = np.array([1, 2, 3, 5, 6, 7])
    assert charts.segments(frames, np.array([1, 1, 2, 2, 0, 1])) == [
        (1, 2, 1), (3, 3, 2), (5, 5, 2), (7, 7, 1)]


def test_a_long_timeline_of_many_trackers_keeps_every_segment() -> None:
    # 20 trackers x 800 frames of random counts: over 5,000 segments, Altair's default limit
    counts = {f"t{i}": _counts(800, i) for i in range(20)}
    expected = sum(len(charts.segments(c.frames, getattr(c, attr)))
                   for c in counts.values() for attr, _, _ in charts.KINDS)
    assert expected > 5000
    spec = charts.timeline("long", counts)
    (rows,) = spec["datasets"].values()
    assert len(rows) == expected
