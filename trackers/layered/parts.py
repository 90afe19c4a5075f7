"""The five-part split of a person box and the per-part features of the PBM tracker.

PBM 2.1 (Fig. 2) splits a person's bounding box into five rectangles: the head (the top
one-seventh of the height), the left and right torso-and-arm, and the left and right leg.
The split is fixed by the global model's six degrees of freedom: the head is the top
``h / 7`` rows; torso and arms run from there down to the centroid row ``yc``; the legs run
from ``yc`` to the bottom; left and right are divided at the centroid column ``xc``. With
the centroid ratios of PBM eqs. 1-2,

    xc = xtl + alpha * w                           (eq. 1)
    yc = ytl + h / 7 + beta * (h - h / 7)          (eq. 2, sign-corrected)

so a box plus (alpha, beta) gives the five rectangles (``part_boxes``; both equations
are in ``occbench.trackers.layered.split``, re-exported here).

PBM 2.2 describes each part by area, perimeter, HSV and XYZ colour histograms,
displacement and overlap. ``PartFeatureExtractor.extract`` measures the first four (plus
the part centroid, from which the displacement follows) for many boxes of one frame;
``part_displacement`` and ``part_overlap`` compare two sets of parts. Sizes are
normalised so one model fits near and far people:

- area: fraction of the part rectangle that is foreground, in [0, 1];
- perimeter: silhouette-outline pixels (foreground pixels with a background 4-neighbour)
  inside the part, divided by the part's half perimeter (w + h);
- colour: joint ``bins**3`` histograms (as ``occbench.trackers.histograms.colour_histogram``) of
  the foreground pixels of the part, in OpenCV's 8-bit HSV (hue 0..179) and XYZ;
- displacement: distance between part centroids, divided by the person height;
- overlap: intersection over union of the two part rectangles.

Every array is float64; boxes are xywh, 0-based pixels.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

from occbench.trackers.common.checks import require
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.layered import colour_kernels, sampling_kernels
from occbench.trackers.layered.split import (  # eqs. 1-2, re-exported here
    HEAD_FRACTION,
    centroid_ratios,  # noqa: F401
    part_boxes,  # noqa: F401
)

PART_NAMES: tuple[str, ...] = (
    "head",
    "left_torso_arm",
    "right_torso_arm",
    "left_leg",
    "right_leg",
)
"""The five parts of PBM 2.1, in the order used by every (N, 5, ...) array."""

N_PARTS = len(PART_NAMES)

FEATURES: tuple[str, ...] = ("area", "perimeter", "hsv", "xyz", "displacement", "overlap")
"""The Nf = 6 features of every part (PBM 2.2), in the order of every (..., 6) array."""
N_FEATURES = len(FEATURES)
#: fewest (rows, cols) samples of a box (the head band, its top 1/7, is whole rows)
MIN_GRID = (7, 2)
#: most sample columns of a box (a grid row is one 64-bit mask in ``sampling_kernels``)
MAX_GRID_COLS = 64

DEFAULT_ALPHA = 0.5
"""Centroid column ratio of an upright symmetric person (eq. 1)."""
DEFAULT_BETA = (0.5 - HEAD_FRACTION) / (1.0 - HEAD_FRACTION)
"""Centroid row ratio of a person whose centroid is at mid-height (eq. 2)."""


@dataclass
class PartFeatures:
    """Features of the five parts of N boxes (PBM 2.2).

    Attributes:
        parts: (N, 5, 4) xywh part rectangles.
        area: (N, 5) foreground fraction of each part rectangle.
        perimeter: (N, 5) outline pixels inside the part / (part w + h).
        hsv: (N, 5, B) joint HSV histograms of the part's foreground pixels (sum 1 or 0).
        xyz: (N, 5, B) joint XYZ histograms.
        centroid: (N, 5, 2) foreground centroid of each part (the rectangle centre when the
            part has no foreground).
        height: (N,) person heights (for the displacement normalisation).
    """

    parts: np.ndarray
    area: np.ndarray
    perimeter: np.ndarray
    hsv: np.ndarray
    xyz: np.ndarray
    centroid: np.ndarray
    height: np.ndarray

    def __len__(self) -> int:
        return len(self.parts)

    def take(self, idx: np.ndarray | list[int] | int) -> PartFeatures:
        """Features of a subset of the boxes (``idx`` an index array, list or integer)."""
        i = np.atleast_1d(np.asarray(idx, dtype=np.int64))
        return PartFeatures(
            self.parts[i], self.area[i], self.perimeter[i], self.hsv[i], self.xyz[i],
            self.centroid[i], self.height[i],
        )

    def shifted(self, shift: np.ndarray) -> PartFeatures:
        """The features with part rectangles and centroids moved by ``shift`` (N, 2) (x, y);
        appearance (area, perimeter, histograms) shared, not copied."""
        d = np.asarray(shift, dtype=np.float64).reshape(-1, 1, 2)
        parts = self.parts.copy()
        parts[..., :2] += d
        return PartFeatures(parts, self.area, self.perimeter, self.hsv, self.xyz,
                            self.centroid + d, self.height)

    def copy(self) -> PartFeatures:
        return PartFeatures(
            self.parts.copy(), self.area.copy(), self.perimeter.copy(), self.hsv.copy(),
            self.xyz.copy(), self.centroid.copy(), self.height.copy(),
        )

    @staticmethod
    def concatenate(items: list[PartFeatures], bins: int) -> PartFeatures:
        """Stack feature sets; an empty list gives zero boxes with ``bins**3`` histograms."""
        if not items:
            nb = bins**3
            return PartFeatures(
                np.zeros((0, N_PARTS, 4)), np.zeros((0, N_PARTS)), np.zeros((0, N_PARTS)),
                np.zeros((0, N_PARTS, nb)), np.zeros((0, N_PARTS, nb)),
                np.zeros((0, N_PARTS, 2)), np.zeros(0),
            )
        return PartFeatures(*(np.concatenate([getattr(f, k) for f in items]) for k in
                              ("parts", "area", "perimeter", "hsv", "xyz", "centroid", "height")))


def part_displacement(a: PartFeatures, b: PartFeatures) -> np.ndarray:
    """(N, M, 5) centroid displacement of each part between feature sets, / b's height."""
    d = np.linalg.norm(a.centroid[:, None] - b.centroid[None, :], axis=3)
    return d / np.maximum(b.height, 1.0)[None, :, None]


