"""What Reta's tracker keeps between frames and what the steps of one frame share.

``Person`` and its ``Branch`` nodes live across frames; ``Frame`` holds Alg. 1's variables of
frame t, filled step by step (``tracker``'s module docstring lists the steps). Boxes are
(N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import csr_array

from occbench.trackers.three_hypothesis.association import Matches
from occbench.trackers.three_hypothesis.graph import Node


@dataclass(slots=True)
class Branch:
    """One live node of a person: kind is 'visible' or a hypothesis kind."""

    kind: str
    x: np.ndarray
    P: np.ndarray
    node: int | None = None  # graph key of the node in the last frame
    occluder: int | None = None  # person key followed / hidden behind
    exposed: int = 0  # consecutive frames in plain view without a detection
    covered: bool = False  # hidden behind a visible person this frame
    unseen: bool = False  # its region holds (almost) no foreground this frame
    share: float = 1.0  # foreground share of its ellipse (measured when ``rules.report`` asks)
    depth: int = 0  # people in front of this node (eq. 3)
    graph_node: Node | None = None  # this frame's graph node


@dataclass
class Person:
    key: int
    q: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    branches: list[Branch]
    shape: np.ndarray  # (4,) xywh region of the last visible node
    id: int = 0  # public id once confirmed
    hits: int = 1
    misses: int = 0
    spawned: bool = False  # occlusion hypotheses created in this hidden streak
    centres: list = field(default_factory=list)  # (frame, xc, yc) last measured (rules.line)
    line_errors: list = field(default_factory=lambda: [0.0, 0.0])  # M's, the line's

    @property
    def confirmed(self) -> bool:
        return self.id > 0

    @property
    def public_id(self) -> int:
        return self.id if self.id > 0 else -self.key


@dataclass(slots=True)
class Frame:
    """What the steps of one frame t share (Alg. 1's variables), filled step by step:
    ``_measure`` sets dets, scores, p, support; ``_predict`` branches .. pred; ``_occlusions`` delta,
    pairs; ``_associate`` matches, matched; ``_sort_occlusions`` in_front;
    ``_update_matched`` visible, visible_dets and absorbed."""

    foreground: np.ndarray | None  # (H, W) mask or label image
    width: int
    height: int
    persons: list[Person]  # tracked at t-1, in key order
    dets: np.ndarray = None  # (D, 4) measurements V
    scores: np.ndarray = None  # (D,) their detection scores
    p: list[np.ndarray] = None  # D histograms (eq. 1)
    support: np.ndarray = None  # (K,) bins where some p is nonzero
    branches: list[Branch] = None  # the B nodes of t-1, grouped by person
    owners: np.ndarray = None  # (B,) person index of each node
    x_prev: np.ndarray = None  # (B, 8) states at t-1
    Xp: np.ndarray = None  # (B, 8) predicted states
    Pp: np.ndarray = None  # (B, 8, 8) predicted covariances
    pred: np.ndarray = None  # (B, 4) predicted regions S^{t|t-1}
    delta: csr_array = None  # (B, D) region similarity (eq. 5) of predictions and V, sparse:
    # stored for the pairs whose boxes meet (0 elsewhere)
    pairs: np.ndarray = None  # O (eq. 2): (K, 2) node index rows (a, b), a < b
    pair_ratio: np.ndarray = None  # (K,) eq. 2's overlap ratio of each pair
    matches: Matches = None
    matched: dict[int, tuple[int, int, int, float]] = None  # person -> (det, node, stage, rho)
    in_front: dict[int, list[int]] = field(default_factory=dict)  # node -> persons in front
    visible: np.ndarray = None  # (K, 4) measurements of the matched persons (the front)
    visible_dets: list[int] = field(default_factory=list)  # their measurement indices
    absorbed: set[int] = field(default_factory=set)  # hidden persons a new track confirmed
