"""The SORT-like baseline on hand-made tracks."""

import numpy as np
import pytest

from occbench.trackers.baseline import BaselineTracker
from occbench.trackers.records import Detections


def _run(tracker, frames):
    return [tracker.update(None, Detections(b, np.ones(len(b)))) for b in frames]


def test_two_walkers_on_separate_rows_keep_their_ids():
    frames = [np.array([[10 + 3 * t, 50, 20, 40], [200 - 3 * t, 150, 20, 40]]) for t in range(30)]
    out = _run(BaselineTracker(), frames)
    assert all(len(o) == 2 for o in out)
    upper = {t.id for o in out for t in o if t.box[1] < 100}
    lower = {t.id for o in out for t in o if t.box[1] >= 100}
    assert len(upper) == 1 and len(lower) == 1 and upper != lower


def test_gap_longer_than_max_age_starts_a_new_id():
    def box(t):
        return np.array([[10 + 2 * t, 50, 20, 40]])

    frames = [box(t) for t in range(10)] + [np.zeros((0, 4))] * 5 + [box(t) for t in range(15, 25)]
    out = _run(BaselineTracker(max_age=3), frames)
    assert {t.id for t in out[5]} == {1}
    assert {t.id for t in out[-1]} == {2}
    out = _run(BaselineTracker(max_age=6), frames)
    assert {t.id for t in out[-1]} == {1}


def test_reset_restarts_ids_and_instances_are_independent():
    a, b = BaselineTracker(), BaselineTracker()
    d = [np.array([[0, 0, 10, 10]])] * 3
    _run(a, d)
    assert _run(b, d)[-1][0].id == 1
    a.reset()
    assert _run(a, [np.array([[50, 50, 10, 10]])] * 3)[-1][0].id == 1


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="iou_threshold"):
        BaselineTracker(iou_threshold=2)
    with pytest.raises(ValueError, match="min_hits"):
        BaselineTracker(min_hits=0)
    with pytest.raises(ValueError, match=r"^iou_threshold must lie in \[0, 1\], got nan"):
        BaselineTracker(iou_threshold=float("nan"))  # the message format of common.checks
