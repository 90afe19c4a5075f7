"""``BackgroundModel``'s settings in groups, one per part of the background subtraction
(``background``'s module docstring).

Each group is a frozen dataclass that checks itself when built (``ValueError`` naming
``background.<group>.<field>`` and the value, through ``occbench.trackers.common.checks``);
the model takes one of each, and Hydra builds them as nested ``_target_`` nodes of
``conf/detector/{foreground,hog,silhouette}.yaml``
(``detector.detector.background.<group>.<field>``); config.yaml's ``background`` (the model
of ``foreground=mog2``) takes the same groups as nested keys.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from occbench.trackers.common.checks import at_least, coerce, require

__all__ = ["GROUPS", "SPANS", "WARMUPS", "FrameInput", "MaskCleanup", "PixelModel", "WarmUp"]

WARMUPS = ("samples", "median", "inpaint")
SPANS = ("sequence", "online")


@dataclass(frozen=True)
class PixelModel:
    """The per-pixel model (MOG2 / KNN; ``history`` also sizes texture_colour's default
    mixture) and its update.

    Args:
        history: frames of history of the model.
        var_threshold: MOG2 squared Mahalanobis threshold (``varThreshold``).
        dist2_threshold: KNN squared distance threshold (``dist2Threshold``; OpenCV's 400 on
            0-255 colour values: a distance of 20, where MOG2's threshold is in variances).
        learning_rate: per-frame update rate in [0, 1]; -1 lets OpenCV choose 1/history.
        detect_shadows: let the model label shadows (then removed from the mask).
        background_ratio: MOG2 share of the mixture weight counted as background (KNN has
            no such setting and ignores it); None
            keeps OpenCV's 0.9, with which anyone present in more than 10% of the recent
            frames becomes background (0.5: more than half).
        shadow_threshold: MOG2/KNN shadow threshold tau: a pixel darker than the background
            by a factor in [tau, 1] with the same chromaticity is shadow (OpenCV 0.5); lower
            values also catch stronger shadows and floor reflections.
    """

    history: int = 500
    var_threshold: float = 25.0
    dist2_threshold: float = 400.0
    learning_rate: float = -1.0
    detect_shadows: bool = True
    background_ratio: float | None = 0.5
    shadow_threshold: float = 0.5

    def __post_init__(self) -> None:
        g = "background.model"
        at_least(g, 1, history=self.history)
        require(f"{g}.var_threshold", self.var_threshold > 0, "must be > 0", self.var_threshold)
        require(f"{g}.dist2_threshold", self.dist2_threshold > 0, "must be > 0",
                self.dist2_threshold)
        require(f"{g}.learning_rate", self.learning_rate == -1 or 0.0 <= self.learning_rate <= 1.0,
                "must be -1 or lie in [0, 1]", self.learning_rate)
        require(f"{g}.background_ratio",
                self.background_ratio is None or 0.0 < self.background_ratio <= 1.0,
                "must lie in (0, 1] or be None", self.background_ratio)
        require(f"{g}.shadow_threshold", 0.0 < self.shadow_threshold < 1.0,
                "must lie in (0, 1)", self.shadow_threshold)
        coerce(self, {"history": int, "var_threshold": float, "dist2_threshold": float,
                      "learning_rate": float,
                      "detect_shadows": bool, "shadow_threshold": float})


def _kernel_size(key: str, size: int | Sequence[int]) -> int | tuple[int, int]:
    """``size`` (an int, or (w, h)) checked: ``>= 0`` each (a kernel size)."""
    sizes = (size, size) if isinstance(size, int) else tuple(size)
    require(key, len(sizes) == 2 and all(int(v) >= 0 for v in sizes),
            "must be >= 0 (a kernel size)", size)
    return int(size) if isinstance(size, int) else (int(sizes[0]), int(sizes[1]))


@dataclass(frozen=True)
class MaskCleanup:
    """The morphology of the mask (``background.clean_mask``).

    Args:
        open_kernel: (w, h) or int size of the elliptic opening kernel; 0/1 disables.
        close_kernel: (w, h) or int size of the elliptic closing kernel; 0/1 disables.
        fill_holes: fill background regions enclosed by foreground (hollow people whose
            clothes match the learnt background).
    """

    open_kernel: int | tuple[int, int] = 3
    close_kernel: int | tuple[int, int] = 7
    fill_holes: bool = False

    def __post_init__(self) -> None:
        for name in ("open_kernel", "close_kernel"):
            size = _kernel_size(f"background.cleanup.{name}", getattr(self, name))
            object.__setattr__(self, name, size)
        coerce(self, {"fill_holes": bool})


@dataclass(frozen=True)
class WarmUp:
    """How the background is learnt before (or while) tracking, for sequences that start
    with people in view.

    Args:
        warmup_frames: number of frames sampled evenly across the sequence to learn the
            background before the first frame (0 disables).
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
    """

    warmup_frames: int = 50
    warmup: str = "inpaint"
    warmup_passes: int = 1
    warmup_span: str = "sequence"
    spread_threshold: float = 12.0

    def __post_init__(self) -> None:
        g = "background.start"
        at_least(g, 1, warmup_passes=self.warmup_passes)
        at_least(g, 0, warmup_frames=self.warmup_frames)
        require(f"{g}.warmup", self.warmup in WARMUPS, f"must be one of {WARMUPS}", self.warmup)
        require(f"{g}.warmup_span", self.warmup_span in SPANS, f"must be one of {SPANS}",
                self.warmup_span)
        coerce(self, {"warmup_frames": int, "warmup_passes": int, "spread_threshold": float})


@dataclass(frozen=True)
class FrameInput:
    """What the model is given of each frame.

    Args:
        work_scale: run the model on frames resized by this factor in (0, 1] (speed); the
            mask is resized back to the frame with nearest-neighbour interpolation before
            the morphology.
        gain_compensation: divide each frame, per channel, by its gain against a reference
            background (the warm-up estimate, else the first frame): the median of
            frame / reference over a sparse pixel grid, robust to the people in view. Global
            illumination and camera-gain changes then do not turn the scene to foreground.
    """

    work_scale: float = 1.0
    gain_compensation: bool = True

    def __post_init__(self) -> None:
        require("background.frames.work_scale", 0.0 < self.work_scale <= 1.0,
                "must lie in (0, 1]", self.work_scale)
        coerce(self, {"work_scale": float, "gain_compensation": bool})


#: the model's groups: its argument -> the group's class
GROUPS = {"model": PixelModel, "cleanup": MaskCleanup, "start": WarmUp, "frames": FrameInput}
