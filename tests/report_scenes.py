"""A small scene for the report tests: two people crossing on a plain background (boxes,
frames, visibility) and a source detecting the visible ones from the ground truth."""

from __future__ import annotations

import cv2
import numpy as np

from occbench.datasets.base import GroundTruth, Sequence
from occbench.io.mot import MotTable
from occbench.trackers.records import Detections, SequenceInfo


def mot(rows, vis=None) -> MotTable:
    a = np.asarray(rows, dtype=np.float64).reshape(-1, 6)
    n = len(a)
    v = np.full(n, np.nan) if vis is None else np.asarray(vis, dtype=np.float64)
    order = np.lexsort((a[:, 1], a[:, 0]))
    return MotTable(a[order, 0].astype(np.int64), a[order, 1].astype(np.int64),
                    a[order, 2:6].copy(), np.ones(n), np.full(n, -1, np.int64), v[order])


class Walk(Sequence):
    """Two people crossing on a plain background: boxes, frames and visibility."""

    def __init__(self, n: int = 12) -> None:
        self.info = SequenceInfo("walk", 160, 120, 10.0, n)
        rows, vis = [], []
        for k in range(1, n + 1):
            rows += [(k, 1, 10 + 8 * k, 30, 20, 50), (k, 2, 130 - 8 * k, 32, 20, 50)]
            hidden = 5 <= k <= 7
            vis += [1.0, 0.0 if hidden else 1.0]
        self.gt = GroundTruth(mot(rows, vis))

    def frame(self, index: int) -> np.ndarray:
        img = np.full((120, 160, 3), 90, np.uint8)
        t = self.gt.table
        for r in self.gt.rows_of(index):
            x, y, w, h = t.boxes[r].astype(int)
            cv2.rectangle(img, (x, y), (x + w, y + h), (40, 40, 200 if t.ids[r] == 1 else 40), -1)
        return img


class GtSource:
    def start(self, sequence) -> None:
        self.seq = sequence

    def detect(self, k, frame):
        t = self.seq.gt.table
        rows = self.seq.gt.rows_of(k)
        keep = rows[np.nan_to_num(t.visibility[rows], nan=1.0) > 0.5]
        return Detections(t.boxes[keep], np.ones(len(keep))), None
