"""The Hydra app: the command line, the printed table and the exit status, run in a
subprocess (``python -m occbench``) or through Hydra's compose API."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from run_scenes import (
    ROOT,
    compose_cfg,
    needs_synthetic,
)

from occbench.errors import RunError
from occbench.metrics import COLUMNS
from occbench.metrics.occlusion import EXTRA_COLUMNS
from occbench.pipeline.experiment import run_experiment as _run_experiment


def run_app(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "HYDRA_FULL_ERROR": ""}
    env.pop("HYDRA_FULL_ERROR")
    return subprocess.run([sys.executable, "-m", "occbench", "progress=false", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=300, env=env, check=False)


# ----------------------------------------------------------------------------- command line


def test_unknown_key_exits_nonzero_naming_it():
    p = run_app("foo=1")
    assert p.returncode != 0
    assert "foo" in p.stderr


@pytest.mark.parametrize("tracker,key", [
    ("reta", "stage1_unmatched_cost"), ("pbm", "occluded_cover"),
    ("pbm", "assignment"), ("pbm", "overlap_as_measured"), ("pbm", "position_gate"),
    ("reta", "noise_estimate"), ("pbm", "merge_stacked"), ("pbm", "twin_refind")])
def test_an_adaptation_key_a_tracker_does_not_have_is_named(tracker, key):
    """A user config naming an adaptation that does not exist (these were removed, not
    taken: docs/adaptations.md) stops the build with the key named, not silently ignored."""
    from occbench.config.build import build_tracker, compose_config

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
    p = run_app("dataset=mot", "detector=noisy_gt", f"dataset.root={mot_root}", "tracker=baseline",
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
