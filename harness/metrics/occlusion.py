"""Occlusion measured directly: metrics split by ground-truth visibility, and re-identification
after total occlusion.

Visibility of a GT row comes from the table's visibility column (synthetic scenes, MOT16+ gt)
where it is a number; where it is NaN and the dataset gives occlusion labels
(``GroundTruth.occluded``, e.g. CAVIAR's ``occluded`` appearance label), a labelled row counts
as visibility 0 and an unlabelled one as 1; rows with neither are left out of the bins.

Per visibility bin [0, .25), [.25, .5), [.5, .75), [.75, 1] (columns ``*_v0-25`` ...):

* ``Recall``: matched GT rows / GT rows of the bin (CLEAR matching, ``rows.match_rows``).
* ``IDP`` (identity precision of the tracked rows): of the matched GT rows of the bin, the
  fraction whose result id is the one globally assigned to that person by the identity
  mapping of IDF1 (Ristani et al. 2016: the one-to-one GT id <-> result id mapping that
  maximises the number of frames the pair overlaps with IoU >= the threshold).
* ``IDs``: identity switches (CLEAR: a GT row matched to an id other than the one its
  person was last matched to) counted in the bin of the row where the switch happens.

Re-identification after total occlusion (``ReID*`` columns): an episode is a maximal run of
consecutive rows of one person with visibility < ``hidden_below`` (or an occluded label).
An episode is scored when the person was matched at least once before it and is seen again
(a row with visibility >= ``hidden_below``) after it. It is re-identified when the first
matched row after the episode carries the id of the last matched row before it.
``ReID`` = re-identified / scored episodes; ``ReID_frames`` = mean number of frames from the
first visible frame after the episode to that first correct match (0 = recovered at once),
over the re-identified episodes; ``ReID_n`` = scored episodes.

Counts are additive over sequences (``OcclusionCounts.__add__``); ``columns`` recomputes
ratios from the sums.

For the runner: ``extra_score(gt, res)`` computes these and the paper metrics
(``occbench.metrics.paper``) of one sequence, ``extra_rows`` turns them into ``metrics.csv``
rows (per sequence and COMBINED) with the columns ``EXTRA_COLUMNS``.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from occbench.datasets.base import GroundTruth
from occbench.io.mot import MotTable
from occbench.metrics.arrays import distinct
from occbench.metrics.counts import combine_counts
from occbench.metrics.frames import FramePairs, frame_pairs
from occbench.metrics.identity import overlap_counts
from occbench.metrics.paper import COLUMNS as PAPER_COLUMNS
from occbench.metrics.paper import PaperCounts, paper_counts
from occbench.metrics.rows import RowMatching, considered_mask, row_matching
from occbench.trackers.common.assignment import assign

if TYPE_CHECKING:
    import pandas as pd

log = logging.getLogger(__name__)

BIN_EDGES = (0.0, 0.25, 0.5, 0.75, 1.0)
BIN_NAMES = ("v0-25", "v25-50", "v50-75", "v75-100")
COLUMNS = [f"{m}_{b}" for b in BIN_NAMES for m in ("Recall", "IDP", "IDs")] + [
    "ReID", "ReID_frames", "ReID_n",
]


def _zeros() -> np.ndarray:
    return np.zeros(len(BIN_NAMES), dtype=np.int64)


@dataclass
class OcclusionCounts:
    """Additive counts per visibility bin and of total-occlusion episodes."""

    rows: np.ndarray = field(default_factory=_zeros)      # GT rows per bin
    matched: np.ndarray = field(default_factory=_zeros)   # matched GT rows per bin
    id_ok: np.ndarray = field(default_factory=_zeros)     # matched with the mapped id
    switches: np.ndarray = field(default_factory=_zeros)  # CLEAR id switches per bin
    episodes: int = 0         # scored total-occlusion episodes
    recovered: int = 0        # re-identified episodes
    recovery_frames: int = 0  # sum of frames to recovery over re-identified episodes

    def __add__(self, other: OcclusionCounts) -> OcclusionCounts:
        return OcclusionCounts(
            self.rows + other.rows, self.matched + other.matched, self.id_ok + other.id_ok,
            self.switches + other.switches, self.episodes + other.episodes,
            self.recovered + other.recovered, self.recovery_frames + other.recovery_frames,
        )

    def columns(self) -> dict[str, float]:
        """Flat dict of COLUMNS (ratios as fractions, NaN where the bin is empty)."""
        out: dict[str, float] = {}
        for b, name in enumerate(BIN_NAMES):
            rows, matched = int(self.rows[b]), int(self.matched[b])
            out[f"Recall_{name}"] = matched / rows if rows else float("nan")
            out[f"IDP_{name}"] = int(self.id_ok[b]) / matched if matched else float("nan")
            out[f"IDs_{name}"] = int(self.switches[b])
        out["ReID"] = self.recovered / self.episodes if self.episodes else float("nan")
        out["ReID_frames"] = (self.recovery_frames / self.recovered if self.recovered
                              else float("nan"))
        out["ReID_n"] = self.episodes
        return out


def row_visibility(gt: MotTable, occluded: np.ndarray | None = None) -> np.ndarray:
    """(N,) float64 visibility per GT row: the visibility column where it is a number, else
    0 for rows labelled occluded and 1 for unlabelled rows when labels exist, else NaN."""
    vis = np.asarray(gt.visibility, dtype=np.float64).copy()
    if occluded is not None:
        occluded = np.asarray(occluded, dtype=bool)
        if occluded.shape != vis.shape:
            raise ValueError(f"occluded has shape {occluded.shape}, gt has {len(gt)} rows")
        unknown = np.isnan(vis)
        vis[unknown] = np.where(occluded[unknown], 0.0, 1.0)
    return vis


def identity_mapping(gt: MotTable, res: MotTable, iou_threshold: float = 0.5,
                     pairs: FramePairs | None = None) -> dict[int, int]:
    """GT id -> result id of the IDF1 mapping (Ristani et al. 2016): the one-to-one pairing
    maximising the number of frames in which the pair overlaps with IoU >= threshold.

    The frame counts are gathered sparse (``occbench.metrics.identity.overlap_counts`` of
    ``pairs``, the ``frame_pairs`` of all rows when already computed); the assignment is
    solved on the dense (GT ids, result ids) matrix, whose tie-breaking among equally good
    mappings decides which rows count as matched with the mapped id."""
    if len(gt) == 0 or len(res) == 0:
        return {}
    if pairs is None:
        pairs = frame_pairs(gt, np.arange(len(gt)), res, np.arange(len(res)))
    g, t, count = overlap_counts(pairs, iou_threshold)
    g_ids, r_ids = distinct(gt.ids), distinct(res.ids)
    cost = np.full((len(g_ids), len(r_ids)), np.inf)
    cost[np.searchsorted(g_ids, g), np.searchsorted(r_ids, t)] = -count.astype(np.float64)
    matched, _, _ = assign(cost, 0.0)
    return {int(g_ids[i]): int(r_ids[j]) for i, j in matched}


def occlusion_counts(gt: MotTable | GroundTruth, res: MotTable, iou_threshold: float = 0.5,
                     hidden_below: float = 0.05, occluded: np.ndarray | None = None,
                     matching: RowMatching | None = None) -> OcclusionCounts:
    """Count the occlusion metrics of one sequence.

    Args:
        gt: ground truth, a MotTable or a GroundTruth (whose ``occluded`` labels are used).
        res: tracker result rows.
        iou_threshold: smallest IoU of a match.
        hidden_below: visibility under which a person counts as fully hidden.
        occluded: (len(gt),) bool labels when ``gt`` is a MotTable (overrides GroundTruth's).
        matching: ``paper.row_matching(gt, res, iou_threshold)`` when already computed.
    """
    if isinstance(gt, GroundTruth):
        occluded = gt.occluded if occluded is None else occluded
        gt = gt.table
    if not 0.0 <= hidden_below <= 1.0:
        raise ValueError(f"hidden_below must be in [0, 1], got {hidden_below}")
    vis = row_visibility(gt, occluded)[considered_mask(gt)]
    m = matching if matching is not None else row_matching(gt, res, iou_threshold)
    gt, match = m.gt, m.match
    out = OcclusionCounts()
    if len(gt) == 0:
        return out
    hit = match >= 0
    mid = np.full(len(gt), -1, dtype=np.int64)
    mid[hit] = res.ids[match[hit]]
    known = ~np.isnan(vis)
    b = np.clip(np.searchsorted(BIN_EDGES, np.where(known, vis, 0.0), side="right") - 1,
                0, len(BIN_NAMES) - 1)

    mapping = identity_mapping(gt, res, iou_threshold, m.pairs)
    keys = np.fromiter(mapping, np.int64, len(mapping))
    mapped = np.full(len(gt), -2, dtype=np.int64)  # each row's mapped result id, -2: none
    if len(keys):
        by_key = np.argsort(keys)
        at = by_key[np.minimum(np.searchsorted(keys, gt.ids, sorter=by_key), len(keys) - 1)]
        found = keys[at] == gt.ids
        mapped[found] = np.fromiter(mapping.values(), np.int64, len(mapping))[at[found]]

    # CLEAR switches: per person, in time order over matched rows, id differs from the last
    order = np.lexsort((gt.frames, gt.ids))
    o_hit = order[hit[order]]
    switch = np.zeros(len(gt), dtype=bool)
    same_person = gt.ids[o_hit][1:] == gt.ids[o_hit][:-1]
    switch[o_hit[1:]] = same_person & (mid[o_hit][1:] != mid[o_hit][:-1])

    nb = len(BIN_NAMES)
    out.rows = np.bincount(b[known], minlength=nb).astype(np.int64)
    out.matched = np.bincount(b[known & hit], minlength=nb).astype(np.int64)
    out.id_ok = np.bincount(b[known & hit & (mid == mapped)], minlength=nb).astype(np.int64)
    out.switches = np.bincount(b[known & switch], minlength=nb).astype(np.int64)

    # total-occlusion episodes, person by person
    hidden = known & (vis < hidden_below)
    visible = known & ~hidden
    ids_o = gt.ids[order]
    starts = np.r_[0, np.flatnonzero(ids_o[1:] != ids_o[:-1]) + 1, len(order)]
    for a, z in itertools.pairwise(starts):
        rows = order[a:z]
        h = hidden[rows]
        if not h.any():
            continue
        edges = np.diff(np.r_[0, h.astype(np.int8), 0])
        for s, e in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
            before = rows[:s][hit[rows[:s]]]
            after_visible = np.flatnonzero(visible[rows[e:]])
            if len(before) == 0 or len(after_visible) == 0:
                continue
            out.episodes += 1
            first_seen = e + after_visible[0]
            later = rows[first_seen:][hit[rows[first_seen:]]]
            if len(later) and mid[later[0]] == mid[before[-1]]:
                out.recovered += 1
                out.recovery_frames += int(gt.frames[later[0]] - gt.frames[rows[first_seen]])
    return out


def occlusion_metrics(gt: MotTable | GroundTruth, res: MotTable, iou_threshold: float = 0.5,
                      hidden_below: float = 0.05) -> dict[str, float]:
    """Flat dict of COLUMNS for one sequence (``Recall_v0-25, IDP_v0-25, IDs_v0-25, ...,
    ReID, ReID_frames, ReID_n``), ready to append to a metrics row."""
    return occlusion_counts(gt, res, iou_threshold, hidden_below).columns()


def combine(counts: dict[str, OcclusionCounts]) -> dict[str, dict[str, float]]:
    """Per-sequence columns plus a ``COMBINED`` entry computed from the summed counts."""
    return combine_counts(counts, OcclusionCounts())


# --------------------------------------------------------------------------- metrics.csv rows

EXTRA_COLUMNS = [*PAPER_COLUMNS, *COLUMNS]


@dataclass
class ExtraScore:
    """The paper-table and occlusion counts of one tracker on one sequence."""

    paper: PaperCounts
    occlusion: OcclusionCounts

    def __add__(self, other: ExtraScore) -> ExtraScore:
        return ExtraScore(self.paper + other.paper, self.occlusion + other.occlusion)

    def columns(self) -> dict[str, float]:
        return {**self.paper.columns(), **self.occlusion.columns()}


def extra_score(gt: MotTable | GroundTruth, res: MotTable, iou_threshold: float = 0.5,
                hidden_below: float = 0.05,
                followers: Mapping[int, int] | None = None) -> ExtraScore:
    """Paper metrics (``occbench.metrics.paper``; ``followers`` as there) and occlusion
    metrics of one sequence."""
    table = gt.table if isinstance(gt, GroundTruth) else gt
    matching = row_matching(table, res, iou_threshold)  # one matching for both
    return ExtraScore(paper_counts(table, res, iou_threshold, matching, followers),
                      occlusion_counts(gt, res, iou_threshold, hidden_below, matching=matching))


def extra_rows(scores: Mapping[str, Mapping[str, ExtraScore]]) -> pd.DataFrame:
    """Rows ``tracker, sequence`` + EXTRA_COLUMNS: each sequence, then a COMBINED row per
    tracker from the summed counts; merge them into metrics.csv on (tracker, sequence)."""
    rows = []
    for tracker, per_seq in scores.items():
        if not per_seq:
            continue
        total = None
        for seq, s in per_seq.items():
            rows.append({"tracker": tracker, "sequence": seq, **s.columns()})
            total = s if total is None else total + s
        rows.append({"tracker": tracker, "sequence": "COMBINED", **total.columns()})
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    return pd.DataFrame(rows, columns=["tracker", "sequence", *EXTRA_COLUMNS])
