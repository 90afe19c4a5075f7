"""The five-part split of a person box and the per-part features of the PBM tracker.

PBM 2.1 (Fig. 2) splits a person's bounding box into five rectangles: the head (the top
one-seventh of the height), the left and right torso-and-arm, and the left and right leg.
The split is fixed by the global model's six degrees of freedom: the head is the top
``h / 7`` rows; torso and arms run from there down to the centroid row ``yc``; the legs run
from ``yc`` to the bottom; left and right are divided at the centroid column ``xc``. With
the centroid ratios of PBM eqs. 1-2,

    xc = xtl + alpha * w                           (eq. 1)
    yc = ytl + h / 7 + beta * (h - h / 7)          (eq. 2, sign-corrected)

so a box plus (alpha, beta) gives the five rectangles (``part_boxes``).

PBM 2.2 describes each part by area, perimeter, HSV and XYZ colour histograms,
displacement and overlap. ``PartFeatureExtractor.extract`` measures the first four (plus
the part centroid, from which the displacement follows) for many boxes of one frame;
``part_displacement`` and ``part_overlap`` compare two sets of parts. Sizes are
normalised so one model fits near and far people:

- area: fraction of the part rectangle that is foreground, in [0, 1];
- perimeter: silhouette-outline pixels (foreground pixels with a background 4-neighbour)
  inside the part, divided by the part's half perimeter (w + h);
- colour: joint ``bins**3`` histograms (as ``trackers.histograms.colour_histogram``) of
  the foreground pixels of the part, in OpenCV's 8-bit HSV (hue 0..179) and XYZ;
- displacement: distance between part centroids, divided by the person height;
- overlap: intersection over union of the two part rectangles.

Every array is float64; boxes are xywh, 0-based pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from trackers.geometry import iou_matrix

PART_NAMES: tuple[str, ...] = (
    "head",
    "left_torso_arm",
    "right_torso_arm",
    "left_leg",
    "right_leg",
)
"""The five parts of PBM 2.1, in the order used by every (N, 5, ...) array."""

N_PARTS = len(PART_NAMES)
HEAD_FRACTION = 1.0 / 7.0
"""The head occupies one seventh of the person height (PBM 2.1)."""

DEFAULT_ALPHA = 0.5
"""Centroid column ratio of an upright symmetric person (eq. 1)."""
DEFAULT_BETA = (0.5 - HEAD_FRACTION) / (1.0 - HEAD_FRACTION)
"""Centroid row ratio of a person whose centroid is at mid-height (eq. 2)."""


def centroid_ratios(boxes: np.ndarray, centroids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ratios alpha (eq. 1) and beta (eq. 2) of centroids inside boxes.

    The paper prints eq. 2 as ``(ytl - yc - h/7) / (h - h/7)``, which is negative for any
    centroid below the head; the ratio it describes ("the height of the torso over the body
    height") is ``(yc - ytl - h/7) / (h - h/7)``, used here.

    Args:
        boxes: (N, 4) xywh. centroids: (N, 2) (xc, yc).
    Returns:
        alpha (N,), beta (N,), clipped to [0.05, 0.95].
    """
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    c = np.asarray(centroids, dtype=np.float64).reshape(-1, 2)
    w = np.maximum(b[:, 2], 1e-9)
    h = np.maximum(b[:, 3], 1e-9)
    alpha = (c[:, 0] - b[:, 0]) / w
    beta = (c[:, 1] - b[:, 1] - HEAD_FRACTION * h) / (h - HEAD_FRACTION * h)
    return np.clip(alpha, 0.05, 0.95), np.clip(beta, 0.05, 0.95)


