"""What Reta's tracker keeps between frames: ``Person`` and its ``Branch`` nodes (what one
frame's steps give each other: ``values``). Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

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
