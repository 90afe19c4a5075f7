"""The frame's candidates (PBM 2, 2.3, 3.1): detection boxes with their heads, and the heads
of foreground blobs that no detection explains.

Heads come from ``Detections.heads`` when given, else from the PBM 2.3 head detector when
``CandidateParams.head_detector`` is set, else from the foreground: the top band (1/7) of a
detection box; on blobs, the peaks of the top profile. With ``foreground=None`` the
detection boxes are the candidate blobs and every box pixel counts as foreground. Boxes
are xywh float64 in pixels.

Three adaptations (``adaptations.Adaptations``; the paper's forms in brackets): a blob's
heads are the peaks of its top profile, ``ProfileHeads`` (the PBM 2.3 head detector run
in the blob, ``DetectorHeads``); detection boxes and blob spans differ systematically (box
margins, swinging limbs), so blob-born boxes are rescaled by a ratio learned online from
isolated person/detection pairs, ``CandidateFinder``'s only state (``blob_box_ratio``;
the paper: the blob's span, PBM 2.1); a detection lying in a blob keeps the blob from being
one target grown, ``HeldDetections`` (the blob's own heads alone, ``NoHeldDetections``).
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.common.checks import require
from occbench.trackers.geometry import iou_matrix, overlap_ratio_matrix
from occbench.trackers.layered.params import CandidateParams
from occbench.trackers.layered.search import (
    Candidates,
    blobs_boxes,
    heads_from_bands,
    residual_foreground,
    split_blob_box,
    top_profile_heads,
)
from occbench.trackers.records import Detections


class ProfileHeads:
    """``profile_heads``: a blob's heads are the peaks of its top profile
    (``search.top_profile_heads``), at least ``head_separation`` x its height apart."""

    def __init__(self, params: CandidateParams) -> None:
        self.separation = params.head_separation

    def heads(self, mask: np.ndarray, sbox: np.ndarray, s: int, frame: np.ndarray | None,
              fg: np.ndarray | None) -> np.ndarray:
        """(K, 2) float64 heads (column centre, top row) in the coordinates of ``mask``, the
        (h, w) bool crop of one blob at ``sbox`` (xywh) of the mask subsampled by ``s``."""
        h = mask.shape[0]
        return top_profile_heads(mask, max(self.separation * h, 3.0 / s), max(0.06 * h, 2.0 / s))


class DetectorHeads:
    """PBM 2.3 as written: a blob's heads are those the hair and skin head detector
    (``candidates.head_detector``, its ``heads_in(frame, foreground, box, max_heads)``)
    finds in the blob's box, greedily, at most ``max_heads`` (a reading: the paper gives
    no number); none found, the blob has no candidate."""

    def __init__(self, params: CandidateParams, max_heads: int = 4) -> None:
        detector = params.head_detector
        require("candidates.head_detector", callable(getattr(detector, "heads_in", None)),
                "must have a heads_in(frame, foreground, box, max_heads) method when "
                "adaptations.profile_heads=false (PBM 2.3)", detector)
        self.detector, self.max_heads = detector, int(max_heads)

    def heads(self, mask: np.ndarray, sbox: np.ndarray, s: int, frame: np.ndarray | None,
              fg: np.ndarray | None) -> np.ndarray:
        """As ``ProfileHeads.heads``: (K, 2) (column centre, top row) in ``mask``'s
        coordinates, from the detector's (K, 4) xywh full-resolution head boxes."""
        if frame is None:
            return np.zeros((0, 2))
        found = self.detector.heads_in(frame, fg, np.asarray(sbox, dtype=np.float64) * s,
                                       self.max_heads)
        found = np.asarray(found, dtype=np.float64).reshape(-1, 4)
        return np.column_stack([(found[:, 0] + 0.5 * found[:, 2]) / s - sbox[0] - 0.5,
                                found[:, 1] / s - sbox[1]])


class NoHeldDetections:
    """The paper's count of a blob's heads: its own (PBM 3.1, "for each detected head in
    the blob"); a detection lying in the blob adds none."""

    def count(self, region: np.ndarray, det_boxes: np.ndarray, on_peak: np.ndarray) -> int:
        """Detections held by the blob at ``region`` besides its heads: none."""
        return 0


