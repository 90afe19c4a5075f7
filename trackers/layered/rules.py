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

from trackers.common.noise import KalmanNoiseML
from trackers.layered.model import Targets
from trackers.layered.params import Adaptations, NoiseParams
from trackers.layered.parts import PartFeatures
from trackers.layered.selection import FrameScores

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


# --------------------------------------------------------------- PBM 3-4: which candidates


class RectangleGate:
    """PBM 3 as written: a target may take any candidate in KF1's gate rectangle."""

    def reset(self) -> None:
        return None

    def withhold(self, frame: int, scores: FrameScores, boxes: np.ndarray,
                 targets: Targets) -> None:
        return None

    def found(self, frame: int, ids: np.ndarray, boxes: np.ndarray, alive: np.ndarray) -> None:
        return None


class PositionGate:
    """``position_gate``: a target found last frame takes no candidate whose box centre lies
    outside ``probability`` of its predicted centre: y' S^-1 y > the chi-square 2-dof
    quantile -2 ln(1 - probability), with the prediction and S of a constant-velocity box
    filter whose noises ``KalmanNoiseML`` estimates from the targets' matched boxes of this
    sequence (``prior``, KF1's noises, until the data beat them). KF1 is unchanged.

    Args:
        probability: the gate's probability, in (0, 1).
        prior: KF1's (position, velocity, measurement) noise per h/10.
        initial_velocity_std: KF1's prior rate standard deviation per h/10.
    """

    def __init__(self, probability: float, prior: tuple[float, float, float],
                 initial_velocity_std: float = 1.0) -> None:
        self.threshold = -2.0 * np.log1p(-float(probability))  # chi-square 2 dof quantile
        self.noise = KalmanNoiseML(prior, initial_velocity_std**2)

    def reset(self) -> None:
        self.noise.reset()

    def withhold(self, frame: int, scores: FrameScores, boxes: np.ndarray,
                 targets: Targets) -> None:
        """Strikes from ``scores.S`` (T, N), in place, the pairs of targets found last frame
        whose box (``pair_boxes``; ``boxes`` (N, 4) xywh the candidates') has its centre
        beyond the quantile."""
        S = scores.S
        ti, n = (np.isfinite(S) & (targets.misses == 0)[:, None]).nonzero()
        if not len(ti):
            return
        centres = pair_boxes(scores, boxes, ti, n)
        centres = centres[:, :2] + centres[:, 2:] / 2
        mean, var = self.noise.predicted(frame, targets.id[ti].tolist())
        d2 = ((centres - mean) ** 2).sum(axis=1) / var                       # y' S^-1 y
        far = d2 > self.threshold
        S[ti[far], n[far]] = -np.inf

    def found(self, frame: int, ids: np.ndarray, boxes: np.ndarray, alive: np.ndarray) -> None:
        """The boxes (M, 4) xywh the targets ``ids`` (M,) were matched to (``pair_boxes``)
        or born from at ``frame`` enter the estimate; tracks not in ``alive`` (the live ids)
        are forgotten."""
        self.noise.forget(set(alive.tolist()))
        self.noise.measure(frame, ids.tolist(), boxes)


def pair_boxes(scores: FrameScores, boxes: np.ndarray, ti: np.ndarray, n: np.ndarray
               ) -> np.ndarray:
    """(K, 4) xywh box of each (target ti[k], candidate n[k]) pair as the model update takes
    it: the carved box of a searched pair (``scores.hyp`` >= 0; PBM 3.1), else the
    candidate's (``boxes`` (N, 4))."""
    out = boxes[n].copy()
    h = scores.hyp[ti, n]
    if (h >= 0).any():
        out[h >= 0] = scores.dof_h[h[h >= 0]][:, [0, 1, 4, 5]]
    return out


class Rules(NamedTuple):
    """One strategy per step an adaptation changes."""

    compared: LastModels | PredictedModels
    match: AnyAboveThreshold | RelativeMatch
    birth: AnyCandidate | ForegroundSupport
    report_box: LastBox | PredictedBox
    position: RectangleGate | PositionGate


def build_rules(a: Adaptations, noise: NoiseParams | None = None) -> Rules:
    """The paper's rule where the adaptation is off (false, 0), ours where it is on;
    ``noise``: the filters' noises (KF1's: the prior of an estimate; None: the defaults)."""
    kf1_noise = (noise or NoiseParams()).kf1
    return Rules(
        compared=PredictedModels() if a.motion_compensation else LastModels(),
        match=RelativeMatch(a.relative_match) if a.relative_match > 0 else AnyAboveThreshold(),
        birth=ForegroundSupport(a.min_support) if a.min_support > 0 else AnyCandidate(),
        report_box=PredictedBox() if a.report_predicted else LastBox(),
        position=PositionGate(a.position_gate, kf1_noise) if a.position_gate > 0 else RectangleGate(),
    )
