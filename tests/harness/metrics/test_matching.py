"""The fast per-frame matching equals its plain definitions on random scenes with empty
frames (no gt, no results, neither), equal IoUs (duplicated boxes on a pixel grid) and ids
that appear and vanish: the sparse IoU of ``pair_frames`` (a compiled kernel) against
``occbench.trackers.geometry.iou_matrix`` frame by frame, CLEAR's matching against its per-frame loop
(TrackEval's ``CLEAR.eval_sequence``), the identity counts against TrackEval's dense
assignment, HOTA against TrackEval's loops, and the paper metrics' matching, responses and
under-segmentation against their loops (``tests/metric_references.py``)."""

from __future__ import annotations

import numpy as np
import pytest
from metric_references import (
    reference_hota,
    reference_match_rows,
    reference_responses,
    reference_under,
)
from mot_tables import table
from scipy.optimize import linear_sum_assignment

from occbench.io.mot import MotTable
from occbench.metrics import score_sequence
from occbench.metrics.clear import ML_BELOW, MT_ABOVE, ClearCounts, clear_counts
from occbench.metrics.frames import FramePairs, pair_frames, scored_gt_mask
from occbench.metrics.hota import hota_counts
from occbench.metrics.identity import identity_counts, max_weight_matching
from occbench.metrics.paper import paper_counts, responses
from occbench.metrics.rows import row_matching
from occbench.trackers.geometry import iou_matrix

EPS = np.finfo(float).eps


def random_tables(rng: np.random.Generator, frames: int = 40, people: int = 8
                  ) -> tuple[MotTable, MotTable]:
    """gt and result tables on a 4-pixel grid (many equal IoUs), with twin people on one
    box, frames without gt, without results or without either, switching result ids."""
    gt_rows, res_rows = [], []
    pos = rng.integers(0, 40, (people, 2)) * 4.0
    for f in range(1, frames + 1):
        pos += rng.integers(-1, 2, pos.shape) * 4.0
        kind = rng.random()
        here = np.flatnonzero(rng.random(people) > 0.3)  # ids appear and vanish
        if kind > 0.1:  # else: no gt in this frame
            for i in here:
                gt_rows.append((f, i + 1, *pos[i], 20, 40))
            if rng.random() < 0.3 and len(here):  # a twin on the same box
                gt_rows.append((f, people + 1, *pos[here[0]], 20, 40))
        if 0.05 < kind < 0.9:  # else: no results in this frame
            for i in here[rng.random(len(here)) > 0.2]:
                jitter = rng.integers(-1, 2, 2) * 4.0
                res_rows.append((f, 100 + i + 20 * rng.integers(0, 2), *(pos[i] + jitter), 20, 40))
            for j in range(rng.integers(0, 3)):  # false boxes, sometimes exact copies
                res_rows.append((f, 200 + j, *rng.integers(0, 40, 2) * 4.0, 20, 40))
    res = [r for k, r in enumerate(res_rows)
           if not any(r[0] == q[0] and r[1] == q[1] for q in res_rows[:k])]  # unique ids
    return table(gt_rows), table(res)


def reference_pairs(gt: MotTable, res: MotTable) -> FramePairs:
    """The per-frame dense definition: scored gt x all results, ``iou_matrix`` per frame."""
    scored = scored_gt_mask(gt)
    g_index, r_index = gt.frame_index(), res.frame_index()
    frames = sorted(set(g_index) | set(r_index))
    empty = np.zeros(0, np.int64)
    g = [g_index.get(f, empty)[scored[g_index.get(f, empty)]] for f in frames]
    r = [r_index.get(f, empty) for f in frames]
    return FramePairs.from_dense([gt.ids[x] for x in g], [res.ids[x] for x in r],
                                 [iou_matrix(gt.boxes[a], res.boxes[b]) for a, b in zip(g, r)])


