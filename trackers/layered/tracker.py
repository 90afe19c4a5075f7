"""PBM: part-based model with layered data association, multi-target.

Paper: "Tracking People under Heavy Occlusions by Layered Data Association" (PBM).
``PBMTracker.update`` runs the paper's Fig. 1 once per frame, one method per step:

1. ``_find_candidates`` (PBM 2, 2.1, 2.3): detections with their heads, the heads of
   foreground blobs no detection explains (``candidates.CandidateFinder``), and each
   candidate's five parts and features on one sample grid.
2. ``Targets.predict`` (PBM 3, eqs. 7-8): KF1 (the gate's size) and KF2 (the size).
3. ``_associate`` (PBM 3, 3.1, 4, 4.1; a large frame in independent blocks,
   ``frame_blocks``), first ``_score_in_gates`` (eqs. 11-13): each target scores the
   candidates in its gate; a candidate whose size differs from the prediction by > 50% is
   occluded, and ``gating.OcclusionSearch`` searches it (larger: head-anchored boxes of
   eqs. 9-10; smaller: aligned on its head, or dismissed).
4. ``selection.MultipleResponsePruning`` (PBM 4 steps 4-5, 4.1): the best candidate must pass
   ``matching.match_threshold`` and beat the runner-up by ``matching.margin_ratio``; an
   ambiguous or weak choice is settled by the target's head template (``rules.match`` may
   withhold poor matches); then each target takes its best candidate (``rules.sharing``).
5. ``_update_models`` (PBM 4.2): global models, KF1, KF2 and the parts of every matched
   target at once.
6. ``_end_targets`` and ``_start_targets`` (ours: PBM 3 starts each target by hand): a
   candidate no target takes starts a TENTATIVE target, CONFIRMED after
   ``life_cycle.min_hits`` matches (``rules.confirmation``: a lone one sooner); a target is
   dropped after ``life_cycle.max_misses`` frames unfound.
7. ``_report``: found targets, and confirmed unfound ones for ``reporting.max_misses``
   frames (OCCLUDED).

Every rule the paper does not have is a field of ``adaptations.Adaptations`` (one row each
in docs/adaptations.md; ``tracker=pbm_paper`` turns them off); a step such a rule changes
calls a strategy of ``rules.py`` (the paper's or ours, chosen once in the constructor).
Readings of the paper where it is silent (paper mode keeps them) are listed there too, among
them features measured on a fixed grid of samples per box (``reading:sample_grid``), delta
of eqs. 9-10 relative, w (1 + delta i) (``reading:relative_delta``), and eq. 2 used
sign-corrected (``reading:eq2_sign``).

Output ``Track.extra``: ``parts`` (5, 4) xywh part boxes, ``occluded_parts`` (5,) bool
(frozen parts), ``part_scores`` (5,), ``gate`` (4,) xywh KF1 gate the frame's candidates
were validated in (None for a target born this frame).
"""

from __future__ import annotations

import logging
from functools import partial

import numpy as np

from occbench.trackers.common.checks import parameter_group
from occbench.trackers.common.spatial import blocks
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.association import LayeredScores
from occbench.trackers.layered.candidates import (CandidateFinder, DetectorHeads, HeldDetections,
                                                  NoHeldDetections, ProfileHeads, checked_inputs)
from occbench.trackers.layered.dynamics import Gate
from occbench.trackers.layered.frame_blocks import Association, interacting_pairs, merged
from occbench.trackers.layered.gating import OcclusionSearch, in_gates, pairs_in_gates
from occbench.trackers.layered.model_update import chosen_candidates, survivors
from occbench.trackers.layered.params import (
    CandidateParams,
    FeatureParams,
    GateParams,
    LifeCycleParams,
    MatchParams,
    NoiseParams,
    PruneParams,
    ReportParams,
    SearchParams,
    UpdateParams,
)
from occbench.trackers.layered.parts import PartFeatureExtractor, PartFeatures, centroid_ratios
from occbench.trackers.layered.rules import build_rules, place_unfound, reset_rules
from occbench.trackers.layered.search import Candidates, head_patch, head_patches, occlusion_kinds
from occbench.trackers.layered.selection import FrameScores, MultipleResponsePruning
from occbench.trackers.layered.starts import AutoStarts, GivenTargetOnly
from occbench.trackers.layered.targets import PartMatches, PartRates, Targets, dof_from_box
from occbench.trackers.records import Detections, Track, TrackState

