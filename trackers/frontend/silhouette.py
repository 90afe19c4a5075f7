"""Silhouette-template person detector (Reta 3.1, adapted).

Reta et al. fit an active-basis silhouette template at several scales over the moving
foreground: the best fit marks its silhouette occupied and the search repeats on the
vacant foreground. We keep the greedy occupancy loop and replace the active basis (Gabor
sketch learnt from their training images, which we do not have) with a mean person mask
``T`` (values in [0, 1], learnt by ``occbench fit silhouette`` from exact person
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
M / sum T >= ``min_visible`` (Reta: people more than 30% visible).

Every sum is a box sum on an integral image, O(1) per placement: the template is scored as
T~, its mean over a grid of cells (the head band, the top 1/7, and ``CELL_ROWS`` - 1 bands
below, by ``CELL_COLS`` columns; ``_Scales``), and the head rule as three rectangles. Each
scale is tried only on the rows its height is allowed at (the height prior); after a fit only
the placements its pixels touch are scored again (``greedy_search``, compiled in
``_silhouette_kernel``).

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
from dataclasses import dataclass
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
        path = resources.files("occbench.trackers.frontend") / "data" / "silhouette.npy"
    path = Path(str(path))
    if not path.is_file():
        raise FileNotFoundError(f"silhouette template not found: {path}")
    t = np.load(path, allow_pickle=False).astype(np.float32)
    if t.ndim != 2 or t.min() < 0 or t.max() > 1:
        raise ValueError(f"{path}: a template must be a 2-D array in [0, 1], got {t.shape}")
    return t


CELL_ROWS = 12  # the template's box-sum cells: the head band (top 1/7) and 11 bands below it,
CELL_COLS = 10  # ... by 10 columns


class _Scales:
    """The template at every searched height, as rectangles whose sums an integral image
    gives in O(1) per placement.

    Scale s (template ``templates[s]``, ``size[s]`` = (th, tw) rows and columns):

    * cells: row edges ``ys[s]`` (CELL_ROWS + 1: the head band, the top 1/7, then equal bands)
      and column edges ``xs[s]`` (CELL_COLS + 1, equal); T~ = T's mean over each cell, so
      sum T~ = sum T = ``tsum[s]``. For an image with integral I (I[y, x] = sum of the
      image above and left of (y, x)) and a placement with top-left (Y, X),

          sum T~ img = sum_cells w_cell boxsum(cell) = sum_{a, b} coef[s, a, b] I[Y + ys[a], X + xs[b]]

      (``coef``: each corner's signed share of the cells around it);
    * the head rule's rectangles ``head[s]`` = (kh, h0, h1, l1, r0): rows [0, kh) (the head
      band); the head, columns [h0, h1) where the band's mean T > 0.5; beside it, columns
      [0, l1) and [r0, tw) where it is < 0.1;
    * ``occ[s]``: (th, tw) pixels a fit marks occupied (T > occupy_level), zero-padded to
      the largest scale.
    """

    def __init__(self, templates: list[np.ndarray], occupy_level: float) -> None:
        S = len(templates)
        self.templates = templates
        self.size = np.array([t.shape for t in templates], dtype=np.int64)
        self.tsum = np.array([float(t.sum()) for t in templates])
        self.ys = np.zeros((S, CELL_ROWS + 1), dtype=np.int64)
        self.xs = np.zeros((S, CELL_COLS + 1), dtype=np.int64)
        self.coef = np.zeros((S, CELL_ROWS + 1, CELL_COLS + 1))
        self.head = np.zeros((S, 5), dtype=np.int64)
        hmax, wmax = self.size.max(axis=0)
        self.occ = np.zeros((S, hmax, wmax), dtype=np.uint8)
        for s, t in enumerate(templates):
            th, tw = t.shape
            kh = max(round(th * HEAD_FRACTION), 1)  # PBM 2.1: the head is 1/7 of the height
            ys = np.r_[0, np.round(np.linspace(kh, th, CELL_ROWS)).astype(np.int64)]
            xs = np.round(np.linspace(0, tw, CELL_COLS + 1)).astype(np.int64)
            w = np.zeros((CELL_ROWS + 2, CELL_COLS + 2))  # zero border: corners' neighbours
            for a in range(CELL_ROWS):
                for b in range(CELL_COLS):
                    cell = t[ys[a] : ys[a + 1], xs[b] : xs[b + 1]]
                    w[a + 1, b + 1] = cell.mean() if cell.size else 0.0
            self.coef[s] = w[:-1, :-1] - w[:-1, 1:] - w[1:, :-1] + w[1:, 1:]
            self.ys[s], self.xs[s] = ys, xs
            band = t[:kh].mean(axis=0)
            inside = np.flatnonzero(band > 0.5)
            h0, h1 = (inside[0], inside[-1] + 1) if len(inside) else (np.argmax(band), np.argmax(band) + 1)
            l1 = int(np.argmax(band[:h0] >= 0.1)) if (band[:h0] >= 0.1).any() else int(h0)
            right = band[h1:][::-1]
            r0 = tw - (int(np.argmax(right >= 0.1)) if (right >= 0.1).any() else len(right))
            self.head[s] = (kh, h0, h1, l1, r0)
            self.occ[s, :th, :tw] = t > occupy_level


def _box(I: np.ndarray, y0, x0, y1, x1):
    """Box sums [y0, y1) x [x0, x1) of the image whose integral is I (arrays of boxes)."""
    return I[y1, x1] - I[y0, x1] - I[y1, x0] + I[y0, x0]


def _integral(img: np.ndarray) -> np.ndarray:
    return cv2.integral(img, sdepth=cv2.CV_32S)


def greedy_search(vp, op, py, px, H, W, ids, bands, ys, xs, coef, size, tsum, head, occ,
                  alpha, beta, threshold, min_visible, head_contrast, fits) -> int:
    """The greedy fits of one region (the plain-numpy equations; ``_silhouette_kernel``
    compiles them).

    Args:
        vp, op: (H + 2 py, W + 2 px) uint8 0/1 vacant and occupied foreground of the region's
            crop, zero-padded by (py, px) (occupied = 1 beyond a frame border: unknown);
            updated in place as fits occupy pixels.
        ids, bands: the scales searched, and for each the centre rows [b0, b1) of the crop
            it is tried at (its height allowed there); every column is tried.
        ys .. occ: the ``_Scales`` arrays.
        fits: (max_people, 9) float64 output, one row per fit in greedy order: scale, top,
            left (crop pixels), E, score E / M, and the box [x0, y0, x1) x [y0, y1) of the
            foreground it explained (-1 when none).
    Returns:
        the number of fits.
    """
    if not len(ids):
        return 0
    s_, r_, c_ = [], [], []
    for s, (b0, b1) in zip(ids, bands):
        r, c = np.mgrid[b0:b1, 0:W]
        s_.append(np.full(r.size, s))
        r_.append(r.ravel())
        c_.append(c.ravel())
    s = np.concatenate(s_)
    th, tw = size[s, 0], size[s, 1]
    Y = np.concatenate(r_) - th // 2 + py  # a kernel is anchored at its centre
    X = np.concatenate(c_) - tw // 2 + px
    rows, cols = Y[:, None, None] + ys[s][:, :, None], X[:, None, None] + xs[s][:, None, :]

    def cells(I):  # sum of T~ over the image of integral I at every placement
        return (coef[s] * I[rows, cols]).sum(axis=(1, 2))

    ts = tsum[s]
    head_ok = np.ones(len(s), dtype=bool)
    if head_contrast > -1.0:  # on the region's foreground before any fit (unknown = fg)
        K, V0 = _integral(vp + op), _integral(vp)
        kh, h0, h1, l1, r0 = head[s].T
        hin = np.minimum(_box(K, Y, X + h0, Y + kh, X + h1), kh * (h1 - h0))
        hout = _box(V0, Y, X, Y + kh, X + l1) + _box(V0, Y, X + r0, Y + kh, X + tw)
        head_ok = (hin / np.maximum(kh * (h1 - h0), 1e-6)
                   - hout / np.maximum(kh * (l1 + tw - r0), 1e-6)) >= head_contrast
    n = 0
    for _ in range(len(fits)):
        IV, IO = _integral(vp), _integral(op)
        tv, bx = cells(IV), _box(IV, Y, X, Y + th, X + tw)
        visible = ts - cells(IO)
        # explained mass E = sum T V - alpha sum T (1 - V) - beta sum (1 - T) V
        e = tv - alpha * (visible - tv) - beta * (bx - tv)
        ok = (head_ok & (e >= threshold * np.maximum(visible, 1e-6))
              & (visible >= min_visible * ts) & (e > 0))
        if not ok.any():
            break
        j = int(np.argmax(np.where(ok, e, -np.inf)))
        k, y, x = s[j], Y[j], X[j]
        sil = occ[k, : th[j], : tw[j]] > 0
        win_v, win_o = vp[y : y + th[j], x : x + tw[j]], op[y : y + th[j], x : x + tw[j]]
        claimed = sil & (win_v > 0)  # the foreground this fit explains
        win_o[claimed] = 1
        win_v[sil] = 0
        fits[n, :5] = k, y - py, x - px, e[j], e[j] / max(visible[j], 1e-6)
        fits[n, 5:] = -1.0
        if claimed.any():
            rr, cc = np.flatnonzero(claimed.any(axis=1)), np.flatnonzero(claimed.any(axis=0))
            fits[n, 5:] = x - px + cc[0], y - py + rr[0], x - px + cc[-1] + 1, y - py + rr[-1] + 1
        n += 1
    return n


def region_arrays(small: np.ndarray, lab: np.ndarray, region: np.ndarray,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The zero-padded vacant and occupied arrays of one region (``search_regions``)."""
    label, x0, y0, x1, y1, py, px, top, bottom, left, right = (int(v) for v in region)
    H, W = y1 - y0, x1 - x0
    vp = np.zeros((H + 2 * py, W + 2 * px), dtype=np.uint8)
    op = np.zeros_like(vp)
    # only this region's pixels (others are found from their own)
    vp[py : py + H, px : px + W] = (lab[y0:y1, x0:x1] == label) & (small[y0:y1, x0:x1] > 0)
    if top:  # beyond the frame's border: unknown, counted as occupied
        op[:py] = 1
    if bottom:
        op[py + H :] = 1
    if left:
        op[:, :px] = 1
    if right:
        op[:, px + W :] = 1
    return vp, op


