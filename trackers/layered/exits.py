"""Which unfound targets have left the picture (our life cycle; the paper tracks a target
"until lost", PBM 3).

``alive_rows`` (the kernel) drops a target whose predicted box crossed an image border
(``adaptations.exit_margin``); ``BorderExit`` (``adaptations.border_exit``) adds a person
who leaves by shrinking where he stands: through a doorway at the image's edge, or walking
out of view slowly, the detections are cut by the border, PBM 3.1 reads each as the target
partly occluded and aligns its predicted-size box on the head, so the box never crosses the
border and the target lives on unfound for ``life_cycle.max_misses`` frames (and takes the
next person through that door). Boxes are xywh pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.layered.targets import Targets


class PredictedExit:
    """Only the predicted box crossing a border (``alive_rows``) tells a target left."""

    def gone(self, targets: Targets, width: int, height: int) -> None:
        return None


@dataclass(frozen=True)
class BorderExit:
    """``border_exit``: an unfound target whose last match was occluded (PBM 3.1: a smaller
    or larger region, its box carved from the prediction) and whose box then touched an
    image border (within ``touch`` pixels of it, or beyond) was hidden by the border, not
    by a person: it has left, and is dropped after ``adaptations.exit_misses`` frames as a
    target whose predicted box left the image is."""

    touch: float = 1.0

    def gone(self, targets: Targets, width: int, height: int) -> np.ndarray:
        """(T,) bool: the targets whose last occluded box touched a border."""
        return targets.occluded & touches_border(targets.dof[:, [0, 1, 4, 5]], width, height,
                                                  self.touch)


def touches_border(boxes: np.ndarray, width: int, height: int, touch: float = 1.0) -> np.ndarray:
    """(N,) bool: the (N, 4) xywh boxes within ``touch`` pixels of a border of the (width,
    height) image, or beyond it."""
    x, y, w, h = boxes[:, 0], boxes[:, 1], boxes[:, 2], boxes[:, 3]
    return (x <= touch) | (y <= touch) | (x + w >= width - touch) | (y + h >= height - touch)


class ReportAnywhere:
    """An unfound target is reported wherever its box lies (the reporting rules of
    ``rules.report_shown`` alone decide)."""

    def shown(self, boxes: np.ndarray, velocity: np.ndarray, found: np.ndarray, width: int,
              height: int, keep: np.ndarray | None) -> np.ndarray | None:
        return keep


@dataclass(frozen=True)
class LeavingUnreported:
    """``leaving_unreported``: an unfound target moving towards an image border (KF1's
    velocity) whose reported box lies within ``margin`` x its width (height) of that border,
    or beyond it, is not reported: unseen where the picture ends, a person walking out has
    left rather than hidden behind someone. Reporting only: the target lives on as before
    (``exit_margin``, ``border_exit``)."""

    margin: float

    def shown(self, boxes: np.ndarray, velocity: np.ndarray, found: np.ndarray, width: int,
              height: int, keep: np.ndarray | None) -> np.ndarray:
        """(R,) bool for the reported (R, 4) xywh ``boxes`` with KF1 velocities (R, 2) and
        found (R,) bool, within ``keep`` (``rules.report_shown``'s, None: all)."""
        x, y, w, h = boxes.T
        vx, vy = velocity.T
        leaving = (((x <= self.margin * w) & (vx < 0))
                   | ((width - (x + w) <= self.margin * w) & (vx > 0))
                   | ((y <= self.margin * h) & (vy < 0))
                   | ((height - (y + h) <= self.margin * h) & (vy > 0)))
        out = found | ~leaving
        return out if keep is None else keep & out
