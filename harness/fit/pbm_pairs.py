"""Samples for fitting PBM's feature models and weights (PBM 2.2, 4.1): pairs (a person in
frame k-1, a person in frame k) of annotated sequences, measured as the tracker measures
them (``occbench.trackers.layered.parts``, eq. 11 differences, optionally motion-compensated).

Positive pairs are a person against itself in the next frame (what the difference models
are fitted on); negative pairs are a person against its nearest other people within the
tracker's gate (what the weight search must tell apart). Used by ``occbench.fit.pbm``.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from occbench.pipeline.loop import ForegroundProvider
from occbench.trackers.layered.association import feature_differences
from occbench.trackers.layered.parts import FEATURES, N_PARTS, PartFeatureExtractor, centroid_ratios
from occbench.trackers.layered.search import region_centroid

log = logging.getLogger(__name__)


@dataclass
class PairSamples:
    """Pairs (a person in frame k-1, a person in frame k) of annotated sequences.

    Attributes:
        d: (M, 6, 5) float64 eq. 11 differences (``FEATURES`` order, ``PART_NAMES`` order).
        positive: (M,) bool, True when both sides are the same person.
        block: (M,) int64 id of the frame block of frame k (one sequence, ``block_frames``
            consecutive frames); cross-validation folds are unions of whole blocks.
    """

    d: np.ndarray
    positive: np.ndarray
    block: np.ndarray

    def __len__(self) -> int:
        return len(self.positive)


def collect_pairs(sequences: Iterable, max_frames: int | None = None, min_visibility: float = 0.7,
                  bins: int = 4, neighbours: int = 3, radius: float = 1.0,
                  block_frames: int = 25, motion_compensation: bool = True,
                  foreground: str = "auto", background: Mapping[str, Any] | None = None,
                  ) -> PairSamples:
    """Positive and negative frame-to-frame pairs of annotated people (PBM 4.1 samples).

    Args:
        sequences: ``occbench.datasets.base.Sequence`` objects with ground truth and frames.
        max_frames: frames read per sequence (None = all).
        min_visibility: people below this visibility (when known) or flagged occluded are
            skipped: the models describe unoccluded matches.
        bins: histogram bins per channel (must match the tracker's ``histogram_bins``).
        neighbours: negatives per person and frame: the nearest other people (0 = none).
        radius: a negative's box centre lies within ``radius`` x (w, h) of the person's
            previous centre (w, h its previous box size), like the tracker's gate (PBM 3).
        block_frames: frames per cross-validation block.
        motion_compensation: as the tracker's ``motion_compensation``: the previous frame's
            parts are moved by the person's previous step (its centroid in frame k-1 minus
            in frame k-2; none when it was not kept in frame k-2) before the overlap and
            displacement differences are taken, as the tracker moves a target's parts model
            by KF1's constant-velocity prediction.
        foreground, background: the foreground the parts are measured on, as the
            tracker gets it (``occbench.pipeline.loop.ForegroundProvider``): ``auto`` = the
            sequence's exact person mask (synthetic scenes), else none (the whole box counts
            as foreground: area and perimeter then carry no information); ``mog2`` = the
            front end's background subtraction (real frames), ``background`` its arguments.
    Returns:
        ``PairSamples``; positives are exactly the pairs ``collect_differences`` returns.
    """
    if neighbours < 0 or radius < 0 or block_frames < 1:
        raise ValueError(f"collect_pairs: neighbours ({neighbours}) and radius ({radius}) must "
                         f"be >= 0 and block_frames ({block_frames}) >= 1")
    ex = PartFeatureExtractor(bins)
    ds: list[np.ndarray] = []
    pos: list[np.ndarray] = []
    blocks: list[np.ndarray] = []
    block_base = 0
    for seq in sequences:
        if seq.gt is None:
            log.warning("%s: no ground truth, skipped", seq.info.name)
            continue
        prev = None  # (ids, boxes, features, centroids) of the previous frame
        before: dict[int, np.ndarray] = {}  # id -> centroid, the frame before that
        warned = False
        frames = seq.frame_numbers()[:max_frames]
        fg_of = ForegroundProvider(foreground, seq, background)
        for k in frames:
            frame = seq.frame(k)
            if frame is None:
                log.warning("%s: no pixels, skipped", seq.info.name)
                break
            fg = fg_of(k, frame, None)
            if fg is None and not warned:
                log.warning("%s: no foreground masks; the whole box counts as foreground",
                            seq.info.name)
                warned = True
            cur = _measure(seq, k, frame, fg, ex, min_visibility)
            if cur is None:
                prev, before = None, {}
                continue
            if prev is not None:
                ti, ci, is_pos = _pairs(prev[0], prev[1], cur[0], cur[1], neighbours, radius)
                if len(ti):
                    model = _moved(prev[2], prev[0], prev[3], before) if motion_compensation \
                        else prev[2]
                    ds.append(feature_differences(model, cur[2])[ti, ci])  # (K, 6, 5)
                    pos.append(is_pos)
                    blocks.append(np.full(len(ti), block_base + (k - frames[0]) // block_frames,
                                          np.int64))
                before = dict(zip(prev[0].tolist(), prev[3]))
            prev = cur
        block_base += (len(frames) - 1) // block_frames + 1
    if not ds:
        return PairSamples(np.zeros((0, len(FEATURES), N_PARTS)), np.zeros(0, bool),
                           np.zeros(0, np.int64))
    return PairSamples(np.concatenate(ds), np.concatenate(pos), np.concatenate(blocks))


def _measure(seq, k: int, frame: np.ndarray, fg: np.ndarray | None, ex: PartFeatureExtractor,
             min_visibility: float) -> tuple | None:
    """(ids, boxes, part features, centroids) of frame ``k``'s unoccluded annotated people,
    measured as the tracker measures them; None when there is nobody (the extractor is
    started on the frame either way)."""
    rows = _unoccluded_rows(seq, k, min_visibility)
    ids = seq.gt.table.ids[rows].astype(np.int64)
    boxes = np.asarray(seq.gt.table.boxes[rows], dtype=np.float64)
    ex.start(frame, fg)
    if len(rows) == 0:
        return None
    cents = np.array([_centroid(fg, b) for b in boxes])
    al, be = centroid_ratios(boxes, cents)
    return ids, boxes, ex.extract(boxes, al, be), cents


def _unoccluded_rows(seq, k: int, min_visibility: float) -> np.ndarray:
    """Ground-truth rows of frame ``k`` whose person is neither flagged occluded nor, when
    the visibility is known, below ``min_visibility``."""
    table, occluded = seq.gt.table, seq.gt.occluded
    rows = seq.gt.rows_of(k)
    keep = np.ones(len(rows), dtype=bool)
    if occluded is not None:
        keep &= ~occluded[rows]
    vis = table.visibility[rows] if hasattr(table, "visibility") else None
    if vis is not None:
        keep &= ~(np.isfinite(vis) & (vis < min_visibility))
    return rows[keep]


def _moved(model, ids: np.ndarray, cents: np.ndarray, before: dict[int, np.ndarray]):
    """The previous frame's parts ``model`` moved by each person's previous step (its
    centroid ``cents`` minus the one of the frame before, ``before``; none when absent)."""
    return model.shifted(np.array([c - before[i] if i in before else np.zeros(2)
                                   for i, c in zip(ids.tolist(), cents)]).reshape(-1, 2))


def _pairs(prev_ids: np.ndarray, prev_boxes: np.ndarray, ids: np.ndarray, boxes: np.ndarray,
           neighbours: int, radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Index pairs (previous person, current person) and whether they are the same person.

    Per previous person: itself when present, then its ``neighbours`` nearest other people
    (centre distance) whose centre lies within ``radius`` x (w, h) of its previous centre.
    Boxes are (N, 4) xywh.
    """
    pc = prev_boxes[:, :2] + prev_boxes[:, 2:] / 2
    cc = boxes[:, :2] + boxes[:, 2:] / 2
    off = np.abs(cc[None] - pc[:, None])  # (P, C, 2)
    near = np.all(off <= radius * prev_boxes[:, None, 2:], axis=2)
    dist = np.hypot(off[..., 0], off[..., 1])
    same = prev_ids[:, None] == ids[None]
    ti: list[int] = []
    ci: list[int] = []
    for t in range(len(prev_ids)):
        hit = np.flatnonzero(same[t])
        ti += [t] * len(hit)
        ci += hit.tolist()
        other = np.flatnonzero(near[t] & ~same[t])
        other = other[np.argsort(dist[t, other], kind="stable")][:neighbours]
        ti += [t] * len(other)
        ci += other.tolist()
    ti_a, ci_a = np.array(ti, np.intp), np.array(ci, np.intp)
    return ti_a, ci_a, same[ti_a, ci_a]


