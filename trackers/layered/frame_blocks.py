"""A frame's association (PBM 3, 3.1, 4, 4.1) as its result, and a large frame's in
independent blocks so that memory grows with the targets and candidates, not with their
product.

The association scores (T, N) matrices (``selection.FrameScores``): 2.2 GB at 5,000 people
in one frame. A target only ever scores a candidate whose box centre lies in its gate
(PBM 3), and the other steps that read more than one pair (lone growth and the lone-shrink
test of PBM 3.1, pruning along a target's row, the contest along a candidate's column,
withholding, the assignment) look at pairs whose boxes meet. ``interacting_pairs`` gives
a superset of those pairs; ``common.spatial.blocks`` splits the targets and candidates
into blocks no such pair crosses (one block of everything while T x N is at most
``spatial.DENSE_LIMIT``: every ordinary frame runs as before), each associated on its own
with dense matrices of its size, and ``merged`` puts their results together.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from occbench.trackers.common.spatial import meeting_pairs
from occbench.trackers.layered.model_update import Chosen
from occbench.trackers.layered.parts import PartFeatures

if TYPE_CHECKING:  # annotations only
    from occbench.trackers.layered.search import Candidates
    from occbench.trackers.layered.targets import Targets

_GROW = np.array([-1.0, -1.0, 2.0, 2.0])  # one pixel on each side: touching boxes meet


class Association(NamedTuple):
    """One frame's association of its targets and candidates.

    Attributes:
        matches: (M, 2) (target, candidate), by target. lost: unmatched targets, free:
            candidates no target takes (ascending). withheld: (N,) bool candidates that
            start no target (``rules.match``), or None.
        chosen: the matched candidates as the model update takes them (``Chosen``; its
            ``k`` rows the frame's features, or ``searched``'s where ``occluded``), None
            without matches. score: (M,) the matches' global scores p (eq. 13).
        searched: features of the searched pairs' best boxes (PBM 3.1), or None.
    """

    matches: np.ndarray
    lost: np.ndarray
    free: np.ndarray
    withheld: np.ndarray | None
    chosen: Chosen | None
    score: np.ndarray
    searched: PartFeatures | None


def interacting_pairs(targets: Targets, cand: Candidates, pred_wh: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """(target, candidate) pairs, a superset of those any step of the association reads
    together: the candidate's box meets the target's KF1 gate (its centre may lie in it),
    the candidate's region meets the target's box (lone growth, the overlap test), or the
    target's box meets the box a gated target of predicted size (w, h) could be aligned in
    at the candidate's head, (x - w, y, 2 w, h) (the lone-shrink occluders), each grown by a
    pixel. Returns (ia, ib) int64, repeats allowed."""
    boxes = targets.boxes + _GROW
    ga, gb = meeting_pairs(targets.gate_boxes() + _GROW, cand.box + _GROW)
    ra, rb = meeting_pairs(boxes, cand.region + _GROW)
    head, w, h = cand.head[gb], pred_wh[ga, 0], pred_wh[ga, 1]
    aligned = np.column_stack([head[:, 0] - w, head[:, 1], 2.0 * w, h]) + _GROW
    oa, ob = meeting_pairs(boxes, aligned)
    return np.concatenate([ga, ra, oa]), np.concatenate([gb, rb, gb[ob]])


def merged(parts: list[tuple[np.ndarray, np.ndarray, Association]], bins: int) -> Association:
    """The association of a frame from those of its blocks (rows, cols, the block's
    association in its own indices), in the frame's indices."""
    matches, lost, free, chosen, score, searched = [], [], [], [], [], []
    withheld = np.zeros(sum(len(cols) for _, cols, _ in parts), dtype=bool)
    offset = 0  # rows of the searched features so far
    for rows, cols, a in parts:
        matches.append(np.column_stack([rows[a.matches[:, 0]], cols[a.matches[:, 1]]]))
        lost.append(rows[a.lost])
        free.append(cols[a.free])
        if a.withheld is not None:
            withheld[cols] = a.withheld
        if a.chosen is not None:
            c = a.chosen
            k = c.k + offset  # a searched box's row
            k[~c.occluded] = cols[c.k[~c.occluded]]  # a candidate's
            chosen.append(c._replace(k=k))
            score.append(a.score)
        if a.searched is not None:
            searched.append(a.searched)
            offset += len(a.searched)
    m = np.concatenate(matches + [np.zeros((0, 2), np.int64)]).astype(np.int64)
    order = np.argsort(m[:, 0], kind="stable")
    picked = (Chosen(*(np.concatenate(f)[order] for f in zip(*chosen, strict=True)))
              if chosen else None)
    return Association(m[order], np.sort(np.concatenate(lost)), np.sort(np.concatenate(free)),
                       withheld, picked, np.concatenate(score + [np.zeros(0)])[order],
                       PartFeatures.concatenate(searched, bins) if searched else None)
