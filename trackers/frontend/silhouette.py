"""Silhouette-template person detector (Reta 3.1, adapted).

Reta et al. fit an active-basis silhouette template at several scales over the moving
foreground: the best fit marks its silhouette occupied and the search repeats on the
vacant foreground. We keep the greedy occupancy loop and replace the active basis (Gabor
sketch learnt from their training images, which we do not have) with a mean person mask
``T`` (values in [0, 1], learnt by ``python -m harness.fit silhouette`` from exact person
masks, or the shipped default).

Fit of the template (scaled to one of ``n_scales`` heights) centred at a pixel, over the
vacant foreground V and the occupied foreground O (both 0/1 images), with the template's
visible mass M = sum T - sum T O (the part not hidden by people already found):

    E     = sum T V - alpha (M - sum T V) - beta sum (1 - T) V     (explained foreground)
    score = E / M

E rewards foreground under the template, pays ``alpha`` for template pixels without
foreground and ``beta`` for foreground where the template expects background; the greedy
step takes the placement and scale of largest E (the active basis' log-likelihood also
grows with the template's size), among placements with ``score >= threshold`` and
M / sum T >= ``min_visible`` (Reta: people more than 30% visible). Every sum is one
``cv2.filter2D`` per scale over a foreground crop, never a Python loop over pixels.

Scene knowledge, all optional: a ground-plane height prior (expected height linear in the
foot row; fixed from a calibration, ``height_model``, or learnt by the detector), template
pixels beyond the frame border treated as unknown (``frame_border``: people cut by the image
edge), and a box convention (``box_scale``: reported box = fitted template box scaled to the
annotations' tighter or looser boxes). On CAVIAR the height prior matters most: without it the
largest-E rule prefers tall fits spanning a group or a person with its floor reflection.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

import cv2
import numpy as np

log = logging.getLogger(__name__)

TEMPLATE_HEIGHT = 64  # rows of the stored template
HEAD_FRACTION = 1 / 7  # head height / person height (PBM 2.1)


def analytic_template(height: int = TEMPLATE_HEIGHT, width_ratio: float = 0.42) -> np.ndarray:
    """A drawn mean-person mask: head 1/7 of height, torso with arms, two legs, blurred.

    Returns (height, round(width_ratio * height)) float32 in [0, 1].
    """
    w = round(width_ratio * height)
    img = np.zeros((height * 4, w * 4), dtype=np.float32)
    H, W = img.shape
    hh = H / 7
    cx = W / 2
    cv2.ellipse(img, (int(cx), int(hh / 2)), (int(0.33 * hh), int(hh / 2)), 0, 0, 360, 1.0, -1)
    cv2.rectangle(img, (int(cx - 0.12 * H / 2.4), int(hh * 0.9)), (int(cx + 0.12 * H / 2.4), int(hh * 1.3)),
                  1.0, -1)  # neck
    torso = np.array([[cx - 0.4 * W, hh * 1.25], [cx + 0.4 * W, hh * 1.25],
                      [cx + 0.45 * W, hh * 4.0], [cx - 0.45 * W, hh * 4.0]], dtype=np.int32)
    cv2.fillPoly(img, [torso], 1.0)
    for side in (-1, 1):
        leg = np.array([[cx + side * 0.02 * W, hh * 3.6], [cx + side * 0.4 * W, hh * 3.6],
                        [cx + side * 0.36 * W, H], [cx + side * 0.06 * W, H]], dtype=np.int32)
        cv2.fillPoly(img, [leg], 1.0)
    img = cv2.GaussianBlur(img, (0, 0), sigmaX=W * 0.06)
    return np.clip(cv2.resize(img, (w, height), interpolation=cv2.INTER_AREA), 0.0, 1.0)


def fit_template(masks: list[np.ndarray], height: int = TEMPLATE_HEIGHT) -> np.ndarray:
    """Mean of person masks, each cropped to its box and resized to a common size.

    Args:
        masks: list of (h_i, w_i) bool/0-1 masks of single people, each cropped to the
            person's box.
        height: rows of the template; its width is height x the median box aspect ratio.
    Returns:
        (height, width) float32 in [0, 1].
    """
    masks = [np.asarray(m, dtype=np.float32) for m in masks if m.size and m.any()]
    if not masks:
        raise ValueError("fit_template: no non-empty masks")
    aspect = float(np.median([m.shape[1] / m.shape[0] for m in masks]))
    width = max(round(aspect * height), 3)
    acc = np.zeros((height, width), dtype=np.float64)
    for m in masks:
        acc += cv2.resize(m, (width, height), interpolation=cv2.INTER_AREA)
    return np.clip(acc / len(masks), 0.0, 1.0).astype(np.float32)


def load_template(path: str | Path | None = None) -> np.ndarray:
    """Load a template ``.npy``; None loads the shipped ``trackers/frontend/data/silhouette.npy``."""
    if path is None:
        path = resources.files("trackers.frontend") / "data" / "silhouette.npy"
    path = Path(str(path))
    if not path.is_file():
        raise FileNotFoundError(f"silhouette template not found: {path}")
    t = np.load(path, allow_pickle=False).astype(np.float32)
    if t.ndim != 2 or t.min() < 0 or t.max() > 1:
        raise ValueError(f"{path}: a template must be a 2-D array in [0, 1], got {t.shape}")
    return t


class SilhouetteMatcher:
    """Greedy multi-scale silhouette fitting over a foreground mask.

    Args:
        template: path of a template ``.npy`` (None: shipped default).
        min_height: smallest person height searched (see ``height_unit``).
        max_height: largest person height searched (see ``height_unit``).
        n_scales: number of heights, geometrically spaced.
        downscale: work on the foreground reduced by this integer factor (speed).
        alpha: penalty weight for template pixels without foreground.
        beta: penalty weight for foreground where the template expects background.
        threshold: smallest accepted score E / M (at most 1).
        min_visible: smallest fraction of template mass not already occupied.
        max_people: safety bound of fits per region.
        margin: pixels (full resolution) added around each foreground region searched.
        occupy_level: template values above which a fit's pixels are marked occupied (its
            silhouette; lower marks a wider region, so arms and bags are not fitted again).
        height_tolerance: with a height model (``set_height_model``: expected person height
            as a linear function of the foot row, a ground-plane prior), a fit of height h
            whose expected height is e is allowed only when 1/tol <= h / e <= tol.
        max_overlap: a fit whose box lies more than this fraction inside an earlier fit's box
            in the same region, and is shorter than ``part_height`` times it, is a part of
            that person (an arm, a bag, a hollow in the foreground): its pixels are marked
            occupied but it is not reported (1 keeps every fit).
        part_height: see ``max_overlap``.
        height_unit: "pixels" (full resolution) or "frame" (fractions of the frame height,
            so that one config serves every frame size).
        aspect: width / height of the template as matched (None: the template's own); the
            template is resized to it, so boxes follow a tighter or looser box convention.
        height_model: fixed ground-plane height prior [a, b] (expected height = a * foot row
            + b, full-resolution pixels), e.g. from a camera calibration; None: no prior
            until ``set_height_model`` gives one.
        frame_border: template pixels outside the frame are unknown rather than background:
            they are left out of the visible mass M (a person cut by the image border is
            scored on its visible part) and boxes are clipped to the frame.
        box_scale: [width, height] factors mapping a fitted template box to the reported
            box (the box convention of the annotations): the width about the box centre,
            the height from the top (the head stays put).
        box: the reported box: "template" (the fitted template's box) or "foreground" (the
            bounding box of the foreground pixels the fit explains: its silhouette's pixels
            that are foreground, as an annotator boxes the visible person) or "region" (the
            bounding box of the region's foreground inside the template box: arms and feet
            outside the mean silhouette included).
        head_contrast: head evidence a fit needs: in the template's head rows (the top 1/7),
            the foreground fill of the head minus the fill beside it (-1: no test). A
            half-body (no head), a box straddling two people (a gap where the head should
            be) and a floor reflection or shadow smear (as wide at the top as below) lack it.
        symmetric: match the mean of the template and its mirror image (people face either
            way; a template learnt from few walkers leans to their side).
        group_gap: foreground components less than this many rows (full resolution) apart
            vertically are searched as one region (a person cut in two by the background).
    """

    def __init__(
        self,
        template: str | None = None,
        min_height: float = 30.0,
        max_height: float = 120.0,
        n_scales: int = 12,
        downscale: int = 2,
        alpha: float = 1.0,
        beta: float = 0.3,
        threshold: float = 0.3,
        min_visible: float = 0.3,
        max_people: int = 20,
        margin: int = 8,
        occupy_level: float = 0.2,
        height_tolerance: float = 1.4,
        max_overlap: float = 0.5,
        part_height: float = 0.8,
        height_unit: str = "pixels",
        aspect: float | None = None,
        height_model: Sequence[float] | None = None,
        frame_border: bool = False,
        box_scale: Sequence[float] = (1.0, 1.0),
        box: str = "template",
        group_gap: float = 0.0,
        head_contrast: float = -1.0,
        symmetric: bool = False,
    ) -> None:
        if not 0 < min_height <= max_height:
            raise ValueError(f"need 0 < min_height <= max_height, got {min_height}, {max_height}")
        if height_unit not in ("pixels", "frame"):
            raise ValueError(f"height_unit must be 'pixels' or 'frame', got {height_unit!r}")
        if height_unit == "frame" and max_height > 1:
            raise ValueError(f"height_unit 'frame' takes fractions <= 1, got max_height {max_height}")
        self.height_unit = height_unit
        if n_scales < 1 or downscale < 1:
            raise ValueError(f"n_scales and downscale must be >= 1, got {n_scales}, {downscale}")
        if not 0.0 < min_visible <= 1.0:
            raise ValueError(f"min_visible must be in (0, 1], got {min_visible}")
        self.template = load_template(template)
        if symmetric:  # people face either way: the mean of the template and its mirror
            self.template = np.ascontiguousarray((self.template + self.template[:, ::-1]) / 2)
        self.min_height, self.max_height = float(min_height), float(max_height)
        self.n_scales, self.downscale = int(n_scales), int(downscale)
        self.alpha, self.beta, self.threshold = float(alpha), float(beta), float(threshold)
        self.min_visible, self.max_people, self.margin = float(min_visible), int(max_people), int(margin)
        if not 0.0 <= occupy_level < 1.0:
            raise ValueError(f"occupy_level must be in [0, 1), got {occupy_level}")
        self.occupy_level = float(occupy_level)
        if height_tolerance < 1.0:
            raise ValueError(f"height_tolerance must be >= 1, got {height_tolerance}")
        self.height_tolerance = float(height_tolerance)
        if aspect is not None and not 0.05 <= aspect <= 2.0:
            raise ValueError(f"aspect must be in [0.05, 2] or None, got {aspect}")
        self.aspect = None if aspect is None else float(aspect)
        self.frame_border = bool(frame_border)
        bs = np.asarray(box_scale, dtype=np.float64).reshape(-1)
        if bs.shape != (2,) or not ((bs > 0.2) & (bs <= 2.0)).all():
            raise ValueError(f"box_scale must be [w, h] factors in (0.2, 2], got {list(box_scale)}")
        self.box_scale = bs
        if box not in ("template", "foreground", "region"):
            raise ValueError(f"box must be 'template', 'foreground' or 'region', got {box!r}")
        self.box = box
        if group_gap < 0:
            raise ValueError(f"group_gap must be >= 0, got {group_gap}")
        self.group_gap = float(group_gap)
        if not -1.0 <= head_contrast <= 1.0:
            raise ValueError(f"head_contrast must be in [-1, 1], got {head_contrast}")
        self.head_contrast = float(head_contrast)
        self.height_model: tuple[float, float] | None = None
        self.fixed_height_model: tuple[float, float] | None = None
        if height_model is not None:
            if len(height_model) != 2:
                raise ValueError(f"height_model must be [a, b], got {height_model}")
            self.fixed_height_model = (float(height_model[0]), float(height_model[1]))
            self.height_model = self.fixed_height_model
        if not 0.0 < max_overlap <= 1.0:
            raise ValueError(f"max_overlap must be in (0, 1], got {max_overlap}")
        self.max_overlap = float(max_overlap)
        self.part_height = float(part_height)
        self._cache: dict[int, list] = {}
        self._kernels: list = []

    def pixel_heights(self, frame_height: int) -> tuple[float, float]:
        """(min, max) person height searched in a frame ``frame_height`` rows high, pixels."""
        f = float(frame_height) if self.height_unit == "frame" else 1.0
        return self.min_height * f, self.max_height * f

    def _kernels_for(self, frame_height: int) -> list:
        key = int(frame_height) if self.height_unit == "frame" else 0
        if key not in self._cache:
            lo, hi = self.pixel_heights(frame_height)
            heights = np.geomspace(lo, hi, self.n_scales) / self.downscale
            aspect = self.aspect or self.template.shape[1] / self.template.shape[0]
            kernels = []
            for h in heights:
                th = max(round(h), 3)
                tw = max(round(h * aspect), 2)
                t = cv2.resize(self.template, (tw, th), interpolation=cv2.INTER_AREA)
                kh = max(round(th * HEAD_FRACTION), 1)  # PBM 2.1: the head is 1/7 of the height
                head = np.zeros_like(t)
                head[:kh] = t[:kh] > 0.5
                beside = np.zeros_like(t)
                beside[:kh] = t[:kh] < 0.1
                kernels.append((t, (head, beside), float(t.sum())))
            self._cache[key] = kernels
        return self._cache[key]

    def set_height_model(self, model: tuple[float, float] | None) -> None:
        """Expected person height = a * foot_row + b (full-resolution pixels); None: no prior
        (or the fixed ``height_model`` given to the constructor, which a learnt one overrides)."""
        if model is None:
            self.height_model = self.fixed_height_model
        else:
            self.height_model = (float(model[0]), float(model[1]))

    def fit(self, foreground: np.ndarray, template_boxes: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Greedy fits over a (H, W) foreground mask (nonzero = foreground).

        Foreground components closer than ``group_gap`` rows one above the other (a person
        whose middle matches the background: torso and legs apart) are searched together.

        Args:
            foreground: (H, W) mask.
            template_boxes: return the fitted templates' boxes (the sizes the height prior
                speaks of) instead of the reported boxes (``box``, ``box_scale``).
        Returns:
            boxes (N, 4) float64 xywh in full-resolution pixels and scores (N,) float64.
        """
        boxes, tight, scores = self.fit_all(foreground)
        if not len(boxes):
            return boxes, scores
        H, W = np.asarray(foreground).shape
        out = boxes if template_boxes or self.box == "template" else tight
        if not template_boxes and (self.box_scale != 1.0).any():
            sw, sh = self.box_scale
            out[:, 0] += out[:, 2] * (1.0 - sw) / 2
            out[:, 2] *= sw
            out[:, 3] *= sh
        if self.frame_border:  # clip to the frame
            x0c, y0c = np.clip(out[:, 0], 0, W), np.clip(out[:, 1], 0, H)
            x1c = np.clip(out[:, 0] + out[:, 2], 0, W)
            y1c = np.clip(out[:, 1] + out[:, 3], 0, H)
            out = np.column_stack([x0c, y0c, x1c - x0c, y1c - y0c])
        return out, scores

    def fit_all(self, foreground: np.ndarray, group: bool = True,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Greedy fits: template boxes (N, 4), the boxes of the foreground each explains
        (N, 4), both xywh full-resolution pixels unclipped, and scores (N,).
        ``group=False`` searches every component alone (``group_gap`` ignored)."""
        d = self.downscale
        fg = (np.asarray(foreground) != 0).astype(np.uint8)
        H, W = fg.shape
        self._kernels = self._kernels_for(H)
        small = fg if d == 1 else cv2.resize(fg, (W // d, H // d), interpolation=cv2.INTER_AREA)
        if d > 1:  # INTER_AREA on 0/1 uint8 rounds: keep cells at least half foreground
            small = cv2.resize(fg * np.uint8(255), (W // d, H // d), interpolation=cv2.INTER_AREA)
            small = (small >= 128).astype(np.uint8)
        gap = int(round(self.group_gap / d)) if group else 0
        grouped = small if gap < 1 else cv2.dilate(small, np.ones((gap + 1, 1), np.uint8),
                                                   anchor=(0, 0))
        n, lab, stats, _ = cv2.connectedComponentsWithStats(grouped, connectivity=8)
        boxes, scores, tight = [], [], []
        m = max(self.margin // d, 1)
        hmax = max(k[0].shape[0] for k in self._kernels)
        wmax = max(k[0].shape[1] for k in self._kernels)
        min_area = 0.15 * self._kernels[0][2]
        for i in range(1, n):
            x, y, w, h, area = stats[i]
            if area < min_area:
                continue
            x0, y0 = max(x - m - wmax // 2, 0), max(y - m - hmax // 2, 0)
            x1, y1 = min(x + w + m + wmax // 2, small.shape[1]), min(y + h + m + hmax // 2, small.shape[0])
            # only this group's pixels in the crop (others are found from their own)
            crop = ((lab[y0:y1, x0:x1] == i) & (small[y0:y1, x0:x1] > 0)).astype(np.float32)
            edges = None
            if self.frame_border:  # which crop sides are the frame's border
                edges = (y0 == 0, y1 == small.shape[0], x0 == 0, x1 == small.shape[1])
            b, s, t = self._greedy(crop, region_height=h, row0=y0, edges=edges)
            for bx, sc, tb in zip(b, s, t):
                boxes.append([(bx[0] + x0) * d, (bx[1] + y0) * d, bx[2] * d, bx[3] * d])
                tight.append([(tb[0] + x0) * d, (tb[1] + y0) * d, tb[2] * d, tb[3] * d])
                scores.append(sc)
        if not boxes:
            return np.zeros((0, 4)), np.zeros((0, 4)), np.zeros(0)
        return (np.asarray(boxes, dtype=np.float64), np.asarray(tight, dtype=np.float64),
                np.asarray(scores, dtype=np.float64))

    def _is_part(self, box: list, boxes: list) -> bool:
        """Whether ``box`` lies more than ``max_overlap`` inside an earlier, taller fit
        (its height under ``part_height`` times that fit's)."""
        from trackers.geometry import intersection_matrix

        b = np.asarray(boxes, dtype=np.float64)
        inter = intersection_matrix(np.asarray([box], dtype=np.float64), b)[0]
        inside = inter / max(box[2] * box[3], 1e-9)
        return bool(((inside > self.max_overlap) & (box[3] < self.part_height * b[:, 3])).any())

    def _allowed_rows(self, th: int, rows: int, row0: int) -> np.ndarray | None:
        """(rows, 1) bool: centre rows where a template th rows high fits the height model."""
        if self.height_model is None:
            return None
        a, b = self.height_model
        d = self.downscale
        foot = (np.arange(rows) + row0 + th - th // 2) * d  # full-resolution foot row
        expected = (a * foot + b) / d
        ratio = th / np.maximum(expected, 1e-6)
        ok = (expected > 0) & (ratio >= 1 / self.height_tolerance) & (ratio <= self.height_tolerance)
        return ok[:, None]

    def _greedy(self, vacant: np.ndarray, region_height: int, row0: int = 0,
                edges: tuple[bool, bool, bool, bool] | None = None) -> tuple[list, list]:
        """Greedy fits in one (h, w) float32 0/1 crop; boxes in crop coordinates.

        ``edges`` (top, bottom, left, right): crop sides on the frame border, beyond which
        template pixels are unknown (counted as occupied: outside the visible mass).

        The per-scale sums (sum T V, box sum of V, sum T O) are computed once over the crop
        and, after each fit, recomputed only in the window its marked pixels can affect.
        """
        H, W = vacant.shape
        cut = False  # a region cut by (or within margin of) the frame's top or bottom: its
        # height does not bound the template heights tried
        if edges is not None:
            rows = np.flatnonzero(vacant.any(axis=1))
            near = max(self.margin // self.downscale, 1)  # frames may have a dark border strip
            cut = bool(len(rows) and ((edges[0] and rows[0] < near) or (edges[1] and rows[-1] >= H - near)))
        kernels = []
        heads = []
        for t, head, tsum in self._kernels:
            rows_ok = self._allowed_rows(t.shape[0], H, row0)
            if (t.shape[0] <= 1.5 * region_height + 4 or cut) and (rows_ok is None or rows_ok.any()):
                kernels.append((t, tsum, rows_ok))
                heads.append(head)
        if not kernels:
            return [], [], []
        # zero-padded storage so that any window's kernel support is inside the array
        py = max(t.shape[0] for t, _, _ in kernels)
        px = max(t.shape[1] for t, _, _ in kernels)
        vp = np.zeros((H + 2 * py, W + 2 * px), dtype=np.float32)
        op = np.zeros_like(vp)
        vp[py : py + H, px : px + W] = vacant
        if edges is not None:
            top, bottom, left, right = edges
            if top:
                op[:py] = 1.0
            if bottom:
                op[py + H :] = 1.0
            if left:
                op[:, :px] = 1.0
            if right:
                op[:, px + W :] = 1.0
        V, O = vp[py : py + H, px : px + W], op[py : py + H, px : px + W]
        F0 = vacant.copy()  # the region's foreground before any fit

        def corr(img, k, r0, r1, c0, c1):
            """Correlation of padded ``img`` with kernel ``k`` (anchored at its centre, as
            filter2D's default) at output rows [r0, r1), cols [c0, c1) of the crop: the valid
            part of ``cv2.matchTemplate`` (TM_CCORR), the same sums as filter2D to float
            rounding and faster for person-sized kernels."""
            th, tw = k.shape
            ay, ax = th // 2, tw // 2
            win = img[py + r0 - ay : py + r1 + th - 1 - ay, px + c0 - ax : px + c1 + tw - 1 - ax]
            return cv2.matchTemplate(win, k, cv2.TM_CCORR)  # the valid part: (r1-r0, c1-c0)

        def sums(t, r0, r1, c0, c1):
            """(sum T V, box sum V, sum T O) at output rows [r0, r1), cols [c0, c1)."""
            th, tw = t.shape
            ay, ax = th // 2, tw // 2  # filter2D's default anchor: the kernel centre
            ys = slice(py + r0 - ay, py + r1 + th - 1 - ay)
            xs = slice(px + c0 - ax, px + c1 + tw - 1 - ax)
            inner = (slice(ay, ay + r1 - r0), slice(ax, ax + c1 - c0))
            tv = corr(vp, t, r0, r1, c0, c1)
            bx = cv2.boxFilter(vp[ys, xs], cv2.CV_32F, (tw, th), anchor=(ax, ay), normalize=False,
                               borderType=cv2.BORDER_CONSTANT)[inner]
            to = corr(op, t, r0, r1, c0, c1) if op[ys, xs].any() else np.zeros_like(tv)
            return tv, bx, to

        # each scale is searched only on the band of centre rows its height is allowed at
        # (the height prior), so a calibrated search costs a few scales per row
        bands = []
        for i, (t, tsum, rows_ok) in enumerate(kernels):
            if rows_ok is None:
                bands.append((0, H))
            else:
                okr = np.flatnonzero(rows_ok[:, 0])
                b0, b1 = int(okr[0]), int(okr[-1]) + 1
                bands.append((b0, b1))
                kernels[i] = (t, tsum, rows_ok[b0:b1])
        maps = [list(sums(t, b0, b1, 0, W)) for (t, _, _), (b0, b1) in zip(kernels, bands)]
        head_ok = [None] * len(kernels)
        if self.head_contrast > -1.0:
            # head evidence on the region's foreground (fixed during the search), pixels
            # beyond the frame's border counting as foreground (unknown): the head rows'
            # fill inside the head minus their fill beside it (Reta: a person's head shows)
            known = vp + op
            for i, ((head, beside), (b0, b1)) in enumerate(zip(heads, bands)):
                hin = corr(known, head, b0, b1, 0, W)
                hout = corr(vp, beside, b0, b1, 0, W)
                c = (np.minimum(hin, head.sum()) / max(head.sum(), 1e-6)
                     - hout / max(beside.sum(), 1e-6))
                head_ok[i] = c >= self.head_contrast
        boxes, scores, tight = [], [], []
        for _ in range(self.max_people):
            best = (0.0, None)
            for (t, tsum, rows_ok), (tv, bx, to), hok, (b0, _b1) in zip(kernels, maps, head_ok, bands):
                visible = tsum - to
                # explained mass E = sum T V - alpha sum T (1 - V) - beta sum (1 - T) V,
                # with sum (1 - T) V = box sum of V - sum T V
                explained = tv - self.alpha * (visible - tv) - self.beta * (bx - tv)
                ok = (explained >= self.threshold * np.maximum(visible, 1e-6)) & (
                    visible >= self.min_visible * tsum)
                if rows_ok is not None:
                    ok &= rows_ok
                if hok is not None:
                    ok &= hok
                if not ok.any():
                    continue
                e = np.where(ok, explained, -np.inf)
                j = int(np.argmax(e))
                r, c = divmod(j, W)
                if e[r, c] > best[0]:
                    best = (float(e[r, c]), (r + b0, c, t, float(e[r, c] / max(visible[r, c], 1e-6))))
            if best[1] is None:
                break
            r, c, t, score = best[1]
            th, tw = t.shape
            top, left = r - th // 2, c - tw // 2  # filter2D anchors kernels at their centre
            box = [left, top, tw, th]
            rr0, cc0 = max(top, 0), max(left, 0)
            rr1, cc1 = min(top + th, H), min(left + tw, W)
            sil = t[rr0 - top : rr1 - top, cc0 - left : cc1 - left] > self.occupy_level
            region = V[rr0:rr1, cc0:cc1]
            if not boxes or not self._is_part(box, boxes):
                boxes.append(box)
                scores.append(score)
                if self.box == "region":  # the region's foreground inside the template box
                    claimed = F0[rr0:rr1, cc0:cc1] > 0
                else:
                    claimed = sil & (region > 0)  # the foreground this fit explains
                rows, cols = np.flatnonzero(claimed.any(axis=1)), np.flatnonzero(claimed.any(axis=0))
                tight.append([cc0 + cols[0], rr0 + rows[0], cols[-1] - cols[0] + 1,
                              rows[-1] - rows[0] + 1] if len(rows) else box)
            # a part of a person already found is not reported, but its pixels are used up
            O[rr0:rr1, cc0:cc1] = np.maximum(O[rr0:rr1, cc0:cc1], sil & (region > 0))
            region[sil] = 0.0
            for (k, _, _), m, (b0, b1) in zip(kernels, maps, bands):  # refresh the affected window only
                kh, kw = k.shape
                o0, o1 = max(rr0 - (kh - 1 - kh // 2), b0), min(rr1 + kh // 2, b1)
                q0, q1 = max(cc0 - (kw - 1 - kw // 2), 0), min(cc1 + kw // 2, W)
                if o1 > o0 and q1 > q0:
                    tv, bx, to = sums(k, o0, o1, q0, q1)
                    m[0][o0 - b0 : o1 - b0, q0:q1] = tv
                    m[1][o0 - b0 : o1 - b0, q0:q1] = bx
                    m[2][o0 - b0 : o1 - b0, q0:q1] = to
        return boxes, scores, tight


def fit_height_model(
    feet: np.ndarray, heights: np.ndarray, min_samples: int = 20, min_span: float = 30.0,
) -> tuple[float, float] | None:
    """Robust line height = a * foot_row + b through single-person samples (pixels).

    Least squares, then twice more without samples further than 2.5 MADs from the line.
    Returns None with fewer than ``min_samples`` samples, a foot-row span under
    ``min_span`` pixels, or a negative slope (a camera above the ground sees nearer people
    lower in the image and larger).
    """
    y = np.asarray(feet, dtype=np.float64)
    h = np.asarray(heights, dtype=np.float64)
    if len(y) < min_samples or np.ptp(y) < min_span:
        return None
    keep = np.ones(len(y), dtype=bool)
    for _ in range(3):
        a, b = np.polyfit(y[keep], h[keep], 1)
        res = np.abs(h - (a * y + b))
        mad = np.median(res[keep]) + 1e-6
        keep = res <= 2.5 * 1.4826 * mad
        if keep.sum() < min_samples // 2:
            return None
    return (float(a), float(b)) if a >= 0 else None
