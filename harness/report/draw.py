"""Draw each tracker's output its own way, and put panels side by side.

* boxes (baseline and any tracker without drawing data): a rectangle per track in the id's
  colour, the id above it; OCCLUDED tracks dashed.
* ellipses (Reta et al. 2015, Figs. 3-5; ``Track.extra['ellipse'] = (xc, yc, phi, rx, ry)``):
  solid ellipse for a node matched by a detection, dashed for hypotheses (HYPOTHESIS and
  OCCLUDED tracks, with the hypothesis kind v/o/s after the id), light grey for tentative
  nodes.
* parts (PBM, Fig. 7; ``Track.extra['parts']`` (5, 4) xywh part rectangles: head, left/right
  torso-arm, left/right leg): the five rectangles in the id's colour, frozen (occluded) parts
  dashed, when ``occbench.report.parts.draw_parts`` (the paper's drawing) fails.

All images are (H, W, 3) uint8 BGR; boxes are xywh with a 0-based top-left (pixels).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import cv2
import numpy as np

from occbench.config.meta import STYLES  # a tracker's style is in its config's meta: block
from occbench.report.graph import id_colour
from occbench.report.parts import draw_parts as pbm_draw_parts
from occbench.report.primitives import (
    GREY,
    WHITE,
    _label,
    _pt,
    dashed_polyline,
    dashed_rectangle,
    legend_block,
    title_band,
)
from occbench.trackers.records import Track, TrackState

log = logging.getLogger(__name__)

__all__ = ["STYLES", "draw_tracks", "grid", "id_colour", "infer_style", "legend"]


def _colour(t: Track):
    return GREY if t.state == TrackState.TENTATIVE else id_colour(t.id)


def _text(t: Track) -> str:
    """A track's label: its id, "-id" while tentative."""
    return str(t.id) if t.state != TrackState.TENTATIVE else f"-{t.id}"


def draw_boxes(img: np.ndarray, tracks: Sequence[Track], thickness: int = 2,
               taken: list | None = None) -> None:
    for t in tracks:
        c = _colour(t)
        if t.state in (TrackState.OCCLUDED, TrackState.HYPOTHESIS):
            dashed_rectangle(img, t.box, c, thickness)
        else:
            x, y, w, h = t.box
            cv2.rectangle(img, _pt(x, y), _pt(x + w, y + h), c, thickness, cv2.LINE_AA)
        _label(img, _text(t), _pt(t.box[0], t.box[1] - 3), c, taken=taken)


def draw_ellipses(img: np.ndarray, tracks: Sequence[Track], thickness: int = 2,
                  taken: list | None = None) -> None:
    for t in tracks:
        e = t.extra.get("ellipse")
        if e is None:
            draw_boxes(img, [t], thickness, taken)
            continue
        xc, yc, phi, rx, ry = (float(v) for v in e)
        c = _colour(t)
        if t.state in (TrackState.HYPOTHESIS, TrackState.OCCLUDED):
            poly = cv2.ellipse2Poly(_pt(xc, yc), (max(int(rx), 1), max(int(ry), 1)),
                                    round(np.degrees(phi)), 0, 360, 15)
            dashed_polyline(img, poly, c, thickness)
        else:
            cv2.ellipse(img, ((xc, yc), (2 * rx, 2 * ry), float(np.degrees(phi))), c, thickness,
                        cv2.LINE_AA)
        text = _text(t)
        kind = t.extra.get("hypothesis")
        if kind:
            text += {"velocity": "v", "occluder": "o", "still": "s"}.get(str(kind), "")
        _label(img, text, _pt(xc - rx, yc - ry - 4), c, taken=taken)


def draw_parts(img: np.ndarray, tracks: Sequence[Track], thickness: int = 1,
               taken: list | None = None) -> None:
    try:  # PBM's own drawing (occbench.report.parts)
        out = pbm_draw_parts(img, tracks, taken=taken)
        if isinstance(out, np.ndarray) and out.shape == img.shape:
            img[...] = out
        return
    except Exception:  # fall back to ours rather than lose the frame
        log.exception("occbench.report.parts.draw_parts failed: drawing parts here")
    for t in tracks:
        parts = t.extra.get("parts")
        if parts is None:
            draw_boxes(img, [t], 2, taken)
            continue
        c = _colour(t)
        hidden = np.asarray(t.extra.get("occluded_parts", np.zeros(len(parts), bool)), bool)
        dashed = t.state == TrackState.OCCLUDED
        for box, off in zip(np.asarray(parts, dtype=np.float64).reshape(-1, 4), hidden):
            if dashed or off:
                dashed_rectangle(img, box, c, thickness, dash=4.0)
            else:
                x, y, w, h = box
                cv2.rectangle(img, _pt(x, y), _pt(x + w, y + h), c, thickness, cv2.LINE_AA)
        _label(img, _text(t), _pt(t.box[0], t.box[1] - 3), c, taken=taken)


