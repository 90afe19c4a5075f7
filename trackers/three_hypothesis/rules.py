"""The steps an adaptation changes, as small strategy objects: the paper's rule and ours.

``build_rules`` picks one of each from ``params.Adaptations`` once, in the tracker's
constructor, so ``RetaTracker.update`` calls a rule instead of testing a flag. Each pair
names the step of Reta et al. 2015 it replaces; ``docs/adaptations.md`` gives the evidence.
Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np

from occbench.trackers.common.measured_velocity import FilterPrediction, MeasuredVelocity
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer, Histogram, towards
from occbench.trackers.three_hypothesis.association import absolute_appearance, appearance_margin
from occbench.trackers.three_hypothesis.contact import (
    AnyCover, AnyLeftover, AppearanceAtContact, AppearanceAtSplit, MeasurementAppearance,
    MeasurementMotion, MergedAppearance, MergedMotion, NearerCover, RegionAtContact, RegionAtSplit,
    SplitParts, UnmixedAppearance, VisibleRegion, WholeRegion)
from occbench.trackers.three_hypothesis.measured_line import FilterVelocity, MeasuredLine
from occbench.trackers.three_hypothesis.motion import (
    BoxState,
    CentreState,
    CorrectedBehind,
    MotionModel,
    PredictedBehind,
)
from occbench.trackers.three_hypothesis.params import Adaptations, LifeCycle
from occbench.trackers.three_hypothesis.reported import FirstHypothesis, LeastContradicted, ReportRule
from occbench.trackers.three_hypothesis.returning import (EndContradicted, HoldLast, RestoreStill,
                                                           Returning, returning_rule)
from occbench.trackers.three_hypothesis.shape_gate import AnyShape, ShapeGate
from occbench.trackers.three_hypothesis.tentative import (
    AfterMatches,
    ClearEarly,
    ConfirmedInStage2,
    EveryNodeInStage2,
)

# --------------------------------------------------------------- eq. 1: which pixels count


@dataclass(frozen=True)
class AllPixels:
    """Eq. 1 as written: the histogram counts every pixel of the ellipse."""

    def mask(self, foreground: np.ndarray | None) -> None:
        return None


@dataclass(frozen=True)
class ForegroundPixels:
    """``foreground_histograms``: with a foreground mask, count only the ellipse's
    foreground pixels (``EllipseHistogrammer`` falls back to every pixel when fewer than
    ``min_foreground`` of them are foreground)."""

    def mask(self, foreground: np.ndarray | None) -> np.ndarray | None:
        return foreground


# --------------------------------------------------------------- 3.3.2: validation gate


@dataclass(frozen=True)
class FixedGate:
    """3.3.2 as written: the validation gate of every prediction is the circle of radius mu_g."""

    def radii(self, P: np.ndarray, R: np.ndarray) -> None:
        return None  # associate() uses mu_g for every node


@dataclass(frozen=True)
class KalmanGate:
    """``gate_sigmas``: the circle approximating each node's Kalman validation region,
    radius ``sigmas`` x the larger standard deviation of its predicted centre (innovation
    covariance H P H' + R over xc, yc); ``associate`` caps it at mu_g."""

    sigmas: float

    def radii(self, P: np.ndarray, R: np.ndarray) -> np.ndarray | None:
        """(B,) radii from P (B, 8, 8) predicted covariances and R (B,) = R[0, 0] of each
        node's person (R = (sigma_z h)^2 I)."""
        if len(P) == 0:
            return None
        var = np.maximum(P[:, 0, 0], P[:, 1, 1]) + R  # S = H P H' + R, centre terms
        return self.sigmas * np.sqrt(var)


# --------------------------------------------------------------- 3.3.2 step 2: appearance in stage 1


@dataclass(frozen=True)
class AbsoluteAppearance:
    """3.3.2 as written: a stage-1 pair's appearance term is rho itself (eq. 4)."""

    evidence = staticmethod(absolute_appearance)  # (rho, admissible) -> rho


@dataclass(frozen=True)
class AppearanceMargin:
    """``appearance_margin``: a stage-1 pair's appearance term is what rho says for this
    pair against its rivals, rho_ij - max(max_{k != i} rho_kj, max_{l != j} rho_il) over
    the admissible pairs, floored at 0: people who all look alike earn no pair its place,
    so the region term (eq. 5) decides; a pair with no rival keeps rho."""

    evidence = staticmethod(appearance_margin)  # (rho (P, D), admissible (P, D)) -> (P, D)


# --------------------------------------------------------------- 3.3.3: a person matched behind others


@dataclass(frozen=True)
class KeepAppearance:
    """3.3.3 as written: the appearance q of a person behind others is kept constant."""

    uses_visible_share: ClassVar[bool] = False

    def update(self, q: Histogram, p: Histogram, visible: float) -> Histogram:
        return q


@dataclass(frozen=True)
class BlendVisible:
    """``blend_visible``: q moves towards the measurement p by the share v of the measured
    region left visible by the people in front: q <- (1 - v) q + v p (v = 1 replaces q as
    for a person absent from any occlusion, v = 0 keeps it as the paper)."""

    uses_visible_share: ClassVar[bool] = True

    def update(self, q: Histogram, p: Histogram, visible: float) -> Histogram:
        if visible > 0:
            return towards(q, p, visible)  # (1 - v) q + v p, compiled
        return q


@dataclass(frozen=True)
class PredictionShape:
    """3.3.3 as written: the shape of a person behind others is its prediction area."""

    def region(self, estimate: list[float], prediction: np.ndarray) -> np.ndarray:
        return prediction.copy()


@dataclass(frozen=True)
class EstimateShape:
    """``shape_estimate``: the shape of a person behind others is the Kalman estimate, the
    prediction corrected by the (possibly partial) measurement (a bare prediction carries a
    size rate nothing corrects: the person shrinks or swells)."""

    def region(self, estimate: list[float], prediction: np.ndarray) -> np.ndarray:
        return np.array(estimate)


# --------------------------------------------------------------- Alg. 1: what a region's foreground says


@dataclass(frozen=True)
class NoSupport:
    """The paper: a hypothesis is judged by coverage and time alone; the image's foreground
    says nothing."""

    def empty(self, foreground: np.ndarray | None, boxes: np.ndarray) -> None:
        return None


@dataclass(frozen=True)
class ForegroundSupport:
    """``foreground_support``: a region whose ellipse holds less than ``min_foreground``
    foreground is seen to be empty (nobody is there to be occluded, or to be detected)."""

    histograms: EllipseHistogrammer

    def empty(self, foreground: np.ndarray | None, boxes: np.ndarray) -> np.ndarray | None:
        """(N,) bool per box, or None without a mask."""
        if foreground is None:
            return None
        h = self.histograms
        return h.foreground_share(foreground, boxes) < h.min_foreground


# ------------------------------------- Alg. 1: what contradicts a hypothesis in plain view


class NoPresence:
    """The paper: every frame a hypothesis spends in plain view without a detection counts
    towards the m frames after which it is contradicted and pruned."""

    def held(self, foreground: np.ndarray | None, boxes: np.ndarray,
             empty: np.ndarray | None) -> None:
        return None


@dataclass(frozen=True)
class ForegroundPresence:
    """``foreground_presence``: a hypothesis whose ellipse holds at least ``min_foreground``
    foreground is not contradicted by the missing detection (the detector missed a person
    who is there); its frames in plain view do not count towards m."""

    histograms: EllipseHistogrammer

    def held(self, foreground: np.ndarray | None, boxes: np.ndarray,
             empty: np.ndarray | None) -> np.ndarray | None:
        """(N,) bool per box, or None without a mask; ``empty``: the support rule's (N,)
        verdict on the same boxes when it measured them (None: measured here)."""
        if foreground is None:
            return None
        if empty is None:
            empty = ForegroundSupport(self.histograms).empty(foreground, boxes)
        return ~empty


# --------------------------------------------------------------- Alg. 1: two hypotheses at one place


@dataclass(frozen=True)
class KeepDuplicates:
    """Alg. 1 as written: PruneHypothesis removes contradicted, false-positive and departed
    hypotheses only; two at the same place both stay."""

    def duplicate(self, corner: list[float], kept: list[list[float]],
                  velocity: list[float] | None = None,
                  kept_velocities: list[list[float]] | None = None) -> bool:
        return False


@dataclass(frozen=True)
class MergeDuplicates:
    """``merge_duplicates``: a hypothesis at the place of one already kept for the same
    person (every xywh value within half a pixel) is dropped; the kinds come in order of
    preference, so the preferred kind stays."""

    def duplicate(self, corner: list[float], kept: list[list[float]],
                  velocity: list[float] | None = None,
                  kept_velocities: list[list[float]] | None = None) -> bool:
        """``corner``: (4,) xywh of a hypothesis; ``kept``: those kept before it."""
        return any(max(abs(u - v) for u, v in zip(corner, k)) < 0.5 for k in kept)


@dataclass(frozen=True)
class MergeTogether:
    """``duplicates_together``: as ``MergeDuplicates``, and the two must also stay together:
    their velocities (vx, vy, vw, vh) differ by less than half a pixel over the m frames
    PruneHypothesis weighs (|dv| m < 0.5). Hypothesis 3 of a person standing with M's
    velocity a few tenths of a pixel per frame starts within half a pixel of hypothesis 1
    and is not dropped for it; hypothesis 1 drifts away, hypothesis 3 stays."""

    m: int

    def duplicate(self, corner: list[float], kept: list[list[float]],
                  velocity: list[float] | None = None,
                  kept_velocities: list[list[float]] | None = None) -> bool:
        """``velocity`` / ``kept_velocities``: (4,) rates of the hypothesis and of those
        kept before it (None: positions alone, as ``MergeDuplicates``)."""
        for i, k in enumerate(kept):
            if max(abs(u - v) for u, v in zip(corner, k)) >= 0.5:
                continue
            if velocity is None or kept_velocities is None or max(
                    abs(u - v) for u, v in zip(velocity, kept_velocities[i])) * self.m < 0.5:
                return True
        return False


# --------------------------------------------------------------- 3.3 / Fig. 3: a confirmed track's id


@dataclass(frozen=True)
class NewIdentity:
    """Alg. 1 as written: a confirmed track takes a new id; a hidden person comes back only
    by matching one of its hypotheses (Fig. 3(d))."""

    def returning(self, box: np.ndarray, pred: np.ndarray, owners: np.ndarray,
                  candidate: np.ndarray) -> None:
        return None


@dataclass(frozen=True)
class HiddenIdentity:
    """``inherit_hidden_id``: a track confirmed where a hidden confirmed person's hypothesis
    stands (IoU >= 0.5) is that person come back (our reading of Fig. 3, ID -14)."""

    def returning(self, box: np.ndarray, pred: np.ndarray, owners: np.ndarray,
                  candidate: np.ndarray) -> int | None:
        """Index of the person whose node overlaps (4,) xywh ``box`` most, at IoU >= 0.5,
        among ``pred`` (B, 4) node regions of ``owners`` (B,) persons; only persons with
        ``candidate`` (P,) True count. None when there is none."""
        best, best_iou = None, 0.5
        for i, iou in zip(owners.tolist(), iou_matrix(box[None], pred)[0].tolist()):
            if candidate[i] and iou >= best_iou:
                best, best_iou = i, iou
        return best


class Rules(NamedTuple):
    """One rule per step an adaptation (or a reading) changes."""

    pixels: AllPixels | ForegroundPixels
    gate: FixedGate | KalmanGate
    stage2: EveryNodeInStage2 | ConfirmedInStage2
    stage1_appearance: AbsoluteAppearance | AppearanceMargin
    contact: AppearanceAtContact | RegionAtContact  # eq. 4 between people in O (3.3.2)
    parts: AnyLeftover | SplitParts  # what stage 2 may match (3.3.2 steps 5-8)
    region: WholeRegion | VisibleRegion  # eq. 5's region term of a node behind others
    split: RegionAtSplit | AppearanceAtSplit  # whose is which box where a merged pair parts
    line: FilterVelocity | MeasuredLine  # hypothesis 1's velocity (3.3.3, case 1)
    motion: CentreState | BoxState  # M's state (3.2)
    motion_behind: PredictedBehind | CorrectedBehind
    motion_front: MeasurementMotion | MergedMotion  # R of a person in front (3.3.3)
    appearance_behind: KeepAppearance | BlendVisible
    appearance_front: MeasurementAppearance | MergedAppearance | UnmixedAppearance  # 3.3.3
    covered: AnyCover | NearerCover  # whose measurement a nearer one covers (3.3.3)
    shape_behind: PredictionShape | EstimateShape
    identity: NewIdentity | HiddenIdentity  # the id a confirmed track takes
    support: NoSupport | ForegroundSupport
    presence: NoPresence | ForegroundPresence  # what contradicts a hypothesis (Alg. 1)
    duplicates: KeepDuplicates | MergeDuplicates | MergeTogether
    choice: LeastContradicted | FirstHypothesis  # which hypothesis is reported (a reading)
    report: ReportRule
    velocity: FilterPrediction | MeasuredVelocity  # where a reported hidden person stands
    shape: AnyShape | ShapeGate  # which sizes may continue a node (3.3.2)
    confirm: AfterMatches | ClearEarly  # when a tentative track is confirmed (3.3)
    returning: Returning  # the appearance a hidden person needs (3.3.2)
    ending: EndContradicted | HoldLast | RestoreStill  # a person with none left (Alg. 1)


def build_rules(adaptations: Adaptations, histograms: EllipseHistogrammer,
                motion: MotionModel | None = None, life_cycle: LifeCycle | None = None) -> Rules:
    """The rules ``adaptations`` selects (``Adaptations.paper()``: the paper's everywhere),
    M's state over the ``motion`` noises, and ``life_cycle``'s reported hypothesis (the
    groups' defaults when None)."""
    a = adaptations
    motion = MotionModel() if motion is None else motion
    life_cycle = LifeCycle() if life_cycle is None else life_cycle
    first = life_cycle.reported_hypothesis == "first"
    return Rules(
        pixels=ForegroundPixels() if a.foreground_histograms else AllPixels(),
        gate=KalmanGate(a.gate_sigmas) if a.gate_sigmas > 0 else FixedGate(),
        stage2=ConfirmedInStage2() if a.tentative_stage1_only else EveryNodeInStage2(),
        stage1_appearance=AppearanceMargin() if a.appearance_margin else AbsoluteAppearance(),
        contact=(RegionAtContact() if a.contact_region
                 else RegionAtContact(life_cycle.cover) if a.contact_coincident
                 else AppearanceAtContact()),
        parts=SplitParts(life_cycle.cover) if a.split_parts else AnyLeftover(),
        region=VisibleRegion() if a.visible_region else WholeRegion(),
        split=(AppearanceAtSplit(a.split_appearance_margin, a.split_appearance_parted)
               if a.split_appearance
               else RegionAtSplit()),
        line=(MeasuredLine(life_cycle.m, a.measured_hypothesis_sigmas, a.measured_step,
                           a.merged_line, a.merged_line_shift, a.measured_still)
              if a.measured_hypothesis else FilterVelocity()),
        motion=BoxState(motion) if a.filter_size else CentreState(motion),
        motion_behind=CorrectedBehind() if a.correct_behind else PredictedBehind(),
        motion_front=MergedMotion() if a.merged_motion else MeasurementMotion(),
        appearance_behind=BlendVisible() if a.blend_visible else KeepAppearance(),
        appearance_front=(MeasurementAppearance() if not a.merged_appearance
                          else UnmixedAppearance(a.merged_unmixed_evidence) if a.merged_unmixed
                          else MergedAppearance()),
        covered=NearerCover(life_cycle.cover) if a.covered_appearance else AnyCover(),
        shape_behind=EstimateShape() if a.shape_estimate else PredictionShape(),
        identity=HiddenIdentity() if a.inherit_hidden_id else NewIdentity(),
        support=ForegroundSupport(histograms) if a.foreground_support else NoSupport(),
        presence=ForegroundPresence(histograms) if a.foreground_presence else NoPresence(),
        duplicates=(KeepDuplicates() if not a.merge_duplicates
                    else MergeTogether(life_cycle.m) if a.duplicates_together
                    else MergeDuplicates()),
        choice=FirstHypothesis() if first else LeastContradicted(),
        report=ReportRule(a.report_exposed, a.report_spread, a.report_support,
                          a.report_memory),
        velocity=MeasuredVelocity() if a.measured_velocity else FilterPrediction(),
        shape=ShapeGate(a.shape_gate) if a.shape_gate > 0 else AnyShape(),
        confirm=(ClearEarly(a.early_confirm, a.early_confirm_score) if a.early_confirm
                 else AfterMatches()),
        returning=returning_rule(a.own_return, life_cycle.m, a.return_floor),
        ending=(HoldLast() if a.hold_last else RestoreStill() if a.restore_still
                else EndContradicted()),
    )
