"""Reta 3.1's shape filter: candidate boxes kept, dropped or split by an active-basis
template's score (``active_basis``), and people proposed on foreground no box explains."""

from __future__ import annotations

from collections.abc import Callable

import cv2
import numpy as np

from occbench.trackers.common.checks import require
from occbench.trackers.frontend.active_basis import ActiveBasis, crop_patch


class ShapeVerifier:
    """Candidate boxes scored by an active-basis template (Reta 3.1's shape filter).

    A candidate is kept when its log-likelihood ratio (eq. 22) is at least ``threshold``.
    A candidate wider than ``split_width`` times a person of its height (the template box's
    aspect) is also tried as two people of that width at its left and right edges: when
    both score at least ``threshold`` and together more than the wide box, the two replace
    it (a merged group split by shape evidence).

    ``propose`` searches the foreground no kept box explains (Reta 3.1: the search repeats
    on the vacant foreground): each of its components large enough gets the box of a person
    whose head is at the component's top, of the size the scene's calibration expects
    there, kept when its score is at least ``propose_above`` (a person whose blob merged
    with another's, e.g. a far person above a near one).

    Args:
        template: the learnt ``ActiveBasis`` (built by the harness from a file).
        threshold: smallest score of a candidate kept (None: keep every candidate).
        split_width: width / (template aspect x height) above which a split is tried
            (None: never).
        propose_above: smallest score of a proposed box (None: no proposals).
        propose_fill: smallest foreground area of a component searched, as a fraction of
            the expected person box's area at its row.
    """

    def __init__(self, template: ActiveBasis, threshold: float | None = 0.0,
                 split_width: float | None = None, propose_above: float | None = None,
                 propose_fill: float = 0.15) -> None:
        if not isinstance(template, ActiveBasis):
            raise TypeError(f"template must be an ActiveBasis, got {type(template).__name__}")
        require("verifier.split_width", split_width is None or split_width > 1.0,
                "must be > 1 or None", split_width)
        require("verifier.propose_fill", 0.0 < propose_fill <= 1.0, "must lie in (0, 1]",
                propose_fill)
        self.template = template
        self.threshold = -np.inf if threshold is None else float(threshold)
        self.split_width = np.inf if split_width is None else float(split_width)
        self.propose_above = None if propose_above is None else float(propose_above)
        self.propose_fill = float(propose_fill)

    def scores(self, grey: np.ndarray, boxes: np.ndarray) -> np.ndarray:
        """(N,) scores of (N, 4) xywh boxes in a (rows, cols) grey or BGR image."""
        t = self.template
        boxes = np.asarray(boxes).reshape(-1, 4)
        if not len(boxes):
            return np.zeros(0)
        return t.scores(np.stack([crop_patch(grey, b, t.size, t.pad) for b in boxes])).astype(np.float64)

    def __call__(self, frame: np.ndarray, boxes: np.ndarray, scores: np.ndarray,
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Kept (and split) boxes (K, 4) xywh and their detector scores (K,) (a split box's
        halves keep the wide box's) of one (H, W, 3) BGR or (H, W) grey frame."""
        boxes = np.asarray(boxes, np.float64).reshape(-1, 4)
        if not len(boxes) or (self.threshold == -np.inf and self.split_width == np.inf):
            return boxes, np.asarray(scores, np.float64).reshape(-1)  # nothing to decide
        grey = frame  # grey or BGR: crop_patch converts the patches only
        s = self.scores(grey, boxes)
        H, W = self.template.size
        aspect = W / H
        out, out_s = [], []
        for b, sc, ls in zip(boxes, scores, s):
            x, y, w, h = b
            wp = aspect * h
            if w > self.split_width * wp:
                halves = np.array([[x, y, wp, h], [x + w - wp, y, wp, h]])
                hs = self.scores(grey, halves)
                if (hs >= self.threshold).all() and hs.sum() > ls:
                    out.extend(halves), out_s.extend([sc, sc])
                    continue
            if ls >= self.threshold:
                out.append(b), out_s.append(sc)
        if not out:
            return np.zeros((0, 4)), np.zeros(0)
        return np.asarray(out, np.float64), np.asarray(out_s, np.float64)

    def vacant(self, fg: np.ndarray, boxes: np.ndarray,
               area: tuple[int, int, int, int] | None = None) -> np.ndarray:
        """(H, W) bool: foreground of the (H, W) mask ``fg`` outside the xywh ``boxes`` (the
        people found), opened by 3x3; only inside ``area`` (rows r0:r1, cols c0:c1) if given.
        Empty without ``propose_above`` (nothing is proposed)."""
        if self.propose_above is None:
            return np.zeros(fg.shape, bool)
        out = np.zeros(fg.shape, np.uint8)
        r0, r1, c0, c1 = area if area is not None else (0, fg.shape[0], 0, fg.shape[1])
        out[r0:r1, c0:c1] = fg[r0:r1, c0:c1]
        for x, y, w, h in np.asarray(boxes, np.float64).reshape(-1, 4):
            out[max(int(y), 0) : max(int(np.ceil(y + h)), 0), max(int(x), 0) : max(int(np.ceil(x + w)), 0)] = 0
        return cv2.morphologyEx(out, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8)) > 0

    def propose(self, frame: np.ndarray, vacant: np.ndarray,
                person_size: Callable[[float], tuple[float, float] | None],
                ) -> tuple[np.ndarray, np.ndarray]:
        """Boxes (K, 4) xywh and shape scores (K,) of people on the (H, W) bool ``vacant``
        foreground (none without ``propose_above``). ``person_size(top_row)`` gives the
        (width, height) of a person's box whose top is at that row (None: nobody fits),
        growing down the picture (a camera above the floor)."""
        if self.propose_above is None or not vacant.any():
            return np.zeros((0, 4)), np.zeros(0)
        # components on every second row and column (4x fewer pixels; sizes scaled back),
        # inside the bounding box of what is left
        half = vacant[::2, ::2]
        rows, cols = np.flatnonzero(half.any(axis=1)), np.flatnonzero(half.any(axis=0))
        if not len(rows):
            return np.zeros((0, 4)), np.zeros(0)
        r0, c0 = int(rows[0]), int(cols[0])
        _, lab, stats, _ = cv2.connectedComponentsWithStats(
            np.ascontiguousarray(half[r0 : rows[-1] + 1, c0 : cols[-1] + 1], dtype=np.uint8), connectivity=8)
        smallest = person_size(0.0)  # people are smallest at the top of the picture
        min_area = self.propose_fill * smallest[0] * smallest[1] / 4 if smallest is not None else 0.0
        cands = []
        for i in np.flatnonzero(stats[:, cv2.CC_STAT_AREA] >= min_area):
            if i == 0:
                continue
            x, top, w, _h, area = (int(v) for v in stats[i])  # in the crop of ``half``
            size = person_size(2.0 * (top + r0))
            if size is None or 4 * area < self.propose_fill * size[0] * size[1]:
                continue
            head = lab[top : top + max(int(size[1] * 0.15 / 2), 1), x : x + w] == i  # top 1/7: the head
            cx = 2.0 * (c0 + x + float(np.nonzero(head)[1].mean())) + 0.5
            cands.append([cx - size[0] / 2, 2.0 * (top + r0), size[0], size[1]])
        if not cands:
            return np.zeros((0, 4)), np.zeros(0)
        boxes = np.asarray(cands, np.float64)
        s = self.scores(frame, boxes)
        keep = s >= self.propose_above
        return boxes[keep], s[keep]