def search_regions(small, lab, regions, bands, ys, xs, coef, size, tsum, head, occ, alpha, beta,
                   threshold, min_visible, head_contrast, fits, counts) -> None:
    """``greedy_search`` on every region of a frame (compiled: ``_silhouette_kernel``).

    Args:
        small: (h, w) uint8 0/1 foreground at working resolution; lab: its (h, w) int32
            component labels.
        regions: (n, 11) int64 rows: label, crop x0, y0, x1, y1 (working pixels), padding
            py, px, and whether the crop's top, bottom, left, right side is the frame border.
        bands: (n, n_scales, 2) int64 centre rows [b0, b1) of the crop each scale is tried
            at (b0 = b1: not tried).
        fits: (n, max_people, 9) float64 output (``greedy_search``'s rows); counts: (n,)
            int64 output, fits per region.
    """
    for i, region in enumerate(regions):
        vp, op = region_arrays(small, lab, region)
        ids = np.flatnonzero(bands[i, :, 1] > bands[i, :, 0])
        counts[i] = greedy_search(vp, op, int(region[5]), int(region[6]), int(region[4] - region[2]),
                                  int(region[3] - region[1]), ids, bands[i, ids], ys, xs, coef,
                                  size, tsum, head, occ, alpha, beta, threshold, min_visible,
                                  head_contrast, fits[i])


