"""The frame loop shared by the runner, the video report and the bench.

Per frame k of a sequence: the frame is read once, the detection source runs once, bad
detections are dropped (``clean_detections``) and the foreground is chosen once
(``ForegroundProvider``); ``frames`` yields them in order (``LoopFrame``). Who consumes
them (``harness.pipeline.experiment.run_sequence``, ``harness.report.video``, ``harness.commands.bench``) decides what
each tracker gets.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from harness.datasets.base import Sequence
from harness.errors import RunError
from harness.io.mot import MotTable
from harness.sources.base import DetectionSource
from trackers.protocol import Tracker
from trackers.records import Detections, Track

log = logging.getLogger(__name__)

FOREGROUND_MODES = ("auto", "exact", "none", "mog2")


class Progress(Protocol):
    def update(self, n: int = 1) -> Any: ...

    def close(self) -> Any: ...


ProgressFactory = Callable[..., Progress]  # called as factory(total=..., desc=...)


class _NoProgress:
    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


def _no_progress(total: int = 0, desc: str = "", unit: str = "frame") -> Progress:
    return _NoProgress()


# --------------------------------------------------------------------------- foreground


class ForegroundProvider:
    """The foreground image handed to the trackers, by mode.

    Modes:
        auto: the detection source's mask when it computes one, else the dataset's exact
            person mask (synthetic scenes) when it has one, else None.
        exact: the dataset's exact person mask; an error when the dataset has none.

    The dataset's exact foreground is a label image of ground-truth ids; trackers get its
    nonzero pixels as a bool mask, never the ids (which would leak the ground truth).
        none: always None.
        mog2: a background-subtraction mask (``trackers.frontend.BackgroundModel``, one
            model per sequence, built with ``background`` as keyword arguments), unless
            the detection source computes its own mask, which then takes precedence.
    """

    def __init__(self, mode: str, sequence: Sequence,
                 background: Mapping[str, Any] | None = None) -> None:
        if mode not in FOREGROUND_MODES:
            raise RunError(f"foreground must be one of {FOREGROUND_MODES}, got {mode!r}")
        self.mode = mode
        self.sequence = sequence
        self._model = None
        if mode == "mog2":
            try:
                from trackers.frontend import BackgroundModel
            except ImportError as err:  # the front end is an optional part of the build
                raise RunError(f"foreground=mog2 needs trackers.frontend ({err})") from err
            self._model = BackgroundModel(**dict(background or {}))
            warm = getattr(self._model, "warm_up_sequence", None)
            if warm is not None:
                warm(sequence.info.length, sequence.nth_frame)

    def __call__(self, index: int, frame: np.ndarray | None,
                 source_mask: np.ndarray | None) -> np.ndarray | None:
        if self.mode == "none":
            return None
        if self.mode == "exact":
            fg = self.sequence.foreground(index)
            if fg is None:
                raise RunError(
                    f"foreground=exact but {self.sequence.info.name!r} has no exact foreground "
                    f"(frame {index}); use foreground=auto, none or mog2"
                )
            return fg != 0
        if self.mode == "mog2":
            mask = self._model.apply(frame) if frame is not None else None
            return source_mask if source_mask is not None else mask
        # auto
        if source_mask is not None:
            return source_mask
        fg = self.sequence.foreground(index)
        return None if fg is None else fg != 0


# --------------------------------------------------------------------------- one sequence


@dataclass
class TrackerOutput:
    """What one tracker reported on one sequence.

    Attributes:
        table: reported tracks as a ``MotTable`` (0-based xywh boxes, ``conf`` = score).
        frames: frames the tracker processed.
        seconds: wall-clock time spent in the tracker's ``update`` (not detection).
        dropped: reported boxes dropped because they were not finite or had no area.
        error: the exception text when the tracker failed (``table`` then holds the frames
            before the failure), else None.
        trace: the traceback of the failure, else None.
    """

    table: MotTable
    frames: int = 0
    seconds: float = 0.0
    dropped: int = 0
    error: str | None = None
    trace: str | None = None

    @property
    def fps(self) -> float:
        return self.frames / self.seconds if self.seconds > 0 else math.inf


class _Rows:
    """Accumulates reported tracks frame by frame."""

    def __init__(self) -> None:
        self.frames: list[int] = []
        self.ids: list[int] = []
        self.boxes: list[np.ndarray] = []
        self.scores: list[float] = []
        self.dropped = 0

    def add(self, k: int, tracks: Iterable[Track]) -> None:
        for t in tracks:
            if not t.state.reported:
                continue
            box = np.asarray(t.box, dtype=np.float64).reshape(4)
            if not (np.isfinite(box).all() and box[2] > 0 and box[3] > 0):
                self.dropped += 1
                continue
            self.frames.append(k)
            self.ids.append(int(t.id))
            self.boxes.append(box)
            self.scores.append(float(t.score))

    def table(self, path: str = "<memory>") -> MotTable:
        n = len(self.frames)
        if n == 0:
            return MotTable.empty(path)
        frames = np.asarray(self.frames, dtype=np.int64)
        ids = np.asarray(self.ids, dtype=np.int64)
        order = np.lexsort((ids, frames))
        return MotTable(frames[order], ids[order], np.asarray(self.boxes)[order],
                        np.asarray(self.scores)[order], np.full(n, -1, dtype=np.int64),
                        np.full(n, np.nan), path)


def clean_detections(dets: Detections) -> tuple[Detections, int]:
    """Drop detections with a non-finite box or score or a box without area.

    Returns the kept detections and the number dropped.
    """
    ok = (np.isfinite(dets.boxes).all(axis=1) & (dets.boxes[:, 2] > 0) & (dets.boxes[:, 3] > 0)
          & np.isfinite(dets.scores))
    if ok.all():
        return dets, 0
    return dets.subset(ok), int((~ok).sum())


def _copy_detections(d: Detections) -> Detections:
    return Detections(d.boxes.copy(), d.scores.copy(),
                      None if d.labels is None else d.labels.copy(),
                      None if d.heads is None else d.heads.copy())


def _copy(a: np.ndarray | None) -> np.ndarray | None:
    return None if a is None else a.copy()


def start_trackers(trackers: Mapping[str, Tracker], sequence: Sequence) -> None:
    """Tell each tracker that has a ``start_sequence(info)`` method the sequence's
    ``SequenceInfo`` (frame rate, size) before its first frame: trackers whose parameters
    are in frames per second (e.g. BoxMOT's, ``trackers.outside.boxmot``) take the rate
    from there rather than from a config value that would be wrong on another dataset."""
    for tracker in trackers.values():
        start = getattr(tracker, "start_sequence", None)
        if callable(start):
            start(sequence.info)


@dataclass(frozen=True)
class LoopFrame:
    """One step of the frame loop.

    Attributes:
        index: the frame number k (1-based, or a window's own numbers).
        image: (H, W, 3) uint8 BGR frame, or None when the sequence has no pixels.
        detections: the detection source's output on frame k after ``clean_detections``
            (boxes (N, 4) xywh, 0-based top-left).
        foreground: (H, W) bool mask chosen by ``ForegroundProvider``, or None.
        dropped: detections ``clean_detections`` removed on this frame.
    """

    index: int
    image: np.ndarray | None
    detections: Detections
    foreground: np.ndarray | None
    dropped: int = 0


def frames(sequence: Sequence, source: DetectionSource, foreground: str = "auto",
           background: Mapping[str, Any] | None = None, last: int | None = None,
           images: Iterable[np.ndarray | None] | None = None, start: bool = True,
           ) -> Iterator[LoopFrame]:
    """The frame loop: ``LoopFrame`` of every frame of ``sequence`` in order.

    The source is started (``source.start(sequence)``, unless ``start`` is False) and the
    ``ForegroundProvider`` built here, before the first frame is asked for, so that a bad
    mode or a failing source raises at the call.

    Args:
        sequence: the sequence; its ``frame_numbers()`` are visited in order.
        source: the detection source, run once per frame.
        foreground, background: the foreground mode and background-model keywords
            (``ForegroundProvider``).
        last: stop after frame number ``last`` (default: the sequence's last frame).
        images: frames already decoded, in ``frame_numbers()`` order (the bench times
            decoding apart); the loop stops when they run out. Default: read each frame.
        start: whether to call ``source.start(sequence)`` here.
    Raises:
        Whatever reading a frame, the detection source or the foreground raise.
    """
    if start:
        source.start(sequence)
    fg_of = ForegroundProvider(foreground, sequence, background)
    numbers: Iterable[int] = sequence.frame_numbers()
    if last is not None:
        numbers = (k for k in numbers if k <= last)
    return _frames(sequence, source, fg_of, numbers, images)


def _frames(sequence: Sequence, source: DetectionSource, fg_of: ForegroundProvider,
            numbers: Iterable[int], images: Iterable[np.ndarray | None] | None,
            ) -> Iterator[LoopFrame]:
    decoded = iter(images) if images is not None else None
    for k in numbers:
        if decoded is None:
            frame = sequence.frame(k)
        else:
            frame = next(decoded, _END)
            if frame is _END:
                return
        dets, mask = source.detect(k, frame)
        dets, bad = clean_detections(dets)
        yield LoopFrame(k, frame, dets, fg_of(k, frame, mask), bad)


_END: Any = object()
