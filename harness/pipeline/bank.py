"""The tracker bank: the one place where trackers are fed a frame.

A ``TrackerBank`` holds the trackers of a run on one sequence. For every frame it gives each
tracker its own copy of the inputs (the frame, the detections, the foreground), times its
``update`` (the copies are made outside the timed section), catches a failure (the tracker
drops out of the sequence, its error and traceback kept in its ``TrackerOutput``) and
collects the tracks it reports. The run (``occbench.pipeline.loop.run_sequence``), the
single-target protocol (``occbench.pipeline.protocols``), the video report and the bench all
feed their trackers through it.
"""

from __future__ import annotations

import logging
import math
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from occbench.datasets.base import Sequence
from occbench.io.mot import MotTable
from occbench.trackers.protocol import StartsSequence, Tracker
from occbench.trackers.records import Detections, Track

log = logging.getLogger(__name__)

Inputs = tuple[np.ndarray | None, Detections, np.ndarray | None]


@dataclass
class TrackerOutput:
    """What one tracker reported on one sequence.

    Attributes:
        table: reported tracks as a ``MotTable`` (0-based xywh boxes, ``conf`` = score).
        frames: frames the tracker processed.
        seconds: time spent in the tracker's ``update`` (not detection), by the bank's clock.
        dropped: reported boxes dropped because they were not finite or had no area.
        error: the exception text when the tracker failed (``table`` then holds the frames
            before the failure), else None.
        trace: the traceback of the failure, else None.
        followers: the single-target protocol's reported id -> the reported id its follower
            started under (a restart belongs to the follower of the person it was started
            for: ``occbench.pipeline.protocols``); None when every id is its own track.
    """

    table: MotTable
    frames: int = 0
    seconds: float = 0.0
    dropped: int = 0
    error: str | None = None
    trace: str | None = None
    followers: dict[int, int] | None = None

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


def copy_inputs(image: np.ndarray | None, detections: Detections,
                foreground: np.ndarray | None) -> Inputs:
    """Fresh copies of one frame's inputs, so that no tracker can disturb another's."""
    d = detections
    dets = Detections(d.boxes.copy(), d.scores.copy(),
                      None if d.labels is None else d.labels.copy(),
                      None if d.heads is None else d.heads.copy())
    return (None if image is None else image.copy(), dets,
            None if foreground is None else foreground.copy())


def start_trackers(trackers: Mapping[str, Tracker], sequence: Sequence) -> None:
    """Tell each tracker that has a ``start_sequence(info)`` method (``StartsSequence``) the sequence's
    ``SequenceInfo`` (frame rate, size) before its first frame: trackers whose parameters
    are in frames per second (e.g. BoxMOT's, ``occbench.trackers.outside.boxmot``) take the rate
    from there rather than from a config value that would be wrong on another dataset."""
    for tracker in trackers.values():
        if isinstance(tracker, StartsSequence):
            tracker.start_sequence(sequence.info)


class TrackerBank:
    """The trackers of one sequence, fed frame by frame.

    Args:
        trackers: name -> tracker, fed by ``step`` in this order. A value may be None when
            the caller hands the tracker to ``feed`` itself (the single-target protocol runs
            one tracker per followed person, all charged to the same name).
        clock: the timer of ``update`` (``time.perf_counter``; the bench passes its CPU clock).
    """

    def __init__(self, trackers: Mapping[str, Tracker | None],
                 clock: Callable[[], float] = time.perf_counter) -> None:
        self.trackers = dict(trackers)
        self.clock = clock
        self.outputs = {n: TrackerOutput(MotTable.empty()) for n in self.trackers}
        self._rows = {n: _Rows() for n in self.trackers}

    @property
    def active(self) -> list[str]:
        """The names of the trackers that have not failed, in order."""
        return [n for n, out in self.outputs.items() if out.error is None]

    def step(self, k: int, image: np.ndarray | None, detections: Detections,
             foreground: np.ndarray | None) -> dict[str, list[Track]]:
        """Feed frame ``k`` to every active tracker and collect what each reports.

        A lone active tracker gets the inputs themselves (there is no one to disturb).

        Returns:
            name -> the tracks its ``update`` returned (every state, not only reported
            ones), for the trackers that did not fail on this frame.
        """
        active = self.active
        out: dict[str, list[Track]] = {}
        for name in active:
            tracks = self.feed(name, k, (image, detections, foreground), copy=len(active) > 1)
            if tracks is not None:
                self.report(name, k, tracks)
                out[name] = tracks
        return out

    def feed(self, name: str, k: int, inputs: Inputs, tracker: Tracker | None = None,
             copy: bool = True, where: str | None = None) -> list[Track] | None:
        """One timed ``update`` of tracker ``name`` (or of ``tracker``, charged to ``name``)
        on frame ``k``'s ``inputs`` (image, detections, foreground).

        Returns:
            the tracks returned, or None when ``update`` raised: the failure is recorded in
            ``outputs[name]`` (``error`` opens with ``where``, default "frame k"; "" for
            none) and ``name`` leaves ``active``.
        """
        tracker = self.trackers[name] if tracker is None else tracker
        args = copy_inputs(*inputs) if copy else inputs
        t0 = self.clock()
        try:
            tracks = tracker.update(*args)
        except Exception as err:  # noqa: BLE001 - one tracker's failure must not stop the others
            self._fail(name, f"frame {k}" if where is None else where, err)
            return None
        out = self.outputs[name]
        out.seconds += self.clock() - t0
        out.frames += 1
        return list(tracks)

    def report(self, name: str, k: int, tracks: Iterable[Track]) -> None:
        """Collect the reported ones of ``tracks`` as ``name``'s rows of frame ``k``."""
        self._rows[name].add(k, tracks)

    def finish(self) -> dict[str, TrackerOutput]:
        """name -> ``TrackerOutput`` with the collected rows as its table."""
        for name, out in self.outputs.items():
            out.table = self._rows[name].table()
            out.dropped = self._rows[name].dropped
        return self.outputs

    def _fail(self, name: str, where: str, err: Exception) -> None:
        out = self.outputs[name]
        out.error = f"{where}: " * bool(where) + f"{type(err).__name__}: {err}"
        out.trace = traceback.format_exc()
        # the caller reports it (run_experiment: errors.txt and one log line)
        log.debug("%s failed at %s: %s: %s", name, where, type(err).__name__, err)
