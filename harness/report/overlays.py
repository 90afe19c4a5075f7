"""Detection overlays of ``occbench detect`` (``overlays.frames``): one frame's front-end
output drawn over the frame.

All images are (H, W, 3) uint8 BGR; boxes are xywh with a 0-based top-left (pixels).
"""

from __future__ import annotations

import cv2
import numpy as np


def draw_overlay(frame: np.ndarray, fg: np.ndarray | None, dets, gt: np.ndarray | None,
                 blob_boxes: np.ndarray | None) -> np.ndarray:
    """A BGR picture of one frame's front-end output."""
    img = frame.copy()
    if fg is not None:
        tint = img.copy()
        tint[np.asarray(fg) != 0] = (255, 0, 255)
        img = cv2.addWeighted(img, 0.6, tint, 0.4, 0)

    def rect(b, colour, t=1):
        x, y, w, h = (round(v) for v in b)
        cv2.rectangle(img, (x, y), (x + w - 1, y + h - 1), colour, t)

    for b in [] if blob_boxes is None else blob_boxes:
        rect(b, (255, 128, 0))
    for b in [] if gt is None else gt:
        rect(b, (255, 255, 255))
    for b, s in zip(dets.boxes, dets.scores):
        rect(b, (0, 255, 0), 2)
        cv2.putText(img, f"{s:.2f}", (int(b[0]), int(b[1]) - 2), cv2.FONT_HERSHEY_PLAIN, 0.8,
                    (0, 255, 0), 1)
    if dets.heads is not None:
        for h in dets.heads[np.isfinite(dets.heads).all(axis=1)]:
            x, y, w, hh = h
            cv2.ellipse(img, (int(x + w / 2), int(y + hh / 2)), (int(w / 2), int(hh / 2)), 0, 0,
                        360, (0, 255, 255), 1)
    return img
