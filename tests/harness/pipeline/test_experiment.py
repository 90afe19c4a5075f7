"""``run_experiment`` (harness/pipeline/experiment.py): the run directory, determinism,
external trackers, failing pieces recorded, bad input refused before the run."""

from __future__ import annotations

import pandas as pd
import pytest
from omegaconf import open_dict
from run_scenes import (
    BoxSequence,
    FailingSequence,
    compose_cfg,
    crossing_rows,
    mot_cfg,
    run_experiment,
    write_mot_sequence,
)

from occbench.errors import RunError
from occbench.io.mot import read_mot
from occbench.metrics import COLUMNS
from occbench.metrics.occlusion import EXTRA_COLUMNS


def test_experiment_writes_run_directory(tmp_path, mot_root):
    out = tmp_path / "run"
    result = run_experiment(mot_cfg(mot_root), out)
    assert result.ok, result.failures
    for name in ("config.yaml", "metrics.csv", "summary.md", "summary.tex", "timings.csv",
                 "plots/metrics.png", "tracks/baseline/cross-a.txt",
                 "tracks/baseline/cross-b.txt"):
        assert (out / name).is_file(), name
    assert not (out / "errors.txt").exists()
    m = pd.read_csv(out / "metrics.csv")
    assert list(m.columns) == ["tracker", "sequence", *COLUMNS, *EXTRA_COLUMNS, "complete"]
    assert list(m["sequence"]) == ["cross-a", "cross-b", "COMBINED"]
    assert set(m["tracker"]) == {"baseline"}
    combined = m[m["sequence"] == "COMBINED"].iloc[0]
    assert combined["Recall"] > 0.5 and combined["IDF1"] > 0
    assert combined["GT"] == 4  # two people in each of two sequences
    assert result.objective() == pytest.approx(combined["IDF1"], abs=1e-6)
    assert result.objective("baseline", "Recall") == pytest.approx(combined["Recall"], abs=1e-6)
    with pytest.raises(RunError, match="not a metric column"):
        result.objective(None, "NOPE")
    assert "dataset:" in (out / "config.yaml").read_text()
    # with several trackers and no objective.tracker: the first of ours, never the baseline
    # listed first (the sweep page's rule; issue 39 item 6)
    result.trackers = ["baseline", "reta"]
    assert result.objective_tracker() == "reta" and result.objective_tracker("baseline") == \
        "baseline"
    summary = (out / "summary.md").read_text()
    assert "| baseline |" in summary and "COMBINED" in summary


def test_single_target_runs_write_each_ids_follower_beside_the_tracks(tmp_path, mot_root):
    out = tmp_path / "run"
    assert run_experiment(mot_cfg(mot_root, "protocol.name=single_target",
                                  "evaluation.plot=[]"), out).ok
    tracks = read_mot(out / "tracks/baseline/cross-a.txt", kind="result")
    followers = pd.read_csv(out / "tracks/baseline/cross-a.followers.csv")
    assert list(followers.columns) == ["id", "follower"]
    assert set(tracks.ids.tolist()) <= set(followers["id"])
    assert set(followers["follower"]) <= set(followers["id"])
    run_experiment(mot_cfg(mot_root, "evaluation.plot=[]"), tmp_path / "multi")
    assert not list((tmp_path / "multi/tracks").rglob("*.followers.csv"))


def test_results_are_reproducible_byte_for_byte(tmp_path, mot_root):
    cfg = mot_cfg(mot_root, "detector.miss_rate=0.2", "detector.jitter=0.05",
                  "detector.fp_rate=0.5", "seed=7", "evaluation.plot=[]")
    run_experiment(cfg, tmp_path / "one")
    run_experiment(cfg, tmp_path / "two")
    files = ["metrics.csv", "summary.md", "tracks/baseline/cross-a.txt",
             "tracks/baseline/cross-b.txt"]
    for f in files:
        assert (tmp_path / "one" / f).read_bytes() == (tmp_path / "two" / f).read_bytes(), f
    # and the seed matters
    run_experiment(mot_cfg(mot_root, "detector.miss_rate=0.2", "detector.jitter=0.05",
                           "detector.fp_rate=0.5", "seed=8", "evaluation.plot=[]"),
                   tmp_path / "three")
    assert ((tmp_path / "one" / files[2]).read_bytes()
            != (tmp_path / "three" / files[2]).read_bytes())


