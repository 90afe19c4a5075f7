"""``box_groups._measure_all``: a searched pair's boxes measured together (``_measure_grid``:
each height's rows, each width's columns and each (width, pixel row)'s foreground mask made
once) give the bits of ``_measure``, box by box; groups that are not such a grid
(``_is_grid``) and the boxes past the groups are measured one by one, as grids of one."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered.association import _arrays, _theta
from occbench.trackers.layered.box_groups import _is_grid, _measure, _measure_all
from occbench.trackers.layered.box_search import _kernel_state
from occbench.trackers.layered.feature_models import load_feature_models
from occbench.trackers.layered.parts import N_FEATURES, N_PARTS, PartFeatureExtractor
from occbench.trackers.layered.search import search_boxes_many

SIDE, M = 5, 25
H, W = 90, 120


def _groups(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """(K, 4) boxes in groups of 25, their alpha and beta (K,) and how many groups are
    grids: search boxes (eqs. 9-10) inside, across the left, top and bottom edges and
    larger than the frame, then a grid with a NaN width, one with -0.0 and 0.0 tops and
    one of random boxes (the last three not grids)."""
    heads = np.array([[60.0, 20.0, 6.0], [3.0, 10.0, 6.0], [100.0, -8.0, 6.0], [40.0, 70.0, 6.0],
                      [60.0, 5.0, 6.0], [30.0, 0.0, 6.0], [80.0, 0.0, 6.0]])
    wh = np.array([[20.0, 50.0], [22.0, 48.0], [18.0, 40.0], [25.0, 60.0], [150.0, 120.0],
                   [20.0, 50.0], [20.0, 50.0]])
    alpha = rng.uniform(0.3, 0.7, len(heads))
    boxes = search_boxes_many(heads, wh, alpha, 0.05, 2).reshape(-1, 4)
    a = np.repeat(alpha, M)
    b = np.repeat(rng.uniform(0.2, 0.8, len(heads)), M)
    boxes[5 * M + 7, 2] = np.nan                      # group 5: a NaN width
    boxes[6 * M:7 * M:2, 1] = -0.0                     # group 6: tops -0.0 and 0.0
    boxes = np.vstack([boxes, np.column_stack([rng.uniform(-10, 100, M), rng.uniform(-10, 60, M),
                                               rng.uniform(5, 40, M), rng.uniform(10, 70, M)])])
    return boxes, np.append(a, rng.uniform(0.2, 0.8, M)), np.append(b, rng.uniform(0.2, 0.8, M)), 5


@pytest.mark.parametrize(("with_fg", "apart"), [(True, False), (False, False), (True, True)])
def test_a_group_measured_together_has_the_bits_of_its_boxes_measured_one_by_one(with_fg, apart):
    rng = np.random.default_rng(5)
    frame = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    ex = PartFeatureExtractor(4, 21, 9)
    ex.start(frame, rng.random((H, W)) < 0.7 if with_fg else None)
    boxes, alpha, beta, grids = _groups(rng)
    K, T = len(boxes), 3
    ti = rng.integers(0, T, K)
    model = ex.extract(rng.uniform(10, 40, (T, 4)) + [20, 10, 0, 20], 0.5, 0.5)
    b, ratios, sampling = ex.sampling(boxes, alpha, beta)
    m, gap, models = _arrays(model), (rng.uniform(0, 3, T), apart), load_feature_models()
    rule = (4.5, np.ones(N_FEATURES), np.ones(N_PARTS))
    scratch, _, _, ref, _, _ = _kernel_state(b, ti, sampling, m, rule, _theta(models))
    for k in range(K):
        _measure(k, b, ti, ratios, sampling, m, gap, scratch, ref)
    scratch, _, _, d, _, _ = _kernel_state(b, ti, sampling, m, rule, _theta(models))
    _measure_all(b, ti, ratios, sampling, m, gap, scratch, M, K - M, d)  # the last: past the groups
    # the grids take the shared path, the other three groups are measured box by box
    assert [_is_grid(b, *ratios, g0, SIDE) for g0 in range(0, K, M)] == [True] * grids + [False] * 3
    assert np.isfinite(ref[:grids * M]).all() and np.isnan(ref[5 * M + 7]).any()
    assert d.tobytes() == ref.tobytes()
