"""The steps an adaptation changes, as small strategy objects: the paper's rule and ours.

``build_rules`` picks one of each from ``adaptations.Adaptations`` once, in the tracker's
constructor, so ``PBMTracker.update`` calls a rule instead of testing a flag. Each pair
names the step of PBM it replaces; ``docs/adaptations.md`` gives the evidence. (Stale
parts are ``adaptations.StaleParts`` or None; the pruning adaptations live in
``selection.MultipleResponsePruning``, the blob-head ones in ``candidates``, PBM 3.1's
smaller region in ``smaller``, the exits in ``exits``, confirmation in
``confirmation``, the model update at a contact in ``contact``.) Boxes are (N, 4)
float64 xywh pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from occbench.trackers.common.assignment import assign
from occbench.trackers.common.measured_velocity import FilterPrediction, MeasuredVelocity
from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.confirmation import InARow, IsolatedEarly
from occbench.trackers.layered.contact import (AsMatched, ColourAtContact, ContactOcclusion,
                                              FrozenAtContact, SizeOcclusion)
from occbench.trackers.layered.evidence import (HiddenEvidence, MissesBound, ReportedBehind,
                                               box_foreground)
from occbench.trackers.layered.exits import (
    BorderExit,
    LeavingUnreported,
    PredictedExit,
    ReportAnywhere,
)
from occbench.trackers.layered.params import ReportParams
from occbench.trackers.layered.parts import PartFeatures
from occbench.trackers.layered.placement import CameraPlacement
from occbench.trackers.layered.record import ReportedByRecord
from occbench.trackers.layered.lost import AllAtOnce, ReportedFirst
from occbench.trackers.layered.reupdate import AfterPrediction, ReUpdate
from occbench.trackers.layered.search import Candidates, match_head_template
from occbench.trackers.layered.merges import AllHolders, FoundElsewhere
from occbench.trackers.layered.smaller import LoneShrink, OccludedSmaller
from occbench.trackers.layered.stacked import FoldTwins, KeepStacked
from occbench.trackers.layered.targets import Targets

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


class AsMeasured:
    """Eq. 11 as written after a gap too: d_ij = |f_ij - F_ij| whatever the frames between."""

    def misses(self, targets: Targets) -> None:
        return None


class PerFrame:
    """``gap_division``: after m frames unfound, eq. 11's displacement and overlap are
    divided by 1 + m (per-frame differences, as the models were fitted on)."""

    def misses(self, targets: Targets) -> np.ndarray:
        """(T,) frames since each target was last found (``association.pair_scores``)."""
        return targets.misses


# --------------------------------------------------------------- PBM 3, eq. 8: KF2 unfound


class PredictedSize:
    """Eq. 8 as written: KF2 keeps predicting an unfound target's size with its rates."""

    def missed(self, targets: Targets, rows: np.ndarray) -> None:
        targets.mark_missed(rows)


class HeldSize:
    """``hold_size``: KF2's size rates are zeroed while a target is unfound, so the
    predicted size of a hidden person is held, not extrapolated (its search boxes, eqs.
    9-10, and occlusion test, PBM 3.1, use that size)."""

    def missed(self, targets: Targets, rows: np.ndarray) -> None:
        targets.mark_missed(rows)
        targets.kf2.x[rows, 2:] = 0.0


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


@dataclass(frozen=True)
class RivalMatch:
    """``relative_match`` and ``rival_match``: as ``RelativeMatch``, and a target found last
    frame takes no candidate scoring below ``rival`` x its last match's score when another
    target may take that candidate (scores it >= ``match_threshold`` and is not so held
    back itself): a neighbour whose own detection was missed does not take a person that
    another target is there for (one person's box over another's, issue 28 item 1)."""

    fraction: float
    rival: float

    def withhold(self, S: np.ndarray, targets: Targets, match_threshold: float) -> np.ndarray | None:
        """As ``RelativeMatch.withhold``; the rival-held pairs are struck from S too, but
        their candidates are not withheld (a rival takes them)."""
        withheld = RelativeMatch(self.fraction).withhold(S, targets, match_threshold)
        if withheld is None:
            return None
        ref = np.where(targets.misses == 0, targets.score, 0.0)
        ok = S >= match_threshold
        low = ok & (S < self.rival * ref[:, None])
        S[low & (ok & ~low).any(axis=0)] = -np.inf
        return withheld


# --------------------------------------------------------------- PBM 4 step 4: who takes what


