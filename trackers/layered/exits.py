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
        x, y, w, h = targets.dof[:, 0], targets.dof[:, 1], targets.dof[:, 4], targets.dof[:, 5]
        at_border = ((x <= self.touch) | (y <= self.touch) | (x + w >= width - self.touch)
                     | (y + h >= height - self.touch))
        return targets.occluded & at_border
