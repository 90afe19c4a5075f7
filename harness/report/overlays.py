"""Detection overlays of ``occbench detect`` (``overlays.frames``): one frame's front-end
output drawn over the frame, with a legend below it.

All images are (H, W, 3) uint8 BGR; boxes are xywh with a 0-based top-left (pixels).
"""

from __future__ import annotations

import cv2
import numpy as np

from occbench.report.primitives import WHITE, _label, legend_block

FOREGROUND = (255, 0, 255)  # magenta tint
BLOB = (255, 128, 0)  # blue
DETECTION = (0, 255, 0)  # green
HEAD = (0, 255, 255)  # yellow
LEGEND = [("foreground (tint)", FOREGROUND, "fill"), ("blob", BLOB, "thin"),
          ("detection, score", DETECTION, "box"), ("ground truth", WHITE, "thin"),
          ("head", HEAD, "ellipse")]


def draw_overlay(frame: np.ndarray, fg: np.ndarray | None, dets, gt: np.ndarray | None,
                 blob_boxes: np.ndarray | None) -> np.ndarray:
    """A BGR picture of one frame's front-end output: the foreground tinted, blobs, ground
    truth, detections with their scores (outlined text, moved off each other) and heads,
    then ``LEGEND`` in a band below the frame (the picture is that much taller)."""
    img = frame.copy()
    if fg is not None:
        tint = img.copy()
        tint[np.asarray(fg) != 0] = FOREGROUND
        img = cv2.addWeighted(img, 0.6, tint, 0.4, 0)

    def rect(b, colour, t=1):
        x, y, w, h = (round(v) for v in b)
        cv2.rectangle(img, (x, y), (x + w - 1, y + h - 1), colour, t)

    for b in [] if blob_boxes is None else blob_boxes:
        rect(b, BLOB)
    for b in [] if gt is None else gt:
        rect(b, WHITE)
    taken: list = []
    for b in dets.boxes:
        rect(b, DETECTION, 2)
    for b, s in zip(dets.boxes, dets.scores):
        _label(img, f"{s:.2f}", (int(b[0]), int(b[1]) - 3), DETECTION, 0.45, taken)
    if dets.heads is not None:
        for h in dets.heads[np.isfinite(dets.heads).all(axis=1)]:
            x, y, w, hh = h
            cv2.ellipse(img, (int(x + w / 2), int(y + hh / 2)), (int(w / 2), int(hh / 2)), 0, 0,
                        360, HEAD, 1)
    return np.vstack([img, legend_block(LEGEND, img.shape[1])])
