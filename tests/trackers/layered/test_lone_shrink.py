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


def _plain_lone(aligned, boxes, ti, present, cover):
    """The occluder test as numpy arrays (P, T): the reference of ``smaller.lone_rows``."""
    w, h = aligned[:, 2], aligned[:, 3]
    x0 = np.maximum(aligned[:, None, 0], boxes[None, :, 0])
    x1 = np.minimum(aligned[:, None, 0] + w[:, None], (boxes[:, 0] + boxes[:, 2])[None])
    y0 = np.maximum(aligned[:, None, 1], boxes[None, :, 1])
    y1 = np.minimum(aligned[:, None, 1] + h[:, None], (boxes[:, 1] + boxes[:, 3])[None])
    with np.errstate(invalid="ignore"):
        inter = np.clip(x1 - x0, 0, None) * np.clip(y1 - y0, 0, None)
        share = inter / np.maximum(w * h, 1e-9)[:, None]
    share[np.arange(len(ti)), ti] = 0.0
    share[:, ~present] = 0.0
    return share.max(axis=1) < cover


def test_lone_rows_equal_the_numpy_arrays_on_random_ties_empty_and_nan():
    from occbench.trackers.layered.smaller import lone_rows

    rng = np.random.default_rng(5)
    for P, T in ((0, 3), (1, 1), (40, 12), (200, 30)):
        aligned = np.column_stack([rng.uniform(0, 100, P), rng.uniform(0, 100, P),
                                   rng.uniform(0, 40, P), rng.uniform(0, 90, P)])
        boxes = np.column_stack([rng.uniform(0, 100, T), rng.uniform(0, 100, T),
                                 rng.uniform(1, 40, T), rng.uniform(1, 90, T)])
        ti, present = rng.integers(0, T, P), rng.random(T) < 0.8
        if P >= 40:
            aligned[3, 2:] = 0.0  # an empty box (area floored at 1e-9)
            aligned[4] = (boxes[(ti[4] + 1) % T, 0], boxes[(ti[4] + 1) % T, 1], 10.0, 10.0)
            boxes[(ti[5] + 1) % T] = (aligned[5, 0], aligned[5, 1], aligned[5, 2], 0.3 * aligned[5, 3])
            aligned[6, 0] = np.nan  # NaN share: not lone, as numpy's max
            boxes[(ti[7] + 1) % T, 2] = np.nan
            aligned[8] = aligned[9]  # ties
            ti[8] = ti[9]
        for cover in (0.0, 0.3, 1.0):  # 0.3: box 5 covered exactly 0.3 by one target
            got = np.empty(P, dtype=bool)
            lone_rows(aligned, boxes, ti, present, cover, got)
            assert got.tolist() == _plain_lone(aligned, boxes, ti, present, cover).tolist(), (P, cover)


def test_narrow_keeps_pbm_31_for_a_sliver_cut_by_a_vertical_edge():
    """With ``lone_shrink_narrow``, a detection much taller than the target's shape (3 x 61
    against 18 x 82: a person stepping behind a doorway's frame) is the target partly
    occluded; a whole person's shape (20 x 60 against 40 x 160) is still the target at its
    own size."""
    def sliver():
        kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0])
        pred[0] = (18.0, 82.0)
        cand.box[0] = cand.region[0] = (100.0, 50.0, 3.0, 61.0)
        return kinds, cand, targets, pred
    kinds, cand, targets, pred = sliver()
    LoneShrink(0.3, shape=0.7).apply(kinds, cand, targets, pred, np.array([True, True]))
    assert kinds.tolist() == [[0], [0]]  # without the bound: the target shrinks to 3 x 61
    kinds, cand, targets, pred = sliver()
    LoneShrink(0.3, shape=0.7, narrow=True).apply(kinds, cand, targets, pred, np.array([True, True]))
    assert kinds.tolist() == [[-1], [0]]
    kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0])
    LoneShrink(0.3, shape=0.7, narrow=True).apply(kinds, cand, targets, pred, np.array([True, True]))
    assert kinds.tolist() == [[0], [0]]
    assert build_rules(Adaptations(lone_shrink_narrow=True)).smaller == LoneShrink(0.3, 0.7, True)
    assert Adaptations.paper().changed() == [] and not Adaptations().lone_shrink_narrow
    with pytest.raises(ValueError, match="lone_shrink_narrow"):
        Adaptations(lone_shrink_shape=0.0, lone_shrink_narrow=True)


def test_only_the_pairs_in_the_gates_are_read():
    """``inside`` (``gating.in_gates``): a smaller pair outside target 0's gate keeps its kind
    (no later step reads it); inside, the rule applies as without the mask."""
    from occbench.trackers.layered.gating import in_gates

    kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0])
    gates = np.array([[0.0, 0.0, 50.0, 50.0], [0.0, 0.0, 1000.0, 1000.0]])  # centre (110, 80)
    inside = in_gates(cand.box, gates)
    assert inside.tolist() == [[False], [True]]
    LoneShrink(0.3).apply(kinds, cand, targets, pred, np.array([True, True]), inside)
    assert kinds.tolist() == [[-1], [0]]
    kinds, cand, targets, pred = _scene([300.0, 50.0, 20.0, 60.0])
    gates[0] = (110.0, 80.0, 10.0, 10.0)  # the centre on the gate's corner: inside
    LoneShrink(0.3).apply(kinds, cand, targets, pred, np.array([True, True]),
                          in_gates(cand.box, gates))
    assert kinds.tolist() == [[0], [0]]
    assert not in_gates(cand.box, np.full((1, 4), np.nan)).any()
