"""BoxMOT's motion-only trackers (occbench.trackers.outside.BoxmotTracker; extra ``boxmot``, skipped
when boxmot is not installed), and a tracker group leaving out a tracker whose optional
library is missing."""

from __future__ import annotations

import numpy as np
import pytest
from omegaconf import OmegaConf

from occbench.datasets.synthetic import load_suite
from occbench.errors import RunError
from occbench.pipeline.experiment import run_experiment
from occbench.pipeline.loop import run_sequence
from occbench.sources.annotations import NoisyGroundTruth
from occbench.trackers.outside._common import require
from occbench.trackers.records import Detections, SequenceInfo

NAMES = ("botsort", "bytetrack", "ocsort", "deepocsort", "hybridsort", "boosttrack",
         "occluboost", "sfsort")
INFO = SequenceInfo("walk", 320, 240, 7.0, 30)


def _make(name: str, **kwargs):
    pytest.importorskip("boxmot")
    from occbench.trackers.outside import BoxmotTracker

    t = BoxmotTracker(name, **kwargs)
    t.start_sequence(INFO)
    return t


def _two_walkers(n: int = 30) -> list[np.ndarray]:
    return [np.array([[40.0 + 3 * k, 20, 30, 60], [200.0 - 2 * k, 25, 30, 60]]) for k in range(n)]


def _run(tracker, frames):
    return [tracker.update(None, Detections(b, np.full(len(b), 0.9))) for b in frames]


@pytest.mark.parametrize("name", NAMES)
def test_follows_two_walkers_with_two_stable_ids_and_is_deterministic(name):
    frames = _two_walkers()
    tracker = _make(name)
    history = _run(tracker, frames)
    ids = {t.id for tracks in history for t in tracks}
    assert ids == {1, 2}, ids
    for k in range(10, len(frames)):
        assert len(history[k]) == 2, (k, history[k])
        for t in history[k]:
            person = int(np.argmin(np.abs(frames[k][:, 0] - t.box[0])))
            np.testing.assert_allclose(t.box, frames[k][person], atol=3.0)
    tracker.reset()
    again = _run(tracker, frames)
    assert [[(t.id, tuple(t.box)) for t in ts] for ts in again] == \
        [[(t.id, tuple(t.box)) for t in ts] for ts in history]


def test_motion_only_and_frame_rate_from_the_sequence():
    t = _make("botsort", params={"track_buffer": 30})
    assert t._tracker.cmc is None  # no camera-motion compensation
    assert t._tracker.max_time_lost == 7  # 30 frames at 30 fps = 1 s = 7 frames at 7 fps
    assert _make("bytetrack", frame_rate=60.0)._tracker.max_time_lost == 50  # 25 at 30 fps
    for name in ("deepocsort", "hybridsort", "boosttrack", "occluboost"):
        assert getattr(_make(name)._tracker, "cmc", None) is None, name
    with pytest.raises(ValueError, match="use_cmc"):
        _make("botsort", params={"use_cmc": True})
    with pytest.raises(ValueError, match="tracker must be one of"):
        _make("strongsort")


def test_runs_in_the_harness_on_box_only_and_rendered_scenes():
    pytest.importorskip("boxmot")
    from occbench.trackers.outside import BoxmotTracker

    seq = load_suite(["crossing"], length=20)[0]
    trackers = {n: BoxmotTracker(n) for n in ("sfsort", "hybridsort")}
    out = run_sequence(trackers, seq, NoisyGroundTruth())
    for n, o in out.items():
        assert o.error is None and len(o.table) > 0, n


class Ghost:
    """A tracker whose optional library is never installed."""

    def __init__(self) -> None:
        require("no_such_tracker_lib", "no_such_tracker_lib==1.0", "Ghost")


def test_a_group_leaves_out_a_tracker_whose_library_is_missing(tmp_path):
    base = {"dataset": {"_target_": "occbench.datasets.synthetic.load_suite",
                        "scenarios": ["crossing"], "length": 10},
            "detector": {"_target_": "occbench.sources.annotations.NoisyGroundTruth"}}
    ghost = {"_target_": f"{__name__}.Ghost"}
    cfg = OmegaConf.create({**base, "tracker": {
        "baseline": {"_target_": "occbench.trackers.baseline.BaselineTracker"}, "ghost": ghost}})
    res = run_experiment(cfg, tmp_path / "group")
    assert res.trackers == ["baseline"] and res.ok
    with pytest.raises(RunError, match="no_such_tracker_lib"):  # selected alone: an error
        run_experiment(OmegaConf.create({**base, "tracker": ghost}), tmp_path / "alone",
                       tracker_name="ghost")
