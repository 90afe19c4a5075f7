"""Background subtraction and mask clean-up (Reta 3.1, PBM 2).

OpenCV's MOG2 (default) or KNN model gives a foreground mask; MOG2/KNN mark shadow pixels
127 and these are dropped (PBM 2: shadow removal). ``clean_mask`` applies the morphological
opening and closing. A warm-up learns the background before the first frame from frames
sampled across the sequence, for sequences that start with people in view.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence

import cv2
import numpy as np

log = logging.getLogger(__name__)

SHADOW_VALUE = 127  # MOG2/KNN shadow label


def _kernel(size: int | Sequence[int], name: str) -> np.ndarray | None:
    if isinstance(size, int | np.integer):
        size = (int(size), int(size))
    kw, kh = (int(v) for v in size)
    if kw < 0 or kh < 0:
        raise ValueError(f"{name} kernel size must be >= 0, got {size}")
    if kw <= 1 and kh <= 1:
        return None
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (max(kw, 1), max(kh, 1)))


def clean_mask(
    mask: np.ndarray, open_kernel: np.ndarray | None, close_kernel: np.ndarray | None
) -> np.ndarray:
    """Opening (removes specks) then closing (fills holes) of a (H, W) uint8 0/255 mask."""
    out = mask
    if open_kernel is not None:
        out = cv2.morphologyEx(out, cv2.MORPH_OPEN, open_kernel)
    if close_kernel is not None:
        out = cv2.morphologyEx(out, cv2.MORPH_CLOSE, close_kernel)
    return out


class BackgroundModel:
    """Adaptive background model producing a clean (H, W) bool foreground mask.

    Args:
        method: "mog2" (Zivkovic's GMM, default) or "knn".
        history: frames of history of the model.
        var_threshold: MOG2 squared Mahalanobis threshold (KNN: squared distance threshold).
        learning_rate: per-frame update rate in [0, 1]; -1 lets OpenCV choose 1/history.
        detect_shadows: let the model label shadows (then removed from the mask).
        open_kernel: (w, h) or int size of the elliptic opening kernel; 0/1 disables.
        close_kernel: (w, h) or int size of the elliptic closing kernel; 0/1 disables.
        warmup_frames: number of frames sampled evenly across the sequence and fed to the
            model before the first frame (0 disables); learns a background when people are
            in view at the start.
        warmup_passes: times the warm-up sample is fed (more passes forget moving people).
        median_init: build the warm-up sample's per-pixel median image and feed it as the
            first warm-up frames (a median background), before the samples.
    """

    def __init__(
        self,
        method: str = "mog2",
        history: int = 500,
        var_threshold: float = 16.0,
        learning_rate: float = -1.0,
        detect_shadows: bool = True,
        open_kernel: int | Sequence[int] = 3,
        close_kernel: int | Sequence[int] = 5,
        warmup_frames: int = 0,
        warmup_passes: int = 1,
        median_init: bool = True,
    ) -> None:
        if method not in ("mog2", "knn"):
            raise ValueError(f"method must be 'mog2' or 'knn', got {method!r}")
        if history < 1:
            raise ValueError(f"history must be >= 1, got {history}")
        if var_threshold <= 0:
            raise ValueError(f"var_threshold must be > 0, got {var_threshold}")
        if not (learning_rate == -1 or 0.0 <= learning_rate <= 1.0):
            raise ValueError(f"learning_rate must be -1 or in [0, 1], got {learning_rate}")
        if warmup_frames < 0 or warmup_passes < 1:
            raise ValueError(
                f"warmup_frames must be >= 0 and warmup_passes >= 1, got "
                f"{warmup_frames}, {warmup_passes}"
            )
        self.method = method
        self.history = int(history)
        self.var_threshold = float(var_threshold)
        self.learning_rate = float(learning_rate)
        self.detect_shadows = bool(detect_shadows)
        self.open_kernel = _kernel(open_kernel, "open_kernel")
        self.close_kernel = _kernel(close_kernel, "close_kernel")
        self.warmup_frames = int(warmup_frames)
        self.warmup_passes = int(warmup_passes)
        self.median_init = bool(median_init)
        self.reset()

    def reset(self) -> None:
        """Forget the learnt background."""
        if self.method == "mog2":
            self._model = cv2.createBackgroundSubtractorMOG2(
                history=self.history, varThreshold=self.var_threshold,
                detectShadows=self.detect_shadows,
            )
        else:
            self._model = cv2.createBackgroundSubtractorKNN(
                history=self.history, dist2Threshold=self.var_threshold,
                detectShadows=self.detect_shadows,
            )

    def warm_up(self, frames: Sequence[np.ndarray]) -> None:
        """Learn the background from ``frames`` ((H, W, 3) uint8 each) before tracking.

        With ``median_init`` the per-pixel median of the frames is fed first (a median
        background), then the frames themselves ``warmup_passes`` times at learning rate
        1/len; the person pixels seen in a minority of frames end up as foreground.
        """
        frames = [f for f in frames if f is not None]
        if not frames:
            return
        rate = 1.0 / max(len(frames), 2)
        if self.median_init:
            med = np.median(np.stack(frames), axis=0).astype(np.uint8)
            for _ in range(min(self.history, 30)):
                self._model.apply(med, learningRate=max(rate, 0.05))
        for _ in range(self.warmup_passes):
            for f in frames:
                self._model.apply(f, learningRate=rate)
        if self.median_init:
            # end on the median so the dominant mode is the background
            for _ in range(10):
                self._model.apply(med, learningRate=0.05)
        log.debug("background warm-up on %d frames", len(frames))

    def warm_up_sequence(self, length: int, frame: Callable[[int], np.ndarray | None]) -> None:
        """Warm up from ``warmup_frames`` frames sampled evenly over 1..length (1-based)."""
        if self.warmup_frames <= 0 or length <= 0:
            return
        ks = np.unique(np.linspace(1, length, min(self.warmup_frames, length)).round().astype(int))
        self.warm_up([frame(int(k)) for k in ks])

    def raw(self, frame: np.ndarray) -> np.ndarray:
        """Raw model output (H, W) uint8: 255 foreground, 127 shadow, 0 background."""
        return self._model.apply(frame, learningRate=self.learning_rate)

    def apply(self, frame: np.ndarray) -> np.ndarray:
        """Update with one (H, W, 3) uint8 BGR frame; (H, W) bool clean foreground mask."""
        return self.clean(self.raw(frame)) > 0

    def clean(self, raw: np.ndarray) -> np.ndarray:
        """Drop shadows (127) then open/close: (H, W) uint8 0/255."""
        # shadows are 127: keep only values above it (without shadow detection: any nonzero)
        level = SHADOW_VALUE if self.detect_shadows else 0
        fg = cv2.threshold(raw, level, 255, cv2.THRESH_BINARY)[1]
        return clean_mask(fg, self.open_kernel, self.close_kernel)

    def background_image(self) -> np.ndarray | None:
        """Current background estimate (H, W, 3) uint8, or None before the first frame."""
        return self._model.getBackgroundImage()