def infer_style(tracks: Sequence[Track]) -> str:
    """The drawing style from the tracks' ``extra`` data."""
    for t in tracks:
        if "ellipse" in t.extra:
            return "ellipses"
        if "parts" in t.extra:
            return "parts"
    return "boxes"


def draw_tracks(frame: np.ndarray, tracks: Sequence[Track], style: str = "auto",
                gt: tuple[np.ndarray, np.ndarray] | None = None, title: str | None = None
                ) -> np.ndarray:
    """A copy of ``frame`` with ``tracks`` drawn in ``style`` (see the module docstring).

    Args:
        frame: (H, W, 3) uint8 BGR.
        tracks: one frame's tracker output (every state: tentative and hypotheses too).
        style: auto, boxes, ellipses or parts.
        gt: optional ((N, 4) xywh boxes, (N,) ids) ground truth, drawn thin white underneath.
        title: the panel's title (the tracker's name), in a band of ``TITLE_BAND`` pixels
            above the picture (the returned image is that much taller), never over it.

    Labels are placed greedily so that they do not cover each other (``_label``).
    """
    if style not in STYLES:
        raise ValueError(f"style must be one of {STYLES}, got {style!r}")
    img = np.ascontiguousarray(frame).copy()
    taken: list = []
    style = infer_style(tracks) if style == "auto" else style
    {"boxes": draw_boxes, "ellipses": draw_ellipses, "parts": draw_parts}[style](
        img, tracks, taken=taken)
    if gt is not None:  # boxes under the tracks' marks, labels placed after theirs
        for box, gid in zip(*gt):
            x, y, w, h = box
            cv2.rectangle(img, _pt(x, y), _pt(x + w, y + h), WHITE, 1, cv2.LINE_AA)
            _label(img, f"gt{int(gid)}", _pt(x, y + h + 11), WHITE, 0.35, taken)
    return title_band(img, title) if title else img


def legend(styles: Sequence[str], gt: bool, graph: bool = False) -> list[tuple]:
    """The legend of panels drawn in ``styles`` (``legend_block``'s items): what a colour,
    a dashed line, a grey mark and a label suffix mean."""
    c = id_colour(1)
    items: list[tuple] = [("ground truth, gtN", WHITE, "thin")] if gt else []
    items += [("track: one colour per id", c, "box"),
              ("dashed: hypothesis / occluded (not seen)", c, "dashed"),
              ("grey, -id: tentative (not reported yet)", GREY, "box")]
    if "ellipses" in styles or graph:
        items.append(("ellipse: Reta node; id+v/o/s: velocity/occluder/still hypothesis", c,
                      "ellipse"))
    if graph:
        items.append(("thin line: edge from the previous frame's node", c, "text"))
    if "parts" in styles:
        items.append(("PBM: 5 part boxes, dashed part frozen (occluded); id?: reported unseen",
                      c, "box"))
    return items


def with_legend(image: np.ndarray, items: list[tuple]) -> np.ndarray:
    """``image`` with ``legend_block(items)`` below it."""
    return np.vstack([image, legend_block(items, image.shape[1])])


def grid(panels: Sequence[np.ndarray], columns: int | None = None,
         background: int = 32) -> np.ndarray:
    """Panels of one size tiled row by row (``columns`` per row; default: all in one row)."""
    if not panels:
        raise ValueError("grid: no panels")
    h, w = panels[0].shape[:2]
    columns = columns or len(panels)
    rows = -(-len(panels) // columns)
    out = np.full((rows * h, columns * w, 3), background, np.uint8)
    for k, p in enumerate(panels):
        if p.shape[:2] != (h, w):
            p = cv2.resize(p, (w, h), interpolation=cv2.INTER_AREA)
        r, c = divmod(k, columns)
        out[r * h:(r + 1) * h, c * w:(c + 1) * w] = p
    return out
