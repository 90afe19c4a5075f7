"""PBM's evaluation protocol: each person started by hand from its ground-truth box, then
followed by the tracker alone, restarts and all.

PBM (Section 3, Table 1) initialises every evaluated person by hand ("the user just drew a
bounding box around the chosen target") and follows it alone. ``run_single_target`` does
that for any tracker: for each chosen ground-truth person, a fresh tracker (a *follower*)
starts at the person's first ground-truth frame, where its only detection is that person's
ground-truth box; from the next frame on it gets the detection source's detections like any
run, and no ground truth. The followed track is the follower's track that best overlaps
(IoU >= 0.5) the ground-truth box on that first frame (a tracker that gives a tentative
track a new id at confirmation is followed to that id by the overlap with its last box).

After that initialisation, which happens once per person, the follower's own ids are
reported as they are: when the followed track is gone from the follower's output and the
follower starts a new track (a single-target tracker restarting after losing its person,
e.g. ``max_targets: 1``), that new track is followed and reported under a new id. A
follower that drifts onto someone else and restarts thus shows as over-segmentation and
more IDs per trajectory; a restart keeps its follower's past (``TrackerOutput.followers``:
reported id -> the id its follower started under, written beside the tracks), so one that
lands on another person is an ID switch, as when PBM's tracker drifts onto someone under its
one id (PBM Table 1's columns, ``occbench.metrics.paper``). A follower's other tracks (people a multi-target
tracker starts while its followed track lives) are not reported; PBM itself runs with
``starts: GivenTargetOnly`` (``occbench.trackers.layered.starts``), so it follows its one target
with no competing or replacing targets. Ids are made unique over the followers of one
tracker (numbered 1, 2, ... in order of first report); the hand-started track is reported
from its first frame, restarts as the tracker reports them. A person's follower ends at the
person's last ground-truth frame.

Frames are read and detected once; every tracker and person gets its own copy. The frames
run are the sequence's own (``Sequence.frame_numbers``: a ``dataset.frames`` window keeps
its original numbers).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from occbench.datasets.base import Sequence
from occbench.errors import RunError
from occbench.io.mot import MotTable
from occbench.pipeline.bank import TrackerBank, TrackerOutput
from occbench.pipeline.loop import ForegroundProvider, clean_detections, no_progress
from occbench.sources.base import DetectionSource
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.protocol import Tracker
from occbench.trackers.records import Detections, Track, TrackState

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


@dataclass
class Follower:
    """One tracker following one person.

    Attributes:
        tracker: the follower's own tracker.
        started: the hand initialisation (its first frame) is done.
        followed: the tracker id followed now; -1 before the start is picked or after a
            pick failed.
        last_box: (4,) xywh of the followed track's last report.
        tentative: the followed track was TENTATIVE at its last report.
        hand_started: the followed track is the hand-started one (reported from its first
            frame whatever its state).
        seen: every tracker id the follower has output so far.
        out_ids: tracker id -> reported id.
        first_id: the reported id of the follower's first report (its hand-started track);
            -1 before it.
    """

    tracker: Tracker
    started: bool = False
    followed: int = -1
    last_box: np.ndarray | None = None
    tentative: bool = True
    hand_started: bool = True
    seen: set[int] = field(default_factory=set)
    out_ids: dict[int, int] = field(default_factory=dict)
    first_id: int = -1


@dataclass
class ReportedIds:
    """One tracker's reported ids under the protocol, unique over all its followers.

    Attributes:
        next: the next free reported id (1-based).
        first_of: reported id -> the reported id of its follower's first report (the
            follower's lineage, ``TrackerOutput.followers``).
    """

    next: int = 1
    first_of: dict[int, int] = field(default_factory=dict)

    def of(self, follower: Follower, track_id: int) -> int:
        """The reported id of ``follower``'s tracker id ``track_id`` (a new one the first time)."""
        if track_id not in follower.out_ids:
            follower.out_ids[track_id] = self.next
            if follower.first_id < 0:
                follower.first_id = self.next
            self.first_of[self.next] = follower.first_id
            self.next += 1
        return follower.out_ids[track_id]


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
        sequence: a sequence with ground truth (a frame window runs its own frames).
        source: detection source for the frames after each person's first.
        foreground, background: as for ``occbench.pipeline.loop.run_sequence``.
        progress: progress-bar factory; None shows nothing.
        targets: ground-truth ids to follow; None = every person.
    Returns:
        name -> ``TrackerOutput`` whose table holds every follower's followed tracks (the
        hand-started one and its restarts, module docstring) under ids unique within the
        table (0-based xywh). A tracker raising is stopped for every person (its ``error``
        set) while the other trackers go on.
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
    live: dict[tuple[str, int], Follower] = {}
    ids = {t: ReportedIds() for t in builders}
    bar = (progress or no_progress)(total=sequence.info.length, desc=name)
    try:
        for k in sequence.frame_numbers():
            frame = sequence.frame(k)
            dets, mask = source.detect(k, frame)
            dets, _ = clean_detections(dets)
            fg = fg_of(k, frame, mask)
            here = sequence.gt.rows_of(k)
            box_of = dict(zip(gt.ids[here].tolist(), gt.boxes[here]))
            for gid, (first, _) in spans.items():
                if first == k:
                    live.update({(t, gid): Follower(builders[t]()) for t in bank.active})
            for (t, gid), follower in list(live.items()):
                if t not in bank.active:  # failed on another person of this frame
                    continue
                start = None if follower.started else box_of[gid]
                inputs = (frame, dets if start is None else Detections(start[None], np.ones(1)), fg)
                tracks = bank.feed(t, k, inputs, follower.tracker, where=f"frame {k}, target {gid}")
                if tracks is None:
                    continue
                mine = _follow(follower, tracks, start)
                follower.started = True
                if start is not None and follower.followed < 0:
                    log.warning("%s on %s: target %d not started at frame %d (no output box "
                                "overlaps its ground truth)", t, name, gid, k)
                bank.report(t, k, [Track(ids[t].of(follower, tr.id), tr.box, tr.state, tr.score,
                                         tr.extra) for tr in mine])
            for key in [key for key in live if key[0] not in bank.active
                        or spans[key[1]][1] == k]:  # failed, or the person's last frame
                del live[key]
            bar.update(1)
    finally:
        bar.close()
    outputs = bank.finish()
    for t, out in outputs.items():
        out.followers = ids[t].first_of
    return outputs


