"""Detection sources built from the dataset's annotations: noisy ground truth and public files.

Both implement ``occbench.sources.base.DetectionSource`` (``start(sequence)``, then
``detect(k, frame) -> (Detections, None)``) and ignore the pixels, so they run on box-only
sequences too. Neither computes a foreground mask.
"""

from __future__ import annotations

import logging
import zlib

import numpy as np

from occbench.datasets.base import Sequence
from occbench.io.mot import MotTable
from occbench.trackers.geometry import clip_boxes
from occbench.trackers.records import Detections, SequenceInfo

log = logging.getLogger(__name__)

#: smallest width and height (pixels) of a box a source returns after clipping
MIN_SIZE = 1.0


def _sequence_key(name: str) -> int:
    """Stable 32-bit key of a sequence name (unlike ``hash``, the same in every process)."""
    return zlib.crc32(name.encode("utf-8"))


class NoisyGroundTruth:
    """Simulated person detector: the ground-truth boxes with misses, jitter and clutter.

    Every visible gt person of a frame is detected with probability ``1 - miss_rate``; its
    box is perturbed by Gaussian noise (centre and size, sigma = ``jitter`` x the box's width
    for x and w, x its height for y and h); Poisson(``fp_rate``) false positives of
    plausible person size (the sequence's gt box sizes) appear at uniform random places.
    Boxes are clipped to the image; true detections score 1, false positives
    U(0.3, 0.9). The output order is shuffled so that it says nothing about identities.

    Hidden people really disappear: a gt row whose visibility (MOT16+ column 9) is below
    ``min_visibility`` is never detected; where the visibility is unknown (NaN), rows
    flagged ``GroundTruth.occluded`` (CAVIAR's ``occluded`` label) count as hidden. Rows with
    conf 0 (MOTChallenge's ignore flag: non-pedestrians, distractors) are never detected.

    Determinism: frame k's random draws come from a generator seeded by
    (seed, crc32(sequence name), k), so a sequence's detections are the same bytes whatever
    the order in which frames or sequences are visited.

    Args:
        miss_rate: probability in [0, 1] that a visible person is not detected.
        jitter: box noise, as a fraction (>= 0) of the box's width and height.
        fp_rate: mean number (>= 0) of false positives per frame.
        seed: integer seed (>= 0).
        min_visibility: visibility in [0, 1] below which a person is not detected.
    """

    #: what the results name this source by (titles, log line, summary, report)
    label = "ground truth + noise"
    #: it reads the ground truth, not pixels
    needs_pixels = False

    def __init__(self, miss_rate: float = 0.0, jitter: float = 0.0, fp_rate: float = 0.0,
                 seed: int = 0, min_visibility: float = 0.3) -> None:
        if not 0.0 <= miss_rate <= 1.0:
            raise ValueError(f"miss_rate must be in [0, 1], got {miss_rate}")
        if not jitter >= 0.0:
            raise ValueError(f"jitter must be >= 0, got {jitter}")
        if not fp_rate >= 0.0:
            raise ValueError(f"fp_rate must be >= 0, got {fp_rate}")
        if int(seed) != seed or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed}")
        if not 0.0 <= min_visibility <= 1.0:
            raise ValueError(f"min_visibility must be in [0, 1], got {min_visibility}")
        self.miss_rate = float(miss_rate)
        self.jitter = float(jitter)
        self.fp_rate = float(fp_rate)
        self.seed = int(seed)
        self.min_visibility = float(min_visibility)
        self._info: SequenceInfo | None = None
        self._table: MotTable | None = None
        self._index: dict[int, np.ndarray] = {}
        self._detectable: np.ndarray | None = None
        self._key = 0
        self._fp_sizes = np.zeros((0, 2))

    def start(self, sequence: Sequence) -> None:
        """Prepare for ``sequence``: index its gt and decide which rows are detectable.

        Raises:
            ValueError: the sequence has no ground truth.
        """
        if sequence.gt is None:
            raise ValueError(
                f"sequence {sequence.info.name!r} has no ground truth: the noisy_gt detector "
                "needs gt (use detector=public or a detector that reads pixels)"
            )
        gt = sequence.gt
        t = gt.table
        self._info = sequence.info
        self._table = t
        self._index = t.frame_index()
        self._key = _sequence_key(sequence.info.name)
        vis = t.visibility
        known = np.isfinite(vis)
        hidden = np.zeros(len(t), dtype=bool)
        hidden[known] = vis[known] < self.min_visibility
        if gt.occluded is not None:
            hidden[~known] = np.asarray(gt.occluded, dtype=bool)[~known]
        self._detectable = (t.conf > 0) & ~hidden
        # false-positive sizes: the (w, h) of the sequence's considered gt boxes
        sizes = t.boxes[t.conf > 0, 2:4]
        if len(sizes) == 0:
            h = 0.3 * sequence.info.height
            sizes = np.array([[0.4 * h, h]])
        self._fp_sizes = sizes
        log.debug("noisy_gt on %s: %d of %d gt rows detectable", sequence.info.name,
                  int(self._detectable.sum()), len(t))

    def rng(self, index: int) -> np.random.Generator:
        """The generator of frame ``index`` of the started sequence."""
        return np.random.default_rng([self.seed, self._key, int(index)])

    def detect(self, index: int, frame: np.ndarray | None = None) -> tuple[Detections, None]:
        """Detections of frame ``index`` (1-based); ``frame`` is not looked at.

        Returns:
            (Detections with (N, 4) xywh 0-based float64 boxes and (N,) scores, None).
        """
        if self._info is None:
            raise RuntimeError("NoisyGroundTruth.detect called before start(sequence)")
        t, info = self._table, self._info
        rng = self.rng(index)
        rows = self._index.get(int(index), np.zeros(0, dtype=np.int64))
        rows = rows[self._detectable[rows]]
        # draw every variate for every row, then select: the draws of one row do not depend
        # on which other rows were kept
        n = len(rows)
        u_miss = rng.random(n)
        noise = rng.standard_normal((n, 4))
        n_fp = int(rng.poisson(self.fp_rate)) if self.fp_rate > 0 else 0
        fp_pick = rng.integers(0, len(self._fp_sizes), n_fp)
        fp_scale = rng.uniform(0.8, 1.2, n_fp)
        fp_pos = rng.random((n_fp, 2))
        fp_score = rng.uniform(0.3, 0.9, n_fp)

        boxes = t.boxes[rows].copy()
        if self.jitter > 0 and n:
            wh = boxes[:, 2:4]
            c = boxes[:, :2] + wh / 2 + self.jitter * wh * noise[:, :2]
            wh = np.maximum(wh * (1 + self.jitter * noise[:, 2:4]), MIN_SIZE)
            boxes = np.hstack([c - wh / 2, wh])
        boxes = boxes[u_miss >= self.miss_rate] if self.miss_rate > 0 else boxes

        fp_wh = np.minimum(self._fp_sizes[fp_pick] * fp_scale[:, None], [info.width, info.height])
        fp_xy = fp_pos * np.maximum([info.width, info.height] - fp_wh, 0)
        fp_boxes = np.hstack([fp_xy, fp_wh]).reshape(-1, 4)

        all_boxes = np.vstack([boxes, fp_boxes])
        scores = np.r_[np.ones(len(boxes)), fp_score]
        all_boxes = clip_boxes(all_boxes, info.width, info.height)
        keep = (all_boxes[:, 2] >= MIN_SIZE) & (all_boxes[:, 3] >= MIN_SIZE)
        order = rng.permutation(len(all_boxes))
        order = order[keep[order]]
        return Detections(all_boxes[order], scores[order]), None


