"""The trajectory-level metrics the two papers report, as pure functions of gt and result.

Both papers score trajectories, not frames. Everything here starts from one frame-by-frame
matching of ground-truth rows to result rows (``match_rows``), made the CLEAR MOT way
(Bernardin & Stiefelhagen 2008): a pair matched in the previous frame is kept while its
IoU stays >= the threshold, the remaining rows are matched by the Hungarian method on IoU
(pairs below the threshold are forbidden). Ground-truth rows with ``conf == 0`` (MOT16
"ignore") or a class other than pedestrian are left out (``considered_mask``).

Reta et al. 2015, Table 1 (metrics "obtained from Song et al. [22]", who took them from
Li, Huang & Nevatia, CVPR 2009), implemented word for word:

* ``GT``: number of ground-truth trajectories.
* ``MT``: percentage of GT trajectories "covered correctly by the tracking algorithm more
  than 80% of the time": matched frames / frames of the trajectory > 0.8.
* ``PT``: percentage covered "between 20% and 80% of the time" (0.2 <= coverage <= 0.8).
* ``ML``: percentage covered "less than 20% of the time" (coverage < 0.2).
* ``Frag``: "the number of times that the ID of a tracked target changed along a GT
  trajectory": walking a GT trajectory through its matched frames, each frame whose
  matched result id differs from the previous matched frame's id counts one (a gap with no
  match in between is not by itself a change).
* ``IDS``: "the number of times that a tracked target changes its ID with another target",
  read as Li et al.'s definition that Reta paraphrases: walking a *result* trajectory
  through its matched frames, each time its matched GT identity changes counts one.

PBM (Section 5.2), with each criterion made precise (the paper gives one line each):

* tracked fraction of a GT trajectory = matched frames / frames of the trajectory.
* ``MT``: number with tracked fraction > 0.8; ``MT1``: of those, the ones whose matched
  frames all carry one single result id ("a single ID assigned to the target over the
  entire trajectory"); ``ML``: tracked fraction < 0.4; ``Missed``: no matched frame.
* ``Under`` (under-segmented, "target being identified as an existing trajectory rather than
  initialized with a new ID"): the first result id matched to the trajectory had already
  been matched, in an earlier frame, to a different GT trajectory.
* ``Over`` (over-segmented, "multiple IDs assigned to a single trajectory"): more than one
  distinct result id among the matched frames.
* ``IDsw/traj`` ("ID swapping between two trajectories during their intersection"): along a
  GT trajectory, a change of matched id from p to q counts as a swap when q's most recent
  earlier match was a different GT trajectory (the id came from another person); total
  swaps / GT.
* ``IDs/traj``: mean number of distinct matched ids per GT trajectory, over the
  trajectories matched at least once (a missed trajectory has none; should be one).
* ``IDs/frame`` (multiple responses, "should be one"): the responses to a GT box in a frame
  are its matched result box plus every unmatched result box that lies at least half inside
  it (|r & g| / |r| >= 0.5; a box inside several GT boxes answers the one covering it
  most); the mean number of distinct ids among the responses, over GT rows with at least one.

PBM Tables 2-4 (segmentation accuracy), "averaged over multiple trajectories, multiple
frames and the possibly multiple responses of a tracker in each single frame": for every
(GT row, response) pair, with centroid (xc, yc) and size (w, h) of the response and
(xg, yg, wg, hg) of the GT box, the relative errors are

    dx = (xc - xg) / wg,  dy = (yc - yg) / hg,  dw = (w - wg) / wg,  dh = (h - hg) / hg

(normalised by the GT box size, so figures do not depend on image size or distance to the
camera); the tables report the mean of their absolute values in percent. The signed
minimum and maximum are also kept (PBM quotes width/height ranges beside Fig. 8).

All counts are additive over sequences: ``PaperCounts.__add__`` sums them and ``columns``
recomputes the ratios, so a COMBINED row is never an average of per-sequence ratios.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, fields

import numpy as np

from harness.io.mot import MotTable, scored_gt_mask
from harness.metrics.counts import combine_counts
from trackers.common.assignment import assign
from trackers.geometry import iou_matrix, overlap_ratio_matrix

log = logging.getLogger(__name__)

# Column names, prefixed by the paper whose table they fill (avoids clashing with CLEAR's
# MT/ML in harness.metrics.COLUMNS, which use different thresholds and matching).
RETA_COLUMNS = ["Song_GT", "Song_MT%", "Song_PT%", "Song_ML%", "Song_Frag", "Song_IDS"]
PBM_COLUMNS = [
    "PBM_GT", "PBM_MT", "PBM_MT1", "PBM_ML", "PBM_Missed", "PBM_Under", "PBM_Over",
    "PBM_IDsw/traj", "PBM_IDs/traj", "PBM_IDs/frame",
]
SEGMENTATION_COLUMNS = ["PBM_dx%", "PBM_dy%", "PBM_dw%", "PBM_dh%"]
COLUMNS = RETA_COLUMNS + PBM_COLUMNS + SEGMENTATION_COLUMNS


def considered_mask(gt: MotTable) -> np.ndarray:
    """(N,) bool: GT rows that are scored, by the MOTChallenge rules of
    ``harness.metrics.frames``: ``conf != 0`` and class pedestrian (1) or none (-1)."""
    return scored_gt_mask(gt)


def considered(gt: MotTable) -> MotTable:
    """The GT rows that are scored (see ``considered_mask``)."""
    return gt.rows(considered_mask(gt))


def match_rows(gt: MotTable, res: MotTable, iou_threshold: float = 0.5) -> np.ndarray:
    """Match GT rows to result rows frame by frame, keeping last frame's pairs (CLEAR MOT).

    Args:
        gt: ground-truth rows (all are matched; filter with ``considered`` first).
        res: result rows.
        iou_threshold: smallest IoU of a match.
    Returns:
        (len(gt),) int64 index of the matched row of ``res`` for each GT row, -1 where none.
    """
    if not 0.0 < iou_threshold <= 1.0:
        raise ValueError(f"iou_threshold must be in (0, 1], got {iou_threshold}")
    out = np.full(len(gt), -1, dtype=np.int64)
    if len(gt) == 0 or len(res) == 0:
        return out
    res_index = res.frame_index()
    previous: dict[int, int] = {}  # gt id -> result id matched in the last frame it was matched
    for frame, g_rows in gt.frame_index().items():
        r_rows = res_index.get(frame)
        if r_rows is None or len(r_rows) == 0:
            continue
        iou = iou_matrix(gt.boxes[g_rows], res.boxes[r_rows])
        iou = np.where(iou >= iou_threshold, iou, 0.0)
        g_ids, r_ids = gt.ids[g_rows], res.ids[r_rows]
        # keep last frame's correspondences that are still valid
        kept = np.zeros(len(g_rows), dtype=bool)
        taken = np.zeros(len(r_rows), dtype=bool)
        for i, gid in enumerate(g_ids):
            rid = previous.get(int(gid))
            if rid is None:
                continue
            j = np.flatnonzero((r_ids == rid) & ~taken)
            if len(j) and iou[i, j[0]] > 0:
                kept[i], taken[j[0]] = True, True
                out[g_rows[i]] = r_rows[j[0]]
        free_g, free_r = np.flatnonzero(~kept), np.flatnonzero(~taken)
        if len(free_g) and len(free_r):
            cost = 1.0 - iou[np.ix_(free_g, free_r)]
            cost[iou[np.ix_(free_g, free_r)] <= 0] = np.inf
            pairs, _, _ = assign(cost, 1.0 - iou_threshold + 1e-12)
            out[g_rows[free_g[pairs[:, 0]]]] = r_rows[free_r[pairs[:, 1]]]
        hit = out[g_rows] >= 0
        previous.update(zip(g_ids[hit].tolist(), res.ids[out[g_rows[hit]]].tolist()))
    return out


def _changes(keys: np.ndarray, order_key: np.ndarray,
             values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sort by (key, order_key); return the permutation and, per sorted element, whether it
    has the same key as the previous element but a different value."""
    order = np.lexsort((order_key, keys))
    k, v = keys[order], values[order]
    change = np.zeros(len(k), dtype=bool)
    change[1:] = (k[1:] == k[:-1]) & (v[1:] != v[:-1])
    return order, change


