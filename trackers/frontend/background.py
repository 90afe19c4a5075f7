"""Background subtraction and mask clean-up (Reta 3.1, PBM 2).

OpenCV's MOG2 (default) or KNN model, or the texture and invariant-colour mixture of Reta 3.1
(``texture_colour.TextureColourMixture``), gives a foreground mask; shadow pixels are
labelled 127 and dropped (PBM 2: shadow removal). ``clean_mask`` applies the morphological
opening and closing. A warm-up learns the background for sequences that start with people in
view: ``warmup_span`` "sequence" (before the first frame, from frames sampled across the whole
sequence: future frames, as an offline detector) or "online" (frames up to the current one
only: frame 1 before the first frame, then again at frames 2, 4, 8, ... from a sample of the
frames seen so far; ``docs/adaptations.md``, "The shared front end").
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence

import cv2
import numpy as np

from occbench.trackers.common.checks import parameter_group, refuse_moved, require
from occbench.trackers.frontend.background_params import (
    GROUPS,
    FrameInput,
    MaskCleanup,
    PixelModel,
    WarmUp,
)
from occbench.trackers.frontend.texture_colour import TextureColourMixture

log = logging.getLogger(__name__)

SHADOW_VALUE = 127  # MOG2/KNN shadow label


def _kernel(size: int | Sequence[int]) -> np.ndarray | None:
    """The elliptic kernel of ``size`` (an int, or (w, h); checked by ``MaskCleanup``), None
    when it would do nothing (0 or 1)."""
    if isinstance(size, int | np.integer):
        size = (int(size), int(size))
    kw, kh = (int(v) for v in size)
    if kw <= 1 and kh <= 1:
        return None
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (max(kw, 1), max(kh, 1)))


def fill_holes(mask: np.ndarray) -> np.ndarray:
    """Fill the background regions of a (H, W) uint8 0/255 mask not connected to its border."""
    h, w = mask.shape
    pad = np.zeros((h + 2, w + 2), dtype=np.uint8)
    pad[1:-1, 1:-1] = mask
    flood = np.zeros((h + 4, w + 4), dtype=np.uint8)
    cv2.floodFill(pad, flood, (0, 0), 255)  # paints the outside background 255
    return mask | ~pad[1:-1, 1:-1]


def clean_mask(
    mask: np.ndarray,
    open_kernel: np.ndarray | None,
    close_kernel: np.ndarray | None,
    holes: bool = False,
) -> np.ndarray:
    """Opening (removes specks), closing (bridges gaps) and optional hole filling of a
    (H, W) uint8 0/255 mask."""
    out = mask
    if open_kernel is not None:
        out = cv2.morphologyEx(out, cv2.MORPH_OPEN, open_kernel)
    if close_kernel is not None:
        out = cv2.morphologyEx(out, cv2.MORPH_CLOSE, close_kernel)
    if holes:
        out = fill_holes(out)
    return out


ONLINE_LAST_REFRESH = 512  # "online": the warm-up is repeated at frames 2, 4, ..., 512
METHODS = ("mog2", "knn", "texture_colour")


def background_estimate(
    frames: Sequence[np.ndarray], inpaint: bool = True, spread_threshold: float = 12.0,
    inpaint_radius: int = 5, spread_quantile: float = 0.5,
) -> np.ndarray:
    """Static background image from frames sampled over a sequence.

    The per-pixel median of the frames; with ``inpaint``, pixels whose temporal spread
    (the ``spread_quantile`` quantile of the grey level's absolute deviation from its
    median: 0.5 is the median absolute deviation, large where about half of the frames
    differ; 0.75 flags pixels where a quarter differ) exceeds ``spread_threshold`` are
    unreliable (people stood there for much of the sample) and are
    filled by ``cv2.inpaint`` (Telea) from the reliable pixels around them, together with
    the steady regions such a ring of unreliable pixels encloses (a person standing still).

    Args:
        frames: (H, W, 3) uint8 images.
    Returns:
        (H, W, 3) uint8 background.
    """
    stack = np.stack(frames)
    med = np.median(stack, axis=0).astype(np.uint8)
    if not inpaint:
        return med
    grey = stack.astype(np.int16).sum(axis=3) // 3
    spread = np.quantile(np.abs(grey - np.median(grey, axis=0)), spread_quantile, axis=0)
    bad = (spread > spread_threshold).astype(np.uint8)
    bad = cv2.morphologyEx(bad, cv2.MORPH_CLOSE,
                           cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (15, 15)))
    # a person standing still is a steady core inside a ring of high spread: fill it too
    bad = cv2.dilate(fill_holes(bad * np.uint8(255)),
                     cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))) // 255
    if not bad.any():
        return med
    return cv2.inpaint(med, bad, inpaint_radius, cv2.INPAINT_TELEA)


class BackgroundModel:
    """Adaptive background model producing a clean (H, W) bool foreground mask.

    The defaults are the values tuned on CAVIAR OneLeaveShop1cor (``conf/detector/*.yaml``).

    Args:
        method: "mog2" (Zivkovic's GMM, default), "knn", or "texture_colour" (Reta 3.1's
            mixture over texture and illumination-invariant colour, ``mixture``).
        model: the per-pixel model and its update (``background_params.PixelModel``).
        cleanup: the mask's morphology (``MaskCleanup``).
        start: the warm-up before (or while) tracking (``WarmUp``).
        frames: what the model is given of each frame (``FrameInput``).
        mixture: the ``TextureColourMixture`` of method "texture_colour" (None: its defaults
            with ``model.history``); ignored by mog2/knn, whose parameters are ``model``'s.
        Each group is its defaults when None; a key of the flat arguments before the groups
        is refused with a TypeError naming its group.
    """

    def __init__(self, method: str = "mog2", model: PixelModel | None = None,
                 cleanup: MaskCleanup | None = None, start: WarmUp | None = None,
                 frames: FrameInput | None = None, mixture: TextureColourMixture | None = None,
                 **moved: object) -> None:
        refuse_moved("background", moved, GROUPS)
        require("background.method", method in METHODS, f"must be one of {METHODS}", method)
        self.method = method
        self.model = parameter_group("model", model, PixelModel)
        self.cleanup = parameter_group("cleanup", cleanup, MaskCleanup)
        self.start = parameter_group("start", start, WarmUp)
        self.frames = parameter_group("frames", frames, FrameInput)
        self.open_kernel = _kernel(self.cleanup.open_kernel)
        self.close_kernel = _kernel(self.cleanup.close_kernel)
        if method == "texture_colour" and mixture is None:
            mixture = TextureColourMixture(history=self.model.history)
        self.mixture = mixture
        self.reset()

    def reset(self) -> None:
        """Forget the learnt background."""
        self._reference: np.ndarray | None = None  # grid samples of the reference background
        self.last_gain = np.ones(3)
        self._seen = 0  # frames applied so far ("online")
        self._sample: list[np.ndarray] = []  # "online": every _stride-th frame seen
        self._stride = 1
        if self.method == "texture_colour":
            self.mixture.reset()
            self._model = self.mixture
            return
        if self.method == "mog2":
            self._model = cv2.createBackgroundSubtractorMOG2(
                history=self.model.history, varThreshold=self.model.var_threshold,
                detectShadows=self.model.detect_shadows,
            )
        else:
            self._model = cv2.createBackgroundSubtractorKNN(
                history=self.model.history, dist2Threshold=self.model.dist2_threshold,
                detectShadows=self.model.detect_shadows,
            )
        if self.method == "mog2" and self.model.background_ratio is not None:  # KNN has none
            self._model.setBackgroundRatio(float(self.model.background_ratio))
        self._model.setShadowThreshold(self.model.shadow_threshold)

    def warm_up(self, frames: Sequence[np.ndarray]) -> None:
        """Learn the background from ``frames`` ((H, W, 3) uint8 each) before tracking
        (see ``warmup``)."""
        frames = [f for f in frames if f is not None]
        if not frames:
            return
        frames = [self._small(f) for f in frames]
        if self.frames.gain_compensation:  # bring the sample to the first frame's brightness
            self._reference = None
            frames = [self._compensate(f) for f in frames]
        if self.start.warmup == "samples":
            rate = 1.0 / max(len(frames), 2)
            for _ in range(self.start.warmup_passes):
                for f in frames:
                    self._model.apply(f, learningRate=rate)
        else:
            bg = background_estimate(frames, inpaint=self.start.warmup == "inpaint",
                                     spread_threshold=self.start.spread_threshold)
            if self.frames.gain_compensation:
                self._reference = self._grid(bg)
            for _ in range(5):
                self._model.apply(bg, learningRate=0.2)
            # then the samples with their people replaced by the estimate, so that the model
            # learns the camera's real pixel noise (30 identical frames would collapse the
            # variances and make every flicker foreground)
            rate = 1.0 / max(len(frames), 2)
            bg16 = bg.astype(np.int16)
            for _ in range(self.start.warmup_passes):
                for f in frames:
                    moving = (np.abs(f.astype(np.int16) - bg16).sum(axis=2) > 3 * 20)[..., None]
                    self._model.apply(np.where(moving, bg, f), learningRate=rate)
        log.debug("background warm-up (%s) on %d frames", self.start.warmup, len(frames))
    def warm_up_sequence(self, length: int, frame: Callable[[int], np.ndarray | None]) -> None:
        """Warm up from ``warmup_frames`` frames sampled evenly over 1..length (1-based);
        "online": from frame 1 alone."""
        self.warm_up(self.sample_frames(length, frame))

    @property
    def uses_future_frames(self) -> bool:
        """Whether the foreground of frame t depends on frames after t."""
        return self.start.warmup_span == "sequence" and self.start.warmup_frames > 0

    def sample_frames(self, length: int, frame: Callable[[int], np.ndarray | None]) -> list:
        """The ``warmup_frames`` frames sampled evenly over 1..length (empty when 0);
        "online": frame 1 only."""
        if self.start.warmup_frames <= 0 or length <= 0:
            return []
        if self.start.warmup_span == "online":
            return [f for f in (frame(1),) if f is not None]
        n = min(self.start.warmup_frames, length)
        ks = np.unique(np.linspace(1, length, n).round().astype(int))
        return [f for f in (frame(int(k)) for k in ks) if f is not None]

    def _small(self, frame: np.ndarray) -> np.ndarray:
        if self.frames.work_scale == 1.0:
            return frame
        h, w = frame.shape[:2]
        scale = self.frames.work_scale
        size = (max(round(w * scale), 1), max(round(h * scale), 1))
        return cv2.resize(frame, size, interpolation=cv2.INTER_AREA)

    GRID = 8  # pixel step of the gain estimate's sample grid

    def _grid(self, img: np.ndarray) -> np.ndarray:
        return img[:: self.GRID, :: self.GRID].reshape(-1, 3).astype(np.float32) + 1.0

    def _compensate(self, frame: np.ndarray) -> np.ndarray:
        """``frame`` scaled per channel to the reference brightness (gain_compensation)."""
        if not self.frames.gain_compensation:
            return frame
        if self._reference is None:
            self._reference = self._grid(frame)
            return frame
        gain = np.median(self._grid(frame) / self._reference, axis=0)
        self.last_gain = gain
        if np.all(np.abs(gain - 1.0) < 0.01):
            return frame
        lut = np.clip(np.arange(256, dtype=np.float32)[:, None] / gain[None, :] + 0.5, 0, 255)
        # one 3-channel table: each channel through its own column, in one pass
        return cv2.LUT(frame, lut.astype(np.uint8).reshape(256, 1, 3))

    def _apply(self, frame: np.ndarray, rate: float) -> np.ndarray:
        out = self._model.apply(self._compensate(self._small(frame)), learningRate=rate)
        if self.frames.work_scale != 1.0:
            out = cv2.resize(out, (frame.shape[1], frame.shape[0]), interpolation=cv2.INTER_NEAREST)
        return out

    def peek(self, frame: np.ndarray) -> np.ndarray:
        """(H, W) bool clean foreground of ``frame`` without updating the model."""
        return self.clean(self._apply(frame, 0.0)) > 0

    def raw(self, frame: np.ndarray) -> np.ndarray:
        """Raw model output (H, W) uint8: 255 foreground, 127 shadow, 0 background."""
        if self.start.warmup_span == "online" and self.start.warmup_frames > 0:
            self._online_warm_up(frame)
        return self._apply(frame, self.model.learning_rate)

    def _online_warm_up(self, frame: np.ndarray) -> None:
        """"online": keep every k-th frame (at most ``warmup_frames``, thinned by halves),
        and at frames 2, 4, 8, ... repeat the warm-up on them: frames up to this one only."""
        self._seen += 1
        t = self._seen
        if (t - 1) % self._stride == 0:
            self._sample.append(frame)
            if len(self._sample) > self.start.warmup_frames:
                self._sample, self._stride = self._sample[::2], 2 * self._stride
        if t >= 2 and t & (t - 1) == 0 and t <= ONLINE_LAST_REFRESH:
            self.warm_up(self._sample)

    def apply(self, frame: np.ndarray) -> np.ndarray:
        """Update with one (H, W, 3) uint8 BGR frame; (H, W) bool clean foreground mask."""
        return self.clean(self.raw(frame)) > 0

    def clean(self, raw: np.ndarray) -> np.ndarray:
        """Drop shadows (127) then open/close: (H, W) uint8 0/255."""
        # shadows are 127: keep only values above it (without shadow detection: any nonzero)
        level = SHADOW_VALUE if self.model.detect_shadows or self.method == "texture_colour" else 0
        fg = cv2.threshold(raw, level, 255, cv2.THRESH_BINARY)[1]
        return clean_mask(fg, self.open_kernel, self.close_kernel, self.cleanup.fill_holes)

    def background_image(self) -> np.ndarray | None:
        """Current background estimate (H, W, 3) uint8, or None before the first frame."""
        return self._model.getBackgroundImage()
