"""Drawing primitives shared by ``harness.report.draw``, ``harness.report.parts`` and the
benchmarks' overlays: points, dashed lines and rectangles (OpenCV has no dashed style),
labels, a legend strip, colours.

All images are (H, W, 3) uint8 BGR; boxes are xywh with a 0-based top-left (pixels).
"""

from __future__ import annotations

import itertools

import cv2
import numpy as np

GREY = (190, 190, 190)
WHITE = (255, 255, 255)


def _pt(x: float, y: float) -> tuple[int, int]:
    return round(x), round(y)


def dashed_polyline(img: np.ndarray, pts: np.ndarray, colour, thickness: int = 1,
                    closed: bool = True) -> None:
    """Every other segment of a densely sampled polyline (OpenCV has no dashed style)."""
    pts = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    if closed:
        pts = np.vstack([pts, pts[:1]])
    for k in range(0, len(pts) - 1, 2):
        cv2.line(img, _pt(*pts[k]), _pt(*pts[k + 1]), colour, thickness, cv2.LINE_AA)


def dashed_rectangle(img: np.ndarray, box: np.ndarray, colour, thickness: int = 1,
                     dash: float = 6.0) -> None:
    x, y, w, h = (float(v) for v in box)
    corners = np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h], [x, y]])
    pts = []
    for a, b in itertools.pairwise(corners):
        n = max(int(np.hypot(*(b - a)) / dash), 1)
        pts.append(a + (b - a) * (np.arange(n)[:, None] / n))
    dashed_polyline(img, np.vstack(pts), colour, thickness)


def _label(img: np.ndarray, text: str, org: tuple[int, int], colour, scale: float = 0.45) -> None:
    org = (max(org[0], 0), max(org[1], 11))
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 3, cv2.LINE_AA)
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv2.LINE_AA)


def legend_strip(items: list[tuple[str, tuple[int, int, int]]], width: int) -> np.ndarray:
    """A (26, width, 3) white strip with a coloured square and its text per (text, colour)."""
    strip = np.full((26, width, 3), 255, np.uint8)
    x = 8
    for text, colour in items:
        cv2.rectangle(strip, (x, 8), (x + 14, 20), colour, 2)
        cv2.putText(strip, text, (x + 20, 19), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (0, 0, 0), 1)
        x += 30 + 8 * len(text)
    return strip
