"""The shared vocabulary: detections, tracker output and sequence metadata.

Box convention everywhere inside the project: ``xywh`` in pixels, float64, with (x, y) the
top-left corner in 0-based image coordinates (pixel (0, 0) is the top-left pixel).
MOTChallenge files are 1-based; ``occbench.io.mot`` is the one place that converts.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np


class TrackState(str, Enum):
    """Life-cycle state of a tracker output.

    CONFIRMED and OCCLUDED tracks are written to result files (OCCLUDED is the tracker's
    single best estimate of a hidden person); TENTATIVE and HYPOTHESIS tracks are drawn but
    not scored.
    """

    CONFIRMED = "confirmed"
    OCCLUDED = "occluded"
    TENTATIVE = "tentative"
    HYPOTHESIS = "hypothesis"

    @property
    def reported(self) -> bool:
        return self in (TrackState.CONFIRMED, TrackState.OCCLUDED)


@dataclass
class Detections:
    """Person detections of one frame.

    Attributes:
        boxes: (N, 4) float64 xywh, pixels, 0-based top-left.
        scores: (N,) float64 confidences in [0, 1] (1 where the source has none).
        labels: optional (H, W) int32 label image: pixel value k + 1 marks detection k's
            mask, 0 is background. None when the source has no masks.
        heads: optional (N, 4) float64 xywh head box per detection, NaN rows where none.
    """

    boxes: np.ndarray
    scores: np.ndarray
    labels: np.ndarray | None = None
    heads: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.boxes = np.asarray(self.boxes, dtype=np.float64).reshape(-1, 4)
        self.scores = np.asarray(self.scores, dtype=np.float64).reshape(-1)
        if len(self.scores) != len(self.boxes):
            raise ValueError(
                f"Detections: {len(self.boxes)} boxes but {len(self.scores)} scores"
            )
        if self.heads is not None:
            self.heads = np.asarray(self.heads, dtype=np.float64).reshape(-1, 4)
            if len(self.heads) != len(self.boxes):
                raise ValueError(f"Detections: {len(self.boxes)} boxes but {len(self.heads)} heads")

    @classmethod
    def empty(cls) -> Detections:
        return cls(np.zeros((0, 4)), np.zeros(0))

    def __len__(self) -> int:
        return len(self.boxes)

    def subset(self, keep: np.ndarray) -> Detections:
        """Detections selected by a boolean mask or index array (label image renumbered)."""
        idx = np.arange(len(self))[keep]
        labels = None
        if self.labels is not None:
            lut = np.zeros(len(self) + 1, dtype=np.int32)
            lut[idx + 1] = np.arange(1, len(idx) + 1, dtype=np.int32)
            labels = lut[self.labels]
        heads = None if self.heads is None else self.heads[idx]
        return Detections(self.boxes[idx], self.scores[idx], labels, heads)


@dataclass
class Track:
    """One tracker output in one frame.

    Attributes:
        id: positive integer identity, unique within one tracker run.
        box: (4,) float64 xywh, pixels.
        state: life-cycle state; only ``state.reported`` tracks are written and scored.
        score: confidence in [0, 1].
        extra: tracker-specific drawing data (an ellipse, part boxes, hypothesis kind).
    """

    id: int
    box: np.ndarray
    state: TrackState = TrackState.CONFIRMED
    score: float = 1.0
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True)
class SequenceInfo:
    """Metadata of a sequence: name, frame size in pixels, frame rate, number of frames."""

    name: str
    width: int
    height: int
    fps: float
    length: int