def reference_clear(pairs: FramePairs, iou_threshold: float = 0.5) -> ClearCounts:
    """TrackEval's CLEAR, frame by frame: continuing pairs (+1000), then the largest IoU."""
    c = ClearCounts()
    ids = np.unique(pairs.gt_ids)
    n = len(ids)
    annotated, matched, stretches = np.zeros(n), np.zeros(n), np.zeros(n)
    last_id, prev_id = np.full(n, np.nan), np.full(n, np.nan)
    for g_ids, t_ids, iou in pairs:
        c.objects += len(g_ids)
        c.predictions += len(t_ids)
        if len(g_ids) == 0:
            c.false_positives += len(t_ids)
            continue
        g = np.searchsorted(ids, g_ids)
        annotated[g] += 1
        if len(t_ids) == 0:
            c.misses += len(g_ids)
            continue
        score = 1000.0 * (t_ids[None, :] == prev_id[g][:, None]) + iou
        score[iou < iou_threshold - EPS] = 0.0
        rows, cols = linear_sum_assignment(-score)
        keep = score[rows, cols] > EPS
        rows, cols = rows[keep], cols[keep]
        gm, tm = g[rows], t_ids[cols].astype(float)
        switch = ~np.isnan(last_id[gm]) & (tm != last_id[gm])
        was_tracked = ~np.isnan(prev_id)
        last_id[gm] = tm
        prev_id[:] = np.nan
        prev_id[gm] = tm
        stretches += ~was_tracked & ~np.isnan(prev_id)
        matched[gm] += 1
        c.switches += int(switch.sum())
        c.matches += int(len(rows) - switch.sum())
        c.misses += len(g_ids) - len(rows)
        c.false_positives += len(t_ids) - len(rows)
        c.iou_sum += float(iou[rows, cols].sum())
    ratio = matched / np.maximum(1.0, annotated)
    c.unique_objects = n
    c.mostly_tracked = int(np.sum(ratio > MT_ABOVE))
    c.partially_tracked = int(np.sum(ratio >= ML_BELOW)) - c.mostly_tracked
    c.mostly_lost = n - c.mostly_tracked - c.partially_tracked
    c.fragmentations = int(np.sum(stretches[stretches > 0] - 1))
    return c


def reference_identity(pairs: FramePairs, iou_threshold: float = 0.5) -> tuple[int, int, int]:
    """TrackEval's ``Identity.eval_sequence``: one (G + T) x (G + T) Hungarian step."""
    if len(pairs.tracker_ids) == 0 or len(pairs.gt_ids) == 0:
        return 0, len(pairs.tracker_ids), len(pairs.gt_ids)
    gu, tu = np.unique(pairs.gt_ids), np.unique(pairs.tracker_ids)
    ng, nt = len(gu), len(tu)
    pot = np.zeros((ng, nt))
    for g_ids, t_ids, iou in pairs:
        gi, ti = np.nonzero(iou >= iou_threshold)
        pot[np.searchsorted(gu, g_ids[gi]), np.searchsorted(tu, t_ids[ti])] += 1
    gc = np.bincount(np.searchsorted(gu, pairs.gt_ids), minlength=ng).astype(float)
    tc = np.bincount(np.searchsorted(tu, pairs.tracker_ids), minlength=nt).astype(float)
    fp, fn = np.zeros((ng + nt, ng + nt)), np.zeros((ng + nt, ng + nt))
    fp[ng:, :nt] = 1e10
    fn[:ng, nt:] = 1e10
    fn[:ng, :nt] = gc[:, None]
    fn[np.arange(ng), nt + np.arange(ng)] = gc
    fp[:ng, :nt] = tc[None, :]
    fp[ng + np.arange(nt), np.arange(nt)] = tc
    fn[:ng, :nt] -= pot
    fp[:ng, :nt] -= pot
    rows, cols = linear_sum_assignment(fn + fp)
    idfn, idfp = int(fn[rows, cols].sum()), int(fp[rows, cols].sum())
    return len(pairs.gt_ids) - idfn, idfp, idfn


