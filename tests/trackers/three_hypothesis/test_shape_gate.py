"""Reta's shape gate (occbench.trackers.three_hypothesis.shape_gate) beside the paper's rule: a
hand-derivable case and a constructed scene where the box of the person in front would carry
a hidden person's id."""

from __future__ import annotations

import numpy as np
import pytest
from reta_scenes import RED, detections, ellipse_frame

from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import TrackState
from occbench.trackers.three_hypothesis import Adaptations, RetaTracker
from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer
from occbench.trackers.three_hypothesis.rules import build_rules
from occbench.trackers.three_hypothesis.shape_gate import AnyShape, ShapeGate, shape_similarity

W, H = 200, 120


def _frame(boxes, colours):
    return ellipse_frame(boxes, colours, (W, H))


def test_paper_mode_has_no_shape_gate():
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).shape, AnyShape)
    assert build_rules(Adaptations(shape_gate=0.7), h).shape == ShapeGate(0.7)
    with pytest.raises(ValueError, match="adaptations.shape_gate"):
        Adaptations(shape_gate=1.0)


def test_shape_similarity_is_boosttracks():
    a = np.array([[0.0, 0.0, 20.0, 60.0]])
    b = np.array([[5.0, 5.0, 30.0, 90.0], [0.0, 0.0, 20.0, 60.0]])
    # |20 - 30| / 30 + |60 - 90| / 90 = 1/3 + 1/3
    assert np.allclose(shape_similarity(a, b), [[np.exp(-2 / 3), 1.0]])


def test_a_box_another_person_fits_is_not_taken_across_a_size_jump():
    # person 0: one node 20x60; person 1: two nodes, 30x90 and 22x66; one 30x90 box
    pred = np.array([[50.0, 30.0, 20.0, 60.0], [60.0, 20.0, 30.0, 90.0], [0.0, 0.0, 22.0, 66.0]])
    owners = np.array([0, 1, 1])
    dets = np.array([[55.0, 20.0, 30.0, 90.0]])
    delta = np.array([[0.4], [0.8], [0.0]])
    gate = ShapeGate(0.7)  # S(20x60, 30x90) = exp(-2/3) = 0.51
    seen = np.array([True, True, False])  # person 1's second node is a hypothesis
    assert gate.admissible(pred, dets, owners, delta, seen).tolist() == [[False], [True], [True]]
    # nobody else meets the box: a size jump of a lone person is still admissible
    alone = np.array([[0.4], [0.0], [0.0]])
    assert gate.admissible(pred, dets, owners, alone, seen).tolist() == [[True], [True], [True]]
    # only a hypothesis explains it: admissible too
    hyp = np.array([True, False, True])
    assert gate.admissible(pred, dets, owners, delta, hyp).tolist() == [[True], [True], [True]]
    assert AnyShape().admissible(pred, dets, owners, delta, seen) is None


def _crossing(tracker, frames: int = 40):
    """A (20x60) stands at x 100; B (30x90, nearer the camera, the same colours) walks left
    3 px a frame, but until frame 12 the detector gives a 20x90 box 20 px right of B's left
    edge (a box drifting with B's shadow: its track learns that place and size); from frame
    12 on B's whole box, which
    covers A, whom the detector then misses until B has passed (ECP frame 105, where gt 3's
    box took gt 1's id). Returns per frame {id: 'A' | 'B'} of the
    confirmed boxes at IoU >= 0.5 with A's or B's box."""
    a = [100.0, 40.0, 20.0, 60.0]
    seen = []
    for t in range(frames):
        b = [140.0 - 3.0 * t, 25.0, 30.0, 90.0]
        part = [b[0] + 20.0, b[1], 20.0, b[3]]
        hidden = b[0] < a[0] + a[2] and a[0] < b[0] + b[2] and t >= 12
        dets = ([] if hidden else [a]) + [part if t < 12 else b]
        out = tracker.update(_frame([a, b], [RED, RED]), detections(dets), None)
        on = {}
        for o in out:
            if o.state == TrackState.CONFIRMED:
                for name, box in (("A", a), ("B", b)):
                    if iou_matrix(np.array([o.box]), np.array([box]))[0, 0] >= 0.5:
                        on[o.id] = name
        seen.append(on)
    return seen


def _people_of(seen):
    ids: dict[int, set] = {}
    for on in seen:
        for i, name in on.items():
            ids.setdefault(i, set()).add(name)
    return ids


def test_shape_gate_keeps_a_hidden_persons_id_off_the_box_in_front():
    paper = _people_of(_crossing(RetaTracker()))
    gated = _people_of(_crossing(RetaTracker(adaptations=Adaptations(shape_gate=0.6))))
    assert any(len(v) > 1 for v in paper.values())  # an id handed from A to B's box
    assert all(len(v) == 1 for v in gated.values())
