"""What PBM's two comparators share: a hue-saturation model of a box and a target life cycle.

PBM (Section 5) compares with mean shift (MS) and a connected-component mean-shift
particle filter (CCMSPF); both follow one target by its colour alone. Each keeps Perez et
al.'s colour model of the target's box (a hue-saturation histogram of the pixels with a hue
and a value histogram of the dark or grey ones) and moves a box of fixed aspect to where
that colour is. Neither uses detections while a target lives: a detection starts a target
where no target stands (the harness's single-target protocol hands it exactly one, the
person's ground-truth box), a target ends when its ``loss`` rule declares it lost or its
centre leaves the image, and a tracker that lost a target starts again from the detection
its ``restart`` rule accepts (``occbench.trackers.comparators.loss``: our reading, PBM states none; ``tracker.meanshift.loss``).

Boxes are xywh float64 pixels, 0-based top-left, as everywhere in ``trackers``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from occbench.trackers.common.checks import require, unit
from occbench.trackers.comparators.loss import AnyDetection, MostSimilar, NeverLost, SimilarityBelow
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import Detections, Track, TrackState

HUE_BINS = 16
SAT_BINS = 16
VAL_BINS = 16
MODEL_BINS = HUE_BINS * SAT_BINS + VAL_BINS


def colour_bins(frame: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 BGR -> (H, W) int64 bin of every pixel in Perez et al.'s colour model:
    hue and saturation bins for a pixel with a hue (saturation >= 30 and value >= 32), else
    HUE_BINS * SAT_BINS plus its value bin (dark and grey pixels carry no usable hue)."""
    hsv = cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)
    hue = hsv[..., 0].astype(np.int64) * HUE_BINS // 180
    sat = hsv[..., 1].astype(np.int64) * SAT_BINS // 256
    val = hsv[..., 2].astype(np.int64) * VAL_BINS // 256
    has_hue = (hsv[..., 1] >= 30) & (hsv[..., 2] >= 32)
    return np.where(has_hue, hue * SAT_BINS + sat, HUE_BINS * SAT_BINS + val)


def clip_box(box: np.ndarray, width: int, height: int) -> tuple[int, int, int, int] | None:
    """xywh float box -> integer (x0, y0, x1, y1) inside the image, None when empty."""
    x0 = max(int(round(box[0])), 0)
    y0 = max(int(round(box[1])), 0)
    x1 = min(int(round(box[0] + box[2])), width)
    y1 = min(int(round(box[1] + box[3])), height)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return None
    return x0, y0, x1, y1


def colour_model(bins: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Perez et al.'s colour model of ``box``: the histogram of its pixels' ``colour_bins``
    (hue-saturation bins, then value bins of the pixels without a hue), (MODEL_BINS,)
    float64 summing to 1 (all zero for an empty box). Grey pixels count too, so a box half
    on the person and half on a grey floor differs from one on the person."""
    r = clip_box(box, bins.shape[1], bins.shape[0])
    if r is None:
        return np.zeros(MODEL_BINS)
    x0, y0, x1, y1 = r
    h = np.bincount(bins[y0:y1, x0:x1].ravel(), minlength=MODEL_BINS).astype(np.float64)
    return h / h.sum()


@dataclass
class ColourTarget:
    """One followed person: its id, box (xywh), colour model q and miss counter."""

    id: int
    box: np.ndarray
    q: np.ndarray
    misses: int = 0


Loss = NeverLost | SimilarityBelow
Restart = AnyDetection | MostSimilar


class ColourTrackerBase:
    """Life cycle shared by the colour-only comparators; subclasses implement ``_follow``.

    Args:
        birth_iou: a detection starts a target when its IoU with every target's box is
            below this.
        loss: when a target is lost (``occbench.trackers.comparators.loss``); None =
            ``SimilarityBelow(0.5, 11)``.
        restart: which detections a tracker that lost a target starts again from; None =
            ``AnyDetection()``.
        max_targets: targets followed at once (None = no bound); 1 makes it the
            single-target tracker the papers compare with (later detections start nothing
            while its target lives).
    """

    needs_frames = True  # colour is all it sees

    def __init__(self, birth_iou: float = 0.3, loss: Loss | None = None,
                 restart: Restart | None = None, max_targets: int | None = None) -> None:
        unit("", birth_iou=birth_iou)
        require("max_targets", max_targets is None or max_targets >= 1, "must be >= 1 or None",
                max_targets)
        self.max_targets = max_targets
        self.birth_iou = birth_iou
        self.loss = SimilarityBelow() if loss is None else loss
        self.restart = AnyDetection() if restart is None else restart
        self.reset()

    def reset(self) -> None:
        """Forget every target (and any loss) and restart ids at 1."""
        self._targets: list[ColourTarget] = []
        self._next_id = 1
        self._lost: np.ndarray | None = None  # the last lost target's q, until a restart

    def _follow(self, target: ColourTarget, bins: np.ndarray) -> float:
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
        bins = colour_bins(frame)
        height, width = frame.shape[:2]
        kept = []
        for t in self._targets:  # 1. follow each target by its colour
            rho = self._follow(t, bins)
            t.misses = t.misses + 1 if self.loss.missed(rho) else 0
            cx, cy = t.box[0] + t.box[2] / 2, t.box[1] + t.box[3] / 2
            inside = 0 <= cx < width and 0 <= cy < height
            if inside and not self.loss.lost(t.misses):  # 2. end the lost
                kept.append(t)
            else:
                self._lost = t.q
        self._targets = kept
        self._births(detections, bins)  # 3. start targets where none stands
        return [Track(t.id, t.box.copy(), TrackState.CONFIRMED) for t in self._targets]

    def _births(self, detections: Detections, bins: np.ndarray) -> None:
        """Start targets from free detections, in the order ``restart`` accepts them."""
        taken = np.array([t.box for t in self._targets]).reshape(-1, 4)
        models = np.array([colour_model(bins, b) for b in detections.boxes]).reshape(-1, MODEL_BINS)
        for i in self.restart.order(models, self._lost):
            box, q = detections.boxes[i], models[i]
            if self.max_targets is not None and len(self._targets) >= self.max_targets:
                return
            if len(taken) and iou_matrix(box[None], taken).max() >= self.birth_iou:
                continue  # a target stands there already
            if q.sum() == 0:
                continue  # the box lies outside the image
            self._targets.append(ColourTarget(self._next_id, box.astype(np.float64), q))
            self._next_id += 1
            self._lost = None  # the loss is answered
            taken = np.vstack([taken, box])
