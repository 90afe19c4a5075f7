"""The SORT-like baseline on hand-made tracks."""

import numpy as np
import pytest

from trackers.baseline import BaselineTracker
from trackers.records import Detections


def _run(tracker, frames):
    return [tracker.update(None, Detections(b, np.ones(len(b)))) for b in frames]


def test_two_parallel_walkers_keep_ids():
    frames = [np.array([[10 + 3 * t, 50, 20, 40], [200 - 3 * t, 150, 20, 40]]) for t in range(30)]
    out = _run(BaselineTracker(), frames)
    ids = {(t.id, round(t.box[1] / 100)) for t in out[-1]}
    assert ids == {(1, 0), (2, 2)} or ids == {(1, 0), (2, 1)} or len({i for i, _ in ids}) == 2
    assert all(len(o) == 2 for o in out)
    assert {t.id for o in out for t in o} == {1, 2}


def test_gap_longer_than_max_age_starts_a_new_id():
    box = lambda t: np.array([[10 + 2 * t, 50, 20, 40]])  # noqa: E731
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
