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
    out = np.empty((n, N_PARTS, 4))
    out[:, 0] = np.column_stack([x, y, w, hh])
    out[:, 1] = np.column_stack([x, y + hh, xs - x, ys - y - hh])
    out[:, 2] = np.column_stack([xs, y + hh, x + w - xs, ys - y - hh])
    out[:, 3] = np.column_stack([x, ys, xs - x, y + h - ys])
    out[:, 4] = np.column_stack([xs, ys, x + w - xs, y + h - ys])
    return out


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


class _Region:
    """Quantised colours, foreground and outline of one image crop (computed once)."""

    __slots__ = ("x0", "y0", "hsv", "xyz", "fg", "edge")

    def __init__(self, frame: np.ndarray, fg: np.ndarray | None, x0: int, y0: int, x1: int,
                 y1: int, bins: int) -> None:
        self.x0, self.y0 = x0, y0
        crop = frame[y0:y1, x0:x1]
        hsv = cv2.cvtColor(crop, cv2.COLOR_BGR2HSV)
        xyz = cv2.cvtColor(crop, cv2.COLOR_BGR2XYZ)
        self.hsv = _joint_index(hsv, bins, (180.0, 256.0, 256.0))
        self.xyz = _joint_index(xyz, bins, (256.0, 256.0, 256.0))
        if fg is None:
            f = np.ones(crop.shape[:2], dtype=np.uint8)
            self.fg = f
            e = np.zeros_like(f)
            e[0, :] = e[-1, :] = 1
            e[:, 0] = e[:, -1] = 1
            self.edge = e
        else:
            f = np.ascontiguousarray(fg[y0:y1, x0:x1]).view(np.uint8)
            self.fg = f
            # outline = foreground with a background 4-neighbour (outside the image = bg)
            er = cv2.erode(f, _CROSS, borderType=cv2.BORDER_CONSTANT, borderValue=0)
            self.edge = f - er


_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))


