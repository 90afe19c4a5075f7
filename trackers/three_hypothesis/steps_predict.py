"""Alg. 1, steps 1-2 (Reta 3.1-3.2, 3.3.3): the measurements V with their histograms
(eq. 1), and the prediction S^{t|t-1} of every node of t-1.
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.geometry import valid_boxes
from occbench.trackers.records import Detections
from occbench.trackers.three_hypothesis import hypotheses as hyp
from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer
from occbench.trackers.three_hypothesis.motion import BoxState, CentreState, state_boxes
from occbench.trackers.three_hypothesis.rules import AllPixels, ForegroundPixels
from occbench.trackers.three_hypothesis.state import Person
from occbench.trackers.three_hypothesis.values import Measurements, Predictions


def measure(image: np.ndarray, detections: Detections, foreground: np.ndarray | None,
            min_score: float, histograms: EllipseHistogrammer,
            pixels: AllPixels | ForegroundPixels) -> Measurements:
    """V = PeopleDetection(I^t) (3.1-3.2): the detections kept (valid, score >= min_score)
    and, per measurement, its histogram p over the ellipse S inscribed in its box (eq. 1,
    over the pixels ``pixels.mask(foreground)`` admits: ``rules.pixels``), and the bins
    where some measurement has pixels."""
    keep = valid_boxes(detections.boxes) & (detections.scores >= min_score)
    boxes = detections.boxes[keep]
    scores = detections.scores[keep]
    p, support = histograms.measure(image, boxes, pixels.mask(foreground))
    height, width = image.shape[:2]
    return Measurements(boxes, scores, p, support, foreground, width, height)


def predict(persons: list[Person], motion: CentreState | BoxState) -> Predictions:
    """S^{t|t-1} of every node of t-1 (3.2: Kalman x = F x, P = F P F' + Q, ``motion``:
    ``rules.motion``); hypotheses first take the velocity of their case (3.3.3): keep it,
    the occluder's, or none."""
    branches = [b for person in persons for b in person.branches]
    owners = np.array([i for i, person in enumerate(persons) for _ in person.branches],
                      dtype=int)
    if not branches:
        empty = np.zeros((0, 8))
        return Predictions(persons, branches, owners, empty, empty, np.zeros((0, 8, 8)),
                           np.zeros((0, 4)))
    x_prev = np.array([b.x for b in branches])
    P_prev = np.array([b.P for b in branches])
    kinds = [b.kind for b in branches]
    occ_v = np.zeros((len(branches), 2))  # read by 'occluder' hypotheses only
    if hyp.OCCLUDER in kinds:
        person_of = {person.key: person for person in persons}
        for r, b in enumerate(branches):
            if b.kind == hyp.OCCLUDER and b.occluder in person_of:
                occ_v[r] = person_of[b.occluder].branches[0].x[4:6]
    x_set = hyp.set_motion(x_prev, kinds, occ_v)
    Qs = np.array([person.Q for person in persons])[owners]
    Xp, Pp = motion.predict(x_set, P_prev, Qs)
    return Predictions(persons, branches, owners, x_prev, Xp, Pp, state_boxes(Xp))
