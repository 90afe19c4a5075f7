"""KF1 and KF2 after a gap: as predicted through it (PBM 3), or OC-SORT's re-update (ours,
``adaptations.reupdate``).

PBM's filters (eq. 7: KF1, Z1 = (xc, yc); eq. 8: KF2, Z2 = (h, w)) predict blindly while a
target is unfound and take one update when it is found again: the velocity they keep is the
drift of those k predictions corrected by one innovation. ``ReUpdate``
(``adaptations.reupdate``, issue 28 item 3) is the observation-centric re-update (ORU) of
Cao et al. 2023, "Observation-Centric SORT", section 3.2: a target found again after k >=
``min_gap`` frames unfound has its filters rewound to their state just after its last
observation z_1 and re-run, predict + update, over the virtual trajectory

    z~_i = z_1 + (i / (k + 1)) (z_2 - z_1),   i = 1 .. k + 1   (OC-SORT section 3.2)

whose last point is the new observation z_2, so the rate learnt through the gap is the
observed (z_2 - z_1) / (k + 1). The gate's growth with misses (PBM 3) is not changed.

An observation is any match, found unoccluded or under occlusion (PBM 3.1's head-anchored
search): every match updates KF1 and KF2 with Z of the updated global model (PBM 4.2, under
occlusion the window mean) and ends the run of misses that ``Targets.misses`` counts, so the
two ends of the virtual trajectory are the two measurements the filters actually took.

OC-SORT's code (``KalmanFilterNew.unfreeze``) rewinds to the state after the first blind
prediction and, after the replay, updates with the new observation once more; here the
filters are rewound to just after the last observation's update and the new observation is
taken once, as the (k + 1)-th point of the trajectory.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.layered.dynamics import (
    ConstantVelocity2D,
    cv_predict_inplace,
    cv_update_inplace,
)
from occbench.trackers.layered.targets import Targets

_ROW0 = np.zeros(1, dtype=np.int64)


class AfterPrediction:
    """PBM 3, eqs. 7-8 as written: after a gap the filters take one update on top of the
    predictions made through it."""

    def update(self, targets: Targets, rows: np.ndarray, dof: np.ndarray, measured: np.ndarray,
               occluded: np.ndarray, part_scores: np.ndarray, part_threshold: float) -> np.ndarray:
        """``Targets.update`` (PBM 4.2) of the matched ``rows``; returns its shifts."""
        return targets.update(rows, dof, measured, occluded, part_scores, part_threshold)


@dataclass(frozen=True)
class ReUpdate:
    """``adaptations.reupdate``: OC-SORT's observation-centric re-update of KF1 and KF2
    (module docstring) of a target found again after >= ``min_gap`` frames unfound.

    Args:
        min_gap: frames unfound before a re-found target's filters are re-run (>= 1).
    """

    min_gap: int

    def update(self, targets: Targets, rows: np.ndarray, dof: np.ndarray, measured: np.ndarray,
               occluded: np.ndarray, part_scores: np.ndarray, part_threshold: float) -> np.ndarray:
        """``Targets.update`` (PBM 4.2) of the matched ``rows``, then the re-update of those
        found after a gap; every matched row's filters remember this observation."""
        rows = np.asarray(rows, dtype=np.int64)
        gaps = targets.misses[rows]  # frames unfound before this match (a copy)
        shift = targets.update(rows, dof, measured, occluded, part_scores, part_threshold)
        d = targets.dof[rows]
        again = gaps >= self.min_gap
        for kf, z in ((targets.kf1, d[:, 2:4]), (targets.kf2, d[:, [5, 4]])):  # eqs. 7, 8
            if again.any():
                re_run(kf, rows[again], z[again], gaps[again] + 1)
            kf.observed(rows, z)
        return shift


def re_run(kf: ConstantVelocity2D, rows: np.ndarray, z: np.ndarray, steps: np.ndarray) -> None:
    """Rewind the filters at ``rows`` to their last observation (``ConstantVelocity2D.seen_*``)
    and run ``steps`` (M,) predict + update steps over the line from that observation's z_1
    to z (M, 2), the last step at z itself (OC-SORT section 3.2), in place."""
    for n, z2, g in zip(rows.tolist(), np.asarray(z, dtype=np.float64), steps.tolist()):
        x, p = kf.seen_x[n:n + 1].copy(), kf.seen_p[n:n + 1].copy()
        z1 = kf.seen_z[n]
        for i in range(1, g + 1):
            cv_predict_inplace(x, p, kf.qp[n:n + 1], kf.qv[n:n + 1])
            cv_update_inplace(x, p, kf.r[n:n + 1], _ROW0, (z1 + (i / g) * (z2 - z1))[None])
        kf.x[n], kf.p[n] = x[0], p[0]
