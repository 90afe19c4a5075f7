"""Front-end person detectors (``occbench.trackers.frontend``) as harness detection sources.

``FrontendSource`` wraps any detector with ``reset()``, ``detect(frame) -> (Detections,
foreground)`` and optionally ``warm_up_sequence(length, frame_fn)``: ``start(sequence)``
resets it and warms its background model up on the sequence, ``detect(k, frame)`` runs it.
Configs: ``conf/detector/{foreground,silhouette,hog}.yaml``.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from occbench.datasets.base import Sequence
from occbench.trackers.records import Detections

log = logging.getLogger(__name__)

CONF_DIR = Path(__file__).resolve().parents[2] / "conf"


class FrontendSource:
    """DetectionSource around a front-end detector.

    Args:
        detector: an object with ``reset()`` and ``detect(frame)``; built by Hydra from the
            nested ``detector`` config.
    """

    #: its outputs are worth keeping in the front-end cache (``occbench.sources.cache``)
    cacheable = True
    #: it reads the frames: a sequence without pixels is refused before the run starts
    needs_pixels = True

    @property
    def label(self) -> str:
        """What the results name this source by: ``silhouette front end`` and the like, with
        ``(warm-up on the whole sequence: future frames)`` when the detector's background or
        calibration saw frames after the one detected (``warmup_span: sequence``)."""
        name = type(self.detector).__name__.removesuffix("Detector").lower()
        future = getattr(self.detector, "uses_future_frames", False)
        return (f"{name or type(self.detector).__name__} front end"
                + (" (warm-up on the whole sequence: future frames)" if future else ""))

    def __init__(self, detector) -> None:
        if not (hasattr(detector, "detect") and hasattr(detector, "reset")):
            raise ValueError(f"detector must have reset() and detect(frame), got {detector!r}")
        self.detector = detector
        self._sequence: Sequence | None = None

    def start(self, sequence: Sequence) -> None:
        if not sequence.has_pixels:
            raise ValueError(
                f"detector {type(self.detector).__name__} needs frames, but sequence "
                f"{sequence.info.name!r} has no pixels (use detector=noisy_gt or public)"
            )
        self._sequence = sequence
        self.detector.reset()
        warm = getattr(self.detector, "warm_up_sequence", None)
        if warm is not None:
            warm(sequence.info.length, sequence.nth_frame)

    def detect(self, index: int, frame: np.ndarray | None) -> tuple[Detections, np.ndarray | None]:
        if self._sequence is None:
            raise RuntimeError("FrontendSource.detect called before start(sequence)")
        if frame is None:
            frame = self._sequence.frame(index)
        if frame is None:
            raise ValueError(f"{self._sequence.info.name}: frame {index} has no pixels")
        return self.detector.detect(frame)
