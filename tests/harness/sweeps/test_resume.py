"""Sweep folders you can trust (issue 24): a job counts as done only with whole outputs and
the same inputs, and a sweep gathers only its own jobs.

Classes covered: outputs damaged after the job finished (a ``metrics.csv`` cut at a line end,
a file removed or edited), data named by a relative path (changed data, a path naming
nothing, a folder with no file), job folders left by an earlier sweep in the same folder.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml
from hydra import compose, initialize_config_dir

from occbench.sweeps.fingerprint import FingerprintError, inputs
from occbench.sweeps.gather import DAMAGED, DONE, gather, main, summary_text
from occbench.sweeps.jobs import begin_sweep
from occbench.sweeps.resume import finished, guarded

ROOT = Path(__file__).resolve().parents[3]
METRICS = ("tracker,sequence,IDF1,IDs,complete\nbaseline,a,0.5,3,True\nbaseline,b,0.7,1,True\n"
           "baseline,COMBINED,0.6,4,True\n")


def _job(job_dir: Path, overrides: list[str], text: str = METRICS):
    """A job that writes its run folder as the app does; returns the run count."""
    calls = []

    def run() -> float:
        calls.append(1)
        (job_dir / "tracks" / "baseline").mkdir(parents=True, exist_ok=True)
        (job_dir / "tracks" / "baseline" / "a.txt").write_text("1,1,1,1,5,5,1,-1,-1,-1\n")
        (job_dir / "metrics.csv").write_text(text)
        return 0.6

    (job_dir / ".hydra").mkdir(parents=True, exist_ok=True)
    (job_dir / ".hydra" / "overrides.yaml").write_text(yaml.safe_dump(overrides))
    return run, calls


@pytest.mark.parametrize("damage", ["cut at a line end", "removed", "edited"])
def test_a_job_with_damaged_outputs_is_not_done(tmp_path, damage):
    job = tmp_path / "0"
    over = ["tracker.max_age=3"]
    run, calls = _job(job, over)
    guarded(job, over, run)
    assert finished(job, over) is not None and gather(tmp_path)["status"].eq(DONE).all()
    if damage == "cut at a line end":  # still a well-formed CSV, one row short
        target = job / "metrics.csv"
        target.write_text(METRICS[:METRICS.index("baseline,COMBINED")])
    elif damage == "removed":
        target = job / "tracks" / "baseline" / "a.txt"
        target.unlink()
    else:
        target = job / "tracks" / "baseline" / "a.txt"
        target.write_text("1,2,1,1,5,5,1,-1,-1,-1\n")  # same size, other bytes
    assert finished(job, over) is None  # a resume runs it again
    frame = gather(tmp_path).drop_duplicates("job")
    assert frame["status"].tolist() == [DAMAGED] and str(target) in frame["error"].iloc[0]
    assert main([str(tmp_path), "--no-plots"]) == 1
    guarded(job, over, run)
    assert len(calls) == 2 and finished(job, over) is not None


def test_a_metrics_file_cut_at_a_line_end_without_a_record_is_damaged(tmp_path):
    """A job folder from before outputs were recorded: the table itself must be whole (every
    tracker's COMBINED row)."""
    job = tmp_path / "0"
    (job / ".hydra").mkdir(parents=True)
    (job / "metrics.csv").write_text(METRICS[:METRICS.index("baseline,COMBINED")])
    (job / "status.json").write_text(json.dumps({"status": "done", "overrides": []}))
    frame = gather(tmp_path)
    assert frame["status"].tolist() == [DAMAGED]
    assert "no COMBINED row for baseline" in frame["error"].iloc[0]


def _cfg(*overrides: str):
    with initialize_config_dir(config_dir=str(ROOT / "conf"), version_base="1.3"):
        return compose("config", overrides=list(overrides))


def _mot(root: Path) -> Path:
    seq = root / "a"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_text("".join(f"{f},1,{10 + f},20,20,50,1,1,1\n"
                                               for f in range(1, 11)))
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=a\nimWidth=100\nimHeight=100\n"
                                     "frameRate=10\nseqLength=10\n")
    return seq / "gt" / "gt.txt"


