"""When the person model does not fit the camera: notice it, say so, detect regions instead.

The silhouette detector assumes upright people whose height grows with the foot row (a
camera above a floor, ``calibration.Perspective``). A wide-angle camera looking down (the
CAVIAR lobby) breaks both: people are seen from above, often wider than tall. Two pieces:

``CameraFitCheck`` decides, from the warm-up's evidence (``FitEvidence``), whether the person
model fits: it does not when the template fits made on the calibration frames explain too
little of the foreground (share of foreground pixels inside a fitted template box), whether
or not the calibration found a line. Its verdict is one line naming what is wrong and what the
front end does instead.

``RegionDetector`` is what it falls back to: foreground regions, with no person shape, on a
background model that can start with people in view (``MedianBackground``), grouped into
person-sized boxes whose size is learnt from the scene as it runs (no ground truth):

* background (``MedianBackground``): the per-pixel median of the first ``init_frames``
  frames (the only frames read ahead: a live camera would start reporting ``init_frames``
  frames late; nothing after them is read before its turn), then a running average updated
  every frame, fast where the frame is background and slow where it is foreground (a person
  standing in the first frames leaves a ghost that fades in about 1 / ``slow_rate`` frames;
  glare pixels are not learnt);
  the threshold is ``k_sigma`` times each pixel's noise (robust spread of the first frames),
  at least ``min_difference`` grey levels;
* glare: a pixel saturated (any channel >= ``saturation``) in the frame or the background, or
  within the blur's reach of one, is never foreground, nor is a pixel that only got brighter with its colour unchanged
  (chromaticity within ``chroma_tolerance``): sun and window glare;
* regions: connected components after an opening and a closing; fragments whose boxes lie
  within ``merge_gap`` person sizes of each other are merged; optionally a region more than
  ``split_ratio`` times the typical person area is split into round(area / typical) boxes
  (k-means on its pixel coordinates, seeded); the typical person area is the running median of
  the areas of the regions reported so far (starting at ``initial_area``).

From the clip alone it finds people who move; people who stay where they are in the first
frames are part of any background learnt from the clip itself. Given other footage of the
same camera (``footage``: ``occbench.trackers.frontend.footage``, images only), the background starts
from the footage's empty floor where the clip shows something steady on it, so that they are
found too.

Plain numpy and OpenCV. Measurement history lives in docs/generalisation.md ("lobby").
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from occbench.trackers.common.checks import at_least, parameter_group, refuse_moved, require
from occbench.trackers.frontend.fallback_params import (
    BACKGROUND_GROUPS,
    GROUPS,
    DifferenceThreshold,
    Glare,
    MaskMorphology,
    RegionFilter,
    RegionGrouping,
    UpdateRates,
)
from occbench.trackers.frontend.footage import CameraBackground, start_with
from occbench.trackers.frontend.regions import merge_near, split_kmeans
from occbench.trackers.records import Detections

log = logging.getLogger(__name__)


@dataclass
class FitEvidence:
    """How well the person model's fits explain the foreground of the calibration frames.

    Attributes:
        frames: calibration frames seen.
        busy_frames: frames with at least ``min_area`` foreground pixels in regions.
        foreground: foreground pixels in regions of at least ``min_area`` pixels, summed.
        explained: those inside a fitted template box, summed.
        min_area: smallest region counted, pixels.
    """

    frames: int = 0
    busy_frames: int = 0
    foreground: int = 0
    explained: int = 0
    min_area: int = 40

    def add(self, fg: np.ndarray, boxes: np.ndarray) -> None:
        """One frame: ``fg`` (H, W) bool foreground, ``boxes`` (N, 4) xywh fitted template
        boxes in the same pixel frame."""
        self.frames += 1
        m = np.asarray(fg).astype(np.uint8)
        _, lab, stats, _ = cv2.connectedComponentsWithStats(m, 8)
        big = np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] >= self.min_area) + 1
        if not len(big):
            return
        regions = np.isin(lab, big)
        count = int(regions.sum())
        self.busy_frames += 1
        self.foreground += count
        inside = np.zeros_like(regions)
        H, W = regions.shape
        for x, y, w, h in np.asarray(boxes, dtype=np.float64).reshape(-1, 4):
            r0, r1 = max(int(y), 0), min(int(np.ceil(y + h)), H)
            c0, c1 = max(int(x), 0), min(int(np.ceil(x + w)), W)
            if r1 > r0 and c1 > c0:
                inside[r0:r1, c0:c1] = True
        self.explained += int((regions & inside).sum())

    @property
    def explained_share(self) -> float:
        """Share of the counted foreground inside fitted boxes (nan without foreground)."""
        return self.explained / self.foreground if self.foreground else float("nan")


class CameraFitCheck:
    """Does the person model fit this camera? (see the module docstring)

    Args:
        min_explained: smallest share of the foreground the fits must explain.
        min_busy_frames: fewest calibration frames with foreground for a verdict (with fewer,
            the scene is too empty to judge and the model is kept).
    """

    def __init__(self, min_explained: float = 0.5, min_busy_frames: int = 10) -> None:
        require("fit_check.min_explained", 0.0 < min_explained <= 1.0, "must lie in (0, 1]",
                min_explained)
        at_least("fit_check", 1, min_busy_frames=min_busy_frames)
        self.min_explained = float(min_explained)
        self.min_busy_frames = int(min_busy_frames)

    def misfit(self, calibrated: bool, evidence: FitEvidence) -> str | None:
        """Why the person model does not fit (one line), or None when it fits or the
        evidence is too thin to say."""
        if evidence.busy_frames < self.min_busy_frames:
            return None
        share = evidence.explained_share
        if share >= self.min_explained:
            return None
        calib = ("found a ground-plane line" if calibrated
                 else "found no consistent upright people")
        return (f"the upright-person model does not fit this camera: calibration {calib}, and "
                f"the template fits explain {100 * share:.0f}% of the foreground of "
                f"{evidence.busy_frames} calibration frames (< {100 * self.min_explained:.0f}%)")


class MedianBackground:
    """Background from the median of the first frames, then a selective running average;
    glare-blind difference (see the module docstring). Frames (H, W, 3) uint8 BGR.

    Args:
        init_frames: frames whose per-pixel median starts the background.
        rates: how fast it learns (``fallback_params.UpdateRates``).
        threshold: when a pixel differs from it (``DifferenceThreshold``).
        glare: which pixels are glare, never foreground (``Glare``).
        morphology: the mask's opening and closing (``MaskMorphology``).
        footage: the camera's background learnt from its other footage
            (``footage.CameraBackground``; None: the clip's own median only). With it the
            clip starts from ``footage.start_with``: the footage's background where the clip's
            own median differs from it on steady floor (someone standing still).
        steady_spread: the footage's spread (grey levels) above which the clip's own median
            is kept (glare and lighting the other clips disagree on).
        Each group is its defaults when None; a key of the flat arguments before the groups
        is refused with a TypeError naming its group.
    """

    def __init__(self, init_frames: int = 100, rates: UpdateRates | None = None,
                 threshold: DifferenceThreshold | None = None, glare: Glare | None = None,
                 morphology: MaskMorphology | None = None,
                 footage: CameraBackground | None = None, steady_spread: float = 8.0,
                 **moved: object) -> None:
        g = "fallback.background"
        refuse_moved(g, moved, BACKGROUND_GROUPS)
        at_least(g, 1, init_frames=init_frames)
        at_least(g, 0, steady_spread=steady_spread)
        self.init_frames = int(init_frames)
        self.rates = parameter_group("rates", rates, UpdateRates)
        self.threshold = parameter_group("threshold", threshold, DifferenceThreshold)
        self.glare = parameter_group("glare", glare, Glare)
        self.morphology = parameter_group("morphology", morphology, MaskMorphology)
        self._open = _ellipse(self.morphology.open_kernel)
        self._close = _ellipse(self.morphology.close_kernel)
        self.footage, self.steady_spread = footage, float(steady_spread)
        self.reset()

    def reset(self) -> None:
        self.background: np.ndarray | None = None  # (H, W, 3) float32
        self.noise: np.ndarray | None = None  # (H, W) float32
        self.from_footage = 0.0  # share of the starting background taken from the footage
        self.unsteady: np.ndarray | None = None  # (H, W) bool: footage spread > steady_spread

    def describe(self) -> str:
        """Where the background starts from, in a few words (for the log line)."""
        if self.footage is None:
            return f"a background from the clip's own first {self.init_frames} frames"
        return (f"a background learnt from other footage of this camera ({self.footage.label}) "
                f"and the clip's own first {self.init_frames} frames")

    def _smooth(self, frame: np.ndarray) -> np.ndarray:
        b = self.threshold.blur
        f = cv2.GaussianBlur(frame, (b, b), 0) if b > 1 else frame
        return f.astype(np.float32)

    def start(self, frames: list[np.ndarray]) -> None:
        """The median of ``frames`` (the first ``init_frames`` of the sequence) and each
        pixel's noise."""
        if not frames:
            raise ValueError("MedianBackground.start: no frames")
        stack = np.stack([self._smooth(f) for f in frames])
        self.background = np.median(stack, axis=0)
        grey = stack.mean(axis=3)
        mad = np.median(np.abs(grey - np.median(grey, axis=0)), axis=0)
        self.noise = np.maximum(1.4826 * mad, 1.0).astype(np.float32)
        if self.footage is not None:
            img, t = self.footage.image, self.threshold
            pooled = replace(self.footage, image=cv2.GaussianBlur(img, (t.blur, t.blur), 0)
                             if t.blur > 1 else img)
            threshold = np.maximum(t.k_sigma * self.noise, t.min_difference)
            self.background, taken = start_with(pooled, self.background, threshold,
                                                self.steady_spread)
            self.from_footage = float(taken.mean())
            self.unsteady = pooled.spread > self.steady_spread
            log.info("background footage (%s) taken on %.1f%% of the picture (where the clip "
                     "shows something steady on the footage's empty floor)",
                     self.footage.label, 100 * self.from_footage)

    def apply(self, frame: np.ndarray) -> np.ndarray:
        """(H, W) bool foreground of ``frame``; then the background learns from it."""
        if self.background is None:
            self.start([frame])
        img = self._smooth(frame)
        B, t, sat = self.background, self.threshold, self.glare.saturation
        diff = np.abs(img - B).max(axis=2)
        fg = diff > np.maximum(t.k_sigma * self.noise, t.min_difference)
        glare = (frame.max(axis=2) >= sat) | (B.max(axis=2) >= sat)
        if self.glare.chroma_tolerance > 0:
            s_img, s_bg = img.sum(axis=2) + 1.0, B.sum(axis=2) + 1.0
            chroma = np.abs(img / s_img[..., None] - B / s_bg[..., None]).max(axis=2)
            glare |= (s_img > s_bg) & (chroma <= self.glare.chroma_tolerance)
        if t.blur > 1:  # the blur spreads glare onto its neighbours
            glare = cv2.dilate(glare.view(np.uint8), _ellipse(t.blur)).view(bool)
        mask = (fg & ~glare).astype(np.uint8)
        if self._open is not None:
            mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, self._open)
        if self._close is not None:
            mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, self._close)
        fgm = mask.astype(bool) & ~glare  # the closing must not bridge into glare
        rate = np.where(fgm, self.rates.slow_rate, self.rates.fast_rate).astype(np.float32)
        rate[glare] = 0.0  # glare teaches the background nothing
        rate = rate[..., None]
        B += rate * (img - B)
        return fgm


