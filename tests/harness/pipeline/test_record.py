"""A run's record (harness/pipeline/record.py): tracks written and scored from the bytes
written, a failed tracker recorded with what it reported kept, the status of a run that is
still going."""

from __future__ import annotations

import pandas as pd
from run_scenes import mot_cfg

from occbench.io.mot import read_mot
from occbench.pipeline.bank import TrackerOutput
from occbench.pipeline.plan import plan_run
from occbench.pipeline.record import RunRecord


def _record(tmp_path, mot_root) -> RunRecord:
    return RunRecord(plan_run(mot_cfg(mot_root), tmp_path / "r", "baseline"))


def test_tracks_are_written_timed_and_scored(tmp_path, mot_root):
    record = _record(tmp_path, mot_root)
    seq = record.plan.sequences[0]
    gt = seq.gt.table
    record.sequence(seq, {"baseline": TrackerOutput(gt, frames=30, seconds=0.5)})
    record.sequence_done(seq.info.name)
    written = read_mot(tmp_path / "r" / "tracks" / "baseline" / "cross-a.txt")
    assert len(written) == len(gt)
    assert record.timings == [{"tracker": "baseline", "sequence": "cross-a", "frames": 30,
                               "seconds": 0.5, "fps": 60.0}]
    m = pd.read_csv(tmp_path / "r" / "metrics.csv")
    row = m[m["sequence"] == "cross-a"].iloc[0]
    assert row["IDF1"] == 1.0 and row["MOTA"] == 1.0  # the ground truth scores perfectly
    assert m[m["sequence"] == "COMBINED"]["complete"].tolist() == [False]  # 1 of 2 so far
    assert "still running (1 of 2 sequences" in (tmp_path / "r" / "summary.md").read_text()


def test_a_failed_tracker_is_recorded_and_its_tracks_kept(tmp_path, mot_root):
    record = _record(tmp_path, mot_root)
    seq = record.plan.sequences[1]
    out = TrackerOutput(seq.gt.table.rows(seq.gt.table.frames <= 3), frames=3,
                        error="frame 4: ValueError: lost")
    record.sequence(seq, {"baseline": out})
    assert [(f.tracker, f.sequence, f.stage) for f in record.failures] == [
        ("baseline", "cross-b", "tracker")]
    assert "frame 4: ValueError: lost" in (tmp_path / "r" / "errors.txt").read_text()
    assert len(read_mot(tmp_path / "r" / "tracks" / "baseline" / "cross-b.txt")) == 6
    assert record.scores["baseline"] == {}  # not scored


def _full_disk(*args, **kwargs):
    raise OSError(28, "No space left on device")


def test_a_full_disk_names_the_file_it_could_not_write(tmp_path, mot_root, monkeypatch):
    # issue 39: "plot failed ... OSError: [Errno 28]" said nothing of which file
    import occbench.report.publish as publish

    record = _record(tmp_path, mot_root)
    for seq in record.plan.sequences:
        record.sequence(seq, {"baseline": TrackerOutput(seq.gt.table, frames=30, seconds=0.5)})
        record.sequence_done(seq.info.name)
    monkeypatch.setattr(publish, "metric_bars", _full_disk)
    monkeypatch.setattr(publish, "hota_alpha_plot", _full_disk)
    record.finish()
    messages = {f.stage: f.message for f in record.failures}
    assert messages["plot"].startswith("plots/metrics.png: OSError: [Errno 28]")
    assert messages["hota_alpha"].startswith("plots/hota_alpha.png: OSError: [Errno 28]")
    errors = (tmp_path / "r" / "errors.txt").read_text()
    assert "plots/metrics.png: OSError" in errors and "plots/hota_alpha.png: OSError" in errors