@dataclass
class PaperCounts:
    """Additive counts behind the paper metrics of one sequence (or a sum of sequences)."""

    gt: int = 0            # GT trajectories
    mt80: int = 0          # coverage > 0.8
    pt: int = 0            # 0.2 <= coverage <= 0.8
    ml20: int = 0          # coverage < 0.2
    frag: int = 0          # Reta/Song Frag
    ids: int = 0           # Reta/Song IDS (result trajectory changes its GT)
    mt1: int = 0           # PBM: > 0.8 and a single id
    ml40: int = 0          # PBM: coverage < 0.4
    missed: int = 0        # PBM: never matched
    under: int = 0         # PBM: under-segmented
    over: int = 0          # PBM: over-segmented
    swaps: int = 0         # PBM: id swaps
    ids_sum: int = 0       # sum of distinct ids over matched trajectories
    matched_traj: int = 0  # trajectories matched at least once
    resp_ids_sum: int = 0  # sum over GT rows of distinct response ids
    resp_rows: int = 0     # GT rows with at least one response
    n_pairs: int = 0       # (GT row, response) pairs for segmentation errors
    abs_dx: float = 0.0
    abs_dy: float = 0.0
    abs_dw: float = 0.0
    abs_dh: float = 0.0
    min_dw: float = np.inf
    max_dw: float = -np.inf
    min_dh: float = np.inf
    max_dh: float = -np.inf

    def __add__(self, other: PaperCounts) -> PaperCounts:
        out = {}
        for f in fields(self):
            a, b = getattr(self, f.name), getattr(other, f.name)
            out[f.name] = min(a, b) if f.name.startswith("min_") else (
                max(a, b) if f.name.startswith("max_") else a + b)
        return PaperCounts(**out)

    def columns(self) -> dict[str, float]:
        """Flat dict of COLUMNS (percentages as 0-100 numbers; NaN where undefined)."""

        def ratio(a: float, b: float, scale: float = 1.0) -> float:
            return float(scale * a / b) if b else float("nan")

        return {
            "Song_GT": self.gt,
            "Song_MT%": ratio(self.mt80, self.gt, 100),
            "Song_PT%": ratio(self.pt, self.gt, 100),
            "Song_ML%": ratio(self.ml20, self.gt, 100),
            "Song_Frag": self.frag,
            "Song_IDS": self.ids,
            "PBM_GT": self.gt,
            "PBM_MT": self.mt80,
            "PBM_MT1": self.mt1,
            "PBM_ML": self.ml40,
            "PBM_Missed": self.missed,
            "PBM_Under": self.under,
            "PBM_Over": self.over,
            "PBM_IDsw/traj": ratio(self.swaps, self.gt),
            "PBM_IDs/traj": ratio(self.ids_sum, self.matched_traj),
            "PBM_IDs/frame": ratio(self.resp_ids_sum, self.resp_rows),
            "PBM_dx%": ratio(self.abs_dx, self.n_pairs, 100),
            "PBM_dy%": ratio(self.abs_dy, self.n_pairs, 100),
            "PBM_dw%": ratio(self.abs_dw, self.n_pairs, 100),
            "PBM_dh%": ratio(self.abs_dh, self.n_pairs, 100),
        }