def test_external_tracker_scores_equal_the_original(tmp_path, mot_root):
    first = run_experiment(mot_cfg(mot_root, "detector.jitter=0.05"), tmp_path / "a")
    folder = tmp_path / "a" / "tracks" / "baseline"
    (folder / "cross-b.txt").unlink()  # a missing file is an empty result
    cfg = mot_cfg(mot_root, "detector.jitter=0.05", f"+external.copy={folder}")
    second = run_experiment(cfg, tmp_path / "b")
    assert second.ok, second.failures
    m = second.metrics
    assert list(dict.fromkeys(m["tracker"])) == ["baseline", "copy"]
    mine = m[(m["tracker"] == "baseline") & (m["sequence"] == "cross-a")][COLUMNS]
    theirs = m[(m["tracker"] == "copy") & (m["sequence"] == "cross-a")][COLUMNS]
    pd.testing.assert_frame_equal(mine.reset_index(drop=True), theirs.reset_index(drop=True))
    orig = first.metrics
    pd.testing.assert_frame_equal(
        orig[orig["sequence"] == "cross-a"][COLUMNS].reset_index(drop=True),
        mine.reset_index(drop=True))
    empty = m[(m["tracker"] == "copy") & (m["sequence"] == "cross-b")].iloc[0]
    assert empty["Recall"] == 0 and empty["FP"] == 0
    assert second.objective("copy", "IDF1") < second.objective("baseline", "IDF1")


def test_report_false_writes_the_same_scores_without_pages_plots_or_pairs(tmp_path, mot_root):
    # a large sweep's jobs (benchmarks/tune_on_choosing.py) need the scores only
    run_experiment(mot_cfg(mot_root, "detector.jitter=0.05"), tmp_path / "a")
    other = f"+external.copy={tmp_path / 'a' / 'tracks' / 'baseline'}"  # a pair to compare
    full = run_experiment(mot_cfg(mot_root, "detector.jitter=0.05", other), tmp_path / "full")
    bare = run_experiment(mot_cfg(mot_root, "detector.jitter=0.05", other, "report=false"),
                          tmp_path / "bare")
    assert full.ok and bare.ok, (full.failures, bare.failures)
    for f in ("metrics.csv", "hota_alpha.csv", "summary.tex", "tracks/baseline/cross-a.txt"):
        assert (tmp_path / "full" / f).read_bytes() == (tmp_path / "bare" / f).read_bytes(), f
    assert (tmp_path / "full" / "report.html").is_file() and full.paired
    assert (tmp_path / "full" / "plots" / "metrics.png").is_file()
    assert not (tmp_path / "bare" / "report.html").exists()
    assert not (tmp_path / "bare" / "plots").exists() and bare.paired == []
    assert "Paired differences" in (tmp_path / "full" / "summary.md").read_text()
    assert "Paired differences" not in (tmp_path / "bare" / "summary.md").read_text()
    with pytest.raises(RunError, match="report"):
        run_experiment(mot_cfg(mot_root, "report=3"), tmp_path / "bad")


def test_external_folder_missing_and_name_clash(tmp_path, mot_root):
    with pytest.raises(RunError, match="result folder not found"):
        run_experiment(mot_cfg(mot_root, f"+external.x={tmp_path / 'nope'}"), tmp_path / "r")
    with pytest.raises(RunError, match="already a tracker"):
        run_experiment(mot_cfg(mot_root, f"+external.baseline={tmp_path}"), tmp_path / "r")


def test_malformed_external_file_is_recorded_and_the_rest_written(tmp_path, mot_root):
    ext = tmp_path / "ext"
    ext.mkdir()
    (ext / "cross-a.txt").write_text("1,1,10,10,40,100,1,-1,-1,-1\n2,1,ten,10,40,100\n")
    result = run_experiment(mot_cfg(mot_root, f"+external.bad={ext}"), tmp_path / "r")
    assert len(result.failures) == 1
    f = result.failures[0]
    assert (f.tracker, f.sequence, f.stage) == ("bad", "cross-a", "external")
    assert "cross-a.txt:2" in f.message
    errors = (tmp_path / "r" / "errors.txt").read_text()
    assert "cross-a.txt:2" in errors
    m = pd.read_csv(tmp_path / "r" / "metrics.csv")
    assert len(m[m["tracker"] == "baseline"]) == 3  # baseline rows are all there


def test_failing_sequence_is_recorded_and_others_go_on(tmp_path, monkeypatch):
    seqs = [FailingSequence("broken", crossing_rows(10), 10),
            BoxSequence("fine", crossing_rows(10), 10)]
    monkeypatch.setattr("occbench.pipeline.plan.load_sequences", lambda node: seqs)
    cfg = compose_cfg("dataset=mot", "detector=noisy_gt", "dataset.root=unused",
                      "tracker=baseline")
    result = run_experiment(cfg, tmp_path / "r")
    assert [(f.tracker, f.sequence, f.stage) for f in result.failures] == [
        ("*", "broken", "sequence")]
    assert "frame 5 is corrupt" in (tmp_path / "r" / "errors.txt").read_text()
    assert list(result.metrics["sequence"]) == ["fine", "COMBINED"]
    assert (tmp_path / "r" / "tracks" / "baseline" / "fine.txt").is_file()