def part_boxes(
    boxes: np.ndarray, alpha: np.ndarray | float = DEFAULT_ALPHA, beta: np.ndarray | float = DEFAULT_BETA
) -> np.ndarray:
    """The five part rectangles of each box (PBM 2.1, Fig. 2).

    Args:
        boxes: (N, 4) xywh person boxes.
        alpha, beta: (N,) or scalar centroid ratios (eqs. 1-2).
    Returns:
        (N, 5, 4) xywh part boxes in ``PART_NAMES`` order.
    """
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    n = len(b)
    a = np.broadcast_to(np.asarray(alpha, dtype=np.float64), (n,))
    be = np.broadcast_to(np.asarray(beta, dtype=np.float64), (n,))
    x, y, w, h = b.T
    hh = HEAD_FRACTION * h
    xs = x + a * w  # split column = centroid column xc
    ys = y + hh + be * (h - hh)  # split row = centroid row yc
    top, left_w, right_w = y + hh, xs - x, x + w - xs
    torso_h, leg_h = ys - y - hh, y + h - ys
    return np.stack([x, y, w, hh, x, top, left_w, torso_h, xs, top, right_w, torso_h,
                     x, ys, left_w, leg_h, xs, ys, right_w, leg_h], axis=1).reshape(n, N_PARTS, 4)


def part_boxes_one(box, alpha: float, beta: float) -> np.ndarray:
    """``part_boxes`` of one xywh box and scalar ratios: (5, 4), the same values computed
    on floats (the per-target model update of PBM 4.2 calls it once per target)."""
    x, y, w, h = (float(v) for v in box)
    alpha, beta = float(alpha), float(beta)
    hh = HEAD_FRACTION * h
    xs = x + alpha * w
    ys = y + hh + beta * (h - hh)
    top, left_w, right_w = y + hh, xs - x, x + w - xs
    torso_h, leg_h = ys - y - hh, y + h - ys
    return np.array([[x, y, w, hh], [x, top, left_w, torso_h], [xs, top, right_w, torso_h],
                     [x, ys, left_w, leg_h], [xs, ys, right_w, leg_h]])


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
_ONES_1x3 = np.ones((1, 3))