def responses(gt: MotTable, res: MotTable, match: np.ndarray,
              inside: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """All (GT row, result row) response pairs: the matched pairs plus unmatched result
    boxes lying at least ``inside`` within a GT box of the same frame (each such box answers
    the GT box covering most of it).

    Returns:
        (K,) GT row indices and (K,) result row indices, sorted by GT row then result row.
    """
    g_rows = [np.flatnonzero(match >= 0)]
    r_rows = [match[g_rows[0]]]
    used = np.zeros(len(res), dtype=bool)
    used[r_rows[0]] = True
    gt_index = gt.frame_index()
    for frame, rr in res.frame_index().items():
        rr = rr[~used[rr]]
        gr = gt_index.get(frame)
        if len(rr) == 0 or gr is None:
            continue
        cover = overlap_ratio_matrix(res.boxes[rr], gt.boxes[gr])  # |r & g| / |r|
        best = np.argmax(cover, axis=1)
        ok = cover[np.arange(len(rr)), best] >= inside
        g_rows.append(gr[best[ok]])
        r_rows.append(rr[ok])
    g, r = np.concatenate(g_rows), np.concatenate(r_rows)
    order = np.lexsort((r, g))
    return g[order], r[order]


def paper_counts(gt: MotTable, res: MotTable, iou_threshold: float = 0.5) -> PaperCounts:
    """Count everything the papers' trajectory tables need for one sequence.

    Args:
        gt: ground truth (rows with conf == 0 are ignored).
        res: tracker result rows.
        iou_threshold: smallest IoU of a match.
    """
    gt = considered(gt)
    out = PaperCounts()
    if len(gt) == 0:
        return out
    match = match_rows(gt, res, iou_threshold)
    hit = match >= 0
    gids, gframes = gt.ids, gt.frames
    mid = np.full(len(gt), -1, dtype=np.int64)
    mid[hit] = res.ids[match[hit]]

    uniq, inverse = np.unique(gids, return_inverse=True)
    n = len(uniq)
    length = np.bincount(inverse, minlength=n)
    covered = np.bincount(inverse, weights=hit, minlength=n)
    coverage = covered / length
    out.gt = n
    out.mt80 = int((coverage > 0.8).sum())
    out.ml20 = int((coverage < 0.2).sum())
    out.pt = n - out.mt80 - out.ml20
    out.ml40 = int((coverage < 0.4).sum())
    out.missed = int((covered == 0).sum())

    # matched rows only, as (gt index, frame, result id)
    m_g, m_f, m_r = inverse[hit], gframes[hit], mid[hit]
    # Frag: id changes along each GT trajectory (matched frames, in time order)
    order, change = _changes(m_g, m_f, m_r)
    out.frag = int(change.sum())
    # IDS: GT changes along each result trajectory
    _, r_change = _changes(m_r, m_f, m_g)
    out.ids = int(r_change.sum())

    # distinct ids per trajectory
    pairs = np.unique(np.column_stack([m_g, m_r]), axis=0) if len(m_g) else np.zeros((0, 2), int)
    n_ids = np.bincount(pairs[:, 0], minlength=n)
    out.mt1 = int(((coverage > 0.8) & (n_ids == 1)).sum())
    out.over = int((n_ids > 1).sum())
    out.ids_sum = int(n_ids.sum())
    out.matched_traj = int((n_ids > 0).sum())

    # swaps: along a GT trajectory an id change p -> q where q's previous match was another GT
    r_order = np.lexsort((m_f, m_r))
    prev_gt = np.full(len(m_g), -1)
    same = np.zeros(len(m_g), dtype=bool)
    same[1:] = m_r[r_order][1:] == m_r[r_order][:-1]
    shifted = np.r_[-1, m_g[r_order][:-1]]
    prev_gt[r_order] = np.where(same, shifted, -1)
    changed = np.zeros(len(m_g), dtype=bool)
    changed[order] = change
    out.swaps = int((changed & (prev_gt >= 0) & (prev_gt != m_g)).sum())

    # under-segmented: first id of a trajectory matched earlier to another trajectory
    if len(m_g):
        first = order[np.r_[True, m_g[order][1:] != m_g[order][:-1]]]  # first match per GT
        for row in first:
            earlier = (m_r == m_r[row]) & (m_f < m_f[row]) & (m_g != m_g[row])
            out.under += int(earlier.any())

    # multiple responses and segmentation errors
    rg, rr = responses(gt, res, match)
    if len(rg):
        distinct = np.unique(np.column_stack([rg, res.ids[rr]]), axis=0)
        out.resp_ids_sum = len(distinct)
        out.resp_rows = len(np.unique(rg))
        gb, rb = gt.boxes[rg], res.boxes[rr]
        dx = (rb[:, 0] + rb[:, 2] / 2 - gb[:, 0] - gb[:, 2] / 2) / gb[:, 2]
        dy = (rb[:, 1] + rb[:, 3] / 2 - gb[:, 1] - gb[:, 3] / 2) / gb[:, 3]
        dw = (rb[:, 2] - gb[:, 2]) / gb[:, 2]
        dh = (rb[:, 3] - gb[:, 3]) / gb[:, 3]
        out.n_pairs = len(rg)
        out.abs_dx, out.abs_dy = float(np.abs(dx).sum()), float(np.abs(dy).sum())
        out.abs_dw, out.abs_dh = float(np.abs(dw).sum()), float(np.abs(dh).sum())
        out.min_dw, out.max_dw = float(dw.min()), float(dw.max())
        out.min_dh, out.max_dh = float(dh.min()), float(dh.max())
    return out


def paper_metrics(gt: MotTable, res: MotTable, iou_threshold: float = 0.5) -> dict[str, float]:
    """Flat dict of COLUMNS for one sequence (see the module docstring for definitions)."""
    return paper_counts(gt, res, iou_threshold).columns()


def combine(counts: dict[str, PaperCounts]) -> dict[str, dict[str, float]]:
    """Per-sequence columns plus a ``COMBINED`` entry from the summed counts."""
    return combine_counts(counts, PaperCounts())