def part_overlap(a: PartFeatures, b: PartFeatures) -> np.ndarray:
    """(N, M, 5) IoU of each part rectangle of ``a`` with the same part of ``b``."""
    out = np.empty((len(a), len(b), N_PARTS))
    for j in range(N_PARTS):
        out[:, :, j] = iou_matrix(a.parts[:, j], b.parts[:, j])
    return out


def _joint_index(img: np.ndarray, bins: int, ranges: tuple[float, float, float]) -> np.ndarray:
    """int64 joint bin index of a (..., 3) uint8 image, as ``colour_histogram`` bins it:
    channel value v falls in bin min(v * bins // range, bins - 1)."""
    v = np.arange(256, dtype=np.int64)
    luts = [np.minimum(v * bins // int(r), bins - 1) * bins ** (2 - c) for c, r in enumerate(ranges)]
    return luts[0][img[..., 0]] + luts[1][img[..., 1]] + luts[2][img[..., 2]]


def _joint_lut(bins: int, ranges: tuple[float, float, float]) -> np.ndarray:
    """(256, 1, 3) ``cv2.LUT`` table whose channel sum is ``_joint_index``'s joint bin:
    channel c maps v to min(v * bins // range_c, bins - 1) * bins ** (2 - c). uint8 when
    ``bins**3 <= 256`` (the usual 4 bins), else uint16."""
    v = np.arange(256, dtype=np.int64)
    lut = np.stack([np.minimum(v * bins // int(r), bins - 1) * bins ** (2 - c)
                    for c, r in enumerate(ranges)], axis=1)
    return lut.astype(np.uint8 if bins**3 <= 256 else np.uint16).reshape(256, 1, 3)


HSV_RANGES = (180.0, 256.0, 256.0)
"""Channel ranges of OpenCV's 8-bit HSV (hue is 0..179)."""
XYZ_RANGES = (256.0, 256.0, 256.0)
_NO_MASK = np.zeros((1, 1), bool)
"""The kernels' mask argument when there is no foreground (never read)."""
_NO_CENTRES = np.zeros((0, 2))
"""The kernels' centroid output when ``extract`` is given the ratios (never written)."""


def _channel_luts(bins: int, ranges: tuple[float, float, float]) -> np.ndarray:
    """(3, 256) int64: row c maps a channel value v to its joint-bin term
    ``min(v * bins // range_c, bins - 1) * bins ** (2 - c)`` (``_joint_lut``)."""
    return np.ascontiguousarray(_joint_lut(bins, ranges).reshape(256, 3).T, dtype=np.int64)


@functools.lru_cache(maxsize=1)
def _check_colour_formulas() -> None:
    """Raise RuntimeError unless the kernels' HSV and XYZ values (OpenCV's integer
    formulas, ``colour_kernels._hsv_xyz``) equal ``cv2.cvtColor``'s on 65**3 colours; run
    once per process (tests/trackers/layered/test_parts.py checks all 2**24)."""
    v = np.append(np.arange(0, 256, 4), 255).astype(np.uint8)
    pixels = np.stack(np.meshgrid(v, v, v, indexing="ij"), -1).reshape(-1, 3)
    got = np.empty((len(pixels), 6), np.uint8)
    colour_kernels.convert(pixels, got)
    want = np.concatenate([cv2.cvtColor(pixels[None], cv2.COLOR_BGR2HSV)[0],
                           cv2.cvtColor(pixels[None], cv2.COLOR_BGR2XYZ)[0]], axis=1)
    if not np.array_equal(got, want):
        raise RuntimeError(
            f"OpenCV {cv2.__version__} converts BGR to 8-bit HSV or XYZ differently from "
            "trackers/layered/colour_kernels._hsv_xyz: update it")


class PixelBins:
    """The frame's pixels' joint HSV and XYZ bins (``bins`` per channel), each converted at
    its first read by a sample of the frame (``sampling_kernels.part_features``'
    ``pixel_bins``: one uint32 an entry, the frame's stamp in the bits above the two bins);
    extractors of the same ``bins`` may share one table (the bins of a pixel are a function
    of its colour alone)."""

    def __init__(self, bins: int) -> None:
        self.bins = bins
        self.shift = max((bins**3 - 1).bit_length(), 1)  # bits of a joint bin
        self._last = (1 << (32 - 2 * self.shift)) - 1  # the largest stamp
        self._table = np.zeros(0, np.uint32)
        self._stamp = 0

    def start(self, size: int) -> None:
        """A new frame of ``size`` pixels: every entry stale (a new stamp; the table zeroed,
        stamp 0, when its size changes or the stamps wrap)."""
        if len(self._table) != size or self._stamp == self._last:
            self._table = np.zeros(size, np.uint32)  # stamp 0: nothing converted
            self._stamp = 0
        self._stamp += 1

    def kernel_args(self) -> tuple[np.ndarray, int, int]:
        """(table (size,) uint32, stamp, shift): ``part_features``' ``pixel_bins``."""
        return self._table, self._stamp, self.shift


class PartFeatureExtractor:
    """Part features of many boxes of one frame (PBM 2.1-2.2), by compiled kernels.

    Each box is measured on a fixed grid of ``grid_rows x grid_cols`` sample points (the
    pixel under each cell centre, i.e. the box resized to the grid by nearest neighbour).
    One kernel call (``occbench.trackers.layered.sampling_kernels.part_features``) walks the samples of every box
    once: foreground test, part label, counts, centroid sums, outline test, and the joint
    HSV and XYZ bins of each foreground sample by OpenCV's own integer formulas (equal to
    ``cv2.cvtColor`` for every colour); the features equal a per-box numpy reference
    (``cv2.cvtColor`` of the gathered samples, ``np.bincount``) to rounding. Features are
    thus scale-free by construction, and the 25 sizes of the head-anchored search (PBM
    3.1) cost one call. Outline (perimeter) samples are foreground samples with a
    background 4-neighbour on the grid (outside the box counts as background). Samples
    outside the image count as background.

    Usage: ``ex.start(frame, fg)`` once per frame, then ``ex.extract(boxes, alpha, beta)``
    (or ``ex.extract_at_centroids(boxes)``, which measures the centroids on the same grid).

    Args:
        bins: histogram bins per channel (joint histograms have ``bins**3`` bins).
        grid_rows, grid_cols: samples per box (rows should be a multiple of 7 so the head
            band of PBM 2.1 is whole rows).
        shared: another extractor of the same ``bins`` whose pixel bins (``PixelBins``) this
            one uses; each ``start``s on the same frame, one after the other.
    """

    def __init__(self, bins: int = 4, grid_rows: int = 35, grid_cols: int = 15,
                 shared: PartFeatureExtractor | None = None) -> None:
        require("features.histogram_bins", 1 <= bins <= 32, "must lie in 1..32", bins)
        require("features.grid", grid_rows >= MIN_GRID[0] and MIN_GRID[1] <= grid_cols <= MAX_GRID_COLS,
                "must be at least {} x {} samples (rows, cols), at most {} columns".format(
                    *MIN_GRID, MAX_GRID_COLS), [grid_rows, grid_cols])
        self.bins = bins
        self.grid_rows = grid_rows
        self.grid_cols = grid_cols
        self._fr = (np.arange(grid_rows) + 0.5) / grid_rows
        self._fc = (np.arange(grid_cols) + 0.5) / grid_cols
        self._luts: tuple[np.ndarray, np.ndarray] | None = None  # made on first use
        require("features.histogram_bins", shared is None or shared.bins == bins,
                "must equal the bins of the extractor whose pixel bins are shared", bins)
        self.pixels = PixelBins(bins) if shared is None else shared.pixels  # (``start``)
        self._frame: np.ndarray | None = None
        self._fg: np.ndarray | None = None  # (H, W) bool, C-contiguous

    def start(self, frame: np.ndarray, foreground: np.ndarray | None) -> None:
        """Set the frame ((H, W, 3) uint8 BGR) and foreground ((H, W) bool or None = all);
        the frame's pixels are converted to bins at their first read until the next
        ``start``, so the frame must not change in between."""
        if (frame is None or frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8
                or frame.size == 0):
            raise ValueError("frame must be a non-empty (H, W, 3) uint8 BGR image")
        if foreground is not None and foreground.shape != frame.shape[:2]:
            raise ValueError(
                f"foreground shape {foreground.shape} differs from frame {frame.shape[:2]}")
        self._frame = np.ascontiguousarray(frame)
        self._fg = None if foreground is None else np.ascontiguousarray(foreground, dtype=bool)
        self.pixels.start(frame.shape[0] * frame.shape[1])  # this frame's: not converted yet

    def _colour_luts(self) -> tuple[np.ndarray, np.ndarray]:
        """The (3, 256) HSV and XYZ channel terms of the joint bins (``_channel_luts``)."""
        if self._luts is None:
            _check_colour_formulas()
            self._luts = (_channel_luts(self.bins, HSV_RANGES), _channel_luts(self.bins, XYZ_RANGES))
        return self._luts

    def _boxes(self, boxes: np.ndarray) -> np.ndarray:
        """The boxes as a new (N, 4) float64 array, once ``start`` was called."""
        if self._frame is None:
            raise RuntimeError("PartFeatureExtractor.start(frame, foreground) was not called")
        return np.array(boxes, dtype=np.float64).reshape(-1, 4)

    def _image(self) -> tuple[np.ndarray, np.ndarray, bool]:
        """The kernels' (frame, foreground mask, whether there is one): a 1 x 1 placeholder
        mask when not (every sample inside the image is then foreground)."""
        if self._fg is None:
            return self._frame, _NO_MASK, False
        return self._frame, self._fg, True

    def centroids(self, boxes: np.ndarray) -> np.ndarray:
        """(N, 2) foreground centroid (xc, yc) of each xywh box from its sample grid (the
        box centre where a box has no foreground; PBM 2.1)."""
        b = self._boxes(boxes)
        n = len(b)
        if n == 0:
            return np.zeros((0, 2))
        out = np.empty((n, 2))
        sampling_kernels.grid_centroids(b, (self._fr, self._fc), self._image(), out)
        return out

    def extract_at_centroids(self, boxes: np.ndarray) -> tuple[np.ndarray, PartFeatures]:
        """Centroids of the boxes and their part features split at them (PBM 2.1): the
        same as ``c = centroids(boxes); extract(boxes, *centroid_ratios(boxes, c))``, in
        one pass over the samples.

        Returns:
            (N, 2) centroids and PartFeatures of N boxes.
        """
        b = self._boxes(boxes)
        n = len(b)
        if n == 0:
            return np.zeros((0, 2)), PartFeatures.concatenate([], self.bins)
        cents = np.empty((n, 2))
        return cents, self._extract(b, np.empty(n), np.empty(n), cents)

    def extract(
        self,
        boxes: np.ndarray,
        alpha: np.ndarray | float = DEFAULT_ALPHA,
        beta: np.ndarray | float = DEFAULT_BETA,
    ) -> PartFeatures:
        """Part features of (N, 4) xywh boxes (PBM 2.2).

        Args:
            boxes: (N, 4) person boxes. alpha, beta: centroid ratios (eqs. 1-2), (N,) or scalar.
        Returns:
            PartFeatures of N boxes.
        """
        b = self._boxes(boxes)
        n = len(b)
        if n == 0:
            return PartFeatures.concatenate([], self.bins)
        a, be = np.empty(n), np.empty(n)
        a[:], be[:] = alpha, beta  # (N,) or scalar, as part_boxes broadcasts them
        return self._extract(b, a, be, None)

    def sampling(self, boxes: np.ndarray, alpha: np.ndarray | float = DEFAULT_ALPHA,
                 beta: np.ndarray | float = DEFAULT_BETA) -> tuple[np.ndarray, tuple, tuple]:
        """What ``extract(boxes, alpha, beta)`` hands its kernel, for a kernel that measures
        the boxes as it does (``association.box_scores``): the (N, 4) float64 boxes, the
        (alpha, beta) (N,) arrays and (grid, image, colour tables, pixel bins)."""
        b = self._boxes(boxes)
        a, be = np.empty(len(b)), np.empty(len(b))
        a[:], be[:] = alpha, beta
        return b, (a, be), ((self._fr, self._fc), self._image(), self._colour_luts(),
                            self.pixels.kernel_args())

    def _extract(self, b: np.ndarray, alpha: np.ndarray, beta: np.ndarray,
                 centres: np.ndarray | None) -> PartFeatures:
        """One ``part_features`` kernel call on (N, 4) boxes and (N,) ratios; with
        ``centres`` (N, 2) the kernel measures the centroids there and the ratios in
        ``alpha``, ``beta`` first (``extract_at_centroids``)."""
        n, nb = len(b), self.bins**3
        parts = np.empty((n, N_PARTS, 4))
        area, perimeter = np.empty((n, N_PARTS)), np.empty((n, N_PARTS))
        hsv, xyz = np.empty((n, N_PARTS, nb)), np.empty((n, N_PARTS, nb))
        centroid = np.empty((n, N_PARTS, 2))
        at_centroids = centres is not None
        sampling_kernels.part_features(b, alpha, beta, at_centroids, centres if at_centroids else _NO_CENTRES,
                               (self._fr, self._fc), self._image(), self._colour_luts(),
                               (parts, area, perimeter, hsv, xyz, centroid),
                               self.pixels.kernel_args())
        return PartFeatures(parts, area, perimeter, hsv, xyz, centroid, b[:, 3].copy())
