"""The Hydra app and its runner: end to end, determinism, external trackers, bad input.

Most runs go through Hydra's compose API and ``harness.pipeline.experiment.run_experiment`` in-process; a
few run ``python -m harness`` in a subprocess to check the command line, the printed table
and the exit status.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pandas as pd
import pytest
from hydra import compose, initialize_config_dir
from omegaconf import open_dict

from harness.datasets.base import GroundTruth, Sequence
from harness.errors import RunError
from harness.io.mot import MotTable, read_mot
from harness.metrics import COLUMNS
from harness.metrics.occlusion import EXTRA_COLUMNS
from harness.pipeline.build import tracker_configs
from harness.pipeline.experiment import run_experiment as _run_experiment
from harness.pipeline.loop import clean_detections, run_sequence, run_tracker
from harness.report.tables import best_mask, comparison, to_latex, to_markdown, to_text
from harness.sources.annotations import NoisyGroundTruth
from trackers.baseline import BaselineTracker
from trackers.records import Detections, SequenceInfo, Track

ROOT = Path(__file__).resolve().parents[3]
CONF = ROOT / "conf"
HAVE_SYNTHETIC = (CONF / "dataset" / "synthetic.yaml").is_file()
needs_synthetic = pytest.mark.skipif(not HAVE_SYNTHETIC,
                                     reason="conf/dataset/synthetic.yaml is not built yet")

# ----------------------------------------------------------------------------- fixtures


def crossing_rows(length: int = 30, width: int = 320) -> list[tuple[int, int, float, float]]:
    """Two people walking towards each other along the same line; they cross mid-sequence."""
    rows = []
    for k in range(1, length + 1):
        t = (k - 1) / (length - 1)
        rows.append((k, 1, 10 + t * (width - 60), 60.0))
        rows.append((k, 2, width - 50 - t * (width - 60), 70.0))
    return rows


def write_mot_sequence(root: Path, name: str, length: int = 30, frames: bool = False,
                       gt_text: str | None = None) -> Path:
    """A MOTChallenge folder: seqinfo.ini, gt/gt.txt (two crossing people), img1/ if asked."""
    folder = root / name
    (folder / "gt").mkdir(parents=True)
    (folder / "seqinfo.ini").write_text(
        f"[Sequence]\nname={name}\nimDir=img1\nframeRate=25\nseqLength={length}\n"
        "imWidth=320\nimHeight=240\nimExt=.jpg\n")
    if gt_text is None:
        gt_text = "".join(f"{k},{i},{x + 1:.2f},{y + 1:.2f},40.00,100.00,1,1,1\n"
                          for k, i, x, y in crossing_rows(length))
    (folder / "gt" / "gt.txt").write_text(gt_text)
    if frames:
        (folder / "img1").mkdir()
        img = np.full((240, 320, 3), 90, np.uint8)
        for k in range(1, length + 1):
            cv2.imwrite(str(folder / "img1" / f"{k:06d}.jpg"), img)
    return folder


@pytest.fixture
def mot_root(tmp_path: Path) -> Path:
    root = tmp_path / "data"
    write_mot_sequence(root, "cross-a", 30)
    write_mot_sequence(root, "cross-b", 24)
    return root


def compose_cfg(*overrides: str):
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        return compose("config", overrides=list(overrides))


def mot_cfg(root: Path, *overrides: str):
    return compose_cfg("dataset=mot", f"dataset.root={root}", "tracker=baseline", *overrides)


class BoxSequence(Sequence):
    """A sequence without pixels whose gt is given as rows (frame, id, x, y)."""

    def __init__(self, name: str, rows, length: int) -> None:
        a = np.asarray(rows, dtype=float)
        n = len(a)
        boxes = np.c_[a[:, 2:4], np.full(n, 40.0), np.full(n, 100.0)]
        table = MotTable(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), boxes, np.ones(n),
                         np.ones(n, dtype=np.int64), np.ones(n))
        self.info = SequenceInfo(name, 320, 240, 25.0, length)
        self.gt = GroundTruth(table)

    @property
    def has_pixels(self) -> bool:
        return False

    def frame(self, index: int):
        return None


class FailingSequence(BoxSequence):
    def frame(self, index: int):
        if index == 5:
            raise OSError(f"{self.info.name}: frame 5 is corrupt")


class FailingTracker(BaselineTracker):
    """Raises at frame ``fail_at``: the other trackers must go on."""

    def __init__(self, fail_at: int = 5, **kwargs) -> None:
        self.fail_at = fail_at
        super().__init__(**kwargs)

    def update(self, frame, detections, foreground=None):
        if self._frame + 1 == self.fail_at:
            raise RuntimeError("deliberate failure")
        return super().update(frame, detections, foreground)


class MutatingTracker(BaselineTracker):
    """Scribbles over its inputs: must not disturb the trackers run beside it."""

    def update(self, frame, detections, foreground=None):
        detections.boxes[:] += 50.0
        return super().update(frame, detections, foreground)


class NanSource(NoisyGroundTruth):
    """Exact detections plus one NaN box and one zero-width box per frame."""

    def detect(self, index, frame=None):
        dets, fg = super().detect(index, frame)
        boxes = np.r_[dets.boxes, [[np.nan, 1, 10, 10], [5, 5, 0, 10]]]
        return Detections(boxes, np.r_[dets.scores, 1.0, 1.0]), fg


def run_experiment(cfg, out_dir, tracker_name=None):
    """``harness.pipeline.experiment.run_experiment`` naming a single tracker as the app does (its choice)."""
    if tracker_name is None and "_target_" in cfg.tracker:
        tracker_name = "baseline"
    return _run_experiment(cfg, out_dir, tracker_name=tracker_name)


def run_app(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "HYDRA_FULL_ERROR": ""}
    env.pop("HYDRA_FULL_ERROR")
    return subprocess.run([sys.executable, "-m", "harness", "progress=false", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=300, env=env, check=False)


# ----------------------------------------------------------------------------- runner


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


def test_tracker_configs_single_and_dict():
    cfg = compose_cfg("dataset=mot", "dataset.root=x", "tracker=baseline")
    assert list(tracker_configs(cfg.tracker, "baseline")) == ["baseline"]
    cfg = compose_cfg("dataset=mot", "dataset.root=x", "tracker=all")
    names = list(tracker_configs(cfg.tracker, "all"))
    assert "baseline" in names
    with pytest.raises(RunError, match="_target_"):
        tracker_configs({"x": {"a": 1}})


# ----------------------------------------------------------------------------- experiment


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
    summary = (out / "summary.md").read_text()
    assert "| baseline |" in summary and "COMBINED" in summary


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
    monkeypatch.setattr("harness.pipeline.plan.load_sequences", lambda node: seqs)
    cfg = compose_cfg("dataset=mot", "dataset.root=unused", "tracker=baseline")
    result = run_experiment(cfg, tmp_path / "r")
    assert [(f.tracker, f.sequence, f.stage) for f in result.failures] == [
        ("*", "broken", "sequence")]
    assert "frame 5 is corrupt" in (tmp_path / "r" / "errors.txt").read_text()
    assert list(result.metrics["sequence"]) == ["fine", "COMBINED"]
    assert (tmp_path / "r" / "tracks" / "baseline" / "fine.txt").is_file()


def test_failing_tracker_in_experiment(tmp_path, mot_root):
    cfg = compose_cfg("dataset=mot", f"dataset.root={mot_root}", "tracker=all",
                      f"+tracker.bad._target_={__name__}.FailingTracker",
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
    cfg = compose_cfg("dataset=mot", f"dataset.root={mot_root}", "tracker=reta")
    with pytest.raises(RunError, match=r"tracker 'reta' needs frame pixels .* sequence\(s\) "
                                       r"have none"):
        run_experiment(cfg, tmp_path / "r", tracker_name="reta")
    assert not (tmp_path / "r" / "tracks").exists()  # nothing started


def test_unbuilt_tracker_fails_clearly(tmp_path, mot_root):
    cfg = compose_cfg("dataset=mot", f"dataset.root={mot_root}", "tracker=baseline",
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


def test_best_values_are_marked_by_direction():
    df = pd.DataFrame({"IDF1": [0.5, 0.7], "FP": [10, 3], "IDs": [2, 2], "PT": [1, 5],
                       "MOTA": [np.nan, -0.2]}, index=pd.Index(["a", "b"], name="tracker"))
    best = best_mask(df)
    assert list(best["IDF1"]) == [False, True]
    assert list(best["FP"]) == [False, True]  # lower is better
    assert list(best["IDs"]) == [True, True]  # a tie marks both
    assert list(best["PT"]) == [False, False]  # neither better nor worse
    assert list(best["MOTA"]) == [False, False]  # one finite value: nothing to compare
    md = to_markdown(df)
    assert "| b | **0.700** | **3** | **2** | 5 | -0.200 |" in md
    tex = to_latex(df.rename(index={"b": "my_tracker"}))
    assert r"my\_tracker & \textbf{0.700} & \textbf{3}" in tex
    assert "0.700*" in to_text(df)


def test_comparison_picks_combined_rows():
    m = pd.DataFrame({"tracker": ["a", "a", "b", "b"],
                      "sequence": ["s", "COMBINED", "s", "COMBINED"],
                      "IDF1": [0.1, 0.2, 0.3, 0.4], "FP": [1, 2, 3, 4]})
    c = comparison(m, ["FP", "IDF1", "absent"])
    assert list(c.index) == ["a", "b"] and list(c.columns) == ["FP", "IDF1"]
    assert list(c["IDF1"]) == [0.2, 0.4]


# ----------------------------------------------------------------------------- command line


def test_unknown_key_exits_nonzero_naming_it():
    p = run_app("foo=1")
    assert p.returncode != 0
    assert "foo" in p.stderr


@pytest.mark.parametrize("tracker,key", [
    ("reta", "stage1_unmatched_cost"), ("pbm", "occluded_cover"), ("pbm", "measured_velocity"),
    ("pbm", "assignment"), ("pbm", "overlap_as_measured"), ("pbm", "position_gate"),
    ("reta", "noise_estimate"), ("pbm", "merge_stacked"), ("pbm", "twin_refind")])
def test_an_adaptation_key_a_tracker_does_not_have_is_named(tracker, key):
    """A user config naming an adaptation that does not exist (these were removed, not
    taken: docs/adaptations.md) stops the build with the key named, not silently ignored."""
    from harness.errors import RunError
    from harness.pipeline.build import build_tracker, compose_config

    node = compose_config([f"tracker={tracker}", f"+tracker.adaptations.{key}=0"]).tracker
    with pytest.raises(RunError, match=rf"tracker\.{tracker}\.adaptations\.{key}: not an argument"):
        build_tracker(tracker, node)


def test_cli_missing_dataset_exits_nonzero_with_message(tmp_path):
    p = run_app("dataset=mot", f"dataset.root={tmp_path / 'absent'}",
                f"hydra.run.dir={tmp_path / 'run'}")
    assert p.returncode != 0
    assert "MOT dataset root not found" in p.stderr and str(tmp_path / "absent") in p.stderr


def test_cli_failure_exits_nonzero_and_keeps_outputs(tmp_path, mot_root):
    ext = tmp_path / "ext"
    ext.mkdir()
    (ext / "cross-a.txt").write_text("1,1,10,10,40,100,1\n1,2,10\n")
    run = tmp_path / "run"
    p = run_app("dataset=mot", f"dataset.root={mot_root}", "tracker=baseline",
                f"+external.broken={ext}", f"hydra.run.dir={run}")
    assert p.returncode != 0
    assert "errors.txt" in p.stderr and "cross-a.txt:2" in p.stderr
    assert "baseline" in p.stdout  # the table is still printed
    assert (run / "metrics.csv").is_file() and (run / "tracks/baseline/cross-b.txt").is_file()


@needs_synthetic
def test_cli_end_to_end_on_synthetic(tmp_path):
    run = tmp_path / "run"
    p = run_app("tracker=baseline", "dataset.length=30", "dataset.scenarios=[crossing,crowd]",
                f"hydra.run.dir={run}")
    assert p.returncode == 0, p.stderr
    assert "IDF1" in p.stdout and "baseline" in p.stdout
    for name in ("metrics.csv", "summary.md", "config.yaml", ".hydra/config.yaml",
                 "plots/metrics.png"):
        assert (run / name).is_file(), name
    m = pd.read_csv(run / "metrics.csv")
    assert list(m.columns) == ["tracker", "sequence", *COLUMNS, *EXTRA_COLUMNS, "complete"]
    seqs = [s for s in m["sequence"] if s != "COMBINED"]
    assert seqs == ["crossing", "crowd"]
    assert all((run / "tracks" / "baseline" / f"{s}.txt").is_file() for s in seqs)
    row = m[m["sequence"] == "COMBINED"].iloc[0]
    assert 0 < row["IDF1"] <= 1 and 0 < row["Recall"] <= 1


@needs_synthetic
def test_every_tracker_is_reproducible_on_synthetic(tmp_path):
    """All built trackers (pixels, exact foreground, noisy detections): same bytes twice."""
    cfg = compose_cfg("dataset.length=24", "dataset.scenarios=[crossing]",
                      "dataset.width=320", "dataset.height=240",
                      "detector.miss_rate=0.1", "detector.jitter=0.03", "detector.fp_rate=0.3",
                      "evaluation.plot=[]")
    a = _run_experiment(cfg, tmp_path / "a", tracker_name="all")
    b = _run_experiment(cfg, tmp_path / "b", tracker_name="all")
    assert a.ok and b.ok, (a.failures, b.failures)
    assert a.trackers == list(cfg.tracker)
    for rel in ["metrics.csv", *[f"tracks/{t}/crossing.txt" for t in a.trackers]]:
        assert (tmp_path / "a" / rel).read_bytes() == (tmp_path / "b" / rel).read_bytes(), rel


def test_every_metric_column_has_a_deliberate_direction():
    from harness.report.tables import direction

    lower = {"FP", "FN", "IDs", "Frag", "ML", "Song_ML%", "Song_IDS", "PBM_Missed",
             "PBM_IDs/frame", "PBM_dx%", "IDs_v0-25", "ReID_frames"}
    neutral = {"GT", "PT", "Song_GT", "PBM_GT", "ReID_n"}
    higher = {"IDF1", "HOTA", "MOTA", "MOTP", "Recall", "MT", "Song_MT%", "PBM_MT",
              "Recall_v0-25", "IDP_v0-25", "ReID"}
    for names, d in ((lower, -1), (neutral, 0), (higher, 1)):
        for c in names:
            assert c in [*COLUMNS, *EXTRA_COLUMNS], c
            assert direction(c) == d, c
