"""Draw PBM tracks the way the paper shows them (PBM Fig. 7): five part rectangles per target.

Each target's head, left/right torso-arm and left/right leg rectangles
(``Track.extra['parts']``, (5, 4) xywh) are drawn in the id's colour over a light tint of
the same colour; a part whose model is frozen (``Track.extra['occluded_parts']``, PBM 4.2)
is drawn dashed without tint; an OCCLUDED target (reported while unfound) is all dashed;
a TENTATIVE target is grey. The id is written above the head; with ``show_gate`` the KF1
gate (``Track.extra['gate']``) is drawn as a thin dashed rectangle (PBM Fig. 5).

All images are (H, W, 3) uint8 BGR; boxes are xywh with a 0-based top-left (pixels).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

from occbench.report.graph import id_colour
from occbench.report.primitives import GREY, _label, _pt, dashed_rectangle
from occbench.trackers.records import Track, TrackState


def _tint(img: np.ndarray, box: np.ndarray, colour, alpha: float) -> None:
    h, w = img.shape[:2]
    x, y, bw, bh = box
    c0, c1 = max(round(x), 0), min(round(x + bw), w)
    r0, r1 = max(round(y), 0), min(round(y + bh), h)
    if c1 <= c0 or r1 <= r0:
        return
    roi = img[r0:r1, c0:c1].astype(np.float32)
    img[r0:r1, c0:c1] = (roi * (1 - alpha) + np.float32(colour) * alpha).astype(np.uint8)


def draw_parts(img: np.ndarray, tracks: Sequence[Track], thickness: int = 1,
               tint: float = 0.18, show_gate: bool = False,
               taken: list | None = None) -> np.ndarray:
    """Draw the five parts of every track onto ``img`` in place; returns ``img``.

    Tracks without ``extra['parts']`` are drawn as a plain rectangle. ``taken``: the label
    rectangles already on ``img`` (``primitives._label`` moves a label off them).
    """
    for t in tracks:
        colour = GREY if t.state == TrackState.TENTATIVE else id_colour(t.id)
        parts = t.extra.get("parts")
        if parts is None:
            parts = np.asarray(t.box, dtype=np.float64).reshape(1, 4)
            frozen = np.zeros(1, dtype=bool)
        else:
            parts = np.asarray(parts, dtype=np.float64).reshape(-1, 4)
            frozen = np.asarray(t.extra.get("occluded_parts", np.zeros(len(parts), bool)),
                                dtype=bool).reshape(-1)
        hidden = t.state in (TrackState.OCCLUDED, TrackState.HYPOTHESIS)
        for box, off in zip(parts, frozen):
            if hidden or off:
                dashed_rectangle(img, box, colour, thickness, dash=4.0)
            else:
                if tint > 0:
                    _tint(img, box, colour, tint)
                x, y, w, h = box
                cv2.rectangle(img, _pt(x, y), _pt(x + w, y + h), colour, thickness, cv2.LINE_AA)
        if show_gate and t.extra.get("gate") is not None:
            dashed_rectangle(img, np.asarray(t.extra["gate"], dtype=np.float64), colour, 1, dash=8.0)
        text = str(t.id) if t.state != TrackState.TENTATIVE else f"-{t.id}"
        if t.state == TrackState.OCCLUDED:
            text += "?"
        _label(img, text, _pt(t.box[0], t.box[1] - 3), colour, taken=taken)
    return img
