"""The compiled shares (``_shares``) against per-row definitions, bit for bit: step 6's own
shares with their partners (``contact.own_shares``), step 8's hidden shares
(``steps_hypotheses._hidden_share``'s continued hypotheses), the measurements another
person's region meets (``tentative.clear_measurements``) and the share of a region the
visible people cover (``occlusion.covered_fraction``)."""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_array

from occbench.trackers.three_hypothesis import _shares
from occbench.trackers.three_hypothesis.contact import own_shares
from occbench.trackers.three_hypothesis.occlusion import (boxes_meet, covered_fraction,
                                                          region_overlaps)
from occbench.trackers.three_hypothesis.values import Match


def _frame(rng: np.random.Generator) -> tuple:
    """A random frame's nodes, measurements and sparse delta (values from a few, for ties)."""
    nodes, dets, people = rng.integers(2, 12), rng.integers(1, 6), rng.integers(2, 8)
    owners = np.sort(rng.integers(0, people, nodes))
    pred = rng.choice([4.0, 8.0, 12.5], (nodes, 4))  # few areas: equal covers happen
    boxes = rng.choice([4.0, 8.0, 12.5], (dets, 4))
    dense = np.where(rng.random((nodes, dets)) < 0.5, rng.choice([0.25, 0.5, 0.7], (nodes, dets)),
                     0.0)
    return owners, people, pred, boxes, dense


def test_own_shares_partner_is_the_last_largest_cover_in_the_pairs_order():
    """Per matched row, the partner is the person of the largest |S_m & S_d| over O's pairs
    (n, m), taken as (a, b) of every pair then (b, a), the last of a tie; rows with no
    hidden partner keep what they had. The shares equal 1 - that cover / |S_d|, clipped."""
    rng = np.random.default_rng(11)
    ties = 0
    for _ in range(200):
        owners, people, pred, boxes, dense = _frame(rng)
        pairs = rng.integers(0, len(owners), (rng.integers(0, 15), 2))
        hidden = rng.random(people) < 0.6
        matched = rng.permutation(len(owners))[: rng.integers(1, len(owners))]
        matches = [Match(det=int(rng.integers(len(boxes))), node=int(n), stage=1, rho=1.0)
                   for n in matched]
        want_own, want_partner = [], []
        for match in matches:
            area = boxes[match.det, 2] * boxes[match.det, 3]
            order = [(a, b) for a, b in pairs.tolist()] + [(b, a) for a, b in pairs.tolist()]
            inter = [(dense[m, match.det] * (pred[m, 2] * pred[m, 3] + area) / 2, owners[m])
                     for n, m in order if n == match.node and hidden[owners[m]]]
            top = max((c for c, _ in inter), default=None)
            ties += sum(c == top for c, _ in inter) > 1
            want_partner.append([o for c, o in inter if c == top][-1] if inter else -7)
            want_own.append(float(np.clip(1.0 - top / max(area, 1e-9), 0.0, 1.0))
                            if inter else 1.0)
        partners = np.full(len(matches), -7)
        got = own_shares(matches, pairs, owners, hidden, pred, boxes, csr_array(dense), partners)
        assert got.tolist() == want_own
        assert partners.tolist() == want_partner
    assert ties > 20  # the tie rule was exercised


def test_hidden_shares_equal_the_per_row_definition_bit_for_bit():
    """fraction[k] of a hypothesis continuing node src[k] (>= 0; -1 left as it is): the
    largest delta (|S_n| + |S_v|) / 2 / max(|S_n|, 1e-9) over the measurements d of the
    visible people (column[d] >= 0) whose delta with n is stored, 0 when none."""
    rng = np.random.default_rng(12)
    for _ in range(200):
        owners, _, pred, boxes, dense = _frame(rng)
        column = np.where(rng.random(len(boxes)) < 0.6, rng.permutation(len(boxes)), -1)
        area_v = rng.choice([4.0, 16.0, 0.0], len(boxes))
        src = rng.integers(-1, len(owners), rng.integers(0, 12))
        area_n = pred[:, 2] * pred[:, 3]
        area_n[rng.random(len(area_n)) < 0.1] = 0.0  # the 1e-9 floor
        want = np.full(len(src), 0.5)
        for k, n in enumerate(src.tolist()):
            if n >= 0:
                covers = [dense[n, d] * (area_n[n] + area_v[column[d]]) / 2 / max(area_n[n], 1e-9)
                          for d in np.flatnonzero(dense[n]).tolist() if column[d] >= 0]
                want[k] = max([0.0] + covers)
        delta = csr_array(dense)
        got = np.full(len(src), 0.5)
        _shares.hidden_shares(src.astype(np.int64), area_n, *_shares.csr(delta),
                              column.astype(np.int64), area_v, got)
        assert got.tolist() == want.tolist()


def test_crowded_by_others_marks_rows_another_persons_region_meets():
    """crowded[r] where some node of another person than row r's (-1: every node is
    another's) has a stored delta > 0 with row r's measurement; others untouched."""
    rng = np.random.default_rng(13)
    for _ in range(200):
        owners, people, _, boxes, dense = _frame(rng)
        rows = rng.permutation(len(boxes))[: rng.integers(1, len(boxes) + 1)]
        column = np.full(len(boxes), -1)
        column[rows] = np.arange(len(rows))
        row_owners = rng.integers(-1, people, len(rows))
        want = [any(dense[n, d] > 0 and owners[n] != row_owners[r] for n in range(len(owners)))
                for r, d in enumerate(rows.tolist())]
        delta = csr_array(dense)
        got = np.zeros(len(rows), dtype=bool)
        _shares.crowded_by_others(*_shares.csr(delta), owners.astype(np.int64), column,
                                  row_owners, got)
        assert got.tolist() == want


def test_covered_fraction_equals_the_per_pair_definition_bit_for_bit():
    """``occlusion.covered_fraction`` (``_shares.covered``): per region i, the largest
    delta (|S_i| + |S_v|) / 2 / max(|S_i|, 1e-9) over the visible regions v whose box meets
    i's (eq. 5's delta from the dense ``region_overlaps``, |S| = pi / 4 w h), 0 when none;
    with ``pairs``, over those pairs only (repeats, pairs that do not meet)."""
    rng = np.random.default_rng(14)
    for _ in range(100):
        boxes = rng.choice([0.0, 3.0, 8.0, 12.5], (rng.integers(1, 6), 4))
        visible = rng.choice([0.0, 3.0, 8.0, 12.5], (rng.integers(1, 6), 4))
        boxes[rng.random(len(boxes)) < 0.1, 2] = 0.0  # no area: it meets nothing
        delta = region_overlaps(boxes, visible, 6)
        meet = boxes_meet(boxes, visible)
        pairs = [(int(a), int(b)) for a, b in zip(rng.integers(0, len(boxes), 8),
                                                  rng.integers(0, len(visible), 8))]
        for asked in (None, pairs):
            listed = asked if asked is not None else [
                (a, b) for a in range(len(boxes)) for b in range(len(visible))]
            want = []
            for i in range(len(boxes)):
                area = np.pi / 4 * boxes[i, 2] * boxes[i, 3]
                covers = [0.5 * delta[a, b] * (area + np.pi / 4 * visible[b, 2] * visible[b, 3])
                          / max(area, 1e-9) for a, b in listed if a == i and meet[a, b]]
                want.append(max([0.0] + covers))
            got = covered_fraction(boxes, visible, 6, None if asked is None else (
                np.array([a for a, _ in pairs]), np.array([b for _, b in pairs])))
            assert got.tolist() == want
