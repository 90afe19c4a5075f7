"""Foreground blobs as people (PBM 2): ``ForegroundDetector``, ``detector=foreground``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.common.checks import at_least, coerce, parameter_group, require
from occbench.trackers.frontend.background import BackgroundModel
from occbench.trackers.frontend.blobs import Blob, blobs_from_mask
from occbench.trackers.frontend.detectors import _ForegroundPipeline
from occbench.trackers.frontend.heads import HeadDetector
from occbench.trackers.records import Detections


@dataclass(frozen=True)
class Blobs:
    """Which foreground blobs are people, and which are groups.

    Args:
        min_area: smallest blob area, pixels, >= 1.
        min_height: smallest person height, pixels, > 0.
        min_aspect: smallest width / height of a person box, > 0 and < ``max_aspect``.
        max_aspect: largest width / height of a single person; wider blobs are split at the
            heads found in them (``ForegroundDetector.heads``, when ``split_heads``); a wide
            blob without two heads stays whole.
        person_aspect: typical person width / height, bounds the number of heads searched.
    """

    min_area: int = 80
    min_height: float = 20.0
    min_aspect: float = 0.15
    max_aspect: float = 0.8
    person_aspect: float = 0.4

    def __post_init__(self) -> None:
        at_least("blobs", 1, min_area=self.min_area)
        require("blobs.min_height", self.min_height > 0, "must be > 0", self.min_height)
        require("blobs.min_aspect", self.min_aspect > 0, "must be > 0", self.min_aspect)
        require("blobs.max_aspect", self.max_aspect > self.min_aspect,
                f"must be > min_aspect {self.min_aspect}", self.max_aspect)
        coerce(self, {"min_area": int, "min_height": float, "min_aspect": float,
                      "max_aspect": float, "person_aspect": float})


class ForegroundDetector(_ForegroundPipeline):
    """Foreground blobs as people: size and aspect filtered, groups split at heads.

    Args:
        background: the background model.
        blobs: which blobs are people (``Blobs``; its defaults when None).
        heads: head detector used to split groups and to report heads (None: no splitting).
        split_heads: split wide blobs at their heads (ours, ``detector.split_heads``: PBM 2
            hands blobs to the tracker whole and resolves merges itself, PBM 3.1); false:
            every blob is one detection.
        report_heads: attach one head box per detection (``Detections.heads``).
    """

    def __init__(self, background: BackgroundModel | None = None, blobs: Blobs | None = None,
                 heads: HeadDetector | None = None, split_heads: bool = True,
                 report_heads: bool = False) -> None:
        super().__init__(background)
        self.blobs = parameter_group("blobs", blobs, Blobs)
        self.split_heads = bool(split_heads)
        self.heads, self.report_heads = heads, bool(report_heads)

    def detect_on(self, frame: np.ndarray, fg: np.ndarray, blobs: list[Blob] | None = None) -> Detections:
        if blobs is None:
            blobs = blobs_from_mask(fg, self.blobs.min_area, perimeter=False)
        if not blobs:
            return Detections.empty()
        labels_in = blobs[0].labels
        boxes: list[np.ndarray] = []
        heads: list[np.ndarray] = []
        labels = np.zeros(fg.shape, dtype=np.int32)
        for b in blobs:
            _x, _y, w, h = b.box
            if h < self.blobs.min_height or w / h < self.blobs.min_aspect:
                continue
            parts = [(b.box, None, None)]
            if w / h > self.blobs.max_aspect and self.heads is not None and self.split_heads:
                n = int(np.ceil(w / (self.blobs.person_aspect * h))) + 1
                hb = self.heads.heads_in(frame, labels_in == b.label, b.box, max_heads=n)
                if len(hb) >= 2:
                    parts = self._split(b, hb)
            for box, head, (r0, c0, m) in ((p[0], p[1], p[2] or (None, None, None)) for p in parts):
                k = len(boxes) + 1
                boxes.append(box)
                heads.append(np.full(4, np.nan) if head is None else head)
                if m is None:
                    labels[labels_in == b.label] = k
                else:
                    sub = labels[r0 : r0 + m.shape[0], c0 : c0 + m.shape[1]]
                    sub[m] = k
        if not boxes:
            return Detections.empty()
        B = np.asarray(boxes, dtype=np.float64)
        Hd = np.asarray(heads, dtype=np.float64)
        if self.report_heads and self.heads is not None:
            missing = ~np.isfinite(Hd).all(axis=1)
            if missing.any():
                Hd[missing] = self.heads.detect(frame, fg, B[missing])
        return Detections(B, np.ones(len(B)), labels, Hd if self.report_heads else None)

    @staticmethod
    def _split(b: Blob, heads: np.ndarray) -> list:
        """Split a blob into vertical strips between consecutive head centres."""
        x, y, w, _h = (int(v) for v in b.box)
        crop = b.crop_mask()
        hx = np.sort(heads[:, 0] + heads[:, 2] / 2) - x
        order = np.argsort(heads[:, 0] + heads[:, 2] / 2)
        cuts = np.r_[0, np.round((hx[1:] + hx[:-1]) / 2).astype(int), w]
        parts = []
        for i in range(len(hx)):
            m = np.zeros_like(crop)
            m[:, cuts[i] : cuts[i + 1]] = crop[:, cuts[i] : cuts[i + 1]]
            rows, cols = np.flatnonzero(m.any(axis=1)), np.flatnonzero(m.any(axis=0))
            if len(rows) == 0:
                continue
            box = np.array([x + cols[0], y + rows[0], cols[-1] - cols[0] + 1, rows[-1] - rows[0] + 1],
                           dtype=np.float64)
            parts.append((box, heads[order[i]], (y, x, m)))
        return parts
