"""Shared vocabulary: geometry, histograms, assignment, MOT I/O, records."""

import itertools

import numpy as np
import pytest

from occbench.io.mot import MotFormatError, read_mot
from occbench.io.write import write_mot
from occbench.trackers.common.assignment import assign, assign_min_cost
from occbench.trackers.geometry import (
    box_ellipses,
    centre_distance_matrix,
    ellipse_boxes,
    ellipse_mask,
    iou_matrix,
    overlap_ratio_matrix,
    valid_boxes,
)
from occbench.trackers.histograms import bhattacharyya, colour_histogram, masked_histogram
from occbench.trackers.records import Detections, TrackState


def test_iou_hand_cases():
    a = np.array([[0, 0, 10, 10]])
    b = np.array([[0, 0, 10, 10], [5, 0, 10, 10], [20, 20, 5, 5], [0, 0, 10, 5]])
    np.testing.assert_allclose(iou_matrix(a, b), [[1.0, 50 / 150, 0.0, 0.5]])
    np.testing.assert_allclose(overlap_ratio_matrix(b[3:], a), [[1.0]])
    assert iou_matrix(np.zeros((0, 4)), b).shape == (0, 4)


def test_centre_distance_and_validity():
    d = centre_distance_matrix([[0, 0, 2, 2]], [[3, 4, 2, 2]])
    assert d[0, 0] == pytest.approx(5.0)
    assert valid_boxes([[0, 0, 1, 1], [0, 0, 0, 1], [np.nan, 0, 1, 1]]).tolist() == [True, False, False]


def test_ellipse_round_trip_and_mask_area():
    box = np.array([[10, 20, 40, 80]])
    e = box_ellipses(box)
    np.testing.assert_allclose(e, [[30, 60, 0, 20, 40]])
    np.testing.assert_allclose(ellipse_boxes(e), box)
    m = ellipse_mask(e[0], (200, 200))
    assert abs(m.sum() - np.pi * 20 * 40) / (np.pi * 800) < 0.02
    rows, cols = np.nonzero(m)
    assert rows.min() >= 20 and rows.max() < 100 and cols.min() >= 10 and cols.max() < 50


def test_histogram_known_bin_and_bhattacharyya():
    pixels = np.array([[0, 0, 0], [255, 255, 255], [17, 33, 200]], dtype=np.uint8)
    h = colour_histogram(pixels)
    assert h.sum() == pytest.approx(1.0)
    assert h[0] == pytest.approx(1 / 3) and h[4095] == pytest.approx(1 / 3)
    assert h[(1 * 16 + 2) * 16 + 12] == pytest.approx(1 / 3)
    assert bhattacharyya(h, h) == pytest.approx(1.0)
    other = colour_histogram(np.array([[100, 100, 100]], dtype=np.uint8))
    assert bhattacharyya(h, other) == 0.0
    img = np.zeros((4, 4, 3), np.uint8)
    img[:2] = 255
    mask = np.zeros((4, 4), bool)
    mask[:2, :2] = True
    assert masked_histogram(img, mask)[4095] == 1.0
    assert bhattacharyya(np.stack([h, other]), np.stack([h])).shape == (2, 1)


def test_assign_respects_gate():
    cost = np.array([[0.1, 0.9], [0.2, 0.3]])
    m, r, c = assign(cost, 0.5)
    assert sorted(map(tuple, m)) == [(0, 0), (1, 1)]
    m, r, c = assign(np.array([[0.1, np.inf], [0.05, 0.9]]), 0.5)
    assert m.tolist() == [[1, 0]] or m.tolist() == [[0, 0]]
    assert len(r) == 1 and len(c) == 1


def test_mot_round_trip_is_byte_stable(tmp_path):
    boxes = np.array([[0.0, 1.5, 10, 20], [5, 5, 3, 4]])
    write_mot(tmp_path / "a.txt", [2, 1], [7, 3], boxes)
    t = read_mot(tmp_path / "a.txt")
    assert t.frames.tolist() == [1, 2] and t.ids.tolist() == [3, 7]
    np.testing.assert_allclose(t.boxes, boxes[::-1])
    write_mot(tmp_path / "b.txt", t.frames, t.ids, t.boxes, t.conf)
    assert (tmp_path / "a.txt").read_bytes() == (tmp_path / "b.txt").read_bytes()
    assert (tmp_path / "a.txt").read_text().startswith("1,3,6.00,6.00,3.00,4.00")


