"""The steps an adaptation changes, as small strategy objects: the paper's rule and ours.

``build_rules`` picks one of each from ``params.Adaptations`` once, in the tracker's
constructor, so ``PBMTracker.update`` calls a rule instead of testing a flag. Each pair
names the step of PBM it replaces; ``docs/adaptations.md`` gives the evidence. (Stale
parts are ``params.StaleParts`` or None; the pruning adaptations live in
``selection.MultipleResponsePruning``.) Boxes are (N, 4) float64 xywh pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from trackers.geometry import iou_matrix
from trackers.layered.model import Targets
from trackers.layered.params import Adaptations
from trackers.layered.parts import PartFeatures

# --------------------------------------------------------------- eq. 11: the model compared


class LastModels:
    """Eq. 11 as written: candidates are compared with the parts models as last updated."""

    def models(self, targets: Targets) -> PartFeatures:
        return targets.parts


class PredictedModels:
    """``motion_compensation``: with the parts models moved by KF1's constant-velocity
    prediction since each target was last found (the gate stays zero-order, PBM 3)."""

    def models(self, targets: Targets) -> PartFeatures:
        return targets.parts.shifted(targets.predicted_shift())


# --------------------------------------------------------------- PBM 4 step 4: a match


class AnyAboveThreshold:
    """PBM 4 step 4 as written: any candidate above ``match_threshold`` may match."""

    def withhold(self, S: np.ndarray, targets: Targets, match_threshold: float) -> None:
        return None


@dataclass(frozen=True)
class RelativeMatch:
    """``relative_match``: a target found last frame takes no candidate scoring below
    ``fraction`` x the score of that match (its own detection missed, a neighbour's is no
    match)."""

    fraction: float

    def withhold(self, S: np.ndarray, targets: Targets, match_threshold: float) -> np.ndarray | None:
        """Strikes such pairs from the (T, N) scores S in place; returns the (N,)
        candidates so withheld (they start no target), None when S is empty."""
        if not S.size:
            return None
        ref = np.where(targets.misses == 0, targets.score, 0.0)
        weak = (S < self.fraction * ref[:, None]) & (S >= match_threshold)
        S[weak] = -np.inf
        return weak.any(axis=0)


# --------------------------------------------------------------- PBM 2: who may start a target


class AnyCandidate:
    """Any free candidate may start a target (the paper starts them by hand)."""

    def supported(self, part_foreground: np.ndarray, has_foreground: bool) -> bool:
        return True


@dataclass(frozen=True)
class ForegroundSupport:
    """``min_support``: with foreground, a candidate starts a target only when one of its
    parts holds at least ``fraction`` foreground (PBM 2: people are foreground)."""

    fraction: float

    def supported(self, part_foreground: np.ndarray, has_foreground: bool) -> bool:
        """``part_foreground``: (5,) foreground fraction of each part (``PartFeatures.area``)."""
        return not (has_foreground and part_foreground.max() < self.fraction)


# --------------------------------------------------------------- reporting: an unfound target


class LastBox:
    """An unfound target is reported at its last validated box."""

    def place(self, boxes: np.ndarray, targets: Targets, rows: np.ndarray, found: np.ndarray) -> None:
        return None


class PredictedBox:
    """``report_predicted``: an unfound target is reported at its last box moved by KF1's
    constant-velocity prediction since it was last found."""

    def place(self, boxes: np.ndarray, targets: Targets, rows: np.ndarray, found: np.ndarray) -> None:
        """Moves ``boxes`` (R, 4) of the targets at ``rows`` in place; found (T,) bool."""
        boxes[:, :2] += np.where(found[rows, None], 0.0, targets.predicted_shift()[rows])


# --------------------------------------------------------------- life cycle: stacked targets


class KeepStacked:
    """Targets whose boxes coincide are left as they are (the paper tracks each by hand)."""

    def reset(self) -> None:
        return None

    def ended(self, targets: Targets, boxes: np.ndarray, rows: np.ndarray) -> np.ndarray:
        return np.zeros(0, dtype=np.intp)


class MergeStacked:
    """``merge_stacked``: two reported targets whose boxes coincide (IoU >= ``iou``) for
    ``frames`` frames in a row, in which each was found while the other was not and never
    both in one frame, are one person taking its one detection in turn: the one with fewer
    matches (hits; then the younger id) is ended. A person hidden behind another is never
    found while covered, and two people are found together as soon as both are detected.

    State (per pair of ids, reset with the tracker): frames stacked in a row, whether each
    was found alone, whether both were found together.
    """

    def __init__(self, frames: int, iou: float = 0.5) -> None:
        if frames < 1:
            raise ValueError(f"MergeStacked: frames must be >= 1, got {frames!r}")
        self.frames, self.iou = int(frames), float(iou)
        self.reset()

    def reset(self) -> None:
        self._pairs: dict[tuple[int, int], tuple[int, bool, bool, bool]] = {}

    def ended(self, targets: Targets, boxes: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """Rows of ``targets`` to end this frame.

        Args:
            boxes: (R, 4) xywh reported boxes of the targets at ``rows`` (R,), as reported
                (an unfound target where it is predicted).
        """
        pairs: dict[tuple[int, int], tuple[int, bool, bool, bool]] = {}
        end: set[int] = set()
        if len(rows) >= 2:
            stacked = np.triu(iou_matrix(boxes, boxes) >= self.iou, 1)
            ids, found, hits = targets.id, targets.misses == 0, targets.hits
            for x, y in zip(*np.nonzero(stacked)):
                a, b = int(rows[x]), int(rows[y])
                key = (int(ids[a]), int(ids[b]))
                run, a_alone, b_alone, both = self._pairs.get(key, (0, False, False, False))
                fa, fb = bool(found[a]), bool(found[b])
                state = (run + 1, a_alone or (fa and not fb), b_alone or (fb and not fa),
                         both or (fa and fb))
                pairs[key] = state
                if state[0] >= self.frames and state[1] and state[2] and not state[3]:
                    end.add(b if (hits[a], -ids[a]) >= (hits[b], -ids[b]) else a)
        self._pairs = pairs
        return np.array(sorted(end), dtype=np.intp)


class Rules(NamedTuple):
    """One strategy per step an adaptation changes."""

    compared: LastModels | PredictedModels
    match: AnyAboveThreshold | RelativeMatch
    birth: AnyCandidate | ForegroundSupport
    report_box: LastBox | PredictedBox
    stacked: KeepStacked | MergeStacked


def build_rules(a: Adaptations, min_hits: int) -> Rules:
    """The paper's rule where the adaptation is off (false, 0), ours where it is on
    (``min_hits``: ``life_cycle.min_hits``, the frames ``merge_stacked`` waits)."""
    return Rules(
        compared=PredictedModels() if a.motion_compensation else LastModels(),
        match=RelativeMatch(a.relative_match) if a.relative_match > 0 else AnyAboveThreshold(),
        birth=ForegroundSupport(a.min_support) if a.min_support > 0 else AnyCandidate(),
        report_box=PredictedBox() if a.report_predicted else LastBox(),
        stacked=MergeStacked(min_hits) if a.merge_stacked else KeepStacked(),
    )
