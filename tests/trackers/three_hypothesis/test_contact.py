"""Reta's rules for people in contact (occbench.trackers.three_hypothesis.contact): a
measurement merged over two tracked people, hand-derivable cases, the paper's rule beside ours."""

from __future__ import annotations

import numpy as np

from occbench.trackers.three_hypothesis import Adaptations
from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer
from occbench.trackers.three_hypothesis.contact import (
    MeasurementAppearance,
    MergedAppearance,
    own_shares,
)
from occbench.trackers.three_hypothesis.rules import build_rules

BOX = np.array([[0.0, 0.0, 10.0, 20.0]])


def test_own_share_is_the_measured_region_no_hidden_partner_covers():
    """Person 0 matched to measurement 0 through node 0; node 1 (person 1) in O with it.
    Same sizes: delta 1 (person 1 wholly inside) leaves 0 of the region to person 0, delta
    0.5 half of it; matched, or not in O, person 1 leaves all of it."""
    pred = np.concatenate([BOX, BOX])
    owners, rows, pairs = np.array([0, 1]), [(0, 0, 0)], np.array([[0, 1]])
    hidden = np.array([False, True])
    for delta, own in ((1.0, 0.0), (0.5, 0.5), (0.0, 1.0)):
        d = np.array([[1.0], [delta]])
        assert own_shares(rows, pairs, owners, hidden, pred, BOX, d) == [own]
    d = np.array([[1.0], [1.0]])
    assert own_shares(rows, pairs, owners, np.array([False, False]), pred, BOX, d) == [1.0]
    assert own_shares(rows, np.zeros((0, 2), dtype=int), owners, hidden, pred, BOX, d) == [1.0]
    # the pair's order in O does not matter
    assert own_shares(rows, np.array([[1, 0]]), owners, hidden, pred, BOX, d) == [0.0]


def test_merged_measurement_moves_q_by_the_own_share_only():
    q, p = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    paper, ours = MeasurementAppearance(), MergedAppearance()
    assert paper.update(q, p, 0.0) is p  # the paper: q = p whoever else is inside
    assert ours.update(q, p, 1.0) is p
    assert ours.update(q, p, 0.0) is q
    assert ours.update(q, p, 0.25).tolist() == [0.75, 0.25]
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).appearance_front, MeasurementAppearance)
    assert isinstance(build_rules(Adaptations(merged_appearance=True), h).appearance_front,
                      MergedAppearance)
    assert "merged_appearance" in Adaptations(merged_appearance=True).changed()
