"""PBM's fitting samples (``occbench.fit.pbm_pairs``): pairs of a person in consecutive frames,
itself and its nearest others inside the tracker's gate, optionally motion-compensated."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.fit.pbm_pairs import collect_pairs
from occbench.trackers.layered.parts import FEATURES

N_PARTS = 5


def test_pairs_are_self_then_nearest_others_inside_the_gate():
    from occbench.fit.pbm_pairs import _pairs

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
    synthetic = pytest.importorskip("occbench.datasets.synthetic")
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
    synthetic = pytest.importorskip("occbench.datasets.synthetic")
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


def test_a_frame_window_collects_the_pairs_of_its_own_frames():
    from occbench.datasets.base import window
    from occbench.datasets.synthetic import load_scenario

    seq = load_scenario("crowd", seed=1, length=12)
    # uncompensated: a compensated window's first pair knows no earlier step
    full = collect_pairs([seq], neighbours=0, motion_compensation=False)
    head = collect_pairs(window([seq], [1, 8]), neighbours=0, motion_compensation=False)
    np.testing.assert_array_equal(
        head.d, collect_pairs([seq], max_frames=8, neighbours=0, motion_compensation=False).d)
    tail = collect_pairs(window([seq], [5, 12]), neighbours=0, motion_compensation=False)
    assert 0 < len(tail) < len(full)
    np.testing.assert_array_equal(tail.d, full.d[-len(tail):])  # the pairs of frames 6-12


def test_background_subtraction_foreground_measures_the_same_pairs_differently():
    """``foreground="mog2"`` (real frames) measures the parts on the front end's background
    subtraction instead of the exact masks: same pairs, other areas."""
    from occbench.datasets.synthetic import load_scenario

    seq = load_scenario("crossing", seed=1, length=12)
    exact = collect_pairs([seq], neighbours=0)
    mog2 = collect_pairs([seq], neighbours=0, foreground="mog2")
    assert len(mog2) == len(exact) > 0
    area = FEATURES.index("area")
    assert not np.array_equal(mog2.d[:, area], exact.d[:, area])
    assert np.isfinite(mog2.d).all()
