"""A tracker's tracking graph recorded by re-running it over a sequence (Reta et al. 2015,
Figs. 3-5), drawn frame by frame with ``occbench.report.graph.draw_graph``."""

from __future__ import annotations

from pathlib import Path

import cv2

from occbench.pipeline.bank import TrackerBank
from occbench.report.graph import GraphRecorder, draw_graph
from occbench.trackers.protocol import KeepsGraph


def record_sequence(tracker, sequence, source, path: str | Path, frames_dir: str | Path | None = None,
                    every: int = 1, foreground: bool = True) -> list[Path]:
    """Run ``tracker`` over ``sequence`` with detections from ``source`` and export its graph.

    Args:
        tracker: a tracker with ``reset``, ``update`` and ``graph_snapshot``.
        sequence: a ``occbench.datasets.base.Sequence`` (frames 1..length are read in order).
        source: a ``DetectionSource``; ``start(sequence)`` is called here.
        path: graph file, ``.csv`` (two files) or ``.json``; put it beside the tracks, e.g.
            ``tracks/<tracker>/<sequence>_graph.csv``.
        frames_dir: when given, every ``every``-th frame is drawn there as ``%06d.png``.
        foreground: pass the source's mask, else the sequence's exact foreground, if any.
    Returns:
        the files written (graph files first, then drawn frames).
    Raises:
        TypeError: the tracker keeps no graph.
    """
    if not isinstance(tracker, KeepsGraph):
        raise TypeError(f"{type(tracker).__name__} has no graph_snapshot(): it keeps no graph")
    tracker.reset()
    source.start(sequence)
    bank = TrackerBank({"tracker": tracker})
    recorder = GraphRecorder(sequence.info.name)
    drawn: list[Path] = []
    if frames_dir is not None:
        frames_dir = Path(frames_dir)
        frames_dir.mkdir(parents=True, exist_ok=True)
    previous: dict | None = None
    for k in sequence.frame_numbers():
        frame = sequence.frame(k)
        dets, mask = source.detect(k, frame)
        fg = (mask if mask is not None else sequence.foreground(k)) if foreground else None
        if not bank.step(k, frame, dets, fg):
            raise RuntimeError(f"{sequence.info.name}: {bank.outputs['tracker'].error}")
        snap = tracker.graph_snapshot()
        recorder.add(snap, frame=k)
        if frames_dir is not None and frame is not None and (k - 1) % max(every, 1) == 0:
            target = frames_dir / f"{k:06d}.png"
            cv2.imwrite(str(target), draw_graph(frame, snap, previous))
            drawn.append(target)
        previous = snap
    return recorder.write(path) + drawn
