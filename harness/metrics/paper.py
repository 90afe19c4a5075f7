"""The trajectory-level metrics the two papers report, as pure functions of gt and result.

Both papers score trajectories, not frames. Everything here starts from one frame-by-frame
matching of ground-truth rows to result rows made the CLEAR MOT way
(``occbench.metrics.rows.match_rows``, re-exported here). Ground-truth rows with
``conf == 0`` (MOT16 "ignore") or a class other than pedestrian are left out
(``considered_mask``).

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
  swaps / GT. Under PBM's single-target protocol an id's history is its *follower's*
  (``followers``: a restart under a new id belongs to the follower started for another
  person, as the paper's tracker keeps its one id when it drifts onto someone else), here and
  in ``Under``.
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
from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from occbench.io.mot import MotTable
from occbench.metrics.arrays import distinct
from occbench.metrics.counts import combine_counts
from occbench.metrics.identity import count_pairs
from occbench.metrics.rows import (  # noqa: F401 - considered, match_rows: paper's API too
    RowMatching,
    considered,
    considered_mask,
    match_rows,
    row_matching,
)

log = logging.getLogger(__name__)

# Column names, prefixed by the paper whose table they fill (avoids clashing with CLEAR's
# MT/ML in occbench.metrics.COLUMNS, which use different thresholds and matching).
RETA_COLUMNS = ["Song_GT", "Song_MT%", "Song_PT%", "Song_ML%", "Song_Frag", "Song_IDS"]
PBM_COLUMNS = [
    "PBM_GT", "PBM_MT", "PBM_MT1", "PBM_ML", "PBM_Missed", "PBM_Under", "PBM_Over",
    "PBM_IDsw/traj", "PBM_IDs/traj", "PBM_IDs/frame",
]
SEGMENTATION_COLUMNS = ["PBM_dx%", "PBM_dy%", "PBM_dw%", "PBM_dh%"]
COLUMNS = RETA_COLUMNS + PBM_COLUMNS + SEGMENTATION_COLUMNS


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


def responses(m: RowMatching, inside: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """All (GT row, result row) response pairs: the matched pairs plus unmatched result
    boxes lying at least ``inside`` (> 0) within a GT box of the same frame (each such box
    answers the GT box covering most of it, the first in table order on a tie).

    Returns:
        (K,) GT row indices and (K,) result row indices, sorted by GT row then result row.
    """
    matched = np.flatnonzero(m.match >= 0)
    used = np.zeros(len(m.res), dtype=bool)
    used[m.match[matched]] = True
    p = m.pairs  # a box covering part of another overlaps it: its IoU is nonzero
    g, r = p.gt_rows[p.row], p.tracker_rows[p.col]
    g, r = g[~used[r]], r[~used[r]]
    cover = _intersection(m.res.boxes[r], m.gt.boxes[g])  # |r & g| / |r|, as
    area = m.res.boxes[r, 2] * m.res.boxes[r, 3]  # occbench.trackers.geometry.overlap_ratio_matrix
    with np.errstate(invalid="ignore", divide="ignore"):
        cover = np.where(area > 0, cover / area, 0.0)
    order = np.lexsort((g, -cover, r))  # per result box the best cover, then the first gt
    best = order[np.r_[True, r[order][1:] != r[order][:-1]]] if len(r) else order
    best = best[cover[best] >= inside]
    g, r = np.r_[matched, g[best]], np.r_[m.match[matched], r[best]]
    order = np.lexsort((r, g))
    return g[order], r[order]


def _intersection(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(K,) intersection areas of the xywh box pairs a[k], b[k] (the entries of
    ``occbench.trackers.geometry.intersection_matrix``, computed alike)."""
    w = np.minimum(a[:, 0] + a[:, 2], b[:, 0] + b[:, 2]) - np.maximum(a[:, 0], b[:, 0])
    h = np.minimum(a[:, 1] + a[:, 3], b[:, 1] + b[:, 3]) - np.maximum(a[:, 1], b[:, 1])
    return np.clip(w, 0.0, None) * np.clip(h, 0.0, None)


def paper_counts(gt: MotTable, res: MotTable, iou_threshold: float = 0.5,
                 matching: RowMatching | None = None,
                 followers: Mapping[int, int] | None = None) -> PaperCounts:
    """Count everything the papers' trajectory tables need for one sequence.

    Args:
        gt: ground truth (rows with conf == 0 are ignored).
        res: tracker result rows.
        iou_threshold: smallest IoU of a match.
        matching: ``row_matching(gt, res, iou_threshold)`` when already computed.
        followers: result id -> the id its follower started under (PBM's single-target
            protocol, ``occbench.pipeline.protocols``); None: every id is its own.

    Raises:
        ValueError: a result id has no follower in ``followers``.
    """
    m = matching if matching is not None else row_matching(gt, res, iou_threshold)
    out = PaperCounts()
    if len(m.gt) == 0:
        return out
    hit = m.match >= 0
    mid = np.full(len(m.gt), -1, dtype=np.int64)
    mid[hit] = m.res.ids[m.match[hit]]
    uniq, inverse = np.unique(m.gt.ids, return_inverse=True)
    n = len(uniq)
    covered = np.bincount(inverse, weights=hit, minlength=n)
    coverage = covered / np.bincount(inverse, minlength=n)
    out.gt = n
    out.mt80 = int((coverage > 0.8).sum())
    out.ml20 = int((coverage < 0.2).sum())
    out.pt = n - out.mt80 - out.ml20
    out.ml40 = int((coverage < 0.4).sum())
    out.missed = int((covered == 0).sum())

    # matched rows only, as (gt index, frame, result id)
    m_g, m_f, m_r = inverse[hit], m.gt.frames[hit], mid[hit]
    # Frag: id changes along each GT trajectory (matched frames, in time order)
    order, change = _changes(m_g, m_f, m_r)
    out.frag = int(change.sum())
    # IDS: GT changes along each result trajectory
    out.ids = int(_changes(m_r, m_f, m_g)[1].sum())

    # distinct ids per trajectory
    n_ids = np.bincount(count_pairs(m_g, m_r)[0], minlength=n)
    out.mt1 = int(((coverage > 0.8) & (n_ids == 1)).sum())
    out.over = int((n_ids > 1).sum())
    out.ids_sum = int(n_ids.sum())
    out.matched_traj = int((n_ids > 0).sum())
    m_u = m_r if followers is None else _follower_of(m_r, followers)
    out.swaps = _swaps(m_g, m_f, m_u, order, change)
    out.under = _under(m_g, m_f, m_u, order)
    _segmentation(out, m, *responses(m))
    return out


