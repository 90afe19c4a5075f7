"""The targets: global model (PBM 2.1), parts model (2.2), filters (3) and update (4.2).

Global model (GM): six degrees of freedom (xtl, ytl, xc, yc, w, h) and the centroid
ratios alpha (eq. 1) and beta (eq. 2), each a running average over ``ratio_window``
frames, which place the five part rectangles and infer xtl and yc under occlusion.

Update (PBM 4.2):
- global DOF: replaced by the candidate's when unoccluded; under occlusion the mean of the
  last ``occluded_window`` DOF vectors (the new estimate included);
- each part whose score p_j (eq. 12) reaches ``part_match_threshold`` moves its area,
  perimeter and colour histograms towards the candidate's by a running average with weight
  ``update_rate * p_j`` (the better the match, the larger the step); a part below the
  threshold does not match and keeps its model frozen (its rectangle follows the GM).

Stale parts (``stale_parts``, an adaptation beyond the paper): a frozen part keeps p_j low
once the person's appearance has moved on, and then never matches again. A part that is
visible (its target matched unoccluded, no other target's box over it, inside the image,
its foreground present) yet fails to match is counted; after ``stale_frames`` such frames
it is re-learned (step ``relearn_rate``). A hidden part is never re-learned.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from occbench.trackers.layered import model_update
from occbench.trackers.layered.dynamics import ConstantVelocity2D, Gate, targets_predict
from occbench.trackers.layered.parts import (
    N_PARTS,
    PartFeatures,
)
from occbench.trackers.layered.split import dof_from_head as dofs_from_heads


def dof_from_box(box: np.ndarray, centroid: np.ndarray) -> np.ndarray:
    """(6,) global DOF (xtl, ytl, xc, yc, w, h) of a box and its centroid."""
    x, y, w, h = box
    return np.array([x, y, centroid[0], centroid[1], w, h], dtype=np.float64)


def dof_from_head(head: np.ndarray, w: float, h: float, alpha: float, beta: float) -> np.ndarray:
    """(6,) DOF under occlusion (PBM 2.1): xc, ytl from the head top; xtl (eq. 1) and yc
    (eq. 2) from the previous frame's alpha and beta (``dofs_from_heads`` of one head)."""
    return dofs_from_heads(np.asarray(head, dtype=np.float64)[None], w, h, alpha, beta)[0]


