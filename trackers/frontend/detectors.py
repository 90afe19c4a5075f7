"""Person detectors on the foreground: ``foreground`` blobs, ``silhouette`` template, ``hog``.

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
from collections.abc import Callable, Sequence

import cv2
import numpy as np

from occbench.trackers.frontend.active_basis import ShapeVerifier
from occbench.trackers.frontend.background import BackgroundModel
from occbench.trackers.frontend.blobs import Blob, blobs_from_mask
from occbench.trackers.frontend.calibration import Perspective, PerspectiveCalibration, active_area
from occbench.trackers.frontend.fallback import CameraFitCheck, FitEvidence, RegionDetector
from occbench.trackers.frontend.heads import HeadDetector
from occbench.trackers.frontend.silhouette import SilhouetteMatcher
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import Detections

log = logging.getLogger(__name__)


def nms(boxes: np.ndarray, scores: np.ndarray, iou_threshold: float) -> np.ndarray:
    """Greedy non-maximum suppression: indices kept, by decreasing score."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    order = np.argsort(-np.asarray(scores), kind="stable")
    iou = iou_matrix(boxes, boxes)
    keep: list[int] = []
    suppressed = np.zeros(len(boxes), dtype=bool)
    for i in order:
        if suppressed[i]:
            continue
        keep.append(int(i))
        suppressed |= iou[i] > iou_threshold
    return np.array(keep, dtype=np.int64)


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