def test_mot_errors_name_file_and_line(tmp_path, caplog):
    p = tmp_path / "gt.txt"
    p.write_text("1,1,1,1,5,5,1,1,1\n2,1,x,1,5,5,1,1,1\n")
    with pytest.raises(MotFormatError, match=r"gt.txt:2"):
        read_mot(p, gt=True)
    p.write_text("1,1,1,1,5,5,1,1,1\n2,1,1,1,nan,5,1,1,1\n3,1,1,1,0,5,1,1,1\n")
    assert len(read_mot(p, gt=True)) == 1
    assert "gt.txt:2" in caplog.text and "gt.txt:3" in caplog.text
    with pytest.raises(FileNotFoundError, match="missing.txt"):
        read_mot(tmp_path / "missing.txt")
    p.write_text("")
    assert len(read_mot(p)) == 0


def test_detections_subset_renumbers_labels():
    labels = np.array([[0, 1, 2, 3]], dtype=np.int32)
    d = Detections(np.arange(12).reshape(3, 4), [0.1, 0.5, 0.9], labels=labels)
    s = d.subset(d.scores > 0.3)
    assert len(s) == 2 and s.labels.tolist() == [[0, 0, 1, 2]]
    with pytest.raises(ValueError, match="scores"):
        Detections(np.zeros((2, 4)), [1.0])
    assert TrackState.OCCLUDED.reported and not TrackState.HYPOTHESIS.reported


def test_assign_without_a_gate_skips_forbidden_pairs():
    cost = np.array([[0.2, np.inf], [np.inf, np.nan], [5.0, 0.1]])
    matches, rows, cols = assign(cost, np.inf)  # used to fail: "cost matrix is infeasible"
    assert matches.tolist() == [[0, 0], [2, 1]] and rows.tolist() == [1] and cols.tolist() == []


def test_assign_min_cost_leaves_a_row_over_rather_than_trade_a_good_pair_for_two_poor_ones():
    """Target 0 holds candidate 0 (cost 0.4); target 1, unfound, could take it (0.7) if
    target 0 moved to a poor candidate 1 (0.74). ``assign`` keeps the most pairs (the
    exchange: 1.44), ``assign_min_cost`` the cheaper total with target 1 left over
    (0.4 + 0.75)."""
    cost = np.array([[0.4, 0.74], [0.7, np.inf]])
    assert assign(cost, 0.75)[0].tolist() == [[0, 1], [1, 0]]
    matches, rows, cols = assign_min_cost(cost, 0.75)
    assert matches.tolist() == [[0, 0]] and rows.tolist() == [1] and cols.tolist() == [1]
    with pytest.raises(ValueError, match="max_cost"):
        assign_min_cost(cost, np.inf)


def test_assign_min_cost_equals_the_exhaustive_minimum():
    """Over small random matrices, the total (pairs plus max_cost per row left over) equals
    the minimum over every one-to-one partial assignment of allowed pairs."""
    rng = np.random.default_rng(3)
    for _ in range(150):
        n, m = rng.integers(1, 5, 2)
        cost = np.where(rng.random((n, m)) < 0.7, rng.uniform(0, 1, (n, m)), np.inf)
        matches, rows, cols = assign_min_cost(cost, 0.75)
        total = sum(cost[i, j] for i, j in matches) + 0.75 * len(rows)
        assert (cost[matches[:, 0], matches[:, 1]] <= 0.75).all()
        assert len(rows) + len(matches) == n and len(cols) + len(matches) == m
        best = min(sum(cost[i, j] if j >= 0 else 0.75 for i, j in enumerate(p))
                   for p in itertools.product(range(-1, m), repeat=n)
                   if len({j for j in p if j >= 0}) == sum(j >= 0 for j in p)
                   and all(j < 0 or cost[i, j] <= 0.75 for i, j in enumerate(p)))
        assert total == pytest.approx(best)
