"""What Reta's tracker reports of a hidden person (the output of Alg. 1: Figs. 3-5 draw every
hypothesis): which hypothesis (a reading, ``life_cycle.reported_hypothesis``) and whether it
is reported as OCCLUDED (``ReportRule``: our rules ``report_exposed``, ``report_spread``,
``report_support``, ``report_memory``); ``rules.build_rules`` picks them.
``docs/adaptations.md`` gives the evidence. Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer
from occbench.trackers.three_hypothesis.hypotheses import PRIORITY


@dataclass(frozen=True)
class LeastContradicted:
    """Our reading (``life_cycle.reported_hypothesis``; the paper draws every hypothesis,
    Figs. 3-5): the hypothesis least
    contradicted by Alg. 1's own pruning criterion: covered by a visible person first (it
    explains the missing detection), then fewest frames in plain view, then velocity >
    occluder > still."""

    def choose(self, kinds: list[str], exposed: list[int], covered: list[bool]) -> int:
        """Index of the reported hypothesis among a hidden person's branches."""
        return min(range(len(kinds)),
                   key=lambda i: (not covered[i], exposed[i], PRIORITY.get(kinds[i], 0)))


@dataclass(frozen=True)
class FirstHypothesis:
    """The other reading (``life_cycle.reported_hypothesis``): hypothesis 1 (velocity, the one Alg. 1 makes for every missing
    person) while it lives, then occluder, then still."""

    def choose(self, kinds: list[str], exposed: list[int], covered: list[bool]) -> int:
        return min(range(len(kinds)), key=lambda i: PRIORITY.get(kinds[i], 0))


@dataclass(frozen=True)
class ReportRule:
    """Whether a hidden person's best hypothesis is reported as OCCLUDED (else only drawn).

    ``exposed``: frames it may stand in plain view (the paper: until pruned); ``spread``:
    largest standard deviation of its centre, in person widths (0: any, the paper);
    ``support`` (``report_support``): with a foreground mask, smallest foreground share of
    its ellipse (0: any, the paper): a hidden person is behind someone, whose pixels are
    foreground, or undetected in view on its own; an ellipse mostly on bare floor holds
    nobody."""

    exposed: int
    spread: float
    support: float = 0.0
    memory: float = 0.0  # ``report_memory``: frames unmatched per match, 0: any

    def shares(self, histograms: EllipseHistogrammer, foreground: np.ndarray | None,
               boxes: np.ndarray) -> np.ndarray | None:
        """(N,) foreground share of each (N, 4) xywh hypothesis box's ellipse when
        ``support`` needs it, else None."""
        if self.support <= 0 or foreground is None:
            return None
        return histograms.foreground_share(foreground, boxes)

    def reported(self, hypothesis, hits: int = 1, misses: int = 0) -> bool:
        """``hypothesis``: a hypothesis branch (``covered``, ``exposed``, ``unseen``,
        ``share``, Kalman ``x`` (8,) and ``P`` (8, 8)) of a person matched ``hits`` times
        and unmatched for ``misses`` frames. A region seen empty is never reported; with
        ``memory``, one nobody covers only while misses <= memory x hits."""
        h = hypothesis
        if h.unseen or (not h.covered and h.exposed > self.exposed) or h.share < self.support:
            return False
        if self.memory > 0 and not h.covered and misses > self.memory * hits:
            return False
        P = h.P
        return not (self.spread > 0 and max(P[0, 0], P[1, 1]) > (self.spread * h.x[2]) ** 2)
