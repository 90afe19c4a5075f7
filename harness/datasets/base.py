"""The sequence interface every dataset reader yields.

A ``Sequence`` has ``info`` (``occbench.trackers.records.SequenceInfo``), optional ground truth
(``GroundTruth``), optional public detections (``occbench.io.mot.MotTable``) and frames:
``frame(k)`` returns frame k (1-based) as an (H, W, 3) uint8 BGR array, or None when the
dataset carries no pixels. Iterating ``frames()`` yields ``(k, image)`` for k in
``frame_numbers()``: 1..length, or first..last for a ``FrameWindow`` (a part of a longer
sequence that keeps the original frame numbers, so its tracks align with the original gt).
"""

from __future__ import annotations

from collections.abc import Iterator
from collections.abc import Sequence as Seq
from dataclasses import dataclass, field, replace

import numpy as np

from occbench.io.mot import MotTable
from occbench.trackers.records import SequenceInfo


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
    #: number of the first frame: 1, or where a ``FrameWindow`` starts in the original
    first_frame: int = 1

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

    def frame_numbers(self) -> range:
        """The frame numbers of this sequence, in order: ``first_frame`` .. ``first_frame +
        length - 1`` (1..length unless it is a window of a longer sequence)."""
        return range(self.first_frame, self.first_frame + self.info.length)

    def nth_frame(self, j: int) -> np.ndarray | None:
        """The ``j``-th frame of this sequence (1-based position, whatever its number); the
        form background models' ``warm_up_sequence(length, frame_fn)`` take."""
        return self.frame(self.first_frame + int(j) - 1)

    def frames(self) -> Iterator[tuple[int, np.ndarray | None]]:
        for k in self.frame_numbers():
            yield k, self.frame(k)

    def __len__(self) -> int:
        return self.info.length

    def __repr__(self) -> str:
        i = self.info
        return f"{type(self).__name__}({i.name!r}, {i.width}x{i.height}, {i.length} frames)"


class FrameWindow(Sequence):
    """Frames ``first``..``last`` (1-based, inclusive) of another sequence, keeping their
    original numbers: ``frame(k)``, the ground truth, the public detections and the
    foreground are the original's for k in the window, nothing outside it exists, and the
    tracks a run writes align frame by frame with the original ground truth.

    Use: choose parameters on one part of a sequence and report on another (e.g. CAVIAR
    OneLeaveShop1cor frames 1-150 and 151-295). Any other attribute is the original's.

    Raises:
        ValueError: the window is empty or not inside the original's frame numbers.
    """

    def __init__(self, inner: Sequence, first: int, last: int) -> None:
        frames = inner.frame_numbers()
        if int(first) != first or int(last) != last:
            raise ValueError(f"{inner.info.name}: frames must be integers, got [{first}, {last}]")
        first, last = int(first), int(last)
        if not (frames.start <= first <= last <= frames.stop - 1):
            raise ValueError(
                f"{inner.info.name}: frames [{first}, {last}] must satisfy "
                f"{frames.start} <= first <= last <= {frames.stop - 1} (its frame numbers)"
            )
        self.inner = inner
        self.first_frame = first
        self.last_frame = last
        self.info = replace(inner.info, length=last - first + 1)
        self.gt = None
        if inner.gt is not None:
            keep = np.flatnonzero((inner.gt.table.frames >= first)
                                  & (inner.gt.table.frames <= last))
            g = inner.gt
            self.gt = GroundTruth(g.table.rows(keep),
                                  None if g.occluded is None else g.occluded[keep],
                                  None if g.labels is None else g.labels[keep])
        self.public_detections = None
        if inner.public_detections is not None:
            d = inner.public_detections
            self.public_detections = d.rows((d.frames >= first) & (d.frames <= last))

    def __getattr__(self, name: str):
        if name == "inner":  # not yet set (e.g. while unpickling)
            raise AttributeError(name)
        return getattr(self.inner, name)

    @property
    def has_pixels(self) -> bool:
        return self.inner.has_pixels

    def _check(self, index: int) -> int:
        k = int(index)
        if not self.first_frame <= k <= self.last_frame:
            raise IndexError(f"{self.info.name}: frame {index} outside the window "
                             f"{self.first_frame}..{self.last_frame}")
        return k

    def frame(self, index: int) -> np.ndarray | None:
        return self.inner.frame(self._check(index))

    def foreground(self, index: int) -> np.ndarray | None:
        return self.inner.foreground(self._check(index))

    def __repr__(self) -> str:
        return f"FrameWindow({self.inner!r}, frames {self.first_frame}..{self.last_frame})"


def window(sequences: Seq[Sequence], frames: Seq[int] | None) -> list[Sequence]:
    """``sequences`` restricted to ``frames = [first, last]`` (1-based, inclusive; original
    numbers kept, see ``FrameWindow``), or unchanged when ``frames`` is None. The datasets'
    ``frames`` config key (``dataset.frames=[151,295]``).

    Raises:
        ValueError: ``frames`` is not two integers, or not inside a sequence's frames.
    """
    seqs = list(sequences)
    if frames is None:
        return seqs
    if isinstance(frames, str | bytes) or len(frames) != 2:
        raise ValueError(f"frames must be [first, last] (1-based, inclusive), got {frames!r}")
    first, last = frames
    return [FrameWindow(s, first, last) for s in seqs]
