"""Adapter for OC-SORT (Cao et al., "Observation-Centric SORT: Rethinking SORT for Robust
Multi-Object Tracking", CVPR 2023), the authors' code as packaged on PyPI by ``ocsort``
(kadirnar/ocsort-pip, a copy of noahcao/OC-SORT's ``trackers/ocsort_tracker``).

That package's ``OCSort.update`` expects a torch tensor with rows (x1, y1, x2, y2, score,
class) and calls ``.numpy()`` on its columns; torch is not needed for anything else, so the
rows are handed over as a numpy array subclass with a ``numpy()`` method. Its output rows
are (x1, y1, x2, y2, id, class, score) of tracks matched this frame: they are reported as
CONFIRMED. It counts ids on a class attribute (shared by every instance): they are
renumbered here.

Install: ``pip install --no-deps ocsort==0.0.2``. Its metadata pins filterpy==1.4.5,
lap==0.4.0 and scipy==1.9.3, which do not build on Python 3.11 / numpy 2; the code itself
only needs numpy, scipy and filterpy (``lap`` is optional: scipy's Hungarian is used when
it is missing). One numpy-2 incompatibility is shimmed: the observation-centric re-update
(ORU, ``KalmanFilterNew.unfreeze``) calls ``float()`` on 1-element arrays, which numpy 2
refuses; the adapter gives ``ocsort.kalmanfilter`` a module-level ``float`` that takes the
single element, exactly what numpy 1 did (the library's arithmetic is untouched).
"""

from __future__ import annotations

import builtins
import importlib

import numpy as np

from occbench.trackers.common import checks
from occbench.trackers.outside._common import IdMap, check_min_score, require, xywh_to_xyxy, xyxy_to_xywh
from occbench.trackers.records import Detections, Track, TrackState

ASSOCIATION_COSTS = ("iou", "giou", "ciou", "diou", "ct_dist")


def _size_one_float(value) -> float:
    """``float`` as numpy 1 had it: a 1-element array of any shape gives its element."""
    if isinstance(value, np.ndarray) and value.size == 1:
        return builtins.float(value.reshape(-1)[0])
    return builtins.float(value)


class _TensorLike(np.ndarray):
    """numpy array that answers ``.numpy()`` like a CPU torch tensor."""

    def numpy(self) -> np.ndarray:
        return np.asarray(self)


class OCSortTracker:
    """OC-SORT: SORT with observation-centric re-update (ORU), momentum (OCM) and
    observation-centric recovery (OCR).

    Args:
        det_thresh: detections scoring at or below this are not associated (first round).
        max_age: frames a track survives unmatched.
        min_hits: matches in a row before a track is reported (all tracks are reported in
            the first ``min_hits`` frames, as in SORT).
        iou_threshold: smallest association score (IoU for ``asso_func="iou"``) of a match.
        delta_t: frames between the two observations whose direction gives the momentum
            (OCM, Cao et al. sec. 4.2).
        asso_func: association cost, one of iou, giou, ciou, diou, ct_dist.
        inertia: weight of the direction-consistency (momentum) cost, lambda in eq. (6).
        use_byte: also associate low-score detections (0.1 < score < det_thresh) in a
            second, BYTE-like round.
        min_score: detections below this score are not given to OC-SORT.
    """

    needs_frames = False  # boxes only (motion-only trackers)

    def __init__(
        self,
        det_thresh: float = 0.05,
        max_age: int = 30,
        min_hits: int = 3,
        iou_threshold: float = 0.3,
        delta_t: int = 3,
        asso_func: str = "iou",
        inertia: float = 0.2,
        use_byte: bool = False,
        min_score: float = 0.0,
    ) -> None:
        self._oc = require("ocsort", "--no-deps ocsort==0.0.2", type(self).__name__)
        kalman_module = importlib.import_module("ocsort.kalmanfilter")
        kalman_module.float = _size_one_float  # numpy-2 shim for ORU (see module docstring)
        checks.require("asso_func", asso_func in ASSOCIATION_COSTS,
                       f"must be one of {ASSOCIATION_COSTS}", asso_func)
        checks.at_least("", 0, max_age=max_age, min_hits=min_hits)
        checks.at_least("", 1, delta_t=delta_t)
        checks.unit("", iou_threshold=iou_threshold)
        self.det_thresh = float(det_thresh)
        self.max_age = int(max_age)
        self.min_hits = int(min_hits)
        self.iou_threshold = float(iou_threshold)
        self.delta_t = int(delta_t)
        self.asso_func = asso_func
        self.inertia = float(inertia)
        self.use_byte = bool(use_byte)
        self.min_score = check_min_score(min_score)
        self.reset()

    def reset(self) -> None:
        """A fresh OCSort (which also resets the library's class-level id counter)."""
        self._tracker = self._oc.OCSort(
            det_thresh=self.det_thresh,
            max_age=self.max_age,
            min_hits=self.min_hits,
            iou_threshold=self.iou_threshold,
            delta_t=self.delta_t,
            asso_func=self.asso_func,
            inertia=self.inertia,
            use_byte=self.use_byte,
        )
        self._ids = IdMap()

    def update(
        self, frame: np.ndarray | None, detections: Detections, foreground: np.ndarray | None = None
    ) -> list[Track]:
        """Advance one frame; ``frame`` and ``foreground`` are unused."""
        keep = detections.scores >= self.min_score
        rows = np.column_stack(
            [xywh_to_xyxy(detections.boxes[keep]), detections.scores[keep], np.zeros(keep.sum())]
        ).reshape(-1, 6)
        result = self._tracker.update(rows.view(_TensorLike), None)
        # the library lists tracks newest first; report them oldest first
        out = []
        for row in np.asarray(result, dtype=np.float64)[::-1]:
            box = xyxy_to_xywh(row[:4])
            box[2:] = np.maximum(box[2:], 1.0)
            score = float(np.clip(row[6], 0.0, 1.0))
            out.append(Track(self._ids(int(row[4])), box, TrackState.CONFIRMED, score=score))
        return out