class PartFeatureExtractor:
    """Part features of many boxes of one frame, vectorised over the boxes.

    Each box is measured on a fixed grid of ``grid_rows x grid_cols`` sample points (the
    pixel under each cell centre, i.e. the box resized to the grid by nearest neighbour):
    one gather (``np.take`` on flat pixel indices) for all boxes, one ``cv2.cvtColor`` to
    HSV and one to XYZ for all samples, one ``cv2.LUT`` per colour space for the quantised
    bins, one ``np.bincount`` per feature for all (box, part) pairs. Features are thus
    scale-free by construction, and the 25 sizes of the head-anchored search (PBM 3.1)
    cost one call. Outline (perimeter) samples are foreground samples with a background
    4-neighbour on the grid (outside the box counts as background). Samples outside the
    image count as background.

    Usage: ``ex.start(frame, fg)`` once per frame, then ``ex.extract(boxes, alpha, beta)``
    (or ``ex.extract_at_centroids(boxes)``, which measures the centroids on the same grid).

    Args:
        bins: histogram bins per channel (joint histograms have ``bins**3`` bins).
        grid_rows, grid_cols: samples per box (rows should be a multiple of 7 so the head
            band of PBM 2.1 is whole rows).
    """

    def __init__(self, bins: int = 4, grid_rows: int = 35, grid_cols: int = 15) -> None:
        if bins < 1 or bins > 32:
            raise ValueError(f"bins must be in 1..32, got {bins}")
        if grid_rows < 7 or grid_cols < 2:
            raise ValueError(f"grid must be at least 7 x 2 samples, got {grid_rows} x {grid_cols}")
        self.bins = bins
        self.grid_rows = grid_rows
        self.grid_cols = grid_cols
        self._fr = (np.arange(grid_rows) + 0.5) / grid_rows
        self._fc = (np.arange(grid_cols) + 0.5) / grid_cols
        self._hsv_lut = _joint_lut(bins, HSV_RANGES)
        self._xyz_lut = _joint_lut(bins, XYZ_RANGES)
        self._frame: np.ndarray | None = None
        self._pixels: np.ndarray | None = None  # (H * W, 3) view of the frame
        self._fg: np.ndarray | None = None
        self._fg_flat: np.ndarray | None = None

    def start(self, frame: np.ndarray, foreground: np.ndarray | None) -> None:
        """Set the frame ((H, W, 3) uint8 BGR) and foreground ((H, W) bool or None = all)."""
        if frame is None or frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ValueError("frame must be an (H, W, 3) uint8 BGR image")
        if foreground is not None and foreground.shape != frame.shape[:2]:
            raise ValueError(
                f"foreground shape {foreground.shape} differs from frame {frame.shape[:2]}")
        self._frame = frame
        self._pixels = frame.reshape(-1, 3)
        self._fg = None if foreground is None else np.asarray(foreground, dtype=bool)
        self._fg_flat = None if self._fg is None else self._fg.reshape(-1)

    def _grid(self, b: np.ndarray):
        """Sample rows ys (N, R) and columns xs (N, C), flat pixel index (N, R, C) of each
        sample (clipped into the image) and its foreground flag (N, R, C)."""
        H, W = self._frame.shape[:2]
        ys = b[:, 1, None] + self._fr[None] * b[:, 3, None]  # (N, R) sample rows
        xs = b[:, 0, None] + self._fc[None] * b[:, 2, None]  # (N, C) sample columns
        yi = np.clip(np.floor(ys), 0, H - 1).astype(np.intp)
        xi = np.clip(np.floor(xs), 0, W - 1).astype(np.intp)
        flat = (yi * W)[:, :, None] + xi[:, None, :]
        row_in, col_in = (ys >= 0) & (ys < H), (xs >= 0) & (xs < W)
        if self._fg_flat is not None and row_in.all() and col_in.all():
            return ys, xs, flat, self._fg_flat.take(flat)  # every sample inside the image
        inside = row_in[:, :, None] & col_in[:, None, :]
        if self._fg_flat is None:
            fg = inside
        else:
            fg = self._fg_flat.take(flat) & inside
        return ys, xs, flat, fg

    @staticmethod
    def _centroids(b: np.ndarray, ys: np.ndarray, xs: np.ndarray, fg: np.ndarray) -> np.ndarray:
        n = fg.sum(axis=(1, 2)).astype(np.float64)
        cx = (fg.sum(axis=1) * xs).sum(1)
        cy = (fg.sum(axis=2) * ys).sum(1)
        centre = b[:, :2] + 0.5 * b[:, 2:]
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(n[:, None] > 0, np.column_stack([cx, cy]) / n[:, None], centre)

    def centroids(self, boxes: np.ndarray) -> np.ndarray:
        """(N, 2) foreground centroid (xc, yc) of each xywh box from its sample grid (the
        box centre where a box has no foreground)."""
        if self._frame is None:
            raise RuntimeError("PartFeatureExtractor.start(frame, foreground) was not called")
        b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        if len(b) == 0:
            return np.zeros((0, 2))
        ys, xs, _, fg = self._grid(b)
        return self._centroids(b, ys, xs, fg)

    def extract_at_centroids(self, boxes: np.ndarray) -> tuple[np.ndarray, PartFeatures]:
        """Centroids of the boxes and their part features split at them (PBM 2.1): the
        same as ``c = centroids(boxes); extract(boxes, *centroid_ratios(boxes, c))``
        with one sample grid.

        Returns:
            (N, 2) centroids and PartFeatures of N boxes.
        """
        if self._frame is None:
            raise RuntimeError("PartFeatureExtractor.start(frame, foreground) was not called")
        b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        if len(b) == 0:
            return np.zeros((0, 2)), PartFeatures.concatenate([], self.bins)
        grid = self._grid(b)
        cents = self._centroids(b, grid[0], grid[1], grid[3])
        alpha, beta = centroid_ratios(b, cents)
        return cents, self._features(b, alpha, beta, grid)

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
        if self._frame is None:
            raise RuntimeError("PartFeatureExtractor.start(frame, foreground) was not called")
        b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        if len(b) == 0:
            return PartFeatures.concatenate([], self.bins)
        return self._features(b, alpha, beta, self._grid(b))

    @staticmethod
    def _bins_of(pix: np.ndarray, code: int, lut: np.ndarray) -> np.ndarray:
        """(M,) joint bin index of a (1, M, 3) uint8 BGR row converted by ``code``
        (``cv2.cvtColor``): per-channel bins by ``cv2.LUT``, summed over the channels by
        ``cv2.transform`` (exact integers)."""
        if pix.size == 0:
            return np.zeros(0, dtype=np.int64)
        return cv2.transform(cv2.LUT(cv2.cvtColor(pix, code), lut), _ONES_1x3).reshape(-1)

    def _features(self, b: np.ndarray, alpha, beta, grid) -> PartFeatures:
        ys, xs, flat, fg = grid
        n, C, P = len(b), self.grid_cols, N_PARTS
        nb = self.bins**3
        parts = part_boxes(b, alpha, beta)
        # the M foreground samples as flat indices into (N, R, C), in row-major order (the
        # order a boolean mask selects them in); every per-sample gather is a ``take``
        idx = np.flatnonzero(fg)
        # colour bins of the foreground samples only (the histograms count nothing else)
        pix = self._pixels.take(flat.reshape(-1).take(idx), axis=0)[None]  # (1, M, 3) BGR: one image row
        hsv_j = self._bins_of(pix, cv2.COLOR_BGR2HSV, self._hsv_lut)
        xyz_j = self._bins_of(pix, cv2.COLOR_BGR2XYZ, self._xyz_lut)
        # part label of every sample (PBM 2.1): head band, torso rows, leg rows; left/right of xc
        head_end = parts[:, 0, 1] + parts[:, 0, 3]
        torso_end = parts[:, 1, 1] + parts[:, 1, 3]
        split = parts[:, 1, 0] + parts[:, 1, 2]
        band = np.where(ys < head_end[:, None], 0, np.where(ys < torso_end[:, None], 1, 3))
        side = (xs >= split[:, None]).astype(np.int64)
        row_key = np.arange(n)[:, None] * P + band  # (N, R): box and band of each row
        key = row_key[:, :, None] + (band > 0)[:, :, None] * side[:, None, :]  # (N, R, C) in 0..N*P
        kf = key.reshape(-1).take(idx)
        cnt = np.bincount(kf, minlength=n * P).astype(np.float64)
        norm = np.maximum(cnt, 1.0)
        kb = kf * nb
        # joint histograms of each (box, part), normalised in place by its foreground count
        h_hsv = np.bincount(kb + hsv_j, minlength=n * P * nb).astype(np.float64).reshape(n, P, nb)
        h_hsv /= norm.reshape(n, P, 1)
        h_xyz = np.bincount(kb + xyz_j, minlength=n * P * nb).astype(np.float64).reshape(n, P, nb)
        h_xyz /= norm.reshape(n, P, 1)
        nr = idx // C  # box * R + row of each foreground sample
        X = xs.reshape(-1).take(nr // fg.shape[1] * C + (idx - nr * C))
        Y = ys.reshape(-1).take(nr)
        cx = np.bincount(kf, weights=X, minlength=n * P)
        cy = np.bincount(kf, weights=Y, minlength=n * P)
        # outline: foreground samples with a background 4-neighbour (outside = background)
        # (samples on the grid border have an outside neighbour: never interior)
        interior = np.zeros_like(fg)
        interior[:, 1:-1, 1:-1] = fg[:, :-2, 1:-1] & fg[:, 2:, 1:-1] & fg[:, 1:-1, :-2] & fg[:, 1:-1, 2:]
        edge = fg & ~interior
        perim = np.bincount(key.reshape(-1).take(np.flatnonzero(edge)), minlength=n * P).astype(np.float64)
        # samples of each part (rows in its band x columns on its side) and its half
        # perimeter in samples (rows in its band + columns on its side)
        rows_band = np.stack([(band == 0).sum(1), (band == 1).sum(1), (band == 3).sum(1)], axis=1)
        cols_right = side.sum(1)
        rows = rows_band[:, [0, 1, 1, 2, 2]]
        cols = np.column_stack([np.full(n, C), C - cols_right, cols_right, C - cols_right, cols_right])
        total = (rows * cols).astype(np.float64).reshape(-1)
        half = (rows + cols).astype(np.float64)
        cen = parts[:, :, :2] + 0.5 * parts[:, :, 2:]
        has = (cnt > 0).reshape(n, P)
        cen = np.where(has[:, :, None], np.stack([cx, cy], axis=1).reshape(n, P, 2)
                       / norm.reshape(n, P, 1), cen)
        return PartFeatures(
            parts,
            (cnt / np.maximum(total, 1.0)).reshape(n, P),
            perim.reshape(n, P) / np.maximum(half, 1.0),
            h_hsv,
            h_xyz,
            cen,
            b[:, 3].copy(),
        )
