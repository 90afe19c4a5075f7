"""Every rule of ours the PBM paper does not have, and the paper's value of each.

``Adaptations`` holds one field per rule (``docs/adaptations.md``, PBM part: one row each,
with the paper's section, its value and the evidence); ``Adaptations.paper()`` is the paper
as written (``conf/tracker/pbm_paper.yaml`` sets every field to it, so
``Adaptations.changed()`` is empty there). ``rules.build_rules`` turns the fields into the
strategy objects the tracker calls. Readings of the paper where it is silent (not
adaptations: paper mode keeps them) are listed in ``docs/adaptations.md`` too.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from occbench.trackers.common.checks import at_least, coerce, require, unit
from occbench.trackers.layered.evidence import HiddenEvidence
from occbench.trackers.layered.parts import PartFeatures
from occbench.trackers.layered.targets import Targets, stale_parts

UNBOUNDED = 1_000_000
"""The paper's "until found or lost" / "never" for a count or a size."""


@dataclass(frozen=True)
class StaleParts:
    """Stale parts (an adaptation beyond PBM 4.2, ``model.stale_parts``): a visible part
    that fails to match ``frames`` times is re-learned; the paper keeps it frozen until it
    matches.

    Args:
        frames: failures in a row of a visible part before it is re-learned (>= 1).
        cover: a part is visible when at most this fraction of its rectangle lies under
            another target's box (found, or reported unfound) or outside the image.
        fill: ... and its foreground area is at least this fraction of its model's (a part
            behind a wall loses its foreground).
        relearn_rate: running-average step of a re-learned part (1 = replaced).
    """

    frames: int = 3
    cover: float = 0.1
    fill: float = 0.75
    relearn_rate: float = 1.0

    def __post_init__(self) -> None:
        at_least("adaptations.stale", 1, frames=self.frames)
        unit("adaptations.stale", cover=self.cover, fill=self.fill, relearn_rate=self.relearn_rate)
        coerce(self, {"frames": int, "cover": float, "fill": float, "relearn_rate": float})

    def relearn(self, targets: Targets, rows: np.ndarray, cand: PartFeatures, ks: np.ndarray,
                part_scores: np.ndarray, part_threshold: float, occluder_misses: int,
                image_size: tuple[int, int]) -> np.ndarray:
        """The (M, 5) parts of the targets at ``rows``, matched unoccluded to the candidates
        at ``ks`` of ``cand``, to re-learn (``model.stale_parts``, which counts
        ``targets.stale``)."""
        return stale_parts(targets, rows, cand, ks, part_scores, part_threshold, occluder_misses,
                           image_size, self.cover, self.fill, self.frames)


