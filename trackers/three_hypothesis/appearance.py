"""Appearance model q (Reta 3.2, eq. 1) and its similarity rho (eq. 4), fast path.

The definition lives in ``occbench.trackers.three_hypothesis.features.ellipse_histograms``: joint
16x16x16 colour histogram over the pixels whose centres lie in the ellipse inscribed in a
box, optionally restricted to foreground pixels. This module computes exactly the same
histograms for boxes snapped to whole pixels (``tests/trackers/three_hypothesis/
test_tracker.py`` checks equality) in one compiled pass over each box's pixels
(``_kernels.ellipse_histograms``) instead of binning the whole frame.
``measure`` also gives the bins any measurement occupies, over which the tracker sums rho
(eq. 4). Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.common.checks import require
from occbench.trackers.three_hypothesis._kernels import blend, blend_at, ellipse_histograms
from occbench.trackers.three_hypothesis.features import bhattacharyya

__all__ = ["EllipseHistogrammer", "bhattacharyya", "snap_boxes", "towards"]

_NO_MASK = np.zeros((1, 1), dtype=bool)
"""The kernel's placeholder foreground when there is none."""


def towards(q: np.ndarray, p: np.ndarray, v: float, bins: np.ndarray | None = None
            ) -> np.ndarray:
    """A new q' = (1 - v) q + v p (v > 0), compiled: the bits of numpy's expression;
    ``bins``, p's nonzero bins (``EllipseHistogrammer.measure``), spares reading the rest."""
    return blend(q, p, v) if bins is None else blend_at(q, p, v, bins)


def snap_boxes(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) xywh rounded to whole pixels (sizes at least 1): the histogram support."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    x0 = np.round(b[:, :2])
    x1 = np.round(b[:, :2] + b[:, 2:])
    return np.concatenate([x0, np.maximum(x1 - x0, 1.0)], axis=1)


class EllipseHistogrammer:
    """Eq. 1 histograms of many ellipses of one frame at once.

    Args:
        bins: bins per colour channel (16 in the paper); must divide 256.
        min_foreground: when a foreground mask is given, the fraction of an ellipse's
            pixels that must be foreground for the mask to be used; below it the whole
            ellipse is counted (a person missed by the background model keeps a model).
        cache_size: most ellipse masks kept (keyed by box height and width).
        stride: count every stride-th row and column only (1 = every pixel, eq. 1 exactly).
    """

    def __init__(self, bins: int = 16, min_foreground: float = 0.2, cache_size: int = 4096,
                 stride: int = 1) -> None:
        require("appearance.bins", bins >= 1 and 256 % bins == 0, "must divide 256", bins)
        require("appearance.pixel_stride", stride >= 1, "must be >= 1", stride)
        self.bins = bins
        self.stride = stride
        self.min_foreground = min_foreground
        self.cache_size = cache_size
        self._masks: dict[tuple[int, int], tuple[np.ndarray, int]] = {}

    def _mask(self, h: int, w: int) -> tuple[np.ndarray, int]:
        """(h, w) uint8 mask (1 = pixel centre inside the ellipse inscribed in an h x w box)
        and its number of pixels |S|, cached by box size."""
        key = (h, w)
        cached = self._masks.get(key)
        if cached is None:
            if len(self._masks) >= self.cache_size:
                self._masks.clear()
            rx, ry = max(w / 2, 0.5), max(h / 2, 0.5)
            xs = (np.arange(w) + 0.5 - w / 2) / rx
            ys = (np.arange(h) + 0.5 - h / 2) / ry
            m = (ys[:, None] ** 2 + xs[None, :] ** 2 <= 1.0).view(np.uint8)
            cached = self._masks[key] = (m, int(np.count_nonzero(m)))
        return cached

    def foreground_share(self, foreground: np.ndarray, boxes: np.ndarray) -> np.ndarray:
        """(N,) share of the pixels of each box's ellipse (snapped as ``snap_boxes``, cut by
        the image border) that are foreground; 0 for an ellipse entirely outside the image.

        Args:
            foreground: (H, W) bool mask or label image (nonzero = foreground).
            boxes: (N, 4) xywh.
        """
        height, width = foreground.shape[:2]
        out = np.zeros(len(boxes))
        for k, (bx, by, bw, bh) in enumerate(np.asarray(boxes, dtype=np.float64)
                                              .reshape(-1, 4).tolist()):
            x, y = round(bx), round(by)
            w, h = max(round(bx + bw) - x, 1), max(round(by + bh) - y, 1)
            r0, r1 = max(y, 0), min(y + h, height)
            c0, c1 = max(x, 0), min(x + w, width)
            if r1 <= r0 or c1 <= c0:
                continue
            m, total = self._mask(h, w)
            if r1 - r0 < h or c1 - c0 < w:
                m = m[r0 - y : r1 - y, c0 - x : c1 - x]
                total = np.count_nonzero(m)
            if total:
                out[k] = np.count_nonzero(m & (foreground[r0:r1, c0:c1] != 0)) / total
        return out

    def __call__(
        self, frame: np.ndarray, boxes: np.ndarray, foreground: np.ndarray | None = None
    ) -> np.ndarray:
        """Histograms of the ellipses of ``boxes`` (snapped with ``snap_boxes``).

        Args:
            frame: (H, W, 3) uint8 image.
            boxes: (N, 4) xywh.
            foreground: optional (H, W) bool mask or label image (nonzero = foreground).
        Returns:
            (N, bins**3) float64 rows summing to 1 (all zero where no pixel is counted).
        """
        p = self.measure(frame, boxes, foreground)[0]
        return np.array(p).reshape(len(p), self.bins**3)

    def measure(
        self, frame: np.ndarray, boxes: np.ndarray, foreground: np.ndarray | None = None
    ) -> tuple[list[np.ndarray], np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """Histograms p (eq. 1), each an array of its own (a person can keep a measurement's
        histogram as its appearance q without a copy), the bins they occupy, and each one's.

        A person's histogram fills few of the bins**3 bins; the Bhattacharyya coefficient
        rho = sum_b sqrt(q_b p_b) (eq. 4) against these measurements only needs the
        ``support`` bins (elsewhere every p_b is 0), and a blend towards p only p's own
        (``_kernels.blend_at``).

        Returns:
            p: list of N (bins**3,) float64 arrays (arguments as ``__call__``);
            support: (K,) int sorted bins where at least one p is nonzero;
            bins: (nonzero, starts): p[i]'s nonzero bins are nonzero[starts[i]:starts[i + 1]]
            (sorted; every other bin of p[i] is +0), starts (N + 1,).
        """
        snapped = snap_boxes(boxes).astype(np.int64)
        hists = np.zeros((len(snapped), self.bins**3))
        occupied = np.zeros(self.bins**3, dtype=bool)
        has_fg = foreground is not None
        if has_fg and foreground.dtype != bool:  # a label image: one compiled kernel serves
            foreground = foreground != 0
        ellipse_histograms(frame, snapped, foreground if has_fg else _NO_MASK, has_fg,
                           float(self.min_foreground), self.stride, self.bins, hists, occupied)
        out = [h.copy() for h in hists]  # one array each: a person keeps its own q
        support = occupied.nonzero()[0]
        rows, cols = np.nonzero(hists[:, support])  # row-major: each row's bins sorted
        starts = np.searchsorted(rows, np.arange(len(hists) + 1))
        return out, support, (support[cols], starts)
