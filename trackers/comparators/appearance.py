"""What PBM's two comparators share: a hue-saturation model of a box and a target life cycle.

PBM (Section 5) compares with mean shift (MS) and a connected-component mean-shift
particle filter (CCMSPF); both follow one target by its colour alone. Each keeps Perez et
al.'s colour model of the target's box (a hue-saturation histogram of the pixels with a hue
and a value histogram of the dark or grey ones) and moves a box of fixed aspect to where
that colour is. Neither uses detections once a target is started: a
detection starts a target where no target stands (the harness's single-target protocol
hands it exactly one, the person's ground-truth box), and a target ends when its colour
is gone (similarity below ``min_similarity`` for ``max_misses`` frames in a row) or its
centre leaves the image.

Boxes are xywh float64 pixels, 0-based top-left, as everywhere in ``trackers``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from trackers.geometry import iou_matrix
from trackers.records import Detections, Track, TrackState

HUE_BINS = 16
SAT_BINS = 16
VAL_BINS = 16
_RANGES = [0, 180, 0, 256]


def hsv_of(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(H, W, 3) uint8 BGR -> its HSV image and the (H, W) uint8 mask of pixels with a hue
    (saturation >= 30 and value >= 32: dark and grey pixels carry no usable hue)."""
    hsv = cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)
    mask = cv2.inRange(hsv, (0, 30, 32), (180, 255, 255))
    return hsv, mask


def clip_box(box: np.ndarray, width: int, height: int) -> tuple[int, int, int, int] | None:
    """xywh float box -> integer (x0, y0, x1, y1) inside the image, None when empty."""
    x0 = max(int(round(box[0])), 0)
    y0 = max(int(round(box[1])), 0)
    x1 = min(int(round(box[0] + box[2])), width)
    y1 = min(int(round(box[1] + box[3])), height)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return None
    return x0, y0, x1, y1


def hs_histogram(hsv: np.ndarray, mask: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Colour model of ``box`` after Perez et al. (2002): a hue-saturation histogram of the
    pixels with a hue (``mask``) followed by a value histogram of the others, (HUE_BINS *
    SAT_BINS + VAL_BINS,) float64 summing to 1 (all zero for an empty box). Grey pixels
    count too, so a box half on the person and half on a grey floor differs from one on
    the person."""
    r = clip_box(box, hsv.shape[1], hsv.shape[0])
    if r is None:
        return np.zeros(HUE_BINS * SAT_BINS + VAL_BINS)
    x0, y0, x1, y1 = r
    roi, m = hsv[y0:y1, x0:x1], mask[y0:y1, x0:x1]
    hs = cv2.calcHist([roi], [0, 1], m, [HUE_BINS, SAT_BINS], _RANGES).ravel()
    v = cv2.calcHist([roi], [2], cv2.bitwise_not(m), [VAL_BINS], [0, 256]).ravel()
    h = np.concatenate([hs, v]).astype(np.float64)
    s = h.sum()
    return h / s if s > 0 else h


@dataclass
class ColourTarget:
    """One followed person: its id, box (xywh), colour model q and miss counter."""

    id: int
    box: np.ndarray
    q: np.ndarray
    misses: int = 0


class ColourTrackerBase:
    """Life cycle shared by the colour-only comparators; subclasses implement ``_follow``.

    Args:
        birth_iou: a detection starts a target when its IoU with every target's box is
            below this.
        min_similarity: Bhattacharyya coefficient of the followed box's colour with the
            model below which the frame counts as a miss.
        max_misses: misses in a row after which a target ends.
    """

    def __init__(self, birth_iou: float = 0.3, min_similarity: float = 0.5,
                 max_misses: int = 10) -> None:
        if not 0.0 <= birth_iou <= 1.0:
            raise ValueError(f"birth_iou must lie in [0, 1], got {birth_iou}")
        if not 0.0 <= min_similarity <= 1.0:
            raise ValueError(f"min_similarity must lie in [0, 1], got {min_similarity}")
        if max_misses < 0:
            raise ValueError(f"max_misses must be >= 0, got {max_misses}")
        self.birth_iou = birth_iou
        self.min_similarity = min_similarity
        self.max_misses = max_misses
        self.reset()

    def reset(self) -> None:
        """Forget every target and restart ids at 1."""
        self._targets: list[ColourTarget] = []
        self._next_id = 1

    def _follow(self, target: ColourTarget, hsv: np.ndarray, mask: np.ndarray) -> float:
        """Move ``target.box`` to where its colour is; return the similarity there."""
        raise NotImplementedError

    def update(self, frame: np.ndarray | None, detections: Detections,
               foreground: np.ndarray | None = None) -> list[Track]:
        """Advance one frame: follow every target, end the lost, start new ones.

        Args:
            frame: (H, W, 3) uint8 BGR; required (colour is all these trackers see).
            detections: boxes that may start targets; otherwise unused.
            foreground: unused.
        Returns:
            One CONFIRMED Track per live target.
        """
        if frame is None:
            raise ValueError(f"{type(self).__name__} needs frames (colour is all it sees)")
        hsv, mask = hsv_of(frame)
        height, width = frame.shape[:2]
        kept = []
        for t in self._targets:  # 1. follow each target by its colour
            rho = self._follow(t, hsv, mask)
            t.misses = t.misses + 1 if rho < self.min_similarity else 0
            cx, cy = t.box[0] + t.box[2] / 2, t.box[1] + t.box[3] / 2
            inside = 0 <= cx < width and 0 <= cy < height
            if inside and t.misses <= self.max_misses:  # 2. end the lost
                kept.append(t)
        self._targets = kept
        self._births(detections, hsv, mask)  # 3. start targets where none stands
        return [Track(t.id, t.box.copy(), TrackState.CONFIRMED) for t in self._targets]

    def _births(self, detections: Detections, hsv: np.ndarray, mask: np.ndarray) -> None:
        taken = np.array([t.box for t in self._targets]).reshape(-1, 4)
        for box in detections.boxes:
            if len(taken) and iou_matrix(box[None], taken).max() >= self.birth_iou:
                continue  # a target stands there already
            q = hs_histogram(hsv, mask, box)
            if q.sum() == 0:
                continue  # nothing with a hue in the box: nothing to follow
            self._targets.append(ColourTarget(self._next_id, box.astype(np.float64), q))
            self._next_id += 1
            taken = np.vstack([taken, box])
