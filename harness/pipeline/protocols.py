"""PBM's evaluation protocol: each target started by hand from its ground-truth box, tracked alone.

PBM (Section 3, Table 1) initialises every evaluated person by hand and follows it alone.
``run_single_target`` does that for any tracker: for each chosen ground-truth person, a
fresh tracker starts at the person's first ground-truth frame, where its only detection is
that person's ground-truth box (a fresh tracker reports what it sees on its first frames,
so the person is followed at once); from the next frame on it gets the detection source's
detections like any run. The followed identity is the tracker's track that best overlaps
(IoU >= 0.5) the ground-truth box on that first frame (while the tracker holds it
tentative, a tracker that gives it a new id at confirmation is followed to that id by the
same overlap with its last box); the tracker's other tracks (other
people it starts from detections) are not reported. The person's run ends at its last
ground-truth frame. Every person's followed boxes go into one result table under the
person's ground-truth id, so the usual metrics read it: a tracker that drifts onto someone
else shows up as a false positive or an identity switch of that person.

Frames are read and detected once; every tracker and person gets its own copy.
"""

from __future__ import annotations

import logging
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np

from harness.datasets.base import Sequence
from harness.io.mot import MotTable
from harness.pipeline.loop import (
    ForegroundProvider,
    RunError,
    Tracker,
    TrackerOutput,
    _copy,
    _copy_detections,
    _no_progress,
    _Rows,
    clean_detections,
)
from harness.sources.base import DetectionSource
from trackers.geometry import iou_matrix
from trackers.records import Detections, Track, TrackState

log = logging.getLogger(__name__)

PROTOCOLS = ("multi", "single_target")
_FOLLOWED = (TrackState.CONFIRMED, TrackState.OCCLUDED, TrackState.TENTATIVE)


def target_spans(gt: MotTable, targets: Iterable[int] | None = None) -> dict[int, tuple[int, int]]:
    """Ground-truth id -> (first, last) frame, for ``targets`` (None = every person).

    Raises:
        RunError: a chosen id is not in the ground truth.
    """
    ids = np.unique(gt.ids)
    chosen = ids if targets is None else np.asarray(list(targets), dtype=np.int64)
    missing = sorted(set(chosen.tolist()) - set(ids.tolist()))
    if missing:
        raise RunError(f"protocol targets {missing} are not ground-truth ids of {gt.path}")
    return {int(i): (int(gt.frames[gt.ids == i].min()), int(gt.frames[gt.ids == i].max()))
            for i in chosen}


def run_single_target(
    builders: Mapping[str, Callable[[], Tracker]],
    sequence: Sequence,
    source: DetectionSource,
    foreground: str = "auto",
    background: Mapping[str, Any] | None = None,
    progress: Callable[..., Any] | None = None,
    targets: Iterable[int] | None = None,
) -> dict[str, TrackerOutput]:
    """Run every tracker once per chosen ground-truth person, started on its box.

    Args:
        builders: tracker name -> a function building a fresh tracker.
        sequence: a sequence with ground truth.
        source: detection source for the frames after each person's first.
        foreground, background: as for ``harness.pipeline.experiment.run_sequence``.
        progress: progress-bar factory; None shows nothing.
        targets: ground-truth ids to follow; None = every person.
    Returns:
        name -> ``TrackerOutput`` whose table holds each followed person's boxes under its
        ground-truth id (0-based xywh). A tracker raising is stopped for every person (its
        ``error`` set) while the other trackers go on.
    Raises:
        RunError: the sequence has no ground truth, or a chosen id is not in it.
    """
    name = sequence.info.name
    if sequence.gt is None:
        raise RunError(f"protocol=single_target needs ground truth; {name!r} has none")
    gt = sequence.gt.table
    spans = target_spans(gt, targets)
    source.start(sequence)
    fg_of = ForegroundProvider(foreground, sequence, background)
    out = {t: TrackerOutput(MotTable.empty()) for t in builders}
    rows = {t: _Rows() for t in builders}
    # (tracker name, person) -> (tracker, [followed id, its last box, still tentative])
    live: dict[tuple[str, int], tuple[Tracker, list]] = {}
    bar = (progress or _no_progress)(total=sequence.info.length, desc=name)
    try:
        for k in range(1, sequence.info.length + 1):
            frame = sequence.frame(k)
            dets, mask = source.detect(k, frame)
            dets, _ = clean_detections(dets)
            fg = fg_of(k, frame, mask)
            here = sequence.gt.rows_of(k)
            box_of = dict(zip(gt.ids[here].tolist(), gt.boxes[here]))
            for gid, (first, _) in spans.items():
                if first == k:
                    for t, build in builders.items():
                        if out[t].error is None:
                            live[(t, gid)] = (build(), [])
            for (t, gid), (tracker, followed) in list(live.items()):
                start = not followed
                given = (Detections(box_of[gid][None], np.ones(1)) if start
                         else _copy_detections(dets))
                t0 = time.perf_counter()
                try:
                    tracks = tracker.update(_copy(frame), given, _copy(fg))
                except Exception as err:  # noqa: BLE001 - this tracker stops, the others go on
                    out[t].error = f"frame {k}, target {gid}: {type(err).__name__}: {err}"
                    out[t].trace = traceback.format_exc()
                    log.error("%s on %s failed at frame %d (target %d): %s: %s", t, name, k,
                              gid, type(err).__name__, err)
                    for key in [key for key in live if key[0] == t]:
                        del live[key]
                    continue
                out[t].seconds += time.perf_counter() - t0
                out[t].frames += 1
                if start:
                    followed.extend([_pick(tracks, box_of[gid]), box_of[gid], True])
                    if followed[0] < 0:
                        log.warning("%s on %s: target %d not started at frame %d (no output "
                                    "box overlaps its ground truth)", t, name, gid, k)
                elif followed[2] and followed[0] not in {tr.id for tr in tracks}:
                    followed[0] = _pick(tracks, followed[1])  # confirmed under a new id
                mine = _relabel(tracks, followed[0], gid)
                if mine:
                    followed[1] = mine[0].box
                    followed[2] = mine[0].extra["tentative"]
                rows[t].add(k, mine)
            for gid, (_, last) in spans.items():
                if last == k:
                    for t in builders:
                        live.pop((t, gid), None)
            bar.update(1)
    finally:
        bar.close()
    for t in builders:
        out[t].table = rows[t].table()
        out[t].dropped = rows[t].dropped
    return out


def _pick(tracks: list[Track], box: np.ndarray) -> int:
    """The id of the followed-state track best overlapping ``box`` (IoU >= 0.5), else -1."""
    cands = [t for t in tracks if t.state in _FOLLOWED]
    if not cands:
        return -1
    iou = iou_matrix(np.array([t.box for t in cands]), box[None])[:, 0]
    best = int(np.argmax(iou))
    return cands[best].id if iou[best] >= 0.5 else -1


def _relabel(tracks: list[Track], followed: int, gid: int) -> list[Track]:
    """The followed track's box (at most one) under the ground-truth id, as CONFIRMED
    (``extra["tentative"]`` tells whether the tracker still held it tentative)."""
    for t in tracks:
        if t.id == followed and t.state in _FOLLOWED:
            return [Track(gid, np.asarray(t.box, dtype=np.float64), TrackState.CONFIRMED,
                          extra={"tentative": t.state == TrackState.TENTATIVE})]
    return []
