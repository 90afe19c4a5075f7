"""Unsupervised scene calibration: the ground-plane perspective learnt from the video.

A camera above a flat floor sees a person whose feet are at image row ``y`` with a height
that is (to first order) linear in ``y`` and vanishes at the horizon row ``y0``:

    h(y) = a * y + b = a * (y - y0),      w(y) = r * h(y)                     (1)

(a pinhole over a ground plane: both height and width scale as 1 / depth, and the foot row
is affine in 1 / depth). ``PerspectiveCalibration`` learns ``a``, ``b`` and the width ratio
``r`` from the foreground alone, without annotations:

1. Samples: connected foreground blobs that look like one well-segmented person
   (``person_like``): inside the frame (not cut by its border), a person's aspect
   (width / height in ``aspect``), filling at least ``min_fill`` of their box, and with a
   head: the top ``1/7`` of the blob (PBM 2.1's head height) is narrower than its shoulders
   (``head_ratio``). Legs, torsos and other fragments have no head on top; groups side by
   side are too wide; a person with its floor reflection is too thin.
2. A robust line through (foot row, height): RANSAC over pairs of samples (seeded, so the
   same samples give the same line), inliers within ``tolerance`` of the line's height,
   refined by least squares on the inliers; ``a > 0`` and a horizon above every inlier and
   above 95% of all samples' feet (a camera above the heads sees nearer people lower in the
   image and larger, and feet only below the horizon).
3. ``r`` is the median width / height of the inliers.

With fewer than ``min_bins`` inliers, or inliers spanning less than ``min_span`` of the
frame's rows, there is too little evidence: ``fit`` returns None and the detector falls back
to searching every height (a warning says so).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from occbench.trackers.common.checks import at_least, coerce, parameter_group, refuse_moved, require
from occbench.trackers.frontend.blobs import Blob

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Perspective:
    """Expected person size as a function of the foot row (eq. 1), full-resolution pixels.

    Attributes:
        a, b: height = a * foot_row + b.
        width_ratio: expected width / height (r).
        samples: inlier samples the line was fitted to.
        bins: distinct foot-row bins (``fit_perspective``'s ``bin_rows``) they occupy.
        spread: median relative deviation |h - h(y)| / h(y) of the inliers (people's own
            height variation plus segmentation noise).
    """

    a: float
    b: float
    width_ratio: float
    samples: int = 0
    bins: int = 0
    spread: float = 0.0

    def height(self, foot_row: np.ndarray | float) -> np.ndarray:
        """Expected person height (pixels) at ``foot_row`` (any shape)."""
        return self.a * np.asarray(foot_row, dtype=np.float64) + self.b

    def width(self, foot_row: np.ndarray | float) -> np.ndarray:
        """Expected person width (pixels) at ``foot_row``."""
        return self.width_ratio * self.height(foot_row)

    @property
    def horizon(self) -> float:
        """Row y0 where the expected height vanishes (above the frame when negative)."""
        return -self.b / self.a if self.a > 0 else float("-inf")

    def describe(self) -> str:
        return (f"person height = {self.a:.3f} * foot_row {self.b:+.1f} px (horizon row "
                f"{self.horizon:.0f}), width = {self.width_ratio:.2f} x height, from "
                f"{self.samples} samples in {self.bins} foot-row bins (median deviation {100 * self.spread:.0f}%)")


def blob_sample(blob: Blob, frame_shape: tuple[int, int], aspect: tuple[float, float] = (0.25, 0.65),
                min_fill: float = 0.5, head_ratio: float = 0.75, border: int = 3,
                min_height: float = 16.0, isolation: float = 0.05) -> tuple[float, float, float] | None:
    """(foot row, height, width) of a blob that looks like one well-segmented person, else None.

    Args:
        blob: a foreground component.
        frame_shape: (H, W) of the frame.
        aspect: [min, max] width / height of a single person.
        min_fill: smallest blob area / box area.
        head_ratio: the head rows (top 1/7 of the box) must be narrower than ``head_ratio``
            times the shoulder rows (1/7 to 2/7 of the box), both as the mean count of
            foreground pixels per row.
        border: pixels from the frame border a blob must keep (cut people are not measured).
        min_height: smallest blob height, pixels.
        isolation: largest share (of the blob's area) of other blobs' pixels allowed in the
            window of half its height above and below and half its width to either side.

    ``blob.labels`` must hold every foreground blob (call ``blobs_from_mask`` with a small
    ``min_area``) for the isolation test to see them.
    """
    H, W = frame_shape
    x, y, w, h = blob.box
    if h < min_height or not aspect[0] <= w / h <= aspect[1]:
        return None
    if y < border or x < border or y + h > H - border or x + w > W - border:
        return None
    if blob.area < min_fill * w * h:
        return None
    # isolated: no other foreground within half its height above and below and half its
    # width aside (a floor reflection has its person above it, a fragment its other parts)
    x0, x1 = int(max(x - w / 2, 0)), int(min(x + 1.5 * w, W))
    y0, y1 = int(max(y - h / 2, 0)), int(min(y + 1.5 * h, H))
    win = blob.labels[y0:y1, x0:x1]
    if np.count_nonzero(win) - np.count_nonzero(win == blob.label) > isolation * blob.area:
        return None
    crop = blob.crop_mask()
    k = max(int(round(h / 7)), 1)
    head = crop[:k].sum(axis=1).mean()
    shoulders = crop[k : 2 * k].sum(axis=1).mean()
    if head >= head_ratio * shoulders:
        return None
    return float(y + h), float(h), float(w)


def fit_perspective(feet: np.ndarray, heights: np.ndarray, widths: np.ndarray,
                    frame_height: int, tolerance: float = 0.15, min_bins: int = 6,
                    min_span: float = 0.15, bin_rows: float = 0.02, iterations: int = 500,
                    seed: int = 0, horizon_above: float = 0.5,
                    ) -> Perspective | None:
    """RANSAC line height = a * foot + b (eq. 1) through person samples, then least squares
    on the inliers; None when the evidence is too thin (see the module docstring).

    Args:
        feet, heights, widths: (N,) samples, pixels.
        frame_height: rows of the frame (``min_span`` is a fraction of it).
        tolerance: inlier band, relative to the line's height at the sample's row.
        min_bins: fewest distinct foot-row bins holding inliers (the evidence counted).
        min_span: smallest foot-row span of the inliers, fraction of the frame height.
        bin_rows: height of a foot-row bin, fraction of the frame height.
        iterations: RANSAC pairs drawn.
        seed: seed of the pair draws.
        horizon_above: the horizon row may lie at most this many frame heights above the
            frame's top (a perspective prior: people at the bottom of the frame are at least
            (1 + 1 / horizon_above) times as tall as at its top; a camera looking
            straight down has no usable line and gets the fallback).
    """
    y = np.asarray(feet, dtype=np.float64)
    h = np.asarray(heights, dtype=np.float64)
    w = np.asarray(widths, dtype=np.float64)
    n = len(y)
    if n < min_bins:
        return None
    rng = np.random.default_rng(seed)
    i, j = rng.integers(0, n, size=(2, iterations))
    dy = y[j] - y[i]
    ok = np.abs(dy) >= 0.05 * frame_height
    i, j, dy = i[ok], j[ok], dy[ok]
    if len(i) == 0:
        return None
    a = (h[j] - h[i]) / dy
    b = h[i] - a * y[i]
    good = a > 0
    a, b = a[good], b[good]
    if len(a) == 0:
        return None
    # a line's support is the number of distinct foot-row bins its inliers occupy: a person
    # standing still gives hundreds of identical samples but one piece of evidence
    bins = np.floor(y / max(bin_rows * frame_height, 1.0)).astype(np.int64)
    bins -= bins.min()
    nb = int(bins.max()) + 1
    pred = a[:, None] * y[None, :] + b[:, None]  # (pairs, N)
    inl = (pred > 0) & (np.abs(h[None, :] - pred) <= tolerance * np.maximum(pred, 1e-6))
    # a horizon far above the image (a near-flat line: people as tall at the bottom of the
    # frame as at the top) is not a surveillance camera's view of a floor (``horizon_above``)
    occupied = np.zeros((len(a), nb), dtype=bool)
    rows, cols = np.nonzero(inl)
    occupied[rows, bins[cols]] = True
    # feet are seen only below the horizon: it must lie above (nearly) every sampled foot
    # row, outliers included (a line through merges may fit many rows yet put the horizon
    # below where people are seen walking)
    top_foot = float(np.quantile(y, 0.05))
    horizon = -b / a
    plausible = (horizon >= -horizon_above * frame_height) & (horizon < top_foot)
    support = np.where(plausible, occupied.sum(axis=1), -1)
    best = int(np.argmax(support))
    keep = inl[best]
    for _ in range(2):  # least squares on the bins' median inliers, inliers again
        ub = np.unique(bins[keep])
        if len(ub) < 2:
            return None
        yb = np.array([np.median(y[keep & (bins == k)]) for k in ub])
        hb = np.array([np.median(h[keep & (bins == k)]) for k in ub])
        a1, b1 = np.polyfit(yb, hb, 1)
        pred1 = a1 * y + b1
        keep = (pred1 > 0) & (np.abs(h - pred1) <= tolerance * np.maximum(pred1, 1e-6))
    nbins = len(np.unique(bins[keep]))
    if a1 <= 0 or nbins < min_bins or np.ptp(y[keep]) < min_span * frame_height:
        return None
    if not -horizon_above * frame_height <= -b1 / a1 < min(y[keep].min(), top_foot):
        return None
    spread = float(np.median(np.abs(h[keep] - pred1[keep]) / pred1[keep]))
    return Perspective(float(a1), float(b1), float(np.median(w[keep] / h[keep])),
                       int(keep.sum()), nbins, spread)


@dataclass(frozen=True)
class PersonBlobs:
    """Which foreground blobs are sampled as one well-segmented person (``blob_sample``).

    Args:
        aspect: [min, max] width / height of a single person.
        min_fill: smallest blob area / box area.
        head_ratio: head rows narrower than this times the shoulder rows.
        min_height: smallest blob height sampled, pixels.
    """

    aspect: tuple[float, float] = (0.25, 0.65)
    min_fill: float = 0.5
    head_ratio: float = 0.75
    min_height: float = 16.0

    def __post_init__(self) -> None:
        lo, hi = (float(v) for v in self.aspect)
        require("calibration.people.aspect", 0 < lo < hi, "must be [min, max] with 0 < min < max",
                list(self.aspect))
        require("calibration.people.min_fill", 0 < self.min_fill <= 1, "must lie in (0, 1]",
                self.min_fill)
        require("calibration.people.head_ratio", 0 < self.head_ratio <= 1, "must lie in (0, 1]",
                self.head_ratio)
        object.__setattr__(self, "aspect", (lo, hi))
        coerce(self, {"min_fill": float, "head_ratio": float, "min_height": float})


@dataclass(frozen=True)
class LineFit:
    """The robust line through the samples and when it is accepted (``fit_perspective``).

    Args:
        tolerance: RANSAC inlier band, relative height.
        min_bins: fewest foot-row bins with inliers for a calibration (else: none, the
            fallback).
        min_span: smallest foot-row span of the inliers, fraction of the frame height.
        horizon_above: see ``fit_perspective``.
        seed: RANSAC seed.
    """

    tolerance: float = 0.15
    min_bins: int = 6
    min_span: float = 0.15
    horizon_above: float = 0.5
    seed: int = 0

    def __post_init__(self) -> None:
        require("calibration.line.tolerance", 0 < self.tolerance < 1, "must lie in (0, 1)",
                self.tolerance)
        at_least("calibration.line", 2, min_bins=self.min_bins)
        require("calibration.line.horizon_above", self.horizon_above > 0, "must be > 0",
                self.horizon_above)
        coerce(self, {"tolerance": float, "min_bins": int, "min_span": float,
                      "horizon_above": float, "seed": int})


#: the calibration's groups: its argument -> the group's class
GROUPS = {"people": PersonBlobs, "line": LineFit}


class PerspectiveCalibration:
    """Collects person-like blob samples frame by frame and fits the perspective (eq. 1).

    Args:
        people: which blobs are sampled as people (``PersonBlobs``; None: its defaults).
        line: the line through them and its acceptance (``LineFit``; None: its defaults).
        A key of the flat arguments before the groups is refused with a TypeError naming
        its group.
    """

    def __init__(self, people: PersonBlobs | None = None, line: LineFit | None = None,
                 **moved: object) -> None:
        refuse_moved("calibration", moved, GROUPS)
        self.people = parameter_group("people", people, PersonBlobs)
        self.line = parameter_group("line", line, LineFit)
        self.reset()

    def reset(self) -> None:
        self.samples: list[tuple[float, float, float]] = []
        self.frame_height = 0

    def collect(self, blobs: list[Blob], frame_shape: tuple[int, int]) -> int:
        """Add the person-like blobs of one frame; returns how many were added."""
        self.frame_height = int(frame_shape[0])
        n0 = len(self.samples)
        p = self.people
        for b in blobs:
            s = blob_sample(b, frame_shape, p.aspect, p.min_fill, p.head_ratio,
                            min_height=p.min_height)
            if s is not None:
                self.samples.append(s)
        return len(self.samples) - n0

    def fit(self) -> Perspective | None:
        """The perspective of the samples so far, or None (too little evidence)."""
        if not self.samples:
            return None
        s = np.asarray(self.samples, dtype=np.float64)
        f = self.line
        return fit_perspective(s[:, 0], s[:, 1], s[:, 2], self.frame_height, f.tolerance,
                               f.min_bins, f.min_span, seed=f.seed,
                               horizon_above=f.horizon_above)


def active_area(frames: list[np.ndarray], flat: float = 2.0) -> tuple[int, int, int, int]:
    """(top, bottom, left, right) bounds of the live picture: rows and columns at the frame's
    edges that are flat in the mean of ``frames`` (a letterbox or padding strip: CAVIAR's
    frames end in 4 uniform grey rows) are not part of the scene, and a blob touching them
    is cut by the picture's border.

    Args:
        frames: (H, W, 3) uint8 images sampled over the sequence.
        flat: largest spatial standard deviation (grey levels) of a dead line of the mean image.
    Returns:
        rows [top, bottom) and columns [left, right) of the live picture (the whole frame
        when no frame is given or every line is flat).
    """
    if not frames:
        return 0, 0, 0, 0
    mean = np.mean([f.mean(axis=2) if f.ndim == 3 else f for f in frames], axis=0)
    H, W = mean.shape
    live_r = np.flatnonzero(mean.std(axis=1) > flat)
    live_c = np.flatnonzero(mean.std(axis=0) > flat)
    if len(live_r) == 0 or len(live_c) == 0:
        return 0, H, 0, W
    return int(live_r[0]), int(live_r[-1]) + 1, int(live_c[0]), int(live_c[-1]) + 1
