"""Confirmation of new targets (ours: PBM 3 starts each target by hand): the life cycle's
rule and ``adaptations.early_confirm``'s. Boxes are (N, 4) float64 xywh pixels."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.geometry import iou_matrix
from occbench.trackers.layered.exits import touches_border
from occbench.trackers.layered.targets import Targets


class InARow:
    """A new target is confirmed after ``life_cycle.min_hits`` matches in a row (a miss
    before that drops it)."""

    def confirm(self, targets: Targets, rows: np.ndarray, min_hits: int) -> None:
        """Confirms, in place, the targets at ``rows`` (matched this frame) that qualify."""
        targets.confirmed[rows] |= targets.hits[rows] >= min_hits

    def confirm_born(self, targets: Targets, rows: np.ndarray, image_size: tuple[int, int]) -> None:
        """Targets born this frame (``rows``) stay TENTATIVE."""


@dataclass(frozen=True)
class IsolatedEarly:
    """``early_confirm``: a new target is confirmed after ``hits`` matches when its box
    overlaps no other live target's (IoU < ``max_iou``): a lone newcomer is a person, not a
    fragment or a second response of one (after ByteTrack and OC-SORT, which report a track
    from its first frames); otherwise after ``life_cycle.min_hits``. With ``hits`` 1 a lone
    newcomer is confirmed at its birth (``confirm_born``), as reta's ``early_confirm`` 1
    starts a confirmed track; with ``border_waits`` (``adaptations.border_birth_waits``) not
    one whose box touches an image border (within 1 pixel, as ``exits.BorderExit``): a
    person partly outside the picture, stepping in, whose first box is a sliver of him."""

    hits: int
    max_iou: float = 0.1
    border_waits: bool = False

    def confirm(self, targets: Targets, rows: np.ndarray, min_hits: int) -> None:
        InARow().confirm(targets, rows, min_hits)
        early = rows[(targets.hits[rows] >= self.hits) & ~targets.confirmed[rows]]
        if not len(early):
            return
        targets.confirmed[early[self._alone(targets, early)]] = True

    def confirm_born(self, targets: Targets, rows: np.ndarray, image_size: tuple[int, int]) -> None:
        """With ``hits`` 1, the targets born this frame (``rows``) that overlap no other
        live target (those born with them included) are confirmed at once: their first
        match is the one that confirms them (``border_waits``: unless at a border of the
        (W, H) ``image_size``)."""
        if self.hits == 1 and len(rows):
            ok = self._alone(targets, rows)
            if self.border_waits:
                ok &= ~touches_border(targets.boxes[rows], *image_size)
            targets.confirmed[rows[ok]] = True

    def _alone(self, targets: Targets, rows: np.ndarray) -> np.ndarray:
        """(len(rows),) bool: the box of each target at ``rows`` overlaps no other's."""
        iou = iou_matrix(targets.boxes[rows], targets.boxes)
        iou[np.arange(len(rows)), rows] = 0.0  # a target does not overlap itself
        return iou.max(axis=1) < self.max_iou
