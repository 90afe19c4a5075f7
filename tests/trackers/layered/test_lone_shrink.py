"""``adaptations.lone_shrink``: a detection smaller than a target's prediction is the
target at its own size unless another live target covers its aligned predicted box
(PBM 3.1 reads every smaller region as a partial occlusion; issue 35, docs/adaptations.md)."""

from types import SimpleNamespace

import numpy as np
import pytest

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.layered.smaller import LoneShrink, OccludedSmaller
from occbench.trackers.layered.search import Candidates


def _scene(occluder_box, blob=False):
    """Target 0 predicted 40 x 160 (grown wrongly), its person's detection 20 x 60 below
    the same head; target 1 elsewhere or over target 0's aligned box."""
    det = np.array([[100.0, 50.0, 20.0, 60.0]])
    cand = Candidates(det, det.copy(), np.array([[110.0, 50.0, 6.0]]), np.array([blob]),
                      np.array([1]))
    dof = np.array([[90.0, 50.0, 110.0, 120.0, 40.0, 160.0],
                    [*occluder_box[:2], 0.0, 0.0, *occluder_box[2:]]])
    targets = SimpleNamespace(alpha=np.array([0.5, 0.5]), dof=dof)
    pred_wh = np.array([[40.0, 160.0], [20.0, 60.0]])
    return np.array([[-1], [0]]), cand, targets, pred_wh


def test_a_smaller_detection_without_an_occluder_is_the_target_at_its_size():
    kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0])
    LoneShrink(0.3).apply(kinds, cand, targets, pred, np.array([True, True]))
    assert kinds.tolist() == [[0], [0]]


def test_an_occluder_over_the_aligned_box_keeps_the_partial_occlusion():
    kinds, cand, targets, pred = _scene([85.0, 110.0, 50.0, 100.0])  # covers its lower part
    LoneShrink(0.3).apply(kinds, cand, targets, pred, np.array([True, True]))
    assert kinds.tolist() == [[-1], [0]]
    kinds, cand, targets, pred = _scene([85.0, 110.0, 50.0, 100.0])
    LoneShrink(0.3).apply(kinds, cand, targets, pred, np.array([True, False]))  # long gone
    assert kinds.tolist() == [[0], [0]]


def test_blobs_and_the_paper_keep_pbm_31():
    kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0], blob=True)
    LoneShrink(0.3).apply(kinds, cand, targets, pred, np.array([True, True]))
    assert kinds.tolist() == [[-1], [0]]
    kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0])
    OccludedSmaller().apply(kinds, cand, targets, pred, np.array([True, True]))
    assert kinds.tolist() == [[-1], [0]]
    assert isinstance(build_rules(Adaptations.paper()).smaller, OccludedSmaller)
    assert isinstance(build_rules(Adaptations(lone_shrink=0.0, lone_shrink_shape=0.0)).smaller,
                      OccludedSmaller)
    assert build_rules(Adaptations()).smaller == LoneShrink(0.3, 0.7)  # the default
    assert isinstance(build_rules(Adaptations(lone_shrink=0.3)).smaller, LoneShrink)


def test_shape_keeps_pbm_31_for_a_piece_of_a_person():
    """With ``lone_shrink_shape``, a smaller detection as wide as it is tall (a head-high
    sliver) is not the target at its own size; a whole person's shape (20 x 60 against a
    40 x 160 prediction: h/w 3 against 4) still is."""
    kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0])
    LoneShrink(0.3, shape=0.5).apply(kinds, cand, targets, pred, np.array([True, True]))
    assert kinds.tolist() == [[0], [0]]
    kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0])
    sliver = np.array([[105.0, 50.0, 12.0, 12.0]])
    cand = Candidates(sliver, sliver.copy(), cand.head, cand.blob, np.array([1]))
    LoneShrink(0.3, shape=0.5).apply(kinds, cand, targets, pred, np.array([True, True]))
    assert kinds.tolist() == [[-1], [0]]
    kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0])
    cand = Candidates(sliver, sliver.copy(), cand.head, cand.blob, np.array([1]))
    LoneShrink(0.3).apply(kinds, cand, targets, pred, np.array([True, True]))  # any shape
    assert kinds.tolist() == [[0], [0]]
    assert build_rules(Adaptations(lone_shrink=0.3, lone_shrink_shape=0.5)).smaller.shape == 0.5


def test_shape_needs_lone_shrink():
    with pytest.raises(ValueError, match="lone_shrink_shape"):
        Adaptations(lone_shrink=0.0, lone_shrink_shape=0.5)
