"""Adapter for BoxMOT's motion-only trackers (mikel-brostrom/boxmot, PyPI ``boxmot``):
BoT-SORT, ByteTrack, OC-SORT, DeepOCSORT, HybridSORT, BoostTrack, OccluBoost and SFSORT,
constructed without ReID (no appearance embeddings, no weights) and without camera-motion
compensation (our cameras are static; the compensation would only add ECC noise).

BoxMOT's ``update(dets, img)`` takes rows (x1, y1, x2, y2, score, class) and returns rows
(x1, y1, x2, y2, id, score, class, detection index) of the tracks it reports this frame:
they are reported as CONFIRMED, ids renumbered per adapter instance.

Frame rate: BoT-SORT and ByteTrack scale their lost-track buffer by ``frame_rate / 30``;
with ``frame_rate`` None the sequence's own rate is used (the harness calls
``start_sequence(info)`` before the first frame). The others have no frame-rate
parameter. SFSORT needs the frame size (its border margins): it is taken from the sequence
too. On sequences without pixels a black frame of the sequence's size is passed to
trackers that ask for one (only its size is read once ReID and CMC are off).

Install (the ``boxmot`` extra): ``pip install torch==2.13.0 && pip install --no-deps
boxmot==25.0.0 && pip install -e ".[boxmot]"``: boxmot pins torchvision and timm, which
only its ReID and detector code import; torchvision has no CPU build here.
"""

from __future__ import annotations

import importlib
import logging
from collections.abc import Mapping
from typing import Any

import numpy as np

from occbench.trackers.common import checks
from occbench.trackers.outside._common import IdMap, check_min_score, require, xywh_to_xyxy, xyxy_to_xywh
from occbench.trackers.records import Detections, SequenceInfo, Track, TrackState

INSTALL = ('torch==2.13.0 && pip install --no-deps boxmot==25.0.0 && '
           'pip install -e ".[boxmot]" --config-settings editable_mode=strict')

#: tracker name -> (module, class) in boxmot 25
CLASSES = {
    "botsort": ("boxmot.trackers.box.botsort.tracker", "BotSort"),
    "bytetrack": ("boxmot.trackers.box.bytetrack.tracker", "ByteTrack"),
    "ocsort": ("boxmot.trackers.box.ocsort.tracker", "OcSort"),
    "deepocsort": ("boxmot.trackers.box.deepocsort.tracker", "DeepOcSort"),
    "hybridsort": ("boxmot.trackers.box.hybridsort.tracker", "HybridSort"),
    "boosttrack": ("boxmot.trackers.box.boosttrack.tracker", "BoostTrack"),
    "occluboost": ("boxmot.trackers.box.occluboost.tracker", "OccluBoost"),
    "sfsort": ("boxmot.trackers.box.sfsort.tracker", "SFSORT"),
}

#: constructor arguments that switch ReID and camera-motion compensation off, per tracker
#: (not overridable: these are the motion-only trackers)
MOTION_ONLY: dict[str, dict[str, Any]] = {
    "botsort": {"use_embeddings": False, "use_cmc": False},
    "bytetrack": {},
    "ocsort": {},
    "deepocsort": {"use_embeddings": False, "cmc_off": True},
    "hybridsort": {"use_embeddings": False, "with_longterm_reid": False, "cmc_method": None},
    "boosttrack": {"use_embeddings": False, "use_cmc": False},
    "occluboost": {"use_embeddings": False, "use_cmc": False},
    "sfsort": {},
}
#: trackers whose constructor takes ``frame_rate``
FRAME_RATE = ("botsort", "bytetrack")
#: trackers whose constructor takes the frame size
FRAME_SIZE = ("sfsort",)


