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


@pytest.mark.parametrize("module", ["occbench.commands.cli", "occbench.commands.run",
                                    "occbench.pipeline.experiment", "occbench.sweeps.callbacks",
                                    "hydra_plugins.occbench_launcher.launcher"])
def test_harness_imports_leave_heavy_libraries_out(module):
    assert _loaded_after(f"import {module}") == []


@pytest.mark.parametrize("tracker", ["reta", "pbm"])
def test_paper_trackers_build_without_filterpy_or_pandas(tracker):
    code = ("from occbench.config.build import build_tracker, compose_config\n"
            f"cfg = compose_config(['tracker={tracker}'])\n"
            f"build_tracker('{tracker}', cfg.tracker, 'tracker')")
    assert _loaded_after(code) == []


def test_baseline_imports_filterpy_only_when_a_filter_is_built():
    assert _loaded_after("from occbench.trackers.baseline import BaselineTracker; BaselineTracker()") == []
    loaded = _loaded_after("import numpy as np\nfrom occbench.trackers.common.kalman import "
                           "constant_velocity_box_filter\n"
                           "constant_velocity_box_filter(np.array([0.0, 0.0, 10.0, 20.0]))")
    assert "filterpy" in loaded


def test_every_numba_kernel_is_cached():
    """Every ``numba.njit`` / ``numba.jit`` in trackers/ and harness/ has ``cache=True``: a
    new process loads the kernels from ``__pycache__`` instead of compiling them."""
    import ast

    missing = []
    for pkg in ("trackers", "harness"):
        for path in sorted((ROOT / pkg).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if not isinstance(node, ast.FunctionDef):
                    continue
                for deco in node.decorator_list:
                    call = deco if isinstance(deco, ast.Call) else None
                    name = ast.unparse(call.func if call else deco)
                    if name.split(".")[-1] not in ("njit", "jit"):
                        continue
                    cached = call is not None and any(
                        k.arg == "cache" and ast.unparse(k.value) == "True" for k in call.keywords)
                    if not cached:
                        missing.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}")
    assert not missing, f"numba kernels compiled in every process: {missing}"


KERNEL_STATS = """
import json, sys
import numba.core.registry
from occbench.config.build import build_tracker, compose_config
from occbench.pipeline.warmup import warm_up
warm_up(build_tracker('reta', compose_config(['tracker=reta']).tracker, 'tracker'))
hits = misses = 0
for module in [m for n, m in list(sys.modules.items()) if n.startswith('occbench.trackers.')]:
    for obj in vars(module).values():
        stats = getattr(obj, 'stats', None)
        if hasattr(stats, 'cache_hits'):
            hits += sum(stats.cache_hits.values())
            misses += sum(stats.cache_misses.values())
print(json.dumps([hits, misses]))
"""


def test_a_new_process_loads_the_kernels_from_the_cache():
    """After one process has compiled (or loaded) reta's kernels, a new one loads every
    kernel it runs from numba's cache: no miss."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    runs = [subprocess.run([sys.executable, "-c", KERNEL_STATS], capture_output=True, text=True,
                           env=env, cwd=ROOT, check=True, timeout=900) for _ in range(2)]
    hits, misses = json.loads(runs[1].stdout.strip().splitlines()[-1])
    assert hits > 0 and misses == 0


def test_the_console_scripts_fast_path_imports_no_library():
    """Before it knows whether a warm server answers (``occbench.server.client.served``),
    ``occbench`` has imported the standard library only: ``harness`` itself imports nothing."""
    code = ("import json, sys\nimport occbench.__main__, occbench.server.client\n"
            "print(json.dumps(sorted({'.'.join(m.split('.')[:2 if m.startswith('occbench.') else 1])"
            " for m in sys.modules} & {'omegaconf', 'hydra', 'numpy', 'yaml', 'occbench.trackers',"
            " 'scipy', 'cv2'})))")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         cwd=ROOT, check=True, timeout=300)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []
