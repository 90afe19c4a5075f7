"""A camera's empty background learnt from other footage of the same camera (no labels).

In a clip that starts with people in view and in which they never leave their spot, a
background learnt from the clip itself holds them. Other clips of the same camera show the
same floor with people elsewhere, so a per-pixel robust statistic over several clips is the
empty scene:

* each clip gives its temporal median ``M_i`` (its own background, with whoever stands still
  in it);
* brightness is normalised per clip (lighting differs from one clip to the next): each
  clip's per-channel gain against the median of all the clips' medians is the median, over
  the pixels, of their ratio (robust to the people in either), and the clip is divided by
  it;
* the camera's background ``P`` is the per-pixel median of the normalised ``M_i`` (a spot
  occupied in one clip is empty in most others), and its ``spread`` the robust spread of
  the ``M_i`` about it (1.4826 MAD of the grey level): large where the clips disagree among
  themselves (glare from the windows, lights, things moved), small on the steady floor.

A clip is then started from ``P`` brought to the clip's own brightness (``start_with``):
where the clip's own median ``M`` agrees with it, or where the footage itself is not steady
(``spread`` above ``steady_spread``: glare and lighting the other clips cannot tell about),
the clip's own ``M``; elsewhere (the footage agrees on an empty floor and the clip shows
something steady on it: someone standing still) ``P``.

Plain numpy. Reading the footage (folders of frames, videos) is the harness's
(``occbench.sources.footage``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CameraBackground:
    """The empty background of one camera, pooled over clips.

    Attributes:
        image: (H, W, 3) float32 BGR background ``P`` at the pool's brightness.
        spread: (H, W) float32 robust spread of the clips' grey level about it.
        clips: number of clips pooled.
        label: what footage it was learnt from (for the log line).
    """

    image: np.ndarray
    spread: np.ndarray
    clips: int
    label: str

    @property
    def shape(self) -> tuple[int, int]:
        return int(self.image.shape[0]), int(self.image.shape[1])


def clip_median(frames: list[np.ndarray]) -> np.ndarray:
    """(H, W, 3) float32 per-pixel temporal median of one clip's (H, W, 3) uint8 frames."""
    if not frames:
        raise ValueError("clip_median: no frames")
    return np.median(np.stack(frames), axis=0).astype(np.float32)


def channel_gain(image: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """(3,) per-channel gain of ``image`` against ``reference`` ((H, W, 3) each): the median
    over the pixels of their ratio (people in either are a minority of the pixels)."""
    return np.median((image.reshape(-1, 3) + 1.0) / (reference.reshape(-1, 3) + 1.0), axis=0)


def pool_clips(medians: list[np.ndarray], label: str) -> CameraBackground:
    """The camera's background from the temporal medians ((H, W, 3) float32) of its clips
    (see the module docstring)."""
    if not medians:
        raise ValueError(f"{label}: no clips to pool")
    shapes = {m.shape for m in medians}
    if len(shapes) > 1:
        raise ValueError(f"{label}: clips of different sizes {sorted(shapes)}")
    stack = np.stack(medians)
    first = np.median(stack, axis=0)
    stack = np.stack([m / channel_gain(m, first) for m in medians])  # brightness per clip
    image = np.median(stack, axis=0).astype(np.float32)
    grey = stack.mean(axis=3)
    spread = 1.4826 * np.median(np.abs(grey - image.mean(axis=2)), axis=0)
    return CameraBackground(image, spread.astype(np.float32), len(medians), label)


def start_with(footage: CameraBackground, own: np.ndarray, threshold: np.ndarray,
               steady_spread: float) -> tuple[np.ndarray, np.ndarray]:
    """The clip's starting background from the footage's and its own median (see the module
    docstring).

    Args:
        footage: the camera's pooled background.
        own: (H, W, 3) float32 the clip's own median (same smoothing as ``footage.image``).
        threshold: (H, W) grey levels above which a pixel differs (the clip's foreground
            threshold).
        steady_spread: footage spread (grey levels) above which the clip's own median is
            kept.
    Returns:
        (H, W, 3) float32 background and (H, W) bool: where the footage's was taken.
    """
    if footage.shape != own.shape[:2]:
        raise ValueError(f"background footage {footage.label}: frames of {footage.shape[1]}x"
                         f"{footage.shape[0]}, the sequence's are {own.shape[1]}x{own.shape[0]}")
    P = footage.image * channel_gain(own, footage.image)  # at the clip's brightness
    differs = np.abs(own - P).max(axis=2) > threshold
    taken = differs & (footage.spread <= steady_spread)
    return np.where(taken[..., None], P, own).astype(np.float32), taken
