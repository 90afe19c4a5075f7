"""Connected components of a foreground mask as blobs (PBM 2).

A blob carries its component mask (as the label number into a shared label image), its
bounding box (xywh, 0-based, float64), centroid, area and perimeter. Everything comes from
one ``cv2.connectedComponentsWithStats`` call and one ``cv2.findContours`` per blob crop.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass
class Blob:
    """One connected foreground component.

    Attributes:
        label: component number k >= 1 in ``labels`` (pixels == k belong to the blob).
        labels: (H, W) int32 label image shared by all blobs of one call (0 = background).
        box: (4,) float64 xywh bounding box, pixels, 0-based top-left.
        centroid: (2,) float64 (x, y) centre of mass in pixel coordinates (pixel centres
            at integer + 0.5, so a one-pixel blob at (0, 0) has centroid (0.5, 0.5)).
        area: number of pixels.
        perimeter: length of the outer contour in pixels (``cv2.arcLength``, closed).
    """

    label: int
    labels: np.ndarray
    box: np.ndarray
    centroid: np.ndarray
    area: int
    perimeter: float

    @property
    def mask(self) -> np.ndarray:
        """(H, W) bool mask of the blob's pixels (full frame)."""
        return self.labels == self.label

    def crop_mask(self) -> np.ndarray:
        """(h, w) bool mask restricted to the blob's bounding box."""
        x, y, w, h = (int(v) for v in self.box)
        return self.labels[y : y + h, x : x + w] == self.label


def blobs_from_mask(
    mask: np.ndarray, min_area: int = 1, connectivity: int = 8, perimeter: bool = True
) -> list[Blob]:
    """Connected components of a foreground mask or label image.

    Args:
        mask: (H, W) bool/uint8 mask, or an integer label image: any nonzero pixel is
            foreground (a label image is NOT split by its label values; components are
            recomputed).
        min_area: smallest blob kept, in pixels.
        connectivity: 4 or 8.
        perimeter: compute contour perimeters (one findContours per blob crop).
    Returns:
        Blobs sorted by decreasing area; their ``labels`` is one shared (H, W) int32 image
        numbered 1..len(blobs) in that order (components under ``min_area`` are 0).
    """
    m = np.asarray(mask)
    if m.ndim != 2:
        raise ValueError(f"blobs_from_mask: mask must be 2-D (H, W), got shape {m.shape}")
    if connectivity not in (4, 8):
        raise ValueError(f"blobs_from_mask: connectivity must be 4 or 8, got {connectivity}")
    fg = m.view(np.uint8) if m.dtype == np.bool_ else (m != 0).astype(np.uint8)
    H, W = fg.shape
    labels = np.zeros((H, W), dtype=np.int32)
    # label only the bounding rectangle of the foreground (usually a small part of a frame)
    rows, cols = np.flatnonzero(fg.any(axis=1)), np.flatnonzero(fg.any(axis=0))
    if len(rows) == 0:
        return []
    r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    n, lab, stats, cents = cv2.connectedComponentsWithStatsWithAlgorithm(
        np.ascontiguousarray(fg[r0:r1, c0:c1]), connectivity, cv2.CV_32S, cv2.CCL_GRANA
    )
    stats[:, 0] += c0
    stats[:, 1] += r0
    cents += (c0, r0)
    areas = stats[1:, cv2.CC_STAT_AREA]
    keep = np.flatnonzero(areas >= max(int(min_area), 1)) + 1
    keep = keep[np.argsort(-stats[keep, cv2.CC_STAT_AREA], kind="stable")]
    lut = np.zeros(n, dtype=np.int32)
    lut[keep] = np.arange(1, len(keep) + 1, dtype=np.int32)
    labels[r0:r1, c0:c1] = np.take(lut, lab)
    blobs: list[Blob] = []
    for new, old in enumerate(keep, 1):
        x, y, w, h, area = (int(v) for v in stats[old])
        per = 0.0
        if perimeter:
            crop = (labels[y : y + h, x : x + w] == new).astype(np.uint8)
            contours, _ = cv2.findContours(crop, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
            per = float(sum(cv2.arcLength(c, True) for c in contours))
        blobs.append(
            Blob(
                label=new,
                labels=labels,
                box=np.array([x, y, w, h], dtype=np.float64),
                centroid=cents[old].astype(np.float64) + 0.5,
                area=area,
                perimeter=per,
            )
        )
    return blobs


def blob_boxes(blobs: list[Blob]) -> np.ndarray:
    """(N, 4) float64 xywh boxes of ``blobs``."""
    if not blobs:
        return np.zeros((0, 4))
    return np.stack([b.box for b in blobs])