def test_failing_tracker_in_experiment(tmp_path, mot_root):
    cfg = compose_cfg("dataset=mot", "detector=noisy_gt", f"dataset.root={mot_root}",
                      "tracker=all",
                      "+tracker.bad._target_=run_scenes.FailingTracker",
                      "+tracker.bad.fail_at=3")
    with open_dict(cfg):  # keep baseline and bad: the others need pixels, this data has none
        for name in [n for n in cfg.tracker if n not in ("baseline", "bad")]:
            del cfg.tracker[name]
    result = run_experiment(cfg, tmp_path / "r", tracker_name="all")
    assert {(f.tracker, f.stage) for f in result.failures} == {("bad", "tracker")}
    assert len(result.failures) == 2  # once per sequence
    m = result.metrics
    assert "bad" not in set(m["tracker"])
    assert len(m[m["tracker"] == "baseline"]) == 3
    # what the failing tracker reported before failing is on disk
    assert read_mot(tmp_path / "r" / "tracks" / "bad" / "cross-a.txt") is not None


def test_pixel_tracker_on_frameless_data_is_refused_before_the_run(tmp_path, mot_root):
    cfg = compose_cfg("dataset=mot", "detector=noisy_gt",
                      f"dataset.root={mot_root}", "tracker=reta")
    with pytest.raises(RunError, match=r"tracker 'reta' needs frame pixels .* sequence\(s\) "
                                       r"have none"):
        run_experiment(cfg, tmp_path / "r", tracker_name="reta")
    assert not (tmp_path / "r" / "tracks").exists()  # nothing started


def test_unbuilt_tracker_fails_clearly(tmp_path, mot_root):
    cfg = compose_cfg("dataset=mot", "detector=noisy_gt",
                      f"dataset.root={mot_root}", "tracker=baseline",
                      "tracker._target_=trackers.not_built_yet.Tracker")
    with pytest.raises(RunError, match="tracker 'baseline': its code "
                       "trackers.not_built_yet.Tracker is not built"):
        run_experiment(cfg, tmp_path / "r", tracker_name="baseline")


def test_bad_tracker_parameter_fails_clearly(tmp_path, mot_root):
    with pytest.raises(RunError, match="min_hits must be >= 1"):
        run_experiment(mot_cfg(mot_root, "tracker.min_hits=0"), tmp_path / "r",
                       tracker_name="baseline")


def test_malformed_gt_line_fails_clearly(tmp_path):
    root = tmp_path / "data"
    write_mot_sequence(root, "bad", 10, gt_text="1,1,10,10,40,100,1,1,1\n2,1,10,10,40\n")
    with pytest.raises(RunError, match=r"gt\.txt:2"):
        run_experiment(mot_cfg(root), tmp_path / "r")


def test_missing_dataset_path_fails_clearly(tmp_path):
    with pytest.raises(RunError, match="not found"):
        run_experiment(mot_cfg(tmp_path / "nowhere"), tmp_path / "r")


def test_empty_det_file_runs_with_no_tracks(tmp_path):
    root = tmp_path / "data"
    folder = write_mot_sequence(root, "nodets", 10)
    (folder / "det").mkdir()
    (folder / "det" / "det.txt").write_text("")
    result = run_experiment(mot_cfg(root, "detector=public"), tmp_path / "r")
    assert result.ok, result.failures
    row = result.metrics[result.metrics["sequence"] == "COMBINED"].iloc[0]
    assert row["Recall"] == 0 and row["FP"] == 0
    assert (tmp_path / "r" / "tracks" / "baseline" / "nodets.txt").read_text() == ""


def test_missing_and_corrupt_frames_fail_only_their_sequence(tmp_path):
    root = tmp_path / "data"
    a = write_mot_sequence(root, "missing", 8, frames=True)
    (a / "img1" / "000004.jpg").unlink()
    b = write_mot_sequence(root, "corrupt", 8, frames=True)
    (b / "img1" / "000003.jpg").write_bytes(b"not a jpeg")
    write_mot_sequence(root, "good", 8, frames=True)
    result = run_experiment(mot_cfg(root, "dataset.prefetch=0"), tmp_path / "r")
    failed = sorted(f.sequence for f in result.failures)
    assert failed == ["corrupt", "missing"]
    assert list(result.metrics["sequence"]) == ["good", "COMBINED"]
    text = (tmp_path / "r" / "errors.txt").read_text()
    assert "000004.jpg" in text and "000003.jpg" in text


# ----------------------------------------------------------------------------- tables


def test_scoring_and_writing_the_outputs_is_a_step_of_its_own(tmp_path, mot_root):
    """issue 39: a long step without a terminal logs a line every 15 s (occbench.progress),
    but the run's scoring, plots and page came after the last step closed: a large run's
    page and bootstrap were silent to their end. They are a step of their own, opened once
    the sequences are done and closed when report.html is written."""
    steps: list[tuple[str, str, bool]] = []

    class Step:
        def __init__(self, desc):
            self.desc = desc
            steps.append((desc, "open", (tmp_path / "run" / "report.html").exists()))

        def update(self, n=1):
            pass

        def close(self):
            steps.append((self.desc, "close", (tmp_path / "run" / "report.html").exists()))

    def factory(total=0, desc="", unit="frame"):
        return Step(desc)

    run_experiment(mot_cfg(mot_root), tmp_path / "run", progress=factory)
    assert steps[-3:] == [("sequences", "close", False),
                          ("scoring and writing the outputs", "open", False),
                          ("scoring and writing the outputs", "close", True)]
