"""The compiled eq. 1 (``_kernels.ellipse_histograms``, through
``EllipseHistogrammer.measure``) against the plain-numpy reading of it, bit for bit: the
ellipse of each snapped box, its foreground pixels when they are at least
``min_foreground`` of it, every ``stride``-th row and column, counts / |S|."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer, snap_boxes
from occbench.trackers.three_hypothesis.features import bin_image, ellipse_histograms


def _reference(frame, boxes, fg, bins, min_foreground, stride):
    """Eq. 1 per box in numpy (the histogrammer's rule for S), and the occupied bins."""
    H, W = frame.shape[:2]
    idx = bin_image(frame, bins)
    out = np.zeros((len(boxes), bins**3))
    for k, (x, y, w, h) in enumerate(snap_boxes(boxes).astype(int).tolist()):
        r0, r1, c0, c1 = max(y, 0), min(y + h, H), max(x, 0), min(x + w, W)
        if r1 <= r0 or c1 <= c0:
            continue
        rx, ry = max(w / 2, 0.5), max(h / 2, 0.5)
        xs = (np.arange(w) + 0.5 - w / 2) / rx
        ys = (np.arange(h) + 0.5 - h / 2) / ry
        m = (ys[:, None] ** 2 + xs[None, :] ** 2 <= 1.0)[r0 - y:r1 - y, c0 - x:c1 - x]
        if fg is not None:
            fm = m & (fg[r0:r1, c0:c1] != 0)
            if np.count_nonzero(fm) >= min_foreground * np.count_nonzero(m):
                m = fm
        m = m[::stride, ::stride]
        total = np.count_nonzero(m)
        if total:
            counts = np.bincount(idx[r0:r1:stride, c0:c1:stride][m], minlength=bins**3)
            nz = counts.nonzero()[0]
            out[k, nz] = counts[nz] / float(total)
    return out, (out > 0).any(axis=0).nonzero()[0]


def _boxes(rng, n):
    b = np.column_stack([rng.uniform(-30, 100, n), rng.uniform(-30, 80, n),
                         rng.uniform(0.2, 60, n), rng.uniform(0.2, 70, n)])
    b[0] = [10.5, 20.5, 7.5, 9.5]  # halves: rounding ties
    b[1] = [200.0, 10.0, 5.0, 5.0]  # outside the image
    b[2] = [-5.0, -5.0, 200.0, 200.0]  # holds the image
    return b


@pytest.mark.parametrize("stride", [1, 2, 3])
@pytest.mark.parametrize("bins", [16, 4])
def test_eq1_kernel_equals_the_numpy_reading(stride, bins):
    rng = np.random.default_rng(stride * 10 + bins)
    frame = rng.integers(0, 256, (90, 120, 3), dtype=np.uint8)
    boxes = _boxes(rng, 40)
    labels = (rng.random((90, 120)) < 0.5) * rng.integers(1, 5, (90, 120))  # a label image
    for fg in (None, labels != 0, labels.astype(np.int32), np.zeros((90, 120), bool)):
        hist = EllipseHistogrammer(bins=bins, min_foreground=0.3, stride=stride)
        p, support = hist.measure(frame, boxes, fg)
        ref, ref_support = _reference(frame, boxes, fg, bins, 0.3, stride)
        assert np.array([h.dense() for h in p]).tobytes() == ref.tobytes()
        assert support.tolist() == ref_support.tolist()
        for h, row in zip(p, ref):  # each p as its own nonzero bins, in order
            assert h.bins.tolist() == np.flatnonzero(row).tolist() and h.size == bins**3
            assert h.values.tobytes() == row[h.bins].tobytes()


def test_eq1_kernel_equals_the_definition_and_takes_no_boxes():
    rng = np.random.default_rng(5)
    frame = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    boxes = snap_boxes(_boxes(rng, 20))
    fg = rng.random((60, 80)) < 0.7
    got = EllipseHistogrammer(min_foreground=0.0)(frame, boxes, fg)
    np.testing.assert_array_equal(got, ellipse_histograms(frame, boxes, mask=fg))
    p, support = EllipseHistogrammer().measure(frame, np.zeros((0, 4)))
    assert p == [] and len(support) == 0


def test_eq5_kernel_has_the_bits_of_the_definition():
    from occbench.trackers.three_hypothesis.features import region_similarity
    from occbench.trackers.three_hypothesis.occlusion import region_overlaps

    rng = np.random.default_rng(9)
    for k in range(40):
        n, m = rng.integers(0, 10, 2)
        a = np.column_stack([rng.uniform(-20, 120, (n, 2)), rng.uniform(0.5, 70, (n, 2))])
        b = np.column_stack([rng.uniform(-20, 120, (m, 2)), rng.uniform(0.5, 70, (m, 2))])
        if n and m:
            b[0] = a[0]  # a tie: the same region twice
        if n > 1:
            a[1, 2] = 0.0  # a degenerate region
        got = region_overlaps(a, b, (12, 24)[k % 2])
        assert got.tobytes() == region_similarity(a, b, samples=(12, 24)[k % 2]).tobytes()


def test_blend_over_the_occupied_bins_has_the_bits_of_the_dense_numpy_expression():
    """``appearance.towards`` (``_kernels.blend`` over the bins q or p occupies) against
    numpy's dense ``(1.0 - v) * q + v * p``, bit for bit once made dense: random sparse and
    dense histograms, empty ones, disjoint and equal supports, ties (q = p), a q holding -0
    (its product is +0 in both), one bin, v from 1e-9 to 1."""
    from occbench.trackers.three_hypothesis.appearance import Histogram, towards

    rng = np.random.default_rng(12)

    def sparse(n, k):
        h = np.zeros(n)
        h[rng.choice(n, k, replace=False)] = rng.random(k)
        return h / h.sum() if k else h

    n = 4096
    cases = [(sparse(n, rng.integers(0, 52)), sparse(n, rng.integers(1, 30)))
             for _ in range(40)]
    q = sparse(n, 16)
    disjoint = np.where(q > 0, 0.0, sparse(n, 20))
    dense = rng.random(7)
    dense[:2] = 0.0
    cases += [(np.zeros(n), np.zeros(n)), (np.zeros(n), sparse(n, 7)), (q, np.zeros(n)),
              (q, disjoint), (q, q.copy()), (-np.zeros(n), sparse(n, 5)),
              (np.zeros(1), np.ones(1)), (dense, rng.random(7)), (rng.random(7), dense)]
    for q, p in cases:
        for v in (1e-9, 0.25, 0.5, 1.0, float(rng.random())):
            want = (1.0 - v) * q + v * p
            got = towards(Histogram.of(q), Histogram.of(p), v)
            assert got.dense().tobytes() == want.tobytes()
            assert (np.diff(got.bins) > 0).all()  # sorted, distinct
            assert got.bins.tolist() == np.flatnonzero((q != 0) | (p != 0)).tolist()


def test_eq3_kernel_gives_the_verdicts_of_depth_order():
    from occbench.trackers.three_hypothesis._kernels import depth_orders
    from occbench.trackers.three_hypothesis.occlusion import depth_order

    rng = np.random.default_rng(3)
    for n in (0, 1, 2, 9):
        pred = np.column_stack([rng.uniform(0, 100, (n, 2)), rng.uniform(0, 60, (n, 2))])
        shapes = pred + rng.normal(0, 5, pred.shape) * (rng.random((n, 1)) < 0.7)
        if n > 2:
            pred[2, 3] = 0.0  # a flat region: ry = 0
            shapes[0, 1::2] = [10.0, 20.0]  # a tie: i's centre row 20 halves j's ellipse
            pred[1] = [30.0, 16.0, 8.0, 8.0]  # exactly (up = down = 8 pi)
        visible = rng.random(n) < 0.6
        if n > 1:
            visible[:2] = True
        pairs = np.array([(a, b) for a in range(n) for b in range(n) if a != b],
                         dtype=np.int64).reshape(-1, 2)
        got = np.full(len(pairs), 7, dtype=np.int64)
        depth_orders(pairs, visible, shapes, pred, got)
        want = [depth_order(bool(visible[a]), bool(visible[b]),
                            shapes[a] if visible[a] else pred[a], pred[b], 0)
                for a, b in pairs.tolist()]
        assert got.tolist() == want
        if n > 2:
            assert 0 in want[:1]  # the tie is undecided


def test_stage1_kernel_has_the_bits_of_the_numpy_stage1():
    """``association._stage1_compiled`` (``_kernels.stage1_costs``) against ``_stage1`` over
    ``_Pairs.of`` (the numpy definition), bit for bit: the person costs, the best nodes and
    the rows, with the evidence None / ``absolute_appearance`` / ``appearance_margin``, one
    threshold or one per person, admissible pairs or all; random frames with persons of one
    to three nodes, ties (rho and delta on a coarse grid), no meeting pairs, one person, one
    measurement, isolated pairs (no Hungarian step) and competing ones."""
    from occbench.trackers.three_hypothesis import association as a

    rng = np.random.default_rng(38)
    cases = []
    for trial in range(120):
        P, D = int(rng.integers(1, 9)), int(rng.integers(1, 9))
        nodes = rng.integers(1, 4, P) if trial % 3 else np.ones(P, dtype=int)
        owners = np.repeat(np.arange(P), nodes)
        grid = trial % 2 == 0  # values on a grid of tenths: ties everywhere
        rho = rng.integers(0, 11, (P, D)) / 10 if grid else rng.random((P, D))
        delta = rng.integers(0, 11, (len(owners), D)) / 10 if grid else rng.random((len(owners), D))
        delta[rng.random(delta.shape) < 0.5] = 0.0  # most pairs do not meet
        if trial % 7 == 0:
            delta[:] = 0.0
        if trial % 5 == 0:  # isolated pairs: one meeting pair per person at most
            delta[:] = 0.0
            for i in range(min(P, D)):
                delta[np.flatnonzero(owners == i)[0], i] = 0.5
        mu = float(rng.choice([0.0, 0.3, 0.5])) if trial % 4 else rng.random(P) * 0.6
        admissible = rng.random(delta.shape) < 0.8 if trial % 6 == 1 else None
        cases.append((owners, rho, delta, mu, admissible))
    boxes = np.zeros((0, 4))
    for owners, rho, delta, mu, admissible in cases:
        for evidence in (None, a.absolute_appearance, a.appearance_margin):
            pairs = a._Pairs.of(boxes, owners, rho, boxes, mu, admissible)
            want, want_best = a._stage1(pairs, delta, evidence)
            got, got_best, made = a._stage1_compiled(boxes, owners, rho.copy(), boxes, mu,
                                                     admissible, delta, evidence)
            assert made is None  # compiled, not by _stage1
            assert got.tobytes() == want.astype(np.int64).tobytes()
            assert (got_best is None) == (want_best is None)
            if want_best is not None:
                assert got_best.tolist() == want_best.tolist()


def test_stage1_kernel_costs_equal_the_numpy_costs():
    """The kernel's (P, D) person costs themselves, bit for bit, against ``_person_costs`` of
    the numpy stage 1's matrix plus ``appearance_margin``'s term; a margin the kernel
    dropped (cost = rho + 0) or a cost with rho and delta swapped would fail."""
    from occbench.trackers.three_hypothesis import association as a
    from occbench.trackers.three_hypothesis._kernels import stage1_costs

    rng = np.random.default_rng(5)
    for trial in range(60):
        P, D = int(rng.integers(1, 7)), int(rng.integers(1, 7))
        owners = np.repeat(np.arange(P), rng.integers(1, 3, P))
        rho = rng.random((P, D))
        delta = rng.random((len(owners), D)) * (rng.random((len(owners), D)) < 0.6)
        starts = np.searchsorted(owners, np.arange(P))
        for margin in (False, True):
            ok = rho[owners] >= 0.2
            c1 = np.where((delta > 0) & ok, (1.0 - rho[owners]) + (1.0 - delta), np.inf)
            want = np.minimum.reduceat(c1, starts, axis=0)
            if margin:
                want = want + (rho - a.appearance_margin(rho, np.isfinite(want)))
            cost, best = np.empty((P, D)), np.empty((P, D), np.int64)
            stage1_costs(rho, owners, starts, np.full(P, 0.2), np.zeros((1, 1), bool), False,
                         delta, margin, cost, best, np.empty((min(P, D), 2), np.int64))
            assert cost.tobytes() == want.tobytes()