class ForegroundDetector(_ForegroundPipeline):
    """Foreground blobs as people: size and aspect filtered, groups split at heads.

    Args:
        background: the background model.
        min_area: smallest blob area, pixels.
        min_height: smallest person height, pixels.
        min_aspect: smallest width / height of a person box.
        max_aspect: largest width / height of a single person; wider blobs are split at the
            heads found in them (``heads``, when ``split_heads``); a wide blob without two
            heads stays whole.
        heads: head detector used to split groups and to report heads (None: no splitting).
        split_heads: split wide blobs at their heads (ours, ``detector.split_heads``: PBM 2
            hands blobs to the tracker whole and resolves merges itself, PBM 3.1); false:
            every blob is one detection.
        report_heads: attach one head box per detection (``Detections.heads``).
        person_aspect: typical person width / height, bounds the number of heads searched.
    """

    def __init__(
        self,
        background: BackgroundModel | None = None,
        min_area: int = 80,
        min_height: float = 20.0,
        min_aspect: float = 0.15,
        max_aspect: float = 0.8,
        heads: HeadDetector | None = None,
        report_heads: bool = False,
        person_aspect: float = 0.4,
        split_heads: bool = True,
    ) -> None:
        super().__init__(background)
        self.split_heads = bool(split_heads)
        if min_area < 1 or min_height <= 0:
            raise ValueError(f"min_area and min_height must be positive, got {min_area}, {min_height}")
        if not 0 < min_aspect < max_aspect:
            raise ValueError(f"need 0 < min_aspect < max_aspect, got {min_aspect}, {max_aspect}")
        self.min_area, self.min_height = int(min_area), float(min_height)
        self.min_aspect, self.max_aspect = float(min_aspect), float(max_aspect)
        self.heads, self.report_heads = heads, bool(report_heads)
        self.person_aspect = float(person_aspect)

    def blobs(self, fg: np.ndarray) -> list[Blob]:
        return blobs_from_mask(fg, self.min_area, perimeter=False)

    def detect_on(self, frame: np.ndarray, fg: np.ndarray, blobs: list[Blob] | None = None) -> Detections:
        blobs = self.blobs(fg) if blobs is None else blobs
        if not blobs:
            return Detections.empty()
        labels_in = blobs[0].labels
        boxes: list[np.ndarray] = []
        heads: list[np.ndarray] = []
        labels = np.zeros(fg.shape, dtype=np.int32)
        for b in blobs:
            _x, _y, w, h = b.box
            if h < self.min_height or w / h < self.min_aspect:
                continue
            parts = [(b.box, None, None)]
            if w / h > self.max_aspect and self.heads is not None and self.split_heads:
                n = int(np.ceil(w / (self.person_aspect * h))) + 1
                hb = self.heads.heads_in(frame, labels_in == b.label, b.box, max_heads=n)
                if len(hb) >= 2:
                    parts = self._split(b, hb)
            for box, head, (r0, c0, m) in ((p[0], p[1], p[2] or (None, None, None)) for p in parts):
                k = len(boxes) + 1
                boxes.append(box)
                heads.append(np.full(4, np.nan) if head is None else head)
                if m is None:
                    labels[labels_in == b.label] = k
                else:
                    sub = labels[r0 : r0 + m.shape[0], c0 : c0 + m.shape[1]]
                    sub[m] = k
        if not boxes:
            return Detections.empty()
        B = np.asarray(boxes, dtype=np.float64)
        Hd = np.asarray(heads, dtype=np.float64)
        if self.report_heads and self.heads is not None:
            missing = ~np.isfinite(Hd).all(axis=1)
            if missing.any():
                Hd[missing] = self.heads.detect(frame, fg, B[missing])
        return Detections(B, np.ones(len(B)), labels, Hd if self.report_heads else None)

    @staticmethod
    def _split(b: Blob, heads: np.ndarray) -> list:
        """Split a blob into vertical strips between consecutive head centres."""
        x, y, w, _h = (int(v) for v in b.box)
        crop = b.crop_mask()
        hx = np.sort(heads[:, 0] + heads[:, 2] / 2) - x
        order = np.argsort(heads[:, 0] + heads[:, 2] / 2)
        cuts = np.r_[0, np.round((hx[1:] + hx[:-1]) / 2).astype(int), w]
        parts = []
        for i in range(len(hx)):
            m = np.zeros_like(crop)
            m[:, cuts[i] : cuts[i + 1]] = crop[:, cuts[i] : cuts[i + 1]]
            rows, cols = np.flatnonzero(m.any(axis=1)), np.flatnonzero(m.any(axis=0))
            if len(rows) == 0:
                continue
            box = np.array([x + cols[0], y + rows[0], cols[-1] - cols[0] + 1, rows[-1] - rows[0] + 1],
                           dtype=np.float64)
            parts.append((box, heads[order[i]], (y, x, m)))
        return parts


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
        verifier: optional shape verifier (``active_basis.ShapeVerifier``: Reta 3.1's
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
        if calibration_frames < 0:
            raise ValueError(f"calibration_frames must be >= 0, got {calibration_frames}")
        self.calibration_frames = int(calibration_frames)
        if calibration_evidence not in ("fits", "blobs"):
            raise ValueError(f"calibration_evidence must be 'fits' or 'blobs', got {calibration_evidence!r}")
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
        if self.background.warmup_span == "online":  # calibrated as the frames arrive
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
            self.background.warmup_span == "sequence" and self.calibration is not None
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


class HogDetector(_ForegroundPipeline):
    """OpenCV's default HOG + linear SVM people detector (Dalal and Triggs; Reta's baseline),
    run only on crops around foreground blobs.

    Args:
        background: the background model.
        full_frame: ignore the foreground and scan the whole frame.
        min_blob_area: smallest foreground blob that gets a crop, pixels.
        margin: crop margin around a blob as a fraction of its height (plus 8 pixels).
        target_height: crops are resized so that their blob is this many pixels high
            (HOG's 64x128 window holds a ~96-pixel person; the pyramid then searches larger
            sizes), by a factor in [``min_scale``, ``max_upscale``].
        max_upscale: largest resize factor (small people).
        min_scale: smallest resize factor (large people).
        hit_threshold: SVM decision threshold (``detectMultiScale`` hitThreshold).
        win_stride: window stride in pixels of the (upscaled) crop.
        scale: pyramid scale step.
        nms_iou: IoU above which overlapping detections (from overlapping crops) are merged.
        box_scale: [width, height] factors shrinking HOG's window around its centre to the
            person ([1, 1] keeps the raw 64x128 window).
        min_foreground: smallest fraction of a (shrunk) box that is foreground.
    """

    def __init__(
        self,
        background: BackgroundModel | None = None,
        full_frame: bool = False,
        min_blob_area: int = 60,
        margin: float = 0.25,
        target_height: float = 100.0,
        max_upscale: float = 4.0,
        min_scale: float = 0.25,
        hit_threshold: float = 0.0,
        win_stride: int = 8,
        scale: float = 1.05,
        nms_iou: float = 0.4,
        box_scale: Sequence[float] = (1.0, 1.0),
        min_foreground: float = 0.0,
    ) -> None:
        super().__init__(background)
        if max_upscale < 1 or target_height <= 0:
            raise ValueError(f"need max_upscale >= 1 and target_height > 0, got {max_upscale}, {target_height}")
        if scale <= 1.0:
            raise ValueError(f"scale must be > 1, got {scale}")
        self.full_frame = bool(full_frame)
        self.min_blob_area, self.margin = int(min_blob_area), float(margin)
        self.target_height, self.max_upscale = float(target_height), float(max_upscale)
        if not 0 < min_scale <= 1:
            raise ValueError(f"min_scale must be in (0, 1], got {min_scale}")
        self.min_scale = float(min_scale)
        self.hit_threshold, self.win_stride = float(hit_threshold), int(win_stride)
        self.scale, self.nms_iou = float(scale), float(nms_iou)
        self.box_scale = np.asarray(box_scale, dtype=np.float64).reshape(2)
        self.min_foreground = float(min_foreground)
        self._hog = cv2.HOGDescriptor()
        self._hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())

    def detect(self, frame: np.ndarray) -> tuple[Detections, np.ndarray]:
        if self.full_frame:
            fg = np.ones(frame.shape[:2], dtype=bool)
            return self.detect_on(frame, fg), fg
        return super().detect(frame)

    def _run(self, img: np.ndarray, upscale: float) -> tuple[np.ndarray, np.ndarray]:
        if upscale != 1.0:
            img = cv2.resize(img, None, fx=upscale, fy=upscale, interpolation=cv2.INTER_LINEAR)
        ph, pw = max(0, 136 - img.shape[0]), max(0, 72 - img.shape[1])
        if ph or pw:  # the crop must hold at least one 64x128 window
            img = cv2.copyMakeBorder(img, ph // 2, ph - ph // 2, pw // 2, pw - pw // 2,
                                     cv2.BORDER_REPLICATE)
        rects, weights = self._hog.detectMultiScale(
            img, hitThreshold=self.hit_threshold, winStride=(self.win_stride, self.win_stride),
            padding=(8, 8), scale=self.scale,
        )
        if len(rects) == 0:
            return np.zeros((0, 4)), np.zeros(0)
        r = np.asarray(rects, dtype=np.float64).reshape(-1, 4)
        r[:, 0] -= pw // 2
        r[:, 1] -= ph // 2
        return r / upscale, np.asarray(weights, dtype=np.float64).reshape(-1)

    def detect_on(self, frame: np.ndarray, fg: np.ndarray) -> Detections:
        H, W = frame.shape[:2]
        if self.full_frame:
            regions = [(0, 0, W, H, 1.0)]
        else:
            blobs = blobs_from_mask(fg, self.min_blob_area, perimeter=False)
            regions = []
            for b in blobs:
                x, y, w, h = b.box
                mg = self.margin * h + 8
                x0, y0 = int(max(x - mg, 0)), int(max(y - mg, 0))
                x1, y1 = int(min(x + w + mg, W)), int(min(y + h + mg, H))
                up = float(np.clip(self.target_height / max(h, 1.0), self.min_scale, self.max_upscale))
                regions.append((x0, y0, x1, y1, up))
        boxes, scores = [], []
        for x0, y0, x1, y1, up in regions:
            r, w = self._run(frame[y0:y1, x0:x1], up)
            if len(r):
                r[:, 0] += x0
                r[:, 1] += y0
                boxes.append(r)
                scores.append(w)
        if not boxes:
            return Detections.empty()
        B, S = np.concatenate(boxes), np.concatenate(scores)
        c = B[:, :2] + B[:, 2:] / 2
        B = np.column_stack([c - B[:, 2:] * self.box_scale / 2, B[:, 2:] * self.box_scale])
        keep = nms(B, S, self.nms_iou)
        B, S = B[keep], S[keep]
        if self.min_foreground > 0 and not self.full_frame:
            frac = np.array([fg[max(int(y), 0):int(y + h), max(int(x), 0):int(x + w)].mean()
                             if w >= 1 and h >= 1 else 0.0 for x, y, w, h in B])
            B, S = B[frac >= self.min_foreground], S[frac >= self.min_foreground]
        scores01 = 1.0 / (1.0 + np.exp(-S))
        return Detections(B, scores01, _labels_from_boxes(B, fg))
