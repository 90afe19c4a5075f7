"""The sequence interface every dataset reader yields.

A ``Sequence`` has ``info`` (``trackers.records.SequenceInfo``), optional ground truth
(``GroundTruth``), optional public detections (``harness.io.mot.MotTable``) and frames:
``frame(k)`` returns frame k (1-based) as an (H, W, 3) uint8 BGR array, or None when the
dataset carries no pixels. Iterating ``frames()`` yields ``(k, image)`` for k = 1..length.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from harness.io.mot import MotTable
from trackers.records import SequenceInfo


@dataclass
class GroundTruth:
    """Ground-truth boxes of one sequence.

    Attributes:
        table: MOT rows (0-based xywh boxes, ``conf`` 1 = consider / 0 = ignore,
            ``visibility`` in [0, 1] or NaN where unknown).
        occluded: (N,) bool per row, True where the person is labelled hidden (CAVIAR's
            ``occluded``) or visibility < the reader's threshold; None when unknown.
        labels: optional (N,) str per row: CAVIAR appearance labels.
    """

    table: MotTable
    occluded: np.ndarray | None = None
    labels: np.ndarray | None = None
    _index: dict[int, np.ndarray] | None = field(default=None, repr=False)

    def rows_of(self, frame: int) -> np.ndarray:
        """Row indices of ``frame`` (1-based) into ``table``."""
        if self._index is None:
            self._index = self.table.frame_index()
        return self._index.get(int(frame), np.zeros(0, dtype=np.int64))


class Sequence:
    """Base class of dataset sequences: subclasses set ``info`` and implement ``frame``."""

    info: SequenceInfo
    gt: GroundTruth | None = None
    public_detections: MotTable | None = None

    @property
    def has_pixels(self) -> bool:
        return True

    def frame(self, index: int) -> np.ndarray | None:
        """Frame ``index`` (1-based) as (H, W, 3) uint8 BGR, or None without pixels."""
        raise NotImplementedError

    def foreground(self, index: int) -> np.ndarray | None:
        """Exact (H, W) int32 person label image of frame ``index`` (pixel value = gt id,
        0 = background) when the dataset knows it (synthetic scenes), else None."""
        return None

    def frames(self) -> Iterator[tuple[int, np.ndarray | None]]:
        for k in range(1, self.info.length + 1):
            yield k, self.frame(k)

    def __len__(self) -> int:
        return self.info.length

    def __repr__(self) -> str:
        i = self.info
        return f"{type(self).__name__}({i.name!r}, {i.width}x{i.height}, {i.length} frames)"