def collect_differences(sequences: Iterable, max_frames: int | None = None,
                        min_visibility: float = 0.7, bins: int = 4,
                        motion_compensation: bool = True, foreground: str = "auto",
                        background: Mapping[str, Any] | None = None) -> dict[str, np.ndarray]:
    """Frame-to-frame part feature differences of annotated people (eq. 11).

    Args:
        sequences: ``occbench.datasets.base.Sequence`` objects with ground truth and frames.
        max_frames: frames read per sequence (None = all).
        min_visibility: people below this visibility (when known) or flagged occluded are
            skipped: the models describe unoccluded matches.
        bins: histogram bins per channel (must match the tracker's ``histogram_bins``).
        motion_compensation, foreground, background: see ``collect_pairs``.
    Returns:
        {feature: (K, 5) differences}.
    """
    return positive_differences(collect_pairs(sequences, max_frames, min_visibility, bins,
                                              neighbours=0,
                                              motion_compensation=motion_compensation,
                                              foreground=foreground, background=background))


def positive_differences(samples: PairSamples) -> dict[str, np.ndarray]:
    """{feature: (K, 5) differences} of the positive pairs (what the models are fitted on)."""
    d = samples.d[samples.positive]
    return {f: d[:, i] for i, f in enumerate(FEATURES)}


def _centroid(fg: np.ndarray | None, box: np.ndarray) -> np.ndarray:
    return region_centroid(fg, box)
