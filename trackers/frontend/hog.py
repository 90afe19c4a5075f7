"""OpenCV's HOG + linear SVM people detector on foreground crops (Dalal and Triggs; Reta's
baseline): ``HogDetector``, ``detector=hog``."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from occbench.trackers.common.checks import at_least, coerce, parameter_group, require
from occbench.trackers.frontend.background import BackgroundModel
from occbench.trackers.frontend.blobs import blobs_from_mask
from occbench.trackers.frontend.detectors import _ForegroundPipeline, _labels_from_boxes
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import Detections


@dataclass(frozen=True)
class Crops:
    """Where HOG looks, and at what size.

    Args:
        full_frame: ignore the foreground and scan the whole frame.
        min_blob_area: smallest foreground blob that gets a crop, pixels.
        margin: crop margin around a blob as a fraction of its height (plus 8 pixels).
        target_height: crops are resized so that their blob is this many pixels high, > 0
            (HOG's 64x128 window holds a ~96-pixel person; the pyramid then searches larger
            sizes), by a factor in [``min_scale``, ``max_upscale``].
        max_upscale: largest resize factor (small people), >= 1.
        min_scale: smallest resize factor (large people), in (0, 1].
    """

    full_frame: bool = False
    min_blob_area: int = 60
    margin: float = 0.25
    target_height: float = 100.0
    max_upscale: float = 4.0
    min_scale: float = 0.25

    def __post_init__(self) -> None:
        at_least("crops", 1, max_upscale=self.max_upscale)
        require("crops.target_height", self.target_height > 0, "must be > 0", self.target_height)
        require("crops.min_scale", 0 < self.min_scale <= 1, "must lie in (0, 1]", self.min_scale)
        coerce(self, {"full_frame": bool, "min_blob_area": int, "margin": float,
                      "target_height": float, "max_upscale": float, "min_scale": float})


@dataclass(frozen=True)
class Scan:
    """The SVM's window scan (``cv2.HOGDescriptor.detectMultiScale``).

    Args:
        hit_threshold: SVM decision threshold (hitThreshold).
        win_stride: window stride in pixels of the (upscaled) crop.
        scale: pyramid scale step, > 1.
    """

    hit_threshold: float = 0.0
    win_stride: int = 8
    scale: float = 1.05

    def __post_init__(self) -> None:
        require("scan.scale", self.scale > 1.0, "must be > 1", self.scale)
        coerce(self, {"hit_threshold": float, "win_stride": int, "scale": float})


@dataclass(frozen=True)
class Boxes:
    """What is reported.

    Args:
        nms_iou: IoU above which overlapping detections (from overlapping crops) are merged.
        box_scale: [width, height] factors shrinking HOG's window around its centre to the
            person ([1, 1] keeps the raw 64x128 window).
        min_foreground: smallest fraction of a (shrunk) box that is foreground.
    """

    nms_iou: float = 0.4
    box_scale: Sequence[float] = (1.0, 1.0)
    min_foreground: float = 0.0

    def __post_init__(self) -> None:
        bs = tuple(float(v) for v in self.box_scale)
        require("boxes.box_scale", len(bs) == 2, "must be [w, h] factors", list(self.box_scale))
        object.__setattr__(self, "box_scale", bs)
        coerce(self, {"nms_iou": float, "min_foreground": float})


def nms(boxes: np.ndarray, scores: np.ndarray, iou_threshold: float) -> np.ndarray:
    """Greedy non-maximum suppression: indices kept, by decreasing score."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    order = np.argsort(-np.asarray(scores), kind="stable")
    iou = iou_matrix(boxes, boxes)
    keep: list[int] = []
    suppressed = np.zeros(len(boxes), dtype=bool)
    for i in order:
        if suppressed[i]:
            continue
        keep.append(int(i))
        suppressed |= iou[i] > iou_threshold
    return np.array(keep, dtype=np.int64)


