"""What every tracker offers the harness: ``reset`` and a per-frame ``update``.

A tracker is built from config by the harness (Hydra's ``instantiate``), then fed frames in
order; it reads no files and no config dicts.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from occbench.trackers.records import Detections, Track


class Tracker(Protocol):
    """A multi-person tracker, one sequence at a time.

    ``update(frame, detections, foreground)``: ``frame`` is the (H, W, 3) uint8 BGR image of
    this frame, or None on frameless data (ground truth and detections only); ``detections``
    are this frame's ``Detections`` (xywh, pixels, 0-based top-left); ``foreground`` is an
    (H, W) bool person mask or None. Returns this frame's ``Track`` list (every state; the
    harness writes the reported ones). ``reset`` forgets every track before a new sequence.
    """

    def reset(self) -> None: ...

    def update(self, frame: np.ndarray | None, detections: Detections,
               foreground: np.ndarray | None = None) -> list[Track]: ...
