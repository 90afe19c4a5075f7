"""Drawing primitives shared by ``occbench.report.draw``, ``occbench.report.parts`` and the
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


FONT = cv2.FONT_HERSHEY_SIMPLEX
TITLE_BAND = 22  # pixels of the band above a panel holding its title


def _label(img: np.ndarray, text: str, org: tuple[int, int], colour, scale: float = 0.45,
           taken: list[tuple[int, int, int, int]] | None = None) -> None:
    """``text`` at ``org`` (bottom-left), outlined in black. With ``taken`` (the (x0, y0, x1,
    y1) rectangles of the labels already drawn on ``img``), a label that would cover one is
    moved down, then up, then aside (greedy: the first free place of a short list, else
    where asked); its rectangle is added to ``taken``."""
    (w, h), base = cv2.getTextSize(text, FONT, scale, 1)
    x, y = max(org[0], 0), max(org[1], h + 1)
    if taken is not None:
        step = h + base + 2
        for dx, dy in ((0, 0), (0, step), (0, 2 * step), (0, -step), (w + 4, 0),
                       (-w - 4, 0), (0, 3 * step)):
            cx, cy = max(x + dx, 0), max(y + dy, h + 1)
            box = (cx - 1, cy - h - 1, cx + w + 1, cy + base)
            if not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3]
                       for b in taken):
                x, y = cx, cy
                break
        taken.append((x - 1, y - h - 1, x + w + 1, y + base))
    cv2.putText(img, text, (x, y), FONT, scale, (0, 0, 0), 3, cv2.LINE_AA)
    cv2.putText(img, text, (x, y), FONT, scale, colour, 1, cv2.LINE_AA)


def title_band(img: np.ndarray, title: str) -> np.ndarray:
    """``img`` with a black band of ``TITLE_BAND`` pixels above it holding ``title``, so that
    the title never covers the picture (CAVIAR frames carry their own timestamp at the top)."""
    band = np.zeros((TITLE_BAND, img.shape[1], 3), np.uint8)
    cv2.putText(band, title, (5, 15), FONT, 0.5, WHITE, 1, cv2.LINE_AA)
    return np.vstack([band, img])


def legend_block(items: list[tuple[str, tuple[int, int, int], str]], width: int,
                 background: int = 40) -> np.ndarray:
    """A (22 x rows, width, 3) legend on a dark background: per (text, colour, mark) a
    sample mark then its text, wrapped onto as many rows as ``width`` needs. Marks: "box"
    (solid rectangle), "thin" (one-pixel rectangle), "dashed", "fill" (filled square),
    "ellipse", "text" (the colour's text sample only)."""
    rows: list[list[tuple[int, str, tuple[int, int, int], str]]] = [[]]
    x = 6
    for text, colour, mark in items:
        need = 24 + cv2.getTextSize(text, FONT, 0.4, 1)[0][0] + 14
        if rows[-1] and x + need > width:
            rows.append([])
            x = 6
        rows[-1].append((x, text, colour, mark))
        x += need
    out = np.full((22 * len(rows), width, 3), background, np.uint8)
    for r, row in enumerate(rows):
        y = 22 * r
        for x0, text, colour, mark in row:
            if mark == "fill":
                cv2.rectangle(out, (x0, y + 5), (x0 + 16, y + 17), colour, -1)
            elif mark == "dashed":
                dashed_rectangle(out, np.array([x0, y + 5, 16, 12.0]), colour, 2, dash=3.0)
            elif mark == "ellipse":
                cv2.ellipse(out, (x0 + 8, y + 11), (8, 6), 0, 0, 360, colour, 1, cv2.LINE_AA)
            elif mark != "text":
                cv2.rectangle(out, (x0, y + 5), (x0 + 16, y + 17), colour,
                              1 if mark == "thin" else 2)
            cv2.putText(out, text, (x0 + 22, y + 15), FONT, 0.4, WHITE, 1, cv2.LINE_AA)
    return out


def legend_strip(items: list[tuple[str, tuple[int, int, int]]], width: int) -> np.ndarray:
    """A (26, width, 3) white strip with a coloured square and its text per (text, colour)."""
    strip = np.full((26, width, 3), 255, np.uint8)
    x = 8
    for text, colour in items:
        cv2.rectangle(strip, (x, 8), (x + 14, 20), colour, 2)
        cv2.putText(strip, text, (x + 20, 19), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (0, 0, 0), 1)
        x += 30 + 8 * len(text)
    return strip