class BoxmotTracker:
    """One of BoxMOT's trackers, motion only (see the module docstring).

    Args:
        tracker: one of ``CLASSES`` (botsort, bytetrack, ocsort, deepocsort, hybridsort,
            boosttrack, occluboost, sfsort).
        params: further constructor arguments of that BoxMOT class (its own names, e.g.
            ``track_buffer``, ``max_age``, ``min_hits``, ``iou_threshold``, ``det_thresh``);
            ReID and CMC switches are not accepted.
        frame_rate: frames per second given to BoT-SORT / ByteTrack; None = the sequence's.
        min_score: detections below this score are not given to the tracker.
    """

    needs_frames = False  # boxes only (motion-only trackers)

    def __init__(self, tracker: str, params: Mapping[str, Any] | None = None,
                 frame_rate: float | None = None, min_score: float = 0.0) -> None:
        require("boxmot", INSTALL, type(self).__name__, f"pip install {INSTALL}")
        checks.require("tracker", tracker in CLASSES, f"must be one of {sorted(CLASSES)}",
                       tracker)
        params = dict(params or {})
        forbidden = sorted(set(params) & (set(MOTION_ONLY[tracker]) | {
            "reid_model", "reid_weights", "device", "half", "frame_rate", "frame_width",
            "frame_height"}))
        checks.require("params", not forbidden, f"of boxmot {tracker} must not set {forbidden}: "
                       "the adapter sets them (motion only, frame rate and size from the "
                       "sequence)", sorted(params))
        checks.require("frame_rate", frame_rate is None or frame_rate > 0, "must be > 0 or None",
                       frame_rate)
        module, name = CLASSES[tracker]
        self._cls = getattr(importlib.import_module(module), name)
        self.tracker = tracker
        self.params = params
        self.frame_rate = None if frame_rate is None else float(frame_rate)
        self.min_score = check_min_score(min_score)
        self._info: SequenceInfo | None = None
        self._black: np.ndarray | None = None
        logging.getLogger("boxmot").setLevel(logging.WARNING)
        self.reset()

    def start_sequence(self, info: SequenceInfo) -> None:
        """Take the sequence's frame rate (where ``frame_rate`` is None) and size."""
        self._info = info
        self._black = None
        self.reset()

    def _kwargs(self) -> dict[str, Any]:
        kw = {**self.params, **MOTION_ONLY[self.tracker]}
        if self.tracker in FRAME_RATE:
            fps = self.frame_rate or (self._info.fps if self._info is not None else None)
            if fps is not None:
                kw["frame_rate"] = max(1, int(round(fps)))
        if self.tracker in FRAME_SIZE and self._info is not None:
            kw["frame_width"], kw["frame_height"] = self._info.width, self._info.height
        return kw

    def reset(self) -> None:
        """A fresh BoxMOT tracker."""
        self._tracker = self._cls(**self._kwargs())
        self._ids = IdMap()

    def _image(self, frame: np.ndarray | None) -> np.ndarray | None:
        if frame is not None or self._info is None:
            return frame
        if self._black is None:
            self._black = np.zeros((self._info.height, self._info.width, 3), np.uint8)
        return self._black

    def update(self, frame: np.ndarray | None, detections: Detections,
               foreground: np.ndarray | None = None) -> list[Track]:
        """Advance one frame; ``frame`` is read only for its size (no ReID, no CMC)."""
        keep = detections.scores >= self.min_score
        rows = np.column_stack([xywh_to_xyxy(detections.boxes[keep]), detections.scores[keep],
                                np.zeros(keep.sum())]).reshape(-1, 6)
        result = np.asarray(self._tracker.update(rows, self._image(frame)), dtype=np.float64)
        out = []
        for row in result.reshape(-1, result.shape[-1] if result.ndim == 2 else 8):
            box = xyxy_to_xywh(row[:4])
            box[2:] = np.maximum(box[2:], 1.0)
            score = float(np.clip(row[5], 0.0, 1.0))
            out.append(Track(self._ids(int(row[4])), box, TrackState.CONFIRMED, score=score))
        out.sort(key=lambda t: t.id)
        return out