@dataclass(frozen=True)
class Adaptations:
    """Every rule of ours that the paper does not have (``docs/adaptations.md``: one row
    each, with the paper's value and the evidence); ``paper()`` holds the paper's values
    (``tracker=pbm_paper``).

    Args:
        model_spread: p(d | theta) applied to d / model_spread (paper: 1, as fitted).
        motion_compensation: eq. 11's displacement and overlap against the parts model
            moved by KF1's constant-velocity prediction (paper: the last frame as it is).
        lone_growth: a larger region with one head that holds the target and no other found
            or reported target is the target grown, not a merge (paper: searched).
        min_support: with foreground, a candidate starts a target only when one of its parts
            has this foreground fraction (paper: 0, any detection).
        relative_match: a target found last frame takes no candidate scoring below this x
            its last match's score, and a candidate so withheld starts no target (paper: 0).
        duplicate_radius: ambiguous candidates whose heads all lie within this many head
            widths of the best's are one response: best kept, no template match (paper:
            negative, always match).
        prune_max_misses: a target unfound for more frames is not pruned by its stale head
            template (paper: unbounded).
        stale: re-learning of stale parts (``StaleParts``); None: frozen until they match
            (the paper).
        gate_max_fraction: the gate stops growing at this many target sizes (paper:
            unbounded).
        exit_margin, exit_misses: an unfound target whose box, moved by KF1's prediction,
            crossed the image border by more than exit_margin pixels is dropped after
            exit_misses frames (paper: never, only after ``life_cycle.max_misses``).
        report_predicted: an unfound target is reported at its last box moved by KF1's
            prediction (paper: reporting is ours; at its last validated box).
        gap_division: after m frames unfound, eq. 11's displacement and overlap are divided
            by 1 + m (per-frame differences; paper: as measured, eq. 11).
        apart_undivided: with ``gap_division``, the overlap of a target none of whose parts
            overlaps the candidate's (every part's IoU 0: 1 - IoU = 1) is not divided: parts
            that miss the candidate entirely cost the full overlap whatever the gap
            (``differences._pair_differences``' ``apart``; false: divided as the rest).
        hold_size: KF2's size rates are zeroed while a target is unfound, so its predicted
            size is held (paper: KF2 predicts, eq. 8).
        blob_box_ratio: a blob-born candidate's box is rescaled by the detection/blob size
            ratio learnt online from isolated people (paper: the blob's span, PBM 2.1).
        several_heads_merge: a blob holding several heads is a merge (searched) whatever
            its size (paper: the 50% size test of PBM 3.1 alone).
        profile_heads: a blob's heads are the peaks of its top profile (paper: the head
            detector of PBM 2.3, ``candidates.head_detector``).
        lone_shrink: a detection smaller than a target's prediction (PBM 3.1's size test)
            is the target at its own size, not partly occluded, unless another live
            target's box covers this share of its aligned predicted-size box
            (``smaller.LoneShrink``; 0: off, the paper's partial occlusion).
        lone_shrink_shape: with ``lone_shrink``, the detection is the target at its own
            size only when its height / width is at least this x the prediction's (a whole
            person, not a piece of one; 0: any shape).
        border_exit: an unfound target whose last match was occluded (PBM 3.1) with its box
            at an image border is gone after ``exit_misses`` frames (``exits.BorderExit``;
            paper: never, only after ``life_cycle.max_misses``).
        held_detections: a blob holding a detection (``search.overlap`` of its box inside)
            whose head is none of the blob's is never one target grown (``lone_growth``),
            ``candidates.HeldDetections`` (paper: off; lone growth is ours).
        one_to_one: targets share candidates one-to-one (Hungarian on 1 - p, as many
            pairs as possible); off, each target takes its best candidate as if tracked
            alone, as the paper tracks each target (PBM 3, 4 step 4).
        report_support: with foreground, an unfound target is reported only while its box
            holds this foreground fraction (paper: 0, reported regardless; off by default:
            docs/adaptations.md).
        hidden_evidence: an unfound target is reported only while evidence of a person at
            its box holds (``evidence.HiddenEvidence``: foreground, a nearer found target
            over it, or memory growing with its matches); None: reported for
            ``reporting.max_misses`` frames (paper: reporting is ours; None). Replaces
            ``report_support`` (one rule per step: set one of the two, the other None / 0).
        rival_match: a target found last frame takes no candidate scoring below this x its
            last match's score that another target may take (``rules.RivalMatch``; paper:
            0, off).
        early_confirm: a new target overlapping no other live target (IoU < 0.1) is
            confirmed after this many matches (``rules.IsolatedEarly``; 0: after
            ``life_cycle.min_hits``, our life cycle's rule; the paper starts targets by hand);
            1: confirmed at its birth.
        border_birth_waits: with ``early_confirm`` 1, a newcomer whose box touches an image
            border (within 1 px) is not confirmed at birth (``confirmation.IsolatedEarly``;
            paper: False).
        reupdate: a target found again after at least this many frames unfound has KF1 and
            KF2 rewound to its last observation and re-run over the line from it to the new
            one (``reupdate.ReUpdate``, OC-SORT's observation-centric re-update; 0: off,
            one update after the gap's predictions, eqs. 7-8).
        contested_template: a candidate that two or more targets with fresh head templates
            may take (each scores it >= ``matching.match_threshold`` and within this ratio
            of the best) goes to the target whose head template matches at its head best
            (PBM 4.1's template, applied to a candidate's column; ``rules.TemplateContest``);
            0: left to the assignment (the paper's pruning looks along a target's row only).
        rival_claims: where PBM 4.1's multiple-response pruning would keep an ambiguous
            target's best without its head template (stale, or the near heads within
            ``duplicate_radius``), it passes over the candidates another target claims (its
            best at p >= ``matching.match_threshold``, scored higher than this target scores
            it) and leaves them to the assignment (``selection.RivalClaims``; paper: false,
            a target's row alone).
        weak_ranked: a weak candidate the head template validates (PBM 4.1) enters the
            assignment at ``matching.match_threshold`` plus 1e-6 x its own score, so two
            targets validated for one candidate are ranked by their scores
            (``selection.RankedAtThreshold``; paper: false, at the threshold, a tie).
        leaving_unreported: an unfound target moving towards an image border whose
            reported box lies within this x its width (height) of it, or beyond, is not
            reported (``exits.LeavingUnreported``; negative: off, reported as the other
            reporting rules say; reporting is ours).
        fold_twins: a confirmed target standing on an older one's box (IoU >= 0.5) for this
            many frames in a row, never found in the same frame as it but found in turn with
            it at least once, and with less than ``fold_twins_own`` foreground of its own
            (outside the older box), is the older one's twin and is ended when the older one
            is found (``stacked.FoldTwins``;
            0: off, each target kept until lost, PBM 3). Stands aside without a mask.
        fold_twins_own: with ``fold_twins``, the foreground share of the younger box lying
            outside the older box below which the younger has no region of its own.
        measured_velocity: an unfound target is reported at its last box moved by its
            measured velocity (the displacement of its last two found boxes per frame) when
            that velocity has predicted its found boxes better than KF1's so far
            (``trackers.common.measured_velocity``, reta's rule; false: where KF1 predicts,
            ``report_predicted``). Reporting only.
        camera_placement: an unfound target is reported by whichever of three predictors
            (the tracker's KF1 box, its last found box moved by its measured velocity, its
            last found box unmoved) has placed the camera's re-found targets best so far,
            pooled over every target of the sequence (``placement.CameraPlacement``; false:
            ``measured_velocity``'s or KF1's). Reporting only.
        reported_behind: with a foreground mask, a confirmed target unfound for longer than
            ``reporting.max_misses`` frames is still reported while a found target nearer
            the camera covers this share of its box (``evidence.ReportedBehind``; 0: off,
            reported for ``reporting.max_misses`` frames at most). Stands aside without a
            mask.
        lone_shrink_narrow: with ``lone_shrink_shape``, a smaller detection is the target at
            its own size only when its height / width is also at most 1 /
            ``lone_shrink_shape`` x the prediction's (not a sliver cut by a vertical edge;
            ``smaller.LoneShrink.narrow``; false: no upper bound).
        merge_found_elsewhere: a detection larger than a target's prediction (one head)
            that PBM 3.1 searched as a merge, whose other holders all took other candidates
            this frame as measured, is the target grown: the frame is associated again with
            that pair unoccluded (``merges.FoundElsewhere``; false: a merge, PBM 3.1).
        merge_recent_holder: a detection (one head) a target
            took as a merge while exactly one other live target holding it, found more
            recently (fewer misses), took nothing, is that target grown: associated again
            with that pair unoccluded and the merge's pair struck
            (``merges.FoundElsewhere.recent_holder``; false: the merge stands, PBM 3.1).
        distinct_detections: with ``duplicate_radius``, coinciding heads are one response
            only when a blob's head is among them; an ambiguous target whose coinciding
            candidates are all detections is not pruned (two people; the one-to-one
            assignment decides; ``selection.DetectionsApart``; false: one response).
        reported_by_record: a confirmed target unfound for m > ``reporting.max_misses``
            frames is still reported while the sequence's resolved runs of >= m misses ended
            found again where reported (IoU >= 0.5) at least half the time
            (``record.ReportedByRecord``; false: reported for ``reporting.max_misses``
            frames at most). Reporting only.
        reported_first: the targets still reported (unfound for at most
            ``reporting.max_misses`` frames) share the frame's candidates among themselves
            first; a target unfound longer takes none of those they take
            (``lost.ReportedFirst``; false: every target in one assignment, PBM 4 step 4).
        reported_first_stay: with ``reported_first``, a lost target still competes for a
            candidate at IoU >= this with its last box moved by KF1's prediction (where
            ``report_predicted`` would report it; 0: for none).
        reported_first_head: with ``reported_first``, a lost target still competes for a
            candidate whose head band (top 1/7 of its box, PBM 2.1's head part) shares rows
            with that of its last box (false: for none).
        contact_frozen, contact_colour: a matched part whose candidate rectangle lies this
            share under another target's box keeps its model as a part not matching / only its
            colour histograms (``contact.FrozenAtContact`` / ``ColourAtContact``; PBM 1-2; 0:
            off); one of the two. contact_occluded: a match whose candidate box lies this share
            under another's is occluded for PBM 4.2's global update (``ContactOcclusion``).
        coarse_search: PBM 3.1's head-anchored boxes of a searched pair are searched coarse
            to fine (every other width and height, then the neighbours of the best of
            those; ``box_search._coarse_group``), not all scored (paper: every box of eqs.
            9-10). A shortcut for speed (issue 38), not exact.
        pyramid_template: PBM 4.1's head template in multiple-response pruning is matched
            at half resolution, then at full resolution around that best
            (``template_match.PyramidMatch``; paper: every position of the window). A
            shortcut for speed (issue 38), not exact.
        large_head_pyramid: with ``pyramid_template`` off, a head template wider than this
            many pixels is matched as ``pyramid_template`` matches it, narrower ones at
            every position (``template_match.PyramidMatch(min_width)``; 0: off, the
            paper's match everywhere). A shortcut for 1920x1080 speed (issue 38), exact
            wherever heads are at most that wide.
        large_head_peaks: with ``large_head_pyramid``, the coarse level's this many best
            peaks are refined at full resolution (within 3 pixels each when more than one;
            ``PyramidMatch.peaks``), the best full-resolution score winning; 1: the coarse
            best alone, within 2 pixels, as ``pyramid_template``.
    """

    model_spread: float = 4.5
    motion_compensation: bool = True
    lone_growth: bool = True
    min_support: float = 0.3
    relative_match: float = 0.5
    duplicate_radius: float = 0.25
    prune_max_misses: int = 5
    stale: StaleParts | None = field(default_factory=StaleParts)
    gate_max_fraction: float = 6.0
    exit_margin: float = 8.0
    exit_misses: int = 3
    report_predicted: bool = True
    gap_division: bool = True
    apart_undivided: bool = False
    hold_size: bool = True
    blob_box_ratio: bool = True
    several_heads_merge: bool = True
    profile_heads: bool = True
    held_detections: bool = False
    lone_shrink: float = 0.3
    lone_shrink_shape: float = 0.7
    border_exit: bool = True
    one_to_one: bool = True
    report_support: float = 0.0
    hidden_evidence: HiddenEvidence | None = field(default_factory=HiddenEvidence)
    rival_match: float = 0.0
    early_confirm: int = 1
    reupdate: int = 0
    contested_template: float = 0.0
    rival_claims: bool = False
    leaving_unreported: float = -1.0
    weak_ranked: bool = False
    coarse_search: bool = False
    pyramid_template: bool = False
    large_head_pyramid: int = 0
    large_head_peaks: int = 1
    fold_twins: int = 0
    fold_twins_own: float = 0.0
    measured_velocity: bool = False
    reported_behind: float = 0.0
    border_birth_waits: bool = False
    camera_placement: bool = False
    reported_by_record: bool = False
    lone_shrink_narrow: bool = False
    merge_found_elsewhere: bool = True
    distinct_detections: bool = False
    merge_recent_holder: bool = True
    reported_first: bool = False
    reported_first_stay: float = 0.0
    reported_first_head: bool = False
    contact_frozen: float = 0.0
    contact_colour: float = 0.0
    contact_occluded: float = 0.0

    def __post_init__(self) -> None:
        require("adaptations.model_spread", self.model_spread > 0, "must be > 0", self.model_spread)
        unit("adaptations", min_support=self.min_support, relative_match=self.relative_match,
             report_support=self.report_support, rival_match=self.rival_match,
             lone_shrink=self.lone_shrink, reported_behind=self.reported_behind,
             contact_frozen=self.contact_frozen, contact_colour=self.contact_colour,
             contact_occluded=self.contact_occluded, fold_twins_own=self.fold_twins_own,
             reported_first_stay=self.reported_first_stay)
        require("adaptations.gate_max_fraction", self.gate_max_fraction > 0, "must be > 0",
                self.gate_max_fraction)
        at_least("adaptations", 0, exit_misses=self.exit_misses, early_confirm=self.early_confirm,
                 reupdate=self.reupdate, fold_twins=self.fold_twins,
                 large_head_pyramid=self.large_head_pyramid)
        at_least("adaptations", 1, large_head_peaks=self.large_head_peaks)
        require("adaptations.reported_first_stay",
                self.reported_first_stay == 0 or self.reported_first,
                "needs adaptations.reported_first", self.reported_first_stay)
        require("adaptations.reported_first_head",
                not self.reported_first_head or self.reported_first,
                "needs adaptations.reported_first", self.reported_first_head)
        require("adaptations.apart_undivided", not self.apart_undivided or self.gap_division,
                "needs adaptations.gap_division", self.apart_undivided)
        require("adaptations.fold_twins_own", self.fold_twins_own == 0 or self.fold_twins > 0,
                "needs adaptations.fold_twins > 0", self.fold_twins_own)
        require("adaptations.lone_shrink_shape", self.lone_shrink_shape >= 0, "must be >= 0",
                self.lone_shrink_shape)
        require("adaptations.lone_shrink_shape",
                self.lone_shrink_shape == 0 or self.lone_shrink > 0,
                "needs adaptations.lone_shrink > 0", self.lone_shrink_shape)
        require("adaptations.lone_shrink_narrow",
                not self.lone_shrink_narrow or self.lone_shrink_shape > 0,
                "needs adaptations.lone_shrink_shape > 0", self.lone_shrink_narrow)
        require("adaptations.reported_by_record",
                not (self.reported_by_record and self.reported_behind > 0),
                "and adaptations.reported_behind are two rules for one step: set one",
                self.reported_by_record)
        require("adaptations.contact_colour", min(self.contact_colour, self.contact_frozen) <= 0,
                "and adaptations.contact_frozen are two rules for one step: set one",
                self.contact_colour)
        require("adaptations.camera_placement",
                not (self.camera_placement and self.measured_velocity),
                "and adaptations.measured_velocity are two rules for one step: set one",
                self.camera_placement)
        require("adaptations.contested_template",
                self.contested_template == 0 or self.contested_template >= 1,
                "must be 0 (off) or >= 1", self.contested_template)
        require("adaptations.stale", self.stale is None or isinstance(self.stale, StaleParts),
                "must be StaleParts or None", self.stale)
        require("adaptations.hidden_evidence",
                self.hidden_evidence is None or isinstance(self.hidden_evidence, HiddenEvidence),
                "must be HiddenEvidence or None", self.hidden_evidence)
        require("adaptations.report_support",
                self.hidden_evidence is None or not self.report_support > 0,
                "and adaptations.hidden_evidence are two rules for one step: set one",
                self.report_support)
        coerce(self, {**dict.fromkeys(("model_spread", "min_support", "relative_match",
                                       "duplicate_radius", "gate_max_fraction", "exit_margin",
                                       "report_support", "rival_match", "contested_template",
                                       "lone_shrink", "lone_shrink_shape", "leaving_unreported",
                                       "fold_twins_own", "reported_behind",
                                       "reported_first_stay", "contact_frozen",
                                       "contact_colour", "contact_occluded"),
                                      float),
                      **dict.fromkeys(("motion_compensation", "lone_growth", "report_predicted",
                                       "gap_division", "hold_size", "blob_box_ratio",
                                       "several_heads_merge", "profile_heads", "held_detections",
                                       "one_to_one", "border_exit", "rival_claims", "weak_ranked",
                                       "coarse_search", "pyramid_template", "measured_velocity",
                                       "border_birth_waits", "camera_placement",
                                       "reported_by_record", "lone_shrink_narrow",
                                       "merge_found_elsewhere", "distinct_detections",
                                       "merge_recent_holder", "reported_first",
                                       "reported_first_head", "apart_undivided"),
                                      bool),
                      "prune_max_misses": int, "exit_misses": int, "early_confirm": int,
                      "reupdate": int, "fold_twins": int, "large_head_pyramid": int,
                      "large_head_peaks": int})

    @classmethod
    def paper(cls) -> Adaptations:
        """Every adaptation off: the paper as written (``conf/tracker/pbm_paper.yaml``)."""
        return cls(model_spread=1.0, motion_compensation=False, lone_growth=False,
                   min_support=0.0, relative_match=0.0, duplicate_radius=-1.0,
                   prune_max_misses=UNBOUNDED, stale=None, gate_max_fraction=float(UNBOUNDED),
                   exit_margin=float(UNBOUNDED), report_predicted=False, gap_division=False,
                   hold_size=False, blob_box_ratio=False, several_heads_merge=False,
                   profile_heads=False, held_detections=False, lone_shrink=0.0,
                   lone_shrink_shape=0.0, border_exit=False,
                   one_to_one=False, report_support=0.0,
                   hidden_evidence=None, rival_match=0.0, early_confirm=0, reupdate=0,
                   contested_template=0.0, rival_claims=False,
                   leaving_unreported=-1.0, weak_ranked=False,
                   coarse_search=False, pyramid_template=False, large_head_pyramid=0,
                   large_head_peaks=1, fold_twins=0, fold_twins_own=0.0,
                   measured_velocity=False, reported_behind=0.0, border_birth_waits=False,
                   camera_placement=False, reported_by_record=False,
                   lone_shrink_narrow=False, merge_found_elsewhere=False,
                   distinct_detections=False, merge_recent_holder=False,
                   reported_first=False, reported_first_stay=0.0, reported_first_head=False,
                   apart_undivided=False, contact_frozen=0.0, contact_colour=0.0,
                   contact_occluded=0.0)

    def changed(self) -> list[str]:
        """Names of the fields that differ from the paper's values."""
        paper = self.paper()
        return [f.name for f in fields(self) if getattr(self, f.name) != getattr(paper, f.name)]
