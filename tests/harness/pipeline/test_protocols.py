"""PBM's single-target protocol (occbench.pipeline.protocols): each person started from its
box once, then followed by the tracker alone, restarts reported under new ids."""

from types import SimpleNamespace

import numpy as np
import pytest

from occbench.datasets.base import window
from occbench.datasets.synthetic import load_suite
from occbench.errors import RunError
from occbench.metrics.paper import paper_metrics
from occbench.pipeline.protocols import run_single_target, target_spans
from occbench.sources.annotations import NoisyGroundTruth
from occbench.trackers.baseline import BaselineTracker
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.records import Detections, Track, TrackState


def _crossing():
    return load_suite(["crossing"], length=40)[0]


def test_each_person_is_started_on_its_box_and_reported_under_an_id_of_its_own():
    seq = _crossing()
    gt = seq.gt.table
    out = run_single_target({"sort": BaselineTracker}, seq, NoisyGroundTruth(miss_rate=0.0))
    table = out["sort"].table
    assert out["sort"].error is None
    spans = target_spans(gt)
    started = set()
    for gid, (first, last) in spans.items():
        truth = np.flatnonzero((gt.ids == gid) & (gt.frames == first))[0]
        start = np.flatnonzero((table.frames == first)
                               & np.all(np.isclose(table.boxes, gt.boxes[truth]), axis=1))
        assert len(start) == 1  # started on its own box
        started.add(int(table.ids[start[0]]))
        assert table.frames[table.ids == table.ids[start[0]]].max() <= last
    assert len(started) == len(spans)  # one id per person's start
    # the SORT-like baseline loses the hidden walker of the crossing and restarts on it
    # under a new id, reported only after the followed id's last report
    (restart,) = set(np.unique(table.ids)) - started
    assert table.frames[table.ids == restart].min() > min(
        table.frames[table.ids == i].max() for i in started)


def test_other_people_the_tracker_starts_are_not_reported():
    seq = _crossing()
    gt = seq.gt.table
    first_id = int(gt.ids[0])
    out = run_single_target({"sort": BaselineTracker}, seq, NoisyGroundTruth(miss_rate=0.0),
                            targets=[first_id])
    table = out["sort"].table
    assert len(np.unique(table.ids)) == 1
    # followed all along: every reported box overlaps that person's true box
    for k, box in zip(table.frames, table.boxes):
        truth = gt.boxes[(gt.frames == k) & (gt.ids == first_id)]
        assert iou_matrix(box[None], truth)[0, 0] > 0.5


class _HoldsItsFirstBox:
    """A stand-in single-target tracker holding its first detection's box (``_follow`` may
    move it on later frames); ``_tracks`` says what it reports on frame ``k``."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.k, self.box = 0, None

    def update(self, frame, detections: Detections, foreground=None) -> list[Track]:
        self.k += 1
        if self.box is None:
            self.box = detections.boxes[0]
        else:
            self._follow(detections)
        return self._tracks()

    def _follow(self, detections: Detections) -> None:
        pass


class _LosesAndRestarts(_HoldsItsFirstBox):
    """Holds its box as id 1 for 5 frames, then loses it and restarts as id 2, following
    the detection nearest its last box."""

    def _follow(self, detections: Detections) -> None:
        if len(detections):
            near = np.argmin(np.abs(detections.boxes[:, :2] - self.box[:2]).sum(axis=1))
            self.box = detections.boxes[near]

    def _tracks(self) -> list[Track]:
        return [Track(1 if self.k <= 5 else 2, self.box.copy())]


def test_a_follower_that_loses_its_person_restarts_under_a_new_id():
    seq = _crossing()
    gt = seq.gt.table
    out = run_single_target({"x": _LosesAndRestarts}, seq, NoisyGroundTruth(miss_rate=0.0))
    table = out["x"].table
    spans = target_spans(gt)
    assert len(np.unique(table.ids)) == 2 * len(spans)  # one restart per person
    followers = out["x"].followers  # id -> its follower's first id: a restart shares it
    firsts = set(followers.values())
    assert len(firsts) == len(spans) and all(followers[f] == f for f in firsts)
    assert all(list(followers.values()).count(f) == 2 for f in firsts)
    m = paper_metrics(gt, table)
    assert m["PBM_Over"] == len(spans)  # each person: two ids
    assert m["PBM_IDs/traj"] == 2.0
    assert m["PBM_MT1"] == 0


class _ConfirmsUnderANewId(_HoldsItsFirstBox):
    """Holds its first detection's box TENTATIVE as id 1 for 2 frames, then CONFIRMED as id
    7 (a tracker numbering tracks at confirmation)."""

    def _tracks(self) -> list[Track]:
        if self.k <= 2:
            return [Track(1, self.box.copy(), TrackState.TENTATIVE)]
        return [Track(7, self.box.copy(), TrackState.CONFIRMED)]


def test_a_track_confirmed_under_a_new_id_keeps_its_reported_id():
    seq = _crossing()
    first_id = int(seq.gt.table.ids[0])
    out = run_single_target({"x": _ConfirmsUnderANewId}, seq, NoisyGroundTruth(miss_rate=0.0),
                            targets=[first_id])
    table = out["x"].table
    first, last = target_spans(seq.gt.table)[first_id]
    assert np.unique(table.ids).tolist() == [1]
    assert table.frames.tolist() == list(range(first, last + 1))  # tentative frames too


def test_a_frame_window_runs_its_own_frames():
    seq = window([_crossing()], [11, 30])[0]
    out = run_single_target({"sort": BaselineTracker}, seq, NoisyGroundTruth(miss_rate=0.0))
    table = out["sort"].table
    assert out["sort"].error is None and len(table.frames)
    assert table.frames.min() >= 11 and table.frames.max() <= 30


def test_unknown_target_and_missing_ground_truth_are_errors():
    seq = _crossing()
    with pytest.raises(RunError, match="999"):
        run_single_target({"sort": BaselineTracker}, seq, NoisyGroundTruth(), targets=[999])
    frames_only = SimpleNamespace(info=seq.info, gt=None)
    with pytest.raises(RunError, match="ground truth"):
        run_single_target({"sort": BaselineTracker}, frames_only, NoisyGroundTruth())
