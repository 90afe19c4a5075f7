"""When a colour comparator declares its person lost, and which detection it restarts from.

PBM (Section 5.2) says only that mean shift and CCMSPF "lose" their target and are given new
ids (its Table 1: 3 unique IDs and 3.11 ID switches per trajectory for MS); it states no loss
test and no restart. Our reading (``tracker.meanshift.loss``, ``tracker.meanshift.restart``), as
two small strategy objects of ``ColourTrackerBase``:

* ``loss``: each frame the comparator reports the Bhattacharyya coefficient rho of its
  followed box's colour with the target's model q (mean shift: at convergence; the particle
  filter: at its posterior-mean box). ``SimilarityBelow(threshold, frames)`` declares the
  target lost after ``frames`` frames in a row with rho < ``threshold``; ``NeverLost`` never
  does (a target then ends only when its centre leaves the image).
* ``restart``: after a loss the tracker starts again from a detection of a later update (the
  same frame's included). ``AnyDetection`` takes the detections in the detection source's
  order, as a first start does; ``MostSimilar(min_similarity)`` takes, while a loss is
  unanswered, only a detection whose colour model has rho >= ``min_similarity`` with the lost
  target's q, the most similar first (the comparator's own cue: colour). The restarted target
  takes the detection's own colour model, as a first start does.

``SimilarityBelow(0.5, 11)`` with ``AnyDetection`` is the comparators' rule before these
objects existed (``min_similarity=0.5``, ``max_misses=10``). docs/adaptations.md ("PBM's
comparators") gives the values the tables use and the evidence.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from occbench.trackers.common.checks import at_least, unit


@dataclass(frozen=True)
class NeverLost:
    """The colour never ends a target: a follower keeps its box wherever it drifts."""

    def missed(self, similarity: float) -> bool:
        """Whether a frame whose followed box has Bhattacharyya ``similarity`` is a miss."""
        return False

    def lost(self, misses: int) -> bool:
        """Whether ``misses`` misses in a row end the target."""
        return False


@dataclass(frozen=True)
class SimilarityBelow:
    """Lost after ``frames`` frames in a row with rho < ``threshold``.

    Args:
        threshold: Bhattacharyya coefficient of the followed box with the model q below which
            a frame is a miss, in [0, 1].
        frames: misses in a row that end the target (k), >= 1.
    """

    threshold: float = 0.5
    frames: int = 11

    def __post_init__(self) -> None:
        unit("loss", threshold=self.threshold)
        at_least("loss", 1, frames=self.frames)

    def missed(self, similarity: float) -> bool:
        """Whether a frame whose followed box has Bhattacharyya ``similarity`` is a miss."""
        return similarity < self.threshold

    def lost(self, misses: int) -> bool:
        """Whether ``misses`` misses in a row end the target."""
        return misses >= self.frames


@dataclass(frozen=True)
class AnyDetection:
    """A restart (like any start) takes the detections in the source's order."""

    def order(self, models: np.ndarray, lost: np.ndarray | None) -> np.ndarray:
        """Detections' indices in the order they may start targets.

        Args:
            models: (n, MODEL_BINS) float64 colour models of the detections' boxes.
            lost: (MODEL_BINS,) the last lost target's model q while no restart answered
                its loss, else None.
        Returns:
            (m,) int64 indices into ``models``.
        """
        return np.arange(len(models))


@dataclass(frozen=True)
class MostSimilar:
    """After a loss, only detections of the lost target's colour, the most similar first.

    Args:
        min_similarity: rho(q_lost, p_detection) a detection needs to restart from, in [0, 1].
    """

    min_similarity: float = 0.0

    def __post_init__(self) -> None:
        unit("restart", min_similarity=self.min_similarity)

    def order(self, models: np.ndarray, lost: np.ndarray | None) -> np.ndarray:
        """As ``AnyDetection.order``; with ``lost`` given, the indices with rho >=
        ``min_similarity`` by decreasing rho (ties in the source's order)."""
        if lost is None:
            return np.arange(len(models))
        rho = np.sqrt(models * lost[None]).sum(axis=1)  # Bhattacharyya coefficient
        order = np.argsort(-rho, kind="stable")
        return order[rho[order] >= self.min_similarity]
