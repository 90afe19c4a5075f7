"""PBM 4.2's model update at a contact: which parts of a matched target learn from its
candidate, and whose global model is window-averaged.

The paper updates a part that matches (p_j, eq. 12, at or above the threshold) and keeps a
part that does not ("all features remain unchanged"); its overview says more: "whenever a
major occlusion is detected over a model's part, its model is kept unchanged until the
occlusion has ceased" (PBM 1) and "five body parts, each updated if not occluded" (PBM 2).
``AsMatched`` reads the update by p_j alone (the paper's 4.2). At a contact the candidate's
part holds the neighbour's pixels, and a running average moves the model towards the
neighbour: ``FrozenAtContact`` (``adaptations.contact_frozen``) keeps a part whose
candidate rectangle lies, by at least a share, under another target's box, as a part that
does not match; ``ColourAtContact`` (``adaptations.contact_colour``) keeps only its colour
histograms there, its area, perimeter and centroid learning as PBM 4.2 says. 4.2 also
window-averages the global model "in the presence of occlusions": ``SizeOcclusion`` reads
occlusion as PBM 3.1's size test (a carved candidate), ``ContactOcclusion``
(``adaptations.contact_occluded``) as that or a candidate box under another target's box.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from occbench.trackers.layered.model_update import contact_parts
from occbench.trackers.layered.parts import PartFeatures
from occbench.trackers.layered.targets import PartMatches, PartRates, Targets, update_parts


class AsMatched:
    """PBM 4.2: a part learns when it matches, whoever stands over it."""

    def update(self, targets: Targets, cand: PartFeatures, m: PartMatches, rates: PartRates,
               occluder_misses: int) -> None:
        """``update_parts`` of the matched targets ``m`` from ``cand``, in place."""
        update_parts(targets.parts, cand, m, rates)


def _at_contact(share: float, targets: Targets, cand: PartFeatures, m: PartMatches,
                occluder_misses: int) -> np.ndarray:
    """(M, 5) bool: the parts of the targets at ``m.rows`` whose candidate rectangle (at
    ``m.ks`` of ``cand``) lies at least ``share`` under the box of another target, found or
    unfound for at most ``occluder_misses`` frames, at its global model after this frame's
    update (``model_update.contact_parts``)."""
    return contact_parts(targets.dof, targets.misses, np.asarray(m.rows, dtype=np.int64),
                         cand.parts, np.asarray(m.ks, dtype=np.int64), int(occluder_misses),
                         float(share))


@dataclass(frozen=True)
class FrozenAtContact:
    """``contact_frozen``: a part at a contact (``_at_contact``) keeps its model (area,
    perimeter, colour histograms; its centroid follows the global model's shift) as a part
    that does not match: read with p_j -inf, not re-learned, flagged in
    ``targets.occluded_parts``."""

    share: float

    def update(self, targets: Targets, cand: PartFeatures, m: PartMatches, rates: PartRates,
               occluder_misses: int) -> None:
        frozen = _at_contact(self.share, targets, cand, m, occluder_misses)
        targets.occluded_parts[m.rows] |= frozen
        update_parts(targets.parts, cand, replace(
            m, part_scores=np.where(frozen, -np.inf, m.part_scores),
            relearn=None if m.relearn is None else m.relearn & ~frozen), rates)


@dataclass(frozen=True)
class ColourAtContact:
    """``contact_colour``: a part at a contact (``_at_contact``) keeps its HSV and XYZ
    histograms; its area, perimeter and centroid are updated as PBM 4.2 says."""

    share: float

    def update(self, targets: Targets, cand: PartFeatures, m: PartMatches, rates: PartRates,
               occluder_misses: int) -> None:
        kept = _at_contact(self.share, targets, cand, m, occluder_misses)[..., None]
        model = targets.parts
        hsv, xyz = model.hsv[m.rows].copy(), model.xyz[m.rows].copy()
        update_parts(model, cand, m, rates)
        model.hsv[m.rows] = np.where(kept, hsv, model.hsv[m.rows])
        model.xyz[m.rows] = np.where(kept, xyz, model.xyz[m.rows])


class SizeOcclusion:
    """PBM 3.1: a match is occluded (its global model window-averaged, PBM 4.2) when its
    candidate was carved from a region off the predicted size by the threshold."""

    def occluded(self, targets: Targets, rows: np.ndarray, dof: np.ndarray, carved: np.ndarray,
                 occluder_misses: int) -> np.ndarray:
        return carved


@dataclass(frozen=True)
class ContactOcclusion:
    """``contact_occluded``: a match is also occluded for PBM 4.2's global update (the six
    DOF window-averaged, alpha and beta not re-measured) when at least ``share`` of its
    candidate's box (``dof`` (M, 6) of the targets at ``rows``) lies under another target's
    box, found or unfound for at most ``occluder_misses`` frames, at its global model before
    this frame's update (``model_update.contact_parts`` on the box as one part)."""

    share: float

    def occluded(self, targets: Targets, rows: np.ndarray, dof: np.ndarray, carved: np.ndarray,
                 occluder_misses: int) -> np.ndarray:
        boxes = np.ascontiguousarray(np.asarray(dof, dtype=np.float64)[:, None, [0, 1, 4, 5]])
        return carved | contact_parts(targets.dof, targets.misses, np.asarray(rows, dtype=np.int64),
                                      boxes, np.arange(len(rows), dtype=np.int64),
                                      int(occluder_misses), float(self.share))[:, 0]