class HogDetector(_ForegroundPipeline):
    """OpenCV's default HOG + linear SVM people detector (Dalal and Triggs; Reta's baseline),
    run only on crops around foreground blobs.

    Args:
        background: the background model.
        crops: where HOG looks, and at what size (``Crops``; its defaults when None).
        scan: the SVM's window scan (``Scan``).
        boxes: what is reported (``Boxes``).
    """

    def __init__(self, background: BackgroundModel | None = None, crops: Crops | None = None,
                 scan: Scan | None = None, boxes: Boxes | None = None) -> None:
        super().__init__(background)
        self.crops = parameter_group("crops", crops, Crops)
        self.scan = parameter_group("scan", scan, Scan)
        self.boxes = parameter_group("boxes", boxes, Boxes)
        self._hog = cv2.HOGDescriptor()
        self._hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())

    def detect(self, frame: np.ndarray) -> tuple[Detections, np.ndarray]:
        if self.crops.full_frame:
            fg = np.ones(frame.shape[:2], dtype=bool)
            return self.detect_on(frame, fg), fg
        return super().detect(frame)

    def _run(self, img: np.ndarray, upscale: float) -> tuple[np.ndarray, np.ndarray]:
        if upscale != 1.0:
            img = cv2.resize(img, None, fx=upscale, fy=upscale, interpolation=cv2.INTER_LINEAR)
        ph, pw = max(0, 136 - img.shape[0]), max(0, 72 - img.shape[1])
        if ph or pw:  # the crop must hold at least one 64x128 window
            img = cv2.copyMakeBorder(img, ph // 2, ph - ph // 2, pw // 2, pw - pw // 2,
                                     cv2.BORDER_REPLICATE)
        rects, weights = self._hog.detectMultiScale(
            img, hitThreshold=self.scan.hit_threshold,
            winStride=(self.scan.win_stride, self.scan.win_stride), padding=(8, 8),
            scale=self.scan.scale,
        )
        if len(rects) == 0:
            return np.zeros((0, 4)), np.zeros(0)
        r = np.asarray(rects, dtype=np.float64).reshape(-1, 4)
        r[:, 0] -= pw // 2
        r[:, 1] -= ph // 2
        return r / upscale, np.asarray(weights, dtype=np.float64).reshape(-1)

    def detect_on(self, frame: np.ndarray, fg: np.ndarray) -> Detections:
        H, W = frame.shape[:2]
        if self.crops.full_frame:
            regions = [(0, 0, W, H, 1.0)]
        else:
            blobs = blobs_from_mask(fg, self.crops.min_blob_area, perimeter=False)
            regions = []
            for b in blobs:
                x, y, w, h = b.box
                mg = self.crops.margin * h + 8
                x0, y0 = int(max(x - mg, 0)), int(max(y - mg, 0))
                x1, y1 = int(min(x + w + mg, W)), int(min(y + h + mg, H))
                up = float(np.clip(self.crops.target_height / max(h, 1.0), self.crops.min_scale,
                                   self.crops.max_upscale))
                regions.append((x0, y0, x1, y1, up))
        boxes, scores = [], []
        for x0, y0, x1, y1, up in regions:
            r, w = self._run(frame[y0:y1, x0:x1], up)
            if len(r):
                r[:, 0] += x0
                r[:, 1] += y0
                boxes.append(r)
                scores.append(w)
        if not boxes:
            return Detections.empty()
        B, S = np.concatenate(boxes), np.concatenate(scores)
        c = B[:, :2] + B[:, 2:] / 2
        bs = np.asarray(self.boxes.box_scale, dtype=np.float64)
        B = np.column_stack([c - B[:, 2:] * bs / 2, B[:, 2:] * bs])
        keep = nms(B, S, self.boxes.nms_iou)
        B, S = B[keep], S[keep]
        if self.boxes.min_foreground > 0 and not self.crops.full_frame:
            frac = np.array([fg[max(int(y), 0):int(y + h), max(int(x), 0):int(x + w)].mean()
                             if w >= 1 and h >= 1 else 0.0 for x, y, w, h in B])
            B, S = B[frac >= self.boxes.min_foreground], S[frac >= self.boxes.min_foreground]
        scores01 = 1.0 / (1.0 + np.exp(-S))
        return Detections(B, scores01, _labels_from_boxes(B, fg))