def _ellipse(size: int) -> np.ndarray | None:
    """The elliptic kernel of ``size`` (None: 0/1, no morphology)."""
    return None if size <= 1 else cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size))


@dataclass
class RegionSizes:
    """Running median of the areas of reported regions: the scene's typical person area.

    Attributes:
        initial_area: typical area before any region is seen, pixels.
        window: most recent areas kept.
    """

    initial_area: float = 600.0
    window: int = 500
    areas: list[float] = field(default_factory=list)

    def typical(self) -> float:
        return float(np.median(self.areas)) if self.areas else self.initial_area

    def add(self, area: float) -> None:
        self.areas.append(float(area))
        if len(self.areas) > self.window:
            del self.areas[0]


class RegionDetector:
    """Foreground regions as person-sized boxes (the fallback; see the module docstring).

    Args:
        background: the ``MedianBackground`` (None: its defaults).
        regions: which regions are kept (``fallback_params.RegionFilter``).
        grouping: how they become person-sized boxes (``fallback_params.RegionGrouping``).
        Each group is its defaults when None; a key of the flat arguments before the groups
        is refused with a TypeError naming its group.
    """

    @property
    def name(self) -> str:
        return (f"foreground regions (occbench.trackers.frontend.fallback.RegionDetector) on "
                f"{self.background.describe()}")

    def __init__(self, background: MedianBackground | None = None,
                 regions: RegionFilter | None = None, grouping: RegionGrouping | None = None,
                 **moved: object) -> None:
        refuse_moved("fallback", moved, GROUPS)
        self.background = background if background is not None else MedianBackground()
        self.regions = parameter_group("regions", regions, RegionFilter)
        self.grouping = parameter_group("grouping", grouping, RegionGrouping)
        self.reset()

    def reset(self) -> None:
        self.background.reset()
        self.sizes = RegionSizes(self.grouping.initial_area)

    def warm_up_sequence(self, length: int, frame: Callable[[int], np.ndarray | None]) -> None:
        """Start the background from frames 1..min(init_frames, length) (1-based)."""
        first = [frame(k) for k in range(1, min(self.background.init_frames, length) + 1)]
        first = [f for f in first if f is not None]
        if first:
            self.background.start(first)

    def detect(self, frame: np.ndarray) -> tuple[Detections, np.ndarray]:
        fg = self.background.apply(frame)
        return self.detect_on(frame, fg), fg

    def _unsteady(self, mask: np.ndarray) -> bool:
        """The region lies mostly where the footage's clips disagree (glare, plants)."""
        zone, most = self.background.unsteady, self.regions.max_unsteady
        return most < 1.0 and zone is not None and zone[mask].mean() > most

    def detect_on(self, frame: np.ndarray, fg: np.ndarray) -> Detections:
        n, lab, stats, _ = cv2.connectedComponentsWithStats(fg.astype(np.uint8), 8)
        typical = self.sizes.typical()
        kept, grouping = self.regions, self.grouping
        floor = max(kept.min_area, kept.min_share * typical)
        keep = [i for i in range(1, n) if stats[i, cv2.CC_STAT_AREA] >= kept.min_area]
        groups = merge_near(stats, keep, grouping.merge_gap * np.sqrt(typical))
        boxes: list[np.ndarray] = []
        labels = np.zeros(fg.shape, dtype=np.int32)
        for g in groups:
            area = float(stats[g, cv2.CC_STAT_AREA].sum())
            if area < floor:
                continue
            mask = np.isin(lab, g)
            if self._unsteady(mask):
                continue
            big = grouping.split_ratio is not None and area > grouping.split_ratio * typical
            parts = max(round(area / typical), 1) if big else 1
            for part in split_kmeans(mask, parts, grouping.seed):
                rows, cols = np.nonzero(part)
                boxes.append(np.array([cols.min(), rows.min(), np.ptp(cols) + 1, np.ptp(rows) + 1],
                                      dtype=np.float64))
                labels[part] = len(boxes)
            self.sizes.add(area / parts)
        if not boxes:
            return Detections.empty()
        return Detections(np.stack(boxes), np.ones(len(boxes)), labels)
