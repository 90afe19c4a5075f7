"""Tentative tracks (3.3): who of them enters association stage 2, and when one is
confirmed; the paper's rule (or reading, ``life_cycle.confirm_frames``) and ours beside each
(``adaptations.tentative_stage1_only``, ``adaptations.early_confirm``), ``rules.build_rules``
picks one. Ours (``adaptations.early_confirm``) against late confirmation (issue 28: with 30% of detections missed, people in view
from a clip's first frame and newcomers stay tentative for their first 3-7 frames);
``docs/adaptations.md`` gives the evidence. Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from scipy.sparse import csr_array

from occbench.trackers.common.spatial import meeting_pairs
from occbench.trackers.three_hypothesis import _shares as shares

# --------------------------------------------------------------- 3.3.2 steps 5-8: who enters stage 2


@dataclass(frozen=True)
class EveryNodeInStage2:
    """Alg. 1 as written: every node of t-1 left unassociated by stage 1, tentative tracks'
    too, competes in stage 2 (MaxSimilarity(n_j, N^{t-1} \\ Assoc))."""

    def entrants(self, confirmed: np.ndarray) -> None:
        return None  # associate() lets every person in


@dataclass(frozen=True)
class ConfirmedInStage2:
    """``tentative_stage1_only``: a tentative track is matched in stage 1 only (it has no
    velocity to justify a jump through the gate)."""

    def entrants(self, confirmed: np.ndarray) -> np.ndarray:
        """(P,) bool: the persons that may take part in stage 2, from (P,) ``confirmed``."""
        return confirmed


# --------------------------------------------------------------- 3.3: when a tentative track is confirmed


@dataclass(frozen=True)
class AfterMatches:
    """3.3 as read (``LifeCycle.confirm_frames``): a tentative track is confirmed after
    ``confirm_frames`` matches, whatever its measurements."""

    uses_clear: ClassVar[bool] = False

    def confirms(self, hits: int, confirm_frames: int, clear: bool, score: float) -> bool:
        return hits >= confirm_frames


def clear_measurements(dets: np.ndarray, rows: np.ndarray, delta: csr_array,
                       owners: np.ndarray, row_owners: np.ndarray) -> np.ndarray:
    """(R,) bool: measurement ``rows[r]`` (distinct rows) of (D, 4) xywh ``dets`` meets no
    other measurement (their boxes share no area) and no predicted region of another person
    (eq. 5 delta 0). ``delta``: sparse (B, D) region similarity of the nodes of t-1 and the
    measurements;
    ``owners``: (B,) person of each node; ``row_owners``: (R,) person of row r (-1: none,
    every node is another's). Memory grows with the pairs that meet."""
    crowded = np.zeros(len(rows), dtype=bool)
    ia, ib = meeting_pairs(dets[rows], dets)
    crowded[ia[ib != rows[ia]]] = True  # a box meets itself
    column = np.full(delta.shape[1], -1)  # measurement -> its index in rows
    column[rows] = np.arange(len(rows))
    shares.crowded_by_others(*shares.csr(delta), np.asarray(owners, dtype=np.int64),
                             column.astype(np.int64), np.asarray(row_owners, dtype=np.int64),
                             crowded)  # every stored pair, compiled
    return ~crowded


@dataclass(frozen=True)
class ClearEarly:
    """``early_confirm``: a tentative track is also confirmed after ``matches`` matches
    (fewer than ``confirm_frames``) when this match's measurement is confident (score >=
    ``min_score``) and unambiguous (``clear_measurements``: it meets no other measurement
    and no other person's predicted region), as ByteTrack activates a track at its second
    match and norfair after its ``initialization_delay``; an ambiguous one waits the full
    ``confirm_frames``."""

    matches: int
    min_score: float
    uses_clear: ClassVar[bool] = True  # the tracker measures ``clear_measurements``

    def confirms(self, hits: int, confirm_frames: int, clear: bool, score: float) -> bool:
        """``hits``: matches so far, this one included; ``clear``, ``score``: this match's
        measurement."""
        return hits >= confirm_frames or (
            hits >= self.matches and clear and score >= self.min_score)