class PublicDetections:
    """The sequence's public detections (MOT ``det/det.txt``) with score >= ``min_score``.

    Scores are the file's column 7 as written (in [0, 1] for the MOT15 Faster R-CNN set;
    DPM files hold unbounded scores, so choose ``min_score`` on the file's scale).

    Args:
        min_score: detections scoring below it are dropped.
    """

    label = "public detections (det/det.txt)"
    needs_pixels = False

    def __init__(self, min_score: float = 0.0) -> None:
        if not np.isfinite(min_score):
            raise ValueError(f"min_score must be a finite number, got {min_score}")
        self.min_score = float(min_score)
        self._table: MotTable | None = None
        self._index: dict[int, np.ndarray] = {}

    def start(self, sequence: Sequence) -> None:
        """Index ``sequence.public_detections``.

        Raises:
            ValueError: the sequence has no det file.
        """
        det = sequence.public_detections
        if det is None:
            raise ValueError(
                f"sequence {sequence.info.name!r} has no public detections (no det/det.txt): "
                "use another detector, e.g. detector=noisy_gt"
            )
        keep = det.conf >= self.min_score
        self._table = det.rows(keep)
        self._index = self._table.frame_index()
        if len(det) == 0:
            log.warning("%s: no public detections in %s", sequence.info.name, det.path)
        else:
            log.debug("public detections of %s: %d of %d rows with score >= %g",
                      sequence.info.name, int(keep.sum()), len(det), self.min_score)

    def detect(self, index: int, frame: np.ndarray | None = None) -> tuple[Detections, None]:
        """Rows of frame ``index`` (1-based): (N, 4) 0-based xywh boxes, scores; and None."""
        if self._table is None:
            raise RuntimeError("PublicDetections.detect called before start(sequence)")
        rows = self._index.get(int(index))
        if rows is None:
            return Detections.empty(), None
        return Detections(self._table.boxes[rows], self._table.conf[rows]), None
