"""Parameter groups of ``RetaTracker``: small frozen dataclasses that check themselves.

Each group gathers the parameters of one part of Reta et al. 2015 and raises ``ValueError``
naming the field and the value when one is out of range. Hydra builds each group as a
nested ``_target_`` of ``conf/tracker/reta.yaml``. ``Adaptations`` holds every rule the
paper does not have (``Adaptations.paper()`` turns them all off, as ``tracker=reta_paper``);
``docs/adaptations.md`` gives each one's paper section, value and evidence. The motion
group is ``occbench.trackers.three_hypothesis.motion.MotionModel`` (Kalman noises of M, 3.2).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from occbench.trackers.common.checks import at_least, coerce, require, unit

__all__ = ["Adaptations", "Appearance", "Association", "LifeCycle", "Occlusion"]


@dataclass(frozen=True, slots=True)
class Association:
    """Two-stage similarity association (3.3.2, Alg. 1's mu_rho and mu_g).

    Args:
        mu_rho: mu_rho, smallest Bhattacharyya coefficient rho (eq. 4) accepted for a
            match, in [0, 1].
        mu_g: mu_g, radius in pixels of the stage-2 validation gate, > 0.
    """

    mu_rho: float = 0.3
    mu_g: float = 120.0

    def __post_init__(self) -> None:
        unit("association", mu_rho=self.mu_rho)
        require("association.mu_g", self.mu_g > 0, "must be > 0 pixels", self.mu_g)


@dataclass(frozen=True, slots=True)
class Occlusion:
    """Occlusion relations O (3.3.1, eq. 2) and the integration of ellipse overlaps.

    Args:
        lam: lambda of eq. 2, the overlap |Si & Sj| / (|Si| + |Sj|) of two predicted
            regions above which they occlude, in [0, 0.5).
        region_samples: grid points per side integrating ellipse overlaps (eqs. 2, 5), >= 2.
    """

    lam: float = 0.05
    region_samples: int = 12

    def __post_init__(self) -> None:
        require("occlusion.lam", 0.0 <= self.lam < 0.5, "must lie in [0, 0.5)", self.lam)
        at_least("occlusion", 2, region_samples=self.region_samples)


@dataclass(frozen=True, slots=True)
class Appearance:
    """Appearance model q (3.2, eq. 1): colour histogram over the ellipse.

    Args:
        bins: histogram bins per colour channel (16 in the paper); must divide 256.
        min_foreground: with a foreground mask, the share of an ellipse that must be
            foreground for its histogram to count foreground pixels only (with
            ``Adaptations.foreground_histograms``) and for its region not to be seen empty
            (with ``Adaptations.foreground_support``), in [0, 1].
        pixel_stride: histogram every pixel_stride-th row and column of an ellipse (1 =
            every pixel, as in eq. 1).
    """

    bins: int = 16
    min_foreground: float = 0.2
    pixel_stride: int = 1

    def __post_init__(self) -> None:
        require("appearance.bins", self.bins >= 1 and 256 % self.bins == 0, "must divide 256",
                self.bins)
        unit("appearance", min_foreground=self.min_foreground)
        at_least("appearance", 1, pixel_stride=self.pixel_stride)


@dataclass(frozen=True, slots=True)
class LifeCycle:
    """Confirmation of tentative tracks (3.3) and pruning after m frames (Alg. 1).

    Args:
        m: m, frames before pruning: a hypothesis in plain view for m frames in a row is
            contradicted by the missing detection and removed; the graph keeps m + 1 frames.
        cover: share of a hypothesis region hidden by a visible person's region above
            which the hypothesis counts as covered (explains its missing detection);
            below it the hypothesis is in plain view (the paper's "contradictory"), in (0, 1].
        confirm_frames: matches that confirm a tentative track, >= 1 (the paper: "confirmed
            in subsequent frames", no number; a reading, ``life_cycle.confirm_frames``).
        reported_hypothesis: which hypothesis of a hidden person is reported as OCCLUDED
            (the paper draws them all and gives no rule; a reading,
            ``life_cycle.reported_hypothesis``): 'least_contradicted'
            (covered by a visible person first, then fewest frames in plain view, then
            velocity > occluder > still) or 'first' (hypothesis 1, velocity, while it
            lives, then occluder, then still).
    """

    m: int = 8
    cover: float = 0.5
    confirm_frames: int = 3
    reported_hypothesis: str = "least_contradicted"

    def __post_init__(self) -> None:
        at_least("life_cycle", 1, m=self.m, confirm_frames=self.confirm_frames)
        require("life_cycle.cover", 0.0 < self.cover <= 1.0, "must lie in (0, 1]", self.cover)
        require("life_cycle.reported_hypothesis",
                self.reported_hypothesis in ("least_contradicted", "first"),
                "must be 'least_contradicted' or 'first'", self.reported_hypothesis)


@dataclass(frozen=True, slots=True)
class Adaptations:
    """Every rule of ours that the paper does not have; ``paper()`` gives the paper's values.

    Args:
        gate_sigmas: the stage-2 gate of a node is the circle approximating its Kalman
            validation region, radius gate_sigmas x the larger standard deviation of its
            predicted centre (innovation H P H' + R), capped at mu_g; 0: mu_g for every node
            (the paper, 3.3.2).
        blend_visible: a matched person behind others moves its appearance q towards its
            measurement p by the share v of the measured region left visible by the people
            in front (q <- (1 - v) q + v p); False: q kept constant (the paper, 3.3.3).
        shape_estimate: the region of a matched person behind others is the Kalman
            estimate (prediction corrected by the measurement); False: the bare prediction
            (the paper, 3.3.3).
        foreground_histograms: histograms (eq. 1) count only foreground pixels when a mask
            is given and covers at least ``Appearance.min_foreground`` of the ellipse;
            False: every pixel of the ellipse (the paper, 3.2).
        foreground_support: with a foreground mask, a hypothesis whose ellipse holds less
            than ``Appearance.min_foreground`` foreground is seen to be empty: never
            covered (pruned after m frames) and never reported, and a detection that empty
            does not count towards confirming a tentative track; False: hypotheses judged
            by coverage and time alone (the paper).
        report_exposed: frames a hidden person's best hypothesis may stand in plain view
            and still be reported as OCCLUDED (then it is only drawn, as a HYPOTHESIS);
            the paper reports it until pruned (1000000).
        report_support: with a foreground mask, a hidden person's best hypothesis is
            reported only while its ellipse holds at least this foreground share; 0 reports
            it on any (the paper).
        report_spread: a hidden person's best hypothesis is reported only while the
            standard deviation of its centre (Kalman P) is at most this many person
            widths; 0 reports it however uncertain (the paper).
        tentative_misses: frames a tentative track may go unmatched before it is dropped
            as a false positive; 0: its tracking ends at the first miss (the paper, Fig. 3).
        max_hidden: most frames a person is kept without a match (the paper: no limit,
            1000000).
        appearance_margin: stage 1 scores a pair's appearance by its margin over its rivals,
            rho minus the larger of the best rho of another person for that measurement and
            of another measurement for that person (0 when the pair is not the best both
            ways), instead of rho itself; a pair with no rival keeps rho (our default).
            False: rho (eq. 4, the paper).
        measured_velocity: a reported hidden person stands at its last measured box moved
            by its measured velocity when that velocity has predicted its measurements
            better than the Kalman filter's so far (``occbench.trackers.common.measured_velocity``);
            False: where M predicts it (the paper's hypothesis region).
        foreground_presence: with a foreground mask, a hypothesis in plain view whose
            ellipse holds at least ``Appearance.min_foreground`` foreground is not
            contradicted by the missing detection: its count of frames in plain view does not
            grow (the detector missed a person who is there; up to ``max_hidden``); False:
            every frame in plain view counts towards the m frames of pruning (the paper).
        tentative_stage1_only: a tentative track is matched in association stage 1 only
            (it has no velocity to justify a jump through the gate); False: every node of
            t-1 left unassociated competes in stage 2 (the paper, Alg. 1's
            MaxSimilarity(n_j, N^{t-1} \\ Assoc)).
        inherit_hidden_id: a tentative track confirmed where a hidden confirmed person's
            hypothesis stands (IoU >= 0.5) takes that person's id and ends its hypotheses;
            False: it takes a new id, a hidden person comes back only by matching one of
            its hypotheses (the paper: Alg. 1 has no such step; Fig. 3(d)).
        merge_duplicates: of two hypotheses of a person at the same place (every box edge
            within half a pixel) only the preferred kind is kept; False: both kept (the
            paper's PruneHypothesis removes contradicted, false-positive and departed ones).
        correct_behind: M of a matched person behind others is corrected by its
            measurement; False: M evolves by its prediction (the paper, 3.3.3: "the motion
            model is updated ... from his current measurement given that the person is not
            being occluded").
        filter_size: M's state is the box, x = (xc, yc, w, h, vx, vy, vw, vh), the size and
            its rate filtered with the centre; False: the centre's position and velocity,
            x = (xc, yc, vx, vy), the size the shape's (the paper, 3.2: "position and
            velocity"; the shape from the measurement, the prediction area's when occluded).
        shape_gate: a node may not take a measurement whose size disagrees with its own
            (BoostTrack's shape similarity exp(-(|dw| / max w + |dh| / max h)) below this)
            while another person's node meets the measurement with a size that agrees, in
            [0, 1); 0: any size (the paper, 3.3.2).
        early_confirm: a tentative track is confirmed after this many matches (fewer
            than ``LifeCycle.confirm_frames``) when its measurement scores at least
            ``early_confirm_score`` and meets no other measurement and no other person's
            predicted region (ByteTrack, norfair: a clear detection confirmed sooner);
            0: after ``confirm_frames`` matches always (the paper's reading, 3.3).
        early_confirm_score: the smallest detection score of an early confirmation, in
            [0, 1].
        report_memory: a hidden person no visible person covers is reported only while
            its frames unmatched are at most this many times its matches (norfair's hit
            counter: the longer tracked, the longer believed); 0 reports it however young
            (the paper).
        contact_region: when two people are in O (eq. 2) and one measurement meets both in
            stage 1, the measurement's histogram holds both, so their two pairs share one
            appearance term (the mean) and the region term (eq. 5) decides between them
            (a merged measurement is an occlusion); False: eq. 4 weighs each pair (the
            paper, 3.3.2).
        merged_appearance: a measurement merged over two tracked people is an occlusion:
            the person matched to it, in O (eq. 2) with a confirmed person unmatched at t,
            moves its appearance q towards the measurement's p only by the share of the
            measured region the unmatched person's predicted region does not cover
            (``contact.MergedAppearance``); False: q = p for everyone matched in front
            (the paper, 3.3.3).
        split_parts: a person partly seen is a split: a measurement stage 1 left over that
            lies mostly (``LifeCycle.cover`` of its ellipse) on the measurements stage 1
            matched is a second measurement of people already measured; stage 2 may not give
            it to anyone and it starts no track (``contact.SplitParts``); False: stage 2 may
            give it to any prediction whose gate holds it, else it starts a track (the
            paper, 3.3.2, 3.3).
        merged_motion: a measurement merged over two tracked people is an occlusion: M of
            the person matched to it in front is corrected with R divided by the share of the
            measured region its unmatched partners in O do not cover
            (``contact.MergedMotion``); False: with R (the paper, 3.3.3).
        visible_region: in stage 1, eq. 5's region term of a node behind others (eq. 3's
            order at t - 1) is scaled by the share of its predicted region the nodes in
            front leave visible (``contact.VisibleRegion``); False: the whole region (the
            paper, 3.3.2).
        measured_hypothesis: hypothesis 1 of a person just missed moves with the velocity of
            the least-squares line through its last m measured centres when that line has
            predicted its measurements better than M so far (``measured_line.MeasuredLine``);
            False: with M's velocity (the paper, 3.3.3 case 1).
        measured_hypothesis_sigmas: with ``measured_hypothesis``, the line's velocity is
            taken only where it is measured to differ from M's: by more than this many
            standard errors of the line's slope, in x or in y (a standing person's jitter
            gives a line no better than M's); 0: whenever the line predicted better.
        split_appearance: a merged measurement is an occlusion: when a person's measurement
            at t - 1 held a hidden partner in O and stage 1 gives the two of them two
            measurements each could take, the appearance (eq. 4) says which is whose: they
            are exchanged when the colours fit the exchange better
            (``contact.AppearanceAtSplit``); False: stage 1's cost decides (the paper, 3.3.2).
        split_appearance_margin: with ``split_appearance``, the colours must win by this
            much: the exchange is taken only when eq. 4's sum over the exchanged pairs
            exceeds stage 1's by more than this margin (PBM's multiple-response test: an
            ambiguous appearance decides nothing); 0: whenever it is larger.
        split_appearance_parted: with ``split_appearance``, only where the measurement stage
            1 gives the merged person has IoU below this with its region at t - 1; 0: always.
        merged_unmixed: with ``merged_appearance``, the person matched to a measurement
            that holds a hidden partner moves q towards the measurement's histogram less
            the partner's q by its share (``contact.UnmixedAppearance``); False: towards
            the measurement's whole histogram p.
        merged_unmixed_evidence: with ``merged_unmixed``, only where p's colours hold both
            (``appearance.holds_both``); elsewhere ``merged_appearance``'s update.
        duplicates_together: with ``merge_duplicates``, two hypotheses of a person are one
            only if they also stay together: their velocities differ by less than half a
            pixel over the m frames of pruning (``rules.MergeTogether``); False: by place
            alone, so hypothesis 3 (still) of a person whose velocity is a few tenths of a
            pixel per frame is dropped at its first frame and hypothesis 1 drifts alone.
        measured_step: with ``measured_hypothesis``, a third predictor of hypothesis 1 is
            scored on the person's measurements, its last step (the displacement of its last
            two measured centres per frame), and taken when its record beats M's and the
            line's (``measured_line.MeasuredLine.step``); False: M's or the line's.
        own_return: a confirmed person hidden at t - 1 may take a measurement only with
            rho at least the lowest rho of its own last m matches (and mu_rho)
            (``returning.OwnReturn``); False: mu_rho for everyone (the paper, 3.3.2).
        hold_last: a confirmed person whose hypotheses are all contradicted is kept, its
            first contradicted hypothesis standing where it is, unreported, until
            ``max_hidden`` (``returning.HoldLast``); False: it ends (Alg. 1).
        return_floor: a confirmed person hidden at t - 1 may take a measurement (stage 1 or
            2, through any hypothesis) only with rho (eq. 4) at least this floor, one value
            for everyone (``returning.ReturnFloor``), in [0, 1]; 0: mu_rho (the paper, 3.3.2).
        restore_still: a confirmed person all of whose hypotheses are contradicted gets back,
            once a hidden spell, the hypothesis 3 ``merge_duplicates`` dropped beside another
            (``returning.RestoreStill``); False: it ends (Alg. 1).
        merged_line: with ``measured_hypothesis``, a measurement that held a hidden partner
            (own share below 1) stays out of the person's line, and hypothesis 1 at a first
            miss right after one starts on the line (or step) at t from the person's own
            measurements (``measured_line.MeasuredLine``); False: every measurement.
        merged_line_shift: with ``merged_line``, such a measurement counts as merged only
            when its centre lies off the line through the person's own last centres towards
            the hidden partner's predicted centre by more than this many times its width
            (``MeasuredLine.shift``); 0: whenever its own share is below 1.
        measured_still: with ``measured_hypothesis``, a person whose last m measured centres
            show no motion (the line's slopes within ``measured_hypothesis_sigmas`` standard
            errors of zero, in x and in y) is missed standing: hypothesis 1 stands at its
            last estimate with velocity 0 (``measured_line.MeasuredLine`` ``still``); False:
            it moves with M's velocity, the line's or the step's.
        contact_coincident: two people in O both seen at t - 1 whose predicted regions
            coincide (each holds at least ``LifeCycle.cover`` of the larger) were measured over
            the same pixels, so eq. 4 cannot tell them apart: on a measurement meeting both in
            stage 1 they share one appearance term (the mean) and the region term (eq. 5)
            decides (``contact.RegionAtContact`` ``coincident``; ``contact_region`` does so
            for every pair of O); False: eq. 4 weighs each pair (the paper, 3.3.2).
        covered_appearance: a person partly seen is hypothesis territory: a person matched
            in front (eq. 3) whose measurement's ellipse one measurement nearer the camera
            (its foot line lower) covers for at least ``LifeCycle.cover`` keeps q, as a
            person behind others does (``contact.NearerCover``); False: q from its
            measurement (the paper, 3.3.3).
    """

    gate_sigmas: float = 3.0
    blend_visible: bool = True
    shape_estimate: bool = True
    foreground_histograms: bool = True
    foreground_support: bool = True
    report_exposed: int = 4
    report_support: float = 0.0
    report_spread: float = 3.0
    tentative_misses: int = 2
    max_hidden: int = 150
    appearance_margin: bool = True
    measured_velocity: bool = True
    foreground_presence: bool = True
    tentative_stage1_only: bool = True
    inherit_hidden_id: bool = True
    merge_duplicates: bool = True
    correct_behind: bool = True
    filter_size: bool = True
    shape_gate: float = 0.0
    early_confirm: int = 1
    early_confirm_score: float = 0.0
    report_memory: float = 1.0
    contact_region: bool = False
    merged_appearance: bool = True
    split_parts: bool = False
    merged_motion: bool = False
    visible_region: bool = False
    measured_hypothesis: bool = True
    measured_hypothesis_sigmas: float = 2.0
    split_appearance: bool = True
    split_appearance_margin: float = 0.1
    split_appearance_parted: float = 0.5
    merged_unmixed: bool = False
    merged_unmixed_evidence: bool = False
    duplicates_together: bool = False
    own_return: bool = False
    hold_last: bool = False
    measured_step: bool = True
    return_floor: float = 0.0
    restore_still: bool = False
    merged_line: bool = False
    merged_line_shift: float = 0.0
    contact_coincident: bool = False
    measured_still: bool = False
    covered_appearance: bool = False

    def __post_init__(self) -> None:
        coerce(self, {"gate_sigmas": float, "report_spread": float, "report_support": float,
                      "shape_gate": float, "early_confirm_score": float,
                      "measured_hypothesis_sigmas": float, "split_appearance_margin": float,
                      "return_floor": float, "merged_line_shift": float,
                      "split_appearance_parted": float, "report_memory": float,
                      "blend_visible": bool, "shape_estimate": bool, "foreground_histograms": bool,
                      "foreground_support": bool, "appearance_margin": bool,
                      "measured_velocity": bool, "foreground_presence": bool,
                      "tentative_stage1_only": bool, "inherit_hidden_id": bool,
                      "merge_duplicates": bool, "correct_behind": bool, "filter_size": bool,
                      "contact_region": bool, "merged_appearance": bool, "split_parts": bool,
                      "merged_motion": bool, "visible_region": bool, "measured_hypothesis": bool,
                      "split_appearance": bool, "merged_unmixed": bool,
                      "merged_unmixed_evidence": bool, "duplicates_together": bool,
                      "own_return": bool, "hold_last": bool, "measured_step": bool,
                      "restore_still": bool, "merged_line": bool, "contact_coincident": bool,
                      "measured_still": bool, "covered_appearance": bool})
        at_least("adaptations", 0, gate_sigmas=self.gate_sigmas,
                 report_exposed=self.report_exposed, report_spread=self.report_spread,
                 report_support=self.report_support,
                 tentative_misses=self.tentative_misses,
                 early_confirm=self.early_confirm, report_memory=self.report_memory,
                 measured_hypothesis_sigmas=self.measured_hypothesis_sigmas,
                 split_appearance_margin=self.split_appearance_margin,
                 merged_line_shift=self.merged_line_shift)
        at_least("adaptations", 1, max_hidden=self.max_hidden)
        unit("adaptations", report_support=self.report_support,
             early_confirm_score=self.early_confirm_score, return_floor=self.return_floor,
             split_appearance_parted=self.split_appearance_parted)  # an IoU
        require("adaptations.shape_gate", 0.0 <= self.shape_gate < 1.0, "must lie in [0, 1)",
                self.shape_gate)

    @classmethod
    def paper(cls) -> Adaptations:
        """Every adaptation off: the paper as written (``conf/tracker/reta_paper.yaml``)."""
        return cls(gate_sigmas=0.0, blend_visible=False, shape_estimate=False,
                   foreground_histograms=False, foreground_support=False,
                   report_exposed=1_000_000, report_support=0.0, report_spread=0.0,
                   tentative_misses=0,
                   max_hidden=1_000_000, appearance_margin=False, measured_velocity=False,
                   foreground_presence=False, tentative_stage1_only=False,
                   inherit_hidden_id=False, merge_duplicates=False, correct_behind=False,
                   filter_size=False, shape_gate=0.0, early_confirm=0,
                   early_confirm_score=0.0, report_memory=0.0, contact_region=False,
                   merged_appearance=False, split_parts=False,
                   merged_motion=False, visible_region=False,
                   measured_hypothesis=False, measured_hypothesis_sigmas=0.0,
                   split_appearance=False, split_appearance_margin=0.0, split_appearance_parted=0.0,
                   merged_unmixed=False, merged_unmixed_evidence=False, duplicates_together=False,
                   own_return=False, hold_last=False, measured_step=False,
                   return_floor=0.0, restore_still=False, merged_line=False,
                   merged_line_shift=0.0, contact_coincident=False,
                   measured_still=False, covered_appearance=False)

    def changed(self) -> list[str]:
        """Names of the fields that differ from the paper's values."""
        paper = self.paper()
        return [f.name for f in fields(self) if getattr(self, f.name) != getattr(paper, f.name)]
