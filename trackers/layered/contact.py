"""Which parts of a matched target learn from its candidate (PBM 4.2's parts update).

The paper updates a part that matches (p_j, eq. 12, at or above the threshold) and keeps a
part that does not ("all features remain unchanged"); its overview says more: "whenever a
major occlusion is detected over a model's part, its model is kept unchanged until the
occlusion has ceased" (PBM 1) and "five body parts, each updated if not occluded" (PBM 2).
``AsMatched`` reads the update by p_j alone (the paper's 4.2); ``FrozenAtContact``
(``adaptations.contact_frozen``) also keeps a part whose candidate rectangle lies, by at
least a share, under another target's box: at a contact the candidate's part holds the
neighbour's pixels, and a running average would move the model towards the neighbour.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.layered.model_update import contact_parts
from occbench.trackers.layered.parts import PartFeatures
from occbench.trackers.layered.targets import Targets


class AsMatched:
    """PBM 4.2: a part learns when it matches, whoever stands over it."""

    def learning(self, targets: Targets, rows: np.ndarray, cand: PartFeatures, ks: np.ndarray,
                 pj: np.ndarray, relearn: np.ndarray | None, occluder_misses: int
                 ) -> tuple[np.ndarray, np.ndarray | None]:
        """The (M, 5) p_j and stale parts (``relearn`` or None) ``update_parts`` takes for
        the targets at ``rows`` matched to the candidates at ``ks`` of ``cand``: as given."""
        return pj, relearn


@dataclass(frozen=True)
class FrozenAtContact:
    """``contact_frozen``: a part of a target at ``rows`` whose candidate rectangle (at
    ``ks`` of ``cand``) lies at least ``share`` under the box of another target, found or
    unfound for at most ``occluder_misses`` frames (at its global model, after this frame's
    update), keeps its model (area, perimeter, colour histograms; its centroid follows the
    global model's shift) as a part that does not match."""

    share: float

    def learning(self, targets: Targets, rows: np.ndarray, cand: PartFeatures, ks: np.ndarray,
                 pj: np.ndarray, relearn: np.ndarray | None, occluder_misses: int
                 ) -> tuple[np.ndarray, np.ndarray | None]:
        """As ``AsMatched.learning``, with the ``frozen`` parts read as not matching (p_j
        -inf, not re-learned) and flagged in ``targets.occluded_parts``."""
        frozen = self.frozen(targets, rows, cand, ks, occluder_misses)
        targets.occluded_parts[rows] |= frozen
        return (np.where(frozen, -np.inf, pj),
                None if relearn is None else relearn & ~frozen)

    def frozen(self, targets: Targets, rows: np.ndarray, cand: PartFeatures, ks: np.ndarray,
               occluder_misses: int) -> np.ndarray:
        """(M, 5) bool: the parts kept (``model_update.contact_parts``)."""
        return contact_parts(targets.dof, targets.misses, np.asarray(rows, dtype=np.int64),
                             cand.parts, np.asarray(ks, dtype=np.int64), int(occluder_misses),
                             float(self.share))