@dataclass
class Candidates:
    """The greedy search's fits over one frame, in the order found (region by region).

    Attributes:
        boxes: (N, 4) float64 xywh fitted template boxes, full-resolution pixels, unclipped.
        tight: (N, 4) float64 xywh boxes of the foreground each fit explains (``box``).
        scores: (N,) float64 E / M.
        region: (N,) int64 the foreground region each was found in.
    """

    boxes: np.ndarray
    tight: np.ndarray
    scores: np.ndarray
    region: np.ndarray

    def __len__(self) -> int:
        return len(self.scores)


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
        compiled: run the greedy search compiled (``_silhouette_kernel``, tested against
            ``greedy_search``); False runs the numpy equations.
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
        compiled: bool = True,
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
        self.compiled = bool(compiled)
        self._cache: dict[int, _Scales] = {}
        self._kernels: _Scales | None = None

    def pixel_heights(self, frame_height: int) -> tuple[float, float]:
        """(min, max) person height searched in a frame ``frame_height`` rows high, pixels."""
        f = float(frame_height) if self.height_unit == "frame" else 1.0
        return self.min_height * f, self.max_height * f

    def _kernels_for(self, frame_height: int) -> _Scales:
        key = int(frame_height) if self.height_unit == "frame" else 0
        if key not in self._cache:
            lo, hi = self.pixel_heights(frame_height)
            heights = np.geomspace(lo, hi, self.n_scales) / self.downscale
            aspect = self.aspect or self.template.shape[1] / self.template.shape[0]
            shapes = [(max(round(h), 3), max(round(h * aspect), 2)) for h in heights]
            self._cache[key] = _Scales(
                [cv2.resize(self.template, (tw, th), interpolation=cv2.INTER_AREA) for th, tw in shapes],
                self.occupy_level)
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
        ``group=False`` searches every component alone (``group_gap`` ignored).

        Two steps: ``candidates`` (the greedy search: every fit, in the order found) and
        ``select`` (which of them are reported)."""
        c = self.candidates(foreground, group)
        keep = self.select(c)
        return c.boxes[keep], c.tight[keep], c.scores[keep]

    def candidates(self, foreground: np.ndarray, group: bool = True) -> Candidates:
        """The greedy search over a (H, W) foreground mask (nonzero = foreground): each
        foreground region (a connected component at working resolution, with ``margin``
        and half the largest template around it) searched on its own pixels."""
        d = self.downscale
        fg = np.asarray(foreground)
        fg = fg.view(np.uint8) if fg.dtype == np.bool_ else (fg != 0).astype(np.uint8)
        H, W = fg.shape
        sc = self._kernels = self._kernels_for(H)
        small = fg
        if d > 1:  # INTER_AREA on 0/1 uint8 rounds: keep cells at least half foreground
            small = cv2.resize(fg * np.uint8(255), (W // d, H // d), interpolation=cv2.INTER_AREA)
            small = (small >= 128).astype(np.uint8)
        hs, ws = small.shape
        gap = int(round(self.group_gap / d)) if group else 0
        grouped = small if gap < 1 else cv2.dilate(small, np.ones((gap + 1, 1), np.uint8),
                                                   anchor=(0, 0))
        _, lab, stats, _ = cv2.connectedComponentsWithStatsWithAlgorithm(
            grouped, 8, cv2.CV_32S, cv2.CCL_GRANA)
        label = 1 + np.flatnonzero(stats[1:, 4] >= 0.15 * sc.tsum[0])
        if not len(label):
            return self._no_candidates()
        x, y, w, h = stats[label, :4].T
        m = max(self.margin // d, 1)
        hmax, wmax = sc.size.max(axis=0)
        x0, y0 = np.maximum(x - m - wmax // 2, 0), np.maximum(y - m - hmax // 2, 0)
        x1, y1 = np.minimum(x + w + m + wmax // 2, ws), np.minimum(y + h + m + hmax // 2, hs)
        edges = np.zeros((len(label), 4), dtype=bool)  # crop sides on the frame's border
        cut = np.zeros(len(label), dtype=bool)  # regions cut by (or within margin of) the
        # frame's top or bottom: their height does not bound the template heights tried
        if self.frame_border:
            edges = np.column_stack([y0 == 0, y1 == hs, x0 == 0, x1 == ws])
            near = max(self.margin // d, 1)  # frames may have a dark border strip
            cut = (edges[:, 0] & (y - y0 < near)) | (edges[:, 1] & (y + h > y1 - near))
        allowed = self._allowed_bands(hs)  # each scale only on its band of centre rows
        if allowed is None:
            bands = np.zeros((len(label), len(sc.size), 2), dtype=np.int64)
            bands[:, :, 1] = (y1 - y0)[:, None]
        else:
            bands = np.clip(allowed[None] - y0[:, None, None], 0, (y1 - y0)[:, None, None])
        bands[~((sc.size[None, :, 0] <= 1.5 * h[:, None] + 4) | cut[:, None])] = 0
        live = bands[:, :, 1] > bands[:, :, 0]
        # zero padding holding every placement: a template is anchored at its centre
        pad = np.where(live[:, :, None], sc.size[None] - sc.size[None] // 2, 0).max(axis=1)
        regions = np.column_stack([label, x0, y0, x1, y1, pad, edges]).astype(np.int64)
        fits = np.zeros((len(label), self.max_people, 9))
        counts = np.zeros(len(label), dtype=np.int64)
        if self.compiled:
            from occbench.trackers.frontend._silhouette_kernel import search_regions_kernel as search
        else:
            search = search_regions
        search(small, lab, regions, np.ascontiguousarray(bands, dtype=np.int64), sc.ys, sc.xs,
               sc.coef, sc.size, sc.tsum, sc.head, sc.occ, self.alpha, self.beta, self.threshold,
               self.min_visible, self.head_contrast, fits, counts)
        # one row per fit: scale, top, left (crop), E, score, explained box x0, y0, x1, y1
        which = np.repeat(np.arange(len(label)), counts)
        f = np.concatenate([fits[i, :n] for i, n in enumerate(counts)]) if counts.any() else None
        if f is None:
            return self._no_candidates()
        size = sc.size[f[:, 0].astype(np.int64)]
        ox, oy = x0[which], y0[which]
        boxes = np.column_stack([f[:, 2] + ox, f[:, 1] + oy, size[:, 1], size[:, 0]]).astype(np.float64)
        tight = np.column_stack([f[:, 5] + ox, f[:, 6] + oy, f[:, 7] - f[:, 5], f[:, 8] - f[:, 6]])
        tight = np.where(f[:, 5:6] >= 0, tight, boxes)  # no foreground explained: its box
        if self.box == "region":  # the region's foreground inside the template box
            for k, (bx, by, bw, bh) in enumerate(boxes.astype(np.int64)):
                r = regions[which[k]]
                sub = slice(max(by, r[2]), min(by + bh, r[4])), slice(max(bx, r[1]), min(bx + bw, r[3]))
                own = (lab[sub] == r[0]) & (small[sub] > 0)
                rr, cc = np.flatnonzero(own.any(axis=1)), np.flatnonzero(own.any(axis=0))
                if len(rr):
                    tight[k] = [sub[1].start + cc[0], sub[0].start + rr[0], cc[-1] - cc[0] + 1,
                                rr[-1] - rr[0] + 1]
                else:
                    tight[k] = boxes[k]
        return Candidates(boxes * d, tight * d, f[:, 4].copy(), which)

    @staticmethod
    def _no_candidates() -> Candidates:
        return Candidates(np.zeros((0, 4)), np.zeros((0, 4)), np.zeros(0), np.zeros(0, dtype=np.int64))

    def select(self, c: Candidates) -> np.ndarray:
        """Which candidates are reported: (N,) bool.

        A candidate lying more than ``max_overlap`` inside an earlier, taller reported fit of
        its region (its height under ``part_height`` times that fit's) is a part of that
        person (an arm, a bag, a hollow in the foreground): its pixels were used up in the
        search but it is not reported. This is the step a verifier of candidate boxes plugs
        into.
        """
        from occbench.trackers.geometry import intersection_matrix

        keep = np.ones(len(c), dtype=bool)
        for k in range(1, len(c)):
            earlier = np.flatnonzero(keep[:k] & (c.region[:k] == c.region[k]))
            if not len(earlier):
                continue
            b = c.boxes[earlier]
            inside = intersection_matrix(c.boxes[k : k + 1], b)[0] / max(c.boxes[k, 2] * c.boxes[k, 3], 1e-9)
            keep[k] = not ((inside > self.max_overlap) & (c.boxes[k, 3] < self.part_height * b[:, 3])).any()
        return keep

    def _allowed_bands(self, rows: int) -> np.ndarray | None:
        """(n_scales, 2) int64: for each scale the centre rows [b0, b1) (working resolution,
        of a frame ``rows`` high) where its height fits the height model (an interval: the
        expected height grows with the row); None without one."""
        if self.height_model is None:
            return None
        a, b = self.height_model
        d = self.downscale
        th = self._kernels.size[:, :1]
        foot = (np.arange(rows)[None, :] + th - th // 2) * d  # full-resolution foot row
        expected = (a * foot + b) / d
        ratio = th / np.maximum(expected, 1e-6)
        ok = (expected > 0) & (ratio >= 1 / self.height_tolerance) & (ratio <= self.height_tolerance)
        b0 = np.argmax(ok, axis=1)
        b1 = rows - np.argmax(ok[:, ::-1], axis=1)
        return np.where(ok.any(axis=1)[:, None], np.column_stack([b0, b1]), 0)


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
