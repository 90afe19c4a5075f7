"""PBM: part-based model with layered data association, multi-target.

Paper: "Tracking People under Heavy Occlusions by Layered Data Association" (PBM). Per
frame (PBM Fig. 1):

1. Candidates (``search.Candidates``): each detection box with its head, plus every head of
   every foreground blob (connected components, PBM 2) that no detection explains. Heads
   come from ``Detections.heads`` when given, else from the foreground: the top band (1/7)
   of a detection box, and the peaks of a blob's top profile. With ``foreground=None`` the
   detection boxes are the candidate blobs and every box pixel counts as foreground
   (area and perimeter then carry no information; colour, displacement and overlap do).
2. Dynamical model (PBM 3): KF1 gives the gate (zero-order centre, size from speed,
   doubled after a miss and growing until found or dropped); KF2 predicts (w, h).
3. Occlusion detection (PBM 3.1): size differs from the prediction by > 50%. Larger
   candidates (and blobs holding several heads) get the head-anchored search over
   w (1 + delta i), h (1 + delta i); smaller ones are aligned on their head or dismissed.
4. Layered association (PBM 4.1): eq. 11 differences -> eq. 12 part scores (weights
   omega) -> eq. 13 global score (weights gamma); per target the best gated candidate must
   pass ``matching.match_threshold`` and beat the runner-up by ``matching.margin_ratio``; otherwise (or when
   all scores are weak, above ``matching.weak_threshold``) the target's head template is matched in
   a local neighbourhood and the candidate nearest the refined head is kept (multiple-
   response pruning). Targets then share candidates one-to-one by the Hungarian method on
   1 - p (a multi-target addition: the paper tracks one target at a time).
5. Model update (PBM 4.2): ``model.Targets.update`` (global model, KF1, KF2) and
   ``model.update_parts`` (the parts models), for all matched targets at once.

Multi-target life cycle (an adaptation: the paper initialises by hand, PBM 3): a candidate
that no target takes starts a TENTATIVE target (new blobs, and heads of a blob that split
from another); it is CONFIRMED after ``life_cycle.min_hits`` matches in a row and dropped if it
misses before. A confirmed target that is not found is reported OCCLUDED for up to
``reporting.max_misses`` frames when ``reporting.occluded``: at its last validated box
(zero-order, as the gate), or moved by KF1's constant-velocity prediction when
``adaptations.report_predicted``; it is dropped after ``life_cycle.max_misses`` frames, or after ``adaptations.exit_misses``
frames when its box moved by KF1's prediction has crossed the image border by more than
``adaptations.exit_margin`` (it left; someone standing at the border and missed is not leaving).

Output ``Track.extra``: ``parts`` (5, 4) part boxes, ``occluded_parts`` (5,) bool (frozen
parts), ``part_scores`` (5,), ``gate`` (4,) xywh KF1 gate the frame's candidates were
validated in (None for a target born this frame).

Adaptations (where the paper is vague or relies on what we do not have):

- Heads: ``Detections.heads`` when given, else the PBM 2.3 hair/skin detector when
  ``candidates.head_detector`` is set, else the top 1/7 band of a detection's foreground; on blobs,
  the peaks of the top profile.
- Features are measured on a fixed grid of samples per box (``PartFeatureExtractor``):
  scale-free area/perimeter/colour, one vectorised pass for all candidates of a frame.
- p(d | theta) of eq. 12 is the model's survival function P(D >= d) (``models``), applied
  to d / ``adaptations.model_spread``: models fitted on clean annotated pairs are stretched for the
  larger differences of live tracking (overlapping people, detection noise).
- delta of eqs. 9-10 is relative (w (1 + delta i)); eq. 2 is used sign-corrected.
- Detection boxes and blob spans differ systematically (box margins, swinging limbs):
  blob-born boxes are rescaled by a ratio learned online from isolated person/detection
  pairs, and a blob candidate keeps KF2's width.
- The occlusion test applies to every candidate as in the paper; a blob with several
  heads counts as merged (searched) whatever its size.
- Lone growth (``adaptations.lone_growth``): a region larger by size alone (one head) that holds the
  target and no other found or reported target is the target grown, not a merge: a person
  walking in through a border or a doorway, whose box widens over ten frames or so. The
  paper's search (w, h within +-10%) would keep the box it was first seen with.
- After a gap of m frames the displacement and overlap differences are divided by 1 + m.
- Motion compensation (``adaptations.motion_compensation``): displacement and overlap (eq. 11) compare
  a candidate with the parts model moved by KF1's constant-velocity prediction since the
  target was last found. The paper compares the last frame as it is; in crowds a
  neighbour's box then overlaps the last box about as much as the person's own. The gate
  stays zero-order (PBM 3), so a person who turns back while hidden is still searched for
  where they were last seen, and after a gap of m frames the differences are divided by
  1 + m as above.
- KF2 holds the size of an unfound target (its size rates are zeroed at a miss): a hidden
  person's size is not extrapolated, so the occlusion test and the search boxes of a long
  lost target keep a person's size.
- Multiple responses (PBM 4.1) whose heads coincide (within ``adaptations.duplicate_radius`` head
  widths of the best one's) are one response: the best is kept, no head template is
  matched (it could not tell them apart).
- A target unfound for more than ``adaptations.prune_max_misses`` frames is not pruned by its head
  template (taken when it was last seen, it has gone stale):
  an ambiguous choice keeps the best candidate, a weak candidate is left.
- Stale parts (``adaptations.stale``): a
  frozen part (PBM 4.2) whose person's appearance has moved on keeps failing to match and
  is never updated again. A
  part is judged hidden from evidence other than p_j: another target's box over it, the
  image border, or its foreground area fallen below ``fill`` of its model's (a wall).
  A part that is visible by all three yet fails to match ``stale_frames`` times is
  re-learned; a hidden part stays frozen, as in the paper.
- Targets are born from detections (and from free blobs when ``life_cycle.blob_births``), and with
  foreground only from candidates with a part holding foreground (``adaptations.min_support``): a
  detection over background is a false alarm, never a person.
- Relative match (``adaptations.relative_match``): a target found in the previous frame takes no
  candidate scoring below ``adaptations.relative_match`` times its last match's score: when its own
  detection is missed, a neighbour's detection that merely passes ``matching.match_threshold`` is
  not taken (in crowds that first swap started the cascades of identity switches).
- ``adaptations.occluded_cover`` (off by default): an unfound target is reported only while found
  targets' boxes cover it.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from trackers.common.assignment import assign
from trackers.geometry import iou_matrix, overlap_ratio_matrix
from trackers.layered._glue_kernels import (
    alive_rows,
    carved_rows,
    gated_pairs,
    matched_rows,
)
from trackers.layered._search_kernels import foreground_counts
from trackers.layered.association import ambiguous_rows, pair_scores
from trackers.layered.dynamics import Gate
from trackers.layered.model import (
    Targets,
    dof_from_box,
    dof_from_head,
    stale_parts,
    update_parts,
)
from trackers.layered.params import (
    Adaptations,
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
from trackers.layered.parts import (
    N_PARTS,
    PartFeatureExtractor,
    PartFeatures,
    centroid_ratios,
)
from trackers.layered.search import (
    Candidates,
    blobs_boxes,
    head_fill,
    head_patch,
    head_patches,
    heads_from_bands,
    match_head_template,
    occlusion_kinds,
    residual_foreground,
    search_boxes_many,
    split_blob_box,
    top_profile_heads,
)
from trackers.records import Detections, Track, TrackState

logger = logging.getLogger(__name__)

_BOX_COLUMNS = np.array([0, 1, 4, 5])  # xywh in the DOF (xtl, ytl, xc, yc, w, h)


def _norms(v: np.ndarray) -> np.ndarray:
    """(K,) Euclidean norms of the rows of v (K, 2), each equal bit for bit to
    ``np.linalg.norm(v[k])`` (the same dot product, one per row)."""
    return np.sqrt(np.vecdot(v, v))


class PBMTracker:
    """Five-part layered-association tracker (PBM), tracking every person in view.

    Its settings come in groups, one per step of PBM Fig. 1 (``trackers.layered.params``;
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
    """

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
    ) -> None:
        groups = {"features": (features, FeatureParams), "candidates": (candidates, CandidateParams),
                  "gate": (gate, GateParams), "noise": (noise, NoiseParams),
                  "search": (search, SearchParams), "matching": (matching, MatchParams),
                  "pruning": (pruning, PruneParams), "model_update": (model_update, UpdateParams),
                  "life_cycle": (life_cycle, LifeCycleParams), "reporting": (reporting, ReportParams),
                  "adaptations": (adaptations, Adaptations)}
        for name, (value, cls) in groups.items():
            if value is None:
                value = cls()
            elif not isinstance(value, cls):
                raise ValueError(f"{name} must be {cls.__name__} or None, got {type(value).__name__}")
            setattr(self, name, value)
        g = self.gate
        self._gate = Gate(g.speed_factor, g.min_fraction, g.miss_factor, g.growth,
                          self.adaptations.gate_max_fraction)
        f = self.features
        self._extractor = PartFeatureExtractor(f.histogram_bins, *f.grid)
        self._search_extractor = PartFeatureExtractor(f.histogram_bins, *f.search_grid)
        self.reset()

    def reset(self) -> None:
        """Forget every target and restart ids at 1."""
        self.targets = Targets(self._gate, self.noise.kf1, self.noise.kf2, self.model_update.ratio_window,
                               self.model_update.occluded_window, self._extractor.bins)
        self._next_id = 1
        self._blob_to_box = np.ones(2)  # detection (w, h) / blob span (w, h), learned online
        self._blob_pairs = 0
        self._frame = 0
        self._had_fg = False

    # ------------------------------------------------------------------ candidates
    def _anchors(self, fg: np.ndarray | None, detections: Detections,
                 frame: np.ndarray | None = None, fg_residual: int | None = None) -> Candidates:
        """The frame's candidates (PBM 2, 3.1): the valid detection boxes with their heads,
        then the heads of foreground blobs that no detection explains (``fg_residual``: the
        number of foreground pixels that no detection box covers, ``residual_foreground``,
        when known)."""
        det_boxes = detections.boxes
        heads = detections.heads
        if heads is None and self.candidates.head_detector is not None and frame is not None and len(det_boxes):
            heads = np.asarray(self.candidates.head_detector.detect(frame, fg, det_boxes), dtype=np.float64)
        valid = (np.logical_and.reduce(np.isfinite(det_boxes), axis=1)
                 & (det_boxes[:, 2] > 1) & (det_boxes[:, 3] > 1)).nonzero()[0]
        box = det_boxes[valid]
        if fg is not None:  # the top 1/7 band's foreground (PBM 3.1)
            head = heads_from_bands(fg, box)
        else:  # the band's centre
            x, y, w = box[:, 0], box[:, 1], box[:, 2]
            head = np.column_stack([x + 0.5 * w, y, 0.5 * w])
        if heads is not None:  # the source's heads where it gives them
            has_head = np.logical_and.reduce(np.isfinite(heads[valid]), axis=1)
            hx, hy, hw = heads[valid[has_head], :3].T
            head[has_head] = np.column_stack([hx + 0.5 * hw, hy, hw])
        rows = (box, box.copy(), head, np.zeros(len(valid), dtype=bool),
                np.ones(len(valid), dtype=np.int64))
        if fg is None:
            return Candidates(*rows)
        # blobs matter only where foreground is left unexplained by the detections
        if fg_residual is None and len(det_boxes):
            fg_residual = residual_foreground(fg, det_boxes)
        if len(det_boxes) and fg_residual < self.candidates.min_blob_area:
            return Candidates(*rows)
        s = self.candidates.blob_downsample
        small = np.ascontiguousarray(fg[::s, ::s]) if s > 1 else fg
        labels, bboxes, numbers = blobs_boxes(small, max(self.candidates.min_blob_area // (s * s), 1))
        if len(bboxes) and len(det_boxes):
            blob_iou = iou_matrix(bboxes * s, det_boxes)  # for ``_calibrate``
            # the head zone of each detection: its top third (and a tenth above)
            zx0, zx1 = det_boxes[:, 0, None], (det_boxes[:, 0] + det_boxes[:, 2])[:, None]
            zy0 = (det_boxes[:, 1] - 0.1 * det_boxes[:, 3])[:, None]
            zy1 = (det_boxes[:, 1] + det_boxes[:, 3] / 3.0)[:, None]
        blob_rows: list[tuple] = []
        for i, (sbox, lab) in enumerate(zip(bboxes, numbers)):
            x, y, w, h = (int(v) for v in sbox)
            mask = labels[y:y + h, x:x + w] == lab
            peaks = top_profile_heads(mask, max(self.candidates.head_separation * h, 3.0 / s),
                                      max(0.06 * h, 2.0 / s))
            bbox = sbox * s
            hx = (peaks[:, 0] + x + 0.5) * s
            hy = (peaks[:, 1] + y) * s
            # heads explained by a detection: inside a detection box's top third
            if len(det_boxes):
                explained = ((hx >= zx0) & (hx <= zx1) & (hy >= zy0) & (hy <= zy1)).any(axis=0)
            else:
                explained = np.zeros(len(peaks), dtype=bool)
            if len(peaks) == 1 and explained[0]:
                self._calibrate(bbox, blob_iou[i], det_boxes)
            if explained.all():
                continue
            n = len(peaks)
            head_w = max(self.candidates.head_separation * bbox[3], 3.0)
            for k in np.nonzero(~explained)[0]:
                own = (bbox.copy() if n == 1
                       else split_blob_box(mask, sbox[:2], peaks[:, 0], int(k)) * s)
                blob_rows.append((self._blob_box_as_detection(own), bbox,
                                  np.array([hx[k], hy[k], head_w]), n))
        if not blob_rows:
            return Candidates(*rows)
        own, region, head, n = zip(*blob_rows)
        return Candidates(np.vstack([rows[0], own]), np.vstack([rows[1], region]),
                          np.vstack([rows[2], head]),
                          np.concatenate([rows[3], np.ones(len(own), dtype=bool)]),
                          np.concatenate([rows[4], np.array(n, dtype=np.int64)]))

    def _calibrate(self, blob_box: np.ndarray, iou: np.ndarray, det_boxes: np.ndarray) -> None:
        """Learn the ratio of detection box size to blob span from isolated people.

        A detector's boxes and a foreground blob's span differ systematically (limbs, box
        margins); a blob holding one head and overlapping exactly one detection (IoU >
        0.5) gives one sample of (w_det / w_blob, h_det / h_blob); the first 20 samples
        are averaged, later ones enter a running average with weight 0.05.

        Args:
            blob_box: (4,) xywh blob. iou: (D,) its IoU with each of ``det_boxes`` (D, 4).
        """
        if (iou > 0.3).sum() != 1 or iou.max() < 0.5:
            return
        d = det_boxes[int(np.argmax(iou))]
        r = d[2:] / np.maximum(blob_box[2:], 1.0)
        self._blob_pairs += 1
        rate = max(1.0 / self._blob_pairs, 0.05)
        self._blob_to_box += rate * (r - self._blob_to_box)

    def _blob_box_as_detection(self, box: np.ndarray) -> np.ndarray:
        """A blob box rescaled about its centre to the detections' box convention."""
        if self._blob_pairs == 0:
            return box
        c = box[:2] + 0.5 * box[2:]
        wh = box[2:] * self._blob_to_box
        return np.array([c[0] - 0.5 * wh[0], box[1], wh[0], wh[1]])

    # ------------------------------------------------------------------ hypotheses
    def _occluded_hypotheses(self, ti: np.ndarray, n: np.ndarray, kind: np.ndarray,
                             cand: Candidates, fg: np.ndarray | None, pred_wh: np.ndarray,
                             model: PartFeatures) -> tuple:
        """Head-anchored search (larger) or alignment (smaller) of PBM 3.1 for the P
        (target ti, candidate n, kind) pairs of the frame, with one feature extraction for
        all: the (2 r + 1)^2 boxes of eqs. 9-10 of every searched pair, then the aligned
        box of every smaller candidate whose head is supported by foreground.

        Args:
            ti, n, kind: (P,) the pairs (kind +1 larger, -1 smaller region).
            model: the parts models of all targets (``PartFeatures``, target order).
        Returns:
            (kept (P,) bool (False: dismissed), score p (P,), part scores p_j (P, 5),
            features, index k (P,) of each pair's best box in them, dof (P, 6)), or None
            when every pair is dismissed.
        """
        targets = self.targets
        alpha_t, beta_t = targets.alpha, targets.beta
        heads = cand.head[n]
        search_q = (kind > 0).nonzero()[0]
        align_q = (kind <= 0).nonzero()[0]
        if len(align_q):
            # the predicted-size box aligned on the head (``search.aligned_box``)
            at = ti[align_q]
            w, h = pred_wh[at, 0], pred_wh[at, 1]
            ha = heads[align_q]
            align_boxes = np.column_stack([ha[:, 0] - alpha_t[at] * w, ha[:, 1], w, h])
            if fg is not None:
                fill = np.array([head_fill(fg, b) for b in align_boxes])
                supported = fill >= self.search.head_min_fill
                align_q, align_boxes = align_q[supported], align_boxes[supported]
        if not len(search_q) and not len(align_q):
            return None
        m = (2 * self.search.range + 1) ** 2
        sti = ti[search_q]
        B = np.concatenate([search_boxes_many(heads[search_q], pred_wh[sti], alpha_t[sti],
                                              self.search.step, self.search.range).reshape(-1, 4),
                            align_boxes if len(align_q) else np.zeros((0, 4))])
        tis = np.concatenate([sti.repeat(m), ti[align_q]])
        feats = self._search_extractor.extract(B, alpha_t[tis], beta_t[tis])
        # eqs. 11-13 of every carved box k against the model of its target tis[k]
        pj, p = self._scores(model, feats, tis, np.arange(len(tis)))
        kept, p_h, pj_h, k, dof = carved_rows(p, pj, B, heads, ti, alpha_t, beta_t, search_q, align_q, m)
        return kept, p_h, pj_h, feats, k, dof

    def _scores(self, model: PartFeatures, feats: PartFeatures, ti: np.ndarray,
                n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Eqs. 11-13 of the pairs (target ti[k], candidate n[k]): p_j (K, 5), p (K,)."""
        return pair_scores(self.features.models, model, feats, ti, n, self.targets.misses,
                           self.features.omega, self.features.gamma, self.adaptations.model_spread)

    # ------------------------------------------------------------------ pruning
    def _prune(self, template: np.ndarray | None, cands: np.ndarray, heads: np.ndarray,
               frame: np.ndarray) -> tuple[int, np.ndarray | None]:
        """Multiple-response pruning (PBM 4.1): the target's head template is matched
        around the heads (x top-centre, y top) (K, 2) of the candidates ``cands`` (K,)
        (``match_head_template``, on the grey of the BGR ``frame``'s search window only);
        returns the candidate nearest the refined head and that head, or (-1, None) when
        the template does not match.

        The centre is the heads' mean, the radius their largest distance from it (plus
        half the template width and 2 pixels); a few heads are summed as Python floats in
        numpy's order (row by row), more by numpy itself.
        """
        if template is None or not len(cands):
            return -1, None
        tw = template.shape[1]
        if len(cands) < 8:
            hs = heads.tolist()
            cx, cy = hs[0]
            for hx, hy in hs[1:]:
                cx, cy = cx + hx, cy + hy
            cx, cy = cx / len(hs), cy / len(hs)
            radius = max(math.sqrt((hx - cx) * (hx - cx) + (hy - cy) * (hy - cy)) for hx, hy in hs)
        else:
            cx, cy = heads.mean(axis=0).tolist()
            radius = float(np.max(np.linalg.norm(heads - [cx, cy], axis=1)))
        tl, corr = match_head_template(frame, template, (cx - 0.5 * tw, cy), radius + 0.5 * tw + 2)
        if corr < self.pruning.template_threshold:
            return -1, None
        rx, ry = tl[0] + 0.5 * tw, float(tl[1])
        if len(cands) < 8:
            dist = [math.sqrt((hx - rx) * (hx - rx) + (hy - ry) * (hy - ry)) for hx, hy in hs]
            nearest = dist.index(min(dist))
        else:
            nearest = int(np.argmin(np.linalg.norm(heads - [rx, ry], axis=1)))
        return int(cands[nearest]), np.array([rx, ry])

    # ------------------------------------------------------------------ update
    def update(self, frame: np.ndarray, detections: Detections | None,
               foreground: np.ndarray | None = None) -> list[Track]:
        """Advance one frame.

        Args:
            frame: (H, W, 3) uint8 BGR image (required: PBM compares colours).
            detections: person boxes (``Detections.heads`` used when present); None = none.
            foreground: (H, W) bool mask or int label image (nonzero = foreground), or None.
        Returns:
            One Track per live target: CONFIRMED when found, OCCLUDED (last box) while
            unfound, TENTATIVE before confirmation.
        """
        if frame is None:
            raise ValueError("PBMTracker.update: frame is None; PBM needs pixels (colour histograms of the parts)")
        frame = np.asarray(frame)
        if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ValueError(f"PBMTracker.update: frame must be (H, W, 3) uint8 BGR, got {frame.shape} {frame.dtype}")
        if detections is None:
            detections = Detections.empty()
        fg, fg_residual = None, None
        if foreground is not None:
            foreground = np.asarray(foreground)
            if foreground.shape != frame.shape[:2]:
                raise ValueError(f"PBMTracker.update: foreground shape {foreground.shape} "
                                 f"differs from frame {frame.shape[:2]}")
            if foreground.dtype == bool:
                fg = np.ascontiguousarray(foreground)
            elif foreground.dtype.kind in "iu" and foreground.dtype.isnative:
                # a label image: the mask, its pixels and those the detections cover, in one pass
                fg, count, covered = foreground_counts(
                    foreground, np.asarray(detections.boxes, dtype=np.float64).reshape(-1, 4))
                fg_residual = count - covered
            else:
                fg = foreground != 0
        self._frame += 1
        self._had_fg = fg is not None
        H, W = frame.shape[:2]
        self._extractor.start(frame, fg)
        self._search_extractor.start(frame, fg)
        cand = self._anchors(fg, detections, frame, fg_residual)
        n_a = len(cand)
        boxes = cand.box
        # foreground centroids (PBM 2.1) and the parts split at them, on one grid
        cand.centroid, feats = self._extractor.extract_at_centroids(boxes)
        targets = self.targets
        pred_wh = targets.predict()
        T = len(targets)
        S = np.empty((T, n_a))
        S.fill(-np.inf)
        # occluded candidates: hyp[ti, n] indexes the pair's row of the search's arrays
        # (``_occluded_hypotheses``); the unoccluded ones are read from the frame's arrays
        hyp = np.empty((T, n_a), dtype=np.intp)
        hyp.fill(-1)
        pj_all = np.zeros((T, n_a, N_PARTS))
        # the search's rows (``_occluded_hypotheses``): none yet
        feats_h, pj_h, k_h, dof_h = None, np.zeros((0, N_PARTS)), np.zeros(0, np.intp), np.zeros((0, 6))
        if T and n_a:
            model = targets.parts
            if self.adaptations.motion_compensation:
                model = model.shifted(targets.predicted_shift())
            gates = targets.gate_boxes()
            targets.last_gate = gates  # the gates this frame's candidates were validated in
            # candidates in each target's gate (PBM 3) and the occlusion test (PBM 3.1): the
            # unoccluded pairs; the occluded ones whose carved (head-anchored) candidate lies
            # in the gate too (its centre hangs half a predicted height below the head) and,
            # for a larger region, that holds the target (PBM 3.1: "the target needs to be
            # located within the blob"): a found target's last box lies at least
            # ``search_overlap`` inside it. A blob holding several heads is a merge: searched.
            kinds = occlusion_kinds(cand.region[:, 2:], pred_wh, self.search.occlusion_threshold)
            present = (targets.misses <= self.reporting.max_misses) & self.adaptations.lone_growth
            ti_in, n_in, ti_s, n_s, kind_s = gated_pairs(
                boxes, cand.region, cand.head, cand.heads_in_region, gates,
                pred_wh, kinds, targets.dof, targets.misses,
                self.search.overlap, present)
            # eqs. 11-13 for the unoccluded candidates
            pj_in, p_in = self._scores(model, feats, ti_in, n_in)
            pj_all[ti_in, n_in] = pj_in
            S[ti_in, n_in] = p_in
            found = (self._occluded_hypotheses(ti_s, n_s, kind_s, cand, fg, pred_wh, model)
                     if len(ti_s) else None)
            if found is not None:
                kept, p_h, pj_h, feats_h, k_h, dof_h = found
                S[ti_s[kept], n_s[kept]] = p_h[kept]
                hyp[ti_s[kept], n_s[kept]] = kept.nonzero()[0]
            # selection per target, with multiple-response pruning (PBM 4, steps 4-5)
            # (the loop below changes only row ti of S, after reading it)
            bests, _, ambs = ambiguous_rows(S, self.matching.match_threshold, self.matching.margin_ratio)
            weaks = (bests < 0) & (np.maximum.reduce(S, axis=1) >= self.matching.weak_threshold)
            heads_xy = cand.head[:, :2]
            for ti in (ambs | weaks).nonzero()[0].tolist():
                row = S[ti]
                best, amb, weak = int(bests[ti]), bool(ambs[ti]), bool(weaks[ti])
                lo = self.matching.match_threshold if amb else self.matching.weak_threshold
                cands = (row >= lo).nonzero()[0]
                # only nearby candidates are multiple responses of one person (PBM 4.1);
                # distant rivals are left to the one-to-one assignment
                r = best if best >= 0 else int(np.argmax(row))
                hw = max(cand.head[r, 2], 1.0)
                dist = _norms(heads_xy[cands] - heads_xy[r])
                near = dist <= self.pruning.radius * hw
                cands = cands[near]
                if amb and len(cands) < 2:
                    continue
                if targets.misses[ti] > self.adaptations.prune_max_misses:
                    # a long-lost target's head template is stale: no pruning by it
                    if weak:
                        continue
                    chosen, refined = best, None
                elif amb and dist[near].max() <= self.adaptations.duplicate_radius * hw:
                    chosen, refined = best, None  # one response: the heads coincide
                else:
                    chosen, refined = self._prune(targets.head_template[ti], cands, heads_xy[cands], frame)
                if chosen < 0:
                    if weak:
                        continue
                    chosen = best
                elif refined is not None and hyp[ti, chosen] >= 0:
                    # "the matching candidate is then updated accordingly": a carved
                    # (occluded) candidate is re-anchored on the refined head
                    q = hyp[ti, chosen]
                    dof_h[q] = dof_from_head(refined, dof_h[q, 4], dof_h[q, 5], targets.alpha[ti],
                                             targets.beta[ti])
                keep = row[chosen]
                S[ti, cands] = -np.inf
                S[ti, chosen] = max(keep, self.matching.match_threshold)
        withheld = None
        if self.adaptations.relative_match > 0 and T and n_a:
            # a target found last frame takes no candidate scoring below relative_match x
            # the score of that match (its own detection missed, a neighbour's is no match)
            ref = np.where(targets.misses == 0, targets.score, 0.0)
            weak = (S < self.adaptations.relative_match * ref[:, None]) & (S >= self.matching.match_threshold)
            withheld = weak.any(axis=0)  # a poor match of a known target starts no new one
            S[weak] = -np.inf
        cost = np.where(np.isfinite(S), 1.0 - S, np.inf)
        matches, lost, free = assign(cost, 1.0 - self.matching.match_threshold)
        if len(matches):
            # model update (PBM 4.2): global models and filters of all matched targets at once
            mt, mn = matches[:, 0], matches[:, 1]
            dof, pj, occl, ks = matched_rows(mt, mn, hyp, boxes, cand.centroid, cand.blob, pred_wh,
                                             targets.alpha, pj_all, dof_h, pj_h, k_h)
            measured = ~occl if fg is not None else np.zeros(len(mt), dtype=bool)
            shift = targets.update(mt, dof, measured, occl, pj, self.model_update.part_threshold)
            # then the parts models, from the feature arrays the candidates were measured in
            dof_t = targets.dof
            n_occl = np.count_nonzero(occl)
            groups = [(~occl, feats)] if n_occl < len(mt) else []
            if n_occl:
                groups.append((occl, feats_h))
            relearn, stale = None, self.adaptations.stale
            if stale is not None and n_occl < len(mt):
                # stale parts (adaptation): visible, failing to match, among unoccluded matches
                # (before the update: the model's foreground area is the reference)
                un = ~occl
                relearn = stale_parts(targets, mt[un], feats, ks[un], pj[un],
                                      self.model_update.part_threshold, self.reporting.max_misses, (W, H),
                                      stale.cover, stale.fill, stale.frames)
            for g, (rows, f) in enumerate(groups):
                r = mt[rows]
                update_parts(targets.parts, r, f, ks[rows], pj[rows], self.model_update.part_threshold,
                             self.model_update.rate, shift[rows], dof_t[r[:, None], _BOX_COLUMNS],
                             targets.alpha[r], targets.beta[r],
                             relearn if g == 0 else None,
                             1.0 if stale is None else stale.relearn_rate)
            targets.score[mt] = S[mt, mn]
            # new head templates of the targets whose head matched, unoccluded (PBM 4.1)
            fresh = mt[~occl & (pj[:, 0] >= self.model_update.part_threshold)]
            for ti, tpl in zip(fresh.tolist(), head_patches(frame, dof_t[fresh[:, None], _BOX_COLUMNS])):
                if tpl is not None:
                    targets.head_template[ti] = tpl
            targets.confirmed[mt] |= targets.hits[mt] >= self.life_cycle.min_hits
        if len(lost):
            targets.mark_missed(lost)
        # drop tentative misses, long-lost and leaving targets
        alive = alive_rows(targets.dof, targets.predicted_shift(), targets.misses,
                           targets.confirmed, W, H, self.adaptations.exit_margin, self.life_cycle.max_misses,
                           self.adaptations.exit_misses)
        if np.count_nonzero(alive) < len(alive):
            targets.take(alive.nonzero()[0])
        # new targets from free candidates (new blobs, split heads)
        live_boxes = targets.boxes if len(free) else None
        for n in free.tolist():  # (``assign`` leaves exactly the untaken candidates free)
            box = boxes[n]
            if box[3] < self.life_cycle.min_height:
                continue
            if cand.blob[n] and not self.life_cycle.blob_births:
                continue
            if withheld is not None and withheld[n]:
                continue
            if fg is not None and feats.area[n].max() < self.adaptations.min_support:
                continue  # too little foreground under its parts to be a person (PBM 2)
            if len(live_boxes) and iou_matrix(box[None], live_boxes).max() > self.life_cycle.new_track_iou:
                continue
            centroid = cand.centroid[n]
            al_n, be_n = centroid_ratios(box[None], centroid[None])
            dof = dof_from_box(box, centroid)
            targets.add(self._next_id, dof, float(al_n[0]), float(be_n[0]), feats.take(n),
                        head_patch(frame, dof[[0, 1, 4, 5]]))
            self._next_id += 1
            if self._frame <= self.life_cycle.min_hits:
                targets.confirmed[-1] = True  # people present from the start are reported at once
            live_boxes = np.vstack([live_boxes, box[None]])
        return self._output()

    def _output(self) -> list[Track]:
        """One Track per reported target: found (CONFIRMED or TENTATIVE), or confirmed
        and unfound for at most ``max_report_misses`` frames (OCCLUDED, score 0)."""
        tg = self.targets
        found = tg.misses == 0
        shown = found
        if self.reporting.occluded:
            shown = found | (tg.confirmed & (tg.misses <= self.reporting.max_misses))
        rows = shown.nonzero()[0]
        # copies (fancy indexing): the rows of the state arrays change in place later
        boxes = tg.dof[rows[:, None], _BOX_COLUMNS]
        if self.adaptations.report_predicted:
            boxes[:, :2] += np.where(found[rows, None], 0.0, tg.predicted_shift()[rows])
        if self.adaptations.occluded_cover > 0 and self._had_fg and not found[rows].all():
            # evidence of occlusion: an unfound target is reported only while found
            # confirmed targets' boxes cover at least ``occluded_cover`` of its box
            fb = tg.dof[(found & tg.confirmed).nonzero()[0][:, None], _BOX_COLUMNS]
            cover = overlap_ratio_matrix(boxes, fb).sum(axis=1) if len(fb) else np.zeros(len(rows))
            keep = found[rows] | (cover >= self.adaptations.occluded_cover)
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
