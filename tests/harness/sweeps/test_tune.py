"""The tune_* experiments on the default launcher (``hydra/launcher=parallel``): a study
finishes and its best trial is the job whose metrics.csv holds that value."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[3]
CONF = ROOT / "conf"
TUNE = sorted(p.stem for p in (CONF / "experiment").glob("tune_*.yaml"))


def _compose(overrides: list[str]):
    from hydra import compose, initialize_config_dir

    from occbench.config import register

    register()  # the ${occbench...} resolvers

    with initialize_config_dir(str(CONF), version_base="1.3"):
        return compose("config", overrides=overrides, return_hydra_config=True)


@pytest.mark.parametrize("name", TUNE)
def test_tune_experiment_composes_with_the_default_launcher(name):
    pytest.importorskip("hydra_plugins.hydra_optuna_sweeper")
    cfg = _compose([f"+experiment={name}"])
    assert cfg.hydra.launcher._target_.endswith("occbench_launcher.launcher.ProcessLauncher")
    assert "optuna" in cfg.hydra.sweeper._target_.lower() and cfg.hydra.sweeper.params
    assert cfg.objective.metric and cfg.objective.tracker


def test_tune_reta_on_the_default_launcher_reports_its_best_job(tmp_path):
    pytest.importorskip("hydra_plugins.hydra_optuna_sweeper")
    cmd = [sys.executable, "-m", "occbench", "+experiment=tune_reta", "hydra.sweeper.n_trials=3",
           "dataset.length=20", "dataset.scenarios=[crossing]", "dataset.width=160",
           "dataset.height=120", f"hydra.sweep.dir={tmp_path}"]
    proc = subprocess.run(cmd, check=False, cwd=ROOT, capture_output=True, text=True,
                          env={**os.environ, "OMP_NUM_THREADS": "1"}, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "objective function returned nan" not in proc.stderr
    best = yaml.safe_load((tmp_path / "optimization_results.yaml").read_text())
    values = {}
    for job in sorted(p for p in tmp_path.iterdir() if p.name.isdigit()):
        status = json.loads((job / "status.json").read_text())
        assert status["status"] == "done"
        metrics = pd.read_csv(job / "metrics.csv")
        row = metrics[(metrics["tracker"] == "reta") & (metrics["sequence"] == "COMBINED")]
        values[job.name] = float(row["IDF1"].iloc[0])
        assert math.isclose(status["objective"], values[job.name], abs_tol=1e-6)
    assert len(values) == 3
    assert math.isclose(best["best_value"], max(values.values()), abs_tol=1e-6)
    best_job = max(values, key=values.get)
    overrides = yaml.safe_load((tmp_path / best_job / ".hydra" / "overrides.yaml").read_text())
    for key, value in best["best_params"].items():
        assert any(o.startswith(f"{key}=") and math.isclose(float(o.split("=", 1)[1]), value)
                   for o in overrides), (key, value, overrides)
