"""Start-up: the modules a run imports before its first frame leave the heavy libraries
(pandas, matplotlib, filterpy and scipy.stats under it, motmetrics) to the code that uses
them, and the compiled kernels load from numba's cache. Each check runs in a fresh
interpreter (``sys.modules`` of this one holds whatever earlier tests imported)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("pandas", "matplotlib", "filterpy", "scipy.stats", "motmetrics")


def _loaded_after(code: str) -> list[str]:
    """The ``HEAVY`` modules in ``sys.modules`` of a fresh interpreter after ``code``."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         env=env, cwd=ROOT, check=True, timeout=300)
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("module", ["harness.commands.cli", "harness.commands.run",
                                    "harness.pipeline.experiment", "harness.sweeps.callbacks",
                                    "hydra_plugins.occbench_launcher.launcher"])
def test_harness_imports_leave_heavy_libraries_out(module):
    assert _loaded_after(f"import {module}") == []


@pytest.mark.parametrize("tracker", ["reta", "pbm"])
def test_paper_trackers_build_without_filterpy_or_pandas(tracker):
    code = ("from harness.pipeline.build import build_tracker, compose_config\n"
            f"cfg = compose_config(['tracker={tracker}'])\n"
            f"build_tracker('{tracker}', cfg.tracker, 'tracker')")
    assert _loaded_after(code) == []


def test_baseline_imports_filterpy_only_when_a_filter_is_built():
    assert _loaded_after("from trackers.baseline import BaselineTracker; BaselineTracker()") == []
    loaded = _loaded_after("import numpy as np\nfrom trackers.common.kalman import "
                           "constant_velocity_box_filter\n"
                           "constant_velocity_box_filter(np.array([0.0, 0.0, 10.0, 20.0]))")
    assert "filterpy" in loaded