class Alone:
    """PBM 3, 4 step 4 as the paper runs them, one target at a time: each target takes its
    best candidate with p >= ``match_threshold`` whatever the other targets take (two
    targets may take one candidate)."""

    def assign(self, cost: np.ndarray, max_cost: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(T, N) costs 1 - p (inf outside the gates) -> matches (K, 2) (target,
        candidate), unmatched targets, candidates no target takes (as ``assign``)."""
        T, N = cost.shape
        if T == 0 or N == 0:
            return np.zeros((0, 2), dtype=int), np.arange(T), np.arange(N)
        best = np.argmin(cost, axis=1)
        ok = cost[np.arange(T), best] <= max_cost
        matches = np.column_stack([ok.nonzero()[0], best[ok]]).astype(int)
        taken = np.zeros(N, dtype=bool)
        taken[best[ok]] = True
        return matches, (~ok).nonzero()[0], (~taken).nonzero()[0]


class OneToOne:
    """``one_to_one``: targets share candidates one-to-one, the Hungarian method on 1 - p
    keeping as many pairs as possible, then the cheapest (``common.assignment.assign``)."""

    def assign(self, cost: np.ndarray, max_cost: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return assign(cost, max_cost)


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


# --------------------------------------------------------------- reporting: is the unfound target there


class ReportUnfound:
    """A confirmed unfound target is reported for ``reporting.max_misses`` frames."""

    def shown(self, boxes: np.ndarray, fg: np.ndarray | None, hits: np.ndarray,
              misses: np.ndarray) -> None:
        return None


@dataclass(frozen=True)
class ReportOnForeground:
    """``report_support``: with a foreground mask, an unfound target is reported only while
    its reported box holds at least ``fraction`` foreground: a hidden person is behind
    someone (whose pixels are foreground) or undetected in view (its own are); a box on bare
    floor holds nobody."""

    fraction: float

    def shown(self, boxes: np.ndarray, fg: np.ndarray | None, hits: np.ndarray,
              misses: np.ndarray) -> np.ndarray | None:
        """(R,) bool per (R, 4) xywh box, None without a mask (``misses`` 0: found)."""
        if fg is None:
            return None
        return (misses == 0) | (box_foreground(boxes, fg) >= self.fraction)


# --------------------------------------------------------------- PBM 4.1: a candidate two targets may take


@dataclass(frozen=True)
class NoContest:
    """PBM 4 step 4 as written: a candidate that several targets may take is left to the
    assignment (4.1's pruning looks along one target's candidates only)."""

    def settle(self, S: np.ndarray, cand: Candidates, targets: Targets, frame: np.ndarray,
               match_threshold: float, template_threshold: float) -> None:
        return None


@dataclass(frozen=True)
class TemplateContest:
    """``contested_template``: PBM 4.1's head template turned to a candidate's column. A
    candidate region that several targets may take (each scores it p >= match_threshold,
    eq. 13, and within ``margin`` of the best: p >= p_best / margin) is one merged or
    shared region; the targets whose head templates are fresh (found within
    ``prune_max_misses`` frames) are matched at its head (``match_head_template``, within
    half a template width and 2 pixels), and only the best correlating one may take it when
    it reaches ``template_threshold``; the others' pairs are struck from S. Targets with a
    stale or no template keep their pairs."""

    margin: float
    prune_max_misses: int

    def settle(self, S: np.ndarray, cand: Candidates, targets: Targets, frame: np.ndarray,
               match_threshold: float, template_threshold: float) -> None:
        """Strikes the losing pairs from the (T, N) scores S in place."""
        if S.shape[0] < 2:
            return
        for n in range(S.shape[1]):
            col = S[:, n]
            rivals = np.flatnonzero(col >= match_threshold)
            if len(rivals) < 2:
                continue
            rivals = rivals[col[rivals] * self.margin >= col[rivals].max()]
            fresh = [t for t in rivals.tolist() if targets.head_template[t] is not None
                     and targets.misses[t] <= self.prune_max_misses]
            if len(fresh) < 2:
                continue
            hx, hy = float(cand.head[n, 0]), float(cand.head[n, 1])
            corr = []
            for t in fresh:
                tw = targets.head_template[t].shape[1]
                corr.append(match_head_template(frame, targets.head_template[t],
                                                (hx - 0.5 * tw, hy), 0.5 * tw + 2)[1])
            k = int(np.argmax(corr))
            if corr[k] < template_threshold:
                continue
            S[[t for j, t in enumerate(fresh) if j != k], n] = -np.inf


class Rules(NamedTuple):
    """One strategy per step an adaptation changes."""

    compared: LastModels | PredictedModels
    match: AnyAboveThreshold | RelativeMatch | RivalMatch
    birth: AnyCandidate | ForegroundSupport
    report_box: LastBox | PredictedBox
    gap: AsMeasured | PerFrame
    unfound_size: PredictedSize | HeldSize
    sharing: Alone | OneToOne
    report_shown: ReportUnfound | ReportOnForeground | HiddenEvidence
    confirmation: InARow | IsolatedEarly
    reupdate: AfterPrediction | ReUpdate
    contest: NoContest | TemplateContest  # a candidate several targets may take (PBM 4.1)
    smaller: OccludedSmaller | LoneShrink  # a region smaller than predicted (PBM 3.1)
    merge: AllHolders | FoundElsewhere  # a larger region whose other holders are found (3.1)
    exit: PredictedExit | BorderExit  # an unfound target that left the picture (ours)
    leaving: ReportAnywhere | LeavingUnreported  # an unfound target walking out: reported?
    twins: KeepStacked | FoldTwins  # a target standing on an older one's person (ours)
    velocity: FilterPrediction | MeasuredVelocity | CameraPlacement  # where unfound (ours)
    behind: MissesBound | ReportedBehind | ReportedByRecord  # past reporting.max_misses? (ours)
    lost: AllAtOnce | ReportedFirst  # lost targets' share of the candidates (PBM 4 step 4)
    contact: AsMatched | FrozenAtContact | ColourAtContact  # which parts learn (PBM 4.2)
    window: SizeOcclusion | ContactOcclusion  # whose global model is window-averaged (4.2)


def build_rules(a: Adaptations, max_misses: int = ReportParams.max_misses) -> Rules:
    """The paper's rule where the adaptation is off (false, 0), ours where it is on;
    ``max_misses``: ``reporting.max_misses`` (frames an unfound target is reported)."""
    return Rules(
        compared=PredictedModels() if a.motion_compensation else LastModels(),
        match=(RivalMatch(a.relative_match, a.rival_match) if a.rival_match > 0 else
               RelativeMatch(a.relative_match) if a.relative_match > 0 else AnyAboveThreshold()),
        birth=ForegroundSupport(a.min_support) if a.min_support > 0 else AnyCandidate(),
        report_box=PredictedBox() if a.report_predicted else LastBox(),
        gap=PerFrame() if a.gap_division else AsMeasured(),
        unfound_size=HeldSize() if a.hold_size else PredictedSize(),
        sharing=OneToOne() if a.one_to_one else Alone(),
        report_shown=a.hidden_evidence or (ReportOnForeground(a.report_support)
                                           if a.report_support > 0 else ReportUnfound()),
        confirmation=(IsolatedEarly(a.early_confirm, border_waits=a.border_birth_waits)
                      if a.early_confirm > 0 else InARow()),
        reupdate=ReUpdate(a.reupdate) if a.reupdate > 0 else AfterPrediction(),
        contest=(TemplateContest(a.contested_template, a.prune_max_misses)
                 if a.contested_template > 0 else NoContest()),
        smaller=(LoneShrink(a.lone_shrink, a.lone_shrink_shape, a.lone_shrink_narrow)
                 if a.lone_shrink > 0
                 else OccludedSmaller()),
        merge=(FoundElsewhere(a.merge_recent_holder, a.merge_found_elsewhere)
               if a.merge_found_elsewhere or a.merge_recent_holder else AllHolders()),
        exit=BorderExit() if a.border_exit else PredictedExit(),
        leaving=(LeavingUnreported(a.leaving_unreported) if a.leaving_unreported >= 0
                 else ReportAnywhere()),
        twins=FoldTwins(a.fold_twins, a.fold_twins_own) if a.fold_twins > 0 else KeepStacked(),
        velocity=(CameraPlacement() if a.camera_placement else
                  MeasuredVelocity() if a.measured_velocity else FilterPrediction()),
        behind=(ReportedByRecord() if a.reported_by_record else
                ReportedBehind(a.reported_behind) if a.reported_behind > 0 else MissesBound()),
        lost=(ReportedFirst(max_misses, a.reported_first_stay, a.reported_first_head) if a.reported_first
              else AllAtOnce()),
        contact=(FrozenAtContact(a.contact_frozen) if a.contact_frozen > 0 else
                 ColourAtContact(a.contact_colour) if a.contact_colour > 0 else AsMatched()),
        window=ContactOcclusion(a.contact_occluded) if a.contact_occluded > 0 else SizeOcclusion(),
    )


def reset_rules(rules: Rules) -> None:
    """Forget the records the stateful rules keep (``measured_velocity``,
    ``camera_placement``, ``reported_by_record``): a new sequence, a new camera."""
    rules.velocity.reset()
    rules.behind.reset()


def place_unfound(rule: FilterPrediction | MeasuredVelocity | CameraPlacement, frame: int,
                  targets: Targets, rows: np.ndarray, boxes: np.ndarray, found: np.ndarray) -> None:
    """``rules.velocity`` (``adaptations.measured_velocity``, ``camera_placement``): record
    the found confirmed targets' boxes among ``rows`` with KF1's velocities, and move the boxes (R, 4) of the
    unfound ones in place where their measured velocity has predicted better; found (T,)
    bool. Reporting only: no target's state changes."""
    seen = found[rows] & targets.confirmed[rows]
    rule.found(frame, targets.id[rows[seen]].tolist(), boxes[seen], targets.kf1.x[rows[seen], 2:4])
    hidden = ~found[rows]
    if hidden.any():
        moved = boxes[hidden]
        rule.place(frame, targets.id[rows[hidden]].tolist(), moved,
                   targets.kf1.x[rows[hidden], 2:4])
        boxes[hidden] = moved
    rule.forget(set(targets.id.tolist()))
