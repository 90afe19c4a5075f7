"""What Reta's tracker keeps between frames: ``Person`` and its ``Branch`` nodes, the
``Memory`` steps 6-9 write, and the ``Setting`` every step reads (what one frame's steps give
each other: ``values``). Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer, Histogram
from occbench.trackers.three_hypothesis.graph import TrackingGraph
from occbench.trackers.three_hypothesis.params import Adaptations, LifeCycle, Occlusion
from occbench.trackers.three_hypothesis.rules import Rules


@dataclass(slots=True)
class Branch:
    """One live node of a person: kind is 'visible' or a hypothesis kind."""

    kind: str
    x: np.ndarray
    P: np.ndarray
    node: int | None = None  # graph key of its node in the last frame (this frame's once added)
    occluder: int | None = None  # person key followed / hidden behind
    exposed: int = 0  # consecutive frames in plain view without a detection
    covered: bool = False  # hidden behind a visible person this frame
    unseen: bool = False  # its region holds (almost) no foreground this frame
    share: float = 1.0  # foreground share of its ellipse (measured when ``rules.report`` asks)
    depth: int = 0  # people in front of this node (eq. 3)


@dataclass
class Person:
    key: int
    q: Histogram  # appearance (eq. 1), its occupied bins
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
    step_error: float = 0.0  # the last step's, on the same measurements (rules.line.step)
    merged: bool = False  # its last measurement held a hidden partner (rules.split)
    matched_rho: list = field(default_factory=list)  # rho of its last m matches (rules.returning)
    merged_still: Branch | None = None  # hypothesis 3 dropped as a duplicate (rules.ending)
    merged_at: int = -1  # frame of its last measurement if left out of its line (rules.line)

    @property
    def confirmed(self) -> bool:
        return self.id > 0

    @property
    def public_id(self) -> int:
        return self.id if self.id > 0 else -self.key


@dataclass
class Memory:
    """What the tracker keeps between frames and steps 6-9 write: the frame number t, the
    graph G, the people N^{t-1} (then N^t), pi (eq. 3) between frames, the next person key
    and public id, and each person's public id at t (``public``: a confirmation changes it
    within the frame)."""

    graph: TrackingGraph
    t: int = 0
    persons: list[Person] = field(default_factory=list)
    pi: dict[tuple[int, int], int] = field(default_factory=dict)  # (key i, key j) -> +-1
    next_key: int = 1
    next_id: int = 1
    public: dict[int, int] = field(default_factory=dict)  # person key -> public id at t

    def begin_frame(self) -> None:
        """t = t + 1: the graph opens frame t; the public ids of N^{t-1}."""
        self.t += 1
        self.graph.begin_frame(self.t)
        self.public = {person.key: person.public_id for person in self.persons}

    def end_frame(self, persons: list[Person]) -> None:
        """N^t = ``persons``; pi forgets the pairs of people gone once it holds more than
        4 P^2 + 16 (P people alive)."""
        alive = {person.key for person in persons}
        if len(self.pi) > 4 * len(alive) ** 2 + 16:
            self.pi = {k: v for k, v in self.pi.items() if k[0] in alive and k[1] in alive}
        self.persons = persons

    def new_key(self) -> int:
        """A new person's key."""
        self.next_key += 1
        return self.next_key - 1

    def new_id(self) -> int:
        """A new public id for a person confirmed at t."""
        self.next_id += 1
        return self.next_id - 1


@dataclass(frozen=True, slots=True)
class Setting:
    """What the steps read of the tracker and never change: the rules ``adaptations``
    selects (``rules.build_rules``), the parameter groups, and the histogrammer of eq. 1."""

    rules: Rules
    occlusion: Occlusion
    life_cycle: LifeCycle
    adaptations: Adaptations
    histograms: EllipseHistogrammer
