"""Learning the feature weights omega of PBM eq. 12 (PBM 4.1) in ``occbench.fit.pbm_weights``."""

from __future__ import annotations

import numpy as np
import pytest
from pbm_scenes import unit_models

from occbench.fit.pbm_pairs import PairSamples
from occbench.fit.pbm_weights import (
    block_folds,
    fold_accuracies,
    pick_best,
    search_weights,
    weight_grid,
)
from occbench.trackers.layered.parts import FEATURES

N_PARTS = 5


def constructed_samples(informative: int, n_blocks: int = 20, per_block: int = 20,
                        seed: int = 0) -> PairSamples:
    """Feature ``informative`` separates positives (d = 0.2) from negatives (d = 4); every
    other feature is noise of the same distribution for both classes."""
    rng = np.random.default_rng(seed)
    m = n_blocks * per_block
    positive = np.tile(np.arange(per_block) % 2 == 0, n_blocks)
    d = rng.uniform(0.0, 3.0, size=(m, len(FEATURES), N_PARTS))
    d[:, informative] = np.where(positive[:, None], 0.2, 4.0)
    block = np.repeat(np.arange(n_blocks) * 7 + 3, per_block)  # arbitrary, sorted ids
    return PairSamples(d, positive, block)


@pytest.mark.parametrize("informative", [0, 3, 5])
def test_search_finds_the_separating_feature(informative):
    samples = constructed_samples(informative)
    fit = search_weights(samples, unit_models(), np.full(N_PARTS, 0.2), threshold=0.5,
                         spread=1.0, step=0.25, k=5, reference={f: 1.0 for f in FEATURES})
    w = np.array([fit.weights[f] for f in FEATURES])
    assert w.sum() == pytest.approx(1.0)
    # p(0.2) = 0.84 and p(4) = 6e-5 for the informative feature; the noise features have
    # mean p ~ 0.5 for both classes: only a large weight on the informative one separates
    assert fit.accuracy == pytest.approx(1.0) and fit.nested_accuracy == pytest.approx(1.0)
    assert np.argmax(w) == informative and w[informative] >= 0.5
    assert fit.reference_accuracy is not None and fit.reference_accuracy < 0.9
    assert fit.settings["positives"] == fit.settings["negatives"] == 200
    assert fit.settings["folds"] == 5 and fit.settings["blocks"] == 20


def test_search_is_deterministic():
    samples = constructed_samples(2, seed=4)
    args = (unit_models(), np.array([0.3, 0.2, 0.2, 0.15, 0.15]), 0.5, 1.0, 0.25, 5)
    a, b = search_weights(samples, *args), search_weights(samples, *args)
    assert a.weights == b.weights and a.accuracy == b.accuracy
    np.testing.assert_array_equal(a.fold_accuracy, b.fold_accuracy)


def test_ties_go_to_the_weights_nearest_uniform():
    grid = weight_grid(0.5)
    uniform = int(np.flatnonzero(np.all(np.isclose(grid, 1 / 6), axis=1))[0])
    assert pick_best(np.ones(len(grid)), grid) == uniform
    acc = np.zeros(len(grid))
    acc[[3, 10]] = 1.0  # a tie between two points: the nearer to uniform wins
    dist = np.linalg.norm(grid[[3, 10]] - 1 / 6, axis=1)
    assert pick_best(acc, grid) == [3, 10][int(np.argmin(dist))]


def test_weight_grid_is_normalised_and_unique():
    grid = weight_grid(0.5)  # {0, 0.5, 1}^6 minus zero: 3^6 - 1 = 728, merged by scale
    assert np.allclose(grid.sum(axis=1), 1.0) and (grid >= 0).all()
    assert len(np.unique(np.round(grid, 12), axis=0)) == len(grid)
    # (0.5, 0, ...) and (1, 0, ...) are one point; so are all-0.5 and all-1
    assert len(grid) == 3**6 - 1 - (2**6 - 1)
    with pytest.raises(ValueError, match="step"):
        weight_grid(0.3)


def test_folds_never_split_a_block():
    rng = np.random.default_rng(1)
    block = rng.integers(0, 40, size=500)
    folds = block_folds(block, 5)
    for b in np.unique(block):
        assert len(np.unique(folds[block == b])) == 1
    assert set(folds.tolist()) == set(range(5))
    with pytest.raises(ValueError, match="blocks"):
        block_folds(np.array([1, 1, 2, 3]), 5)


def test_fold_accuracy_is_balanced():
    q = np.array([[1.0] + [0] * 5, [1.0] + [0] * 5, [1.0] + [0] * 5, [0.0] * 6])
    positive = np.array([True, False, False, False])
    grid = np.eye(6)[:1]  # omega on feature 0 only: scores 1, 1, 1, 0
    acc = fold_accuracies(q, positive, np.zeros(4, int), 1, grid, threshold=0.5)
    # positives all right (1/1), negatives 1 of 3 right: balanced 0.5 * (1 + 1/3)
    assert acc[0, 0] == pytest.approx(2 / 3)