class Targets:
    """Every tracked person, one row each (the tracker's state, stepped for all at once).

    Attributes (T rows, in the tracker's target order):
        id: (T,) track ids. dof: (T, 6) global models (xtl, ytl, xc, yc, w, h).
        alpha, beta: (T,) centroid ratios, each the running average of its last
            ``ratio_window`` measurements (eqs. 1-2).
        kf1, kf2: ``ConstantVelocity2D`` of (xc, yc) and (h, w) (PBM 3, eqs. 7-8).
        parts: PartFeatures of T rows: the parts models (PBM 2.2), updated by ``update_parts``.
        hits, misses: (T,) life-cycle counters. confirmed: (T,) passed ``min_hits``.
        occluded: (T,) the last match was an occluded candidate.
        occluded_parts: (T, 5) parts frozen at the last update. part_scores: (T, 5) p_j.
        stale: (T, 5) frames each part failed to match while visible (``stale_parts``).
        score: (T,) global score of the last match. last_gate: (T, 4) the gate the last
            frame's candidates were validated in (NaN before the first).
        head_template: per target, the head patch (``search.head_patch``, a BGR crop) that
            multiple-response pruning matches, or None.

    Args:
        gate: the gate rule. gate_noise, size_noise: (position, velocity, measurement)
            noise of KF1 and KF2. ratio_window, occluded_window: running-average windows of
            alpha/beta and of the DOF under occlusion. bins: histogram bins of the parts.
    """

    def __init__(self, gate: Gate, gate_noise: tuple[float, float, float],
                 size_noise: tuple[float, float, float], ratio_window: int,
                 occluded_window: int, bins: int) -> None:
        self.gate = gate
        self.kf1 = ConstantVelocity2D(*gate_noise)
        self.kf2 = ConstantVelocity2D(*size_noise, initial_velocity_std=0.1)
        self.id = np.zeros(0, dtype=np.int64)
        self.dof = np.zeros((0, 6))
        # windows (T, L, K), newest entry last; a young target's first entries are unused
        self._bins = int(bins)
        self._ratios = np.zeros((0, int(ratio_window), 2))
        self._n_ratios = np.zeros(0, dtype=np.int64)
        self.alpha = np.zeros(0)
        self.beta = np.zeros(0)
        self._history = np.zeros((0, int(occluded_window), 6))
        self._n_history = np.zeros(0, dtype=np.int64)
        self.parts = PartFeatures.concatenate([], self._bins)
        self.hits = np.zeros(0, dtype=np.int64)
        self.misses = np.zeros(0, dtype=np.int64)
        self.confirmed = np.zeros(0, dtype=bool)
        self.occluded = np.zeros(0, dtype=bool)
        self.occluded_parts = np.zeros((0, N_PARTS), dtype=bool)
        self.part_scores = np.zeros((0, N_PARTS))
        self.stale = np.zeros((0, N_PARTS), dtype=np.int64)
        self.score = np.zeros(0)
        self.last_gate = np.zeros((0, 4))
        self.head_template: list[np.ndarray | None] = []

    def __len__(self) -> int:
        return len(self.id)

    @property
    def boxes(self) -> np.ndarray:
        """(T, 4) xywh of the global models (a copy)."""
        return self.dof[:, [0, 1, 4, 5]]

    def add(self, track_id: int, dof: np.ndarray, alpha: float, beta: float,
            parts: PartFeatures, head_template: np.ndarray | None) -> None:
        """Append a new target (its first match: hits 1, unconfirmed)."""
        self.extend([track_id], np.asarray(dof, dtype=np.float64)[None], [alpha], [beta], parts,
                     [head_template])

    def extend(self, track_ids: list[int], dof: np.ndarray, alpha: list[float],
               beta: list[float], parts: PartFeatures, head_templates: list[np.ndarray | None]
               ) -> None:
        """Append K new targets (``add`` of each, in order, with one copy of the arrays):
        ids, DOF (K, 6), ratios, parts (K rows) and head templates."""
        K = len(track_ids)
        dof = np.asarray(dof, dtype=np.float64).reshape(K, 6)
        self.kf1.extend(dof[:, 2:4], dof[:, 5] / 10.0)
        self.kf2.extend(dof[:, [5, 4]], dof[:, 5] / 10.0)
        cat = np.concatenate  # one new array each, the old rows first
        alpha, beta = [float(a) for a in alpha], [float(b) for b in beta]
        self.id = cat((self.id, np.asarray(track_ids, dtype=np.int64)))
        self.dof = cat((self.dof, dof))
        r = np.zeros((K,) + self._ratios.shape[1:])
        r[:, -1, 0], r[:, -1, 1] = alpha, beta
        self._ratios = cat((self._ratios, r))
        ones, zeros = np.ones(K, dtype=np.int64), np.zeros(K, dtype=np.int64)
        self._n_ratios = cat((self._n_ratios, ones))
        self.alpha = cat((self.alpha, alpha))
        self.beta = cat((self.beta, beta))
        h = np.zeros((K,) + self._history.shape[1:])
        h[:, -1] = dof
        self._history = cat((self._history, h))
        self._n_history = cat((self._n_history, ones))
        self.parts = PartFeatures.concatenate([self.parts, parts], self._bins)
        self.hits = cat((self.hits, ones))
        self.misses = cat((self.misses, zeros))
        self.confirmed = cat((self.confirmed, np.zeros(K, dtype=bool)))
        self.occluded = cat((self.occluded, np.zeros(K, dtype=bool)))
        self.occluded_parts = cat((self.occluded_parts, np.zeros((K, N_PARTS), dtype=bool)))
        self.part_scores = cat((self.part_scores, np.ones((K, N_PARTS))))
        self.stale = cat((self.stale, np.zeros((K, N_PARTS), dtype=np.int64)))
        self.score = cat((self.score, np.zeros(K)))
        self.last_gate = cat((self.last_gate, np.full((K, 4), np.nan)))
        self.head_template.extend(head_templates)

    def take(self, rows) -> None:
        """Keep only the targets at ``rows`` (in that order)."""
        rows = np.asarray(rows, dtype=np.intp)
        self.kf1.take(rows)
        self.kf2.take(rows)
        for name in ("id", "dof", "_ratios", "_n_ratios", "alpha", "beta", "_history",
                     "_n_history", "hits", "misses", "confirmed", "occluded",
                     "occluded_parts", "part_scores", "stale", "score", "last_gate"):
            setattr(self, name, getattr(self, name)[rows])
        self.parts = self.parts.take(rows)
        self.head_template = [self.head_template[i] for i in rows.tolist()]

    def subset(self, rows: np.ndarray) -> Targets:
        """A new ``Targets`` of copies of the targets at ``rows`` (one block of a large frame,
        ``frame_blocks``); this one is left as it was."""
        out = copy.copy(self)
        out.kf1, out.kf2 = copy.copy(self.kf1), copy.copy(self.kf2)
        out.take(rows)
        return out

    def predict(self) -> np.ndarray:
        """Advance KF1 and KF2 one frame; returns the predicted (w, h) (T, 2) (KF2), floored
        at 2 pixels (KF2's rates are zeroed where they would shrink it below)."""
        kf1, kf2 = self.kf1, self.kf2
        targets_predict((kf1.x, kf1.p, kf1.qp, kf1.qv), (kf2.x, kf2.p, kf2.qp, kf2.qv))
        return self.predicted_size()

    def predicted_size(self) -> np.ndarray:
        """(T, 2) KF2's (w, h), floored at 2 pixels."""
        return np.maximum(self.kf2.x[:, 1::-1], 2.0)

    def gate_boxes(self) -> np.ndarray:
        """(T, 4) xywh gates (PBM 3): centred on the last validated centroid."""
        return self.gate.boxes(self.dof[:, 2:4], self.kf1.x[:, 2:], self.predicted_size(),
                               self.misses)

    def predicted_shift(self) -> np.ndarray:
        """(T, 2) KF1's predicted centroid (after ``predict``) minus the last validated one:
        the constant-velocity motion since each target was last found."""
        return self.kf1.x[:, :2] - self.dof[:, 2:4]

    def mark_missed(self, rows: np.ndarray) -> None:
        """The targets at ``rows`` were not found: every part counts as occluded (KF2 and
        its rates: ``rules.unfound_size``)."""
        self.misses[rows] += 1
        self.occluded_parts[rows] = True

    def update(self, rows: np.ndarray, dof: np.ndarray, centroid_measured: np.ndarray,
               occluded: np.ndarray, part_scores: np.ndarray, part_match_threshold: float
               ) -> np.ndarray:
        """PBM 4.2 update of the global models and the filters of the targets at ``rows``
        (unique) from their chosen candidates (the parts models: ``update_parts``).

        Args:
            dof: (M, 6) the candidates' global models. centroid_measured: (M,) xc, yc come
                from the candidate's own foreground (then alpha, beta are re-measured,
                eqs. 1-2). occluded: (M,) the candidate was occluded: the DOF becomes the
                mean of the last ``occluded_window`` ones (this one included).
            part_scores: (M, 5) p_j (eq. 12); a part below ``part_match_threshold`` is frozen.
        Returns:
            (M, 2) shift of the centroid (xc, yc), which frozen parts' centroids follow.
        """
        rows = np.asarray(rows, dtype=np.int64)
        shift = np.empty((len(rows), 2))
        kf1, kf2 = self.kf1, self.kf2
        model_update.targets_update(
            (self.dof, self._history, self._n_history, self._ratios, self._n_ratios, self.alpha,
             self.beta, self.part_scores, self.occluded_parts, self.occluded, self.hits,
             self.misses),
            (kf1.x, kf1.p, kf1.r), (kf2.x, kf2.p, kf2.r), rows,
            np.asarray(dof, dtype=np.float64).reshape(-1, 6),
            (np.asarray(centroid_measured, dtype=bool), np.asarray(occluded, dtype=bool)),
            np.asarray(part_scores, dtype=np.float64).reshape(-1, N_PARTS),
            float(part_match_threshold), shift)
        return shift


