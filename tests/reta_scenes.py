"""Small cv2-drawn frames for reta's tests: people as two-colour ellipses in their boxes."""

from __future__ import annotations

import cv2
import numpy as np

from occbench.trackers.records import Detections

RED = ((40, 40, 200), (60, 60, 120))  # (shirt, body) BGR of a person in red


def ellipse_frame(boxes, colours, size: tuple[int, int]) -> np.ndarray:
    """(H, W, 3) image (``size`` = (W, H)) of people drawn in their xywh ``boxes``: a body
    ellipse and a shirt ellipse over its upper part, ``colours`` = (shirt, body) BGR each."""
    width, height = size
    img = np.full((height, width, 3), 90, np.uint8)
    for (x, y, w, h), (top, body) in zip(boxes, colours):
        c = (int(x + w / 2), int(y + h / 2))
        cv2.ellipse(img, (c, (int(w), int(h)), 0), body, -1)
        cv2.ellipse(img, ((c[0], int(y + h * 0.3)), (int(w * 0.9), int(h * 0.55)), 0), top, -1)
    return img


def detections(boxes) -> Detections:
    """Detections of score 1 at the xywh ``boxes``."""
    b = np.array(boxes, dtype=float).reshape(-1, 4)
    return Detections(b, np.ones(len(b)))
