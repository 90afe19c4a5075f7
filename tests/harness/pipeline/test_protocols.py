"""PBM's single-target protocol (harness.pipeline.protocols): each person started from its box, alone."""

from types import SimpleNamespace

import numpy as np
import pytest

from harness.datasets.synthetic import load_suite
from harness.errors import RunError
from harness.pipeline.protocols import run_single_target, target_spans
from harness.sources.annotations import NoisyGroundTruth
from trackers.baseline import BaselineTracker
from trackers.geometry import iou_matrix


def _crossing():
    return load_suite(["crossing"], length=40)[0]


def test_each_person_is_followed_under_its_ground_truth_id_from_its_box():
    seq = _crossing()
    gt = seq.gt.table
    out = run_single_target({"sort": BaselineTracker}, seq, NoisyGroundTruth(miss_rate=0.0))
    table = out["sort"].table
    assert out["sort"].error is None
    assert set(np.unique(table.ids)) == set(np.unique(gt.ids))
    for gid, (first, last) in target_spans(gt).items():
        mine = table.ids == gid
        assert table.frames[mine].min() == first and table.frames[mine].max() <= last
        start = np.flatnonzero(mine & (table.frames == first))[0]
        truth = np.flatnonzero((gt.ids == gid) & (gt.frames == first))[0]
        assert np.allclose(table.boxes[start], gt.boxes[truth])  # started on its own box


def test_other_people_the_tracker_starts_are_not_reported():
    seq = _crossing()
    gt = seq.gt.table
    first_id = int(gt.ids[0])
    out = run_single_target({"sort": BaselineTracker}, seq, NoisyGroundTruth(miss_rate=0.0),
                            targets=[first_id])
    table = out["sort"].table
    assert set(np.unique(table.ids)) == {first_id}
    # followed all along: every reported box overlaps that person's true box
    for k, box in zip(table.frames, table.boxes):
        truth = gt.boxes[(gt.frames == k) & (gt.ids == first_id)]
        assert iou_matrix(box[None], truth)[0, 0] > 0.5


def test_unknown_target_and_missing_ground_truth_are_errors():
    seq = _crossing()
    with pytest.raises(RunError, match="999"):
        run_single_target({"sort": BaselineTracker}, seq, NoisyGroundTruth(), targets=[999])
    frames_only = SimpleNamespace(info=seq.info, gt=None)
    with pytest.raises(RunError, match="ground truth"):
        run_single_target({"sort": BaselineTracker}, frames_only, NoisyGroundTruth())
