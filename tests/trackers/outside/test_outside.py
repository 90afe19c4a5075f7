"""Outside-tracker adapters (occbench.trackers.outside) on short synthetic scenes with exact detections.

Each library is optional (the ``outside`` extra): its tests are skipped when it is missing.
ByteTrack (``occbench.trackers.bytetrack``) is our re-implementation, run through the same tests and
always tested.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import occbench.trackers
from occbench.trackers.outside._common import require
from occbench.trackers.records import Detections, TrackState

ADAPTERS = {  # class name -> import name of the library it wraps (None: ours)
    "ByteTrackTracker": None,
    "OCSortTracker": "ocsort",
    "NorfairTracker": "norfair",
    "MotpyTracker": "motpy",
}


def _make(name: str, **kwargs):
    library = ADAPTERS[name]
    if library is not None:
        pytest.importorskip(library)
    from occbench.trackers import bytetrack, outside

    return getattr(bytetrack if name == "ByteTrackTracker" else outside, name)(**kwargs)


def _two_walkers(n: int = 30) -> list[np.ndarray]:
    """Two 30x60 people walking apart, (2, 4) xywh per frame, row k is person k."""
    return [np.array([[40.0 + 3 * k, 20, 30, 60], [200.0 - 2 * k, 25, 30, 60]]) for k in range(n)]


def _run(tracker, frames, scores=None):
    out = []
    for k, boxes in enumerate(frames):
        s = np.ones(len(boxes)) if scores is None else scores[k]
        out.append(tracker.update(None, Detections(boxes, s)))
    return out


def _as_tuples(history):
    return [
        [(t.id, t.state, tuple(np.round(t.box, 9)), t.score) for t in tracks] for tracks in history
    ]


def test_trackers_package_is_this_repository():
    assert Path(occbench.trackers.__file__).resolve().parents[1] == Path(__file__).resolve().parents[3]


@pytest.mark.parametrize("name", ADAPTERS)
def test_adapter_follows_two_walkers_with_two_stable_ids(name):
    frames = _two_walkers()
    history = _run(_make(name), frames)
    reported = [[t for t in tracks if t.state.reported] for tracks in history]
    ids = {t.id for tracks in reported for t in tracks}
    assert ids == {1, 2}  # renumbered from 1, no identity switch or duplicate
    for k in range(10, len(frames)):  # warmed up (norfair: 7 hits): both reported, on their person
        assert len(reported[k]) == 2, (k, reported[k])
        for t in reported[k]:
            person = int(np.argmin(np.abs(frames[k][:, 0] - t.box[0])))
            assert person == t.id - 1  # person 0 was first (leftmost-first creation order)
            np.testing.assert_allclose(t.box, frames[k][person], atol=2.0)


@pytest.mark.parametrize("name", ADAPTERS)
def test_adapter_is_deterministic_and_reset_restarts(name):
    rng = np.random.default_rng(3)
    frames = [b + rng.normal(0, 1.5, b.shape) * [1, 1, 0, 0] for b in _two_walkers(25)]
    frames[10] = frames[10][:1]  # a miss
    frames[11] = np.zeros((0, 4))  # an empty frame
    first = _make(name)
    a = _as_tuples(_run(first, frames))
    first.reset()
    b = _as_tuples(_run(first, frames))
    c = _as_tuples(_run(_make(name), frames))
    assert a == b == c
    assert any(a)


@pytest.mark.parametrize("name", ADAPTERS)
def test_adapter_ignores_detections_below_min_score(name):
    tracker = _make(name, **({} if name == "ByteTrackTracker" else {"min_score": 0.5}))
    frames = _two_walkers(12)
    scores = [np.array([0.9, 0.2])] * len(frames)
    # (ByteTrack needs no min_score: 0.2 is below its new_track_thresh and never starts a track)
    history = _run(tracker, frames, scores)
    ids = {t.id for tracks in history for t in tracks if t.state.reported}
    assert ids == {1}
    assert all(abs(t.box[0] - frames[k][0, 0]) < 3 for k, ts in enumerate(history) for t in ts)


def test_missing_library_names_the_extra():
    with pytest.raises(ImportError, match=r"outside.*pip install no_such_tracker_lib==1\.0"):
        require("no_such_tracker_lib", "no_such_tracker_lib==1.0", "Demo")


def test_bytetrack_second_association_keeps_low_score_track():
    """BYTE's point (Zhang et al. 2022): a low-score (occluded) detection keeps its track."""
    frames = _two_walkers(20)
    scores = [np.array([0.9, 0.9]) for _ in frames]
    for k in range(8, 14):
        scores[k] = np.array([0.3, 0.9])  # person 0 partly occluded: low score
    byte = _run(_make("ByteTrackTracker"), frames, scores)
    for k in range(8, 14):
        assert {t.id for t in byte[k]} == {1, 2}
    # without the low-score round (low_thresh above 0.3) person 0 is lost meanwhile
    plain = _run(_make("ByteTrackTracker", low_thresh=0.4), frames, scores)
    for k in range(8, 14):
        assert {t.id for t in plain[k]} == {2}
    # and re-found with its old identity when the score comes back
    assert {t.id for t in plain[15]} == {1, 2}


def test_bytetrack_refinds_lost_track_within_buffer_and_reports_lost_when_asked():
    frames = _two_walkers(30)
    for k in range(10, 16):
        frames[k] = frames[k][1:]  # person 0 missed for 6 frames
    out = _run(_make("ByteTrackTracker", report_lost=3), frames)
    assert {t.id for t in out[20]} == {1, 2}  # re-found: no new identity
    assert max(t.id for ts in out for t in ts) == 2
    hidden = [[t for t in out[k] if t.id == 1] for k in range(10, 16)]
    assert [len(h) for h in hidden] == [1, 1, 1, 0, 0, 0]  # reported 3 frames while lost
    assert all(h[0].state == TrackState.OCCLUDED for h in hidden[:3])
    short = _run(_make("ByteTrackTracker", track_buffer=3), frames)
    assert {t.id for t in short[20]} == {2, 3}  # buffer exceeded: a new identity


def test_bytetrack_rejects_bad_arguments():
    from occbench.trackers.bytetrack import ByteTrackTracker

    with pytest.raises(ValueError, match="match_thresh"):
        ByteTrackTracker(match_thresh=1.5)
    with pytest.raises(ValueError, match="low_thresh"):
        ByteTrackTracker(low_thresh=0.6, track_thresh=0.5)