def stale_parts(targets: Targets, rows: np.ndarray, cand: PartFeatures, ks: np.ndarray,
                part_scores: np.ndarray, part_match_threshold: float, occluder_misses: int,
                image_size: tuple[int, int], max_cover: float, min_fill: float,
                stale_frames: int) -> np.ndarray:
    """Stale parts (an adaptation beyond PBM 4.2) of the targets at ``rows`` (unique),
    matched unoccluded to the candidates at ``ks`` of ``cand``, after ``Targets.update``
    and before ``update_parts``: returns the (M, 5) parts to re-learn, and counts
    ``targets.stale``.

    A part is visible when at most ``max_cover`` of its rectangle (the candidate's) lies
    under the box of another target unfound for at most ``occluder_misses`` frames (at its
    global model), or outside the image (W, H), and its foreground area is at least
    ``min_fill`` x its model's (a part hidden behind a wall loses its foreground). A visible
    part below ``part_match_threshold`` adds one to its count, a matching part resets it;
    a count reaching ``stale_frames`` is re-learned (no longer flagged frozen) and reset.
    A hidden part keeps its count and its model stays frozen.
    """
    relearn = np.zeros((len(rows), N_PARTS), dtype=np.bool_)
    W, H = image_size
    model_update.stale_parts(
        (targets.stale, targets.occluded_parts, targets.parts.area), targets.dof, targets.misses,
        np.asarray(rows, dtype=np.int64), (cand.parts, cand.area), np.asarray(ks, dtype=np.int64),
        np.asarray(part_scores, dtype=np.float64).reshape(-1, N_PARTS),
        (float(part_match_threshold), int(occluder_misses), float(W), float(H), float(max_cover),
         float(min_fill), int(stale_frames)), relearn)
    return relearn


