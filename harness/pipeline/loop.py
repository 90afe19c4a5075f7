"""The frame loop shared by the runner, the video report and the bench.

Per frame k of a sequence: the frame is read once, the detection source runs once, bad
detections are dropped (``clean_detections``) and the foreground is chosen once
(``ForegroundProvider``); ``frames`` yields them in order (``LoopFrame``). The consumers
(``run_sequence`` here, ``occbench.replay.video``, ``occbench.commands.bench``) hand each step
to a ``occbench.pipeline.bank.TrackerBank``, which feeds the trackers.

Frames are visited once, in order, and every tracker advances on the same frame before the
next one is read: the detections are computed once per sequence, identical for every
tracker, and no more than one frame is held in memory.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from occbench.config.check import FOREGROUND_MODES
from occbench.datasets.base import Sequence
from occbench.errors import RunError
from occbench.io.mot import MotTable
from occbench.pipeline.bank import TrackerBank, TrackerOutput, start_trackers
from occbench.sources.base import DetectionSource
from occbench.trackers.protocol import Tracker
from occbench.trackers.records import Detections

log = logging.getLogger(__name__)


class Progress(Protocol):
    def update(self, n: int = 1) -> Any: ...

    def close(self) -> Any: ...


ProgressFactory = Callable[..., Progress]  # called as factory(total=..., desc=...)


class _NoProgress:
    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


def no_progress(total: int = 0, desc: str = "", unit: str = "frame") -> Progress:
    return _NoProgress()


# --------------------------------------------------------------------------- foreground


def background_model(settings: Mapping[str, Any]) -> Any:
    """The ``BackgroundModel`` of ``foreground=mog2`` from config.yaml's ``background``: its
    ``method`` and ``mixture``, and each parameter group as a mapping of its fields
    (``background.model.history``, ``background.start.warmup_span``; ``background_params``).

    Raises:
        RunError: the front end is not installed, or a key or value is refused (a flat key
            of the model before its groups names its group's key).
    """
    try:
        # start-up: the front end (~7 ms CPU), for foreground=mog2 only
        from occbench.trackers.frontend import BackgroundModel
        from occbench.trackers.frontend.background_params import GROUPS
    except ImportError as err:  # the front end is an optional part of the build
        raise RunError(f"foreground=mog2 needs occbench.trackers.frontend ({err})") from err
    try:
        groups = {k: GROUPS[k](**v) for k, v in settings.items()
                  if k in GROUPS and isinstance(v, Mapping)}
        return BackgroundModel(**{**settings, **groups})
    except (TypeError, ValueError) as err:  # the model's own messages name the key
        text = str(err)
        raise RunError(text if text.startswith("background.") else f"background: {text}") from err


class ForegroundProvider:
    """The foreground image handed to the trackers, by mode.

    Modes:
        auto: the detection source's mask when it computes one, else the dataset's exact
            person mask (synthetic scenes) when it has one, else None.
        exact: the dataset's exact person mask; an error when the dataset has none.

    The dataset's exact foreground is a label image of ground-truth ids; trackers get its
    nonzero pixels as a bool mask, never the ids (which would leak the ground truth).
        none: always None.
        mog2: a background-subtraction mask (``occbench.trackers.frontend.BackgroundModel``, one
            model per sequence, built from ``background`` by ``background_model``), unless
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
            self._model = background_model(background or {})
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


def clean_detections(dets: Detections) -> tuple[Detections, int]:
    """Drop detections with a non-finite box or score or a box without area.

    Returns the kept detections and the number dropped.
    """
    ok = (np.isfinite(dets.boxes).all(axis=1) & (dets.boxes[:, 2] > 0) & (dets.boxes[:, 3] > 0)
          & np.isfinite(dets.scores))
    if ok.all():
        return dets, 0
    return dets.subset(ok), int((~ok).sum())


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


def run_sequence(
    trackers: Mapping[str, Tracker],
    sequence: Sequence,
    source: DetectionSource,
    foreground: str = "auto",
    background: Mapping[str, Any] | None = None,
    progress: ProgressFactory | None = None,
    on_update: Callable[[str, int, Tracker], None] | None = None,
) -> dict[str, TrackerOutput]:
    """Run several trackers side by side on one sequence: the frame loop into a
    ``TrackerBank`` (each tracker its own copy of the frame, the detections and the
    foreground, so no tracker can disturb another's input).

    Args:
        trackers: name -> freshly built tracker.
        sequence: the sequence; its ``frame_numbers()`` (1..length, or a window's
            first..last) are visited in order, and tracks carry those numbers.
        source: detection source; ``start(sequence)`` is called here.
        foreground: foreground mode (see ``ForegroundProvider``).
        background: keyword arguments of the background model for ``foreground="mog2"``.
        progress: progress-bar factory ``(total=, desc=)``; None shows nothing.
        on_update: called as ``on_update(name, k, tracker)`` after each successful update
            of frame k, outside the timed section (e.g. ``GraphExport.record``).
    Returns:
        name -> ``TrackerOutput``. A tracker raising an exception is stopped there (its
        ``error`` set, the exception logged) while the others go on.
    Raises:
        Whatever reading a frame, the detection source or the foreground raise: the sequence
        cannot go on for any tracker.
    """
    name = sequence.info.name
    loop = frames(sequence, source, foreground, background)
    start_trackers(trackers, sequence)
    bank = TrackerBank(trackers)
    dropped_dets = 0
    bar = (progress or no_progress)(total=sequence.info.length, desc=name)
    try:
        for step in loop if bank.active else ():
            dropped_dets += step.dropped
            fed = bank.step(step.index, step.image, step.detections, step.foreground)
            if on_update is not None:
                for t in fed:
                    on_update(t, step.index, trackers[t])
            bar.update(1)
            if not bank.active:  # read no further frame
                break
    finally:
        bar.close()
    if dropped_dets:
        log.warning("%s: %d detections with a NaN/infinite box or score or no area dropped",
                    name, dropped_dets)
    out = bank.finish()
    for t, o in out.items():
        if o.dropped:
            log.warning("%s on %s: %d reported boxes not finite or without area dropped",
                        t, name, o.dropped)
    return out


def run_tracker(tracker: Tracker, sequence: Sequence, source: DetectionSource,
                foreground: str = "auto") -> MotTable:
    """Run one tracker on one sequence; the reported tracks (0-based xywh) as a MotTable.

    Raises:
        RuntimeError: the tracker raised (the original exception is chained).
    """
    out = run_sequence({"tracker": tracker}, sequence, source, foreground)["tracker"]
    if out.error is not None:
        raise RuntimeError(f"tracker failed on {sequence.info.name}: {out.error}")
    return out.table
