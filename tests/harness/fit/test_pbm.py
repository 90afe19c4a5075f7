"""Learning the feature weights omega of PBM eq. 12 (PBM 4.1) in ``harness.fit.pbm``."""

from __future__ import annotations

import numpy as np
import pytest

from harness.fit.pbm import (
    PairSamples,
    WeightFit,
    block_folds,
    collect_pairs,
    fold_accuracies,
    load_feature_weights,
    pick_best,
    save_fit,
    search_weights,
    weight_grid,
    weights_override,
)
from trackers.layered.feature_models import FeatureModels, FoldedMixture, load_feature_models
from trackers.layered.parts import FEATURES

N_PARTS = 5


def unit_models() -> FeatureModels:
    """Half-normal models with sigma 1 for every feature and part."""
    return FeatureModels({f: [FoldedMixture([1.0], [0.0], [1.0])] * N_PARTS for f in FEATURES})


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


def test_yaml_round_trip_and_older_files(tmp_path):
    models = unit_models()
    fit = WeightFit({f: w for f, w in zip(FEATURES, [0.2, 0.0, 0.2, 0.4, 0.2, 0.0], strict=True)},
                    0.9, np.array([0.8, 1.0]), 0.85, 0.7, {"grid_step": 0.2})
    path = tmp_path / "m.yaml"
    save_fit(models, path, "PBM feature-difference models\nsecond line", fit)
    text = path.read_text()
    assert text.startswith("# PBM feature-difference models\n# second line\n")
    assert load_feature_weights(path) == fit.weights
    back = load_feature_models(path)  # the model loader ignores the extra keys
    np.testing.assert_array_equal(back.match_probability(np.full((6, 5), 0.7)),
                                  models.match_probability(np.full((6, 5), 0.7)))
    old = tmp_path / "old.yaml"
    save_fit(models, old, "older fit")
    assert load_feature_weights(old) is None
    load_feature_models(old)
    bad = tmp_path / "bad.yaml"
    assert "\n  overlap: 0.0\n" in text
    bad.write_text(text.replace("\n  overlap: 0.0\n", "\n", 1))
    with pytest.raises(ValueError, match="bad.yaml: feature_weights"):
        load_feature_weights(bad)
    assert weights_override(fit.weights) == (
        "'tracker.pbm.features.feature_weights={area:0.2,perimeter:0,hsv:0.2,xyz:0.4,displacement:0.2,overlap:0}'")


def test_pairs_are_self_then_nearest_others_inside_the_gate():
    from harness.fit.pbm import _pairs

    prev_ids = np.array([1, 2])
    prev_boxes = np.array([[0.0, 0, 10, 20], [100.0, 0, 10, 20]])  # centres (5, 10), (105, 10)
    ids = np.array([7, 1, 8, 9])
    boxes = np.array([[12.0, 0, 10, 20],   # id 7: centre (17, 10), dx 12 > w: outside
                      [1.0, 0, 10, 20],    # id 1 itself
                      [8.0, 5, 10, 20],    # id 8: centre (13, 15), dx 8, dy 5: inside
                      [3.0, -15, 10, 20]])  # id 9: centre (8, -5), dx 3, dy 15: inside
    ti, ci, same = _pairs(prev_ids, prev_boxes, ids, boxes, neighbours=1, radius=1.0)
    # person 1: itself, then the nearest other inside (id 8 at 9.4 px before id 9 at 15.3)
    assert ti.tolist() == [0, 0] and ci.tolist() == [1, 2] and same.tolist() == [True, False]
    ti, ci, same = _pairs(prev_ids, prev_boxes, ids, boxes, neighbours=5, radius=1.0)
    assert ci.tolist() == [1, 2, 3] and same.tolist() == [True, False, False]


def test_collect_pairs_on_a_synthetic_scene():
    synthetic = pytest.importorskip("harness.datasets.synthetic")
    seq = synthetic.load_scenario("crowd", seed=1, length=8)
    samples = collect_pairs([seq], neighbours=2, radius=1.0, block_frames=3)
    assert samples.d.shape == (len(samples), len(FEATURES), N_PARTS)
    assert samples.positive.any() and (~samples.positive).any()
    assert set(np.unique(samples.block).tolist()) <= {0, 1, 2}
    # same-person pairs move little; other people are further away (head displacement)
    disp = samples.d[:, FEATURES.index("displacement"), 0]
    assert np.median(disp[samples.positive]) < np.median(disp[~samples.positive])
    only_pos = collect_pairs([seq], neighbours=0)
    assert only_pos.positive.all() and len(only_pos) == samples.positive.sum()


def test_motion_compensated_pairs_measure_overlap_after_the_previous_step():
    """With ``motion_compensation`` (the tracker's default) a person's previous parts are
    moved by its previous step: walking people then differ far less in displacement and
    overlap; the appearance features are untouched; the first pair of a person (no step
    known yet) is the same either way."""
    synthetic = pytest.importorskip("harness.datasets.synthetic")
    seq = synthetic.load_scenario("crowd", seed=1, length=20)
    moved = collect_pairs([seq], neighbours=0)
    plain = collect_pairs([seq], neighbours=0, motion_compensation=False)
    assert len(moved) == len(plain) > 100
    for f in ("displacement", "overlap"):  # measured: 0.66 and 0.58 times
        i = FEATURES.index(f)
        assert np.median(moved.d[:, i]) < 0.8 * np.median(plain.d[:, i])
    same = [FEATURES.index(f) for f in ("area", "perimeter", "hsv", "xyz")]
    np.testing.assert_array_equal(moved.d[:, same], plain.d[:, same])
    n_first = len(collect_pairs([synthetic.load_scenario("crowd", seed=1, length=2)], neighbours=0))
    np.testing.assert_array_equal(moved.d[:n_first], plain.d[:n_first])
