"""Appearance model q (Reta 3.2, eq. 1) and its similarity rho (eq. 4), fast path.

The definition lives in ``occbench.trackers.three_hypothesis.features.ellipse_histograms``: joint
16x16x16 colour histogram over the pixels whose centres lie in the ellipse inscribed in a
box, optionally restricted to foreground pixels. This module computes exactly the same
histograms for boxes snapped to whole pixels (``tests/trackers/three_hypothesis/
test_tracker.py`` checks equality) in one compiled pass over each box's pixels
(``_kernels.ellipse_histograms``) instead of binning the whole frame.
A histogram fills few of its bins**3 bins (a measurement's about 7 of 4,096 at 16 bins, a
person's q a few tens): ``Histogram`` keeps its occupied bins and their values (the others
are +0), the measurements' from eq. 1's kernel and the people's q from the blends towards
them, so a frame neither zeroes, copies nor reads the empty bins. ``measure`` also gives
the bins any measurement occupies, over which the tracker sums rho (eq. 4), and
``columns`` the (N, K) values there. Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from occbench.trackers.common.checks import require
from occbench.trackers.three_hypothesis._kernels import blend, ellipse_histograms
from occbench.trackers.three_hypothesis.features import bhattacharyya

__all__ = ["EllipseHistogrammer", "Histogram", "bhattacharyya", "columns", "holds_both",
           "snap_boxes", "towards"]

_NO_MASK = np.zeros((1, 1), dtype=bool)
"""The kernel's placeholder foreground when there is none."""


class Histogram(NamedTuple):
    """A colour histogram (eq. 1) over ``size`` bins, kept as its occupied ``bins`` (sorted,
    distinct int64) and their ``values`` (float64); every other bin is +0."""

    bins: np.ndarray
    values: np.ndarray
    size: int

    @classmethod
    def of(cls, dense: np.ndarray) -> Histogram:
        """The histogram of a dense (size,) array (its nonzero bins)."""
        bins = np.flatnonzero(dense)
        return cls(bins, dense[bins], len(dense))

    def dense(self) -> np.ndarray:
        """The (size,) float64 array."""
        out = np.zeros(self.size)
        out[self.bins] = self.values
        return out


def towards(q: Histogram, p: Histogram, v: float) -> Histogram:
    """A new q' = (1 - v) q + v p (v > 0), compiled over the bins either occupies: the bits
    of numpy's dense expression (``_kernels.blend``)."""
    return Histogram(*blend(q.bins, q.values, p.bins, p.values, v), q.size)


def holds_both(q: Histogram, p: Histogram, own: float, partner: Histogram) -> bool:
    """Eq. 4 of p with the mixture own q + (1 - own) q_j above its rho with q and q_j
    alone: p's colours hold both people (``contact.UnmixedAppearance``'s evidence)."""
    p_, q_, q_j = p.dense(), q.dense(), partner.dense()
    mix = bhattacharyya(p_, own * q_ + (1.0 - own) * q_j)
    return mix > max(bhattacharyya(p_, q_), bhattacharyya(p_, q_j))


def columns(histograms: list[Histogram], support: np.ndarray) -> np.ndarray:
    """(N, K) values of the N ``histograms`` at the K ``support`` bins (sorted), +0 where a
    histogram does not occupy one (the dense rows' ``[:, support]``)."""
    out = np.zeros((len(histograms), len(support)))
    if not histograms or not len(support):
        return out
    bins = np.concatenate([h.bins for h in histograms])
    rows = np.repeat(np.arange(len(histograms)), [len(h.bins) for h in histograms])
    at = np.full(histograms[0].size, -1)  # each bin's column in support, -1: none
    at[support] = np.arange(len(support))
    col = at[bins]
    hit = col >= 0
    out[rows[hit], col[hit]] = np.concatenate([h.values for h in histograms])[hit]
    return out


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
        return np.array([h.dense() for h in p]).reshape(len(p), self.bins**3)

    def measure(
        self, frame: np.ndarray, boxes: np.ndarray, foreground: np.ndarray | None = None
    ) -> tuple[list[Histogram], np.ndarray]:
        """Histograms p (eq. 1) as ``Histogram``s and the bins they occupy.

        The Bhattacharyya coefficient rho = sum_b sqrt(q_b p_b) (eq. 4) against these
        measurements only needs the ``support`` bins (elsewhere every p_b is 0).

        Returns:
            p: list of N ``Histogram``s (arguments as ``__call__``);
            support: (K,) int sorted bins where at least one p is nonzero.
        """
        snapped = snap_boxes(boxes).astype(np.int64)
        size = self.bins**3
        nonzero = np.empty(len(snapped) * size, dtype=np.int64)
        values = np.empty(len(snapped) * size)
        starts = np.empty(len(snapped) + 1, dtype=np.int64)
        occupied = np.zeros(size, dtype=bool)
        has_fg = foreground is not None
        if has_fg and foreground.dtype != bool:  # a label image: one compiled kernel serves
            foreground = foreground != 0
        used = ellipse_histograms(frame, snapped, foreground if has_fg else _NO_MASK, has_fg,
                                  float(self.min_foreground), self.stride, self.bins, nonzero,
                                  values, starts, occupied)
        nonzero, values, bounds = nonzero[:used].copy(), values[:used].copy(), starts.tolist()
        p = [Histogram(nonzero[a:b], values[a:b], size)
             for a, b in zip(bounds[:-1], bounds[1:])]
        return p, occupied.nonzero()[0]
