"""PBM warm-up (trackers/layered/warmup.py): it loads every kernel a run uses, and it leaves
the tracker exactly as built."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
from hydra.utils import instantiate
from omegaconf import OmegaConf

from harness.datasets.synthetic import load_scenario
from harness.detection_sources import NoisyGroundTruth
from harness.run import run_sequence
from trackers.layered.warmup import warm_up

ROOT = Path(__file__).resolve().parents[1]

# in a fresh process: build a tracker (which warms up), then count the numba signatures a
# crowd run adds, with and without a foreground mask
_FRESH = r"""
import importlib, pkgutil, sys
from hydra.utils import instantiate
from numba.core.registry import CPUDispatcher
from omegaconf import OmegaConf
import trackers
from harness.datasets.synthetic import load_scenario
from harness.detection_sources import NoisyGroundTruth
from harness.run import run_sequence

instantiate(OmegaConf.load(sys.argv[1]))
kernels = {}
for m in pkgutil.walk_packages(trackers.__path__, "trackers."):
    if m.name.startswith("trackers.outside"):
        continue
    for v in vars(importlib.import_module(m.name)).values():
        if isinstance(v, CPUDispatcher):
            kernels[f"{v.__module__}.{v.__name__}"] = v
before = {k: len(v.signatures) for k, v in kernels.items()}
seq = load_scenario("crowd", seed=0, length=60, people=8)
for fg in ("exact", "none"):
    run_sequence({"pbm": instantiate(OmegaConf.load(sys.argv[1]))}, seq,
                 NoisyGroundTruth(miss_rate=0.3, seed=0), foreground=fg)
print(sorted(k for k, v in kernels.items() if len(v.signatures) != before[k]))
print(sum(before.values()))
"""


def test_a_built_tracker_has_loaded_every_kernel_a_run_uses():
    out = subprocess.run([sys.executable, "-c", _FRESH, str(ROOT / "conf" / "tracker" / "pbm.yaml")],
                         capture_output=True, text=True, cwd=ROOT, check=True).stdout.splitlines()
    assert out[-2] == "[]"  # no kernel compiled or loaded during the run
    assert int(out[-1]) >= 20  # and the warm-up did load the kernels


def test_warm_up_leaves_the_tracker_as_built():
    cfg = OmegaConf.load(ROOT / "conf" / "tracker" / "pbm.yaml")
    cfg.warm_up = False
    seq = load_scenario("pair_walk", seed=1, length=60)
    plain, warmed = instantiate(cfg), instantiate(cfg)
    warm_up(warmed)
    res = run_sequence({"plain": plain, "warmed": warmed}, seq, NoisyGroundTruth(miss_rate=0.3, seed=1),
                       foreground="exact")
    a, b = res["plain"].table, res["warmed"].table
    assert len(a) > 100
    np.testing.assert_array_equal(a.ids, b.ids)
    np.testing.assert_array_equal(a.boxes, b.boxes)
