"""The tracker bank (harness/pipeline/bank.py): each tracker its own copy of the inputs,
``update`` timed by the bank's clock, a failing tracker dropped out and recorded while the
others go on, the reported rows collected."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from occbench.pipeline.bank import TrackerBank, copy_inputs
from occbench.trackers.records import Detections, Track, TrackState


class _Scribbler:
    """Reports one confirmed track on its first detection and one tentative track, after
    scribbling over every input it is given."""

    def __init__(self, fail_at: int | None = None) -> None:
        self.fail_at, self.k, self.seen = fail_at, 0, []

    def reset(self) -> None:
        self.k = 0

    def update(self, frame, detections, foreground=None):
        self.k += 1
        if self.k == self.fail_at:
            raise ValueError("lost its way")
        self.seen.append((frame.copy(), detections.boxes.copy(), foreground.copy()))
        box = detections.boxes[0].copy()
        frame[:] = 255
        detections.boxes[:] = -1.0
        foreground[:] = False
        return [Track(7, box, TrackState.CONFIRMED, score=0.5),
                Track(8, box, TrackState.TENTATIVE)]


def _inputs(k: int):
    frame = np.full((4, 5, 3), k, np.uint8)
    dets = Detections(np.array([[1.0, 2.0, 3.0, 4.0 + k]]), np.ones(1))
    fg = np.ones((4, 5), bool)
    return frame, dets, fg


def test_every_tracker_gets_its_own_copy_of_the_inputs():
    a, b = _Scribbler(), _Scribbler()
    bank = TrackerBank({"a": a, "b": b})
    for k in (1, 2):
        bank.step(k, *_inputs(k))
    for k, seen in enumerate(b.seen, 1):  # b saw the frame a had scribbled over untouched
        frame, boxes, _ = _inputs(k)
        assert np.array_equal(seen[0], frame) and np.array_equal(seen[1], boxes.boxes)
        assert seen[2].all()


def test_copy_inputs_copies_every_array():
    frame, dets, fg = _inputs(1)
    c = copy_inputs(frame, dets, fg)
    assert c[0] is not frame and c[1].boxes is not dets.boxes and c[2] is not fg
    assert np.array_equal(c[0], frame) and np.array_equal(c[1].scores, dets.scores)
    assert copy_inputs(None, dets, None)[::2] == (None, None)


def test_a_failing_tracker_drops_out_and_the_others_go_on():
    bad, good = _Scribbler(fail_at=2), _Scribbler()
    bank = TrackerBank({"bad": bad, "good": good})
    fed = [bank.step(k, *_inputs(k)) for k in (1, 2, 3)]
    assert [sorted(f) for f in fed] == [["bad", "good"], ["good"], ["good"]]
    assert bank.active == ["good"] and bad.k == 2  # not fed after its failure
    out = bank.finish()
    assert out["bad"].error == "frame 2: ValueError: lost its way"
    assert "lost its way" in out["bad"].trace
    assert out["bad"].frames == 1 and out["bad"].table.frames.tolist() == [1]  # kept
    assert out["good"].error is None and out["good"].table.frames.tolist() == [1, 2, 3]


def test_update_is_timed_by_the_banks_clock():
    ticks = itertools.count(0.0, 0.25)  # every reading 0.25 s after the last
    bank = TrackerBank({"a": _Scribbler()}, clock=lambda: next(ticks))
    for k in (1, 2, 3, 4):
        bank.step(k, *_inputs(k))
    out = bank.finish()["a"]
    assert out.frames == 4 and out.seconds == pytest.approx(1.0) and out.fps == pytest.approx(4)


def test_only_reported_finite_tracks_are_collected():
    bank = TrackerBank({"a": _Scribbler()})
    tracks = bank.step(1, *_inputs(1))["a"]
    assert [t.id for t in tracks] == [7, 8]  # every state returned
    bank.report("a", 2, [Track(9, np.array([0.0, 0.0, np.nan, 1.0]), TrackState.CONFIRMED)])
    out = bank.finish()["a"]
    assert out.table.ids.tolist() == [7] and out.dropped == 1
    assert out.table.boxes.tolist() == [[1.0, 2.0, 3.0, 5.0]] and out.table.conf.tolist() == [0.5]


def test_feed_charges_a_given_tracker_to_a_name():
    bank = TrackerBank(dict.fromkeys(["t"]))
    one, two = _Scribbler(), _Scribbler(fail_at=1)
    assert bank.feed("t", 1, _inputs(1), one) is not None
    assert bank.feed("t", 1, _inputs(1), two, where="frame 1, target 3") is None
    out = bank.finish()["t"]
    assert out.frames == 1 and out.error == "frame 1, target 3: ValueError: lost its way"
    assert bank.active == []