@dataclass(frozen=True)
class PartMatches:
    """The M matched targets whose parts models ``update_parts`` updates (PBM 4.2), one row
    each.

    Attributes:
        rows: (M,) the targets' rows. ks: (M,) their chosen candidates' rows.
        part_scores: (M, 5) p_j (eq. 12). shift: (M, 2) centroid shifts (``Targets.update``).
        boxes: (M, 4) xywh, alpha, beta: (M,) the updated global models.
        relearn: (M, 5) stale parts (``stale_parts``): moved towards the candidate by
            ``PartRates.relearn_rate`` whatever p_j, and given its centroid. None: none.
    """

    rows: np.ndarray
    ks: np.ndarray
    part_scores: np.ndarray
    shift: np.ndarray
    boxes: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray
    relearn: np.ndarray | None = None


@dataclass(frozen=True)
class PartRates:
    """How a part's model learns (PBM 4.2): ``threshold``, the part_match_threshold a part's
    p_j must reach to match; ``rate``, eta = rate p_j of a match; ``relearn_rate``, eta of a
    stale part."""

    threshold: float
    rate: float
    relearn_rate: float = 1.0


def update_parts(model: PartFeatures, cand: PartFeatures, m: PartMatches,
                 rates: PartRates) -> None:
    """PBM 4.2 parts-model update of several targets at once, in place.

    Each part whose score p_j reaches ``rates.threshold`` moves its area, perimeter and
    colour histograms towards the candidate's by a running average with weight
    ``rates.rate * p_j``, and takes the candidate's centroid; a part below it keeps its
    model frozen, its centroid following the global model's ``shift``. The rectangles
    follow the (updated) global model.

    Args:
        model: the parts models of all targets, updated at ``m.rows``.
        cand: features holding the chosen candidates at ``m.ks`` (no copy).
        m: the matched targets (``PartMatches``). rates: how the parts learn.
    """
    relearn = np.zeros((len(m.rows), N_PARTS), dtype=bool) if m.relearn is None else m.relearn
    model_update.update_parts_kernel(
        (model.parts, model.area, model.perimeter, model.hsv, model.xyz, model.centroid,
         model.height), np.asarray(m.rows, dtype=np.int64),
        (cand.parts, cand.area, cand.perimeter, cand.hsv, cand.xyz, cand.centroid, cand.height),
        np.asarray(m.ks, dtype=np.int64), np.asarray(m.part_scores, dtype=np.float64),
        (float(rates.threshold), float(rates.rate), float(rates.relearn_rate)),
        np.asarray(m.shift, dtype=np.float64),
        (np.asarray(m.alpha, dtype=np.float64), np.asarray(m.beta, dtype=np.float64)),
        np.asarray(m.boxes, dtype=np.float64), np.asarray(relearn, dtype=np.bool_))