logger = logging.getLogger(__name__)

_BOX_COLUMNS = np.array([0, 1, 4, 5])  # xywh in the DOF (xtl, ytl, xc, yc, w, h)


class PBMTracker:
    """Five-part layered-association tracker (PBM), tracking every person in view.

    Its settings come in groups, one per step of PBM Fig. 1 (``occbench.trackers.layered.params``;
    each checks itself and raises ``ValueError`` naming ``<group>.<field>``); None takes
    a group's defaults, which are ``conf/tracker/pbm.yaml``'s.

    Args:
        features: the parts' features and the layers' weights (PBM 2.2, 4.1, eqs. 11-13).
        candidates: detections' heads and foreground blobs (PBM 2, 2.3).
        gate: KF1's gate (PBM 3). noise: KF1 and KF2 noise (eqs. 7-8).
        search: occlusion test and head-anchored search (PBM 3.1, eqs. 9-10).
        matching: thresholds of a match (PBM 4, steps 4-5).
        pruning: multiple-response pruning by the head template (PBM 4.1).
        model_update: the parts and global models' update (PBM 4.2).
        life_cycle: births, confirmation and deaths of targets (ours: PBM 3 starts targets
            by hand).
        reporting: unfound targets in the output.
        adaptations: every rule the paper does not have (``tracker=pbm_paper``: all off).
        starts: who may start a target (``occbench.trackers.layered.starts``): None = ``AutoStarts``
            (every person in view); ``GivenTargetOnly`` for the single-target protocol.
    """

    needs_frames = True  # colour histograms of the parts (PBM 2.2)

    def __init__(
        self,
        features: FeatureParams | None = None,
        candidates: CandidateParams | None = None,
        gate: GateParams | None = None,
        noise: NoiseParams | None = None,
        search: SearchParams | None = None,
        matching: MatchParams | None = None,
        pruning: PruneParams | None = None,
        model_update: UpdateParams | None = None,
        life_cycle: LifeCycleParams | None = None,
        reporting: ReportParams | None = None,
        adaptations: Adaptations | None = None,
        starts: AutoStarts | GivenTargetOnly | None = None,
    ) -> None:
        self.features = parameter_group("features", features, FeatureParams)
        self.candidates = parameter_group("candidates", candidates, CandidateParams)
        self.gate = parameter_group("gate", gate, GateParams)
        self.noise = parameter_group("noise", noise, NoiseParams)
        self.search = parameter_group("search", search, SearchParams)
        self.matching = parameter_group("matching", matching, MatchParams)
        self.pruning = parameter_group("pruning", pruning, PruneParams)
        self.model_update = parameter_group("model_update", model_update, UpdateParams)
        self.life_cycle = parameter_group("life_cycle", life_cycle, LifeCycleParams)
        self.reporting = parameter_group("reporting", reporting, ReportParams)
        self.adaptations = parameter_group("adaptations", adaptations, Adaptations)
        g = self.gate
        self._gate = Gate(g.speed_factor, g.min_fraction, g.miss_factor, g.growth,
                          self.adaptations.gate_max_fraction)
        f = self.features
        self._extractor = PartFeatureExtractor(f.histogram_bins, *f.grid)
        self._search_extractor = PartFeatureExtractor(f.histogram_bins, *f.search_grid, self._extractor)
        a = self.adaptations
        blob_heads = ProfileHeads(self.candidates) if a.profile_heads else DetectorHeads(self.candidates)
        held = HeldDetections(self.search.overlap) if a.held_detections else NoHeldDetections()
        self._finder = CandidateFinder(self.candidates, blob_heads, a.blob_box_ratio, held)
        self._pruning = MultipleResponsePruning(self.matching, self.pruning, self.adaptations)
        self._scores = LayeredScores(f.models, f.omega, f.gamma, a.model_spread,  # eqs. 11-13
                                     a.apart_undivided)
        self._search_occluded = OcclusionSearch(self.search, self._scores, self._search_extractor,
                                                a.coarse_search)
        self.rules = build_rules(self.adaptations, self.reporting.max_misses)
        self.starts = AutoStarts() if starts is None else starts
        self.reset()

    def reset(self) -> None:
        """Forget every target and restart ids at 1."""
        u = self.model_update
        self.targets = Targets(self._gate, self.noise.kf1, self.noise.kf2, u.ratio_window,
                               u.occluded_window, self._extractor.bins)
        self._finder.reset()
        self._next_id, self._frame = 1, 0
        self._stacked: dict[tuple[int, int], int] = {}  # adaptations.fold_twins' evidence
        reset_rules(self.rules)  # the records of measured_velocity, reported_by_record, ...

    # ------------------------------------------------------------------ update (PBM Fig. 1)
    def update(self, frame: np.ndarray, detections: Detections | None,
               foreground: np.ndarray | None = None) -> list[Track]:
        """Advance one frame: the steps of PBM Fig. 1 (module docstring).

        Args:
            frame: (H, W, 3) uint8 BGR image (required: PBM compares colours).
            detections: person boxes (``Detections.heads`` used when present); None = none.
            foreground: (H, W) bool mask or int label image (nonzero = foreground), or None.
        Returns:
            One Track per reported target: CONFIRMED when found, OCCLUDED while unfound,
            TENTATIVE before confirmation.
        """
        frame, detections, fg = checked_inputs(frame, detections, foreground)
        self._frame += 1
        H, W = frame.shape[:2]
        cand, feats = self._find_candidates(frame, detections, fg)  # PBM 2
        pred_wh = self.targets.predict()  # PBM 3, eqs. 7-8
        found = self._associate(frame, cand, feats, fg, pred_wh)  # PBM 3, 3.1, 4, 4.1
        if len(found.matches):
            self._update_models(frame, found, feats, fg, (W, H))  # PBM 4.2
        if len(found.lost):
            self.rules.unfound_size.missed(self.targets, found.lost)
        self._end_targets(W, H, fg)
        self._start_targets(frame, found.free, cand, feats, fg, found.withheld)
        return self._report(fg, W, H)

    def _find_candidates(self, frame: np.ndarray, detections: Detections, fg: np.ndarray | None
                         ) -> tuple[Candidates, PartFeatures]:
        """PBM 2, 2.1: the frame's N candidates (``CandidateFinder``) with their foreground
        centroids set, and their parts split at them (eqs. 1-2) with the features of PBM 2.2."""
        self._extractor.start(frame, fg)
        self._search_extractor.start(frame, fg)
        cand = self._finder.find(fg, detections, frame)
        cand.centroid, feats = self._extractor.extract_at_centroids(cand.box)
        return cand, feats

    def _associate(self, frame: np.ndarray, cand: Candidates, feats: PartFeatures,
                   fg: np.ndarray | None, pred_wh: np.ndarray) -> Association:
        """PBM 3, 3.1, 4, 4.1 on the frame's targets and candidates, in the independent
        blocks of a large frame (``frame_blocks``; one block, the whole frame, while T x N
        is at most ``spatial.DENSE_LIMIT``)."""
        targets = self.targets
        parts = blocks(len(targets), len(cand), lambda: interacting_pairs(targets, cand, pred_wh))
        block = partial(self.rules.merge.associate, self._associate_block)  # merges.py
        if len(parts) == 1:
            return block(frame, targets, cand, feats, fg, pred_wh)
        targets.last_gate = targets.gate_boxes()  # as _score_in_gates sets it
        return merged([(rows, cols, block(
            frame, targets.subset(rows), cand.take(cols), feats.take(cols), fg, pred_wh[rows]))
            for rows, cols in parts], self._extractor.bins)

    def _associate_block(self, frame: np.ndarray, targets: Targets, cand: Candidates,
                         feats: PartFeatures, fg: np.ndarray | None, pred_wh: np.ndarray
                         ) -> Association:
        """One frame's (or block's) scores (``_score_in_gates``), multiple-response pruning
        and contest (PBM 4.1), the matches ``rules.match`` withholds, the lost targets'
        share (``rules.lost``) and the sharing of candidates by 1 - p (``rules.sharing``,
        PBM 4 step 4)."""
        m = self.matching
        scores = FrameScores.empty(len(targets), len(cand))
        if len(targets) and len(cand):
            self._score_in_gates(scores, targets, cand, feats, fg, pred_wh)  # PBM 3, 3.1, eqs. 9-13
            self._pruning(scores, cand, targets, frame, self.rules.merge.matched)  # PBM 4, 4.1
            self.rules.contest.settle(scores.S, cand, targets, frame,  # 4.1, by column
                                      m.match_threshold, self.pruning.template_threshold)
        withheld = self.rules.match.withhold(scores.S, targets, m.match_threshold)
        self.rules.lost.strike(scores.S, targets, self.rules.sharing, 1.0 - m.match_threshold,
                               cand.box)
        cost = np.where(np.isfinite(scores.S), 1.0 - scores.S, np.inf)
        matches, lost, free = self.rules.sharing.assign(cost, 1.0 - m.match_threshold)
        chosen = chosen_candidates(matches, scores, cand, targets, pred_wh) if len(matches) else None
        return Association(matches, lost, free, withheld, chosen,
                           scores.S[matches[:, 0], matches[:, 1]], scores.feats_h)

    def _score_in_gates(self, scores: FrameScores, targets: Targets, cand: Candidates,
                        feats: PartFeatures, fg: np.ndarray | None, pred_wh: np.ndarray) -> None:
        """PBM 3, 3.1, eqs. 11-13: each target scores the candidates in its KF1 gate.

        The unoccluded pairs are scored as measured; the occluded ones (PBM 3.1: size off
        the prediction by more than ``search.occlusion_threshold``) whose carved
        (head-anchored) candidate lies in the gate too (its centre hangs half a predicted
        height below the head) and, for a larger region, that holds the target ("the target
        needs to be located within the blob": a found target's last box lies at least
        ``search.overlap`` inside it) are searched (``gating.OcclusionSearch``). A blob holding
        several heads is a merge, searched (``adaptations.several_heads_merge``). With
        ``adaptations.lone_growth``, a larger
        region holding only this target is the target grown: unoccluded.
        """
        model = self.rules.compared.models(targets)  # eq. 11: the model compared with
        gates = targets.gate_boxes()
        targets.last_gate = gates  # the gates this frame's candidates were validated in
        kinds = occlusion_kinds(cand.region[:, 2:], pred_wh, self.search.occlusion_threshold)
        live = targets.misses <= self.reporting.max_misses
        self.rules.smaller.apply(kinds, cand, targets, pred_wh, live, in_gates(cand.box, gates))
        self.rules.merge.apply(kinds, cand, targets, live, self.search.overlap)
        present = live & self.adaptations.lone_growth
        pairs = pairs_in_gates(targets, cand, gates, pred_wh, kinds, present, self.search.overlap,
                               self.adaptations.several_heads_merge)
        misses = self.rules.gap.misses(targets)  # eq. 11 after a gap
        self.rules.merge.score(scores, pairs, lambda ti, n: self._scores.pairs(  # eqs. 11-13
            model, feats, ti, n, misses), lambda: self._search_occluded(  # PBM 3.1
            targets, cand, pairs, fg, pred_wh, model, misses))
        self.rules.merge.strike(scores.S)  # merges.py: a merge read as another target grown

    # ------------------------------------------------------------------ model update (PBM 4.2)
    def _update_models(self, frame: np.ndarray, found: Association, feats: PartFeatures,
                       fg: np.ndarray | None, image_size: tuple[int, int]) -> None:
        """PBM 4.2 for the frame's matches (``found``), all at once: the global
        models and filters (``Targets.update``: DOF measured when unoccluded, window-averaged
        when occluded; after a gap ``rules.reupdate``), then each part by a running average
        weighted by p_j, frozen below ``model_update.part_threshold`` (``update_parts``; with
        ``adaptations.stale`` a visible part failing to match is re-learned; with
        ``adaptations.contact_frozen`` / ``contact_colour`` a part under another target's box
        keeps its model / its colours: ``rules.contact``), the match
        scores, the head templates of unoccluded targets whose head matched (PBM 4.1), and
        confirmation after ``life_cycle.min_hits`` matches (``rules.confirmation``)."""
        targets, u = self.targets, self.model_update
        mt = found.matches[:, 0]
        dof, pj, occl, ks = found.chosen
        measured = ~occl if fg is not None else np.zeros(len(mt), dtype=bool)
        window = self.rules.window.occluded(targets, mt, dof, occl, self.reporting.max_misses)
        shift = self.rules.reupdate.update(targets, mt, dof, measured, window, pj, u.part_threshold)
        targets.occluded[mt] = occl  # PBM 3.1's carved match (exits read it), whatever averaged
        # then the parts models, from the feature arrays the candidates were measured in
        dof_t = targets.dof
        n_occl = np.count_nonzero(occl)
        groups = [(~occl, feats)] if n_occl < len(mt) else []
        if n_occl:
            groups.append((occl, found.searched))
        relearn, stale = None, self.adaptations.stale
        if stale is not None and n_occl < len(mt):
            # among unoccluded matches, before the update (the model's foreground area is
            # the reference)
            un = ~occl
            relearn = stale.relearn(targets, mt[un], feats, ks[un], pj[un], u.part_threshold,
                                    self.reporting.max_misses, image_size)
        rates = PartRates(u.part_threshold, u.rate, 1.0 if stale is None else stale.relearn_rate)
        for g, (rows, f) in enumerate(groups):
            r = mt[rows]
            self.rules.contact.update(targets, f, PartMatches(  # update_parts (contact_*)
                r, ks[rows], pj[rows], shift[rows], dof_t[r[:, None], _BOX_COLUMNS],
                targets.alpha[r], targets.beta[r], relearn if g == 0 else None), rates,
                self.reporting.max_misses)
        targets.score[mt] = found.score
        fresh = mt[~occl & (pj[:, 0] >= u.part_threshold)]
        for ti, tpl in zip(fresh.tolist(), head_patches(frame, dof_t[fresh[:, None], _BOX_COLUMNS])):
            if tpl is not None:
                targets.head_template[ti] = tpl
        self.rules.confirmation.confirm(targets, mt, self.life_cycle.min_hits)

    # ------------------------------------------------------------------ life cycle (ours)
    def _end_targets(self, W: int, H: int, fg: np.ndarray | None) -> None:
        """Drop tentative targets that missed, confirmed ones unfound for more than
        ``life_cycle.max_misses`` frames, (``adaptations.exit_margin``) those unfound for
        ``adaptations.exit_misses`` frames whose predicted box left the (W, H) image, and
        (``adaptations.fold_twins``) twins standing on an older target's person."""
        targets, a = self.targets, self.adaptations
        alive = survivors(targets, W, H, a, self.life_cycle.max_misses)
        gone = self.rules.exit.gone(targets, W, H)  # adaptations.border_exit
        if gone is not None:
            alive &= ~(gone & (targets.misses >= max(a.exit_misses, 1)))
        alive &= ~self.rules.twins.folded(targets, self.rules.report_box, fg,  # fold_twins
                                          self.reporting.max_misses, self._stacked)
        if np.count_nonzero(alive) < len(alive):
            targets.take(alive.nonzero()[0])

    def _start_targets(self, frame: np.ndarray, free: np.ndarray, cand: Candidates,
                       feats: PartFeatures, fg: np.ndarray | None, withheld: np.ndarray | None) -> None:
        """While ``starts`` allows, a TENTATIVE target from each free candidate (new blobs,
        split heads) that is tall enough (``life_cycle.min_height``), a detection or
        (``life_cycle.blob_births``) a blob, not withheld (``rules.match``), supported by
        foreground (``rules.birth``) and overlapping no live target
        (``life_cycle.new_track_iou``); confirmed at once in the first ``min_hits`` frames."""
        targets, lc = self.targets, self.life_cycle
        live_boxes = targets.boxes if len(free) else None
        new: list[tuple] = []  # (id, dof, alpha, beta, candidate, head template), in order
        for n in free.tolist():  # (the assignment leaves exactly the untaken candidates free)
            if not self.starts.may_start(self._frame, self._next_id - 1):
                break
            box = cand.box[n]
            if box[3] < lc.min_height:
                continue
            if cand.blob[n] and not lc.blob_births:
                continue
            if withheld is not None and withheld[n]:
                continue
            if not self.rules.birth.supported(feats.area[n], fg is not None):
                continue
            if len(live_boxes) and iou_matrix(box[None], live_boxes).max() > lc.new_track_iou:
                continue
            centroid = cand.centroid[n]
            al_n, be_n = centroid_ratios(box[None], centroid[None])
            dof = dof_from_box(box, centroid)
            new.append((self._next_id, dof, float(al_n[0]), float(be_n[0]), n,
                        head_patch(frame, dof[[0, 1, 4, 5]])))
            self._next_id += 1
            live_boxes = np.vstack([live_boxes, box[None]])
        if new:  # added at once (one copy of the state arrays)
            ids, dofs, alphas, betas, ns, templates = zip(*new, strict=True)
            targets.extend(list(ids), np.array(dofs), list(alphas), list(betas),
                           feats.take(list(ns)), list(templates))
            born = np.arange(len(targets.id) - len(new), len(targets.id))
            targets.confirmed[born] |= self._frame <= lc.min_hits
            self.rules.confirmation.confirm_born(targets, born, frame.shape[1::-1])  # early_confirm 1

    # ------------------------------------------------------------------ report
    def _report(self, fg: np.ndarray | None, W: int, H: int) -> list[Track]:
        """One Track per reported target: found, or confirmed and unfound for at most
        ``reporting.max_misses`` frames (``rules.behind``: longer; OCCLUDED, score 0) where
        ``rules.report_box`` / ``rules.velocity`` put it, as ``rules.report_shown`` and
        ``rules.leaving`` allow in the (W, H) image."""
        tg = self.targets
        found = shown = tg.misses == 0
        if self.reporting.occluded:
            shown = found | (tg.confirmed & (tg.misses <= self.reporting.max_misses))
            shown = self.rules.behind.shown(tg, found, shown, self.rules.report_box, fg)
        rows = shown.nonzero()[0]
        # copies (fancy indexing): the rows of the state arrays change in place later
        boxes = tg.dof[rows[:, None], _BOX_COLUMNS]
        self.rules.report_box.place(boxes, tg, rows, found)
        place_unfound(self.rules.velocity, self._frame, tg, rows, boxes, found)
        keep = self.rules.report_shown.shown(boxes, fg, tg.hits[rows], tg.misses[rows])
        keep = self.rules.leaving.shown(boxes, tg.kf1.x[rows, 2:], found[rows], W, H, keep)
        if keep is not None:
            rows, boxes = rows[keep], boxes[keep]
        rects = tg.parts.parts[rows]
        occluded_parts, part_scores, gates = tg.occluded_parts[rows], tg.part_scores[rows], tg.last_gate[rows]
        found = found[rows]
        score = np.where(found, tg.score[rows].clip(0.0, 1.0), 0.0).tolist()
        states = [(TrackState.CONFIRMED if c else TrackState.TENTATIVE) if f else TrackState.OCCLUDED
                  for f, c in zip(found.tolist(), tg.confirmed[rows].tolist())]
        return [Track(i, box, state, s, {"parts": r, "occluded_parts": o, "part_scores": p,
                                         "gate": g if has_g else None})
                for i, box, state, s, r, o, p, g, has_g in zip(
                    tg.id[rows].tolist(), boxes, states, score, rects, occluded_parts, part_scores,
                    gates, np.isfinite(gates[:, 0]).tolist())]