def _follow(follower: Follower, tracks: list[Track], start: np.ndarray | None) -> list[Track]:
    """The follower's tracks of one frame -> the followed one to report (at most one).

    ``start``: the person's ground-truth box on its first frame (the hand initialisation:
    the followed track is picked by overlap), else None. Later, when the followed id is
    absent, a track the follower never output before is followed instead: the confirmed
    form of a tentative followed track when one overlaps its last box (reported under the
    same id), else the follower's restart (the new track of lowest id).
    """
    now = [t for t in tracks if t.state in _FOLLOWED]
    ids = {t.id for t in now}
    if start is not None:
        follower.followed = _pick(now, start)
    elif follower.followed not in ids:
        new = [t for t in now if t.id not in follower.seen]
        same = _pick(new, follower.last_box) if follower.tentative and new else -1
        if same >= 0:  # confirmed under a new id: still the hand-started track, same report id
            if follower.followed in follower.out_ids:
                follower.out_ids[same] = follower.out_ids[follower.followed]
            follower.followed = same
        elif new:
            follower.followed = min(t.id for t in new)  # a restart
            follower.hand_started = False
    follower.seen |= {t.id for t in tracks}
    for t in now:
        if t.id == follower.followed:
            follower.last_box = np.asarray(t.box, dtype=np.float64)
            follower.tentative = t.state == TrackState.TENTATIVE
            hand = follower.hand_started and follower.tentative
            state = TrackState.CONFIRMED if hand else t.state
            return [Track(t.id, follower.last_box, state, t.score,
                          {"tentative": follower.tentative})]
    return []


def _pick(tracks: list[Track], box: np.ndarray) -> int:
    """The id of the track of ``tracks`` best overlapping ``box`` (IoU >= 0.5), else -1."""
    if not tracks:
        return -1
    iou = iou_matrix(np.array([t.box for t in tracks]), box[None])[:, 0]
    best = int(np.argmax(iou))
    return tracks[best].id if iou[best] >= 0.5 else -1
