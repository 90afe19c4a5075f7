"""Other footage of a camera, read into its empty background (``occbench.trackers.frontend.footage``).

``camera_background(paths)`` is what ``detector.detector.fallback.background.footage`` builds
(``conf/detector/silhouette.yaml``): each path is one clip of the same camera, either a
folder of frames (a MOTChallenge sequence folder: its ``img1/``; or a folder of image files,
taken in name order) or a video file. ``frames_per_clip`` frames sampled evenly over each clip
give its temporal median; the clips' medians are pooled (``footage.pool_clips``). Images only:
no label file is read. An empty list gives None (no footage: the clip's own background).

A path that does not exist, a folder without frames, a frame or video that does not decode,
or clips of different sizes stop the run with one line naming the path. The front-end cache
key holds the bytes of every file of every named folder (``occbench.sources.cache.keys``).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from occbench.datasets.images import IMAGE_EXTENSIONS, FrameError, read_image
from occbench.datasets.video import VideoSequence
from occbench.trackers.frontend.footage import CameraBackground, clip_median, pool_clips

log = logging.getLogger(__name__)


class FootageError(ValueError):
    """Background footage that cannot be read; the message names the path."""


def clip_frames(path: str | Path, count: int) -> list[np.ndarray]:
    """``count`` frames sampled evenly over the clip at ``path`` ((H, W, 3) uint8 each)."""
    p = Path(path).expanduser()
    if not p.exists():
        raise FootageError(f"background footage {p}: no such file or folder")
    if p.is_file():
        return _video_frames(p, count)
    folder = p / "img1" if (p / "img1").is_dir() else p
    files = sorted(f for f in folder.iterdir() if f.suffix.lower() in IMAGE_EXTENSIONS)
    if not files:
        raise FootageError(f"background footage {p}: no image files in {folder}")
    picks = np.unique(np.linspace(0, len(files) - 1, min(count, len(files))).round().astype(int))
    try:
        return [read_image(files[i]) for i in picks]
    except FrameError as err:
        raise FootageError(f"background footage {p}: {err}") from None


def _video_frames(path: Path, count: int) -> list[np.ndarray]:
    try:
        video = VideoSequence(path)
        n = video.info.length
        picks = np.unique(np.linspace(1, n, min(count, n)).round().astype(int))
        frames = [video.frame(int(k)) for k in picks]
        video.close()
    except (FrameError, OSError, ValueError) as err:
        raise FootageError(f"background footage {path}: {err}") from None
    return frames


def camera_background(paths: list[str] | None, frames_per_clip: int = 50) -> CameraBackground | None:
    """The empty background of the camera that filmed ``paths`` (one clip each), or None
    for no paths.

    Raises:
        FootageError: a path is missing or unreadable, or the clips differ in size.
    """
    if not paths:
        return None
    if frames_per_clip < 1:
        raise ValueError(f"frames_per_clip must be >= 1, got {frames_per_clip}")
    medians, sizes = [], {}
    for path in paths:
        frames = clip_frames(path, frames_per_clip)
        shapes = {f.shape for f in frames}
        if len(shapes) > 1:
            raise FootageError(f"background footage {path}: frames of different sizes")
        sizes[str(path)] = frames[0].shape
        medians.append(clip_median(frames))
    if len(set(sizes.values())) > 1:
        raise FootageError("background footage: clips of different sizes: " + ", ".join(
            f"{p} {s[1]}x{s[0]}" for p, s in sizes.items()))
    names = [Path(p).name for p in paths]
    label = f"{len(paths)} clip(s): {', '.join(names[:3])}{', ...' if len(names) > 3 else ''}"
    log.info("background footage: %s, %d frames each at most", label, frames_per_clip)
    return pool_clips(medians, label)
