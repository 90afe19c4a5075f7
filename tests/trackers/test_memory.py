"""Memory per frame grows with the detections, not with their square: 5,000 detections in
one frame (a 4K frame of small, scattered people) stay under a bound linear in the
detections for each tracker (issue 39: reta took 2.2 GB, the baseline 0.8 GB and pbm 2.2
GB for 5,000 detections, in (N, M) matrices)."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from occbench.config.build import build_tracker, compose_config
from occbench.trackers.records import Detections

N = 5000


def _peak_bytes(name: str) -> int:
    """Peak traced memory of the second frame's update (5,000 predictions x 5,000
    detections), above what the tracker held before it."""
    tracker = build_tracker(name, compose_config([f"tracker={name}"]).tracker)
    tracker.reset()
    rng = np.random.default_rng(0)
    boxes = np.column_stack([rng.uniform([0, 0], [3820, 2120], (N, 2)), np.full((N, 2), [16.0, 36.0])])
    image = rng.integers(0, 255, (2160, 3840, 3), dtype=np.uint8)
    tracker.update(image, Detections(boxes, np.ones(N)), None)
    moved = boxes + np.column_stack([rng.normal(0, 1, (N, 2)), np.zeros((N, 2))])
    tracemalloc.start()
    try:
        tracks = tracker.update(image, Detections(moved, np.ones(N)), None)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(tracks) > 0.9 * N
    return peak


def _reta_bound() -> int:
    """Four (bins^3,) float64 histograms a detection brings (p, q and their square roots over
    the bins in use, eq. 4) and 40 kB besides, per detection."""
    bins = compose_config(["tracker=reta"]).tracker.appearance.bins
    return N * (4 * 8 * bins ** 3 + 40_000)


def _pbm_bound() -> int:
    """A candidate's and a target's five parts (HSV and XYZ histograms of bins^3 float64
    each) several times over, 20 kB besides, per detection, and 64 MB for one block of the
    association (``frame_blocks``: at most 2^18 pairs with their part scores)."""
    bins = compose_config(["tracker=pbm"]).tracker.features.histogram_bins
    return N * (8 * 2 * 5 * 8 * bins ** 3 + 20_000) + 64 * 2**20


@pytest.mark.parametrize("name, bound", [("baseline", lambda: N * 20_000), ("reta", _reta_bound),
                                         ("pbm", _pbm_bound)])
def test_5000_detections_in_one_frame_stay_under_a_linear_memory_bound(name, bound):
    assert _peak_bytes(name) <= bound()
