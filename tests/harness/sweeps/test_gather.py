"""Sweeps: job status and skipping, gathering into sweep.csv, plots, launchers.

The end-to-end tests run a real Hydra multirun of the baseline tracker on a tiny box-only
MOT sequence written to a temporary folder (noisy-gt detections: seed matters).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from occbench.report.tables import comparison, to_markdown
from occbench.sweeps.gather import (
    DONE,
    FAILED,
    aggregate,
    finished,
    gather,
    guarded,
    interval,
    is_replicate,
    plot_sweep,
    setting_table,
    summary_text,
    swept,
    tick,
    write_status,
    write_sweep,
)
from occbench.sweeps.gather import main as sweep_main
from occbench.sweeps.tables import markdown_table

ROOT = Path(__file__).resolve().parents[3]


# --------------------------------------------------------------------------- unit


def test_guarded_records_done_skips_repeats_and_records_failures(tmp_path):
    calls = []

    def job() -> float:
        calls.append(1)
        return 0.75

    over = ["tracker.max_age=3", "seed=1"]
    assert guarded(tmp_path / "0", over, job) == 0.75
    assert json.loads((tmp_path / "0" / "status.json").read_text())["status"] == DONE
    # same overrides again: skipped, stored objective returned
    assert guarded(tmp_path / "0", over, job) == 0.75 and len(calls) == 1
    # other overrides in the same job dir (a different sweep): run again
    assert guarded(tmp_path / "0", ["tracker.max_age=5", "seed=1"], job) == 0.75
    assert len(calls) == 2

    def bad() -> float:
        raise ValueError("max_age must be >= 0, got -1")

    assert math.isnan(guarded(tmp_path / "1", over, bad))
    status = json.loads((tmp_path / "1" / "status.json").read_text())
    assert status["status"] == FAILED and "max_age must be >= 0" in status["error"]
    assert finished(tmp_path / "1", over) is None  # a failed job is run again next time


def test_a_failed_job_is_one_line_its_traceback_only_when_verbose(tmp_path, caplog, monkeypatch):
    """An input mistake fails every job of a sweep alike: one line per job, no traceback
    (issue 39: a traceback per job); ``occbench -v`` (OCCBENCH_VERBOSE=1) shows it."""
    def bad() -> float:
        raise ValueError("max_age must be >= 0, got -1")

    monkeypatch.delenv("OCCBENCH_VERBOSE", raising=False)
    with caplog.at_level("ERROR"):
        guarded(tmp_path / "0", ["tracker.max_age=-1"], bad)
    (record,) = caplog.records
    assert record.getMessage().endswith("job failed: ValueError: max_age must be >= 0, got -1")
    assert not record.exc_info and "Traceback" not in caplog.text
    caplog.clear()
    monkeypatch.setenv("OCCBENCH_VERBOSE", "1")
    with caplog.at_level("ERROR"):
        guarded(tmp_path / "1", ["tracker.max_age=-1"], bad)
    assert caplog.records[0].exc_info and "Traceback" in caplog.text


def test_a_job_refused_by_the_app_says_its_cause_once(tmp_path, caplog, monkeypatch):
    """The app's refusal is already one line 'occbench: <cause>': a sweep's line says the
    cause, not 'job failed: AppError: occbench: tracker ...' (two prefixes, a class name)."""
    from occbench.commands.run import AppError

    def refused() -> float:
        raise AppError("occbench: tracker 'baseline': ValueError: max_age must be >= 0")

    monkeypatch.delenv("OCCBENCH_VERBOSE", raising=False)
    with caplog.at_level("ERROR"):
        guarded(tmp_path / "0", ["tracker.max_age=-1"], refused)
    assert caplog.records[0].getMessage().endswith(
        "job failed: tracker 'baseline': ValueError: max_age must be >= 0")
    status = json.loads((tmp_path / "0" / "status.json").read_text())
    assert status["error"] == "tracker 'baseline': ValueError: max_age must be >= 0"


def _fake_job(root: Path, num: int, overrides: list[str], metrics: dict | None,
              status: str = DONE, error: str | None = None) -> None:
    d = root / str(num)
    (d / ".hydra").mkdir(parents=True)
    (d / ".hydra" / "overrides.yaml").write_text(yaml.safe_dump(overrides))
    if metrics is not None:
        rows = [{"tracker": "baseline", "sequence": s, **metrics} for s in ("a", "COMBINED")]
        pd.DataFrame(rows).to_csv(d / "metrics.csv", index=False)
    write_status(d, status, overrides, metrics and metrics["IDF1"], error)


def test_gather_one_row_per_job_and_sequence_with_params_status_and_errors(tmp_path):
    _fake_job(tmp_path, 0, ["tracker=baseline", "tracker.max_age=1", "seed=0"],
              {"IDF1": 0.5, "IDs": 3})
    _fake_job(tmp_path, 1, ["tracker=baseline", "tracker.max_age=1", "seed=1"],
              {"IDF1": 0.7, "IDs": 1})
    _fake_job(tmp_path, 2, ["tracker=baseline", "tracker.max_age=3", "seed=0"], None,
              FAILED, "ValueError: boom")
    (tmp_path / "10" / ".hydra").mkdir(parents=True)  # a job that never finished
    frame = gather(tmp_path)
    assert frame["job"].tolist() == ["0", "0", "1", "1", "2", "10"]  # numeric job order
    assert list(frame.columns[:6]) == ["job", "tracker_choice", "tracker.max_age", "seed",
                                       "status", "error"]
    assert frame["status"].tolist() == [DONE] * 4 + [FAILED, "missing"]
    assert frame.loc[4, "error"] == "ValueError: boom"
    assert frame["IDs"].dtype.name == "Int64"  # counts stay integers beside empty rows
    assert swept(frame) == ["tracker.max_age", "seed"]
    agg = aggregate(frame, ["tracker.max_age"], ["IDF1"])
    assert len(agg) == 1 and agg.loc[0, "IDF1"] == pytest.approx(0.6)
    # 95% bootstrap interval of (0.5, 0.7): means of resamples of two, 0.5 .. 0.7
    assert (agg.loc[0, "IDF1_low"], agg.loc[0, "IDF1_high"]) == pytest.approx((0.5, 0.7))
    write_sweep(tmp_path, ["IDF1", "IDs"])
    again = pd.read_csv(tmp_path / "sweep.csv", keep_default_na=False)
    assert len(again) == 6
    md = (tmp_path / "sweep.md").read_text()
    assert "2 failed or missing" in md and "job 2: failed: ValueError: boom" in md
    assert (tmp_path / "plots" / "sweep_tracker_max_age.png").is_file()


def test_interval_hand_values():
    mean, low, high = interval(np.array([1.0, 2.0, 3.0, np.nan]))
    assert mean == 2.0 and 1.0 <= low < 2.0 < high <= 3.0
    assert interval(np.array([4.0])) == (4.0, 4.0, 4.0)
    assert math.isnan(interval(np.array([]))[0])


def test_two_swept_parameters_give_a_heatmap(tmp_path):
    num = 0
    for a in (1, 3):
        for b in (0.1, 0.3):
            for seed in (0, 1):
                _fake_job(tmp_path, num, [f"tracker.max_age={a}", f"tracker.iou_threshold={b}",
                                          f"seed={seed}"], {"IDF1": a * b + seed, "HOTA": 0.5})
                num += 1
    frame = gather(tmp_path)
    paths = plot_sweep(frame, tmp_path / "plots", ["IDF1", "HOTA"])
    names = sorted(p.name for p in paths)
    assert "heatmap_IDF1_tracker_max_age_tracker_iou_threshold.png" in names
    assert "sweep_tracker_iou_threshold.png" in names and "sweep_seed.png" not in names
    agg = aggregate(frame, ["tracker.max_age", "tracker.iou_threshold"], ["IDF1"])
    assert agg["IDF1"].tolist() == pytest.approx([0.6, 0.8, 0.8, 1.4])
    assert agg["tracker.max_age"].tolist() == ["1", "1", "3", "3"]


def test_keys_named_seed_are_replicates():
    assert all(map(is_replicate, ["seed", "dataset.seed", "detector.seed", "a.b.seed"]))
    assert not any(map(is_replicate, ["seeds", "dataset.seed_offset", "tracker.max_age"]))


def _seed_sweep(root: Path, seed_key: str = "dataset.seed") -> None:
    num = 0
    for age in (1, 3):
        for seed in (0, 1, 2):
            _fake_job(root, num, ["tracker=baseline", f"tracker.max_age={age}",
                                  f"{seed_key}={seed}"],
                      {"IDF1": 0.5 + 0.1 * age + 0.01 * seed, "HOTA": 0.4})
            num += 1


@pytest.mark.parametrize("seed_key", ["dataset.seed", "seed"])
def test_a_seed_in_any_group_gives_mean_and_interval_never_an_axis(tmp_path, seed_key):
    _seed_sweep(tmp_path, seed_key)
    frame = gather(tmp_path)
    table = setting_table(frame, ["IDF1"])
    assert table["tracker.max_age"].tolist() == ["1", "3"] and table["n"].tolist() == [3, 3]
    assert seed_key not in table.columns
    # mean of 0.6, 0.61, 0.62 and its bootstrap interval, inside the values seen
    assert table.loc[0, "IDF1"] == "0.610 [0.600, 0.620]"
    names = sorted(p.name for p in plot_sweep(frame, tmp_path / "plots", ["IDF1", "HOTA"]))
    assert names == ["sweep_tracker_max_age.png"]  # no seed axis, no heatmap over seeds
    md = write_sweep(tmp_path, ["IDF1"]) is not None and (tmp_path / "sweep.md").read_text()
    assert f"mean [95% interval] over {seed_key}" in md


def test_no_heatmap_over_the_tracker_choice(tmp_path):
    num = 0
    for tracker in ("reta", "pbm"):
        for age in (1, 3):
            _fake_job(tmp_path, num, [f"tracker={tracker}", f"tracker.max_age={age}"],
                      {"IDF1": 0.5, "HOTA": 0.4})
            num += 1
    frame = gather(tmp_path)
    names = sorted(p.name for p in plot_sweep(frame, tmp_path / "plots", ["IDF1"]))
    assert names == ["sweep_tracker_max_age.png"]


def test_a_sweep_table_shows_a_figure_as_a_run_table_does(tmp_path):
    """One rounding rule (occbench.report.tables.number): 3 decimals, counts whole; sweep.md's
    tables and the printed summary showed 4 significant digits (0.8123, 12.67)."""
    for num, (idf1, ids) in enumerate([(0.81234, 12), (0.81234, 13), (0.70001, 4)]):
        _fake_job(tmp_path, num, ["tracker=baseline", f"tracker.max_age={1 + (num > 1)}",
                                  f"seed={num}"], {"IDF1": idf1, "IDs": ids})
    frame = gather(tmp_path)
    run = to_markdown(comparison(frame[frame["job"] == "0"].drop(columns=["job"]),
                                 ["IDF1", "IDs"]))
    assert "| baseline | 0.812 | 12 |" in run
    md = markdown_table(frame[frame["sequence"] == "COMBINED"][["job", "IDF1", "IDs"]])
    assert "| 0 | 0.812 | 12 |" in md and "| 2 | 0.700 | 4 |" in md
    table = setting_table(frame, ["IDF1", "IDs"])
    assert table.loc[0, "IDF1"] == "0.812" and table.loc[1, "IDF1"] == "0.700"
    assert table.loc[0, "IDs"] == "12.500 [12.000, 13.000]" and table.loc[1, "IDs"] == "4.000"
    text = summary_text(frame, ["IDF1", "IDs"])
    assert "0.812" in text and "0.8123" not in text and "12.500 [12.000, 13.000]" in text


def test_summary_shows_settings_and_every_jobs_overrides(tmp_path):
    _seed_sweep(tmp_path)
    text = summary_text(gather(tmp_path), ["IDF1"], "demo")
    assert text.startswith("sweep demo: 6 jobs, 6 done, 0 failed or missing")
    assert "mean [95% interval] over dataset.seed" in text and "0.810 [0.800, 0.820]" in text
    assert "\n    5  tracker.max_age=3 dataset.seed=2  [done]\n" in text
    assert "jobs (all with tracker=baseline):" in text


def test_ticks_are_rounded():
    assert tick("0.30000000000000004") == "0.3" and tick(41.999999999) == "42"
    assert tick("reta") == "reta" and tick(3) == "3"


# --------------------------------------------------------------------------- end to end


@pytest.fixture(scope="module")
def tiny_mot(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("tiny_mot")
    seq = root / "walk"
    (seq / "gt").mkdir(parents=True)
    rows = []
    for f in range(1, 26):
        rows.append(f"{f},1,{10 + 3 * f},20,20,50,1,-1,-1,-1")
        rows.append(f"{f},2,{140 - 3 * f},24,20,50,1,-1,-1,-1")
        if f > 4:
            rows.append(f"{f},3,60,{30 + f},22,48,1,-1,-1,-1")
    (seq / "gt" / "gt.txt").write_text("\n".join(rows) + "\n")
    (seq / "seqinfo.ini").write_text(
        "[Sequence]\nname=walk\nimWidth=200\nimHeight=120\nframeRate=10\nseqLength=25\n")
    return root


def _multirun(data: Path, sweep_dir: Path, *extra: str) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "occbench", "-m", "tracker=baseline", "tracker.max_age=1,3",
           "seed=0,1,2", "dataset=mot", f"dataset.root={data}", "detector=noisy_gt",
           "detector.miss_rate=0.25",
           "detector.jitter=0.05", "progress=false", f"hydra.sweep.dir={sweep_dir}", *extra]
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    proc = subprocess.run(cmd, check=False, cwd=ROOT, capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc


def test_joblib_sweep_equals_basic_launcher(tiny_mot, tmp_path):
    basic_run = _multirun(tiny_mot, tmp_path / "basic", "hydra/launcher=basic")
    _multirun(tiny_mot, tmp_path / "joblib", "hydra/launcher=parallel",
              "hydra.launcher.n_jobs=2")
    # stdout: the sweep's summary once (seeds as replicates), no table per job
    assert basic_run.stdout.count("COMBINED, mean [95% interval] over seed\n") == 1
    assert "results:" not in basic_run.stdout and "    5  tracker.max_age=3 seed=2" in basic_run.stdout
    basic = (tmp_path / "basic" / "sweep.csv").read_text()
    assert basic == (tmp_path / "joblib" / "sweep.csv").read_text()
    frame = pd.read_csv(tmp_path / "basic" / "sweep.csv")
    assert frame["job"].nunique() == 6 and (frame["status"] == DONE).all()
    assert swept(frame) == ["tracker.max_age", "seed"]
    combined = frame[frame["sequence"] == "COMBINED"]
    assert len(combined) == 6 and combined["IDF1"].between(0, 1).all()
    assert combined["IDF1"].nunique() > 1  # the seed changes the detections
    assert (tmp_path / "basic" / "plots" / "sweep_tracker_max_age.png").is_file()


def test_failing_job_is_recorded_and_a_rerun_skips_finished_jobs(tiny_mot, tmp_path):
    cmd = [sys.executable, "-m", "occbench", "-m", "tracker=baseline", "tracker.max_age=-1,2",
           "dataset=mot", "detector=noisy_gt", f"dataset.root={tiny_mot}", "progress=false",
           f"hydra.sweep.dir={tmp_path}", "hydra/launcher=basic"]
    proc = subprocess.run(cmd, check=False, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1, proc.stderr[-3000:]  # a sweep with a failed job fails
    assert "1 of 2 sweep jobs not done" in proc.stderr and "Traceback" not in proc.stderr
    table = (tmp_path / "sweep.csv").read_text()
    frame = pd.read_csv(tmp_path / "sweep.csv", keep_default_na=False)
    first = frame[frame["job"] == 0]
    assert first["status"].tolist() == [FAILED] and "max_age" in first["error"].iloc[0]
    assert (frame[frame["job"] == 1]["status"] == DONE).all()
    # the same sweep into the same directory: the finished job is skipped, the failed one
    # is tried again, and the gathered table is the same
    proc = subprocess.run(cmd, check=False, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.stderr.count("already done with the same overrides: skipped") == 1
    assert proc.stderr.count("job failed") == 1
    assert (tmp_path / "sweep.csv").read_text() == table


def test_ray_launcher_sweep_equals_basic(tiny_mot, tmp_path):
    pytest.importorskip("ray")
    pytest.importorskip("hydra_plugins.hydra_ray_launcher")
    _multirun(tiny_mot, tmp_path / "basic", "hydra/launcher=basic")
    _multirun(tiny_mot, tmp_path / "ray", "hydra/launcher=ray_cluster",
              "hydra.launcher.ray.init.num_cpus=2")
    assert ((tmp_path / "basic" / "sweep.csv").read_text()
            == (tmp_path / "ray" / "sweep.csv").read_text())


def test_optuna_study_starts_with_the_defaults_and_is_drawn_by_optuna(tmp_path):
    pytest.importorskip("hydra_plugins.hydra_optuna_sweeper")
    cmd = [sys.executable, "-m", "occbench", "+experiment=tune_baseline",
           "hydra.sweeper.n_trials=3", "hydra.sweeper.n_jobs=1", "hydra/launcher=basic",
           "dataset.length=12", "dataset.scenarios=[crossing]", "dataset.width=160",
           "dataset.height=120", f"hydra.sweep.dir={tmp_path}"]
    proc = subprocess.run(cmd, check=False, cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    first = yaml.safe_load((tmp_path / "0" / ".hydra" / "overrides.yaml").read_text())
    defaults = yaml.safe_load((ROOT / "conf" / "tracker" / "baseline.yaml").read_text())
    for key in ("iou_threshold", "min_hits", "max_age"):  # the searched parameters
        assert f"tracker.{key}={defaults[key]}" in first
    names = sorted(p.name for p in (tmp_path / "plots").iterdir())
    assert {"optuna_history.png", "optuna_slice.png", "optuna_contour.png"} <= set(names)
    assert not [n for n in names if n.startswith(("sweep_", "heatmap_"))]
    # the summary once, at the end, on stdout; no job prints a table of its own
    assert proc.stdout.count("jobs (all with") == 1 and "results:" not in proc.stdout
    # gathered by hand (occbench sweep DIR): the same Optuna views, found from the job folders
    for png in (tmp_path / "plots").iterdir():
        png.unlink()
    assert sweep_main([str(tmp_path)]) == 0
    assert sorted(p.name for p in (tmp_path / "plots").iterdir()) == names
