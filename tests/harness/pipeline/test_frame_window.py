"""Frame windows (``dataset.frames=[first, last]``): a part of a sequence run and scored on
its own, with the original frame numbers kept, so tuning and reporting parts of one
sequence never mix."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hydra import compose, initialize_config_dir

from occbench.datasets.base import FrameWindow, window
from occbench.datasets.mot import load_mot
from occbench.datasets.synthetic import load_suite
from occbench.io.mot import read_mot
from occbench.pipeline.experiment import run_experiment
from occbench.pipeline.loop import run_sequence
from occbench.sources.annotations import NoisyGroundTruth, PublicDetections
from occbench.trackers.baseline import BaselineTracker

ROOT = Path(__file__).resolve().parents[3]


def _mot_folder(root: Path, length: int = 20) -> Path:
    """A box-only MOT sequence: one person walking right, gt and det on every frame."""
    folder = root / "walk"
    (folder / "gt").mkdir(parents=True)
    (folder / "det").mkdir()
    (folder / "seqinfo.ini").write_text(
        f"[Sequence]\nname=walk\nframeRate=25\nseqLength={length}\nimWidth=320\nimHeight=240\n")
    gt = "".join(f"{k},1,{10 + 5 * k},50,40,100,1,1,1\n" for k in range(1, length + 1))
    det = "".join(f"{k},-1,{11 + 5 * k},51,40,100,0.9\n" for k in range(1, length + 1))
    (folder / "gt" / "gt.txt").write_text(gt)
    (folder / "det" / "det.txt").write_text(det)
    return folder


def test_window_keeps_original_numbers_gt_and_detections(tmp_path):
    seq = load_mot(_mot_folder(tmp_path))[0]
    win = load_mot(tmp_path / "walk", frames=[8, 15])[0]
    assert isinstance(win, FrameWindow) and win.info.length == 8 and win.info.name == "walk"
    assert list(win.frame_numbers()) == list(range(8, 16))
    assert sorted(set(win.gt.table.frames.tolist())) == list(range(8, 16))
    assert sorted(set(win.public_detections.frames.tolist())) == list(range(8, 16))
    keep = (seq.gt.table.frames >= 8) & (seq.gt.table.frames <= 15)
    np.testing.assert_array_equal(win.gt.table.boxes, seq.gt.table.boxes[keep])
    # the public detections of a window frame are the original's, under its own number
    src_full, src_win = PublicDetections(), PublicDetections()
    src_full.start(seq)
    src_win.start(win)
    np.testing.assert_array_equal(src_win.detect(12, None)[0].boxes,
                                  src_full.detect(12, None)[0].boxes)
    assert len(src_win.detect(3, None)[0]) == 0  # nothing outside the window


def test_window_frames_and_foreground_are_the_originals_and_nothing_else():
    seq = load_suite(["crossing"], length=12)[0]
    win = window([seq], [5, 9])[0]
    np.testing.assert_array_equal(win.frame(5), seq.frame(5))
    np.testing.assert_array_equal(win.foreground(9), seq.foreground(9))
    np.testing.assert_array_equal(win.nth_frame(1), seq.frame(5))
    for k in (4, 10):
        with pytest.raises(IndexError, match="outside the window 5..9"):
            win.frame(k)
    assert [k for k, _ in win.frames()] == [5, 6, 7, 8, 9]


@pytest.mark.parametrize("frames", [[0, 5], [5, 4], [5, 13], [5], [1.5, 3]])
def test_bad_window_is_a_clear_error(frames):
    seq = load_suite(["crossing"], length=12)[0]
    with pytest.raises(ValueError, match="frames"):
        window([seq], frames)


def test_run_on_a_window_reports_original_frame_numbers_and_same_detections():
    """A tracker run on frames 6..12 sees exactly the detections the whole run gives those
    frames (noisy gt is seeded per frame number) and writes tracks numbered 6..12."""
    seq = load_suite(["crossing"], length=12)[0]
    win = window([seq], [6, 12])[0]

    class Recorder(BaselineTracker):
        def __init__(self):
            super().__init__(min_hits=1)
            self.seen = []

        def update(self, frame, detections, foreground=None):
            self.seen.append(detections.boxes.copy())
            return super().update(frame, detections, foreground)

    full, part = Recorder(), Recorder()
    run_sequence({"t": full}, seq, NoisyGroundTruth(miss_rate=0.3, jitter=0.05, seed=2))
    out = run_sequence({"t": part}, win, NoisyGroundTruth(miss_rate=0.3, jitter=0.05, seed=2))
    assert len(part.seen) == 7
    for a, b in zip(part.seen, full.seen[5:], strict=True):
        np.testing.assert_array_equal(a, b)
    frames = out["t"].table.frames
    assert len(frames) and frames.min() >= 6 and frames.max() <= 12


def test_dataset_frames_key_in_the_app_config(tmp_path):
    _mot_folder(tmp_path / "data")
    with initialize_config_dir(config_dir=str(ROOT / "conf"), version_base="1.3"):
        cfg = compose("config", overrides=[
            "dataset=mot", f"dataset.root={tmp_path / 'data'}", "dataset.frames=[11,20]",
            "detector=public", "tracker=baseline", "tracker.min_hits=1"])
    res = run_experiment(cfg, tmp_path / "run", tracker_name="baseline")
    assert res.ok
    tracks = read_mot(tmp_path / "run" / "tracks" / "baseline" / "walk.txt")
    assert tracks.frames.min() == 11 and tracks.frames.max() == 20
    row = res.metrics[(res.metrics.sequence == "walk")].iloc[0]
    assert row["FN"] == 0 and row["FP"] == 0  # scored on frames 11..20 only
    for name in ("caviar", "mot", "video", "replay", "synthetic"):
        with initialize_config_dir(config_dir=str(ROOT / "conf"), version_base="1.3"):
            c = compose("config", overrides=[f"dataset={name}", "dataset.frames=[2,3]"])
        assert list(c.dataset.frames) == [2, 3]
