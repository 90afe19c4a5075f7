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
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np

from harness.datasets.base import Sequence
from harness.errors import RunError
from harness.io.mot import MotTable
from harness.pipeline.bank import TrackerBank, TrackerOutput
from harness.pipeline.loop import ForegroundProvider, clean_detections, no_progress
from harness.sources.base import DetectionSource
from trackers.geometry import iou_matrix
from trackers.protocol import Tracker
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
        foreground, background: as for ``harness.pipeline.loop.run_sequence``.
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
    bank = TrackerBank(dict.fromkeys(builders))  # one tracker per person, fed by hand
    # (tracker name, person) -> (tracker, [followed id, its last box, still tentative])
    live: dict[tuple[str, int], tuple[Tracker, list]] = {}
    bar = (progress or no_progress)(total=sequence.info.length, desc=name)
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
                    live.update({(t, gid): (builders[t](), []) for t in bank.active})
            for (t, gid), (tracker, followed) in list(live.items()):
                _follow(bank, t, gid, k, tracker, followed, box_of, (frame, dets, fg), name)
            for key in [key for key in live if key[0] not in bank.active
                        or spans[key[1]][1] == k]:  # failed, or the person's last frame
                del live[key]
            bar.update(1)
    finally:
        bar.close()
    return bank.finish()


def _follow(bank: TrackerBank, t: str, gid: int, k: int, tracker: Tracker, followed: list,
            box_of: dict[int, np.ndarray], inputs: tuple, sequence: str) -> None:
    """Frame ``k`` of tracker ``t`` following person ``gid``: on the person's first frame
    its only detection is the person's ground-truth box and the followed id is picked; the
    followed track's box is reported under ``gid``."""
    if t not in bank.active:  # failed on another person of this frame
        return
    start = not followed
    if start:
        inputs = (inputs[0], Detections(box_of[gid][None], np.ones(1)), inputs[2])
    tracks = bank.feed(t, k, inputs, tracker, where=f"frame {k}, target {gid}")
    if tracks is None:
        return
    if start:
        followed.extend([_pick(tracks, box_of[gid]), box_of[gid], True])
        if followed[0] < 0:
            log.warning("%s on %s: target %d not started at frame %d (no output box overlaps "
                        "its ground truth)", t, sequence, gid, k)
    elif followed[2] and followed[0] not in {tr.id for tr in tracks}:
        followed[0] = _pick(tracks, followed[1])  # confirmed under a new id
    mine = _relabel(tracks, followed[0], gid)
    if mine:
        followed[1] = mine[0].box
        followed[2] = mine[0].extra["tentative"]
    bank.report(t, k, mine)


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