def _joint_index(img: np.ndarray, bins: int, ranges: tuple[float, float, float]) -> np.ndarray:
    """(h, w) int64 joint bin index of a 3-channel uint8 image (as colour_histogram)."""
    q = [np.minimum((img[..., c].astype(np.int64) * bins) // int(ranges[c]), bins - 1)
         for c in range(3)]
    return (q[0] * bins + q[1]) * bins + q[2]


class PartFeatureExtractor:
    """Per-frame part features: colour conversion once per region, bincounts per box.

    Usage: ``ex = PartFeatureExtractor(bins); ex.start(frame, fg)`` once per frame, then
    ``ex.extract(boxes, alpha, beta, region=...)`` as often as needed. Boxes extracted with
    the same ``region`` (an xywh box that contains them, e.g. a foreground blob) share one
    HSV/XYZ conversion of that region: the head-anchored search of PBM 3.1 evaluates 25
    sizes per head at the cost of bincounts only.

    Args:
        bins: histogram bins per channel (joint histograms have ``bins**3`` bins).
    """

    def __init__(self, bins: int = 4) -> None:
        if bins < 1 or bins > 32:
            raise ValueError(f"bins must be in 1..32, got {bins}")
        self.bins = bins
        self._frame: np.ndarray | None = None
        self._fg: np.ndarray | None = None
        self._cache: dict[tuple[int, int, int, int], _Region] = {}

    def start(self, frame: np.ndarray, foreground: np.ndarray | None) -> None:
        """Set the frame ((H, W, 3) uint8 BGR) and foreground ((H, W) bool or None = all)."""
        if frame is None or frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ValueError("frame must be an (H, W, 3) uint8 BGR image")
        if foreground is not None and foreground.shape != frame.shape[:2]:
            raise ValueError(
                f"foreground shape {foreground.shape} differs from frame {frame.shape[:2]}")
        self._frame = frame
        self._fg = None if foreground is None else np.asarray(foreground, dtype=bool)
        self._cache = {}

    def _region(self, box: np.ndarray) -> _Region:
        H, W = self._frame.shape[:2]
        x, y, w, h = box
        x0 = min(max(int(np.floor(x)), 0), W - 1)
        y0 = min(max(int(np.floor(y)), 0), H - 1)
        x1 = max(min(int(np.ceil(x + w)), W), x0 + 1)
        y1 = max(min(int(np.ceil(y + h)), H), y0 + 1)
        key = (x0, y0, x1, y1)
        reg = self._cache.get(key)
        if reg is None:
            reg = _Region(self._frame, self._fg, x0, y0, x1, y1, self.bins)
            self._cache[key] = reg
        return reg

    def extract(
        self,
        boxes: np.ndarray,
        alpha: np.ndarray | float = DEFAULT_ALPHA,
        beta: np.ndarray | float = DEFAULT_BETA,
        region: np.ndarray | None = None,
    ) -> PartFeatures:
        """Part features of (N, 4) xywh boxes (PBM 2.2).

        Args:
            boxes: (N, 4) person boxes. alpha, beta: centroid ratios, (N,) or scalar.
            region: optional (4,) xywh box holding all ``boxes``: one colour conversion for
                all of them; pixels of a box outside the region count as background.
        Returns:
            PartFeatures of N boxes.
        """
        if self._frame is None:
            raise RuntimeError("PartFeatureExtractor.start(frame, foreground) was not called")
        b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        n = len(b)
        nb = self.bins**3
        parts = part_boxes(b, alpha, beta)
        area = np.zeros((n, N_PARTS))
        perim = np.zeros((n, N_PARTS))
        hsv = np.zeros((n, N_PARTS, nb))
        xyz = np.zeros((n, N_PARTS, nb))
        cen = parts[:, :, :2] + 0.5 * parts[:, :, 2:]
        shared = None if region is None else self._region(np.asarray(region, dtype=np.float64))
        for k in range(n):
            reg = shared if shared is not None else self._region(b[k])
            rh, rw = reg.fg.shape
            # box and split lines in region pixel coordinates
            x, y, w, h = b[k]
            c0 = min(max(int(round(x)) - reg.x0, 0), rw)
            c1 = min(max(int(round(x + w)) - reg.x0, c0), rw)
            r0 = min(max(int(round(y)) - reg.y0, 0), rh)
            r1 = min(max(int(round(y + h)) - reg.y0, r0), rh)
            if c1 <= c0 or r1 <= r0:
                continue
            p = parts[k]
            head_end = int(round(p[0, 1] + p[0, 3])) - reg.y0
            torso_end = int(round(p[1, 1] + p[1, 3])) - reg.y0
            split = int(round(p[1, 0] + p[1, 2])) - reg.x0
            rows = np.arange(r0, r1)
            cols = np.arange(c0, c1)
            band = np.where(rows < head_end, 0, np.where(rows < torso_end, 1, 3))
            side = (cols >= split).astype(np.int64)
            label = band[:, None] + np.where(band[:, None] == 0, 0, side[None, :])  # (h, w)
            fg = reg.fg[r0:r1, c0:c1]
            lab = label[fg.astype(bool)]
            if lab.size:
                cnt = np.bincount(lab, minlength=N_PARTS).astype(np.float64)
                yy, xx = np.nonzero(fg)
                sx = np.bincount(lab, weights=xx + c0 + reg.x0 + 0.5, minlength=N_PARTS)
                sy = np.bincount(lab, weights=yy + r0 + reg.y0 + 0.5, minlength=N_PARTS)
                has = cnt > 0
                cen[k, has, 0] = sx[has] / cnt[has]
                cen[k, has, 1] = sy[has] / cnt[has]
                hs = np.bincount(lab * nb + reg.hsv[r0:r1, c0:c1][fg.astype(bool)],
                                 minlength=N_PARTS * nb).reshape(N_PARTS, nb)
                xz = np.bincount(lab * nb + reg.xyz[r0:r1, c0:c1][fg.astype(bool)],
                                 minlength=N_PARTS * nb).reshape(N_PARTS, nb)
                norm = np.maximum(cnt, 1.0)[:, None]
                hsv[k] = hs / norm
                xyz[k] = xz / norm
                e = reg.edge[r0:r1, c0:c1].astype(bool)
                perim[k] = np.bincount(label[e], minlength=N_PARTS)
                area[k] = cnt
        size = parts[:, :, 2] * parts[:, :, 3]
        with np.errstate(invalid="ignore", divide="ignore"):
            area = np.where(size > 0, area / np.maximum(size, 1e-9), 0.0)
            perim = perim / np.maximum(parts[:, :, 2] + parts[:, :, 3], 1.0)
        return PartFeatures(parts, np.clip(area, 0.0, 1.0), perim, hsv, xyz, cen, b[:, 3].copy())
