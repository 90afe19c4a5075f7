"""PBM 4 step 4's sharing of candidates between reported targets and lost ones.

PBM tracks each target alone until it is found or lost (PBM 3); with many targets the
tracker shares the frame's candidates in one assignment on 1 - p (``rules.sharing``), so a
target unfound for many frames, no longer reported, competes on its score alone with a
target found last frame. ``ReportedFirst`` (``adaptations.reported_first``) lets the
reported targets choose first, as a matching cascade does (Wojke et al. 2017, DeepSORT's
cascade by time since the last update). S is the (T, N) score matrix (-inf: no candidate).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from occbench.trackers.geometry import iou_matrix
from occbench.trackers.layered.split import HEAD_FRACTION

if TYPE_CHECKING:  # annotations only
    from occbench.trackers.layered.rules import Alone, OneToOne
    from occbench.trackers.layered.targets import Targets


class AllAtOnce:
    """Every live target in one assignment, lost or reported (the frame's sharing as it
    stands)."""

    def strike(self, S: np.ndarray, targets: Targets, sharing: Alone | OneToOne,
               max_cost: float, boxes: np.ndarray | None = None) -> None:
        """Leaves the scores as they are."""


@dataclass(frozen=True)
class ReportedFirst:
    """``reported_first``: the targets unfound for at most ``max_misses`` frames (still
    reported, ``reporting.max_misses``) share the candidates among themselves first, by
    ``sharing`` on 1 - p alone; a target unfound longer (lost, no longer reported) takes
    none of the candidates they take (its pairs with them struck in S). It re-finds its
    person only on a candidate no reported target wants.

    Why (docs/generalisation.md, "pbm, tenth round"): on ecp1-180 gt seed 1000 frame 168
    person 3's target 4, unfound 9 frames since he sank out of view through the stairwell,
    scores person 4's detection 0.513 against person 4's own target 6 (found at 167) 0.463,
    takes it, and person 4 carries person 3's id for four frames.

    ``stay`` (``adaptations.reported_first_stay``; 0: none): a lost target still competes
    for a candidate lying where it would be reported, IoU >= ``stay`` with its last box
    moved by KF1's prediction (``report_predicted``'s box): a person who went unseen behind
    another is found again where he went unseen (docs/generalisation.md, "pbm, seventh
    round": runs of 6 or more misses on the silhouette sets and synth-tune's crowd mostly
    ended found again there). Why: without it, on ecp1-180 sil person 2, behind person 3 at
    frames 85-101, is no longer found again by his own target (unfound 13 frames, at 98, on
    the pair's box: IoU 0.505 with its last box) and ends with person 3's target's id; the
    stairwell's person 4 stands elsewhere (IoU 0.14 with target 4's last box).

    ``head`` (``adaptations.reported_first_head``): a lost target still competes for a
    candidate whose head band (the top ``HEAD_FRACTION`` of its box, PBM 2.1's head part)
    shares rows with the head band of the lost target's last box (not moved: KF1's
    velocity run on over a long gap drifts): a person who went unseen behind another comes
    out with his head at the height it had; one sinking out of view and the one rising
    where he sank do not. Why: at the stairwell (ecp1-180 gt 168) target 4's head band,
    rows 108-117, lies 8 rows below person 4's, rows 86-100; on ecp1-180 sil at 98 person
    2's target's, 66-75, and the pair's box's, 64-77, share rows; on cav1-150 sil at 19-23
    person 5's target (unfound 10-14 frames, last band 50-59) is right on his box (48-57),
    where KF1's prediction had moved its band 9-13 rows down."""

    max_misses: int
    stay: float = 0.0
    head: bool = False

    def strike(self, S: np.ndarray, targets: Targets, sharing: Alone | OneToOne,
               max_cost: float, boxes: np.ndarray | None = None) -> None:
        """Sets S[lost, n] = -inf in place for every candidate n the reported targets take
        when ``sharing`` assigns them alone (cost 1 - S, at most ``max_cost``), but (with
        ``stay``) where n's box (``boxes`` (N, 4) xywh) lies at the lost target's
        predicted box, or (with ``head``) where n's head band shares rows with that of the
        lost target's last box."""
        lost = targets.misses > self.max_misses
        if not S.size or not lost.any() or lost.all():
            return
        Ss = S[~lost]
        matches, _, _ = sharing.assign(np.where(np.isfinite(Ss), 1.0 - Ss, np.inf), max_cost)
        if not len(matches):
            return
        rows, taken = np.flatnonzero(lost), matches[:, 1]
        struck = np.ones((len(rows), len(taken)), dtype=bool)
        if self.stay > 0:
            at = targets.boxes[rows]
            at[:, :2] += targets.predicted_shift()[rows]
            struck &= iou_matrix(at, boxes[taken]) < self.stay
        if self.head:
            struck &= ~_head_bands_meet(targets.boxes[rows], boxes[taken])
        sub = S[np.ix_(rows, taken)]
        sub[struck] = -np.inf
        S[np.ix_(rows, taken)] = sub


def _head_bands_meet(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(A, B) whether the head bands (rows y .. y + HEAD_FRACTION h) of xywh boxes a (A, 4)
    and b (B, 4) share rows (touching counts)."""
    top = np.maximum(a[:, None, 1], b[None, :, 1])
    bottom = np.minimum(a[:, None, 1] + HEAD_FRACTION * a[:, None, 3],
                        b[None, :, 1] + HEAD_FRACTION * b[None, :, 3])
    return bottom >= top
