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

from occbench.trackers.common.checks import at_least, require
from occbench.trackers.frontend.texture_colour import TextureColourMixture

log = logging.getLogger(__name__)

SHADOW_VALUE = 127  # MOG2/KNN shadow label


def _kernel(size: int | Sequence[int], name: str) -> np.ndarray | None:
    if isinstance(size, int | np.integer):
        size = (int(size), int(size))
    kw, kh = (int(v) for v in size)
    require(f"background.{name}", kw >= 0 and kh >= 0, "must be >= 0 (a kernel size)", size)
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


WARMUPS = ("samples", "median", "inpaint")
SPANS = ("sequence", "online")
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
        history: frames of history of the model.
        var_threshold: MOG2 squared Mahalanobis threshold (KNN: squared distance threshold).
        learning_rate: per-frame update rate in [0, 1]; -1 lets OpenCV choose 1/history.
        detect_shadows: let the model label shadows (then removed from the mask).
        background_ratio: MOG2 share of the mixture weight counted as background; None
            keeps OpenCV's 0.9, with which anyone present in more than 10% of the recent
            frames becomes background (0.5: more than half).
        open_kernel: (w, h) or int size of the elliptic opening kernel; 0/1 disables.
        close_kernel: (w, h) or int size of the elliptic closing kernel; 0/1 disables.
        fill_holes: fill background regions enclosed by foreground (hollow people whose
            clothes match the learnt background).
        warmup_frames: number of frames sampled evenly across the sequence to learn the
            background before the first frame (0 disables): for sequences that start with
            people in view.
        warmup: how the sample teaches the model: "samples" feeds the frames themselves
            (``warmup_passes`` times, rate 1/len), "median" feeds their per-pixel median,
            "inpaint" feeds the median with high-spread pixels inpainted
            (``background_estimate``: for people who stay in one place).
        warmup_passes: times the sample is fed.
        warmup_span: which frames the warm-up may see: "sequence" (``warmup_frames`` sampled
            evenly over the whole sequence before the first frame: the detections of frame t
            then depend on frames after t) or "online" (only frames up to the current one:
            frame 1 before the first frame; at frames t = 2, 4, 8, ... up to
            ``ONLINE_LAST_REFRESH`` the warm-up is repeated, without a reset, on at most
            ``warmup_frames`` frames spread evenly over 1..t, kept by halving a sample of
            every k-th frame as it fills).
        spread_threshold: grey-level spread above which a pixel is inpainted ("inpaint").
        gain_compensation: divide each frame, per channel, by its gain against a reference
            background (the warm-up estimate, else the first frame): the median of
            frame / reference over a sparse pixel grid, robust to the people in view. Global
            illumination and camera-gain changes then do not turn the scene to foreground.
        work_scale: run the model on frames resized by this factor in (0, 1] (speed); the
            mask is resized back to the frame with nearest-neighbour interpolation before
            the morphology.
        shadow_threshold: MOG2/KNN shadow threshold tau: a pixel darker than the background
            by a factor in [tau, 1] with the same chromaticity is shadow (OpenCV 0.5); lower
            values also catch stronger shadows and floor reflections.
        mixture: the ``TextureColourMixture`` of method "texture_colour" (None: its defaults
            with ``history``); ignored by mog2/knn, whose parameters are the ones above.
    """

    def __init__(
        self,
        method: str = "mog2",
        history: int = 500,
        var_threshold: float = 25.0,
        learning_rate: float = -1.0,
        detect_shadows: bool = True,
        background_ratio: float | None = 0.5,
        open_kernel: int | Sequence[int] = 3,
        close_kernel: int | Sequence[int] = 7,
        fill_holes: bool = False,
        warmup_frames: int = 50,
        warmup: str = "inpaint",
        warmup_passes: int = 1,
        warmup_span: str = "sequence",
        spread_threshold: float = 12.0,
        shadow_threshold: float = 0.5,
        work_scale: float = 1.0,
        gain_compensation: bool = True,
        mixture: TextureColourMixture | None = None,
    ) -> None:
        require("background.method", method in METHODS, f"must be one of {METHODS}", method)
        at_least("background", 1, history=history, warmup_passes=warmup_passes)
        at_least("background", 0, warmup_frames=warmup_frames)
        require("background.var_threshold", var_threshold > 0, "must be > 0", var_threshold)
        require("background.learning_rate", learning_rate == -1 or 0.0 <= learning_rate <= 1.0,
                "must be -1 or lie in [0, 1]", learning_rate)
        require("background.background_ratio",
                background_ratio is None or 0.0 < background_ratio <= 1.0,
                "must lie in (0, 1] or be None", background_ratio)
        require("background.warmup", warmup in WARMUPS, f"must be one of {WARMUPS}", warmup)
        require("background.warmup_span", warmup_span in SPANS, f"must be one of {SPANS}",
                warmup_span)
        require("background.shadow_threshold", 0.0 < shadow_threshold < 1.0, "must lie in (0, 1)",
                shadow_threshold)
        require("background.work_scale", 0.0 < work_scale <= 1.0, "must lie in (0, 1]",
                work_scale)
        self.method = method
        self.history = int(history)
        self.var_threshold = float(var_threshold)
        self.learning_rate = float(learning_rate)
        self.detect_shadows = bool(detect_shadows)
        self.background_ratio = background_ratio
        self.open_kernel = _kernel(open_kernel, "open_kernel")
        self.close_kernel = _kernel(close_kernel, "close_kernel")
        self.fill_holes = bool(fill_holes)
        self.warmup_frames = int(warmup_frames)
        self.warmup = warmup
        self.warmup_passes = int(warmup_passes)
        self.warmup_span = warmup_span
        self.spread_threshold = float(spread_threshold)
        self.shadow_threshold = float(shadow_threshold)
        self.work_scale = float(work_scale)
        self.gain_compensation = bool(gain_compensation)
        if method == "texture_colour" and mixture is None:
            mixture = TextureColourMixture(history=self.history)
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
                history=self.history, varThreshold=self.var_threshold,
                detectShadows=self.detect_shadows,
            )
        else:
            self._model = cv2.createBackgroundSubtractorKNN(
                history=self.history, dist2Threshold=self.var_threshold,
                detectShadows=self.detect_shadows,
            )
        if self.background_ratio is not None:
            self._model.setBackgroundRatio(float(self.background_ratio))
        self._model.setShadowThreshold(self.shadow_threshold)

    def warm_up(self, frames: Sequence[np.ndarray]) -> None:
        """Learn the background from ``frames`` ((H, W, 3) uint8 each) before tracking
        (see ``warmup``)."""
        frames = [f for f in frames if f is not None]
        if not frames:
            return
        frames = [self._small(f) for f in frames]
        if self.gain_compensation:  # bring the sample to the first frame's brightness
            self._reference = None
            frames = [self._compensate(f) for f in frames]
        if self.warmup == "samples":
            rate = 1.0 / max(len(frames), 2)
            for _ in range(self.warmup_passes):
                for f in frames:
                    self._model.apply(f, learningRate=rate)
        else:
            bg = background_estimate(frames, inpaint=self.warmup == "inpaint",
                                     spread_threshold=self.spread_threshold)
            if self.gain_compensation:
                self._reference = self._grid(bg)
            for _ in range(5):
                self._model.apply(bg, learningRate=0.2)
            # then the samples with their people replaced by the estimate, so that the model
            # learns the camera's real pixel noise (30 identical frames would collapse the
            # variances and make every flicker foreground)
            rate = 1.0 / max(len(frames), 2)
            bg16 = bg.astype(np.int16)
            for _ in range(self.warmup_passes):
                for f in frames:
                    moving = (np.abs(f.astype(np.int16) - bg16).sum(axis=2) > 3 * 20)[..., None]
                    self._model.apply(np.where(moving, bg, f), learningRate=rate)
        log.debug("background warm-up (%s) on %d frames", self.warmup, len(frames))
    def warm_up_sequence(self, length: int, frame: Callable[[int], np.ndarray | None]) -> None:
        """Warm up from ``warmup_frames`` frames sampled evenly over 1..length (1-based);
        "online": from frame 1 alone."""
        self.warm_up(self.sample_frames(length, frame))

    @property
    def uses_future_frames(self) -> bool:
        """Whether the foreground of frame t depends on frames after t."""
        return self.warmup_span == "sequence" and self.warmup_frames > 0

    def sample_frames(self, length: int, frame: Callable[[int], np.ndarray | None]) -> list:
        """The ``warmup_frames`` frames sampled evenly over 1..length (empty when 0);
        "online": frame 1 only."""
        if self.warmup_frames <= 0 or length <= 0:
            return []
        if self.warmup_span == "online":
            return [f for f in (frame(1),) if f is not None]
        ks = np.unique(np.linspace(1, length, min(self.warmup_frames, length)).round().astype(int))
        return [f for f in (frame(int(k)) for k in ks) if f is not None]

    def _small(self, frame: np.ndarray) -> np.ndarray:
        if self.work_scale == 1.0:
            return frame
        h, w = frame.shape[:2]
        size = (max(round(w * self.work_scale), 1), max(round(h * self.work_scale), 1))
        return cv2.resize(frame, size, interpolation=cv2.INTER_AREA)

    GRID = 8  # pixel step of the gain estimate's sample grid

    def _grid(self, img: np.ndarray) -> np.ndarray:
        return img[:: self.GRID, :: self.GRID].reshape(-1, 3).astype(np.float32) + 1.0

    def _compensate(self, frame: np.ndarray) -> np.ndarray:
        """``frame`` scaled per channel to the reference brightness (gain_compensation)."""
        if not self.gain_compensation:
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
        if self.work_scale != 1.0:
            out = cv2.resize(out, (frame.shape[1], frame.shape[0]), interpolation=cv2.INTER_NEAREST)
        return out

    def peek(self, frame: np.ndarray) -> np.ndarray:
        """(H, W) bool clean foreground of ``frame`` without updating the model."""
        return self.clean(self._apply(frame, 0.0)) > 0

    def raw(self, frame: np.ndarray) -> np.ndarray:
        """Raw model output (H, W) uint8: 255 foreground, 127 shadow, 0 background."""
        if self.warmup_span == "online" and self.warmup_frames > 0:
            self._online_warm_up(frame)
        return self._apply(frame, self.learning_rate)

    def _online_warm_up(self, frame: np.ndarray) -> None:
        """"online": keep every k-th frame (at most ``warmup_frames``, thinned by halves),
        and at frames 2, 4, 8, ... repeat the warm-up on them: frames up to this one only."""
        self._seen += 1
        t = self._seen
        if (t - 1) % self._stride == 0:
            self._sample.append(frame)
            if len(self._sample) > self.warmup_frames:
                self._sample, self._stride = self._sample[::2], 2 * self._stride
        if t >= 2 and t & (t - 1) == 0 and t <= ONLINE_LAST_REFRESH:
            self.warm_up(self._sample)

    def apply(self, frame: np.ndarray) -> np.ndarray:
        """Update with one (H, W, 3) uint8 BGR frame; (H, W) bool clean foreground mask."""
        return self.clean(self.raw(frame)) > 0

    def clean(self, raw: np.ndarray) -> np.ndarray:
        """Drop shadows (127) then open/close: (H, W) uint8 0/255."""
        # shadows are 127: keep only values above it (without shadow detection: any nonzero)
        level = SHADOW_VALUE if self.detect_shadows or self.method == "texture_colour" else 0
        fg = cv2.threshold(raw, level, 255, cv2.THRESH_BINARY)[1]
        return clean_mask(fg, self.open_kernel, self.close_kernel, self.fill_holes)

    def background_image(self) -> np.ndarray | None:
        """Current background estimate (H, W, 3) uint8, or None before the first frame."""
        return self._model.getBackgroundImage()
