"""Two targets on one person: when is the younger one a twin of the older? (our life cycle;
the paper starts each target by hand and tracks it "until lost", PBM 3).

With the own detector a second target can come to stand on a person another target already
holds (a target that lost its own person, or a birth from a second box on one person); the
two then take the person's single detection in turn, the one left unfound reported hidden
behind the other, and neither is ever lost (docs/generalisation.md, issue 35, "stacked
targets"). ``KeepStacked`` is the paper's life cycle; ``FoldTwins``
(``adaptations.fold_twins``) ends the younger of such a pair once time has shown it has
nothing of its own, in the terms of the paper's track termination: a target that is not
found is lost. Boxes are (R, 4) float64 xywh pixels; masks (H, W), nonzero = foreground.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.geometry import iou_matrix
from occbench.trackers.layered.targets import Targets

#: two reported boxes at this IoU stand on one place (the metrics' and the stacks' threshold)
STACK_IOU = 0.5


def own_foreground(box: np.ndarray, other: np.ndarray, fg: np.ndarray) -> float:
    """Share of the xywh ``box``'s area (clipped to the mask) that is foreground lying
    outside the xywh box ``other``: the pixels only ``box``'s target can explain."""
    H, W = fg.shape
    x0, y0 = max(round(box[0]), 0), max(round(box[1]), 0)
    x1, y1 = min(round(box[0] + box[2]), W), min(round(box[1] + box[3]), H)
    if x1 <= x0 or y1 <= y0:
        return 0.0
    own = fg[y0:y1, x0:x1] != 0
    ox0, oy0 = max(round(other[0]) - x0, 0), max(round(other[1]) - y0, 0)
    ox1, oy1 = max(round(other[0] + other[2]) - x0, 0), max(round(other[1] + other[3]) - y0, 0)
    own[oy0:oy1, ox0:ox1] = False
    return np.count_nonzero(own) / ((x1 - x0) * (y1 - y0))


class KeepStacked:
    """Each target is kept until lost, whoever stands with it (PBM 3)."""

    def folded(self, targets: Targets, place, fg: np.ndarray | None, max_misses: int,
               runs: dict) -> np.ndarray:
        return np.zeros(len(targets.id), dtype=bool)


@dataclass(frozen=True)
class FoldTwins:
    """``fold_twins``: a confirmed target whose reported box has stood on an older one's
    (IoU >= ``STACK_IOU``) for ``frames`` frames in a row without ever being found in the
    same frame as it (never a detection of its own) but found in turn with it at least once
    (it took the detection the older one takes: a person wholly hidden behind another is
    never found while covered) and without foreground of its own (its box holds < ``own``
    foreground outside the older one's box, every one of those frames) is the older
    target's twin: it is ended at the first such frame in which the older one is found.
    Without a mask it stands aside (no evidence of the last half).

    Args:
        frames: frames in a row the evidence must hold (>= 1).
        own: foreground share of the younger box lying outside the older box below which
            the younger has no region of its own (0-1).
    """

    frames: int
    own: float

    def folded(self, targets: Targets, place, fg: np.ndarray | None, max_misses: int,
               runs: dict) -> np.ndarray:
        """(T,) bool: which targets are folded this frame, among the confirmed ones
        reported (unfound for at most ``max_misses`` frames) at the boxes ``place``
        (``rules.report_box``) puts them. ``runs`` maps a pair (older id, younger id) to its
        frames of evidence so far and whether the younger was found in them; it is updated in place (a pair missing from this frame's
        evidence is forgotten)."""
        rows = (targets.confirmed & (targets.misses <= max_misses)).nonzero()[0]
        out = np.zeros(len(targets.id), dtype=bool)
        if fg is None or len(rows) < 2:
            runs.clear()
            return out
        rows = rows[np.argsort(targets.id[rows], kind="stable")]  # birth order: older first
        ids, all_found = targets.id[rows], targets.misses == 0
        boxes = targets.dof[rows][:, [0, 1, 4, 5]]
        place.place(boxes, targets, rows, all_found)
        found = all_found[rows]
        near = np.triu(iou_matrix(boxes, boxes) >= STACK_IOU, 1)
        seen: dict[tuple[int, int], tuple[int, bool]] = {}
        fold = np.zeros(len(ids), dtype=bool)
        for a, b in zip(*np.nonzero(near), strict=True):
            key = (int(ids[a]), int(ids[b]))
            if found[a] and found[b]:
                continue  # each found: two detections, two people
            if own_foreground(boxes[b], boxes[a], fg) >= self.own:
                continue  # the younger explains pixels the older does not
            frames, took = runs.get(key, (0, False))
            seen[key] = frames + 1, took or bool(found[b])  # found in turn: the older's detection
            if seen[key][0] >= self.frames and seen[key][1] and found[a]:
                fold[b] = True
        runs.clear()
        runs.update(seen)
        out[rows] = fold
        return out
