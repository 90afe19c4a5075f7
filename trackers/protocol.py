"""What every tracker offers the harness, declared: ``reset``, a per-frame ``update`` and
whether that update reads the frame's pixels (``needs_frames``), and the two optional hooks
a tracker may have (``KeepsGraph``, ``StartsSequence``), checked with ``isinstance``.

A tracker is built from config by the harness (Hydra's ``instantiate``), then fed frames in
order; it reads no files and no config dicts.
"""

from __future__ import annotations

from typing import ClassVar, Protocol, runtime_checkable

import numpy as np

from occbench.trackers.records import Detections, SequenceInfo, Track


@runtime_checkable
class Tracker(Protocol):
    """A multi-person tracker, one sequence at a time.

    ``needs_frames`` (a class attribute): True when ``update`` reads the frame's pixels
    (colour, texture), so that the harness refuses frameless data (ground truth and
    detections only) before the first frame instead of failing on it. ``update(frame,
    detections, foreground)``: ``frame`` is the (H, W, 3) uint8 BGR image of this frame, or
    None on frameless data; ``detections`` are this frame's ``Detections`` (xywh, pixels,
    0-based top-left); ``foreground`` is an (H, W) bool person mask or None. Returns this
    frame's ``Track`` list (every state; the harness writes the reported ones). ``reset``
    forgets every track before a new sequence.
    """

    needs_frames: ClassVar[bool]

    def reset(self) -> None: ...

    def update(self, frame: np.ndarray | None, detections: Detections,
               foreground: np.ndarray | None = None) -> list[Track]: ...


@runtime_checkable
class KeepsGraph(Protocol):
    """A tracker that keeps a tracking graph (Reta et al. 2015, Figs. 3-5): the current frame's
    ``{'frame': t, 'nodes': [...], 'edges': [...]}`` (``occbench.report.graph``)."""

    def graph_snapshot(self) -> dict: ...


@runtime_checkable
class StartsSequence(Protocol):
    """A tracker told the sequence's ``SequenceInfo`` (frame rate, size) before its first frame:
    one whose parameters are in frames per second takes the rate from there."""

    def start_sequence(self, info: SequenceInfo) -> None: ...


def needs_frames(tracker: object) -> bool:
    """The class's declared ``needs_frames``.

    Raises:
        TypeError: the class does not declare it (say True when its ``update`` reads pixels).
    """
    declared = getattr(type(tracker), "needs_frames", None)
    if not isinstance(declared, bool):
        raise TypeError(f"{type(tracker).__name__} does not declare needs_frames (a class "
                        "attribute: True when its update reads the frame's pixels; "
                        "occbench.trackers.protocol.Tracker)")
    return declared
