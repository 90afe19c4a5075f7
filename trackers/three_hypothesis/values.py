"""What each step of Alg. 1 gives the next for frame t: one frozen value per step.

``tracker``'s module docstring lists the steps; each takes the values of the steps before it
and returns its own. The values are frozen (their arrays are not written after the step
that made them); the people (``state.Person``) are the tracker's, updated in place by
steps 6-9 as Alg. 1's UpdateAttributes, AddNodeToGraph and PruneHypothesis do. Indices:
a person is its index in ``Predictions.persons``, a node its row in ``Predictions``, a
measurement its row in ``Measurements``. Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.sparse import csr_array

from occbench.trackers.three_hypothesis.appearance import Histogram
from occbench.trackers.three_hypothesis.state import Branch, Person


@dataclass(frozen=True, slots=True)
class Measurements:
    """Step 1, V = PeopleDetection(I^t) (3.1-3.2), and the picture they come from."""

    boxes: np.ndarray  # (D, 4) the detections kept
    scores: np.ndarray  # (D,) their detection scores
    p: list[Histogram]  # D histograms over their ellipses (eq. 1), as their occupied bins
    support: np.ndarray  # (K,) bins where some p is nonzero
    foreground: np.ndarray | None  # (H, W) mask or label image
    width: int
    height: int


@dataclass(frozen=True, slots=True)
class Predictions:
    """Step 2, S^{t|t-1} of every node of t-1 (3.2, 3.3.3), grouped by person."""

    persons: list[Person]  # N^{t-1}: the people tracked at t-1, in key order
    branches: list[Branch]  # their B nodes, grouped by person
    owners: np.ndarray  # (B,) person index of each node, sorted
    x_prev: np.ndarray  # (B, 8) states at t-1
    Xp: np.ndarray  # (B, 8) predicted states
    Pp: np.ndarray  # (B, 8, 8) predicted covariances
    boxes: np.ndarray  # (B, 4) predicted regions S^{t|t-1}


@dataclass(frozen=True, slots=True)
class Occlusions:
    """Step 3, O = Occlusion(N^{t-1}, lambda) (3.3.1, eq. 2), and the region similarity
    (eq. 5) of the predictions and V from the same integration."""

    pairs: np.ndarray  # (K, 2) node index rows (a, b), a < b, of different people
    ratio: np.ndarray  # (K,) eq. 2's overlap ratio of each pair
    delta: csr_array  # (B, D) eq. 5's delta of nodes and measurements, stored where boxes meet


class Match(NamedTuple):
    """One person's match of step 4: its measurement, the node that matched (one of its
    hypotheses, or its visible node), the stage (1 or 2) and rho (eq. 4)."""

    det: int
    node: int
    stage: int
    rho: float


@dataclass(frozen=True, slots=True)
class Matching:
    """Step 4, MaxSimilarity (3.3.2): Assoc, person index -> ``Match`` (stage 1's, then
    stage 2's, each in person order), and the measurements nobody matched (ascending)."""

    matched: dict[int, Match]
    unmatched: np.ndarray

    def first_stage(self) -> list[int]:
        """The measurements stage 1 matched."""
        return [m.det for m in self.matched.values() if m.stage == 1]


@dataclass(frozen=True, slots=True)
class DepthOrder:
    """Step 5, pi = SortOcclusionTargets(O) (eq. 3) as frame t reads it: node -> the
    persons in front of it (nodes behind nobody are absent)."""

    in_front: dict[int, list[int]]


@dataclass(frozen=True, slots=True)
class Updated:
    """Step 6, UpdateAttributes(N_o^t) (3.3.3): the matched people (updated, in person
    order), their measurements (the front at t: ``visible`` boxes, ``visible_dets`` rows of
    V), and the hidden people a newly confirmed track took the id of (they end)."""

    persons: list[Person]
    visible: np.ndarray  # (K, 4)
    visible_dets: list[int]  # (K,)
    absorbed: frozenset[int]  # person indices


@dataclass(frozen=True, slots=True)
class Continuation:
    """Step 7 for one unmatched person: its new branches (N_h1, and N_h2, N_h3 at its first
    total occlusion) and, per branch, the node of t-1 it continues (-1 when spawned)."""

    person: Person
    branches: list[Branch]
    sources: list[int]
