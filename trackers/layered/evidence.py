"""Is an unfound target still there? The evidence a hidden-person report rests on.

PBM reports a target until it is lost (PBM 3) and says nothing of how long an unfound one
is shown; ``reporting.max_misses`` bounds it. ``HiddenEvidence`` (an adaptation, issue 28
item 2(b)) shows an unfound target only while one piece of evidence for a person at its box
holds. Boxes are (R, 4) float64 xywh pixels; masks (H, W), nonzero = foreground.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.common.checks import at_least, coerce


def box_foreground(boxes: np.ndarray, fg: np.ndarray) -> np.ndarray:
    """(R,) foreground fraction of each (R, 4) xywh box, clipped to the (H, W) mask (0 for
    a box wholly outside it)."""
    H, W = fg.shape
    out = np.zeros(len(boxes))
    for k, (x, y, w, h) in enumerate(np.asarray(boxes, dtype=np.float64).tolist()):
        x0, y0 = max(round(x), 0), max(round(y), 0)
        x1, y1 = min(round(x + w), W), min(round(y + h), H)
        if x1 > x0 and y1 > y0:
            out[k] = np.count_nonzero(fg[y0:y1, x0:x1]) / ((x1 - x0) * (y1 - y0))
    return out


def covered_from_front(boxes: np.ndarray, front: np.ndarray) -> np.ndarray:
    """(R, F) share of each of the (R, 4) xywh boxes that lies under each of the (F, 4)
    ``front`` boxes, 0 where the front box's bottom edge is not below the box's (not nearer
    the camera: on a ground plane seen from above, the lower feet are the nearer person)."""
    a, b = boxes[:, None, :], front[None, :, :]
    iw = np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2]) - np.maximum(a[..., 0], b[..., 0])
    ih = np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3]) - np.maximum(a[..., 1], b[..., 1])
    share = iw.clip(0.0) * ih.clip(0.0) / np.maximum(a[..., 2] * a[..., 3], 1e-9)
    nearer = b[..., 1] + b[..., 3] > a[..., 1] + a[..., 3]
    return np.where(nearer, share, 0.0)


@dataclass(frozen=True)
class HiddenEvidence:
    """``adaptations.hidden_evidence``: with a foreground mask, an unfound target is
    reported only while a person there is still explained by one of
    (1) its own pixels or an occluder's: its reported box holds >= ``foreground``
        foreground;
    (2) an occluder: a target found this frame whose bottom edge lies below its own
        (nearer the camera) covers >= ``cover`` of its box;
    (3) memory: it was last found at most ``memory`` x (its matches) frames ago (a person
        behind scenery; the longer a target was tracked, the longer it is believed, as
        norfair's hit counter keeps a track alive for as many frames as it was matched).
    ``reporting.max_misses`` still bounds every report. Without a mask the image gives no
    evidence to weigh and every unfound target is reported as before (memory alone cut
    true reports of young targets under independent misses: docs/adaptations.md).

    Args:
        foreground: foreground fraction of the box (0-1; > 1 never holds).
        cover: share of the box under a nearer found target (0-1; > 1 never holds).
        memory: frames of belief per match (>= 0; 0: no memory).
    """

    foreground: float = 0.6
    cover: float = 0.3
    memory: float = 0.2

    def __post_init__(self) -> None:
        at_least("adaptations.hidden_evidence", 0, foreground=self.foreground,
                 cover=self.cover, memory=self.memory)
        coerce(self, {"foreground": float, "cover": float, "memory": float})

    def shown(self, boxes: np.ndarray, fg: np.ndarray | None, hits: np.ndarray,
              misses: np.ndarray) -> np.ndarray | None:
        """(R,) bool: is the target at each of the (R, 4) reported boxes shown? ``hits``,
        ``misses``: (R,) matches so far and frames since last found (0 = found: always
        shown). None without a mask (all shown)."""
        if fg is None:
            return None
        found = misses == 0
        show = found | (misses <= self.memory * hits)  # (3)
        hidden = ~show
        if hidden.any() and found.any():  # (2)
            show[hidden] = (covered_from_front(boxes[hidden], boxes[found]) >= self.cover).any(axis=1)
        hidden = ~show
        if hidden.any():  # (1)
            show[hidden] = box_foreground(boxes[hidden], fg) >= self.foreground
        return show


class MissesBound:
    """An unfound target is reported for ``reporting.max_misses`` frames at most."""

    def reset(self) -> None:  # no record (``record.ReportedByRecord`` keeps one)
        pass

    def shown(self, targets, found: np.ndarray, shown: np.ndarray, report_box,
              fg: np.ndarray | None) -> np.ndarray:
        return shown


@dataclass(frozen=True)
class ReportedBehind:
    """``adaptations.reported_behind``: with a foreground mask, a confirmed target unfound for
    longer than ``reporting.max_misses`` frames is still reported while a target found this
    frame, nearer the camera (``covered_from_front``), covers >= ``cover`` of the box it
    would be reported at (``rules.report_box``): a person standing or walking behind
    another, PBM's own case, whom the paper tracks "until lost" (PBM 3). The other
    reporting rules then apply as to any unfound target; it lives as long as before
    (``life_cycle.max_misses``). Without a mask it stands aside, as ``HiddenEvidence``
    does (its first form, everywhere, reported people who had left: docs/adaptations.md).

    Args:
        cover: share of the box under one nearer found target (0-1).
    """

    cover: float

    def reset(self) -> None:  # no record: each frame's mask decides
        pass

    def shown(self, targets, found: np.ndarray, shown: np.ndarray, report_box,
              fg: np.ndarray | None) -> np.ndarray:
        """(T,) bool: ``shown`` (found, or confirmed and unfound <= ``reporting.max_misses``)
        with the confirmed unfound targets behind a found one added; ``found`` (T,) bool;
        ``targets``: ``Targets``; ``fg`` the frame's mask (None: ``shown`` as it is)."""
        rows = (targets.confirmed & ~shown).nonzero()[0]
        if fg is None or not len(rows) or not found.any():
            return shown
        boxes = targets.boxes[rows]
        report_box.place(boxes, targets, rows, found)
        behind = (covered_from_front(boxes, targets.boxes[found]) >= self.cover).any(axis=1)
        out = shown.copy()
        out[rows[behind]] = True
        return out