def test_a_relative_data_path_is_fingerprinted_by_its_files(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    gt = _mot(tmp_path / "rs2")
    cfg = _cfg("dataset=mot", "dataset.root=rs2", "tracker=baseline")  # no "/" nor "."
    first = inputs(cfg)
    assert first["data"] == inputs(_cfg("dataset=mot", f"dataset.root={tmp_path / 'rs2'}",
                                        "tracker=baseline"))["data"]  # the same folder
    gt.write_text(gt.read_text().replace("1,1,11,20", "1,1,12,20"))  # same size
    assert inputs(cfg)["data"] != first["data"]
    with pytest.raises(FingerprintError, match="dataset.root=nowhere: no such file"):
        inputs(_cfg("dataset=mot", "dataset.root=nowhere", "tracker=baseline"))
    (tmp_path / "hollow").mkdir()
    with pytest.raises(FingerprintError, match="hollow: no data file"):
        inputs(_cfg("dataset=mot", "dataset.root=hollow", "tracker=baseline"))
    empty = "e3b0c44298fc1c14"  # sha256 of no bytes
    assert inputs(_cfg("tracker=baseline"))["data"] != empty  # synthetic: no files


def test_a_job_whose_inputs_cannot_be_fingerprinted_always_runs(tmp_path):
    job = tmp_path / "0"
    run, calls = _job(job, [])

    def broken() -> dict:
        raise FingerprintError("dataset.root=x: no such file or folder")

    guarded(job, [], run, broken)
    guarded(job, [], run, broken)
    assert len(calls) == 2


def test_jobs_of_an_earlier_sweep_in_the_folder_are_ignored_and_named(tmp_path):
    begin_sweep(tmp_path, ["tracker.max_age=1,3,5"])
    for num, age in enumerate((1, 3, 5)):
        run, _ = _job(tmp_path / str(num), [f"tracker.max_age={age}"])
        guarded(tmp_path / str(num), [f"tracker.max_age={age}"], run)
    assert gather(tmp_path)["job"].nunique() == 3
    begin_sweep(tmp_path, ["tracker.max_age=1,3", "seed=1"])  # other settings, same folder
    for num, age in enumerate((1, 3)):
        over = [f"tracker.max_age={age}", "seed=1"]
        run, _ = _job(tmp_path / str(num), over)
        guarded(tmp_path / str(num), over, run)
    frame = gather(tmp_path)
    assert sorted(frame["job"].unique()) == ["0", "1"] and (frame["seed"] == "1").all()
    text = summary_text(frame, ["IDF1"])
    assert "ignored 1 job folder(s) not of this sweep" in text
    assert "job 2 (tracker.max_age=5): left by an earlier sweep" in text
    assert main([str(tmp_path), "--no-plots"]) == 0
    assert "tracker.max_age=5" in (tmp_path / "sweep.md").read_text()  # named, not gathered
    assert len(pd.read_csv(tmp_path / "sweep.csv")["job"].unique()) == 2


def test_resumed_sweep_over_a_relative_root_and_other_settings(tmp_path):
    """End to end, as the issue reproduced it: a sweep over ``dataset.root=rs2`` (relative),
    the gt edited, the sweep run again with fewer settings into the same folder."""
    gt = _mot(tmp_path / "rs2")
    env = {**os.environ, "OMP_NUM_THREADS": "1",
           "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}

    def sweep(ages: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "occbench", "-m", "tracker=baseline", f"tracker.max_age={ages}",
             "dataset=mot", "detector=noisy_gt",
 "dataset.root=rs2", "progress=false", "hydra.sweep.dir=S",
             "hydra/launcher=basic"], check=False, cwd=tmp_path, env=env, text=True,
            capture_output=True, timeout=300)

    first = sweep("1,3,5")
    assert first.returncode == 0, first.stderr[-3000:]
    gt.write_text(gt.read_text().replace("1,1,11,20", "1,1,12,20"))
    second = sweep("1,3")
    assert second.returncode == 0, second.stderr[-3000:]
    assert "skipped" not in second.stderr and "inputs changed" in second.stderr
    assert "sweep S: 2 jobs, 2 done" in second.stdout
    (ignored,) = [line for line in second.stdout.splitlines() if "job 2 (" in line]
    assert "tracker.max_age=5" in ignored and "left by an earlier sweep" in ignored