@pytest.mark.parametrize("seed", range(8))
def test_sparse_pairs_equal_the_dense_iou_of_every_frame(seed):
    gt, res = random_tables(np.random.default_rng(seed))
    got, ref = pair_frames(gt, res), reference_pairs(gt, res)
    for name in ("gt_ids", "tracker_ids", "gt_start", "tracker_start", "row", "col",
                 "entry_start"):
        np.testing.assert_array_equal(getattr(got, name), getattr(ref, name), err_msg=name)
    assert got.iou.tobytes() == ref.iou.tobytes()  # bit for bit
    for k in range(len(got)):
        assert all(np.array_equal(a, b) for a, b in zip(got.frame(k), ref.frame(k)))


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("threshold", [0.5, 0.3])
def test_clear_and_identity_equal_trackeval_definitions(seed, threshold):
    pairs = pair_frames(*random_tables(np.random.default_rng(seed)))
    got, ref = clear_counts(pairs, threshold), reference_clear(pairs, threshold)
    ref.idtp, ref.idfp, ref.idfn = reference_identity(pairs, threshold)
    ref.frames = len(pairs)
    assert got == ref
    assert got.switches > 0 and got.fragmentations > 0  # a scene that exercises them


@pytest.mark.parametrize("seed", range(8))
def test_hota_equals_trackeval_loops_with_ties_and_empty_frames(seed):
    pairs = pair_frames(*random_tables(np.random.default_rng(seed)))
    dense = [pairs.frame(k) for k in range(len(pairs))]
    got = hota_counts(pairs)
    ref = reference_hota(*map(list, zip(*dense)))
    for name in ("tp", "fn", "fp", "loc_a"):  # the same matches, ties broken alike; LocA
        # summed in TrackEval's order, bit for bit
        assert getattr(got, name).tobytes() == getattr(ref, name).tobytes(), name
    for name in ("ass_a", "ass_re", "ass_pr"):  # sums over pairs in another order
        np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-13,
                                   err_msg=name)


def test_empty_sides_score_like_trackeval():
    gt, res = random_tables(np.random.default_rng(0))
    for g, r in ((gt, MotTable.empty()), (MotTable.empty(), res),
                 (MotTable.empty(), MotTable.empty())):
        pairs = pair_frames(g, r)
        c = clear_counts(pairs)
        assert (c.idtp, c.idfp, c.idfn) == reference_identity(pairs) == (0, len(r), len(g))
        ref = reference_clear(pairs)
        ref.frames, ref.idfp, ref.idfn = len(pairs), len(r), len(g)
        assert c == ref
        s = score_sequence(g, r)
        assert s.clear.misses == len(g) and s.clear.false_positives == len(r)


def test_max_weight_matching_finds_the_optimum_across_components():
    # component 1: g1-t1 (3), g1-t2 (2), g2-t1 (2): best is g1-t2 + g2-t1 = 4 > 3
    # component 2: g3-t3 (1) alone
    g, t, w = np.array([1, 1, 2, 3]), np.array([1, 2, 1, 3]), np.array([3, 2, 2, 1])
    assert max_weight_matching(g, t, w).tolist() == [1, 2, 3]
    assert identity_counts(pair_frames(MotTable.empty(), MotTable.empty())) == (0, 0, 0)


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("threshold", [0.5, 0.3])
def test_paper_matching_responses_and_under_equal_their_loops(seed, threshold):
    gt, res = random_tables(np.random.default_rng(seed))
    m = row_matching(gt, res, threshold)
    assert np.array_equal(m.match, reference_match_rows(m.gt, res, threshold))
    for got, ref in zip(responses(m), reference_responses(m.gt, res, m.match)):
        assert np.array_equal(got, ref)
    assert paper_counts(gt, res, threshold).under == reference_under(m.gt, res, m.match)


def test_under_segmented_when_the_first_id_served_another_person_before():
    # id 7 follows person 1 (frames 1-2), then person 2 starts with it (frame 3)
    gt = table([(1, 1, 0, 0, 10, 10), (2, 1, 0, 0, 10, 10), (3, 2, 50, 0, 10, 10)])
    res = table([(1, 7, 0, 0, 10, 10), (2, 7, 0, 0, 10, 10), (3, 7, 50, 0, 10, 10)])
    assert paper_counts(gt, res).under == 1
    assert paper_counts(gt, res.rows(np.array([2]))).under == 0
