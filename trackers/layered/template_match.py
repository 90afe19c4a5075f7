"""PBM 4.1's head-template match in multiple-response pruning, as the paper does it
(``ExactMatch``: every position of the window, ``search.match_head_template``) and as
``adaptations.pyramid_template`` does it (``PyramidMatch``, ours: coarse to fine, for speed;
not exact), or ``adaptations.large_head_pyramid`` (``PyramidMatch`` for templates wider
than a number of pixels only, exact below it). Each returns the best top-left corner (2,)
float64 (x, y) and its normalised correlation (TM_CCOEFF_NORMED), -1 when the window cannot
hold the template."""

from __future__ import annotations

import cv2
import numpy as np

from occbench.trackers.layered.search import grey_region, match_head_template, search_window


class ExactMatch:
    """PBM 4.1 as written: "an image template of the target's head is exhaustively matched
    in a local neighborhood" (``match_head_template``)."""

    def __call__(self, image: np.ndarray, template: np.ndarray, centre, radius: float
                 ) -> tuple[np.ndarray, float]:
        return match_head_template(image, template, centre, radius)


class PyramidMatch:
    """``pyramid_template``: the window and the template at half resolution
    (``cv2.pyrDown``) matched first, then the template at full resolution at the positions
    within ``REFINE`` pixels of the coarse best (doubled); the correlation returned is that
    full-resolution one. A window of fewer than ``MIN_POSITIONS`` positions, or a template
    under ``MIN_SIDE`` pixels a side, is matched exactly (``match_head_template``). The
    chosen corner may differ from the exact match where the correlation has several peaks.

    Args:
        min_width: a template at most this many pixels wide is matched exactly too
            (``adaptations.large_head_pyramid``; 0: every template above ``MIN_SIDE``).
        peaks: the coarse level's ``peaks`` best positions are refined, each at least
            ``SEPARATION`` coarse pixels (a square) from the ones before it, within
            ``REFINE_PEAKS`` pixels when more than one; the best full-resolution score wins
            (the first peak on ties). ``adaptations.large_head_peaks``; 1: the coarse best
            alone.
    """

    REFINE = 2
    REFINE_PEAKS = 3
    SEPARATION = 2
    MIN_POSITIONS = 400
    MIN_SIDE = 8

    def __init__(self, min_width: int = 0, peaks: int = 1) -> None:
        self.min_width = int(min_width)
        self.peaks = int(peaks)

    def __call__(self, image: np.ndarray, template: np.ndarray, centre, radius: float
                 ) -> tuple[np.ndarray, float]:
        grey = grey_region(template, 0, template.shape[0], 0, template.shape[1])
        th, tw = grey.shape
        window = search_window(image.shape, grey.shape, centre, radius)
        if window is None:
            return np.asarray(centre, dtype=np.float64), -1.0
        r0, r1, c0, c1 = window
        ny, nx = r1 - r0 - th + 1, c1 - c0 - tw + 1  # positions of the exact match
        if ny * nx < self.MIN_POSITIONS or min(th, tw) < self.MIN_SIDE or tw <= self.min_width:
            return match_head_template(image, grey, centre, radius)
        region = grey_region(image, r0, r1, c0, c1)
        coarse = cv2.matchTemplate(cv2.pyrDown(region), cv2.pyrDown(grey), cv2.TM_CCOEFF_NORMED)
        R = self.REFINE if self.peaks == 1 else self.REFINE_PEAKS
        best, corner = -np.inf, None
        for _ in range(self.peaks):
            _, top, _, (bx, by) = cv2.minMaxLoc(coarse)
            if top == -np.inf:  # fewer coarse positions than peaks
                break
            x0, y0 = min(max(2 * bx - R, 0), nx - 1), min(max(2 * by - R, 0), ny - 1)
            x1, y1 = min(2 * bx + R, nx - 1), min(2 * by + R, ny - 1)
            fine = cv2.matchTemplate(region[y0:y1 + th, x0:x1 + tw], grey, cv2.TM_CCOEFF_NORMED)
            _, score, _, (fx, fy) = cv2.minMaxLoc(fine)
            if corner is None or score > best:
                best, corner = score, (c0 + x0 + fx, r0 + y0 + fy)
            S = self.SEPARATION
            coarse[max(by - S, 0):by + S + 1, max(bx - S, 0):bx + S + 1] = -np.inf
        return np.array(corner, dtype=np.float64), float(best)


def template_matcher(pyramid: bool, large_head: int = 0, peaks: int = 1
                     ) -> ExactMatch | PyramidMatch:
    """The strategy of ``adaptations.pyramid_template`` (every template) or, when that is
    off, of ``adaptations.large_head_pyramid`` (templates wider than ``large_head`` pixels,
    ``peaks`` coarse peaks refined: ``adaptations.large_head_peaks``; 0: off)."""
    if pyramid:
        return PyramidMatch()
    return PyramidMatch(min_width=large_head, peaks=peaks) if large_head > 0 else ExactMatch()
