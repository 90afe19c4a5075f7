"""The frame loop and ``run_sequence`` (harness/pipeline/loop.py): every tracker on the same
untouched input, failures and bad boxes recorded, the foreground modes."""

from __future__ import annotations

import numpy as np
import pytest
from run_scenes import (
    BoxSequence,
    FailingTracker,
    MutatingTracker,
    NanSource,
    crossing_rows,
)

from occbench.errors import RunError
from occbench.io.mot import MotTable
from occbench.pipeline.loop import background_model, clean_detections, run_sequence, run_tracker
from occbench.sources.annotations import NoisyGroundTruth
from occbench.trackers.baseline import BaselineTracker
from occbench.trackers.records import Detections, Track


def test_run_tracker_on_exact_crossing_detections():
    seq = BoxSequence("cross", crossing_rows(30), 30)
    res = run_tracker(BaselineTracker(), seq, NoisyGroundTruth())
    assert isinstance(res, MotTable) and len(res) > 0
    assert set(np.unique(res.frames)) <= set(range(1, 31))
    # the baseline confirms after min_hits, so early frames report exact boxes
    first = res.rows(res.frames == 1)
    np.testing.assert_allclose(np.sort(first.boxes[:, 0]), [10.0, 270.0])


def test_every_tracker_sees_the_same_untouched_input():
    seq = BoxSequence("cross", crossing_rows(30), 30)
    alone = run_tracker(BaselineTracker(), seq, NoisyGroundTruth(jitter=0.05, seed=3))
    out = run_sequence({"mutant": MutatingTracker(), "base": BaselineTracker()}, seq,
                       NoisyGroundTruth(jitter=0.05, seed=3))
    together = out["base"].table
    np.testing.assert_array_equal(alone.ids, together.ids)
    np.testing.assert_array_equal(alone.boxes, together.boxes)
    assert out["mutant"].frames == 30


def test_failing_tracker_is_recorded_and_others_go_on():
    seq = BoxSequence("cross", crossing_rows(30), 30)
    out = run_sequence({"bad": FailingTracker(fail_at=5), "base": BaselineTracker()}, seq,
                       NoisyGroundTruth())
    assert out["bad"].error is not None and "deliberate failure" in out["bad"].error
    assert out["bad"].frames == 4
    assert out["base"].error is None and out["base"].frames == 30


def test_bad_detections_are_dropped_and_counted(caplog):
    dets = Detections([[0, 0, 10, 10], [np.nan, 0, 1, 1], [0, 0, -1, 5]], [1.0, 1.0, 1.0])
    kept, dropped = clean_detections(dets)
    assert dropped == 2 and len(kept) == 1
    seq = BoxSequence("cross", crossing_rows(30), 30)
    with caplog.at_level("WARNING"):
        res = run_tracker(BaselineTracker(), seq, NanSource())
    assert np.isfinite(res.boxes).all()
    assert "60 detections" in caplog.text  # 2 per frame x 30 frames, counted once


class NanTracker(BaselineTracker):
    """Reports one NaN box per frame beside its real tracks."""

    def update(self, frame, detections, foreground=None):
        return [*super().update(frame, detections, foreground),
                Track(99, np.array([np.nan, 0.0, 10.0, 10.0]))]


def test_non_finite_tracker_boxes_are_dropped_and_counted():
    seq = BoxSequence("cross", crossing_rows(10), 10)
    out = run_sequence({"nan": NanTracker()}, seq, NoisyGroundTruth())["nan"]
    assert out.dropped == 10 and out.error is None
    assert 99 not in out.table.ids and np.isfinite(out.table.boxes).all()


def test_foreground_modes():
    seq = BoxSequence("cross", crossing_rows(10), 10)
    with pytest.raises(RunError, match="exact foreground"):
        run_tracker(BaselineTracker(), seq, NoisyGroundTruth(), foreground="exact")
    with pytest.raises(RunError, match="foreground must be one of"):
        run_tracker(BaselineTracker(), seq, NoisyGroundTruth(), foreground="magic")


class LabelledSequence(BoxSequence):
    """Pixels and an exact label image, as a synthetic scene has."""

    def frame(self, index: int):
        img = np.full((240, 320, 3), 80, np.uint8)
        for row in self.gt.rows_of(index):
            x, y, w, h = self.gt.table.boxes[row].astype(int)
            img[y:y + h, x:x + w] = 200
        return img

    def foreground(self, index: int):
        lab = np.zeros((240, 320), np.int32)
        for row in self.gt.rows_of(index):
            x, y, w, h = self.gt.table.boxes[row].astype(int)
            lab[y:y + h, x:x + w] = self.gt.table.ids[row]
        return lab


class Recorder(BaselineTracker):
    """Keeps the foreground images it is given."""

    def __init__(self) -> None:
        super().__init__()
        self.seen = []

    def update(self, frame, detections, foreground=None):
        self.seen.append(foreground)
        return super().update(frame, detections, foreground)


class MaskSource(NoisyGroundTruth):
    """Exact detections plus its own (all-True) foreground mask."""

    def detect(self, index, frame=None):
        dets, _ = super().detect(index, frame)
        return dets, np.ones((240, 320), bool)


@pytest.mark.parametrize("mode", ["auto", "exact", "none", "mog2"])
def test_foreground_reaches_the_tracker(mode):
    seq = LabelledSequence("cross", crossing_rows(12, 320), 12)
    rec = Recorder()
    run_tracker(rec, seq, NoisyGroundTruth(), foreground=mode)
    assert len(rec.seen) == 12
    if mode == "none":
        assert all(fg is None for fg in rec.seen)
    elif mode == "mog2":
        assert all(fg.shape == (240, 320) and fg.dtype == bool for fg in rec.seen)
    else:  # the exact person mask, without the ground-truth ids of the label image
        assert all(fg.dtype == bool for fg in rec.seen)
        np.testing.assert_array_equal(rec.seen[3], seq.foreground(4) != 0)
    rec = Recorder()
    run_tracker(rec, seq, MaskSource(), foreground="auto")  # the detector's own mask wins
    assert all(fg.dtype == bool and fg.all() for fg in rec.seen)


def test_the_background_block_builds_the_model_from_its_groups():
    """config.yaml's ``background`` (foreground=mog2): nested group keys build the groups; a
    flat key before the groups and a refused value are one RunError naming the key."""
    model = background_model({"method": "texture_colour", "model": {"history": 80},
                              "start": {"warmup_span": "online"}})
    assert (model.model.history, model.mixture.history, model.start.warmup_span) == (
        80, 80, "online")
    assert model.model.var_threshold == 25.0 and model.cleanup.close_kernel == 7  # defaults
    with pytest.raises(RunError, match=r"^background\.history: moved to background\.model\.history"):
        background_model({"history": 80})
    with pytest.raises(RunError, match=r"^background\.model\.var_threshold must be > 0"):
        background_model({"model": {"var_threshold": 0}})
    with pytest.raises(RunError, match=r"^background: .*histry"):
        background_model({"model": {"histry": 80}})
