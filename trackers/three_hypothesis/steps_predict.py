"""Alg. 1, steps 1-2 (Reta 3.1-3.2, 3.3.3): the measurements V with their histograms
(eq. 1), and the prediction S^{t|t-1} of every node of t-1.
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.geometry import valid_boxes
from occbench.trackers.records import Detections
from occbench.trackers.three_hypothesis import hypotheses as hyp
from occbench.trackers.three_hypothesis.motion import state_boxes
from occbench.trackers.three_hypothesis.state import Frame


class PredictSteps:
    """``RetaTracker``'s steps 1-2 (a mixin: ``self`` is the tracker)."""

    def _measure(self, f: Frame, frame: np.ndarray, detections: Detections) -> None:
        """V = PeopleDetection(I^t) (3.1-3.2): the detections kept and, per measurement,
        its score and its histogram p over the ellipse S inscribed in its box (eq. 1), and
        ``support``, the bins where some measurement has pixels."""
        keep = valid_boxes(detections.boxes) & (detections.scores >= self.min_score)
        f.dets = detections.boxes[keep]
        f.scores = detections.scores[keep]
        f.p, f.support = self.histograms.measure(frame, f.dets, self.rules.pixels.mask(f.foreground))

    def _predict(self, f: Frame) -> None:
        """S^{t|t-1} of every node of t-1 (3.2: Kalman x = F x, P = F P F' + Q); hypotheses
        first take the velocity of their case (3.3.3): keep it, the occluder's, or none."""
        persons = f.persons
        f.branches = branches = [b for person in persons for b in person.branches]
        f.owners = np.array([i for i, person in enumerate(persons) for _ in person.branches],
                            dtype=int)
        if not branches:
            f.x_prev = f.Xp = np.zeros((0, 8))
            f.Pp = np.zeros((0, 8, 8))
            f.pred = np.zeros((0, 4))
            return
        f.x_prev = np.array([b.x for b in branches])
        P_prev = np.array([b.P for b in branches])
        kinds = [b.kind for b in branches]
        occ_v = np.zeros((len(branches), 2))  # read by 'occluder' hypotheses only
        if hyp.OCCLUDER in kinds:
            velocity = {person.key: person.branches[0].x[4:6] for person in persons}
            for r, b in enumerate(branches):
                if b.kind == hyp.OCCLUDER and b.occluder in velocity:
                    occ_v[r] = velocity[b.occluder]
        x_set = hyp.set_motion(f.x_prev, kinds, occ_v)
        Qs = np.array([person.Q for person in persons])[f.owners]
        f.Xp, f.Pp = self.rules.motion.predict(x_set, P_prev, Qs)
        f.pred = state_boxes(f.Xp)
