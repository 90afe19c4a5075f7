"""The silhouette person detector (``SilhouetteDetector``) and what every front-end detector
shares (``_ForegroundPipeline``); the others: ``foreground.ForegroundDetector`` (blobs),
``hog.HogDetector`` (HOG + SVM), ``shape_search.ActiveBasisDetector``.

Every detector has ``reset()``, ``warm_up_sequence(length, frame_fn)`` and
``detect(frame) -> (Detections, foreground)`` where ``frame`` is (H, W, 3) uint8 BGR and
``foreground`` the (H, W) bool clean foreground mask of the frame. Each owns a
``BackgroundModel`` (built by Hydra from the nested ``background`` config). The stages are
also callable one by one (``foreground(frame)``, ``detect_on(frame, mask)``) so that
benchmarks can time them. Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import numpy as np

from occbench.trackers.common.checks import at_least, require
from occbench.trackers.frontend.background import BackgroundModel
from occbench.trackers.frontend.blobs import blobs_from_mask
from occbench.trackers.frontend.calibration import Perspective, PerspectiveCalibration, active_area
from occbench.trackers.frontend.fallback import CameraFitCheck, FitEvidence, RegionDetector
from occbench.trackers.frontend.heads import HeadDetector
from occbench.trackers.frontend.shape_verifier import ShapeVerifier
from occbench.trackers.frontend.silhouette import SilhouetteMatcher
from occbench.trackers.records import Detections

log = logging.getLogger(__name__)


def _labels_from_boxes(boxes: np.ndarray, fg: np.ndarray) -> np.ndarray:
    """(H, W) int32 label image: detection k's box pixels that are foreground get k + 1
    (later boxes do not overwrite earlier ones)."""
    fg = np.asarray(fg, dtype=bool)
    lab = np.zeros(fg.shape, dtype=np.int32)
    H, W = fg.shape
    for k in range(len(boxes) - 1, -1, -1):  # last to first: earlier boxes written over later
        x, y, w, h = boxes[k]
        r0, r1 = max(int(y), 0), min(math.ceil(y + h), H)
        c0, c1 = max(int(x), 0), min(math.ceil(x + w), W)
        if r1 > r0 and c1 > c0:
            lab[r0:r1, c0:c1][fg[r0:r1, c0:c1]] = k + 1
    return lab


class _ForegroundPipeline:
    """Background model + warm-up shared by the detectors."""

    def __init__(self, background: BackgroundModel | None) -> None:
        self.background = background if background is not None else BackgroundModel()

    def reset(self) -> None:
        self.background.reset()

    def warm_up_sequence(self, length: int, frame: Callable[[int], np.ndarray | None]) -> None:
        """Learn the background from frames sampled over the sequence (see BackgroundModel)."""
        self.background.warm_up_sequence(length, frame)

    @property
    def uses_future_frames(self) -> bool:
        """Whether the detections of frame t depend on frames after t (the warm-up's span)."""
        return self.background.uses_future_frames

    def foreground(self, frame: np.ndarray) -> np.ndarray:
        """(H, W) bool clean foreground of one frame (updates the model)."""
        return self.background.apply(frame)

    def detect(self, frame: np.ndarray) -> tuple[Detections, np.ndarray]:
        fg = self.foreground(frame)
        return self.detect_on(frame, fg), fg

    def detect_on(self, frame: np.ndarray, fg: np.ndarray) -> Detections:
        raise NotImplementedError


class SilhouetteDetector(_ForegroundPipeline):
    """Reta 3.1 adapted: greedy multi-scale silhouette-template fitting on the foreground,
    at the sizes a self-calibrated ground plane allows at each row.

    Scene self-calibration (``calibration``, no annotations): in the warm-up, the template
    is fitted without a size prior over ``calibration_frames`` frames sampled evenly over
    the sequence (the foreground of each from the warmed-up background, without updating
    it); the fits not cut by the picture's border, and the isolated person-like blobs, are
    (foot row, height, width) samples of the perspective line ``calibration.Perspective``
    (height = a * foot_row + b), fitted robustly (RANSAC, ``fit_perspective``). The detector
    then searches only heights within ``matcher.heights.height_tolerance`` of the line at each row.
    With too little evidence it logs a warning and searches every height (the fallback).
    A fixed ``matcher.heights.height_model`` (a camera calibration) skips the learning.

    The live picture (``calibration.active_area``: flat padding strips at the frame's edges
    excluded) is found in the warm-up too; the matcher works on it, so that a person cut
    by the picture's border is scored on its visible part.

    Args:
        background: the background model.
        matcher: the ``SilhouetteMatcher`` (template, scales, alpha, beta, threshold, ...).
        heads: optional head detector to report one head per detection.
        calibration: the ``PerspectiveCalibration`` (None: no learning, the matcher's fixed
            ``heights.height_model`` or none).
        calibration_frames: frames sampled over the sequence for the calibration.
        calibration_evidence: "fits" (template fits without a size prior; the line is then
            in the template's own units, as the matcher uses it) or "blobs" (isolated
            person-like blobs).
        verifier: optional shape verifier (``shape_verifier.ShapeVerifier``: Reta 3.1's
            active-basis template of Gabor elements on the frame's grey levels) that keeps,
            drops or splits the matcher's boxes.
        fit_check: the ``fallback.CameraFitCheck`` judging, after the calibration, whether
            the person model fits the camera, on the "fits" evidence (None, or "blobs"
            evidence: never judged).
        fallback: the detector used instead when it does not (``fallback.RegionDetector``;
            None: keep the silhouette search). ``fallback_reason`` says why, in one line,
            and the warm-up logs it with the fallback's name.
    """

    def __init__(
        self,
        background: BackgroundModel | None = None,
        matcher: SilhouetteMatcher | None = None,
        heads: HeadDetector | None = None,
        calibration: PerspectiveCalibration | None = None,
        calibration_frames: int = 100,
        calibration_evidence: str = "fits",
        verifier: ShapeVerifier | None = None,
        fit_check: CameraFitCheck | None = None,
        fallback: RegionDetector | None = None,
    ) -> None:
        super().__init__(background)
        self.fit_check, self.fallback = fit_check, fallback
        self.matcher = matcher if matcher is not None else SilhouetteMatcher()
        self.verifier = verifier
        self.heads = heads
        self.calibration = calibration
        at_least("detector", 0, calibration_frames=calibration_frames)
        self.calibration_frames = int(calibration_frames)
        require("detector.calibration_evidence", calibration_evidence in ("fits", "blobs"),
                "must be 'fits' or 'blobs'", calibration_evidence)
        self.calibration_evidence = calibration_evidence
        self.reset()

    def reset(self) -> None:
        super().reset()
        self.perspective: Perspective | None = None
        self.area: tuple[int, int, int, int] | None = None  # live picture, see active_area
        self.evidence = FitEvidence()
        self.fallback_reason: str | None = None  # why the fallback detects, None: it does not
        self._online_frames: int | None = None  # "online": frames calibrated on so far
        if self.fallback is not None:
            self.fallback.reset()
        if self.calibration is not None:
            self.calibration.reset()
        self.matcher.set_height_model(None)

    def warm_up_sequence(self, length: int, frame: Callable[[int], np.ndarray | None]) -> None:
        frames = self.background.sample_frames(length, frame)
        self.background.warm_up(frames)
        if frames:
            self.area = active_area(frames)
        if self.calibration is None or self.matcher.fixed_height_model is not None:
            return
        if self.background.start.warmup_span == "online":  # calibrated as the frames arrive
            self._online_frames = 0
            return
        n = min(self.calibration_frames, length)
        ks = np.unique(np.linspace(1, length, n).round().astype(int)) if n > 0 else []
        for k in ks:
            f = frame(int(k))
            if f is not None:
                self._collect(self.background.peek(f))
        self.perspective = self.calibration.fit()
        if self._fall_back(length, frame):
            return
        if self.perspective is None:
            log.warning("scene calibration: too little evidence (%d samples from %d frames); "
                        "searching every person height", len(self.calibration.samples), len(ks))
            return
        log.info("scene calibration: %s, from %d frames", self.perspective.describe(), len(ks))
        self.matcher.set_height_model((self.perspective.a, self.perspective.b))

    def _fall_back(self, length: int, frame: Callable[[int], np.ndarray | None]) -> bool:
        """Switch to ``fallback`` when ``fit_check`` finds the person model misfits (one
        warning naming the fallback and why); True when it did."""
        if self.fit_check is None or self.fallback is None:
            return False
        reason = self.fit_check.misfit(self.perspective is not None, self.evidence)
        log.info("camera fit: the template fits explain %.0f%% of the foreground of %d of %d "
                 "calibration frames", 100 * self.evidence.explained_share,
                 self.evidence.busy_frames, self.evidence.frames)
        if reason is None:
            return False
        self.fallback_reason = reason
        log.warning("front end: %s; detecting with %s instead", reason, self.fallback.name)
        self.fallback.warm_up_sequence(length, frame)
        return True

    @property
    def uses_future_frames(self) -> bool:
        """Whether the detections of frame t depend on frames after t: the background's
        warm-up, and the calibration's frames sampled over the sequence, when
        ``warmup_span`` is "sequence"."""
        return self.background.uses_future_frames or (
            self.background.start.warmup_span == "sequence" and self.calibration is not None
            and self.calibration_frames > 0 and self.matcher.fixed_height_model is None)

    def detect(self, frame: np.ndarray) -> tuple[Detections, np.ndarray]:
        if self.fallback_reason is not None:
            return self.fallback.detect(frame)
        fg = self.foreground(frame)
        if self._online_frames is not None and self._online_frames < self.calibration_frames:
            self._calibrate_online(fg)
        return self.detect_on(frame, fg), fg

    def _calibrate_online(self, fg: np.ndarray) -> None:
        """"online" calibration: this frame's samples, the line re-fitted at frames 16, 32,
        64, ... and at ``calibration_frames`` (every height searched until a line is
        found; the camera fit check and its fallback are not run online)."""
        learnt = self.matcher.height_model
        self.matcher.set_height_model(None)  # samples from fits without a size prior
        self._collect(fg)
        self.matcher.set_height_model(learnt)
        self._online_frames += 1
        t = self._online_frames
        if (t >= 16 and t & (t - 1) == 0) or t == self.calibration_frames:
            perspective = self.calibration.fit()
            if perspective is not None:
                self.perspective = perspective
                self.matcher.set_height_model((perspective.a, perspective.b))

    def _live(self, fg: np.ndarray) -> tuple[np.ndarray, int, int]:
        """The live picture's part of ``fg`` and its (row, column) offset."""
        if self.area is None:
            return fg, 0, 0
        r0, r1, c0, c1 = self.area
        return fg[r0:r1, c0:c1], r0, c0

    def _collect(self, fg: np.ndarray) -> None:
        """Calibration samples of one frame (``calibration_evidence``): "fits", the template
        boxes of unconstrained fits (every component searched alone) inside the live
        picture; "blobs", the isolated person-like blobs (``calibration.blob_sample``)."""
        live, _, _ = self._live(fg)
        if self.calibration_evidence == "blobs":
            self.calibration.collect(blobs_from_mask(live, 1, perimeter=False), live.shape)
            return
        self.calibration.frame_height = live.shape[0]
        boxes, _, _ = self.matcher.fit_all(live, group=False)
        self.evidence.add(live, boxes)
        blobs = blobs_from_mask(live, 1, perimeter=False)
        if not len(boxes) or not blobs:
            return
        # a component explained by exactly one fit is one well-segmented person
        bb = np.stack([b.box for b in blobs])
        c = boxes[:, :2] + boxes[:, 2:] / 2
        inside = ((c[:, None, 0] >= bb[None, :, 0]) & (c[:, None, 0] < bb[None, :, 0] + bb[None, :, 2])
                  & (c[:, None, 1] >= bb[None, :, 1]) & (c[:, None, 1] < bb[None, :, 1] + bb[None, :, 3]))
        H, W = live.shape
        edge = 2 * self.matcher.search.downscale
        lo, hi = (self.matcher._kernels.size[k, 0] * self.matcher.search.downscale for k in (0, -1))
        for j in np.flatnonzero(inside.sum(axis=0) == 1):
            x, y, w, h = boxes[int(np.flatnonzero(inside[:, j])[0])]
            # fits at the smallest or largest height searched are censored (a fragment or a
            # merge may be smaller or larger still): no evidence of a person's size
            if lo < h < hi and y >= edge and x >= edge and y + h <= H - edge and x + w <= W - edge:
                self.calibration.samples.append((float(y + h), float(h), float(w)))

    def _person_size(self, top: float) -> tuple[float, float] | None:
        """(width, height) of the reported box of a person whose box top is at live-picture
        row ``top``, by the height model (template height t at foot row top + t), None
        without one."""
        if self.matcher.height_model is None:
            return None
        a, b = self.matcher.height_model
        t = (a * top + b) / (1.0 - a) if a < 1.0 else -1.0
        if t <= 0:
            return None
        T = self.matcher.template
        aspect = self.matcher.person.aspect or T.shape[1] / T.shape[0]
        sw, sh = self.matcher.report.box_scale
        return aspect * t * sw, t * sh

    def _template_boxes(self, boxes: np.ndarray) -> np.ndarray:
        """(N, 4) xywh: the fitted template boxes of reported ``boxes`` (``box_scale`` undone)."""
        sw, sh = self.matcher.report.box_scale
        out = np.asarray(boxes, np.float64).reshape(-1, 4).copy()
        tw = out[:, 2] / sw
        out[:, 0] -= (tw - out[:, 2]) / 2
        out[:, 2], out[:, 3] = tw, out[:, 3] / sh
        return out

    def detect_on(self, frame: np.ndarray, fg: np.ndarray) -> Detections:
        live, r0, c0 = self._live(fg)
        boxes, scores = self.matcher.fit(live)
        boxes[:, 0] += c0
        boxes[:, 1] += r0
        if self.verifier is not None:
            boxes, scores = self.verifier(frame, boxes, scores)
            vacant = self.verifier.vacant(fg, self._template_boxes(boxes), self.area)
            extra, _ = self.verifier.propose(frame, vacant, lambda top: self._person_size(top - r0))
            boxes = np.vstack([boxes, extra])
            scores = np.r_[scores, np.full(len(extra), self.matcher.score.threshold)]
        if len(boxes) == 0:
            return Detections.empty()
        heads = None if self.heads is None else self.heads.detect(frame, fg, boxes)
        return Detections(boxes, np.clip(scores, 0.0, 1.0), _labels_from_boxes(boxes, fg), heads)
