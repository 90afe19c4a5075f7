"""The detection-source interface: what the harness asks of every ``detector=`` config.

A source is built by ``hydra.utils.instantiate`` from ``conf/detector/<name>.yaml``. The
runner calls ``start(sequence)`` once per sequence, then ``detect(k, frame)`` for frames
k = 1..length in order. ``detect`` returns the frame's detections and, when the source
computes one, the (H, W) bool foreground mask (else None).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from occbench.datasets.base import Sequence
from occbench.trackers.records import Detections


class DetectionSource(Protocol):
    def start(self, sequence: Sequence) -> None: ...

    def detect(self, index: int, frame: np.ndarray | None) -> tuple[Detections, np.ndarray | None]: ...