def _follower_of(ids: np.ndarray, followers: Mapping[int, int]) -> np.ndarray:
    """Each id's follower (``followers[id]``)."""
    keys, values = np.array(sorted(followers.items()), dtype=np.int64).reshape(-1, 2).T
    pos = np.searchsorted(keys, ids)
    found = pos < len(keys)
    found[found] = keys[pos[found]] == ids[found]
    if not found.all():
        raise ValueError(f"result ids {sorted(set(ids[~found].tolist()))[:5]} have no follower")
    return values[pos]


def _swaps(m_g: np.ndarray, m_f: np.ndarray, m_u: np.ndarray, order: np.ndarray,
           change: np.ndarray) -> int:
    """PBM's swaps: along a GT trajectory an id change p -> q where q's previous match was
    another GT (``order``, ``change``: ``_changes(m_g, m_f, m_r)``; ``m_u``: the matched ids,
    or their followers, whose previous match counts)."""
    r_order = np.lexsort((m_f, m_u))
    prev_gt = np.full(len(m_g), -1)
    same = np.zeros(len(m_g), dtype=bool)
    same[1:] = m_u[r_order][1:] == m_u[r_order][:-1]
    shifted = np.r_[-1, m_g[r_order][:-1]]
    prev_gt[r_order] = np.where(same, shifted, -1)
    changed = np.zeros(len(m_g), dtype=bool)
    changed[order] = change
    return int((changed & (prev_gt >= 0) & (prev_gt != m_g)).sum())


def _under(m_g: np.ndarray, m_f: np.ndarray, m_r: np.ndarray, order: np.ndarray) -> int:
    """PBM's under-segmented trajectories: the first id of a trajectory was matched, in an
    earlier frame, to another trajectory (``order`` sorts the matches by GT, then frame;
    ``m_r``: the matched ids, or their followers).

    Per result id: its earliest match (frame f1, GT g1) and its earliest match to a GT other
    than g1 (frame f2); a trajectory g starting at frame f with that id is under-segmented
    when f1 < f for g != g1, or f2 < f for g == g1."""
    if len(m_g) == 0:
        return 0
    first = order[np.r_[True, m_g[order][1:] != m_g[order][:-1]]]  # first match per GT
    ids, r = np.unique(m_r, return_inverse=True)
    by_time = np.lexsort((m_f, r))
    head = by_time[np.r_[True, r[by_time][1:] != r[by_time][:-1]]]  # earliest match per id
    f1, g1 = np.empty(len(ids), m_f.dtype), np.empty(len(ids), m_g.dtype)
    f1[r[head]], g1[r[head]] = m_f[head], m_g[head]
    other = m_g != g1[r]
    f2 = np.full(len(ids), np.iinfo(np.int64).max)
    np.minimum.at(f2, r[other], m_f[other])
    f, g, k = m_f[first], m_g[first], r[first]
    return int(np.where(g != g1[k], f1[k] < f, f2[k] < f).sum())


def _segmentation(out: PaperCounts, m: RowMatching, rg: np.ndarray, rr: np.ndarray) -> None:
    """Multiple responses and PBM's segmentation errors from the response pairs."""
    if len(rg) == 0:
        return
    out.resp_ids_sum = len(count_pairs(rg, m.res.ids[rr])[0])  # distinct (row, id) pairs
    out.resp_rows = len(distinct(rg))
    gb, rb = m.gt.boxes[rg], m.res.boxes[rr]
    dx = (rb[:, 0] + rb[:, 2] / 2 - gb[:, 0] - gb[:, 2] / 2) / gb[:, 2]
    dy = (rb[:, 1] + rb[:, 3] / 2 - gb[:, 1] - gb[:, 3] / 2) / gb[:, 3]
    dw = (rb[:, 2] - gb[:, 2]) / gb[:, 2]
    dh = (rb[:, 3] - gb[:, 3]) / gb[:, 3]
    out.n_pairs = len(rg)
    out.abs_dx, out.abs_dy = float(np.abs(dx).sum()), float(np.abs(dy).sum())
    out.abs_dw, out.abs_dh = float(np.abs(dw).sum()), float(np.abs(dh).sum())
    out.min_dw, out.max_dw = float(dw.min()), float(dw.max())
    out.min_dh, out.max_dh = float(dh.min()), float(dh.max())


def paper_metrics(gt: MotTable, res: MotTable, iou_threshold: float = 0.5) -> dict[str, float]:
    """Flat dict of COLUMNS for one sequence (see the module docstring for definitions)."""
    return paper_counts(gt, res, iou_threshold).columns()


def combine(counts: dict[str, PaperCounts]) -> dict[str, dict[str, float]]:
    """Per-sequence columns plus a ``COMBINED`` entry from the summed counts."""
    return combine_counts(counts, PaperCounts())
