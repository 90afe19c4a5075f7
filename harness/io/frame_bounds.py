"""What a frame of known size refuses in a box file: a box many frames wide or tall (a
misprint: beyond every overlap the scoring could find), and a gt box to score lying wholly
outside the frame (nobody there can be seen: it would only count as a miss)."""

from __future__ import annotations

import numpy as np

MAX_SIZE_RATIO = 100  # a box wider or taller than this many frames is refused


def beyond_frame(boxes: np.ndarray, scored_gt: np.ndarray | None,
                 image: tuple[int, int]) -> np.ndarray:
    """(R,) bool rows refused by the frame ``image`` (width, height): ``boxes`` (R, 4) xywh
    with a 0-based top-left; ``scored_gt`` (R,) bool rows of gt to score (None: not gt)."""
    width, height = image
    huge = (boxes[:, 2] > MAX_SIZE_RATIO * width) | (boxes[:, 3] > MAX_SIZE_RATIO * height)
    if scored_gt is None:
        return huge
    outside = ((boxes[:, 0] + boxes[:, 2] <= 0) | (boxes[:, 1] + boxes[:, 3] <= 0)
               | (boxes[:, 0] >= width) | (boxes[:, 1] >= height))
    return huge | (outside & scored_gt)


def why_beyond(box: np.ndarray, image: tuple[int, int]) -> str:
    """The reason ``beyond_frame`` refuses one (4,) xywh box."""
    width, height = image
    if box[2] > MAX_SIZE_RATIO * width or box[3] > MAX_SIZE_RATIO * height:
        return (f"box {box[2]:g}x{box[3]:g} is more than {MAX_SIZE_RATIO} times the "
                f"{width}x{height} frame")
    return (f"gt box to score lies wholly outside the {width}x{height} frame (nobody there "
            f"can be seen: it would count as a miss; conf 0 ignores a row)")