class HeldDetections:
    """``held_detections``: a detection whose box lies in a blob's region (at least
    ``overlap`` of its area inside), its head not one of the blob's own peaks, is a second
    person in the region: the region is no target grown (``lone_growth``), whatever its
    one peak says. A person standing below another, their heads one above the other,
    has no peak in the blob's top profile; the detection found on it says the blob holds
    two people. The region's heads (``several_heads_merge``) are still its own peaks.

    Args:
        overlap: share of a detection's box inside the blob's (``search.overlap``, the
            share with which a region holds a target's box, PBM 3.1).
    """

    def __init__(self, overlap: float) -> None:
        self.overlap = float(overlap)

    def count(self, region: np.ndarray, det_boxes: np.ndarray, on_peak: np.ndarray) -> int:
        """Detections (D, 4) held by the blob at ``region`` (4,) xywh besides its heads;
        ``on_peak`` (D,) bool: the detection's head zone holds one of the blob's peaks."""
        if not len(det_boxes):
            return 0
        held = overlap_ratio_matrix(det_boxes, region[None])[:, 0] >= self.overlap
        return int(np.count_nonzero(held & ~on_peak))


class CandidateFinder:
    """Candidates of each frame (``find``), learning the blob-to-detection box ratio.

    Args:
        params: blob size, head separation, downsampling and the head detector.
        blob_heads: how a blob's heads are found (``ProfileHeads``, ``DetectorHeads``);
            None: ``ProfileHeads``.
        blob_box_ratio: rescale blob-born boxes by the learnt ratio (an adaptation; off,
            a blob's box is its span, PBM 2.1).
        held: how the detections lying in a blob count (``HeldDetections``,
            ``NoHeldDetections``; ``Candidates.held``); None: ``NoHeldDetections``.
    """

    def __init__(self, params: CandidateParams, blob_heads: ProfileHeads | DetectorHeads | None = None,
                 blob_box_ratio: bool = True,
                 held: HeldDetections | NoHeldDetections | None = None) -> None:
        self.params = params
        self.blob_heads = ProfileHeads(params) if blob_heads is None else blob_heads
        self.blob_box_ratio = bool(blob_box_ratio)
        self.held = NoHeldDetections() if held is None else held
        self.reset()

    def reset(self) -> None:
        """Forget the learned blob-to-detection ratio."""
        self._blob_to_box = np.ones(2)  # detection (w, h) / blob span (w, h), learned online
        self._blob_pairs = 0

    def find(self, fg: np.ndarray | None, detections: Detections,
             frame: np.ndarray | None = None) -> Candidates:
        """The frame's candidates (PBM 2, 3.1): the valid detection boxes with their heads,
        then the heads of foreground blobs that no detection explains."""
        det_boxes = detections.boxes
        heads = detections.heads
        detector = self.params.head_detector
        if heads is None and detector is not None and frame is not None and len(det_boxes):
            heads = np.asarray(detector.detect(frame, fg, det_boxes), dtype=np.float64)
        valid = (np.logical_and.reduce(np.isfinite(det_boxes), axis=1)
                 & (det_boxes[:, 2] > 1) & (det_boxes[:, 3] > 1)).nonzero()[0]
        box = det_boxes[valid]
        if fg is not None:  # the top 1/7 band's foreground (PBM 3.1)
            head = heads_from_bands(fg, box)
        else:  # the band's centre
            x, y, w = box[:, 0], box[:, 1], box[:, 2]
            head = np.column_stack([x + 0.5 * w, y, 0.5 * w])
        if heads is not None:  # the source's heads where it gives them
            has_head = np.logical_and.reduce(np.isfinite(heads[valid]), axis=1)
            hx, hy, hw = heads[valid[has_head], :3].T
            head[has_head] = np.column_stack([hx + 0.5 * hw, hy, hw])
        rows = (box, box.copy(), head, np.zeros(len(valid), dtype=bool),
                np.ones(len(valid), dtype=np.int64))
        if fg is None:
            return Candidates(*rows)
        # blobs matter only where foreground is left unexplained by the detections
        if len(det_boxes) and residual_foreground(fg, det_boxes) < self.params.min_blob_area:
            return Candidates(*rows)
        s = self.params.blob_downsample
        small = np.ascontiguousarray(fg[::s, ::s]) if s > 1 else fg
        labels, bboxes, numbers = blobs_boxes(small, max(self.params.min_blob_area // (s * s), 1))
        if len(bboxes) and len(det_boxes):
            blob_iou = iou_matrix(bboxes * s, det_boxes)  # for ``_calibrate``
            # the head zone of each detection: its top third (and a tenth above)
            zx0, zx1 = det_boxes[:, 0, None], (det_boxes[:, 0] + det_boxes[:, 2])[:, None]
            zy0 = (det_boxes[:, 1] - 0.1 * det_boxes[:, 3])[:, None]
            zy1 = (det_boxes[:, 1] + det_boxes[:, 3] / 3.0)[:, None]
        blob_rows: list[tuple] = []
        for i, (sbox, lab) in enumerate(zip(bboxes, numbers)):
            x, y, w, h = (int(v) for v in sbox)
            mask = labels[y:y + h, x:x + w] == lab
            peaks = self.blob_heads.heads(mask, sbox, s, frame, fg)
            bbox = sbox * s
            hx = (peaks[:, 0] + x + 0.5) * s
            hy = (peaks[:, 1] + y) * s
            # heads explained by a detection: inside a detection box's top third
            if len(det_boxes):
                zone = (hx >= zx0) & (hx <= zx1) & (hy >= zy0) & (hy <= zy1)  # (D, K)
                explained = zone.any(axis=0)
            else:
                zone = np.zeros((0, len(peaks)), dtype=bool)
                explained = np.zeros(len(peaks), dtype=bool)
            if len(peaks) == 1 and explained[0] and self.blob_box_ratio:
                self._calibrate(bbox, blob_iou[i], det_boxes)
            if explained.all():
                continue
            n = len(peaks)
            held = self.held.count(bbox, det_boxes, zone.any(axis=1))
            head_w = max(self.params.head_separation * bbox[3], 3.0)
            for k in np.nonzero(~explained)[0]:
                own = (bbox.copy() if n == 1
                       else split_blob_box(mask, sbox[:2], peaks[:, 0], int(k)) * s)
                blob_rows.append((self._blob_box_as_detection(own), bbox,
                                  np.array([hx[k], hy[k], head_w]), n, held))
        if not blob_rows:
            return Candidates(*rows)
        own, region, head, n, held = zip(*blob_rows)
        return Candidates(np.vstack([rows[0], own]), np.vstack([rows[1], region]),
                          np.vstack([rows[2], head]),
                          np.concatenate([rows[3], np.ones(len(own), dtype=bool)]),
                          np.concatenate([rows[4], np.array(n, dtype=np.int64)]),
                          held=np.concatenate([np.zeros(len(rows[0]), dtype=np.int64),
                                               np.array(held, dtype=np.int64)]))

    def _calibrate(self, blob_box: np.ndarray, iou: np.ndarray, det_boxes: np.ndarray) -> None:
        """Learn the ratio of detection box size to blob span from isolated people.

        A detector's boxes and a foreground blob's span differ systematically (limbs, box
        margins); a blob holding one head and overlapping exactly one detection (IoU >
        0.5) gives one sample of (w_det / w_blob, h_det / h_blob); the first 20 samples
        are averaged, later ones enter a running average with weight 0.05.

        Args:
            blob_box: (4,) xywh blob. iou: (D,) its IoU with each of ``det_boxes`` (D, 4).
        """
        if (iou > 0.3).sum() != 1 or iou.max() < 0.5:
            return
        d = det_boxes[int(np.argmax(iou))]
        r = d[2:] / np.maximum(blob_box[2:], 1.0)
        self._blob_pairs += 1
        rate = max(1.0 / self._blob_pairs, 0.05)
        self._blob_to_box += rate * (r - self._blob_to_box)

    def _blob_box_as_detection(self, box: np.ndarray) -> np.ndarray:
        """A blob box rescaled about its centre to the detections' box convention."""
        if self._blob_pairs == 0:
            return box
        c = box[:2] + 0.5 * box[2:]
        wh = box[2:] * self._blob_to_box
        return np.array([c[0] - 0.5 * wh[0], box[1], wh[0], wh[1]])


def checked_inputs(frame: np.ndarray, detections: Detections | None,
                   foreground: np.ndarray | None) -> tuple:
    """``PBMTracker.update``'s inputs checked (ValueError naming the argument): (frame,
    detections, fg (H, W) C-contiguous bool or None)."""
    if frame is None:
        raise ValueError("PBMTracker.update: frame is None; PBM needs pixels (colour histograms of the parts)")
    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
        raise ValueError(f"PBMTracker.update: frame must be (H, W, 3) uint8 BGR, got {frame.shape} {frame.dtype}")
    if detections is None:
        detections = Detections.empty()
    fg = None
    if foreground is not None:
        foreground = np.asarray(foreground)
        if foreground.shape != frame.shape[:2]:
            raise ValueError(f"PBMTracker.update: foreground shape {foreground.shape} "
                             f"differs from frame {frame.shape[:2]}")
        fg = np.ascontiguousarray(foreground if foreground.dtype == bool else foreground != 0)
    return frame, detections, fg
